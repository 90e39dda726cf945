"""Put the "SH World Edit" group where the world's colour reaches its Background, take it out
again exactly.

``edit_world(scene)`` finds the Background nodes the world's outputs render (through Mix
Shader nodes; an Add Shader or another emitter is refused: it is not clear which Background
carries the light), and for each puts a group node between its Color and what fed it (the
world's own Mapping, textures, Sky, gradients and mixes keep working in front of it); the
group's Strength follows the Background's (linked to the same source, else its value). L⁰ and
k of the group (``nodes``) are the scene's Reset values if they were computed from this world
(``scene_data.get_computed``, provenance "world"), else 0 and 0: the nine terms alone.

Identity, without ID pointers (an ID pointer in a custom property is user-counted, and the
copies of the group EEVEE frees after compiling the world shader in Blender 4.3 decrement the
user count of what it points at: "id_us_min: ID user decrement error"). Edit World gives the
world and its group one random token (plain strings: ``WORLD_TOKEN`` on the world, ``OWNER``
{"token", "world": its name} on the group); the world's group is a group its own node tree uses
with that token. A copy of the world inherits the token and shares the group through its
copied node tree; the name tells them apart: the group is the world's the owner record names,
or, the world renamed, the only world holding the token's. So ``remove`` of a copy is False and
leaves the original's edit (and the group) alone, and Apply on a copy takes the inherited group
node out of the copy's tree (``_take_out_inherited``) and makes the copy its own group. A copy
of the group holds the token but no world's tree uses it with that token. Files saved before
(the world and group pointing at each other) are read as they were and take the token form at
the next Apply. The links replaced are recorded on the group (JSON); ``remove`` puts each back,
deletes the group nodes and the group (when nothing else uses it). An error while inserting
rolls back.

``Clamping`` (``core.world_edit``): where k L_world + Σ ΔL Y goes below zero the clamp adds
light; Apply measures it on the world's map and keeps the numbers on the group (the panel
shows them).
"""

import json
import secrets

import bpy
import numpy as np

from ...core import world_edit as core_world_edit
from ...core.downsample import block_downsample, whole_factor
from ..data import compat, scene_data
from ..data.node_links import WORLD_EDIT_MARKER, is_world_edit, source_socket
from ..design import lights as design_lights
from ..world import reader
from . import lights, nodes

WORLD_TOKEN = "sh_lighting_world_edit"  # on the world: the token it shares with its group
OWNER = "sh_lighting_world_edit_owner"  # on the group: JSON {"token", "world": the world's name}
LEGACY_GROUP_WORLD = "sh_lighting_world"  # before the token: on the group, an ID pointer to it
RECORD = "sh_lighting_world_edit_record"  # on the group: JSON of the links replaced
CLAMPING = "sh_lighting_world_edit_clamping"  # on the group: {"share", "difference", ...}
LAMPS = "sh_lighting_world_edit_lamps"  # on the group: JSON {"lamps": [names of the lamps shown]}
NODE_LABEL = "SH World Edit"
ESTIMATE_WIDTH = 512  # the clamping is measured on the world's map box-averaged to this width
CAPTURE_WIDTH = 256  # a procedural world is captured this wide for it
NEGLIGIBLE = 1e-4  # a clamp adding less than this share of the light is not reported


class WorldEditError(ValueError):
    """The world cannot be edited; the message says why and what to do. Nothing changed."""


def _owner(group):
    """The group's {"token", "world"} record, or None (not a World Edit group with one)."""
    if not isinstance(group, bpy.types.NodeTree) or WORLD_EDIT_MARKER not in group:
        return None
    try:
        record = json.loads(group[OWNER])
    except (KeyError, ValueError, TypeError):
        return None
    if not isinstance(record, dict) or not isinstance(record.get("token"), str):
        return None
    return record


def _groups_used(world):
    """The World Edit groups ``world``'s node tree uses, each once, in node order."""
    tree = world.node_tree if compat.uses_nodes(world) else None
    found = {}
    for node in tree.nodes if tree is not None else ():
        if is_world_edit(node):
            found.setdefault(node.node_tree.as_pointer(), node.node_tree)
    return list(found.values())


