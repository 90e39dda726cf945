"""The "SH Irradiance" shader node group: eq. 13 of the paper, built from native nodes only.

E(n) = c1 L22 (x² − y²) + c3 L20 z² + c4 L00 − c5 L20 + 2 c1 (L2-2 xy + L21 xz + L2-1 yz)
+ 2 c2 (L11 x + L1-1 y + L10 z), with L_lm = s_lm · c_lm read at render time by Attribute
nodes (View Layer) from the scene's ``sh_L..`` properties and the gains' three packs
(``data.gain_packs``: 12 lookups, which EEVEE compiles 25× faster than 18): one group per file,
no add-on needed to render. Inputs Normal (zero: the shading normal) and Albedo; outputs Irradiance,
Diffuse = Albedo · E / π and Shader (an Emission of Diffuse). Found by ``GROUP_MARKER``;
``ensure_node_group`` rebuilds it in place. Details: docs/modules.md.
"""

from math import pi

import bpy

from ...core.irradiance import C1, C2, C3, C4, C5
from ...core.sh import COEFFICIENT_NAMES
from ..data import gain_packs, scene_data
from ..data.scene_data import PROPERTY_NAMES

GROUP_NAME = "SH Irradiance"
# Custom property on the node group; its value is the layout version of the tree inside.
GROUP_MARKER = "sh_lighting_group"
GROUP_VERSION = 5
DESCRIPTION = (
    "Diffuse lighting from 9 spherical-harmonic coefficients (scene custom properties "
    "sh_L00 ... sh_L22 times sh_L00_gain ... sh_L22_gain), eq. 13 of Ramamoorthi and "
    "Hanrahan 2001"
)

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
# Attribute node outputs by index: Color, Vector, Fac ("Factor" from 5.0 on), Alpha.
ATTRIBUTE_VECTOR, ATTRIBUTE_FAC = 1, 2


def find_marked_group(marker, name):
    """The file's local shader node group carrying custom property ``marker``, the one named
    ``name`` first (then by name), or None: how each of the add-on's groups is found."""
    found = [tree for tree in bpy.data.node_groups if tree.library is None
             and tree.bl_idname == "ShaderNodeTree" and marker in tree]
    found.sort(key=lambda tree: (tree.name != name, tree.name))
    return found[0] if found else None


def find_node_group():
    """The local SH group of this file or None; "SH Irradiance" itself is preferred."""
    return find_marked_group(GROUP_MARKER, GROUP_NAME)


def ensure_node_group():
    """The file's "SH Irradiance" ShaderNodeTree, created if missing, its nodes (re)built.

    The group reads the coefficients of whatever scene renders it. The interface is kept
    (links into it from materials survive); the nodes are rebuilt, repairing a hand edit.
    Scenes with coefficients but no gains (files from before the gains) get gains of 1, so
    that they render as before.
    """
    tree = find_node_group()
    if tree is None:
        tree = bpy.data.node_groups.new(GROUP_NAME, "ShaderNodeTree")
    _ensure_interface(tree)
    _build_nodes(tree)
    tree[GROUP_MARKER] = GROUP_VERSION
    if hasattr(tree, "description"):  # NodeTree.description is not in every 4.x
        tree.description = DESCRIPTION
    readable_everywhere()
    return tree


def readable_everywhere():
    """Give every scene with coefficients what the groups read: missing gains (s = 1) and
    the gains' packs (``gain_packs``). Each builder of a group reading the lighting calls it."""
    for scene in bpy.data.scenes:
        scene_data.add_missing_gains(scene)


def build_node_group(name=GROUP_NAME):
    """A new group holding the nodes of eq. 13 but no ``GROUP_MARKER`` (benchmarks, tests):
    the add-on never finds or reuses it."""
    tree = bpy.data.node_groups.new(name, "ShaderNodeTree")
    _ensure_interface(tree)
    _build_nodes(tree)
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
        if socket.description != text:
            socket.description = text
        if default is not None and tuple(socket.default_value) != default:
            socket.default_value = default
    socket = _interface_socket(tree, "Normal", "INPUT")
    if not socket.hide_value:
        socket.hide_value = True
    # Order: outputs and inputs each in INTERFACE order (Blender lists outputs first).
    ordered = [spec for spec in INTERFACE if spec[1] == "OUTPUT"] + [
        spec for spec in INTERFACE if spec[1] == "INPUT"
    ]
    for position, (name, in_out, *_rest) in enumerate(ordered):
        item = _interface_socket(tree, name, in_out)
        if item.position != position:
            interface.move(item, position)


