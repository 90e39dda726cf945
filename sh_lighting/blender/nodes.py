"""The "SH Irradiance" shader node group: eq. 13 of the paper, built from native nodes only.

One group serves every material and every scene of a .blend file. Its Attribute nodes of type
View Layer read ``sh_L00`` ... ``sh_L22`` (``scene_data.PROPERTY_NAMES``) at render time from
the view layer, scene or world being rendered, so

* editing or keyframing a coefficient reaches the next render without rebuilding the tree;
* a material shared by two scenes shows each scene's own lighting: the group does not depend on
  the scene it was built for, hence one group per file, not one per scene;
* a saved .blend renders the same where this add-on is not installed (no Script/OSL node, no
  registered property: plain custom properties, REFERENCE.md §3), in Cycles and EEVEE alike.

Fitted to the lighting (a ``GroupSpec`` chosen by ``fitting.fitted_spec``): the group holds
only the terms the file's lighting needs (``core.pruning``: a term is left out when it, and the
sum of everything left out, stay below the scene's tolerance at every keyed frame), scalar
Math nodes when the kept coefficients are grey, and a clamp max(E, 0) only when E can go
negative (or the scene asks for one). A band with no kept term has no nodes at all.
``FULL_SPEC`` (all nine terms, RGB, no clamp) is what a file without coefficients gets; a
tolerance of 0 keeps all nine terms (grey and clamp still follow the lighting).

Interface
  inputs   Normal (vector, world space; unlinked or zero = the shading normal of the Geometry
           node. Shader node groups cannot default a socket to the normal, so a zero-length
           input is replaced by Geometry > Normal inside the group),
           Albedo (colour, default white)
  outputs  Irradiance (E(n), eq. 13), Diffuse (Albedo · E / π, the radiance a Lambertian
           surface reflects), Shader (Emission of colour Diffuse, strength 1: a drop-in surface)

The group is recognised by the custom property ``GROUP_MARKER`` (not by its name, which the
user may change). ``FIT_PROPERTY`` (JSON) records what it was built for: the spec, what was left
out and its exact error bound, the node count, a fingerprint of the nodes (a hand edit is
repaired at the next fit) and a signature of each scene's coefficient animation (the panel's
"Refit needed" hint). The tree is rebuilt in place (its interface and the links of materials
into it are kept) only when the spec or the fingerprint differs.
"""

import hashlib
import json
from dataclasses import dataclass
from math import pi

import bpy

from ..core.irradiance import C1, C2, C3, C4, C5
from ..core.pruning import ALL_TERMS
from ..core.sh import COEFFICIENT_NAMES
from . import fitting
from .scene_data import PROPERTY_NAMES

GROUP_NAME = "SH Irradiance"
# Custom property on the node group; its value is the layout version of the tree inside.
GROUP_MARKER = "sh_lighting_group"
GROUP_VERSION = 3
FIT_PROPERTY = "sh_lighting_fit"

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


@dataclass(frozen=True)
class GroupSpec:
    """What the group computes: kept terms (indices l(l+1)+m), scalar math, clamp."""

    terms: tuple = ALL_TERMS
    scalar: bool = False
    clamp: bool = False

    def as_dict(self):
        return {"terms": list(self.terms), "scalar": self.scalar, "clamp": self.clamp}

    @classmethod
    def from_dict(cls, data):
        terms = tuple(sorted({int(t) for t in data["terms"] if 0 <= int(t) <= 8}))
        return cls(terms, bool(data["scalar"]), bool(data["clamp"]))


FULL_SPEC = GroupSpec()


@dataclass(frozen=True)
class FitReport:
    """What ``refit_node_group`` did. ``group`` is None when the file has no SH group."""

    group: object
    spec: GroupSpec
    rebuilt: bool
    node_count: int
    omitted: tuple  # names of the left-out terms
    bound: float  # exact max |Σ omitted| over sphere and keyed frames, / mean irradiance
    bound_absolute: float


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


def fit_info(tree):
    """The decoded ``FIT_PROPERTY`` of a group, or None (absent, unreadable, older layout)."""
    if tree is None or tree.get(GROUP_MARKER) != GROUP_VERSION:
        return None
    try:
        info = json.loads(tree[FIT_PROPERTY])
        info["spec"] = GroupSpec.from_dict(info["spec"])
        return info
    except (KeyError, TypeError, ValueError):
        return None


def ensure_node_group(scene):
    """The file's "SH Irradiance" ShaderNodeTree, created if missing and fitted (see
    ``refit_node_group``); a tree edited by hand is rebuilt, repairing the edit.

    ``scene`` is the scene whose lighting is meant; the group reads the coefficients of
    whatever scene renders it, so it is fitted to every scene of the file that has them.
    The interface is kept (links into it from materials survive).
    """
    _check_scene(scene)
    tree = find_node_group()
    if tree is None:
        tree = bpy.data.node_groups.new(GROUP_NAME, "ShaderNodeTree")
    return _fit(tree).group


