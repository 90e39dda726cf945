"""Where a scene keeps its SH lighting, and ``store``: the one function that writes it.

Custom properties that an Attribute node reads at render time in any Blender: c_lm in
``scene["sh_L00"]`` ... ``["sh_L22"]`` (RGB), the gains s_lm in ``["sh_L00_gain"]`` ... (read
through three driven copies, ``gain_packs``), the lighting L_lm = s_lm · c_lm;
``["sh_computed"]`` the Reset values, ``["sh_provenance"]`` where the values came from. ``store`` validates, writes c = coeffs and s = 1 (or c only, ``gains=
"KEEP"``), follows the ``animation`` policy (KEY, CLEAR, REFUSE) over animated properties,
records the provenance, tags the depsgraph, and returns a ``Stored`` array whose ``note`` says
what it did about animation. The properties and the policy in detail: docs/modules.md.
"""

import bpy
import numpy as np

from ...core.coefficients import FLOAT32_MAX, check_coefficients, real_number, type_name
from ...core.sh import COEFFICIENT_NAMES, COEFFICIENT_PHRASES
from . import gain_packs
from .animated import (  # noqa: F401 (the write policy's names, also used through here)
    ANIMATION_POLICIES,
    AnimatedError,
    animation_of,
    check_animation,
    clear_animation,
    listed,
)

# Attribute/custom-property names: "L1-1" -> "sh_L1m1" (no '-' inside an attribute name).
PROPERTY_NAMES = tuple("sh_" + name.replace("-", "m") for name in COEFFICIENT_NAMES)
GAIN_NAMES = tuple(name + "_gain" for name in PROPERTY_NAMES)
COMPUTED_PROPERTY = "sh_computed"
PROVENANCE_PROPERTY = "sh_provenance"
COMPUTED_PROVENANCE_PROPERTY = "sh_computed_provenance"
SOURCES = ("WORLD", "PRESET", "SCRIPT", "PHOTO")

# Soft limits of a channel: ±SOFT_RANGE × the largest magnitude of the stored values (a drag
# across the field spans a few times the lighting), at least SOFT_FLOOR.
SOFT_RANGE = 2.0
SOFT_FLOOR = 1e-3
GAIN_SOFT_MIN, GAIN_SOFT_MAX = -2.0, 4.0
PRECISION = 4
DEFAULT_ANIMATION = "KEY"
GAIN_POLICIES = ("UNIT", "KEEP")


class Stored(np.ndarray):
    """The (9, 3) float64 values ``store`` wrote (a plain array otherwise), with ``note``: what
    it did about animated properties, a sentence ("" if nothing)."""

    note = ""


def _stored(values, note):
    stored = np.array(values, dtype=np.float64).view(Stored)
    stored.note = note
    return stored


def has_coefficients(scene):
    """True when every one of the 9 coefficient properties exists on ``scene``."""
    return all(name in scene for name in PROPERTY_NAMES)


class PropertyError(ValueError):
    """A coefficient or gain custom property holds something the lighting cannot be made of
    (text, a dict, two numbers, NaN, beyond float32...): the message names the property, its
    value and how to put it right."""


def _plain(value):
    """An ID property's value as plain Python (lists and dicts for arrays and groups)."""
    if hasattr(value, "to_dict"):
        return value.to_dict()
    if hasattr(value, "to_list"):
        return value.to_list()
    return value


def _shown(value):
    text = repr(value)
    return f"{type_name(value)} ({text if len(text) <= 40 else text[:37] + '...'})"


def _bad(scene, name, why):
    """The PropertyError of property ``name``: ``why`` (a sentence naming "VALUE"), where,
    and what to do (fix the animation, else Repair)."""
    how = animation_of(scene, name)
    where = f"scene['{name}']"
    if how is not None:
        where += f" ({how}) at frame {scene.frame_current}"
        fix = "fix its keyframes or driver (Graph Editor, Drivers Editor), or delete them"
    else:
        fix = ("Repair in the SH Lighting panel (or Reset, Compute from World, a preset) "
               "writes a valid value")
    return PropertyError(f"{why.replace('VALUE', where, 1)}; {fix}")


