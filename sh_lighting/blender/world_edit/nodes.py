"""The "SH World Edit" node group: the designed change added to the world's colour.

    C'(ω) = max(0, k C(ω) + Σ (s_lm c_lm − L⁰_lm) Y_lm(ω) / S)

where C is the colour reaching the world's Background (its Strength S multiplies C' after),
s_lm c_lm = L_lm the designed lighting read at render time by Attribute nodes of type View
Layer (``shading.nodes.lighting_readers``: the same properties the material group reads, so
keyframes, drivers and a farm without the add-on see them), L⁰ the world's own coefficients
and k = 1 (k = 0, L⁰ = 0: a world with none of its own, which then renders the nine terms
alone), both constants of the group. Y_lm (core/sh.py, eq. 3) of the ray direction in
Blender's world axes (Texture Coordinate > Generated, normalised), as the material group
evaluates them at a normal. With L = L⁰ each term is exactly 0 and C' = C: the world itself.

Interface: inputs Color (the world's colour), Strength (the Background's: linked to the same
source, or the value it had when the edit went in); output Color.
"""

import bpy

from ...core.sh import COEFFICIENT_NAMES, Y00, Y1, Y2_XY, Y20, Y22
from ..data.node_links import WORLD_EDIT_MARKER
from ..shading.nodes import Builder, lighting_readers, readable_everywhere

GROUP_NAME = "SH World Edit"
GROUP_VERSION = 2
DESCRIPTION = (
    "Adds the designed SH lighting change to the world's colour: max(0, k·Color + "
    "Σ (L_lm − L0_lm) Y_lm(direction) / Strength), L_lm read from the scene's sh_L00 ... "
    "sh_L22 times their gains at render time"
)
INTERFACE = (
    ("Color", "INPUT", "NodeSocketColor", "The colour reaching the world's Background"),
    ("Strength", "INPUT", "NodeSocketFloat", "The Background's Strength"),
    ("Color", "OUTPUT", "NodeSocketColor", "The edited colour"),
)


def new_group(world):
    """A new, empty-interfaced group for ``world`` (its nodes come from ``build``)."""
    tree = bpy.data.node_groups.new(f"{GROUP_NAME} ({world.name})", "ShaderNodeTree")
    for name, in_out, kind, text in INTERFACE:
        socket = tree.interface.new_socket(name, in_out=in_out, socket_type=kind)
        socket.description = text
    if hasattr(tree, "description"):
        tree.description = DESCRIPTION
    tree[WORLD_EDIT_MARKER] = GROUP_VERSION
    return tree


def _basis(b, direction):
    """{index: scalar socket of Y_lm(ω)} from the unit direction socket."""
    linear = b.vector_math("SCALE", 3, 1, "Y1 (x y z)")
    b.link(direction, linear.inputs[0])
    linear.inputs["Scale"].default_value = Y1
    linear_xyz = b.node("ShaderNodeSeparateXYZ", 4, 1, "Y1-1, Y10, Y11")
    b.link(linear.outputs["Vector"], linear_xyz.inputs[0])
    basis = {1: linear_xyz.outputs["Y"], 2: linear_xyz.outputs["Z"], 3: linear_xyz.outputs["X"]}

    xyz = b.node("ShaderNodeSeparateXYZ", 1, 0, "x y z")
    b.link(direction, xyz.inputs[0])
    yzx = b.node("ShaderNodeCombineXYZ", 2, 0, "y z x")
    for source, target in (("Y", "X"), ("Z", "Y"), ("X", "Z")):
        b.link(xyz.outputs[source], yzx.inputs[target])
    products = b.vector_math("MULTIPLY", 3, 0, "xy yz zx")
    b.link(direction, products.inputs[0])
    b.link(yzx.outputs["Vector"], products.inputs[1])
    cross = b.vector_math("SCALE", 4, 0, "Y2 (xy yz zx)")
    b.link(products.outputs["Vector"], cross.inputs[0])
    cross.inputs["Scale"].default_value = Y2_XY
    cross_xyz = b.node("ShaderNodeSeparateXYZ", 5, 0, "Y2-2, Y2-1, Y21")
    b.link(cross.outputs["Vector"], cross_xyz.inputs[0])
    basis.update({4: cross_xyz.outputs["X"], 5: cross_xyz.outputs["Y"],
                  7: cross_xyz.outputs["Z"]})

    squares = b.vector_math("MULTIPLY", 3, 2, "x² y² z²")
    b.link(direction, squares.inputs[0])
    b.link(direction, squares.inputs[1])
    # Y20 = Y20 (3z² − 1) = (x², y², z²)·(−Y20, −Y20, 2 Y20) on the unit sphere
    for index, weights, row, label in (
        (6, (-Y20, -Y20, 2.0 * Y20), 3, "Y20"),
        (8, (Y22, -Y22, 0.0), 2, "Y22"),
    ):
        dot = b.vector_math("DOT_PRODUCT", 4, row, label)
        b.link(squares.outputs["Vector"], dot.inputs[0])
        dot.inputs[1].default_value = weights
        basis[index] = dot.outputs["Value"]
    return basis


