"""The few places where Blender 4.2 LTS and 5.0 differ, in one module (docs/reference.md §3b)."""

import math

import bpy

BLENDER_VERSION = bpy.app.version


def eevee_engine_id():
    """'BLENDER_EEVEE_NEXT' in 4.2-4.5, 'BLENDER_EEVEE' from 5.0 on."""
    return "BLENDER_EEVEE" if BLENDER_VERSION >= (5, 0, 0) else "BLENDER_EEVEE_NEXT"


def ensure_node_tree(datablock):
    """The node tree of a material or world, creating it the way this Blender version wants.

    ``use_nodes`` is deprecated in 5.0, where new materials and worlds already have trees.
    """
    if datablock.node_tree is None:
        datablock.use_nodes = True
    return datablock.node_tree


def set_equirectangular_panorama(camera_data):
    """Make ``camera_data`` a full-sphere equirectangular panoramic camera.

    The panorama settings live on the Camera itself in recent versions (checked on 5.0) and
    on its Cycles settings (``camera.cycles``) in older ones; whichever holds them is used.
    """
    camera_data.type = "PANO"
    holder = camera_data if hasattr(camera_data, "panorama_type") else camera_data.cycles
    holder.panorama_type = "EQUIRECTANGULAR"
    holder.latitude_min, holder.latitude_max = -0.5 * math.pi, 0.5 * math.pi
    holder.longitude_min, holder.longitude_max = -math.pi, math.pi


def uses_nodes(datablock):
    """True when a material or world renders from its node tree.

    Before 5.0 a tree can exist with ``use_nodes`` off (then Blender ignores it); in 5.0
    ``use_nodes`` is deprecated and a present tree is always used.
    """
    if datablock.node_tree is None:
        return False
    return BLENDER_VERSION >= (5, 0, 0) or bool(datablock.use_nodes)


def action_fcurves(datablock):
    """The F-curves of the action assigned to ``datablock`` (its own slot's), or ().

    4.2 keeps them on ``Action.fcurves``; 4.4 added layered actions with slots, and 5.0 removed
    ``Action.fcurves``: the curves are in the channelbag of the ID's assigned slot
    (``bpy_extras.anim_utils.animdata_get_channelbag_for_assigned_slot``, 4.4+).
    """
    animation = getattr(datablock, "animation_data", None)
    if animation is None or animation.action is None:
        return ()
    action = animation.action
    if hasattr(action, "layers"):
        from bpy_extras import anim_utils

        get = getattr(anim_utils, "animdata_get_channelbag_for_assigned_slot", None)
        if get is not None:
            channelbag = get(animation)
            return tuple(channelbag.fcurves) if channelbag is not None else ()
    return tuple(getattr(action, "fcurves", ()))


def remove_fcurve(datablock, curve):
    """Remove F-curve ``curve`` of the action assigned to ``datablock`` (``action_fcurves``):
    from ``Action.fcurves`` (4.2) or from the assigned slot's channelbag (4.4+, 5.0)."""
    action = datablock.animation_data.action
    if hasattr(action, "layers"):
        from bpy_extras import anim_utils

        get = getattr(anim_utils, "animdata_get_channelbag_for_assigned_slot", None)
        if get is not None:
            get(datablock.animation_data).fcurves.remove(curve)
            return
    action.fcurves.remove(curve)


def nla_fcurves(datablock):
    """F-curves of the actions in ``datablock``'s NLA strips (any slot), or ().

    Only used to find which properties the NLA animates (their values are not sampled).
    """
    animation = getattr(datablock, "animation_data", None)
    if animation is None:
        return ()
    curves = []
    for track in animation.nla_tracks:
        for strip in track.strips:
            action = strip.action
            if action is None:
                continue
            if hasattr(action, "layers"):
                for layer in action.layers:
                    for action_strip in layer.strips:
                        for bag in getattr(action_strip, "channelbags", ()):
                            curves.extend(bag.fcurves)
            else:
                curves.extend(action.fcurves)
    return tuple(curves)


def working_space():
    """The file's working (scene-linear) colour space: ``bpy.data.colorspace.working_space``
    in 5.0 ("Linear Rec.709", "Linear Rec.2020" or "ACEScg"); always "Linear Rec.709" before
    (4.2–4.5 have no such choice)."""
    colorspace = getattr(bpy.data, "colorspace", None)
    return colorspace.working_space if colorspace is not None else "Linear Rec.709"
