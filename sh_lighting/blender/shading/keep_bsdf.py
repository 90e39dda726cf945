"""Apply mode "KEEP_BSDF": the material keeps its BSDF, the SH term replaces the world's diffuse.

The material's Surface becomes Add Shader(original surface, SH group "Shader"), the group's
Albedo being the BSDF's diffuse weight: for a Diffuse BSDF its Color; for a Principled BSDF

    Base Color · (1 − Metallic) · (1 − Transmission Weight) · (1 − F0),  F0 = ((η − 1)/(η + 1))²

with η its IOR. That is how Cycles layers the Principled BSDF: metallic and transmission are
mixed in over the dielectric base, and the dielectric specular layer takes its directional
albedo off the diffuse below it. F0 (the layer's albedo at normal incidence, smooth) stands in
for Cycles' tabulated albedo, which also depends on roughness and view angle: measured on a
white sphere under a white sky (diffuse light = render − render with the world invisible to
diffuse rays, 512 samples), Cycles' diffuse weight at IOR 1.5 is 0.959-0.965 facing the camera
(F0 gives 0.960) and falls to 0.88 (roughness 0) / 0.92 (roughness 0.5) at grazing view.
Coat, sheen and Specular IOR Level are not modelled (their attenuation of the diffuse is
left out). Linked inputs are followed: the weight is computed by Math nodes at render time.

The world's diffuse light must then not reach the BSDF as well. In Cycles the world's ray
visibility for diffuse rays (``World.cycles_visibility.diffuse``) is switched off: diffuse
closures neither see the world through bounces nor sample it as a light, while glossy and
transmission closures still reflect and refract it, and lamps light every closure
(``hide_world_diffuse``). The original value is kept on the world (``WORLD_MARKER``) and put
back when no material of the file is applied in this mode any more (``restore_worlds``).
EEVEE has no such switch: its world lighting is one capture (a sphere probe plus the
spherical harmonics derived from it) serving diffuse and glossy alike, and it ignores ray
visibility, so in EEVEE this mode adds the SH term to the world's own diffuse light (counted
twice); use the "EMISSION" mode for EEVEE renders (or a world without lighting).
"""

import json

# Custom property of a world whose diffuse visibility this module switched off: JSON
# {"diffuse": the original value}.
WORLD_MARKER = "sh_lighting_world_diffuse"

PRINCIPLED = "ShaderNodeBsdfPrincipled"
# Principled inputs each taking a fraction (its value) of the diffuse base away (4.2-5.0 names).
WEIGHT_INPUTS = ("Metallic", "Transmission Weight")


def _feed(tree, socket, source):
    """Drive node input ``socket`` by BSDF input ``source``: its link if linked, else its value."""
    if source.is_linked and not getattr(source.links[0], "is_muted", False):
        tree.links.new(source.links[0].from_socket, socket)
    else:
        socket.default_value = source.default_value


def _math(tree, added, operation, first=None, second=None):
    node = tree.nodes.new("ShaderNodeMath")
    node.operation = operation
    node.label = f"SH diffuse weight ({operation.lower()})"
    added.append(node)
    for socket, value in ((node.inputs[0], first), (node.inputs[1], second)):
        if isinstance(value, (int, float)):
            socket.default_value = value
        elif value is not None:
            tree.links.new(value, socket)
    return node


def diffuse_weight(tree, bsdf, added):
    """An output socket of the Principled ``bsdf``'s diffuse weight (module docstring), built
    from Math nodes appended to ``added``; None for a BSDF whose weight is 1 (Diffuse BSDF)."""
    if bsdf.bl_idname != PRINCIPLED:
        return None
    factors = []
    for name in WEIGHT_INPUTS:
        source = bsdf.inputs.get(name)
        if source is None:
            continue
        node = _math(tree, added, "SUBTRACT", 1.0)
        _feed(tree, node.inputs[1], source)
        factors.append(node.outputs[0])
    ior = bsdf.inputs.get("IOR")
    if ior is not None:
        below = _math(tree, added, "SUBTRACT", None, 1.0)
        above = _math(tree, added, "ADD", None, 1.0)
        _feed(tree, below.inputs[0], ior)
        _feed(tree, above.inputs[0], ior)
        ratio = _math(tree, added, "DIVIDE", below.outputs[0], above.outputs[0])
        f0 = _math(tree, added, "POWER", ratio.outputs[0], 2.0)
        factors.append(_math(tree, added, "SUBTRACT", 1.0, f0.outputs[0]).outputs[0])
    weight = factors[0] if factors else None
    for factor in factors[1:]:
        weight = _math(tree, added, "MULTIPLY", weight, factor).outputs[0]
    return weight


def weighted_albedo(tree, colour_socket, weight, added):
    """An output socket of colour × ``weight`` (a Vector Math Scale node, appended to ``added``).

    ``colour_socket``: the output linked to the base colour, or a colour value (4-tuple).
    """
    node = tree.nodes.new("ShaderNodeVectorMath")
    node.operation = "SCALE"
    node.label = "SH diffuse albedo"
    added.append(node)
    if isinstance(colour_socket, tuple):
        node.inputs[0].default_value = colour_socket[:3]
    else:
        tree.links.new(colour_socket, node.inputs[0])
    tree.links.new(weight, node.inputs["Scale"])
    return node.outputs["Vector"]


def hide_world_diffuse(world):
    """Switch ``world``'s Cycles diffuse ray visibility off, remembering the original once."""
    if world is None or world.library is not None:
        return
    if WORLD_MARKER not in world:
        world[WORLD_MARKER] = json.dumps({"diffuse": bool(world.cycles_visibility.diffuse)})
    world.cycles_visibility.diffuse = False


def restore_worlds(worlds):
    """Give every world of ``worlds`` marked by ``hide_world_diffuse`` its original diffuse
    visibility back and drop the mark; returns the names of the worlds restored."""
    restored = []
    for world in worlds:
        if world.library is not None or WORLD_MARKER not in world:
            continue
        try:
            original = bool(json.loads(world[WORLD_MARKER])["diffuse"])
        except (ValueError, KeyError, TypeError):
            original = True  # Blender's default
        world.cycles_visibility.diffuse = original
        del world[WORLD_MARKER]
        restored.append(world.name)
    return restored
