"""The float32 model of the node group in tests/core/test_stability.py is the group nodes.py
builds: its tree, evaluated node by node with one float32 rounding per operation (Cycles' SVM
does one per node operation), gives the model's values bit for bit, so the error measured
there for the chosen summation order is the group's own.
"""

import bpy
import numpy as np
import pytest
from quadrature import random_directions
from test_stability import NODE_GROUP_ORDER, NODE_ORDERS, eval_node_chain

from sh_lighting.blender.shading import nodes
from sh_lighting.blender.data import gain_packs
from sh_lighting.blender.data.scene_data import PROPERTY_NAMES

pytestmark = pytest.mark.blender

F32 = np.float32


class TreeEvaluator:
    """Evaluates a shader node tree's Math, Vector Math, Separate/Combine XYZ and Attribute
    nodes in float32 over N normals; the node labelled "n" yields the given normals."""

    def __init__(self, tree, normals, attributes):
        self.tree, self.normals, self.attributes = tree, normals, attributes
        self.memo = {}

    def input(self, socket):
        if socket.is_linked:
            link = socket.links[0]
            return self.output(link.from_node, link.from_socket)
        value = socket.default_value
        return np.array([value[:]], F32) if hasattr(value, "__len__") else F32(value)  # (1, 3)

    def output(self, node, socket):
        key = (node.name, socket.identifier)
        if key not in self.memo:
            self.memo[key] = self.evaluate(node, socket)
        return self.memo[key]

    def evaluate(self, node, socket):
        kind, inputs = node.bl_idname, node.inputs
        if node.label == "n":
            return self.normals
        if kind == "ShaderNodeAttribute":
            return self.attributes[node.attribute_name]
        if kind == "ShaderNodeSeparateXYZ":
            return self.input(inputs[0])[:, "XYZ".index(socket.name)]
        if kind == "ShaderNodeCombineXYZ":
            return np.stack([self.input(inputs[axis]) for axis in "XYZ"], axis=-1)
        a = self.input(inputs[0])
        b = self.input(inputs[1]) if node.operation != "SCALE" else self.input(inputs["Scale"])
        if node.operation == "MULTIPLY":
            return vector(a) * vector(b) if kind == "ShaderNodeVectorMath" else a * b
        if node.operation == "SCALE":
            return a * b
        if node.operation == "MULTIPLY_ADD":
            c = self.input(inputs[2])
            if kind == "ShaderNodeVectorMath":
                return vector(a) * vector(b) + vector(c)
            return a * b + c
        if node.operation == "DOT_PRODUCT":
            products = a * b
            return (products[..., 0] + products[..., 1]) + products[..., 2]
        raise NotImplementedError(f"{kind} {node.operation}")


def vector(value):
    """A float socket feeding a vector input becomes (v, v, v), as in Blender."""
    value = np.asarray(value, F32)
    return value[..., None] if value.ndim == 1 else value


def group_irradiance(tree, normals, coeffs, gains):
    attributes = {
        name: np.broadcast_to(coeffs[i], (len(normals), 3)) for i, name in enumerate(PROPERTY_NAMES)
    }
    size = gain_packs.PACK_SIZE
    attributes.update({name: np.broadcast_to(F32(gains[k * size:(k + 1) * size]),
                                             (len(normals), size))
                       for k, name in enumerate(gain_packs.PACK_NAMES)})
    (output,) = [n for n in tree.nodes if n.bl_idname == "NodeGroupOutput"]
    return TreeEvaluator(tree, normals, attributes).input(output.inputs["Irradiance"])


def test_group_tree_is_the_float32_model_bit_for_bit():
    rng = np.random.default_rng(7)
    normals = random_directions(500, seed=8).astype(F32)
    scale = np.array([1.0, 0.3, 0.3, 0.3, 0.1, 0.1, 0.1, 0.1, 0.1])[:, None]
    coeffs = (rng.normal(size=(9, 3)) * scale).astype(F32)
    tree = nodes.build_node_group()
    read = {n.attribute_name for n in tree.nodes if n.bl_idname == "ShaderNodeAttribute"}
    assert read == set(PROPERTY_NAMES) | set(gain_packs.PACK_NAMES)
    got = group_irradiance(tree, normals, coeffs, np.ones(9))  # gains 1: nothing rounds more
    for channel in range(3):
        model = eval_node_chain(coeffs[:, channel], normals, NODE_ORDERS[NODE_GROUP_ORDER])
        assert got.dtype == F32 and np.array_equal(got[:, channel], model), channel
        other = eval_node_chain(coeffs[:, channel], normals, NODE_ORDERS["L00 first, index order"])
        assert not np.array_equal(got[:, channel], other)  # the order is visible in the bits
    gains = rng.uniform(-2.0, 3.0, 9)
    scaled = group_irradiance(tree, normals, coeffs, gains)
    for channel in range(3):
        model = eval_node_chain(
            (coeffs[:, channel] * gains).astype(F32), normals, NODE_ORDERS[NODE_GROUP_ORDER]
        )
        assert np.abs(scaled[:, channel] - model).max() < 1e-5 * np.abs(coeffs).max()
    bpy.data.node_groups.remove(tree)
