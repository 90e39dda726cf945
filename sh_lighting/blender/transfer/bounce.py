"""The lamps' bounce in EEVEE: the "SH Lamp Bounce" group and its EEVEE-only output.

EEVEE's lamps light surfaces directly (with shadows) but bounce nothing off them, so under
Transfer + Extract Lights a scene whose Suns light a bright floor renders dark in EEVEE
(sunrise: 0.91 of the path-traced brightness, benchmarks/REPORT.md "texel"). The bake stores
the lamps' bounce B (irradiance after at least one bounce, ``bake``: a tenth Cycles bake with
the world black, Indirect only) per corner (``BOUNCE_ATTRIBUTE``) or per texel
(``BOUNCE_IMAGE``). The group emits Albedo · B / π; Apply adds it to the material's EEVEE
Material Output only (``glossy.add_for_eevee``): Cycles bounces the lamps itself.
"""

import json
from math import pi

import bpy

from ..shading import glossy, keep_bsdf, materials
from ..shading.nodes import Builder, find_marked_group
from .stale import BOUNCE_ATTRIBUTE, UV_NAME, bounce_image, record

GROUP_NAME = "SH Lamp Bounce (EEVEE)"
GROUP_MARKER = "sh_lighting_bounce_group"
GROUP_VERSION = 1
LABEL = "BSDF + SH diffuse + lamps' bounce (EEVEE)"
DESCRIPTION = ("The light of the scene's lamps after a bounce, baked by Cycles (EEVEE's lamps "
               "bounce none): an Emission of Albedo · B / π, B from the mesh attribute sh_TB or "
               "the image 'SH Transfer TB'")


def find_group():
    return find_marked_group(GROUP_MARKER, GROUP_NAME)


def ensure_group():
    """The file's "SH Lamp Bounce (EEVEE)" group, made if missing, its nodes (re)built."""
    tree = find_group()
    if tree is None:
        tree = bpy.data.node_groups.new(GROUP_NAME, "ShaderNodeTree")
        albedo = tree.interface.new_socket("Albedo", in_out="INPUT", socket_type="NodeSocketColor")
        albedo.default_value = (1.0, 1.0, 1.0, 1.0)
        tree.interface.new_socket("Shader", in_out="OUTPUT", socket_type="NodeSocketShader")
    tree.nodes.clear()
    b = Builder(tree)
    group_in = b.node("NodeGroupInput", 0, 1)
    attribute = b.node("ShaderNodeAttribute", 0, 0, "B per corner",
                       attribute_type="GEOMETRY", attribute_name=BOUNCE_ATTRIBUTE)
    bounce = attribute.outputs["Color"]
    image = bounce_image()
    if image is not None:  # a mesh without the UV map reads the atlas's zero corner
        uv = b.node("ShaderNodeAttribute", 0, 2, "Transfer UV",
                    attribute_type="GEOMETRY", attribute_name=UV_NAME)
        texel = b.node("ShaderNodeTexImage", 1, 2, "B per texel", image=image,
                       interpolation="Linear", extension="EXTEND")
        b.link(uv.outputs["Vector"], texel.inputs["Vector"])
        both = b.vector_math("ADD", 2, 0, "B corner + texel")
        b.link(bounce, both.inputs[0])
        b.link(texel.outputs["Color"], both.inputs[1])
        bounce = both.outputs["Vector"]
    lit = b.vector_math("MULTIPLY", 3, 0, "Albedo · B")
    b.link(group_in.outputs["Albedo"], lit.inputs[0])
    b.link(bounce, lit.inputs[1])
    scaled = b.vector_math("SCALE", 4, 0, "/ π")
    b.link(lit.outputs["Vector"], scaled.inputs[0])
    scaled.inputs["Scale"].default_value = 1.0 / pi
    emission = b.node("ShaderNodeEmission", 5, 0)
    b.link(scaled.outputs["Vector"], emission.inputs["Color"])
    group_out = b.node("NodeGroupOutput", 6, 0)
    b.link(emission.outputs["Emission"], group_out.inputs["Shader"])
    tree[GROUP_MARKER] = GROUP_VERSION
    if hasattr(tree, "description"):
        tree.description = DESCRIPTION
    return tree


def has_bounce(material):
    """True when an object using ``material`` has a bake with the lamps' bounce."""
    return any((record(o) or {}).get("bounce") for o in bpy.data.objects
               if any(s.material == material for s in getattr(o, "material_slots", ())))


def add_to_material(material, node):
    """Add the lamps' bounce to ``material``'s EEVEE output beside Apply's group ``node``
    (Keep BSDF only: Emission Only has no lamps), its nodes listed in ``node``'s record so
    that Remove deletes them. True if added."""
    record_text = node.get(materials.NODE_MARKER)
    applied = json.loads(record_text) if record_text else {}
    if applied.get("mode") != "KEEP_BSDF" or not has_bounce(material):
        return False
    tree = material.node_tree
    added = []
    b = keep_bsdf.Builder(material, added, [])
    group = b.node("ShaderNodeGroup", "SH Lamp Bounce (EEVEE)")
    group.node_tree = ensure_group()
    group.location = (node.location.x, node.location.y + 200.0)
    albedo = node.inputs["Albedo"]
    if albedo.is_linked:
        tree.links.new(albedo.links[0].from_socket, group.inputs["Albedo"])
    else:
        group.inputs["Albedo"].default_value = albedo.default_value
    outputs = [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial"]
    active = next((n for n in outputs if n.is_active_output and n.target != "EEVEE"),
                  next((n for n in outputs if n.target != "EEVEE"), outputs[0]))
    glossy.add_for_eevee(b, group.outputs["Shader"], outputs, active, LABEL)
    applied["added"] = list(applied.get("added", ())) + [n.name for n in added]
    node[materials.NODE_MARKER] = json.dumps(applied)
    material.update_tag()
    return True
