"""The "SH Irradiance" shader node group: eq. 13 of the paper, built from native nodes only.

One group serves every material and every scene of a .blend file. Its nine Attribute nodes of
type View Layer read ``sh_L00`` ... ``sh_L22`` (``scene_data.PROPERTY_NAMES``) at render time
from the view layer, scene or world being rendered, so

* editing or keyframing a coefficient reaches the next render without rebuilding the tree;
* a material shared by two scenes shows each scene's own lighting: the group does not depend on
  the scene it was built for, hence one group per file, not one per scene;
* a saved .blend renders the same where this add-on is not installed (no Script/OSL node, no
  registered property: plain custom properties, REFERENCE.md §3), in Cycles and EEVEE alike.

Interface
  inputs   Normal (vector, world space; unlinked or zero = the shading normal of the Geometry
           node. Shader node groups cannot default a socket to the normal, so a zero-length
           input is replaced by Geometry > Normal inside the group),
           Albedo (colour, default white)
  outputs  Irradiance (E(n), eq. 13), Diffuse (Albedo · E / π, the radiance a Lambertian
           surface reflects), Shader (Emission of colour Diffuse, strength 1: a drop-in surface)

The group is recognised by the custom property ``GROUP_MARKER`` (not by its name, which the
user may change); ``ensure_node_group`` rebuilds the inside of the existing group (keeping its
interface, so materials stay linked) instead of adding a second one.
"""

from math import pi

import bpy

from ..core.irradiance import C1, C2, C3, C4, C5
from ..core.sh import COEFFICIENT_NAMES
from .scene_data import PROPERTY_NAMES

GROUP_NAME = "SH Irradiance"
# Custom property on the node group; its value is the layout version of the tree inside.
GROUP_MARKER = "sh_lighting_group"
GROUP_VERSION = 1

# (name, in_out, socket type, default value, description), in interface order.
INTERFACE = (
    (
        "Normal",
        "INPUT",
        "NodeSocketVector",
        (0.0, 0.0, 0.0),
        "World-space unit normal; leave unlinked for the shading normal",
    ),
    ("Albedo", "INPUT", "NodeSocketColor", (1.0, 1.0, 1.0, 1.0), "Diffuse reflectance"),
    ("Irradiance", "OUTPUT", "NodeSocketColor", None, "E(n), eq. 13 of Ramamoorthi-Hanrahan"),
    ("Diffuse", "OUTPUT", "NodeSocketColor", None, "Albedo times irradiance divided by pi"),
    ("Shader", "OUTPUT", "NodeSocketShader", None, "Emission of the Diffuse colour"),
)

# Below this squared length the Normal input counts as unlinked (its default is zero).
ZERO_NORMAL_SQUARED = 1e-12


def is_sh_group(tree):
    """True for a node group built by this module."""
    return getattr(tree, "bl_idname", "") == "ShaderNodeTree" and GROUP_MARKER in tree


def find_node_group():
    """The local SH group of this file or None; "SH Irradiance" itself is preferred."""
    found = [
        tree for tree in bpy.data.node_groups if tree.library is None and is_sh_group(tree)
    ]
    found.sort(key=lambda tree: (tree.name != GROUP_NAME, tree.name))
    return found[0] if found else None


def ensure_node_group(scene):
    """The file's "SH Irradiance" ShaderNodeTree, created or rebuilt in place.

    ``scene`` is the scene whose lighting is meant; the group reads the coefficients of
    whatever scene renders it (see the module docstring), so it is the same for all scenes.
    Calling this again reuses the group: its interface is kept (links into it from materials
    survive) and its nodes are rebuilt, repairing any edit made by hand.
    """
    if not isinstance(scene, bpy.types.Scene):
        raise TypeError(f"ensure_node_group needs a bpy.types.Scene, got {type(scene).__name__}")
    tree = find_node_group()
    if tree is None:
        tree = bpy.data.node_groups.new(GROUP_NAME, "ShaderNodeTree")
    _ensure_interface(tree)
    _build_nodes(tree)
    tree[GROUP_MARKER] = GROUP_VERSION
    if hasattr(tree, "description"):  # NodeTree.description is not in every 4.x
        tree.description = (
            "Diffuse lighting from 9 spherical-harmonic coefficients (scene custom properties "
            "sh_L00 ... sh_L22), eq. 13 of Ramamoorthi and Hanrahan 2001"
        )
    return tree


