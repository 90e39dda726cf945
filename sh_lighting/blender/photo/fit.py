"""Match Photo: the scene's lighting from a photo of a grey ball (``core.photo``), stored.

The photo is read as Blender renders it (``world.images.linear_pixels``), fitted by
``core.photo.fit_photo`` and stored under provenance "PHOTO". Clipped pixels: a byte of 255
(8-bit), 1.0 (16-bit PNG), above ``clip`` (EXR, HDR). The camera: a camera object (the scene's
by default) or a view direction and roll. A chrome ball (a mirror-ball image, or the world when
it is one) is the prior "chrome" and ``exposure_match`` compares the fit with it; a
``SecondPhoto`` is the prior "photo".
"""

import os
from dataclasses import dataclass

import bpy
import numpy as np

from ...core.ball_camera import PhotoCamera, PhotoError, camera_looking
from ...core.ball_detect import detect_ball
from ...core.photo import (
    DEFAULT_ALBEDO,
    DEFAULT_MARGIN,
    DEFAULT_PRIOR_WEIGHT,
    fit_photo,
    match_exposure,
)
from ..data import scene_data
from ..world import images
from ..world import reader
from ..world.hdri import read_hdri

# File formats whose values have no top code (linear light): nothing is clipped by default.
HDR_FORMATS = {"OPEN_EXR", "OPEN_EXR_MULTILAYER", "HDR"}


@dataclass(frozen=True)
class PhotoSource:
    """A photo as read: linear (H, W, 4) pixels, its clipped pixels (H, W) bool, the file,
    and where an 8-bit photo with alpha is opaque ((H, W) bool; None: all of it)."""

    pixels: np.ndarray
    clipped: np.ndarray
    path: str
    file_format: str
    opaque: np.ndarray = None


def read_photo(path):
    """The photo at ``path`` as Blender renders it (a ``PhotoSource``), nothing left in
    bpy.data; a ValueError saying what to do when it cannot be read."""
    path = os.path.normpath(bpy.path.abspath(os.fspath(path)))
    if not os.path.isfile(path):
        raise PhotoError(f"photo '{path}' does not exist: check the path")
    try:
        image = bpy.data.images.load(path, check_existing=False)
    except RuntimeError as error:
        raise PhotoError(f"Blender could not open photo '{path}' as an image: {error}") from None
    try:
        raw = images.image_pixels(image)
        # a cut-out (the ball opaque, the rest transparent): only the circle's texels matter,
        # and the fit leaves out (or refuses) transparent ones there
        pixels = images.linear_pixels(image, keep_transparent=True)
        file_format = image.file_format
        opaque = None
        if not image.is_float and image.alpha_mode in ("STRAIGHT", "PREMUL"):
            alpha = raw[..., 3]
            opaque = None if (alpha >= 1.0).all() else alpha >= 1.0
        if not image.is_float:
            clipped = (raw[..., :3] >= 1.0).any(axis=-1)  # a byte of 255
        elif file_format in HDR_FORMATS:
            clipped = np.zeros(raw.shape[:2], dtype=bool)
        else:
            clipped = (raw[..., :3] >= 1.0 - 1e-6).any(axis=-1)  # the top code of the file
    finally:
        bpy.data.images.remove(image)
    return PhotoSource(pixels, clipped, path, file_format, opaque)


def detect_circle(path):
    """The ``core.ball_detect.BallGuess`` of the ball in the photo at ``path`` (a suggestion:
    ``.circle``, ``.score``, ``summary()``), or a PhotoError when no ball is found."""
    source = read_photo(path)
    guess = detect_ball(source.pixels)
    if guess is None:
        raise PhotoError(f"no ball found in '{os.path.basename(source.path)}' (no circular "
                         "outline stands out): give the ball's circle, typed or dragged")
    return guess


