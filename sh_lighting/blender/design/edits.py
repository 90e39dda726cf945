"""Lighting design on a scene's coefficients: plain functions for the operators and the API.

Each takes the scene (never ``bpy.context``), reads its coefficients (a LookupError without
any), lets the core compute and stores the result with ``scene_data.store`` (provenance with
the edit; edits are not Reset values). Errors are ValueError/LookupError with a message for
the user, nothing changed; angles in radians. Match Mapping and the window's error read the
world image with ``reader.read_world``, as Compute from World does.
"""

import math
from dataclasses import dataclass
from numbers import Real

import numpy as np

from ...core import edits, windowing
from ...core.coefficients import type_name
from ...core.colour import luminance_weights
from ...core.minimum import irradiance_minimum, negative_light_warning
from ...core.rotation import rotate_coefficients
from ...core.sh import spread_normals
from ...core.world_map import (
    map_irradiance,
    mapping_rotation,
)
from ..data import compat, scene_data
from ..world import compute
from ..world import reader

# Normals at which a window's error is measured against the world (brute force, eq. 1).
COST_NORMALS = 256

WINDOWS = ("HANNING", "LANCZOS", "MINIMAL")
DEFAULT_WIDTH = 3.0  # Hanning/Lanczos width L + 1 (core.windowing): (1, 3/4, 1/4) for Hanning
BANDS = {"ALL": None, "AMBIENT": (0,), "DIRECTIONAL": (1,), "QUADRATIC": (2,), "COLOURED": (1, 2)}


class DesignError(ValueError):
    """A design tool cannot run on this scene; the message says why and what to do."""


MAX_STOPS = 256.0  # 2^±256 takes any float32 lighting out of range: no exposure beyond it


