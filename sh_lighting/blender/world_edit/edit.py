"""Put the "SH World Edit" group where the world's colour reaches its Background, take it out
again exactly.

``edit_world(scene)`` finds the Background nodes the world's outputs render (through Mix
Shader nodes; an Add Shader or another emitter is refused: it is not clear which Background
carries the light), and for each puts a group node between its Color and what fed it (the
world's own Mapping, textures, Sky, gradients and mixes keep working in front of it); the
group's Strength follows the Background's (linked to the same source, else its value). L⁰ and
k of the group (``nodes``) are the scene's Reset values if they were computed from this world
(``scene_data.get_computed``, provenance "world"), else 0 and 0: the nine terms alone.

Identity: the world and its group point at each other (ID pointer custom properties). A copy
of the world keeps the pointer to the group, but the group points back at the original, so
``remove`` never deletes what a copy holds; a copy of the group is pointed at by no world.
The links replaced are recorded on the group (JSON); ``remove`` puts each back, deletes the
group nodes and the group (when nothing else uses it). An error while inserting rolls back.

``Clamping`` (``core.world_edit``): where k L_world + Σ ΔL Y goes below zero the clamp adds
light; Apply measures it on the world's map and keeps the numbers on the group (the panel
shows them).
"""

import json

import bpy
import numpy as np

from ...core import world_edit as core_world_edit
from ...core.downsample import block_downsample, whole_factor
from ..data import compat, scene_data
from ..data.node_links import WORLD_EDIT_MARKER, is_world_edit, source_socket
from ..design import lights as design_lights
from ..world import reader
from . import lights, nodes

WORLD_POINTER = "sh_lighting_world_edit"  # on the world: its group
GROUP_WORLD = "sh_lighting_world"  # on the group: the world it was made for
RECORD = "sh_lighting_world_edit_record"  # on the group: JSON of the links replaced
CLAMPING = "sh_lighting_world_edit_clamping"  # on the group: {"share", "difference", ...}
LAMPS = "sh_lighting_world_edit_lamps"  # on the group: {"lamps": [the Sun lamps it shows]}
NODE_LABEL = "SH World Edit"
ESTIMATE_WIDTH = 512  # the clamping is measured on the world's map box-averaged to this width
CAPTURE_WIDTH = 256  # a procedural world is captured this wide for it
NEGLIGIBLE = 1e-4  # a clamp adding less than this share of the light is not reported


class WorldEditError(ValueError):
    """The world cannot be edited; the message says why and what to do. Nothing changed."""


def group_of(world):
    """The World Edit group the add-on made for ``world`` (mutual pointers), or None."""
    if world is None:
        return None
    group = world.get(WORLD_POINTER)
    if not isinstance(group, bpy.types.NodeTree) or WORLD_EDIT_MARKER not in group:
        return None
    return group if group.get(GROUP_WORLD) == world else None


def is_edited(world):
    return group_of(world) is not None


def own_coefficients(scene, world):
    """(L⁰ (9, 3), k): the Reset values and True when they were computed from ``world``, else
    zeros and False (a preset, a photo fit, a blank world: the nine terms replace it)."""
    try:
        computed = scene_data.get_computed(scene)
    except scene_data.PropertyError:
        computed = None
    record = scene_data.computed_provenance(scene)
    if computed is not None and record.get("world") == world.name:
        return computed, True
    return np.zeros((9, 3)), False


def _problem(scene, world):
    if world is None:
        return (f"scene '{scene.name}' has no world: add one (Properties > World > New), or use "
                "Keep BSDF")
    if world.library is not None or getattr(world, "override_library", None) is not None:
        return (f"world '{world.name}' is linked from a library: make it local (Object > "
                "Relations > Make Local) or use Keep BSDF")
    if not compat.uses_nodes(world):
        return (f"world '{world.name}' does not use nodes: click Use Nodes in Properties > "
                "World, or use Keep BSDF")
    if not scene_data.has_coefficients(scene):
        return (f"scene '{scene.name}' has no SH lighting yet: run Compute from World or load "
                "a preset first")
    return None


def backgrounds(world):
    """The Background nodes ``world``'s World Outputs render, through Mix Shaders; a
    WorldEditError for any other shader on the way."""
    found, stack, seen = {}, [], set()
    for node in world.node_tree.nodes:
        if node.bl_idname == "ShaderNodeOutputWorld" and not node.mute:
            stack.append(source_socket(node.inputs["Surface"]))
    while stack:
        socket = stack.pop()
        if socket is None or socket.node.as_pointer() in seen:
            continue
        node = socket.node
        seen.add(node.as_pointer())
        if node.bl_idname == "ShaderNodeBackground" and not node.mute:
            found[node.name] = node
        elif node.bl_idname == "ShaderNodeMixShader" and not node.mute:
            stack.extend(source_socket(node.inputs[i]) for i in (1, 2))
        else:
            raise WorldEditError(
                f"world '{world.name}' renders a {node.bl_label} node ('{node.name}') as its "
                "surface: Edit World changes Background nodes (mixed by Mix Shader nodes) "
                "only; use Keep BSDF for this world")
    if not found:
        raise WorldEditError(f"world '{world.name}' has no Background node connected to a World "
                             "Output: connect one, or use Keep BSDF")
    return list(found.values())


