"""Which SH group a file's lighting needs: the coefficient values of every scene at every
keyed frame, handed to ``core.pruning`` (all the math is there).

A scene's *samples* are its current values plus, when ``scene["sh_L.."]`` are keyframed, their
values at every frame of the frame range and of the preview range (Bézier curves can overshoot
between keys, so every frame is evaluated, not only the keys; time remapping adds the remapped
frames). Only the frames where some curve is not flat are evaluated: outside the span of the
keys, curves without modifiers and with constant extrapolation hold their end values.
Values that the F-curves of the active action cannot tell (a driver, an NLA strip, a blended
or partial active action on a coefficient) make the scene *unknown*: every term is kept, RGB
math, and a clamp unless the scene says Never.

The group serves every scene of the file, so the needed terms are those of all scenes with
coefficients, each judged with its own tolerance; the clamp is added when any scene asks for
it (Always) or needs it (Auto and E < 0 somewhere); a scene set to Never cannot veto that.
"""

import hashlib
from collections import OrderedDict
from dataclasses import dataclass, field

import numpy as np

from ..core import pruning
from ..core.sh import COEFFICIENT_NAMES
from . import compat, scene_data

CLAMP_MODES = ("AUTO", "ALWAYS", "NEVER")
# data_path of each coefficient's custom property, both quote styles -> coefficient index.
_PATHS = {}
for _index, _name in enumerate(scene_data.PROPERTY_NAMES):
    _PATHS[f'["{_name}"]'] = _index
    _PATHS[f"['{_name}']"] = _index

# Samples known to give E >= 0 everywhere: (kept terms, float64 bytes of one (9, 3) sample),
# least recently used first. Each costs an exact minimum (ms) to decide, and refits repeat
# them: the keyed frames do not change when a slider stores new current values.
NON_NEGATIVE_CACHE_SIZE = 4096
_non_negative = OrderedDict()


@dataclass(frozen=True)
class SceneSamples:
    samples: np.ndarray  # (S, 9, 3)
    unknown: bool  # some coefficient is animated in a way not sampled here
    signature: str  # digest of the animation and frame ranges (for the "Refit needed" hint)


@dataclass(frozen=True)
class Fit:
    terms: tuple
    scalar: bool
    clamp: bool
    bound: float = 0.0
    bound_absolute: float = 0.0
    scenes: dict = field(default_factory=dict)  # name -> {"animation": signature}


def fit_settings(scene):
    """(relative tolerance, clamp mode) of ``scene``; the defaults when not registered."""
    settings = getattr(scene, "sh_lighting", None)
    relative = getattr(settings, "fit_tolerance", pruning.DEFAULT_RELATIVE_TOLERANCE)
    mode = getattr(settings, "clamp_mode", "AUTO")
    return float(relative), mode if mode in CLAMP_MODES else "AUTO"


def _coefficient_curves(scene):
    """[(index, channel, fcurve)] of the active action's coefficient curves that animate
    (unmuted, with keys or modifiers: Blender skips empty curves)."""
    found = []
    for curve in compat.action_fcurves(scene):
        index = _PATHS.get(curve.data_path)
        if index is None or not 0 <= curve.array_index < 3 or curve.mute:
            continue
        if len(curve.keyframe_points) or len(curve.modifiers):
            found.append((index, curve.array_index, curve))
    return found


def _is_unknown(scene, curves=None):
    """True when the coefficients' values are not those of the active action's F-curves alone
    (``curves``: ``_coefficient_curves(scene)`` if the caller has them)."""
    animation = scene.animation_data
    if animation is None:
        return False
    if any(_PATHS.get(d.data_path) is not None for d in animation.drivers):
        return True
    if any(_PATHS.get(c.data_path) is not None for c in compat.nla_fcurves(scene)):
        return True
    blended = animation.action_blend_type != "REPLACE" or animation.action_influence != 1.0
    if not blended:
        return False
    return bool(_coefficient_curves(scene) if curves is None else curves)


def _frames(scene, curves):
    """Every frame at which the coefficients can differ from each other (see the docstring)."""
    ranges = [(scene.frame_start, scene.frame_end)]
    if scene.use_preview_range:
        ranges.append((scene.frame_preview_start, scene.frame_preview_end))
    frames = {float(scene.frame_current)}
    for first, last in ranges:
        frames.update(float(f) for f in range(first, last + 1))
    remap = scene.render.frame_map_old / scene.render.frame_map_new
    if remap != 1.0:
        frames |= {f * remap for f in frames}
    flat_outside = all(
        c.extrapolation == "CONSTANT" and len(c.modifiers) == 0 and len(c.keyframe_points)
        for _i, _ch, c in curves
    )
    if flat_outside:
        first = min(c.keyframe_points[0].co[0] for _i, _ch, c in curves)
        last = max(c.keyframe_points[-1].co[0] for _i, _ch, c in curves)
        frames = {min(max(f, first), last) for f in frames}
    return sorted(frames)


