"""Put the "SH Irradiance" group into materials and take it out again, leaving no trace.

Its Emission is the surface's diffuse albedo × E(n)/π (eq. 13 of Ramamoorthi and Hanrahan
2001). "KEEP_BSDF" (default) adds it to the material's BSDF and takes the world's diffuse light
away (``world_diffuse``; EEVEE's reflections come back from ``glossy``'s maps); "EMISSION"
drives the Surface with it alone. The replaced links and settings are recorded in the added
node's ``NODE_MARKER`` property and ``remove_from_materials`` restores them. Materials without
a readable diffuse part are skipped with the reason, except a Principled BSDF that only
reflects (Metallic 1.0): it gets a black Albedo and, in EEVEE, the world's reflections back.
Errors roll back. Details: docs/modules.md.
"""

import functools
import json
from typing import NamedTuple

import bpy

from ...choices import MATERIAL_MODES
from ..data import compat
from . import glossy, keep_bsdf, world_diffuse
from .diffuse_weight import diffuse_leaves, linked_socket, reflects_only, surface_leaves
from .nodes import GROUP_NAME, ensure_node_group

# Custom property of the added group node: JSON {"version": 2, "mode": ..., "outputs": [...],
# "added": [names of the other nodes added]} (version 1: emission, nothing else added).
NODE_MARKER = "sh_lighting_original_links"
RECORD_VERSION = 2
MODES = MATERIAL_MODES
DEFAULT_MODE = MODES[0]
GROUP_NODE_WIDTH = 200.0  # px in the node editor: "SH Irradiance" and its sockets in full

# BSDF node type -> its diffuse colour input.
BASE_COLOUR_INPUTS = {
    "ShaderNodeBsdfPrincipled": "Base Color",
    "ShaderNodeBsdfDiffuse": "Color",
}


class Result(NamedTuple):
    """What a call did: names of the changed materials, (name, reason) of the skipped ones.

    A NamedTuple, so ``changed, skipped = apply_to_materials(...)`` works too.
    """

    changed: list
    skipped: list


class SkipMaterial(Exception):
    """A material this module leaves alone, with the reason as message."""


def added_nodes(material):
    """The group nodes this module added to ``material`` (normally zero or one): marked, and
    named in their own record (a user's Shift+D copy, which copies the mark, has another
    name; a record of an older version names no node)."""
    tree = getattr(material, "node_tree", None)
    if tree is None:
        return []
    return [
        node for node in tree.nodes if node.bl_idname == "ShaderNodeGroup" and NODE_MARKER in node
        and _recorded_name(node) in (None, node.name)
    ]


def _recorded_name(node):
    try:
        return json.loads(node[NODE_MARKER]).get("node")
    except (ValueError, TypeError, AttributeError):
        return None


def is_applied(material):
    """True when ``material`` holds an SH Irradiance node added by ``apply_to_materials``."""
    return bool(added_nodes(material))


def mode_of(material):
    """The mode ``material`` is applied in ("KEEP_BSDF", "EMISSION"), or None if not applied."""
    for node in added_nodes(material):
        try:
            return json.loads(node[NODE_MARKER]).get("mode", "EMISSION")
        except (ValueError, TypeError, AttributeError):
            return None
    return None


def check_mode(mode):
    """``mode`` itself, or a ValueError saying which modes there are."""
    if mode not in MODES:
        raise ValueError(f"unknown Apply mode {mode!r}: use one of {', '.join(MODES)}")
    return mode


def materials_of(objects):
    """The distinct materials in the material slots of ``objects``, in slot order."""
    found = {}
    for obj in objects:
        for slot in getattr(obj, "material_slots", ()):
            if slot.material is not None:
                found.setdefault(slot.material.name_full, slot.material)
    return list(found.values())


def objects_without_material(objects):
    """Names of the ``objects`` that could have materials but have none in any slot."""
    return [
        obj.name for obj in objects
        if hasattr(getattr(obj, "data", None), "materials")
        and not any(slot.material is not None for slot in obj.material_slots)
    ]