def build_node_group(spec, name=GROUP_NAME):
    """A new, unregistered-for-fitting group built to ``spec`` exactly (benchmarks, tests).

    It carries no ``GROUP_MARKER``, so the add-on never finds, refits or reuses it.
    """
    tree = bpy.data.node_groups.new(name, "ShaderNodeTree")
    _ensure_interface(tree)
    _build_nodes(tree, spec)
    return tree


def refit_node_group(scene):
    """Refit the file's SH group to the coefficients of every scene that has them.

    The needed terms are those of the current values and of every keyframed value at every
    frame of the scenes' frame (and preview) ranges (``fitting.scene_samples``). The tree is
    rebuilt only when that set, the scalar/clamp choice or the nodes themselves differ from
    what it holds. Without an SH group in the file nothing is created: returns a FitReport
    with ``group`` None.
    """
    _check_scene(scene)
    tree = find_node_group()
    if tree is None:
        return FitReport(None, FULL_SPEC, False, 0, (), 0.0, 0.0)
    return _fit(tree)


def _check_scene(scene):
    if not isinstance(scene, bpy.types.Scene):
        raise TypeError(f"the SH node group needs a bpy.types.Scene, got {type(scene).__name__}")


def _fit(tree):
    fit = fitting.fitted_spec(bpy.data.scenes)
    spec = GroupSpec(fit.terms, fit.scalar, fit.clamp)
    _ensure_interface(tree)
    info = fit_info(tree)
    # The nodes are compared only when the recorded spec is the wanted one.
    fingerprint = _fingerprint(tree) if info is not None and info["spec"] == spec else None
    rebuilt = fingerprint is None or info.get("fingerprint") != fingerprint
    if rebuilt:
        _build_nodes(tree, spec)
        tree[GROUP_MARKER] = GROUP_VERSION
        fingerprint = _fingerprint(tree)
    if hasattr(tree, "description"):  # NodeTree.description is not in every 4.x
        description = (
            "Diffuse lighting from 9 spherical-harmonic coefficients (scene custom properties "
            "sh_L00 ... sh_L22), eq. 13 of Ramamoorthi and Hanrahan 2001"
        )
        if tree.description != description:
            tree.description = description
    record = {
        "spec": spec.as_dict(),
        "omitted": [COEFFICIENT_NAMES[i] for i in ALL_TERMS if i not in spec.terms],
        "bound": fit.bound,
        "bound_absolute": fit.bound_absolute,
        "nodes": len(tree.nodes),
        "fingerprint": fingerprint,
        "scenes": fit.scenes,
    }
    text = json.dumps(record, sort_keys=True)
    if tree.get(FIT_PROPERTY) != text:
        tree[FIT_PROPERTY] = text
    return FitReport(
        tree, spec, rebuilt, len(tree.nodes), tuple(record["omitted"]), fit.bound,
        fit.bound_absolute,
    )


def refit_hint(scene, *, tree=..., info=...):
    """None when the file's SH group suits ``scene``'s current lighting, else a short reason.

    Cheap enough for a panel's draw: the current values only (no F-curve sampling), plus a
    comparison of the scene's animation signature with the one the group was fitted to.
    ``tree`` and ``info``: the group and its ``fit_info`` when the caller has them already
    (default: ``find_node_group()`` and ``fit_info(tree)``).
    """
    if tree is ...:
        tree = find_node_group()
    if tree is None:
        return None
    if info is ...:
        info = fit_info(tree)
    spec = info["spec"] if info is not None else FULL_SPEC
    recorded = info["scenes"].get(scene.name) if info is not None else None
    return fitting.hint(scene, spec.terms, spec.scalar, spec.clamp, recorded)


def _fingerprint(tree):
    """A digest of the nodes, their settings, unlinked input values and links."""
    parts = []
    for node in sorted(tree.nodes, key=lambda n: n.name):
        values = []
        for socket in node.inputs:
            if socket.is_linked or not hasattr(socket, "default_value"):
                continue
            value = socket.default_value
            value = tuple(value) if hasattr(value, "__len__") else (value,)
            values.append((socket.identifier, tuple(f"{v:.9g}" for v in value)))
        settings = tuple(
            str(getattr(node, key, "")) for key in ("operation", "attribute_type", "attribute_name")
        )
        parts.append((node.name, node.bl_idname, node.mute, settings, tuple(values)))
    links = sorted(
        (
            link.from_node.name,
            link.from_socket.identifier,
            link.to_node.name,
            link.to_socket.identifier,
            bool(getattr(link, "is_muted", False)),
        )
        for link in tree.links
    )
    return hashlib.blake2b(repr((parts, links)).encode(), digest_size=16).hexdigest()


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