def group_of(world):
    """The World Edit group the add-on made for ``world``, or None: a group its node tree uses
    that holds the world's token and is its own (the group names it, or no other world holds
    the token: a rename); a copy of the world is not (the original holds the token too)."""
    if world is None:
        return None
    token = world.get(WORLD_TOKEN)
    if isinstance(token, bpy.types.NodeTree):  # a file from before the token
        legacy = token
        if WORLD_EDIT_MARKER in legacy and legacy.get(LEGACY_GROUP_WORLD) == world:
            return legacy
        return None
    if not isinstance(token, str) or not token:
        return None
    for group in _groups_used(world):
        record = _owner(group)
        if record is None or record["token"] != token:
            continue
        if record.get("world") == world.name or not any(
                other != world and other.get(WORLD_TOKEN) == token for other in bpy.data.worlds):
            return group
    return None


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
    _take_out_inherited(world)
    group = nodes.new_group(world)
    record = {"version": 1, "backgrounds": []}
    token = secrets.token_hex(8)
    try:
        nodes.build(group, own, keep, sources, lights.luminance())
        group[OWNER] = json.dumps({"token": token, "world": world.name})
        for background in targets:
            record["backgrounds"].append(_insert(world.node_tree, background, group))
        group[RECORD] = json.dumps(record)
        if clamping is not None:
            group[CLAMPING] = {"share": clamping.share, "texels": clamping.texels,
                               "difference": clamping.difference}
        world[WORLD_TOKEN] = token
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


def _record_of(group):
    try:
        record = json.loads(group.get(RECORD, "{}"))
    except (ValueError, TypeError):
        record = {}
    return record if isinstance(record, dict) else {}


def remove(world):
    """Take the World Edit out of ``world``, restoring the links it replaced; True if there
    was one of the add-on's."""
    group = group_of(world)
    if group is None:
        return False
    _restore(world, group, _record_of(group))
    return True


def _take_out_inherited(world):
    """Before Apply makes ``world`` its own group: take out of its tree the World Edit groups
    it holds but that are not its (a copy of an edited world shares the original's), their
    links restored by their record (the node names are the copy's too); the original keeps its
    group, its lamps and its token."""
    for group in _groups_used(world):
        _restore(world, group, _record_of(group), own=False)


def _restore(world, group, record, own=True):
    """Put back the links of ``record`` in ``world``'s tree and delete the nodes of ``group``
    there; ``own``: the world's own edit (its lamps hidden again, its token deleted)."""
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
    if own:
        _hide_lamps(group)
    for node in [n for n in tree.nodes if n.bl_idname == "ShaderNodeGroup"
                 and n.node_tree == group]:
        tree.nodes.remove(node)
    if own:
        for holder, key in ((world, WORLD_TOKEN), (group, LEGACY_GROUP_WORLD)):
            if key in holder:
                del holder[key]
    if group.users == 0:
        bpy.data.node_groups.remove(group)
    world.update_tag()


def _show_lamps(scene, group):
    """Extract Lights' lamps are hidden from glossy and transmission rays while the world
    shows their sources; the edited world does not, so the lamps are shown to them (their
    reflections are the sources'), recorded on the group by name for ``_hide_lamps`` (no ID
    pointer on the group: see the module's note)."""
    shown = []
    for obj in design_lights.extracted_lights(scene):
        if not obj.visible_glossy or not obj.visible_transmission:
            obj.visible_glossy = obj.visible_transmission = True
            shown.append(obj.name)
    if shown:
        group[LAMPS] = json.dumps({"lamps": shown})


def _lamps_shown(group):
    """The lamps ``group`` recorded as shown: local light objects by the names it holds (or,
    a file from before, the objects it pointed at)."""
    value = group.get(LAMPS)
    if hasattr(value, "to_dict"):  # a file from before: {"lamps": [Object]}
        found = [obj for obj in value.get("lamps", ()) if isinstance(obj, bpy.types.Object)]
    else:
        try:
            names = json.loads(value).get("lamps", ())
        except (AttributeError, ValueError, TypeError):
            names = ()
        found = [bpy.data.objects.get(name) for name in names if isinstance(name, str)]
    return [obj for obj in found
            if obj is not None and obj.library is None and obj.type == "LIGHT"]


def _hide_lamps(group):
    for obj in _lamps_shown(group):
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