def apply_to_materials(materials, scene, mode=DEFAULT_MODE):
    """Light each material by the SH group in ``mode`` (``MODES``); ``Result(changed, skipped)``.

    In "KEEP_BSDF" mode the scene's world stops giving diffuse light in Cycles
    (``keep_bsdf.hide_world_diffuse``) once a material has been changed.
    """
    check_mode(mode)
    materials = list(materials)
    if mode == "KEEP_BSDF":
        names = [m.name_full for m in materials if isinstance(m, bpy.types.Material)]
        for world in _worlds_lighting(names, scene):
            reason = world_diffuse.problem(world)
            if reason is not None:
                raise world_diffuse.WorldError(f"Keep BSDF refused, nothing changed: {reason}")
    changed, skipped = [], []
    # The group, built once, when the first material gets it (an error: again next time).
    group = functools.cache(ensure_node_group)
    # The world's prefiltered maps, read once, when the first Principled BSDF reflects them.
    maps = functools.cache(lambda: glossy.maps_for(scene))
    for material in _unique(materials):
        name = _name(material)
        try:
            _apply_one(material, group, mode, maps)
        except SkipMaterial as error:
            skipped.append((name, str(error)))
            continue
        changed.append(name)
    if changed and mode == "KEEP_BSDF":
        for world in _worlds_lighting(changed, scene):
            world_diffuse.prepare(world)
    _restore_worlds_if_unused()
    return Result(changed, skipped)


def scene_materials(scene):
    """Full names of the materials in the slots of ``scene``'s objects."""
    return {slot.material.name_full for obj in scene.objects
            for slot in getattr(obj, "material_slots", ()) if slot.material is not None}


def _worlds_lighting(names, scene):
    """The worlds of ``scene`` and of every other scene showing one of the materials
    ``names``: each must stop giving diffuse light (a world shared or not, it is one each)."""
    worlds = {scene.world.as_pointer(): scene.world} if scene.world is not None else {}
    wanted = set(names)
    for other in bpy.data.scenes:
        if other.world is not None and wanted & scene_materials(other):
            worlds.setdefault(other.world.as_pointer(), other.world)
    return list(worlds.values())


def _restore_worlds_if_unused():
    """The worlds' diffuse visibility back, the prefiltered maps deleted, once no material of
    the file keeps its BSDF."""
    if not any(mode_of(m) == "KEEP_BSDF" for m in bpy.data.materials if m.library is None):
        world_diffuse.restore_worlds(bpy.data.worlds)
        glossy.remove_maps()


def _apply_one(material, group, mode, maps=lambda: None):
    """Apply to one material (refreshing it if applied); SkipMaterial when left alone.

    ``group``: returns the SH group, called only once the material is known to take it;
    ``maps``: returns the world's prefiltered maps (``glossy.maps_for``) or None.
    """
    _check_editable(material)
    refreshed = is_applied(material)
    if refreshed:
        try:
            _remove(material)
        except SkipMaterial as error:
            raise SkipMaterial(f"SH lighting is already applied and {error}") from None
    try:
        plan = _plan(material, mode)
    except SkipMaterial as error:
        if refreshed:
            raise SkipMaterial(f"SH lighting removed, not re-applied: {error}") from None
        raise
    tree = group()
    try:
        _apply(material, plan, tree, mode, maps)
    except Exception as error:  # rolled back by _apply: report, go on with the rest
        state = "without SH lighting" if refreshed else "unchanged"
        raise SkipMaterial(f"failed and was left {state}: {error}") from error


def remove_from_materials(materials):
    """Restore the links ``apply_to_materials`` replaced, delete its nodes; ``Result``."""
    changed, skipped = [], []
    for material in _unique(materials):
        name = _name(material)
        try:
            _check_editable(material)
            if not is_applied(material):
                raise SkipMaterial("SH lighting is not applied to it")
            _remove(material)
        except SkipMaterial as error:
            skipped.append((name, str(error)))
            continue
        changed.append(name)
    _restore_worlds_if_unused()
    return Result(changed, skipped)


def _unique(materials):
    """The given materials once each, in order (a material may sit in many slots)."""
    seen = set()
    for material in materials:
        key = material.as_pointer() if isinstance(material, bpy.types.Material) else id(material)
        if key not in seen:
            seen.add(key)
            yield material


def _name(material):
    if material is None:
        return "(empty slot)"
    return getattr(material, "name_full", None) or repr(material)