# The readers refuse ±FLOAT32_MAX itself: it is what Blender makes of a key or driver beyond
# float32 (a driver computing 1e39 gives 3.40282e+38), which renders black.


def read_gain(scene, index):
    """s_lm of coefficient ``index`` as a float (1.0 when the property is missing), or a
    PropertyError naming a value that is not a finite number within float32."""
    name = GAIN_NAMES[index]
    if name not in scene:
        return 1.0
    try:
        return real_number(_plain(scene[name]), "VALUE", limit=FLOAT32_MAX)
    except ValueError as error:
        raise _bad(scene, name, str(error)) from None


def read_channel(scene, index):
    """c_lm of coefficient ``index``, 3 floats, or a PropertyError naming what is wrong."""
    name = PROPERTY_NAMES[index]
    value = _plain(scene[name])
    if isinstance(value, str) or not isinstance(value, (list, tuple)) or len(value) != 3:
        raise _bad(scene, name, f"VALUE is {_shown(value)}, not 3 numbers (R, G, B)")
    try:
        return [real_number(v, f"VALUE channel {c}", limit=FLOAT32_MAX)
                for v, c in zip(value, "RGB")]
    except ValueError as error:
        raise _bad(scene, name, str(error)) from None


def gain(scene, index):
    """s_lm of coefficient ``index`` (``read_gain``)."""
    return read_gain(scene, index)


def get_coefficients(scene):
    """The scene's (9, 3) float64 lighting L_lm = s_lm · c_lm, read and checked: the one
    reader of the properties (panel, API, export, render). A LookupError if never set, a
    PropertyError (a ValueError) naming the first property that is not valid."""
    missing = [name for name in PROPERTY_NAMES if name not in scene]
    if missing:
        raise LookupError(
            f"scene '{scene.name}' has no SH lighting coefficients yet ({', '.join(missing)} "
            "missing): run Compute from World or set them first"
        )
    s = np.array([read_gain(scene, index) for index in range(9)])
    return get_channels(scene) * s[:, None]


def get_channels(scene):
    """The scene's (9, 3) float64 channels c_lm, without the gains (``read_channel``)."""
    return np.array([read_channel(scene, index) for index in range(9)], dtype=np.float64)


def problems(scene):
    """[(property name, message)] of every coefficient and gain property of ``scene`` that
    ``get_coefficients`` would refuse, and of every broken pack of the gains
    (``gain_packs.broken``); empty when all are valid or none exist."""
    found = []
    for index, (name, gain_name) in enumerate(zip(PROPERTY_NAMES, GAIN_NAMES)):
        for prop, read in ((name, read_channel), (gain_name, read_gain)):
            if prop not in scene:
                continue
            try:
                read(scene, index)
            except PropertyError as error:
                found.append((prop, str(error)))
    return found + gain_packs.broken(scene, GAIN_NAMES)


def repair(scene):
    """Write a valid value over every invalid, unanimated coefficient or gain property: a
    gain 1, a channel its Reset value (the last computed from the world) or 0; broken packs
    of the gains are made again (``gain_packs.ensure``). Returns the names repaired; a
    PropertyError, nothing changed, when an invalid one is animated (its keyframes or driver
    would write it again)."""
    bad = [name for name, _message in problems(scene) if name not in gain_packs.PACK_NAMES]
    animated_bad = {name: how for name, how in animated(scene, bad).items()}
    if animated_bad:
        name = sorted(animated_bad)[0]
        index = (PROPERTY_NAMES + GAIN_NAMES).index(name) % 9
        (read_channel if name in PROPERTY_NAMES else read_gain)(scene, index)  # its message
    try:
        computed = get_computed(scene)
    except PropertyError:
        computed = None
    for name in bad:
        if name in GAIN_NAMES:
            scene[name] = 1.0
        else:
            row = PROPERTY_NAMES.index(name)
            scene[name] = [float(v) for v in computed[row]] if computed is not None else [0.0] * 3
    packs = [name for name, _message in gain_packs.broken(scene, GAIN_NAMES)]
    if packs:
        gain_packs.ensure(scene, GAIN_NAMES)
    if bad or packs:
        ensure_ui(scene)
        scene.update_tag()
        redraw()
    return bad + packs