def animation_signature(scene, curves=None, unknown=None):
    """A digest of everything the sampled values depend on besides the current values.

    ``curves``, ``unknown``: ``_coefficient_curves(scene)`` and ``_is_unknown(scene)`` when the
    caller has them already (else found here).
    """
    if curves is None:
        curves = _coefficient_curves(scene)
    if unknown is None:
        unknown = _is_unknown(scene, curves)
    h = hashlib.blake2b(digest_size=16)
    r = scene.render
    h.update(
        repr(
            (
                scene.frame_start,
                scene.frame_end,
                scene.use_preview_range,
                scene.frame_preview_start,
                scene.frame_preview_end,
                r.frame_map_old,
                r.frame_map_new,
                unknown,
            )
        ).encode()
    )
    for index, channel, curve in curves:
        points = curve.keyframe_points
        h.update(repr((index, channel, curve.extrapolation, len(curve.modifiers))).encode())
        for key in ("co", "handle_left", "handle_right"):
            values = np.zeros(2 * len(points), dtype=np.float32)
            points.foreach_get(key, values)
            h.update(values.tobytes())
        for key in ("interpolation", "easing"):
            values = np.zeros(len(points), dtype=np.int32)
            points.foreach_get(key, values)
            h.update(values.tobytes())
        if any(p.interpolation in ("BACK", "ELASTIC") for p in points):
            h.update(repr([(p.back, p.amplitude, p.period) for p in points]).encode())
        for modifier in curve.modifiers:  # modifiers: flag only that they changed somehow
            h.update(repr((modifier.type, modifier.mute, modifier.influence)).encode())
    return h.hexdigest()


def scene_samples(scene):
    """``SceneSamples`` of a scene that has coefficients (current values + keyed frames)."""
    current = scene_data.get_coefficients(scene)
    curves = _coefficient_curves(scene)
    samples = [current]
    if curves:
        frames = _frames(scene, curves)
        block = np.repeat(current[None], len(frames), axis=0)
        for index, channel, curve in curves:
            block[:, index, channel] = [curve.evaluate(f) for f in frames]
        samples.extend(block)
    unknown = _is_unknown(scene, curves)
    signature = animation_signature(scene, curves, unknown)
    return SceneSamples(np.array(samples), unknown, signature)


def can_be_negative(samples, kept):
    """``pruning.can_be_negative(samples, kept)``, remembering the samples found non-negative.

    The same answer: E < 0 for some sample iff for some distinct sample not known to be
    non-negative. Only those are tested, in one call; when it says False they are all
    remembered (bounded LRU). A True answer is not attributed to a sample (finding which one
    could cost an exact minimum per sample), so it is recomputed the next time.
    """
    s = pruning.as_samples(samples)  # its errors, before anything is remembered
    kept = tuple(int(i) for i in kept)
    untested = {}
    for sample in s:
        key = (kept, sample.tobytes())
        if key in _non_negative:
            _non_negative.move_to_end(key)
        else:
            untested.setdefault(key, sample)
    if not untested:
        return False
    if pruning.can_be_negative(np.array(list(untested.values())), kept):
        return True
    for key in untested:
        _non_negative[key] = True
        if len(_non_negative) > NON_NEGATIVE_CACHE_SIZE:
            _non_negative.popitem(last=False)
    return False


def fitted_spec(scenes):
    """The ``Fit`` (terms, scalar, clamp, exact bound) for all ``scenes`` with coefficients."""
    parts = []
    for scene in scenes:
        if scene_data.has_coefficients(scene):
            relative, mode = fit_settings(scene)
            parts.append((scene, scene_samples(scene), relative, mode))
    if not parts:
        return Fit(pruning.ALL_TERMS, False, False)
    names = {scene.name: {"animation": s.signature} for scene, s, _r, _m in parts}
    if any(s.unknown for _scene, s, _r, _m in parts):
        clamp = any(mode != "NEVER" for *_rest, mode in parts)
        return Fit(pruning.ALL_TERMS, False, clamp, 0.0, 0.0, names)
    samples = np.concatenate([s.samples for _scene, s, _r, _m in parts])
    relative = np.concatenate([np.full(len(s.samples), r) for _scene, s, r, _m in parts])
    fit = pruning.fit_terms(samples, relative)
    auto = [s.samples for _scene, s, _r, mode in parts if mode == "AUTO"]
    clamp = any(mode == "ALWAYS" for *_rest, mode in parts) or (
        bool(auto) and can_be_negative(np.concatenate(auto), fit.kept)
    )
    scalar = pruning.is_grey(samples, fit.kept)
    return Fit(fit.kept, scalar, clamp, fit.bound, fit.bound_absolute, names)


def hint(scene, terms, scalar, clamp, recorded):
    """Why a group (``terms``, ``scalar``, ``clamp``) does not suit ``scene`` now, or None.

    ``recorded``: what the group recorded for this scene when it was fitted (or None). Checks
    the current values exactly (cheap), and the animation only by its signature.
    """
    if not scene_data.has_coefficients(scene):
        return None
    current = scene_data.get_coefficients(scene)
    relative, mode = fit_settings(scene)
    omitted = [i for i in pruning.ALL_TERMS if i not in terms]
    if omitted and not pruning.omission_holds(current, omitted, relative):
        tolerance = pruning.tolerances(current, relative)[0]
        peaks = pruning.term_peaks(current)[0].max(axis=1)
        needed = [COEFFICIENT_NAMES[i] for i in omitted if peaks[i] >= tolerance]
        what = ", ".join(needed) if needed else "the left-out terms together"
        return f"Refit needed: {what} now matter"
    if scalar and not pruning.is_grey(current, terms):
        return "Refit needed: the lighting is no longer grey"
    if not clamp and (
        mode == "ALWAYS" or (mode == "AUTO" and can_be_negative(current, terms))
    ):
        return "Refit needed: the irradiance can go negative and the group has no clamp"
    if recorded is None:
        return "Not fitted to this scene's lighting yet: Refit"
    if recorded.get("animation") != animation_signature(scene):
        return "Keyframes or frame range changed since the last fit: Refit"
    return None