def _check_editable(material):
    if not isinstance(material, bpy.types.Material):
        raise SkipMaterial(f"not a material ({type(material).__name__})")
    if material.library is not None:
        raise SkipMaterial(f"linked from library '{material.library.filepath}': not editable")
    if material.is_grease_pencil:
        raise SkipMaterial("Grease Pencil material: has no shader nodes")
    if not compat.uses_nodes(material):
        raise SkipMaterial("does not use nodes (no shader node tree in use)")


class _Plan(NamedTuple):
    outputs: list  # every Material Output node
    active: object  # the output the surface was traced from, for placing the new node
    leaves: list  # diffuse_weight.Leaf of the surface's diffuse shaders
    normal: object  # socket linked to the first diffuse shader's Normal, or None
    surface: list  # diffuse_weight.Leaf of every shader of the surface (for its reflections)


def _plan(material, mode=DEFAULT_MODE):
    """Check ``material`` and find what to link, without changing anything."""
    tree = material.node_tree
    outputs = [node for node in tree.nodes if node.bl_idname == "ShaderNodeOutputMaterial"]
    if not outputs:
        raise SkipMaterial("no Material Output node")
    active = next((node for node in outputs if node.is_active_output), outputs[0])
    leaves, reason = diffuse_leaves(active)
    if reason is not None and not (mode == "KEEP_BSDF" and reflects_only(active)):
        raise SkipMaterial(reason)
    surface = surface_leaves(active)
    first = (leaves or [leaf for leaf in surface
                        if leaf.node.bl_idname in BASE_COLOUR_INPUTS])[0].node
    return _Plan(outputs=outputs, active=active, leaves=leaves,
                 normal=linked_socket(first.inputs.get("Normal")), surface=surface)