def _ensure_interface(tree):
    """Give ``tree`` exactly the INTERFACE sockets, reusing matching ones (their links too)."""
    wanted = {(name, in_out): kind for name, in_out, kind, _default, _text in INTERFACE}
    interface = tree.interface
    for panel in [item for item in interface.items_tree if item.item_type == "PANEL"]:
        interface.remove(panel, move_content_to_parent=True)
    existing = {}
    for item in list(interface.items_tree):
        key = (item.name, item.in_out)
        if wanted.get(key) != item.socket_type or key in existing:
            interface.remove(item)
        else:
            existing[key] = item
    for name, in_out, kind, default, text in INTERFACE:
        socket = existing.get((name, in_out))
        if socket is None:
            socket = interface.new_socket(name, in_out=in_out, socket_type=kind)
        socket.description = text
        if default is not None:
            socket.default_value = default
    socket = _interface_socket(tree, "Normal", "INPUT")
    socket.hide_value = True
    # Order: outputs and inputs each in INTERFACE order (Blender lists outputs first).
    for position, (name, in_out, *_rest) in enumerate(
        [spec for spec in INTERFACE if spec[1] == "OUTPUT"]
        + [spec for spec in INTERFACE if spec[1] == "INPUT"]
    ):
        interface.move(_interface_socket(tree, name, in_out), position)


def _interface_socket(tree, name, in_out):
    for item in tree.interface.items_tree:
        if item.item_type == "SOCKET" and item.name == name and item.in_out == in_out:
            return item
    raise LookupError(f"node group '{tree.name}' has no {in_out.lower()} socket '{name}'")


class _Builder:
    """Small helpers to add nodes at grid positions and link them by socket index or name."""

    def __init__(self, tree):
        self.tree = tree

    def node(self, kind, column, row, label="", **settings):
        node = self.tree.nodes.new(kind)
        node.location = (column * 200.0, -row * 160.0)
        if label:
            node.label = label
        for key, value in settings.items():
            setattr(node, key, value)
        return node

    def vector_math(self, operation, column, row, label=""):
        return self.node("ShaderNodeVectorMath", column, row, label, operation=operation)

    def math(self, operation, column, row, label=""):
        return self.node("ShaderNodeMath", column, row, label, operation=operation)

    def link(self, from_socket, to_socket):
        self.tree.links.new(from_socket, to_socket)


