"""Writing over animated custom properties: the policy of ``scene_data.store``.

A value written over a keyframed or driven property is what Blender shows until the next
frame change, when the animation overrides it. ``store`` asks
``check_animation`` which of the properties it writes are animated (an F-curve of the
scene's action or of its NLA strips, or a driver) and what the policy allows
(``ANIMATION_POLICIES``: "KEY" keys the new value at the current frame, a driven one refused;
"CLEAR" removes their F-curves and drivers first; "REFUSE" raises), naming the property.
"""

from . import compat

ANIMATION_POLICIES = ("KEY", "CLEAR", "REFUSE")


class AnimatedError(ValueError):
    """A property ``store`` would write is animated and the policy forbids writing over it."""


def _path(name):
    return f'["{name}"]'


def animation_of(scene, name):
    """How custom property ``name`` of ``scene`` is animated: "driven", "keyframed" or None."""
    animation = getattr(scene, "animation_data", None)
    if animation is None:
        return None
    path = _path(name)
    if any(curve.data_path == path for curve in animation.drivers):
        return "driven"
    curves = compat.action_fcurves(scene) + compat.nla_fcurves(scene)
    if any(curve.data_path == path for curve in curves):
        return "keyframed"
    return None


def animated(scene, names):
    """{name: "driven" | "keyframed"} of the custom properties ``names`` animated on ``scene``."""
    found = {}
    for name in names:
        how = animation_of(scene, name)
        if how is not None:
            found[name] = how
    return found


def clear_animation(scene, names):
    """Remove the F-curves (of the scene's own action) and drivers of ``names``; only those."""
    animation = scene.animation_data
    paths = {_path(name) for name in names}
    for curve in [c for c in animation.drivers if c.data_path in paths]:
        animation.drivers.remove(curve)
    for curve in [c for c in compat.action_fcurves(scene) if c.data_path in paths]:
        compat.remove_fcurve(scene, curve)
    left = animated(scene, names)
    if left:  # an NLA strip's action (shared, maybe by other scenes): not ours to edit
        raise AnimatedError(
            f"{listed(left)} animated by an NLA strip: nothing stored; remove the strip "
            "or mute it, then try again"
        )


def listed(found):
    names = sorted(found)
    return f"{', '.join(names)} {'is' if len(names) == 1 else 'are'}"


def check_animation(scene, names, animation):
    """The animated ones of ``names`` that ``store`` may write under policy ``animation``
    ({name: how}), or an AnimatedError saying which property and what to do."""
    if animation not in ANIMATION_POLICIES:
        raise ValueError(
            f"animation must be one of {', '.join(ANIMATION_POLICIES)}, got {animation!r}"
        )
    found = animated(scene, names)
    if not found or animation == "CLEAR":
        return found
    if animation == "REFUSE":
        raise AnimatedError(
            f"{listed(found)} animated ({', '.join(sorted(set(found.values())))}), so a "
            "value written now would be undone at the next frame: nothing stored; key the "
            "new values at this frame (animation='KEY', --animation key) or remove the "
            "animation (animation='CLEAR', --animation clear)"
        )
    driven = {name: how for name, how in found.items() if how == "driven"}
    if driven:
        raise AnimatedError(
            f"{listed(driven)} driven by a driver, which overrides any value or key: "
            "nothing stored; remove the driver (Clear Driver on the field, or "
            "animation='CLEAR', --animation clear), then try again"
        )
    return found