def _interface_socket(tree, name, in_out):
    for item in tree.interface.items_tree:
        if item.item_type == "SOCKET" and item.name == name and item.in_out == in_out:
            return item
    raise LookupError(f"node group '{tree.name}' has no {in_out.lower()} socket '{name}'")


class _Builder:
    """Small helpers to add nodes at grid positions and link them by socket index or name."""

    def __init__(self, tree):
        self.tree = tree
        self.readers = {}  # nodes read once per group (``lighting_readers``'s gain packs)

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


def _normal(b, group_in):
    """n = Normal input if it is non-zero, else the shading normal; then normalised."""
    geometry = b.node("ShaderNodeNewGeometry", 0, 2)
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
    return normal.outputs["Vector"]


def _factors(b, n):
    """{term index: output socket of its polynomial factor} for l ≥ 1.

    Band 1: 2 c2 (x, y, z). Band 2: 2 c1 (xy, yz, zx) from n ⊙ (y, z, x); since |n| = 1,
    c3 z² − c5 = (x², y², z²) · (−c5, −c5, c3 − c5) and c1 (x² − y²) = (x², y², z²) · (c1, −c1, 0).
    """
    linear = b.vector_math("SCALE", 8, 1, "2 c2 n")
    b.link(n, linear.inputs[0])
    linear.inputs["Scale"].default_value = 2.0 * C2
    linear_xyz = b.node("ShaderNodeSeparateXYZ", 9, 1, "2c2 x, 2c2 y, 2c2 z")
    b.link(linear.outputs["Vector"], linear_xyz.inputs[0])
    factors = {1: linear_xyz.outputs["Y"], 2: linear_xyz.outputs["Z"], 3: linear_xyz.outputs["X"]}

    xyz = b.node("ShaderNodeSeparateXYZ", 5, 0, "x y z")
    b.link(n, xyz.inputs[0])
    yzx = b.node("ShaderNodeCombineXYZ", 6, 0, "y z x")
    for source, target in (("Y", "X"), ("Z", "Y"), ("X", "Z")):
        b.link(xyz.outputs[source], yzx.inputs[target])
    products = b.vector_math("MULTIPLY", 7, 0, "xy yz zx")
    b.link(n, products.inputs[0])
    b.link(yzx.outputs["Vector"], products.inputs[1])
    cross = b.vector_math("SCALE", 8, 0, "2 c1 (xy yz zx)")
    b.link(products.outputs["Vector"], cross.inputs[0])
    cross.inputs["Scale"].default_value = 2.0 * C1
    cross_xyz = b.node("ShaderNodeSeparateXYZ", 9, 0, "2c1 xy, 2c1 yz, 2c1 zx")
    b.link(cross.outputs["Vector"], cross_xyz.inputs[0])
    factors.update(
        {4: cross_xyz.outputs["X"], 5: cross_xyz.outputs["Y"], 7: cross_xyz.outputs["Z"]}
    )

    squares = b.vector_math("MULTIPLY", 7, 2, "x² y² z²")
    b.link(n, squares.inputs[0])
    b.link(n, squares.inputs[1])
    for index, weights, row, label in (
        (6, (-C5, -C5, C3 - C5), 3, "c3 z² − c5"),
        (8, (C1, -C1, 0.0), 2, "c1 (x² − y²)"),
    ):
        dot = b.vector_math("DOT_PRODUCT", 8, row, label)
        b.link(squares.outputs["Vector"], dot.inputs[0])
        dot.inputs[1].default_value = weights
        factors[index] = dot.outputs["Value"]
    return factors


