"""Public scripting API of SH Lighting; works in background mode without any UI context.

    coeffs = api.compute_from_world(scene)        # (9, 3) L_lm, stored on the scene too
    coeffs[2] *= 2.0                              # twice the light from above vs below
    api.set_coefficients(scene, coeffs)
    api.apply_to_materials(bpy.data.materials, scene)

Coefficients are raw radiance L_lm (Ramamoorthi and Hanrahan 2001, eq. 10) in the order of
``core.sh.COEFFICIENT_NAMES``, RGB per row, Blender world axes; errors carry the operators'
messages. Also re-exported: presets, design edits, lights, transfer, photo (``__all__``).
"""

import bpy

from .blender.photo import fit as _photo
from .blender.photo.fit import SecondPhoto
from .blender.data import scene_data as _scene_data
from .blender.design.edits import (  # lighting design: exact edits and windows
    DesignError,
    apply_window,
    band_gains,
    describe,
    exposure,
    flip_vertical,
    match_mapping,
    negative_warning,
    rotate,
    saturation,
)
from .blender.design import lights as _lights
from .blender.luminaire import build as _luminaire
from .blender.presets.preset_io import (
    FORMATS,
    export_preset,
    import_preset,
    remove_user_preset,
    save_user_preset,
    shipped_presets,
    user_presets,
)  # presets and interop: JSON, three.js, glTF, Filament
from .blender.shading import materials as _materials
from .blender.shading import nodes as _nodes
from .blender.transfer import apply as _transfer_apply
from .blender.transfer import bake as _transfer
from .blender.transfer import on_apply as _on_apply
from .blender.design import compute as _design_compute
from .blender.world import reader as _world
from .blender import world_edit as _world_edit
from .formats.presets import PresetError

# What the command line (sh_lighting.cli) uses of the Blender layer, through here only.
from .blender.data.compat import eevee_engine_id
from .blender.data.scene_data import has_coefficients
from .blender.data.scene_data import validate as validate_coefficients
from .blender.presets.preset_io import (
    export_coefficients,
    read_preset_file,
    scene_metadata,
    world_environment,
)
from .blender.shading.materials import materials_of, objects_without_material
from .blender.shading.notes import shared_scene_notes
from .blender.world.hdri import (
    ERROR_NORMALS as HDRI_ERROR_NORMALS,
    hdri_lights,
    hdri_metadata,
    read_hdri,
)

WorldError = _world.WorldError
AnimatedError = _scene_data.AnimatedError

__all__ = [
    # computing, storing and applying the coefficients
    "WorldError", "AnimatedError", "compute_from_world", "get_coefficients", "get_computed", "get_provenance",
    "set_coefficients",
    "reset", "ensure_node_group", "apply_to_materials", "remove_from_materials",
    "edit_world", "edit_world_report", "remove_world_edit",
    # presets and interop
    "FORMATS", "PresetError", "export_preset", "import_preset", "shipped_presets",
    "user_presets", "save_user_preset", "remove_user_preset",
    # lighting design
    "DesignError", "rotate", "match_mapping", "exposure", "saturation", "band_gains",
    "flip_vertical", "apply_window", "split_sun", "describe", "negative_warning",
    "extract_lights",
    # for the command line
    "eevee_engine_id", "has_coefficients", "validate_coefficients",
    "export_coefficients", "read_preset_file", "scene_metadata", "world_environment",
    "materials_of", "objects_without_material", "shared_scene_notes", "HDRI_ERROR_NORMALS",
    "hdri_lights", "hdri_metadata", "read_hdri",
    # precomputed radiance transfer (shadows and bounce light)
    "TransferError", "bake_transfer", "transfer_refusal", "transfer_status", "apply_transfer",
    "delete_transfer", "apply_with_shadows",
    # lighting from a photo of a grey ball
    "coefficients_from_photo", "photo_exposure", "SecondPhoto", "detect_photo_ball",
    # measured luminaires (IES, EULUMDAT)
    "PhotometryError", "LuminaireFit", "add_luminaire", "refit_luminaire", "remove_luminaire",
    "luminaire_lit_distance",
    "set_luminaire_temperature", "luminaire_sh_at",
]

TransferError = _transfer.TransferError
PhotometryError = _luminaire.PhotometryError
LuminaireFit = _luminaire.FitSettings


