"""The SH group's Albedo: the diffuse part of a material's surface, followed, never copied.

albedo = Σ_leaves Π_path (Fac or 1 − Fac) · colour · w over the diffuse leaves of the Surface
(``diffuse_weight.surface_leaves``): w = 1 for a Diffuse BSDF; for a Principled BSDF
w = Alpha · (1 − Metallic) · (1 − Transmission Weight) · (1 − F0), F0 = ((η − 1)/(η + 1))² · 2s
with s its Specular IOR Level (left out in "EMISSION"), as Cycles layers it. Each input is
linked to the same source, or to a Value/RGB node holding its value (with its keyframes and
drivers) that feeds both the BSDF and the SH term; ``release`` puts the values back. Details:
docs/modules.md.
"""

from ..data import compat
from ..data.node_links import source_socket
from .diffuse_weight import DIFFUSE_SHADERS
from .world_diffuse import WORLD_MARKER  # noqa: F401  (the world's mark; kept importable here)

PRINCIPLED = "ShaderNodeBsdfPrincipled"
# Principled inputs each taking a fraction (its value) of the diffuse base away (4.2-5.0 names).
WEIGHT_INPUTS = ("Metallic", "Transmission Weight")


class Builder:
    """Adds nodes (appended to ``added``) and drivers to ``material``'s tree."""

    def __init__(self, material, added, held):
        self.material = material
        self.tree = material.node_tree
        self.added = added
        self.held = held
        self.sources = {}

    def node(self, kind, label, **settings):
        node = self.tree.nodes.new(kind)
        node.label = label
        for key, value in settings.items():
            setattr(node, key, value)
        self.added.append(node)
        return node

    def follow(self, target, source):
        """Link input ``target`` to what feeds input ``source`` of the user's node: its link's
        source socket; an unlinked ``source`` first gets a Value (or RGB) node of its value,
        which then feeds both (its keyframes and drivers move along: ``release``)."""
        linked = source_socket(source)
        if linked is None:
            key = source.as_pointer()
            linked = self.sources.get(key)
            if linked is None:
                linked = self.sources[key] = _hold(self.tree, source, self.held)
        self.tree.links.new(linked, target)

    def math(self, operation, first=None, second=None, third=None, label="SH diffuse weight",
             clamp=False):
        """A Math node; each operand a number, an output socket, or ("follow", input socket);
        ``clamp``: its result clamped to [0, 1]."""
        node = self.node("ShaderNodeMath", f"{label} ({operation.lower()})",
                         operation=operation, use_clamp=clamp)
        for socket, value in zip(node.inputs, (first, second, third)):
            if isinstance(value, (int, float)):
                socket.default_value = value
            elif isinstance(value, tuple):
                self.follow(socket, value[1])
            elif value is not None:
                self.tree.links.new(value, socket)
        return node.outputs[0]


def coverage_factors(b, leaf):
    """Output sockets whose product is the share of the surface the leaf renders: its Mix
    factors and, for a Principled BSDF, its Alpha."""
    factors = []
    for mix, second in leaf.path:
        fac = mix.inputs[0]
        factors.append(b.math("MULTIPLY", ("follow", fac), 1.0) if second
                       else b.math("SUBTRACT", 1.0, ("follow", fac)))
    alpha = leaf.node.inputs.get("Alpha") if leaf.node.bl_idname == PRINCIPLED else None
    if alpha is not None:
        factors.append(b.math("MULTIPLY", ("follow", alpha), 1.0))
    return factors


def product(b, factors, label="SH diffuse weight"):
    """An output socket of the product of ``factors`` (1.0 when there are none)."""
    weight = factors[0] if factors else 1.0
    for factor in factors[1:]:
        weight = b.math("MULTIPLY", weight, factor, label=label)
    return weight


def _leaf_factors(b, leaf, with_specular):
    """Output sockets (or numbers) whose product is the leaf's weight, Mix factors included."""
    factors = coverage_factors(b, leaf)
    bsdf = leaf.node
    if bsdf.bl_idname != PRINCIPLED:
        return factors
    for name in WEIGHT_INPUTS:
        source = bsdf.inputs.get(name)
        if source is not None:
            factors.append(b.math("SUBTRACT", 1.0, ("follow", source)))
    f0 = dielectric_f0(b, bsdf) if with_specular else None
    if f0 is not None:
        factors.append(b.math("SUBTRACT", 1.0, f0))
    return factors