def validate(coeffs):
    """A finite (9, 3) float64 copy of ``coeffs`` or a ValueError saying what is wrong: the one
    validation before coefficients are stored (``core.coefficients.check_coefficients``:
    numbers only, within Blender's float32 range)."""
    return check_coefficients(coeffs)


def _check_provenance(provenance):
    if not isinstance(provenance, dict) or provenance.get("source") not in SOURCES:
        raise ValueError(
            f"provenance must be a dict with 'source' one of {', '.join(SOURCES)}, "
            f"got {provenance!r}"
        )
    for key, value in provenance.items():
        if not isinstance(key, str) or not isinstance(value, (str, int, float, bool, list)):
            raise ValueError(f"provenance entry {key!r}: {value!r} is not text, number or list")
    return dict(provenance)


def animated(scene, names=None):
    """{name: "driven" | "keyframed"} of the coefficient and gain properties (or ``names``)
    that are animated on ``scene`` (``animated.animated``)."""
    from . import animated as module

    return module.animated(scene, PROPERTY_NAMES + GAIN_NAMES if names is None else names)


def gains_animated(scene):
    """True when any gain s_lm of ``scene`` is keyframed or driven."""
    return bool(animated(scene, GAIN_NAMES))


def add_missing_gains(scene):
    """Gains s = 1 for the coefficients of ``scene`` that have none (files from before the
    gains render as before), and the packs the node groups read them through
    (``gain_packs``), with their UI data and a tag; returns the names written."""
    missing = [g for n, g in zip(PROPERTY_NAMES, GAIN_NAMES) if n in scene and g not in scene]
    for name in missing:
        scene[name] = 1.0
    if has_coefficients(scene):
        missing += gain_packs.ensure(scene, GAIN_NAMES)
    if missing:
        ensure_ui(scene)
        scene.update_tag()
    return missing


def store(scene, coeffs, provenance, animation=DEFAULT_ANIMATION, gains="UNIT"):
    """Write (9, 3) L_lm on ``scene`` as c = ``coeffs``, s = 1: the one write of coefficients.

    ``provenance``: a dict with "source" (``SOURCES``) and what the writer knows of it; a
    "WORLD" record without "edit" (values as computed) also makes them the Reset values.
    ``animation``: what to do when a written property is animated (``ANIMATION_POLICIES``,
    module docstring). ``gains``: "UNIT" writes s = 1; "KEEP" writes the channels c only
    (``coeffs`` are then c, the lighting s · c). Validates first (ValueError, nothing
    changed), then writes, keys or clears, records, sets the UI data, tags the scene for the
    depsgraph (the viewports and the next render see the new values) and redraws the panels.
    Returns the stored float64 copy, a ``Stored`` whose ``note`` says what was done about
    animated properties.
    """
    c = validate(coeffs)
    record = _check_provenance(provenance)
    if gains not in GAIN_POLICIES:
        raise ValueError(f"gains must be one of {', '.join(GAIN_POLICIES)}, got {gains!r}")
    written = PROPERTY_NAMES + (GAIN_NAMES if gains == "UNIT" else ())
    found = check_animation(scene, written, animation)
    note = ""
    if found and animation == "CLEAR":
        clear_animation(scene, found)
        note = f"animation of {', '.join(sorted(found))} removed"
    for name, gain_name, rgb in zip(PROPERTY_NAMES, GAIN_NAMES, c):
        scene[name] = [float(v) for v in rgb]
        if gains == "UNIT":
            scene[gain_name] = 1.0
    if found and animation == "KEY":
        frame = scene.frame_current
        for name in found:
            scene.keyframe_insert(f'["{name}"]', frame=frame)
        note = f"keyed at frame {frame} because {listed(found)} animated"
    gain_packs.ensure(scene, GAIN_NAMES)
    if record["source"] == "WORLD" and "edit" not in record:
        scene[COMPUTED_PROPERTY] = [float(v) for v in c.ravel()]
        scene[COMPUTED_PROVENANCE_PROPERTY] = record
    scene[PROVENANCE_PROPERTY] = record
    ensure_ui(scene)
    scene.update_tag()
    redraw()
    return _stored(c if gains == "UNIT" else get_coefficients(scene), note)