def camera_of(camera_object, scene=None):
    """The ``PhotoCamera`` of a Blender camera object (orientation as evaluated in ``scene``,
    with parents and constraints; ORTHO/PERSP, lens, sensor); a PhotoError for a panoramic
    or shifted camera, which the fit does not model."""
    if camera_object is None or camera_object.type != "CAMERA":
        raise PhotoError("no camera: set the scene's camera, or give a view direction instead")
    data = camera_object.data
    if data.type not in ("ORTHO", "PERSP"):
        raise PhotoError(f"camera '{camera_object.name}' is {data.type.lower()}: Match Photo "
                         "takes a perspective or orthographic camera")
    if abs(data.shift_x) > 1e-6 or abs(data.shift_y) > 1e-6:
        raise PhotoError(f"camera '{camera_object.name}' has a lens shift, which Match Photo "
                         "does not model: set Shift X and Y to 0 or give a view direction")
    matrix_world = camera_object.matrix_world
    if scene is not None:  # a camera just moved by a script: its matrix_world is stale
        view_layer = bpy.context.view_layer if bpy.context.scene == scene else scene.view_layers[0]
        view_layer.update()
        matrix_world = camera_object.evaluated_get(view_layer.depsgraph).matrix_world
    matrix = np.array(matrix_world.to_3x3().normalized())
    fit = data.sensor_fit
    sensor = data.sensor_height if fit == "VERTICAL" else data.sensor_width
    return PhotoCamera(tuple(map(tuple, matrix)), data.type, float(data.lens), float(sensor), fit)


def photo_camera(scene, camera_object=None, direction=None, roll=0.0, projection="ORTHO",
                 focal_mm=50.0, sensor_mm=36.0):
    """(PhotoCamera, its provenance entries): from ``direction`` and ``roll`` when a direction
    is given, else from ``camera_object`` (default: the scene's camera)."""
    if direction is not None:
        camera = camera_looking(direction, roll, projection, focal_mm, sensor_mm)
        return camera.checked(), {"camera": "DIRECTION", "direction": [float(v) for v in
                                                                       direction],
                                  "roll": float(roll)}
    camera_object = scene.camera if camera_object is None else camera_object
    camera = camera_of(camera_object, scene).checked()
    return camera, {"camera": camera_object.name}


@dataclass(frozen=True)
class SecondPhoto:
    """A second photo of the same ball from another side (the prior "photo"): its file, the
    ball's circle in it, and its camera: a camera object, or a view direction and roll (the
    first photo's projection, lens and sensor)."""

    path: str
    circle: tuple
    camera_object: object = None
    direction: tuple = None
    roll: float = 0.0


def _clipped(source, clip):
    """The file's clipped pixels, and those with a linear channel ≥ ``clip`` if given."""
    if clip is None:
        return source.clipped
    return source.clipped | (source.pixels[..., :3] >= float(clip)).any(axis=-1)


def chrome_coefficients(scene, chrome=None):
    """(the chrome ball's (9, 3) L_lm, its provenance name): from a mirror-ball image file
    ``chrome``, or the scene's world when None (a chrome ball set as the world)."""
    if chrome is None:
        coeffs, _info = reader.world_coefficients(scene)
        return coeffs, "WORLD"
    path = os.path.normpath(bpy.path.abspath(os.fspath(chrome)))
    if not os.path.isfile(path):
        raise PhotoError(f"chrome ball '{path}' does not exist: check the path")
    return read_hdri(path, projection="mirror_ball").coefficients, os.path.basename(path)


def _second_fit(scene, second, first_camera, albedo, margin, clip):
    """(``PhotoFit`` of the ``SecondPhoto``, prior "none"; its provenance entries, each
    named "second_...")."""
    if second is None:
        raise PhotoError("the second-photo prior needs a second photo of the ball from "
                         "another side: give its file, circle and camera or view direction")
    if second.camera_object is None and second.direction is None:
        raise PhotoError("the second photo needs its camera: a camera object, or the view "
                         "direction it was taken along")
    camera, record = photo_camera(scene, second.camera_object, second.direction, second.roll,
                                  first_camera.projection, first_camera.focal_mm,
                                  first_camera.sensor_mm)
    source = read_photo(second.path)
    try:
        fit = fit_photo(source.pixels, second.circle, camera, albedo=albedo, margin=margin,
                        clip=_clipped(source, clip), prior="none", opaque=source.opaque)
    except PhotoError as error:
        raise PhotoError(f"second photo '{os.path.basename(source.path)}': {error}") from None
    record = {"file": os.path.basename(source.path),
              "circle": [float(v) for v in second.circle], **record,
              "residual": fit.residual, "used": fit.used}
    return fit, {f"second_{key}": value for key, value in record.items()}