def add_luminaire(scene, path, collection=None, location=(0.0, 0.0, 3.0),
                  rotation=(0.0, 0.0, 0.0), fit=LuminaireFit(), power=1.0):
    """A measured luminaire from an IES or EULUMDAT file (``blender.luminaire.build``): a point
    light aimed down its local −Z with Blender's IES node (Cycles, exact) and up to
    ``fit.max_lamps`` fitted spot/point lights as its children (EEVEE). ``power`` 1 W renders
    the file's candela. A bad file raises ``PhotometryError`` (one line naming the line) and
    creates nothing. ``fit.near_distance`` (metres to the nearest lit surface; 0, the default:
    far field) below 5 × the luminous opening repeats the lamps over the opening's cells, with
    one Cycles IES light per cell. Returns a ``LuminaireInfo`` (``.report()``, ``.root``,
    ``.lamps``, ``.cycles_cells``)."""
    return _luminaire.add_luminaire(scene, path, collection, location, rotation, fit, power)


def refit_luminaire(scene, root, fit=LuminaireFit()):
    """Fit the EEVEE lamps of the luminaire ``root`` again with other ``fit`` settings."""
    return _luminaire.refit(scene, root, fit)


def luminaire_lit_distance(scene, root):
    """Metres from the luminaire ``root`` along its axis to the first surface it meets, or
    None: a ``fit.near_distance`` read from the scene (``refit_luminaire`` with it)."""
    return _luminaire.lit_distance(scene, root)


def set_luminaire_temperature(root, kelvin):
    """Colour the luminaire ``root`` as a blackbody at ``kelvin`` (800-20000 K), in Cycles
    and EEVEE (Blender's Light Temperature where it has one, else its colour)."""
    _luminaire.set_colour_temperature(root, kelvin)


def luminaire_sh_at(scene, root, point):
    """The (9, 3) L_lm the luminaire ``root`` adds at the world ``point`` (beside the scene's
    nine: a source of irradiance I/r² from its direction)."""
    return _luminaire.luminaire_sh_at(scene, root, point)


def remove_luminaire(scene, root):
    """Delete a luminaire the add-on made: its light, lamps and packed IES text."""
    _luminaire.remove_luminaire(scene, root)


def bake_transfer(scene, objects, samples=_transfer.DEFAULT_SAMPLES, report=print,
                  error_target=None, store="AUTO"):
    """Bake the transfer T_lm (Sloan, Kautz and Snyder 2002) of the meshes ``objects`` in
    ``scene`` with Cycles: per face corner, the irradiance each SH basis function gives
    through the scene's shadows and interreflection, stored in the meshes' colour attributes
    sh_T00 ... sh_T22. ``report(text)`` gets a line per basis function with its time.
    ``error_target`` (a fraction, e.g. 0.01): choose the samples for that noise instead.
    ``store``: "AUTO" bakes meshes too coarse for a shadow at their corners per texel (a
    lightmap atlas on a UV map the add-on adds), "CORNERS" or "TEXELS" every mesh so.
    Returns a ``BakeInfo`` (objects, corners, vertices, samples, seconds, basis_seconds,
    notes, texel_objects, texels); a ``TransferError`` (nothing changed) for objects that
    cannot be baked (modifiers, linked duplicates, no faces, not meshes, hidden)."""
    return _transfer.bake_transfer(scene, objects, samples, report, error_target, store)


def transfer_refusal(scene, obj, store="AUTO"):
    """Why ``obj`` cannot be transfer-baked in ``scene`` with ``store`` (``bake_transfer``;
    one line with what to do), or None."""
    return _transfer.refusal(scene, obj, store=store)


def transfer_status(scene, obj):
    """(state, message) of ``obj``'s bake: "NONE", "OK" or "STALE" (edited, moved, or what
    the bake saw of the scene's rendered objects changed: placement, geometry, shape keys,
    modifiers, render visibility, collections, ray visibility; bake again). Evaluated at
    once: a script's edit counts before the view layer updates."""
    return _transfer.status(scene, obj)


def apply_transfer(objects, scene=None, mode="KEEP_BSDF"):
    """Light the materials of the baked ``objects`` by the "SH Transfer" group (mode
    "KEEP_BSDF" or "EMISSION", as ``apply_to_materials``); returns (changed, skipped).
    ``remove_from_materials`` takes it out again."""
    return _transfer_apply.apply_transfer(objects, scene or bpy.context.scene, mode)


def apply_with_shadows(scene, objects=None, mode="TRANSFER", report=print):
    """Apply's "Keep BSDF with Shadows" (EEVEE's Default): bake the transfer of ``objects``
    (default: the scene's) where it is missing or stale, then Keep BSDF on every material of
    the scene, the baked objects' through the transfer. ``mode`` "AUTO" bakes only when
    estimated at most ``AFFORDABLE_SECONDS``. Returns (result, lit, info, notes); a
    TransferError from the bake changes nothing."""
    objects = list(scene.objects) if objects is None else list(objects)
    return _on_apply.bake_and_apply(scene, objects, mode, report)


