"""Temporary worlds whose radiance is one spherical harmonic (plus a constant), for the bake.

World 0 emits 1; world k ≥ 1 emits OFFSETS[k] + Y_lm(ω) (never negative: Cycles samples the
world as non-negative light), OFFSETS[k] = −min Y_lm, from native nodes (Texture Coordinate >
Generated is the ray's direction in a world). The bake is linear in the world, so the transfer
of Y_lm is bake(k) − OFFSETS[k] · bake(0) (Sloan, Kautz and Snyder 2002, §3-4). Checked: the
world 1 + ω_z bakes to 1 + 2/3 on an upward plane, ∫(1 + z) cos θ dω / π.
"""

import bpy

from ..data import compat
from ...core.sh import Y1, Y2_XY, Y20, Y22, Y00

WORLD_NAME = "SH Transfer Basis (temporary)"

# −min Y_lm over the unit sphere, in index order (index 0: the constant world, no offset).
OFFSETS = (0.0, Y1, Y1, Y1, Y2_XY / 2.0, Y2_XY / 2.0, Y20, Y2_XY / 2.0, Y22)
# The constant world's transfer is Y00 times its bake (Y_00 is the constant Y00).
CONSTANT_SCALE = Y00

# Y_lm as (scale, first component, second component) for the products and linear terms;
# components are "X", "Y", "Z" of ω; None = no second factor.
_PRODUCTS = {
    1: (Y1, "Y", None), 2: (Y1, "Z", None), 3: (Y1, "X", None),
    4: (Y2_XY, "X", "Y"), 5: (Y2_XY, "Y", "Z"), 7: (Y2_XY, "X", "Z"),
}


def new_basis_world(index):
    """A new world emitting basis world ``index`` (0-8, see the module docstring).

    The caller removes it (``bpy.data.worlds.remove``); it has no fake user and is named
    ``WORLD_NAME`` (Blender appends .001 ... if the name is taken).
    """
    if not 0 <= index <= 8:
        raise ValueError(f"basis index {index} out of range 0-8")
    world = bpy.data.worlds.new(WORLD_NAME)
    # No importance map: the radiance is smooth (degree ≤ 2), cosine-weighted BSDF sampling
    # suits it, and building Cycles' map for each bake cost ~15 s of a ~16 s bake.
    world.cycles.sampling_method = "NONE"
    tree = compat.ensure_node_tree(world)
    tree.nodes.clear()
    background = tree.nodes.new("ShaderNodeBackground")
    background.inputs["Strength"].default_value = 1.0
    output = tree.nodes.new("ShaderNodeOutputWorld")
    output.location = (300.0, 0.0)
    tree.links.new(background.outputs["Background"], output.inputs["Surface"])
    if index == 0:
        background.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
        return world
    value = _basis_value(tree, index)
    offset = _math(tree, "ADD", -200.0)
    tree.links.new(value, offset.inputs[0])
    offset.inputs[1].default_value = OFFSETS[index]
    tree.links.new(offset.outputs[0], background.inputs["Color"])
    return world


def _math(tree, operation, x):
    node = tree.nodes.new("ShaderNodeMath")
    node.operation = operation
    node.location = (x, 0.0)
    return node


def _basis_value(tree, index):
    """Output socket of Y_lm(ω) for ``index`` ≥ 1 (ω = normalised Generated)."""
    coordinates = tree.nodes.new("ShaderNodeTexCoord")
    coordinates.location = (-1200.0, 0.0)
    unit = tree.nodes.new("ShaderNodeVectorMath")
    unit.operation = "NORMALIZE"
    unit.location = (-1000.0, 0.0)
    tree.links.new(coordinates.outputs["Generated"], unit.inputs[0])
    xyz = tree.nodes.new("ShaderNodeSeparateXYZ")
    xyz.location = (-800.0, 0.0)
    tree.links.new(unit.outputs["Vector"], xyz.inputs[0])
    if index in _PRODUCTS:
        scale, first, second = _PRODUCTS[index]
        value = xyz.outputs[first]
        if second is not None:
            product = _math(tree, "MULTIPLY", -600.0)
            tree.links.new(xyz.outputs[first], product.inputs[0])
            tree.links.new(xyz.outputs[second], product.inputs[1])
            value = product.outputs[0]
        scaled = _math(tree, "MULTIPLY", -400.0)
        tree.links.new(value, scaled.inputs[0])
        scaled.inputs[1].default_value = scale
        return scaled.outputs[0]
    # Y20 = Y20 (3 z² − 1) = 3 Y20 z² − Y20;  Y22 = Y22 (x² − y²) = Y22 (x − y)(x + y).
    if index == 6:
        square = _math(tree, "MULTIPLY", -600.0)
        tree.links.new(xyz.outputs["Z"], square.inputs[0])
        tree.links.new(xyz.outputs["Z"], square.inputs[1])
        value = _math(tree, "MULTIPLY_ADD", -400.0)
        tree.links.new(square.outputs[0], value.inputs[0])
        value.inputs[1].default_value = 3.0 * Y20
        value.inputs[2].default_value = -Y20
        return value.outputs[0]
    difference = _math(tree, "SUBTRACT", -650.0)
    tree.links.new(xyz.outputs["X"], difference.inputs[0])
    tree.links.new(xyz.outputs["Y"], difference.inputs[1])
    total = _math(tree, "ADD", -650.0)
    tree.links.new(xyz.outputs["X"], total.inputs[0])
    tree.links.new(xyz.outputs["Y"], total.inputs[1])
    product = _math(tree, "MULTIPLY", -500.0)
    tree.links.new(difference.outputs[0], product.inputs[0])
    tree.links.new(total.outputs[0], product.inputs[1])
    value = _math(tree, "MULTIPLY", -400.0)
    tree.links.new(product.outputs[0], value.inputs[0])
    value.inputs[1].default_value = Y22
    return value.outputs[0]
