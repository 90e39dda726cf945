"""The "SH Transfer" shader node group: E(p) = Σ T_lm(p) L_lm from native nodes only.

Precomputed radiance transfer for diffuse surfaces (Sloan, Kautz and Snyder 2002, eq. 3): L_lm
= s_lm · c_lm from the "SH Irradiance" group's View Layer readers (live sliders, keyframes),
T_lm(p) per face corner from the colour attributes ``bake.ATTRIBUTE_NAMES`` plus, where the
file has a per-texel atlas (``texels``), its nine images read at the UV map ``UV_NAME`` (a
mesh without either reads 0 from it); per channel E = Σ T_lm ⊙ L_lm. Same interface as "SH Irradiance" (Normal unused: T_lm holds the
orientation); outputs Irradiance, Diffuse = Albedo · E / π, Shader (an Emission of Diffuse
that diffuse rays do not see: the bounce is in T_lm already). Unbaked objects read 0.
"""

import bpy

from ...core.sh import COEFFICIENT_NAMES
from ..shading.nodes import (
    Builder,
    diffuse_outputs,
    ensure_interface,
    find_marked_group,
    lighting_readers,
    readable_everywhere,
)
from .stale import ATTRIBUTE_NAMES, UV_NAME, atlas_images

GROUP_NAME = "SH Transfer"
GROUP_MARKER = "sh_lighting_transfer_group"
GROUP_VERSION = 3
DESCRIPTION = (
    "Diffuse lighting with shadows and interreflection: E = sum of T_lm (baked per corner in "
    "the mesh attributes sh_T00 ... sh_T22) times L_lm (scene properties sh_L00 ... sh_L22 "
    "times their gains); precomputed radiance transfer, Sloan, Kautz and Snyder 2002"
)


def find_node_group():
    return find_marked_group(GROUP_MARKER, GROUP_NAME)


def ensure_node_group():
    """The file's "SH Transfer" group, created if missing, its nodes (re)built."""
    tree = find_node_group()
    if tree is None:
        tree = bpy.data.node_groups.new(GROUP_NAME, "ShaderNodeTree")
    ensure_interface(tree)
    _build_nodes(tree)
    readable_everywhere()
    tree[GROUP_MARKER] = GROUP_VERSION
    if hasattr(tree, "description"):
        tree.description = DESCRIPTION
    return tree


def _build_nodes(tree):
    tree.nodes.clear()
    b = Builder(tree)
    group_in = b.node("NodeGroupInput", 0, 9)
    images = atlas_images()  # no image nodes where no mesh is baked per texel
    if images is not None:
        uv = b.node("ShaderNodeAttribute", 0, 10, "Transfer UV",
                    attribute_type="GEOMETRY", attribute_name=UV_NAME)
    total = None
    for index in reversed(range(9)):
        name = COEFFICIENT_NAMES[index]
        coefficient, gain = lighting_readers(b, index, 3, 1, index)
        transfer = b.node(
            "ShaderNodeAttribute", 2, index, f"T {name}",
            attribute_type="GEOMETRY", attribute_name=ATTRIBUTE_NAMES[index],
        )
        scaled = b.vector_math("SCALE", 4, index + 0.5, f"s {name} · T")
        if images is None:
            b.link(transfer.outputs["Color"], scaled.inputs[0])
        else:
            texel = b.node("ShaderNodeTexImage", 1, index + 0.5, f"T {name} per texel",
                           image=images[index], interpolation="Linear", extension="EXTEND")
            b.link(uv.outputs["Vector"], texel.inputs["Vector"])
            both = b.vector_math("ADD", 3, index + 0.5, f"T {name} corner + texel")
            b.link(transfer.outputs["Color"], both.inputs[0])
            b.link(texel.outputs["Color"], both.inputs[1])
            b.link(both.outputs["Vector"], scaled.inputs[0])
        b.link(gain, scaled.inputs["Scale"])
        if total is None:
            term = b.vector_math("MULTIPLY", 5, index, f"T {name} L {name}")
        else:
            term = b.vector_math("MULTIPLY_ADD", 5, index, f"+ T {name} L {name}")
            b.link(total, term.inputs[2])
        b.link(coefficient, term.inputs[0])
        b.link(scaled.outputs["Vector"], term.inputs[1])
        total = term.outputs[0]

    emission = diffuse_outputs(b, group_in, total, 6)
    # Strength 1 − Is Diffuse Ray: T_lm already holds the interreflection, so diffuse rays
    # arriving from other surfaces must not see this light again (in "KEEP_BSDF" the BSDF
    # would count it twice); camera, glossy and transmission rays see it.
    light_path = b.node("ShaderNodeLightPath", 6, 9)
    strength = b.math("SUBTRACT", 7, 9, "1 − diffuse ray")
    strength.inputs[0].default_value = 1.0
    b.link(light_path.outputs["Is Diffuse Ray"], strength.inputs[1])
    b.link(strength.outputs[0], emission.inputs["Strength"])