def coefficients_from_photo(scene, path, circle, *, camera_object=None, direction=None,
                            roll=0.0, projection="ORTHO", focal_mm=50.0, sensor_mm=36.0,
                            albedo=DEFAULT_ALBEDO, margin=DEFAULT_MARGIN, prior="mirror",
                            prior_weight=DEFAULT_PRIOR_WEIGHT, clip=None, chrome=None,
                            second=None, store=True):
    """Fit the photo at ``path`` (ball ``circle`` (cx, cy, r) in pixels from the top-left)
    and store the result on ``scene`` (unless ``store`` is False). Returns (coeffs (9, 3),
    ``core.photo.PhotoFit``). ``clip``: a linear threshold added to the file's own clipping.
    Prior "chrome": the chrome ball is the mirror-ball image file ``chrome``, or the scene's
    world when None, and the record's "exposure_..." entries are the ``exposure_match``
    against it (with its "exposure_summary" line); prior "photo": ``second`` is a ``SecondPhoto``.
    Any problem raises a ValueError (PhotoError) with one line, the scene unchanged."""
    camera, camera_record = photo_camera(scene, camera_object, direction, roll, projection,
                                         focal_mm, sensor_mm)
    source = read_photo(path)
    reference, extra = None, {}
    if prior == "chrome":
        reference, extra["chrome"] = chrome_coefficients(scene, chrome)
    elif prior == "photo":
        reference, extra = _second_fit(scene, second, camera, albedo, margin, clip)
    fit = fit_photo(source.pixels, circle, camera, albedo=albedo, margin=margin,
                    clip=_clipped(source, clip), prior=prior, prior_weight=prior_weight,
                    reference=reference, opaque=source.opaque)
    if fit.prior_scale is not None:
        extra["prior_scale"] = [float(v) for v in fit.prior_scale]
        match = match_exposure(fit.coefficients, reference, fit.normals)
        extra.update(exposure_scale=match.scale, exposure_seen_scale=match.seen_scale,
                     exposure_seen=match.seen, exposure_everywhere=match.everywhere,
                     exposure_summary=match.summary())
    record = {
        "source": "PHOTO", "file": os.path.basename(source.path), "path": source.path,
        "circle": [float(v) for v in circle], **camera_record,
        "projection": camera.projection, "matrix": [float(v) for v in
                                                    np.ravel(camera.rotation())],
        "albedo": float(albedo), "margin": float(margin), "prior": prior,
        "prior_weight": fit.prior_weight, "residual": fit.residual,
        "condition": fit.condition, "used": fit.used, "clipped": fit.clipped,
        "weak_terms": list(fit.weak_terms), **extra,
    }
    if fit.warning() is not None:
        record["warning"] = fit.warning()
    if camera.projection == "PERSP":
        record.update(focal_mm=camera.focal_mm, sensor_mm=camera.sensor_mm,
                      sensor_fit=camera.sensor_fit)
    coeffs = scene_data.store(scene, fit.coefficients, record) if store else fit.coefficients
    return coeffs, fit


def exposure_match(scene, fit, chrome=None):
    """Both balls: ``core.photo.ExposureMatch`` of a grey-ball ``fit`` against a chrome ball
    (the mirror-ball image file ``chrome``, or the lighting of the scene's world as the add-on
    reads it when None: a chrome ball's mirror-ball image, an HDRI): the exposure scale that
    makes the grey ball's L00 agree, and how far the rest disagree on the seen normals and
    everywhere. Reads only (nothing is stored)."""
    coeffs, _name = chrome_coefficients(scene, chrome)
    return match_exposure(fit.coefficients, coeffs, fit.normals)
