"""Which shaders make up a material's surface, with the weight each is mixed in at.

``surface_leaves`` walks the Surface through reroutes, Mix and Add Shaders to the shaders they
combine; a Mix renders (1 − Fac) · Shader 1 + Fac · Shader 2, so each leaf carries its path of
factors (``Leaf.path``), which scale its SH term too. Muted links are absent, a muted Mix or
Add passes its first input. Principled and Diffuse BSDFs have a diffuse part,
``NO_DIFFUSE_SHADERS`` none; any other leaf (a group, Subsurface, Toon) makes the material
refused by name.
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


def reflects_only(output):
    """True when ``output``'s surface has no diffuse part but a Principled BSDF (a metal, a
    glass): Keep BSDF adds no SH diffuse term to it, yet it reflects the world."""
    leaves, reason = diffuse_leaves(output)
    if reason is None or not reason.startswith("no diffuse base colour"):
        return False
    return any(leaf.node.bl_idname == "ShaderNodeBsdfPrincipled"
               for leaf in surface_leaves(output))


def no_diffuse_reason(active):
    """Why what Material Output ``active`` renders has no readable diffuse part, or None."""
    return diffuse_leaves(active)[1]