def _without_sources(b, colour, direction, sources, luminance):
    """The colour with each extracted source (``lights.Source``) lowered to min(C, B) where
    ω is within its cone and C is brighter than its threshold (``lights``)."""
    for row, source in enumerate(sources):
        row = 12 + 2 * row
        near = b.vector_math("DOT_PRODUCT", 2, row, "ω · source")
        b.link(direction, near.inputs[0])
        near.inputs[1].default_value = source.direction
        inside = b.math("GREATER_THAN", 3, row, "in its cone")
        b.link(near.outputs["Value"], inside.inputs[0])
        inside.inputs[1].default_value = source.cos_radius
        bright = b.vector_math("DOT_PRODUCT", 2, row + 1, "luminance")
        b.link(colour, bright.inputs[0])
        bright.inputs[1].default_value = tuple(float(v) for v in luminance)
        above = b.math("GREATER_THAN", 3, row + 1, "its texels")
        b.link(bright.outputs["Value"], above.inputs[0])
        above.inputs[1].default_value = source.threshold
        taken = b.math("MULTIPLY", 4, row, "taken out")
        b.link(inside.outputs["Value"], taken.inputs[0])
        b.link(above.outputs["Value"], taken.inputs[1])
        lowered = b.vector_math("MINIMUM", 4, row + 1, "min(C, B)")
        b.link(colour, lowered.inputs[0])
        lowered.inputs[1].default_value = source.background
        change = b.vector_math("SUBTRACT", 5, row, "min(C, B) − C")
        b.link(lowered.outputs["Vector"], change.inputs[0])
        b.link(colour, change.inputs[1])
        result = b.vector_math("MULTIPLY_ADD", 6, row, "without the source")
        b.link(change.outputs["Vector"], result.inputs[0])
        b.link(taken.outputs["Value"], result.inputs[1])
        b.link(colour, result.inputs[2])
        colour = result.outputs["Vector"]
    return colour


def build(tree, own, keep, sources=(), luminance=(0.2126, 0.7152, 0.0722)):
    """Clear ``tree`` and add the nodes of C' (module docstring): ``own`` (9, 3) L⁰,
    ``keep`` k (True: the world's colour stays, under the change), ``sources`` the
    ``lights.Source``s the world must no longer emit (their Sun lamps do), ``luminance`` the
    RGB weights of their thresholds."""
    tree.nodes.clear()
    readable_everywhere()
    b = Builder(tree)
    group_in = b.node("NodeGroupInput", 0, 4)
    coordinates = b.node("ShaderNodeTexCoord", 0, 1)
    direction = b.vector_math("NORMALIZE", 1, 1, "ω")
    b.link(coordinates.outputs["Generated"], direction.inputs[0])
    basis = _basis(b, direction.outputs["Vector"])
    colour = _without_sources(b, group_in.outputs[0], direction.outputs["Vector"], sources,
                              luminance)

    total = None
    for index in reversed(range(9)):  # small terms first, L00 last (as the material group)
        name = COEFFICIENT_NAMES[index]
        coefficient, gain = lighting_readers(b, index, 7, 6, index)
        designed = b.vector_math("SCALE", 8, index, f"{name} = s c")
        b.link(coefficient, designed.inputs[0])
        b.link(gain, designed.inputs["Scale"])
        change = b.vector_math("SUBTRACT", 9, index, f"{name} − own")
        b.link(designed.outputs["Vector"], change.inputs[0])
        change.inputs[1].default_value = tuple(float(v) for v in own[index])
        if total is None:
            term = b.vector_math("MULTIPLY", 10, index, f"{name} change")
        else:
            term = b.vector_math("MULTIPLY_ADD", 10, index, f"+ {name} change")
            b.link(total, term.inputs[2])
        b.link(change.outputs["Vector"], term.inputs[0])
        if index == 0:
            term.inputs[1].default_value = (Y00, Y00, Y00)
        else:
            b.link(basis[index], term.inputs[1])
        total = term.outputs["Vector"]

    inverse = b.math("DIVIDE", 10, 10, "1 / Strength")  # 0 for Strength 0 (safe division)
    inverse.inputs[0].default_value = 1.0
    b.link(group_in.outputs["Strength"], inverse.inputs[1])
    scaled = b.vector_math("SCALE", 11, 9, "change / Strength")
    b.link(total, scaled.inputs[0])
    b.link(inverse.outputs["Value"], scaled.inputs["Scale"])
    edited = b.vector_math("MULTIPLY_ADD", 12, 9, "k Color + change")
    b.link(colour, edited.inputs[0])
    value = 1.0 if keep else 0.0
    edited.inputs[1].default_value = (value, value, value)
    b.link(scaled.outputs["Vector"], edited.inputs[2])
    clamped = b.vector_math("MAXIMUM", 13, 9, "max(0, ·)")
    b.link(edited.outputs["Vector"], clamped.inputs[0])
    clamped.inputs[1].default_value = (0.0, 0.0, 0.0)
    group_out = b.node("NodeGroupOutput", 14, 9)
    b.link(clamped.outputs["Vector"], group_out.inputs[0])
    tree[WORLD_EDIT_MARKER] = GROUP_VERSION