def dielectric_f0(b, bsdf, label="SH diffuse weight"):
    """An output socket of F0 = min(((η − 1)/(η + 1))² · 2 s, 1) of Principled ``bsdf``'s IOR
    η and Specular IOR Level s (followed; s = 0.5 leaves F0 as the IOR gives it, 0 takes the
    reflection away, as Cycles scales it), or None when it has no IOR input."""
    ior = bsdf.inputs.get("IOR")
    if ior is None:
        return None
    ratio = b.math("DIVIDE", b.math("SUBTRACT", ("follow", ior), 1.0, label=label),
                   b.math("ADD", ("follow", ior), 1.0, label=label), label=label)
    f0 = b.math("POWER", ratio, 2.0, label=label)
    level = bsdf.inputs.get("Specular IOR Level")
    if level is None:
        return f0
    return b.math("MULTIPLY", f0, b.math("MULTIPLY", ("follow", level), 2.0, label=label),
                  label=label, clamp=True)


def albedo(material, leaves, with_specular, added, held, builder=None):
    """An output socket of the surface's diffuse albedo (module docstring), built from nodes
    appended to ``added``; ``with_specular``: include the (1 − F0) factor. The inputs given a
    Value/RGB node are appended to ``held`` as records for ``release``. ``builder``: a
    ``Builder`` shared with other nodes built from the same inputs (``glossy``), so that one
    held node feeds them all."""
    b = builder or Builder(material, added, held)
    total = None
    for leaf in leaves:
        weight = product(b, _leaf_factors(b, leaf, with_specular))
        scaled = b.node("ShaderNodeVectorMath", "SH diffuse albedo", operation="SCALE")
        b.follow(scaled.inputs[0], leaf.node.inputs[DIFFUSE_SHADERS[leaf.node.bl_idname]])
        if isinstance(weight, float):
            scaled.inputs["Scale"].default_value = weight
        else:
            b.tree.links.new(weight, scaled.inputs["Scale"])
        if total is None:
            total = scaled.outputs["Vector"]
        else:
            add = b.node("ShaderNodeVectorMath", "SH diffuse albedo (sum)", operation="ADD")
            b.tree.links.new(total, add.inputs[0])
            b.tree.links.new(scaled.outputs["Vector"], add.inputs[1])
            total = add.outputs["Vector"]
    return total


def _escape(name):
    return name.replace("\\", "\\\\").replace('"', '\\"')


def _move_curves(tree, old, new):
    """Point the keyframes and drivers of ``tree`` animating data path ``old`` at ``new``."""
    animation = tree.animation_data
    if animation is None:
        return
    curves = list(animation.drivers)
    if animation.action is not None:
        curves += list(compat.action_fcurves(tree))
    for fcurve in curves:
        if fcurve.data_path == old:
            fcurve.data_path = new


def _hold(tree, source, held):
    """A Value/RGB node holding unlinked input ``source``'s value, linked into it; returns its
    output socket and appends {"node", "to_node", "to_socket"} to ``held``."""
    colour = source.type == "RGBA"
    node = tree.nodes.new("ShaderNodeRGB" if colour else "ShaderNodeValue")
    owner = source.node
    node.label = f"{owner.name}: {source.name}"
    node.location = (owner.location.x - 220.0, owner.location.y - 60.0 * len(held))
    output = node.outputs[0]
    output.default_value = source.default_value
    _move_curves(tree, f'nodes["{_escape(owner.name)}"].{_input_path(source)}',
                 f'nodes["{_escape(node.name)}"].outputs[0].default_value')
    tree.links.new(output, source)
    held.append({"node": node.name, "to_node": owner.name, "to_socket": source.identifier})
    return output


def _input_path(socket):
    index = list(socket.node.inputs).index(socket)
    return f"inputs[{index}].default_value"


def release(tree, records):
    """Undo ``_hold``: each input gets its held node's current value (and its keyframes and
    drivers) back, unlinked; the held node is deleted."""
    for record in reversed(records):
        node = tree.nodes.get(record.get("node", ""))
        owner = tree.nodes.get(record.get("to_node", ""))
        if node is None or node.bl_idname not in ("ShaderNodeRGB", "ShaderNodeValue"):
            continue
        socket = None
        if owner is not None:
            socket = next((s for s in owner.inputs if s.identifier == record.get("to_socket")),
                          None)
        if socket is not None:
            socket.default_value = node.outputs[0].default_value
            _move_curves(tree, f'nodes["{_escape(node.name)}"].outputs[0].default_value',
                         f'nodes["{_escape(owner.name)}"].{_input_path(socket)}')
        tree.nodes.remove(node)