def reset(scene):
    """Store the values last computed from the world again (Reset), with their provenance.

    A LookupError if nothing was computed yet. Returns the restored (9, 3) array.
    """
    computed = get_computed(scene)
    if computed is None:
        raise LookupError("Nothing to reset to: run Compute from World first")
    return store(scene, computed, computed_provenance(scene) or {"source": "WORLD"})


def edited(scene, edit):
    """The provenance of the scene's values after design edit ``edit`` (e.g. "exposure"):
    where they came from, with "edit" set."""
    record = provenance(scene)
    record["edit"] = str(edit)
    return record


def provenance(scene):
    """The recorded provenance of the stored values as a plain dict ({} when unknown)."""
    return _as_dict(scene.get(PROVENANCE_PROPERTY))


def computed_provenance(scene):
    """The provenance of the Reset values ({} when unknown)."""
    return _as_dict(scene.get(COMPUTED_PROVENANCE_PROPERTY))


def _as_dict(value):
    return value.to_dict() if hasattr(value, "to_dict") else {}


def get_computed(scene):
    """The (9, 3) values last computed from the world, or None."""
    if COMPUTED_PROPERTY not in scene:
        return None
    value = _plain(scene[COMPUTED_PROPERTY])
    try:
        if isinstance(value, str) or not isinstance(value, (list, tuple)) or len(value) != 27:
            raise ValueError(f"VALUE is {_shown(value)}, not 27 numbers")
        numbers = [real_number(v, "VALUE") for v in value]
    except ValueError as error:
        raise PropertyError(
            f"{str(error).replace('VALUE', f'scene[{COMPUTED_PROPERTY!r}]', 1)}: the Reset "
            "values are lost; Compute from World writes them again"
        ) from None
    return np.array(numbers, dtype=np.float64).reshape(9, 3)


def coefficient_description(index):
    """The tooltip of coefficient ``index``: name, what it does, what the numbers are."""
    return (
        f"{COEFFICIENT_NAMES[index]}, {COEFFICIENT_PHRASES[index]}: signed RGB coefficient "
        "c_lm (radiance, Blender world axes); the lighting is gain × c_lm; keyframable"
    )


def gain_description(index):
    """The tooltip of gain ``index``."""
    return (
        f"Strength of the {COEFFICIENT_PHRASES[index]} term ({COEFFICIENT_NAMES[index]}): 1 as "
        "computed (after Compute, Reset or a preset), 0 removes it, 2 doubles it, below 0 "
        "turns it over; press I to keyframe. The swatch beside it is the term's colour. "
        "(The paper's gain s_lm: the lighting is s_lm × c_lm)"
    )


def ensure_ui(scene):
    """Give the coefficient and gain custom properties their UI data: descriptions, soft
    limits following the stored values, plain number fields (subtype NONE, which neither
    clamps to 0-1 nor shows a colour swatch)."""
    values = [list(scene[name]) for name in PROPERTY_NAMES if name in scene]
    largest = float(np.max(np.abs(values))) if values else 0.0
    soft = max(SOFT_RANGE * largest, SOFT_FLOOR)
    for index, (name, gain_name) in enumerate(zip(PROPERTY_NAMES, GAIN_NAMES)):
        if name in scene:
            scene.id_properties_ui(name).update(
                subtype="NONE", description=coefficient_description(index),
                soft_min=-soft, soft_max=soft, precision=PRECISION, step=1,
            )
        if gain_name in scene:
            scene.id_properties_ui(gain_name).update(
                subtype="NONE", description=gain_description(index), default=1.0,
                soft_min=GAIN_SOFT_MIN, soft_max=GAIN_SOFT_MAX, precision=3, step=1,
            )


def redraw():
    """Redraw every area of every window (the panels show the new values at once); nothing
    in background mode, where there are no windows."""
    window_manager = getattr(bpy.context, "window_manager", None)
    if bpy.app.background or window_manager is None:
        return
    for window in window_manager.windows:
        for area in window.screen.areas:
            area.tag_redraw()