def _world_map(scene, rest=None):
    """(pixels, Strength, Mapping Euler) of the world without the edit (``rest``: that map
    with the extracted sources taken out), box-averaged to about ``ESTIMATE_WIDTH`` wide."""
    pixels, strength, euler = rest or reader.world_radiance(scene, CAPTURE_WIDTH)
    height, width = pixels.shape[:2]
    factor = whole_factor(height, width, ESTIMATE_WIDTH)
    if factor > 1:
        pixels = block_downsample(pixels, factor)[0]
    return pixels, strength, euler


def measure_clamping(scene, own, keep, rest=None):
    """``core.world_edit.Clamping`` of the scene's designed lighting over its world (``rest``:
    the world's map without its extracted sources)."""
    designed = scene_data.get_coefficients(scene)
    if keep:
        pixels, strength, euler = _world_map(scene, rest)
    else:
        pixels, strength, euler = np.zeros((64, 128, 3)), 1.0, None
    return core_world_edit.clamped_edit(pixels, strength, euler, designed - own, keep, designed)


def edit_world(scene, measure=True):
    """Insert (or refresh) the World Edit of ``scene``'s world; returns the ``Clamping``
    measured (None when ``measure`` is False). WorldEditError, nothing changed, when the world
    cannot be edited."""
    world = scene.world
    reason = _problem(scene, world)
    if reason is not None:
        raise WorldEditError(reason)
    try:
        scene_data.get_coefficients(scene)
    except (LookupError, ValueError) as error:
        raise WorldEditError(str(error)) from None
    if is_edited(world):
        remove(world)
    targets = backgrounds(world)
    own, keep = own_coefficients(scene, world)
    try:
        sources, rest = lights.extracted_sources(scene, world) if keep else ([], None)
        clamping = measure_clamping(scene, own, keep, rest) if measure else None
    except ValueError as error:  # reader.WorldError, or the extraction refusing its record
        raise WorldEditError(f"Edit World: {error}") from None
    strength_zero = [bg.name for bg in targets if not bg.inputs["Strength"].is_linked
                     and bg.inputs["Strength"].default_value == 0.0]
    if strength_zero:
        raise WorldEditError(f"world '{world.name}': Background '{strength_zero[0]}' has "
                             "Strength 0, so no change can show: raise its Strength, or use "
                             "Keep BSDF")
    group = nodes.new_group(world)
    record = {"version": 1, "backgrounds": []}
    try:
        nodes.build(group, own, keep, sources, lights.luminance())
        group[GROUP_WORLD] = world
        for background in targets:
            record["backgrounds"].append(_insert(world.node_tree, background, group))
        group[RECORD] = json.dumps(record)
        if clamping is not None:
            group[CLAMPING] = {"share": clamping.share, "texels": clamping.texels,
                               "difference": clamping.difference}
        world[WORLD_POINTER] = group
        if sources:
            _show_lamps(scene, group)
    except Exception:
        _restore(world, group, record)
        raise
    world.update_tag()
    return clamping


def _insert(tree, background, group):
    colour, strength = background.inputs["Color"], background.inputs["Strength"]
    source = source_socket(colour)  # through reroutes; None for a muted link
    link = colour.links[0] if colour.is_linked else None  # what Remove puts back, as it was
    entry = {"node": background.name,
             "from": [link.from_node.name, link.from_socket.identifier] if link else None,
             "muted": bool(link is not None and getattr(link, "is_muted", False))}
    node = tree.nodes.new("ShaderNodeGroup")
    node.node_tree = group
    node.label = NODE_LABEL
    node.width = 180.0
    node.location = (background.location.x - 220.0, background.location.y - 40.0)
    entry["group_node"] = node.name
    if source is not None:
        tree.links.new(source, node.inputs["Color"])
    else:
        node.inputs["Color"].default_value = tuple(colour.default_value)
    strength_source = source_socket(strength)
    if strength_source is not None:
        tree.links.new(strength_source, node.inputs["Strength"])
    else:
        node.inputs["Strength"].default_value = strength.default_value
    tree.links.new(node.outputs["Color"], colour)
    return entry


def remove(world):
    """Take the World Edit out of ``world``, restoring the links it replaced; True if there
    was one of the add-on's."""
    group = group_of(world)
    if group is None:
        return False
    try:
        record = json.loads(group.get(RECORD, "{}"))
    except (ValueError, TypeError):
        record = {}
    _restore(world, group, record)
    return True


