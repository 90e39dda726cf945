"""Light baked objects' materials by the "SH Transfer" group instead of "SH Irradiance".

``shading.materials``' Apply does the work in the chosen mode, then each added group node is
pointed at "SH Transfer" (same interface) and marked ``NODE_MARKER``; Remove undoes it like any
Apply (Emission Sampling None included: with Auto the transfer scene rendered 6.4 % too
bright). ``apply_keeping_transfer`` (the panel's Apply) keeps the transfer of baked objects.
Only materials of baked objects change: one also used by an unbaked object is skipped with the
reason (its Attribute nodes would read 0). Kept beside ``shading.materials``, not as one of its
MODES, while those modes are being restructured.
"""

from typing import NamedTuple

import bpy

from ..shading import materials
from . import bake, bounce, nodes

NODE_MARKER = "sh_lighting_transfer"
MODES = ("KEEP_BSDF", "EMISSION")


class Result(NamedTuple):
    changed: list  # material names
    skipped: list  # (material or object name, reason)


def baked_objects(objects):
    """The objects among ``objects`` holding a transfer bake (a record and the attributes)."""
    return [o for o in objects if o.type == "MESH" and bake.record(o) is not None
            and bake.missing_parts(o, bake.record(o)) is None]


def is_transfer_node(node):
    return node.bl_idname == "ShaderNodeGroup" and NODE_MARKER in node


def apply_transfer(objects, scene, mode="KEEP_BSDF"):
    """Apply "SH Transfer" to the materials of the baked ``objects``; ``Result``.

    Objects without a bake are skipped (named in ``skipped``); a ValueError for an unknown
    mode or when none of the objects is baked.
    """
    if mode not in MODES:
        raise ValueError(f"unknown transfer mode {mode!r}: use one of {', '.join(MODES)}")
    objects = list(objects)
    baked = baked_objects(objects)
    if not baked:
        raise ValueError("none of the objects has a transfer bake: bake the transfer first")
    skipped = [(o.name, "no transfer bake") for o in objects if o not in baked]
    baked_meshes = {o.data.as_pointer() for o in baked}
    users = {}
    for obj in bpy.data.objects:
        for slot in getattr(obj, "material_slots", ()):
            if slot.material is not None:
                users.setdefault(slot.material.name_full, []).append(obj)
    wanted = {}
    for obj in baked:
        for slot in obj.material_slots:
            material = slot.material
            if material is None or material.name_full in wanted:
                continue
            unbaked = [u.name for u in users.get(material.name_full, ())
                       if u.type != "MESH" or u.data.as_pointer() not in baked_meshes]
            if unbaked:
                skipped.append((material.name_full, (
                    f"also used by '{unbaked[0]}', which has no transfer bake (it would get no "
                    "light): bake it too or give it its own material")))
                continue
            wanted[material.name_full] = material
    result = materials.apply_to_materials(list(wanted.values()), scene, mode)
    use_transfer_group([wanted.get(n) or bpy.data.materials.get(n) for n in result.changed])
    return Result(list(result.changed), skipped + list(result.skipped))


def apply_keeping_transfer(materials_list, scene, mode):
    """``materials.apply_to_materials``, the materials lit by the transfer staying so (in
    ``mode``); (its ``Result``, names of those that kept the transfer)."""
    materials_list = list(materials_list)
    lit = {m.name_full: m for m in materials_list if uses_transfer(m)}
    result = materials.apply_to_materials(materials_list, scene, mode)
    kept = [name for name in result.changed if name in lit]
    use_transfer_group([lit[name] for name in kept])
    return result, kept


def use_transfer_group(materials_list):
    """Point the group nodes Apply added to ``materials_list`` at "SH Transfer" (same
    interface and record), mark them with ``NODE_MARKER``, and add the lamps' bounce for
    EEVEE where the bake has one (``bounce``)."""
    group = None
    for material in materials_list:
        for node in materials.added_nodes(material):
            group = group or nodes.ensure_node_group()
            node.node_tree = group
            node.label = nodes.GROUP_NAME
            node[NODE_MARKER] = 1
            bounce.add_to_material(material, node)


def remove_transfer_from(materials_list):
    """Take the transfer out of those of ``materials_list`` using it
    (``materials.remove_from_materials``: links, nodes and the Emission Sampling Apply set, as
    for any Apply); the ``Result`` of the removal."""
    return materials.remove_from_materials([m for m in materials_list if uses_transfer(m)])


def delete_bakes(objects, material_names=()):
    """Delete the transfer bakes (attributes, record) of ``objects`` and of the objects
    using a material named in ``material_names`` (those Remove took the lighting out of);
    the names of the objects that had one."""
    names = set(material_names)
    wanted = {o.as_pointer(): o for o in objects}
    for obj in bpy.data.objects:
        if any(s.material is not None and s.material.name_full in names
               for s in getattr(obj, "material_slots", ())):
            wanted.setdefault(obj.as_pointer(), obj)
    local = [o for o in wanted.values() if o.library is None
             and (o.type != "MESH" or o.data.library is None)]
    return [o.name for o in local if bake.remove_transfer(o)]


def uses_transfer(material):
    tree = getattr(material, "node_tree", None)
    return tree is not None and any(is_transfer_node(n) for n in tree.nodes)
