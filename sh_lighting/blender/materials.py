"""Put the "SH Irradiance" group into materials and take it out again, leaving no trace.

``apply_to_materials`` adds one group node per material. Its Albedo comes from the material's
diffuse base colour (Principled BSDF "Base Color" or Diffuse BSDF "Color": the node linked to it,
or its value), its Normal from that BSDF's linked Normal input if any (normal and bump maps
keep working), and its "Shader" output drives the Surface of every Material Output node, so
Cycles and EEVEE outputs agree. The links it replaces are recorded as JSON in the custom
property ``NODE_MARKER`` of the added node; ``remove_from_materials`` relinks them and deletes
that node, which also deletes the links into it. Nothing else in the material is touched.

The BSDF is the one linked to the active Material Output's Surface (through reroutes), or
else the only Principled/Diffuse BSDF of the material. Applying to a material that already has
the group first removes it, then applies it again (a refresh: nothing stacks).

Materials without a diffuse part are left alone and reported as skipped: a Surface made only of
(mixes and sums of) Emission, Glass, Refraction, Transparent, Holdout, Glossy, Metallic, hair,
Ray Portal or Background shaders, or of a Principled BSDF whose unlinked Metallic or
Transmission Weight is 1; an unconnected Surface (volume-only or empty). A node group in the
surface counts as possibly diffuse. Only the materials given are changed; the shared group is
(re)built once per call (``nodes.ensure_node_group``).
Every material is checked before it is changed; an error while changing it is rolled back.
"""

import functools
import json
from typing import NamedTuple

import bpy

from . import compat
from .nodes import GROUP_NAME, ensure_node_group

# Custom property of the added group node: JSON {"version": 1, "outputs": [...]}.
NODE_MARKER = "sh_lighting_original_links"
RECORD_VERSION = 1

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
    """The group nodes this module added to ``material`` (normally zero or one)."""
    tree = getattr(material, "node_tree", None)
    if tree is None:
        return []
    return [
        node for node in tree.nodes if node.bl_idname == "ShaderNodeGroup" and NODE_MARKER in node
    ]


def is_applied(material):
    """True when ``material`` holds an SH Irradiance node added by ``apply_to_materials``."""
    return bool(added_nodes(material))


def apply_to_materials(materials, scene):
    """Drive each material's surface by the SH group; returns ``Result(changed, skipped)``."""
    changed, skipped = [], []
    # The group, built once, when the first material gets it (an error: again next time).
    group = functools.cache(ensure_node_group)
    for material in _unique(materials):
        name = _name(material)
        try:
            _apply_one(material, group)
        except SkipMaterial as error:
            skipped.append((name, str(error)))
            continue
        changed.append(name)
    return Result(changed, skipped)


def _apply_one(material, group):
    """Apply to one material (refreshing it if applied); SkipMaterial when left alone.

    ``group``: returns the SH group, called only once the material is known to take it.
    """
    _check_editable(material)
    refreshed = is_applied(material)
    if refreshed:
        try:
            _remove(material)
        except SkipMaterial as error:
            raise SkipMaterial(f"SH lighting is already applied and {error}") from None
    try:
        plan = _plan(material)
    except SkipMaterial as error:
        if refreshed:
            raise SkipMaterial(f"SH lighting removed, not re-applied: {error}") from None
        raise
    tree = group()
    try:
        _apply(material, plan, tree)
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


# Shader nodes without a diffuse part (4.2 to 5.0 names; absent ones simply never match).
NO_DIFFUSE_SHADERS = frozenset(
    {
        "ShaderNodeEmission",
        "ShaderNodeBsdfGlass",
        "ShaderNodeBsdfRefraction",
        "ShaderNodeBsdfTransparent",
        "ShaderNodeHoldout",
        "ShaderNodeBsdfGlossy",
        "ShaderNodeBsdfAnisotropic",
        "ShaderNodeBsdfMetallic",
        "ShaderNodeBsdfHair",
        "ShaderNodeBsdfHairPrincipled",
        "ShaderNodeBsdfRayPortal",
        "ShaderNodeBackground",
    }
)
SHADER_SUMS = frozenset({"ShaderNodeMixShader", "ShaderNodeAddShader"})
# Unlinked Principled inputs that remove its diffuse base when at 1.
PRINCIPLED_NON_DIFFUSE_INPUTS = ("Metallic", "Transmission Weight", "Transmission")


def _surface_shaders(output):
    """The shader nodes the Surface of ``output`` sums (through reroutes, Mix and Add Shader).

    [] when the Surface is not connected.
    """
    leaves, stack, seen = [], [output.inputs["Surface"]], set()
    while stack:
        node = _source_node(stack.pop())
        if node is None or node.as_pointer() in seen:
            continue
        seen.add(node.as_pointer())
        if node.bl_idname in SHADER_SUMS and not node.mute:
            stack.extend(s for s in node.inputs if s.type == "SHADER")
        else:
            leaves.append(node)
    return leaves