def surface_shaders(material):
    """The ``diffuse_weight.Leaf``s of what ``material``'s active Material Output renders
    ([] without nodes or output)."""
    tree = getattr(material, "node_tree", None)
    outputs = [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial"] if tree else []
    if not outputs:
        return []
    active = next((node for node in outputs if node.is_active_output), outputs[0])
    try:
        return surface_leaves(active)
    except ValueError:
        return []


def _surface_record(output):
    surface = output.inputs["Surface"]
    if not surface.is_linked:
        return {"output": output.name, "from_node": None, "from_socket": None, "muted": False}
    link = surface.links[0]
    return {
        "output": output.name,
        "from_node": link.from_node.name,
        "from_socket": link.from_socket.identifier,
        "muted": bool(getattr(link, "is_muted", False)),
    }


def _apply(material, plan, group, mode, maps=lambda: None):
    tree = material.node_tree
    record = {"version": RECORD_VERSION, "mode": mode, "added": [],
              "outputs": [_surface_record(o) for o in plan.outputs]}
    cycles = getattr(material, "cycles", None)
    if cycles is not None and hasattr(cycles, "emission_sampling"):
        record["emission_sampling"] = cycles.emission_sampling
    node = tree.nodes.new("ShaderNodeGroup")
    added, held = [], []
    try:
        node.node_tree = group
        if node.node_tree != group:
            raise TypeError(f"'{group.name}' is not a shader node group")
        node.name = GROUP_NAME
        node.label = GROUP_NAME
        # Left of the Material Output and above its inputs: a short forward wire into
        # Surface, wide enough for the full name.
        node.width = GROUP_NODE_WIDTH
        node.location = (plan.active.location.x - GROUP_NODE_WIDTH - 60.0,
                         plan.active.location.y + 220.0)
        record["node"] = node.name  # its identity: a copy of it has another name
        node[NODE_MARKER] = json.dumps(record)
        builder = keep_bsdf.Builder(material, added, held)
        if plan.leaves:
            albedo = keep_bsdf.albedo(material, plan.leaves, mode == "KEEP_BSDF", added,
                                      held, builder)
            tree.links.new(albedo, node.inputs["Albedo"])
        else:  # reflects only (a metal): no diffuse part for the SH term to light
            node.inputs["Albedo"].default_value = (0.0, 0.0, 0.0, 1.0)
        if plan.normal is not None:
            tree.links.new(plan.normal, node.inputs["Normal"])
        for output in plan.outputs:
            _drive_surface(tree, output, node, mode, added)
        if mode == "KEEP_BSDF":  # the world's reflections, which EEVEE's lighting lost
            glossy.add_eevee_reflections(builder, plan.surface, plan.outputs, plan.active, maps)
        for index, extra in enumerate(added):
            extra.location = (node.location.x - 220.0 - 180.0 * (index // 6),
                              node.location.y - 120.0 * (index % 6))
        record["added"] = [extra.name for extra in added]
        record["held"] = held
        node[NODE_MARKER] = json.dumps(record)
        if "emission_sampling" in record:
            # The SH emission is light reflected, not a lamp: Cycles must not sample it as
            # one (measured: noise at 16 spp, benchmarks/REPORT.md).
            cycles.emission_sampling = "NONE"
        material.update_tag()
    except Exception:
        record["added"] = [extra.name for extra in added]
        record["held"] = held
        _restore(material, node, record)
        raise


def _drive_surface(tree, output, node, mode, added):
    """Link the SH ``node`` into ``output``'s Surface: alone ("EMISSION", or nothing was
    linked), or added to what was linked there ("KEEP_BSDF")."""
    surface = output.inputs["Surface"]
    original = linked_socket(surface)
    if mode == "EMISSION" or original is None:
        tree.links.new(node.outputs["Shader"], surface)
        return
    add = tree.nodes.new("ShaderNodeAddShader")
    add.label = "BSDF + SH diffuse"
    add.location = (output.location.x - 180.0, output.location.y + 120.0)
    added.append(add)
    tree.links.new(original, add.inputs[0])
    tree.links.new(node.outputs["Shader"], add.inputs[1])
    tree.links.new(add.outputs[0], surface)


def _remove(material):
    """Undo every added node of ``material``; SkipMaterial (and no change) if one cannot be."""
    tree = material.node_tree
    work = []
    for node in added_nodes(material):
        try:
            record = json.loads(node[NODE_MARKER])
            entries = record["outputs"]
        except (ValueError, KeyError, TypeError):
            raise SkipMaterial(
                f"node '{node.name}' has an unreadable record of the original links: "
                "delete it and relink the Material Output by hand"
            ) from None
        for entry in entries:
            for key in ("output", "from_node"):
                wanted = entry.get(key)
                if wanted is not None and tree.nodes.get(wanted) is None:
                    raise SkipMaterial(
                        f"cannot restore the original link: node '{wanted}' no longer exists "
                        f"(delete node '{node.name}' and relink by hand)"
                    )
            source = tree.nodes.get(entry["from_node"]) if entry["from_node"] else None
            if source is not None and _output_by_identifier(source, entry["from_socket"]) is None:
                raise SkipMaterial(
                    f"cannot restore the original link: node '{source.name}' has no output "
                    f"'{entry['from_socket']}' any more"
                )
        work.append((node, record))
    for node, record in work:
        _restore(material, node, record)


def _restore(material, node, record):
    """Relink each recorded output still driven by ``node`` or the nodes added with it (or
    left unlinked); delete them, their drivers and what else Apply set."""
    tree = material.node_tree
    added = [tree.nodes.get(name) for name in record.get("added", ())]
    ours = {node.name, *(extra.name for extra in added if extra is not None)}
    for entry in record["outputs"]:
        output = tree.nodes.get(entry["output"])
        if output is None or output.bl_idname != "ShaderNodeOutputMaterial":
            continue
        surface = output.inputs["Surface"]
        if surface.is_linked and surface.links[0].from_node.name not in ours:
            continue  # relinked by the user since: keep their choice
        for link in list(surface.links):
            tree.links.remove(link)
        if entry["from_node"] is None:
            continue
        source = tree.nodes.get(entry["from_node"])
        socket = _output_by_identifier(source, entry["from_socket"]) if source else None
        if socket is None:
            continue
        link = tree.links.new(socket, surface)
        if entry.get("muted") and hasattr(link, "is_muted"):
            link.is_muted = True
    keep_bsdf.release(tree, record.get("held", ()))
    for extra in added:
        if extra is not None:
            tree.nodes.remove(extra)
    tree.nodes.remove(node)
    sampling = record.get("emission_sampling")
    cycles = getattr(material, "cycles", None)
    if (sampling is not None and cycles is not None
            and getattr(cycles, "emission_sampling", None) == "NONE"):
        # Put back only what Apply changed: a value chosen since is the user's.
        cycles.emission_sampling = sampling
    material.update_tag()


def _output_by_identifier(node, identifier):
    return next((s for s in node.outputs if s.identifier == identifier), None)