AFFORDABLE_SECONDS = _on_apply.AFFORDABLE_SECONDS


def delete_transfer(obj):
    """Take the transfer out of ``obj``'s materials and delete its transfer attributes and
    record; True if it had any."""
    _transfer_apply.remove_transfer_from(
        [slot.material for slot in obj.material_slots if slot.material is not None])
    return _transfer.remove_transfer(obj)


def extract_lights(scene, count=3, error_target=None, size_limit=_lights.SIZE_LIMIT,
                   nonfinite="raise"):
    """Take up to ``count`` compact bright sources of the world image out as Sun lights and
    store the coefficients of the rest (``blender.design.lights``); an ``error_target``
    (fraction of the world's light) stops earlier; sources wider than ``size_limit`` (radians
    across) stay in the SH. The rest also becomes the Reset values; the lights it made earlier
    (never an artist's, nor a duplicate of one) are updated or deleted, and Compute from World
    deletes them. Returns a ``LightsInfo`` (``.report()``: one line saying what was found and
    why not more). ``nonfinite`` "zero": NaN/Inf texels of the world image count as black. An
    edited world (``edit_world``) takes the new values as its own."""
    info = _lights.extract_lights(scene, count, error_target, size_limit, nonfinite)
    _world_edit.refresh(scene)
    return info


def split_sun(scene):
    """The world image's sun as one Sun light: ``extract_lights(scene, count=1)``."""
    return extract_lights(scene, count=1)


def compute_from_world(scene, capture_width=None, nonfinite="raise"):
    """Project ``scene``'s world onto 9 SH coefficients and store them on the scene.

    Reads the Environment Texture image directly when the world is one, else renders a
    ``capture_width`` × ``capture_width/2`` equirectangular capture (default: the scene's
    override, else the add-on preferences, else 256). The result also becomes the Reset
    values, and the scene records where it came from (``get_provenance``). ``nonfinite``
    "zero": NaN/Inf texels of the world image count as black ("raise" refuses them). Returns
    the (9, 3) float64 array; raises ``WorldError`` (a ValueError) with a
    user-facing message, leaving the scene unchanged, when the world cannot be read.
    """
    # also deletes extracted lights; an edited world (``edit_world``) takes the new values
    coeffs = _design_compute.compute_from_world(scene, capture_width, nonfinite=nonfinite)[0]
    _world_edit.refresh(scene)
    return coeffs


def coefficients_from_photo(scene, path, circle, **options):
    """Fit the lighting to a photo of a grey (matte) ball and store it on ``scene``
    (provenance "PHOTO": file, circle, camera, the fit's report).

    ``circle``: (cx, cy, r), the ball's centre and radius in pixels from the photo's top-left
    corner. ``options`` (``blender.photo.coefficients_from_photo``): ``camera_object``
    (default the scene's camera) or ``direction`` and ``roll`` with ``projection``
    ("ORTHO"/"PERSP"), ``focal_mm``, ``sensor_mm``; ``albedo`` (0.18), ``margin`` (0.05 of
    the radius), ``prior`` ("mirror", "ambient", "chrome", "photo", "none"), ``chrome`` (for
    "chrome": a mirror-ball image file; None: the scene's world), ``second`` (for "photo": a
    ``SecondPhoto(path, circle, camera_object=None, direction=None, roll=0.0)``), ``clip``,
    ``store`` (True).
    Returns (the (9, 3) coefficients, the ``core.photo.PhotoFit`` report: residual,
    condition, weak_terms, used, clipped, summary()); a ValueError with one line, the scene
    unchanged, when the photo cannot give lighting.
    """
    return _photo.coefficients_from_photo(scene, path, circle, **options)


def detect_photo_ball(path):
    """A suggested circle for ``coefficients_from_photo``: the ball found in the photo at
    ``path`` (``core.ball_detect``: ``.circle`` (cx, cy, r) in pixels, ``.score`` the share of
    its rim on the circle, ``summary()``); a ValueError when none is found. Check it before
    using it: it is the most circular outline in the photo, not necessarily the grey ball."""
    return _photo.detect_circle(path)