def _has_no_diffuse(node):
    if node.bl_idname in NO_DIFFUSE_SHADERS:
        return True
    if node.bl_idname != "ShaderNodeBsdfPrincipled" or node.mute:
        return False
    for name in PRINCIPLED_NON_DIFFUSE_INPUTS:
        socket = node.inputs.get(name)
        if socket is not None and not socket.is_linked and socket.default_value >= 1.0:
            return True
    return False


def _check_diffuse_part(active):
    """SkipMaterial when what ``active`` renders has no diffuse part (see the docstring)."""
    leaves = _surface_shaders(active)
    if not leaves:
        if _linked_socket(active.inputs["Volume"]) is not None:
            raise SkipMaterial("volume only: no surface shader, so no diffuse part to light")
        raise SkipMaterial("no diffuse part: the Material Output's Surface is not connected")
    if all(_has_no_diffuse(node) for node in leaves):
        kinds = ", ".join(sorted({node.bl_idname for node in leaves}))
        raise SkipMaterial(
            f"no diffuse base colour: the surface is only {kinds}, which has no diffuse part"
        )


class _Plan(NamedTuple):
    outputs: list  # every Material Output node
    active: object  # the output the BSDF was traced from, for placing the new node
    albedo: object  # socket linked to the base colour, or None
    albedo_value: tuple  # base colour value, used when ``albedo`` is None
    normal: object  # socket linked to the BSDF's Normal, or None


def _plan(material):
    """Check ``material`` and find what to link, without changing anything."""
    tree = material.node_tree
    outputs = [node for node in tree.nodes if node.bl_idname == "ShaderNodeOutputMaterial"]
    if not outputs:
        raise SkipMaterial("no Material Output node")
    active = next((node for node in outputs if node.is_active_output), outputs[0])
    _check_diffuse_part(active)
    bsdf = _traced_bsdf(active)
    if bsdf is None:
        candidates = [node for node in tree.nodes if node.bl_idname in BASE_COLOUR_INPUTS]
        if len(candidates) != 1:
            surface = _source_node(active.inputs["Surface"])
            what = f"a {surface.bl_idname} node" if surface else "nothing"
            raise SkipMaterial(
                f"no diffuse base colour: the surface is {what} and the material has "
                f"{len(candidates)} Principled/Diffuse BSDF nodes (need exactly one)"
            )
        bsdf = candidates[0]
    colour = bsdf.inputs[BASE_COLOUR_INPUTS[bsdf.bl_idname]]
    return _Plan(
        outputs=outputs,
        active=active,
        albedo=_linked_socket(colour),
        albedo_value=tuple(colour.default_value),
        normal=_linked_socket(bsdf.inputs.get("Normal")),
    )


def _linked_socket(socket):
    """The output socket feeding ``socket`` through an unmuted link, or None."""
    if socket is None or not socket.is_linked:
        return None
    link = socket.links[0]
    return None if getattr(link, "is_muted", False) else link.from_socket


def _source_node(socket):
    """The node feeding ``socket``, looking through reroutes; None when unlinked."""
    for _ in range(1000):
        linked = _linked_socket(socket)
        if linked is None:
            return None
        node = linked.node
        if node.bl_idname != "NodeReroute":
            return node
        socket = node.inputs[0]
    return None


def _traced_bsdf(output):
    node = _source_node(output.inputs["Surface"])
    return node if node is not None and node.bl_idname in BASE_COLOUR_INPUTS else None


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


def _apply(material, plan, group):
    tree = material.node_tree
    record = {"version": RECORD_VERSION, "outputs": [_surface_record(o) for o in plan.outputs]}
    node = tree.nodes.new("ShaderNodeGroup")
    try:
        node.node_tree = group
        if node.node_tree != group:
            raise TypeError(f"'{group.name}' is not a shader node group")
        node.name = GROUP_NAME
        node.label = GROUP_NAME
        node.location = (plan.active.location.x - 40.0, plan.active.location.y + 260.0)
        node[NODE_MARKER] = json.dumps(record)
        if plan.albedo is not None:
            tree.links.new(plan.albedo, node.inputs["Albedo"])
        else:
            node.inputs["Albedo"].default_value = plan.albedo_value
        if plan.normal is not None:
            tree.links.new(plan.normal, node.inputs["Normal"])
        for output in plan.outputs:
            tree.links.new(node.outputs["Shader"], output.inputs["Surface"])
    except Exception:
        _restore(tree, node, record)
        raise


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
        _restore(tree, node, record)


def _restore(tree, node, record):
    """Relink each recorded output still driven by ``node`` (or left unlinked), drop ``node``."""
    for entry in record["outputs"]:
        output = tree.nodes.get(entry["output"])
        if output is None or output.bl_idname != "ShaderNodeOutputMaterial":
            continue
        surface = output.inputs["Surface"]
        if surface.is_linked and surface.links[0].from_node != node:
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
    tree.nodes.remove(node)


def _output_by_identifier(node, identifier):
    return next((s for s in node.outputs if s.identifier == identifier), None)
