"""Which shaders make up a material's surface, with the weight each is mixed in at.

``surface_leaves`` walks the Material Output's Surface through reroutes, Mix Shader and Add
Shader nodes down to the shaders they combine. A Mix Shader renders (1 − Fac) · Shader 1 +
Fac · Shader 2, so each leaf carries the path of mix factors that scales it (``Leaf.path``):
the SH term of a leaf is scaled by the same factors (a Mix 0.5 of a Principled and a black
Emission gets half the SH term, a Mix with a Transparent BSDF as much less as the
Transparent takes). A shader reached along two paths is two leaves. Muted links count as
absent; a muted Mix or Add Shader passes its first shader input on (Blender's internal
link), a muted shader renders nothing.

A material has a diffuse part when a leaf is a Principled BSDF or a Diffuse BSDF; shaders
without one (``NO_DIFFUSE_SHADERS``) are left out of the sum; any other leaf (a node group,
Subsurface Scattering, Toon, ...) is one whose diffuse colour this module cannot read, and
the material is refused with its name rather than given some other node's colour.

Reroutes are looked through by ``node_links.source_socket``, the project's one walker.
"""

from typing import NamedTuple

from ..data.node_links import source_socket


def linked_socket(socket):
    """The output socket feeding ``socket`` (through reroutes, unmuted links), or None."""
    return source_socket(socket)


def source_node(socket):
    """The node feeding ``socket``, looking through reroutes; None when unlinked."""
    linked = source_socket(socket)
    return None if linked is None else linked.node


# Shader nodes without a diffuse part (4.2 to 5.0 names; absent ones simply never match).
NO_DIFFUSE_SHADERS = frozenset(
    {
        "ShaderNodeEmission",
        "ShaderNodeBsdfGlass",
        "ShaderNodeBsdfRefraction",
        "ShaderNodeBsdfTransparent",
        "ShaderNodeHoldout",
        "ShaderNodeBsdfGlossy",
        "ShaderNodeBsdfAnisotropic",
        "ShaderNodeBsdfMetallic",
        "ShaderNodeBsdfHair",
        "ShaderNodeBsdfHairPrincipled",
        "ShaderNodeBsdfRayPortal",
        "ShaderNodeBackground",
    }
)
DIFFUSE_SHADERS = {"ShaderNodeBsdfPrincipled": "Base Color", "ShaderNodeBsdfDiffuse": "Color"}
# Unlinked Principled inputs that remove its diffuse base when at 1.
PRINCIPLED_NON_DIFFUSE_INPUTS = ("Metallic", "Transmission Weight", "Transmission")
MAX_LEAVES = 64


class Leaf(NamedTuple):
    node: object
    # ((mix node, True for Shader 2 / False for Shader 1), ...) from the output down
    path: tuple


def surface_leaves(output):
    """The ``Leaf``s of what Material Output ``output``'s Surface renders (module docstring)."""
    leaves, stack = [], [(output.inputs["Surface"], ())]
    while stack:
        socket, path = stack.pop()
        node = source_node(socket)
        if node is None:
            continue
        kind = node.bl_idname
        if kind == "ShaderNodeMixShader":
            shaders = [s for s in node.inputs if s.type == "SHADER"]
            if node.mute:
                stack.append((shaders[0], path))
            else:
                stack.append((shaders[1], path + ((node, True),)))
                stack.append((shaders[0], path + ((node, False),)))
        elif kind == "ShaderNodeAddShader":
            shaders = [s for s in node.inputs if s.type == "SHADER"]
            stack.extend((s, path) for s in (shaders[:1] if node.mute else reversed(shaders)))
        elif not node.mute:
            leaves.append(Leaf(node, path))
        if len(leaves) > MAX_LEAVES:
            raise ValueError(f"the surface combines more than {MAX_LEAVES} shaders")
    return leaves


def _has_no_diffuse(node):
    if node.bl_idname in NO_DIFFUSE_SHADERS:
        return True
    if node.bl_idname != "ShaderNodeBsdfPrincipled":
        return False
    for name in PRINCIPLED_NON_DIFFUSE_INPUTS:
        socket = node.inputs.get(name)
        if socket is not None and not socket.is_linked and socket.default_value >= 1.0:
            return True
    return False


def diffuse_leaves(output):
    """(the diffuse leaves of ``output``'s surface, why it has none or cannot be read).

    Exactly one of the two is empty/None.
    """
    try:
        leaves = surface_leaves(output)
    except ValueError as error:
        return [], str(error)
    if not leaves:
        if source_socket(output.inputs["Volume"]) is not None:
            return [], "volume only: no surface shader, so no diffuse part to light"
        return [], "no diffuse part: the Material Output's Surface is not connected"
    unreadable = [leaf.node for leaf in leaves
                  if leaf.node.bl_idname not in DIFFUSE_SHADERS
                  and leaf.node.bl_idname not in NO_DIFFUSE_SHADERS]
    if unreadable:
        node = unreadable[0]
        what = (f"node group '{node.node_tree.name}'" if node.bl_idname == "ShaderNodeGroup"
                and node.node_tree is not None else f"a {node.bl_idname} node")
        return [], (f"its surface comes from {what} ('{node.name}'), whose diffuse colour "
                    "cannot be read: connect a Principled or Diffuse BSDF to the Material "
                    "Output (or use Emission Only with your own SH Irradiance node)")
    diffuse = [leaf for leaf in leaves if not _has_no_diffuse(leaf.node)]
    if not diffuse:
        kinds = ", ".join(sorted({leaf.node.bl_idname for leaf in leaves}))
        return [], f"no diffuse base colour: the surface is only {kinds}, which has no diffuse part"
    return diffuse, None


def no_diffuse_reason(active):
    """Why what Material Output ``active`` renders has no readable diffuse part, or None."""
    return diffuse_leaves(active)[1]