def _number(value, what, hint):
    """``value`` as a finite float, or a DesignError "what is ...: hint" (not a raw
    TypeError for a string, a RuntimeWarning for inf, NaN lighting)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, Real):
        shown = type_name(value) if value is None else f"{type_name(value)} ({value!r})"
        raise DesignError(f"{what} is {shown}, not a number: {hint}")
    number = float(value)
    if not math.isfinite(number):
        raise DesignError(f"{what} is {number!r}, not a finite number: {hint}")
    return number


# -- the scene's coefficients ------------------------------------------------------------------


def _edited_values(scene):
    """(values an edit works on, ``store``'s gains policy). While a gain s_lm is keyframed or
    driven, the channels c_lm alone (the gains and their animation stay: L = s(t) · c' at
    every frame; folding an animated gain into c would apply it twice at the next
    frame); else the lighting L = s · c, stored with s = 1. Exposure, saturation,
    band gains, the flip and the windows scale whole rows, so they commute with the gains;
    a rotation mixes the rows of a band, so with unequal animated gains in a band the gains
    then scale the rotated rows."""
    if scene_data.gains_animated(scene):
        scene_data.get_coefficients(scene)  # the LookupError when there are none
        return scene_data.get_channels(scene), "KEEP"
    return scene_data.get_coefficients(scene), "UNIT"


def _edit(scene, function, *args, **kwargs):
    values, gains = _edited_values(scene)
    edited = function(values, *args, **kwargs)
    return scene_data.store(
        scene, edited, scene_data.edited(scene, function.__name__), gains=gains
    )


def rotate(scene, yaw=0.0, pitch=0.0, roll=0.0):
    """Turn the lighting by yaw (about +Z), pitch (+X), roll (+Y), radians (``core.edits``)."""
    hint = "give an angle in radians (math.radians(90) for 90°)"
    angles = [_number(v, w, hint) for v, w in zip((yaw, pitch, roll), ("yaw", "pitch", "roll"))]
    return _edit(scene, edits.rotate, *angles)


def exposure(scene, stops):
    """L' = 2^stops L. Returns the stored (9, 3) coefficients."""
    stops = _number(stops, "stops", "give photographic stops, e.g. 1 (twice as bright)")
    if abs(stops) > MAX_STOPS:
        raise DesignError(
            f"stops is {stops:g}: 2^{stops:g} takes the lighting beyond float32; give at most "
            f"±{MAX_STOPS:g} stops"
        )
    return _edit(scene, edits.exposure, stops)


def saturation(scene, amount, band=None):
    """Blend each coefficient's RGB with its grey: 0 grey, 1 unchanged, > 1 more colourful.

    ``band``: None (all), an int l, an iterable of l, or a key of ``BANDS``.
    """
    if isinstance(band, str):
        if band not in BANDS:
            raise DesignError(f"unknown band {band!r}: use one of {', '.join(BANDS)}")
        band = BANDS[band]
    elif isinstance(band, (int, np.integer)):
        band = (int(band),)
    amount = _number(amount, "amount", "give a factor, 0 grey, 1 unchanged, 2 twice as colourful")
    return _edit(scene, edits.saturation, amount, band, luminance())


def band_gains(scene, ambient=1.0, directional=1.0, quadratic=1.0):
    """Scale band l = 0, 1, 2 by ``ambient``, ``directional``, ``quadratic``."""
    factors = [_number(v, w, "give a factor, 1 unchanged") for v, w in zip(
        (ambient, directional, quadratic), ("ambient", "directional", "quadratic"))]
    return _edit(scene, edits.band_gains, *factors)


def flip_vertical(scene):
    """Mirror the lighting top to bottom: lit from below instead of above."""
    return _edit(scene, edits.flip_vertical)


def describe(scene):
    """Nine short strings: what each coefficient does in the scene's lighting."""
    return edits.describe_coefficients(scene_data.get_coefficients(scene), luminance())


def luminance():
    """The luminance weights of the file's working colour space (``core.colour``)."""
    return luminance_weights(compat.working_space())


def negative_warning(scene):
    """A sentence when the scene's 9-term irradiance goes below zero somewhere, else None."""
    return negative_light_warning(scene_data.get_coefficients(scene))


# -- the world's image -------------------------------------------------------------------------


def _world_image(scene, what, equirect=True):
    """The scene's world as a ``reader.ImageSource`` (``reader.read_world``), what Compute from
    World reads; DesignError when it is not an image (or not an equirect one, if asked),
    ``reader.WorldError`` for a broken world."""
    source = reader.read_world(scene)
    if isinstance(source, reader.ProceduralSource):
        raise DesignError(
            f"world '{source.world}' is not an Environment Texture image read directly "
            f"({source.reason}): {what} needs World Output ← Background ← Environment "
            "Texture [← Mapping ← Texture Coordinate]"
        )
    if equirect and source.projection != "EQUIRECTANGULAR":
        raise DesignError(
            f"{what} needs an equirectangular world image; image '{source.image.name}' of "
            f"world '{source.world}' is a {source.projection.replace('_', ' ').lower()}"
        )
    return source


def match_mapping(scene):
    """Rotate the coefficients by the world's Mapping node rotation, as Blender renders it.

    For coefficients computed from the image without the rotation (or from another world):
    afterwards they are what Compute from World gives with it. DesignError when the world
    has no Mapping rotation that SH Lighting reads.
    """
    values, gains = _edited_values(scene)
    image = _world_image(scene, "Match Mapping", equirect=False)
    if image.rotation is None:
        raise DesignError(
            f"world '{image.world}' has no Mapping node between Texture Coordinate and its "
            "Environment Texture: there is no rotation to match"
        )
    rotated = rotate_coefficients(values, mapping_rotation(image.rotation))
    return scene_data.store(
        scene, rotated, scene_data.edited(scene, "match_mapping"), gains=gains
    )


# -- windows -----------------------------------------------------------------------------------


LABELS = {"HANNING": "Hanning", "LANCZOS": "Lanczos", "MINIMAL": "Minimal"}


@dataclass(frozen=True, eq=False)
class WindowResult:
    """What ``apply_window`` did.

    kind, window (3,) w_0..w_2, coefficients (9, 3) stored. costs: {kind:
    ``core.windowing.WindowCost``} of every window (the one applied and the others, for
    comparison, at the same width) against the world image's brute-force irradiance, as
    fractions of its total light; empty, with ``note`` saying why (the operator's report
    says it too), when the coefficients are not those of an equirect world image.
    ``minimum``: computed only when read.
    """

    kind: str
    window: np.ndarray
    coefficients: np.ndarray
    costs: dict
    note: str

    @property
    def minimum(self):
        """(3,) exact min of the new E(n) per channel, computed when asked for."""
        return irradiance_minimum(self.coefficients).value

    @property
    def cost(self):
        """The ``WindowCost`` of the window applied, or None."""
        return self.costs.get(self.kind)


def window_for(kind, coeffs, width=DEFAULT_WIDTH):
    """The band factors (3,) of window ``kind`` (``WINDOWS``) for ``coeffs``; ``width`` > 0,
    inf for no window (``core.windowing``)."""
    hint = f"give a window width > 0, e.g. {DEFAULT_WIDTH:g} (inf: no window)"
    if not (isinstance(width, Real) and not isinstance(width, (bool, np.bool_))
            and width == math.inf):
        width = _number(width, "width", hint)
    if not width > 0:
        raise DesignError(f"width is {width:g}: {hint}")
    if kind == "HANNING":
        return windowing.hanning_window(width)
    if kind == "LANCZOS":
        return windowing.lanczos_window(width)
    if kind == "MINIMAL":
        return windowing.minimal_nonnegative_window(coeffs).window
    raise DesignError(f"unknown window {kind!r}: use one of {', '.join(WINDOWS)}")


def _world_costs(scene, coeffs, kind, window, width):
    """({kind: WindowCost} of every window against the world image, ""), or ({}, why not)."""
    try:
        image = _world_image(scene, "the error against the world")
    except DesignError:
        return {}, "no error vs the world shown: it is not an equirectangular world image"
    except ValueError as why:  # WorldError: no world, missing image, ...
        return {}, f"no error vs the world shown: {why}"
    match = compute.world_match(scene)
    if match.source is None or match.record.get("sun"):
        why = match.reason or "lights were extracted from the world"
        return {}, f"no error vs the world shown: the coefficients are not the world's ({why})"
    pixels = image.pixels()
    normals = spread_normals(COST_NORMALS)
    truth = map_irradiance(pixels, normals, image.strength, image.rotation)
    costs = {}
    for other in WINDOWS:
        try:
            w = window if other == kind else window_for(other, coeffs, width)
        except ValueError:  # no minimal window (L00 ≤ 0): nothing to compare with
            continue
        costs[other] = windowing.window_cost(coeffs, w, normals, truth)
    return costs, ""


def apply_window(scene, kind, width=DEFAULT_WIDTH):
    """Smooth the lighting with window ``kind`` ("HANNING", "LANCZOS" or "MINIMAL").

    ``width``: of Hanning and Lanczos (ignored by MINIMAL, the least smoothing that makes E
    non-negative everywhere). Returns a ``WindowResult``; when the coefficients are those of
    an equirect world image, it holds the error each window costs against that image's
    brute-force irradiance at ``COST_NORMALS`` normals.
    """
    coeffs = scene_data.get_coefficients(scene)  # the window is chosen for the lighting
    window = window_for(kind, coeffs, width)
    costs, note = _world_costs(scene, coeffs, kind, window, width)
    values, gains = _edited_values(scene)  # band factors commute with the gains
    stored = scene_data.store(
        scene, windowing.apply_window(values, window),
        scene_data.edited(scene, f"{kind} window"), gains=gains,
    )
    return WindowResult(kind, window, stored, costs, note)