def _restore(world, group, record):
    tree = world.node_tree
    for entry in record.get("backgrounds", ()):
        background = tree.nodes.get(entry.get("node", ""))
        if background is None or background.bl_idname != "ShaderNodeBackground":
            continue
        colour = background.inputs["Color"]
        if colour.is_linked and not is_world_edit(colour.links[0].from_node):
            continue  # relinked by the user since: their choice stays
        for link in list(colour.links):
            tree.links.remove(link)
        origin = entry.get("from")
        source = tree.nodes.get(origin[0]) if origin else None
        socket = next((s for s in source.outputs if s.identifier == origin[1]), None) \
            if source is not None else None
        if socket is not None:
            link = tree.links.new(socket, colour)
            if entry.get("muted") and hasattr(link, "is_muted"):
                link.is_muted = True
    _hide_lamps(group)
    for node in [n for n in tree.nodes if n.bl_idname == "ShaderNodeGroup"
                 and n.node_tree == group]:
        tree.nodes.remove(node)
    if world.get(WORLD_POINTER) == group:
        del world[WORLD_POINTER]
    if group.users == 0:
        bpy.data.node_groups.remove(group)
    world.update_tag()


def _show_lamps(scene, group):
    """Extract Lights' lamps are hidden from glossy and transmission rays while the world
    shows their sources; the edited world does not, so the lamps are shown to them (their
    reflections are the sources'), recorded on the group for ``_hide_lamps``."""
    shown = []
    for obj in design_lights.extracted_lights(scene):
        if not obj.visible_glossy or not obj.visible_transmission:
            obj.visible_glossy = obj.visible_transmission = True
            shown.append(obj)
    if shown:
        group[LAMPS] = {"lamps": shown}


def _hide_lamps(group):
    value = group.get(LAMPS)
    lamps = value.get("lamps", ()) if hasattr(value, "to_dict") else ()
    for obj in lamps:
        if isinstance(obj, bpy.types.Object) and obj.library is None:
            obj.visible_glossy = obj.visible_transmission = False
    if LAMPS in group:
        del group[LAMPS]


def clamping_of(world):
    """{"share", "texels", "difference"} measured when the edit went in, or None."""
    group = group_of(world)
    value = group.get(CLAMPING) if group is not None else None
    return value.to_dict() if hasattr(value, "to_dict") else None


def clamping_note(clamping):
    """One line on what the clamp changed, or None when it changed (next to) nothing."""
    if clamping is None or clamping.share < NEGLIGIBLE:
        return None
    return (f"the edited world goes below zero over {100 * clamping.texels:.1f} % of the sky; "
            f"clamping it adds {100 * clamping.share:.2f} % of its light, so its nine terms "
            f"differ from the designed ones by up to {100 * clamping.difference:.2f} % of L00")


# One line each under Apply in the sidebar (shading.notes.MODE_NOTE_CHARACTERS: 34).
STATUS_NOTES = {
    "AUTO": "Default here: Edit World",
    "WORLD": "World edited: shadows, bounces",
    "REPLACE": "No own SH: the 9 terms replace it",
    "EDITED": "World Edit in: Apply to refresh",
    "CLAMPED": "Clamp adds {share:.1f} % of the light",
}


def status_lines(scene, mode):
    """[(icon, line)] the panel shows under Apply when Apply edits the world (``mode``
    "AUTO" resolved to it, or "WORLD")."""
    lines = []
    if mode == "AUTO":
        lines.append(("INFO", STATUS_NOTES["AUTO"]))
    lines.append(("INFO", STATUS_NOTES["WORLD"]))
    world = scene.world
    if world is not None and scene_data.has_coefficients(scene):
        if not own_coefficients(scene, world)[1]:
            lines.append(("INFO", STATUS_NOTES["REPLACE"]))
    clamping = clamping_of(world)
    if clamping is not None and clamping.get("share", 0.0) >= NEGLIGIBLE:
        lines.append(("ERROR", STATUS_NOTES["CLAMPED"].format(share=100 * clamping["share"])))
    return lines


def applied_message(scene, clamping):
    """Apply's report when it edited the world."""
    world = scene.world
    own, keep = own_coefficients(scene, world)
    designed = scene_data.get_coefficients(scene)
    if not keep:
        what = ("it has no coefficients of its own (Compute from World), so the nine designed "
                "terms replace it, clamped at zero")
    elif np.array_equal(designed, own):
        what = "no edit yet: it renders exactly as before, edits reach it at render time"
    else:
        what = "it renders with the designed change to its nine terms"
    return f"Edit World: world '{world.name}' edited, materials untouched; {what}"


def refresh(scene):
    """After Compute from World or Extract Lights wrote new Reset values: an edited world of
    ``scene`` takes them as its own (and leaves out the new sources); a line saying so, or
    None when the world is not edited. A WorldEditError: the edit was taken out, the world is
    as it was without it."""
    if not is_edited(scene.world):
        return None
    try:
        clamping = edit_world(scene)
    except WorldEditError:
        remove(scene.world)
        raise
    note = clamping_note(clamping)
    return "World Edit refreshed with the new values" + (f"; {note}" if note else "")