def _factors(b, n, terms):
    """{term index: output socket of its polynomial factor}, only for ``terms`` (l ≥ 1).

    Band 1: 2 c2 (x, y, z). Band 2: 2 c1 (xy, yz, zx) from n ⊙ (y, z, x); since |n| = 1,
    c3 z² − c5 = (x², y², z²) · (−c5, −c5, c3 − c5) and c1 (x² − y²) = (x², y², z²) · (c1, −c1, 0).
    """
    factors = {}
    if {1, 2, 3} & set(terms):
        linear = b.vector_math("SCALE", 8, 1, "2 c2 n")
        b.link(n, linear.inputs[0])
        linear.inputs["Scale"].default_value = 2.0 * C2
        linear_xyz = b.node("ShaderNodeSeparateXYZ", 9, 1, "2c2 x, 2c2 y, 2c2 z")
        b.link(linear.outputs["Vector"], linear_xyz.inputs[0])
        factors.update({1: linear_xyz.outputs["Y"], 2: linear_xyz.outputs["Z"]})
        factors[3] = linear_xyz.outputs["X"]
    if {4, 5, 7} & set(terms):
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
        factors.update({4: cross_xyz.outputs["X"], 5: cross_xyz.outputs["Y"]})
        factors[7] = cross_xyz.outputs["Z"]
    if {6, 8} & set(terms):
        squares = b.vector_math("MULTIPLY", 7, 2, "x² y² z²")
        b.link(n, squares.inputs[0])
        b.link(n, squares.inputs[1])
        for index, weights, row, label in (
            (6, (-C5, -C5, C3 - C5), 3, "c3 z² − c5"),
            (8, (C1, -C1, 0.0), 2, "c1 (x² − y²)"),
        ):
            if index in terms:
                dot = b.vector_math("DOT_PRODUCT", 8, row, label)
                b.link(squares.outputs["Vector"], dot.inputs[0])
                dot.inputs[1].default_value = weights
                factors[index] = dot.outputs["Value"]
    return factors


def _build_nodes(tree, spec):
    """Clear ``tree`` and add the nodes of eq. 13 for ``spec`` (see the module docstring)."""
    tree.nodes.clear()
    b = _Builder(tree)
    group_in = b.node("NodeGroupInput", 0, 0)
    terms = tuple(sorted(spec.terms))
    factors = _factors(b, _normal(b, group_in), terms) if any(terms) else {}

    # E = Σ factor_lm L_lm, one (Vector) Math node per kept term (factor c4 for L00), summed
    # from L22 back to L00: the usual smaller terms first, the constant c4 L00 last. Of the
    # orders a node tree can take, this one rounds least on physical lighting (float32 error
    # ≤ 3.1 u against 5.8 u for index order; tests/core/test_stability.py measures them).
    total = None
    kind = ATTRIBUTE_FAC if spec.scalar else ATTRIBUTE_VECTOR
    new_math = b.math if spec.scalar else b.vector_math
    for index in reversed(terms):
        name = COEFFICIENT_NAMES[index]
        attribute = b.node(
            "ShaderNodeAttribute",
            10,
            index,
            name,
            attribute_type="VIEW_LAYER",
            attribute_name=PROPERTY_NAMES[index],
        )
        label = "c4 L00" if index == 0 else f"{name} term"
        if total is None:
            term = new_math("MULTIPLY", 11, index, label)
        else:
            term = new_math("MULTIPLY_ADD", 11, index, f"+ {label}")
            b.link(total, term.inputs[2])
        b.link(attribute.outputs[kind], term.inputs[0])
        if index == 0:
            term.inputs[1].default_value = C4 if spec.scalar else (C4, C4, C4)
        else:
            b.link(factors[index], term.inputs[1])
        total = term.outputs[0]
    if total is None:  # nothing kept: E = 0
        total = b.node("ShaderNodeValue", 11, 0, "E = 0").outputs[0]
        total.default_value = 0.0
    if spec.clamp:
        clamp = new_math("MAXIMUM", 12, 6, "max(E, 0)")
        b.link(total, clamp.inputs[0])
        clamp.inputs[1].default_value = 0.0 if spec.scalar else (0.0, 0.0, 0.0)
        total = clamp.outputs[0]

    albedo_e = b.vector_math("MULTIPLY", 12, 7, "Albedo · E")
    b.link(group_in.outputs["Albedo"], albedo_e.inputs[0])
    b.link(total, albedo_e.inputs[1])
    diffuse = b.vector_math("SCALE", 13, 7, "/ π")
    b.link(albedo_e.outputs["Vector"], diffuse.inputs[0])
    diffuse.inputs["Scale"].default_value = 1.0 / pi
    emission = b.node("ShaderNodeEmission", 14, 8)
    b.link(diffuse.outputs["Vector"], emission.inputs["Color"])
    emission.inputs["Strength"].default_value = 1.0

    group_out = b.node("NodeGroupOutput", 15, 7)
    b.link(total, group_out.inputs["Irradiance"])
    b.link(diffuse.outputs["Vector"], group_out.inputs["Diffuse"])
    b.link(emission.outputs["Emission"], group_out.inputs["Shader"])