def lighting_readers(b, index, column, gain_column, row):
    """The Attribute nodes (type View Layer) reading coefficient ``index`` of the scene being
    rendered: (c_lm vector socket, s_lm gain socket). The gain comes from its pack
    (``gain_packs``: three gains a lookup, 12 lookups in all), read once per group and split.
    Every group reading the lighting uses these (the "SH Transfer" group too), so all read
    the same properties the same way."""
    name = COEFFICIENT_NAMES[index]
    coefficient = b.node(
        "ShaderNodeAttribute", column, row, name,
        attribute_type="VIEW_LAYER", attribute_name=PROPERTY_NAMES[index],
    )
    pack, element = gain_packs.pack_of(index)
    split = b.readers.get(pack)
    if split is None:
        reader = b.node(
            "ShaderNodeAttribute", gain_column - 1, row + 0.5, f"gains {pack[-1]}",
            attribute_type="VIEW_LAYER", attribute_name=pack,
        )
        split = b.node("ShaderNodeSeparateXYZ", gain_column, row + 0.5, f"gains {pack[-1]}")
        b.link(reader.outputs[ATTRIBUTE_VECTOR], split.inputs[0])
        b.readers[pack] = split
    return coefficient.outputs[ATTRIBUTE_VECTOR], split.outputs[element]


def ensure_interface(tree):
    """Give ``tree`` the group interface of INTERFACE (Normal, Albedo; Irradiance, Diffuse,
    Shader), keeping matching sockets and their links (groups sharing it are swappable)."""
    _ensure_interface(tree)


Builder = _Builder  # for groups built beside this one (``transfer.nodes``)


def _build_nodes(tree):
    """Clear ``tree`` and add the nodes of eq. 13 (see the module docstring)."""
    tree.nodes.clear()
    b = _Builder(tree)
    group_in = b.node("NodeGroupInput", 0, 0)
    factors = _factors(b, _normal(b, group_in))

    # E = Σ (s_lm factor_lm) c_lm, one Vector Math node per term (factor c4 for L00), summed
    # from L22 back to L00: the usual smaller terms first, the constant c4 L00 last. Of the
    # orders a node tree can take, this one rounds least on physical lighting (float32 error
    # ≤ 3.1 u against 5.8 u for index order; tests/core/test_stability.py measures them).
    # The gain multiplies the scalar factor (one Math node), so s = 1 rounds nothing.
    total = None
    for index in reversed(range(9)):
        name = COEFFICIENT_NAMES[index]
        coefficient, gain = lighting_readers(b, index, 10, 9, index)
        scaled = b.math("MULTIPLY", 10, index + 0.5, f"s {name} × factor")
        b.link(gain, scaled.inputs[0])
        if index == 0:
            scaled.inputs[1].default_value = C4
        else:
            b.link(factors[index], scaled.inputs[1])
        label = "c4 L00" if index == 0 else f"{name} term"
        if total is None:
            term = b.vector_math("MULTIPLY", 11, index, label)
        else:
            term = b.vector_math("MULTIPLY_ADD", 11, index, f"+ {label}")
            b.link(total, term.inputs[2])
        b.link(coefficient, term.inputs[0])
        b.link(scaled.outputs[0], term.inputs[1])
        total = term.outputs[0]

    diffuse_outputs(b, group_in, total, 12)


def diffuse_outputs(b, group_in, total, column):
    """The group's outputs from its irradiance ``total`` (E): Irradiance E, Diffuse =
    Albedo · E / π and Shader, an Emission of Diffuse (Strength 1), in the columns from
    ``column`` on. Returns the Emission node (the transfer group drives its Strength)."""
    albedo_e = b.vector_math("MULTIPLY", column, 7, "Albedo · E")
    b.link(group_in.outputs["Albedo"], albedo_e.inputs[0])
    b.link(total, albedo_e.inputs[1])
    diffuse = b.vector_math("SCALE", column + 1, 7, "/ π")
    b.link(albedo_e.outputs["Vector"], diffuse.inputs[0])
    diffuse.inputs["Scale"].default_value = 1.0 / pi
    emission = b.node("ShaderNodeEmission", column + 2, 8)
    b.link(diffuse.outputs["Vector"], emission.inputs["Color"])
    emission.inputs["Strength"].default_value = 1.0
    group_out = b.node("NodeGroupOutput", column + 3, 7)
    b.link(total, group_out.inputs["Irradiance"])
    b.link(diffuse.outputs["Vector"], group_out.inputs["Diffuse"])
    b.link(emission.outputs["Emission"], group_out.inputs["Shader"])
    return emission
