"""Light baked objects' materials by the "SH Transfer" group instead of "SH Irradiance".

The Apply machinery of ``shading.materials`` does the work (albedo and diffuse weight linked
from the BSDF, the recorded links, rollback, Remove): the materials are applied in the chosen
mode ("KEEP_BSDF": lamps, shadows and glossy reflections stay, the world's diffuse light is
replaced; "EMISSION": the transfer alone, exact and noise free at one sample), then each added
group node is pointed at the "SH Transfer" group (same interface) and marked with
``NODE_MARKER``. Remove (``materials.remove_from_materials``) undoes it like any Apply; Apply
again (the plain one) puts "SH Irradiance" back.

Only materials of baked objects are changed. A material also used by an object without a bake
would give that object no light (its Attribute nodes read 0): such materials are skipped with
the reason, nothing changed.

This is kept beside ``shading.materials`` rather than as one of its MODES while that module's
modes are being restructured (issue 21).
"""

from typing import NamedTuple

import bpy

from ..shading import materials
from . import bake, nodes

NODE_MARKER = "sh_lighting_transfer"
# Material custom property: its Cycles Emission Sampling before Apply Transfer set it to None.
SAMPLING_MARKER = "sh_lighting_transfer_emission_sampling"
MODES = ("KEEP_BSDF", "EMISSION")


class Result(NamedTuple):
    changed: list  # material names
    skipped: list  # (material or object name, reason)


def baked_objects(objects):
    """The objects among ``objects`` holding a transfer bake (a record and the attributes)."""
    return [o for o in objects if o.type == "MESH" and bake.record(o) is not None
            and all(o.data.color_attributes.get(n) for n in bake.ATTRIBUTE_NAMES)]


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
    group = nodes.ensure_node_group()
    result = materials.apply_to_materials(list(wanted.values()), scene, mode)
    for name in result.changed:
        material = wanted.get(name) or bpy.data.materials.get(name)
        for node in materials.added_nodes(material):
            node.node_tree = group
            node.label = nodes.GROUP_NAME
            node[NODE_MARKER] = 1
    return Result(list(result.changed), skipped + list(result.skipped))


def restore_emission_sampling(material):
    """Put back the Emission Sampling an older Apply Transfer replaced and marked with
    ``SAMPLING_MARKER`` (once the transfer is out). Apply itself now sets it to None and puts it
    back (``materials``: Cycles must not sample the SH emission as a light; measured on the
    transfer's test scene: 6.4 % too bright (8.7 % RMSE) with Auto, 0.05 % (0.96 %) with None)."""
    original = material.get(SAMPLING_MARKER)
    if original is None:
        return
    if getattr(material, "cycles", None) is not None and not uses_transfer(material):
        material.cycles.emission_sampling = original
        del material[SAMPLING_MARKER]


def remove_transfer_from(materials_list):
    """Take the transfer out of ``materials_list`` (``materials.remove_from_materials`` on
    those using it) and restore their Emission Sampling; the ``Result`` of the removal."""
    used = [m for m in materials_list if uses_transfer(m)]
    result = materials.remove_from_materials(used)
    for material in materials_list:
        restore_emission_sampling(material)
    return result


def uses_transfer(material):
    tree = getattr(material, "node_tree", None)
    return tree is not None and any(is_transfer_node(n) for n in tree.nodes)