def photo_exposure(scene, fit, chrome=None):
    """Both balls: how a grey-ball ``fit`` (from ``coefficients_from_photo``) compares with a
    chrome ball: the mirror-ball image file ``chrome``, or the scene's world when None (a
    chrome ball's mirror-ball image, or an HDRI): ``.scale``, the exposure making the grey
    ball's L00 agree, and ``.seen``/``.everywhere``, how far the rest then disagree (RMS of
    E, / its mean); ``summary()`` says it in one line."""
    return _photo.exposure_match(scene, fit, chrome)


def get_coefficients(scene):
    """The scene's (9, 3) float64 lighting L_lm = s_lm · c_lm (each coefficient's gain times
    its RGB custom property); a LookupError if they were never set."""
    return _scene_data.get_coefficients(scene)


def get_provenance(scene):
    """Where the stored values came from, as recorded when they were stored: a dict with
    "source" ("WORLD", "PRESET", "SCRIPT" or "PHOTO") and what is known of it ({} if unknown)."""
    return _scene_data.provenance(scene)


def get_computed(scene):
    """The (9, 3) values last computed from the world (what Reset restores), or None."""
    return _scene_data.get_computed(scene)


def set_coefficients(scene, coeffs, provenance=None, animation="KEY"):
    """Store (9, 3) L_lm on ``scene`` (a ValueError, nothing changed, if not finite 9×3):
    the RGB properties get ``coeffs``, the gains 1.

    ``provenance``: what to record about the values (default ``{"source": "SCRIPT"}``).
    ``animation``: when a property written is keyframed or driven, "KEY" (default) keys the
    new value at the current frame (a driven one is refused: ``AnimatedError`` naming it),
    "CLEAR" removes its animation first, "REFUSE" raises ``AnimatedError``
    (``blender.scene_data``). The scene is tagged, so open viewports show the new values at
    once, and materials that SH Lighting was applied to follow at the next render. Returns the
    stored float64 copy; its ``note`` says what was done about animation ("" if nothing).
    """
    return _scene_data.store(scene, coeffs, provenance or {"source": "SCRIPT"}, animation)


def reset(scene):
    """Set the coefficients back to the values last computed from the world.

    A LookupError if nothing was computed yet. Returns the restored (9, 3) array.
    """
    return _scene_data.reset(scene)


def ensure_node_group():
    """The file's "SH Irradiance" shader node group (all nine terms, reading the coefficients
    of whatever scene renders it), created once, its nodes rebuilt."""
    return _nodes.ensure_node_group()


def apply_to_materials(materials, scene=None, mode=_materials.DEFAULT_MODE):
    """Add SH irradiance lighting to ``materials`` (any iterable of Material), using the
    coefficients of ``scene`` (default: the context scene). ``mode``: "KEEP_BSDF" (default:
    the BSDF stays, SH replaces the world's diffuse light, which Cycles then no longer gives
    to diffuse rays) or "EMISSION" (the SH emission alone). Returns which materials were
    changed and which were skipped, with reasons; a ValueError for an unknown mode. Materials
    lit by the transfer (``apply_transfer``) keep it, in ``mode``.
    """
    if scene is None:
        scene = bpy.context.scene
    return _transfer_apply.apply_keeping_transfer(_material_list(materials), scene, mode)[0]


def edit_world(scene=None):
    """Edit World: add the designed change of ``scene``'s lighting to its world (the default
    Apply in Cycles, docs/blender.md); returns the ``core.world_edit.Clamping`` measured.
    A ValueError, nothing changed, when the world cannot be edited."""
    return _world_edit.edit_world(scene or bpy.context.scene)


def edit_world_report(scene, clamping):
    """What Apply says after ``edit_world``: (its line on the edited world, the clamp's line
    or None when the clamp changed next to nothing)."""
    return _world_edit.applied_message(scene, clamping), _world_edit.clamping_note(clamping)


def remove_world_edit(scene=None):
    """Take the World Edit out of ``scene``'s world, restoring it; True if there was one."""
    scene = scene or bpy.context.scene
    return _world_edit.remove(scene.world)


def remove_from_materials(materials):
    """Undo ``apply_to_materials`` on ``materials`` (and give the worlds their diffuse
    visibility back once no material keeps its BSDF); returns which were changed or skipped."""
    return _materials.remove_from_materials(_material_list(materials))


def _material_list(materials):
    """``materials`` as a list, or a TypeError saying what to pass (one Material: [it])."""
    if isinstance(materials, bpy.types.Material):
        raise TypeError(f"materials is one Material ({materials.name!r}): pass a list, [material]")
    try:
        return list(materials)
    except TypeError:
        raise TypeError(
            f"materials is {type(materials).__name__}: pass an iterable of Material, "
            "e.g. bpy.data.materials or [material]"
        ) from None