def _build_nodes(tree):
    """Clear ``tree`` and add the nodes of eq. 13 (see the module docstring)."""
    tree.nodes.clear()
    b = _Builder(tree)
    group_in = b.node("NodeGroupInput", 0, 0)
    geometry = b.node("ShaderNodeNewGeometry", 0, 2)

    # n = Normal input if it is non-zero, else the shading normal; then normalised.
    length2 = b.vector_math("DOT_PRODUCT", 1, 0, "|Normal|²")
    b.link(group_in.outputs["Normal"], length2.inputs[0])
    b.link(group_in.outputs["Normal"], length2.inputs[1])
    unlinked = b.math("LESS_THAN", 2, 0, "Normal unlinked")
    b.link(length2.outputs["Value"], unlinked.inputs[0])
    unlinked.inputs[1].default_value = ZERO_NORMAL_SQUARED
    chosen = b.vector_math("MULTIPLY_ADD", 3, 1, "Normal or shading normal")
    b.link(geometry.outputs["Normal"], chosen.inputs[0])
    b.link(unlinked.outputs["Value"], chosen.inputs[1])
    b.link(group_in.outputs["Normal"], chosen.inputs[2])
    normal = b.vector_math("NORMALIZE", 4, 1, "n")
    b.link(chosen.outputs["Vector"], normal.inputs[0])

    # The polynomial factors of each L_lm in eq. 13.
    xyz = b.node("ShaderNodeSeparateXYZ", 5, 0, "x y z")
    b.link(normal.outputs["Vector"], xyz.inputs[0])
    yzx = b.node("ShaderNodeCombineXYZ", 6, 0, "y z x")
    for source, target in (("Y", "X"), ("Z", "Y"), ("X", "Z")):
        b.link(xyz.outputs[source], yzx.inputs[target])
    products = b.vector_math("MULTIPLY", 7, 0, "xy yz zx")
    b.link(normal.outputs["Vector"], products.inputs[0])
    b.link(yzx.outputs["Vector"], products.inputs[1])
    cross = b.vector_math("SCALE", 8, 0, "2 c1 (xy yz zx)")
    b.link(products.outputs["Vector"], cross.inputs[0])
    cross.inputs["Scale"].default_value = 2.0 * C1
    cross_xyz = b.node("ShaderNodeSeparateXYZ", 9, 0, "2c1 xy, 2c1 yz, 2c1 zx")
    b.link(cross.outputs["Vector"], cross_xyz.inputs[0])

    linear = b.vector_math("SCALE", 8, 1, "2 c2 n")
    b.link(normal.outputs["Vector"], linear.inputs[0])
    linear.inputs["Scale"].default_value = 2.0 * C2
    linear_xyz = b.node("ShaderNodeSeparateXYZ", 9, 1, "2c2 x, 2c2 y, 2c2 z")
    b.link(linear.outputs["Vector"], linear_xyz.inputs[0])

    squares = b.vector_math("MULTIPLY", 7, 2, "x² y² z²")
    b.link(normal.outputs["Vector"], squares.inputs[0])
    b.link(normal.outputs["Vector"], squares.inputs[1])
    f22 = b.vector_math("DOT_PRODUCT", 8, 2, "c1 (x² − y²)")
    b.link(squares.outputs["Vector"], f22.inputs[0])
    f22.inputs[1].default_value = (C1, -C1, 0.0)
    squares_xyz = b.node("ShaderNodeSeparateXYZ", 8, 3, "x² y² z²")
    b.link(squares.outputs["Vector"], squares_xyz.inputs[0])
    f20 = b.math("MULTIPLY_ADD", 9, 3, "c3 z² − c5")
    b.link(squares_xyz.outputs["Z"], f20.inputs[0])
    f20.inputs[1].default_value = C3
    f20.inputs[2].default_value = -C5

    factors = {
        "L1-1": linear_xyz.outputs["Y"],
        "L10": linear_xyz.outputs["Z"],
        "L11": linear_xyz.outputs["X"],
        "L2-2": cross_xyz.outputs["X"],
        "L2-1": cross_xyz.outputs["Y"],
        "L20": f20.outputs["Value"],
        "L21": cross_xyz.outputs["Z"],
        "L22": f22.outputs["Value"],
    }

    # E = c4 L00 + Σ factor_lm L_lm, one Multiply Add per term (RGB as vectors).
    total = None
    for row, (name, prop) in enumerate(zip(COEFFICIENT_NAMES, PROPERTY_NAMES)):
        attribute = b.node(
            "ShaderNodeAttribute",
            10,
            row,
            name,
            attribute_type="VIEW_LAYER",
            attribute_name=prop,
        )
        if total is None:
            term = b.vector_math("SCALE", 11, row, "c4 L00")
            b.link(attribute.outputs["Vector"], term.inputs[0])
            term.inputs["Scale"].default_value = C4
        else:
            term = b.vector_math("MULTIPLY_ADD", 11, row, f"+ {name} term")
            b.link(attribute.outputs["Vector"], term.inputs[0])
            b.link(factors[name], term.inputs[1])
            b.link(total.outputs["Vector"], term.inputs[2])
        total = term

    albedo_e = b.vector_math("MULTIPLY", 12, 7, "Albedo · E")
    b.link(group_in.outputs["Albedo"], albedo_e.inputs[0])
    b.link(total.outputs["Vector"], albedo_e.inputs[1])
    diffuse = b.vector_math("SCALE", 13, 7, "/ π")
    b.link(albedo_e.outputs["Vector"], diffuse.inputs[0])
    diffuse.inputs["Scale"].default_value = 1.0 / pi
    emission = b.node("ShaderNodeEmission", 14, 8)
    b.link(diffuse.outputs["Vector"], emission.inputs["Color"])
    emission.inputs["Strength"].default_value = 1.0

    group_out = b.node("NodeGroupOutput", 15, 7)
    b.link(total.outputs["Vector"], group_out.inputs["Irradiance"])
    b.link(diffuse.outputs["Vector"], group_out.inputs["Diffuse"])
    b.link(emission.outputs["Emission"], group_out.inputs["Shader"])
