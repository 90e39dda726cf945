"""Does a material's surface have a diffuse part? And the link-following helpers it needs.

A Surface made only of (mixes and sums of) Emission, Glass, Refraction, Transparent, Holdout,
Glossy, Metallic, hair, Ray Portal or Background shaders, or of a Principled BSDF whose
unlinked Metallic or Transmission Weight is 1, has none; nor has an unconnected Surface
(volume-only or empty). A node group in the surface counts as possibly diffuse. Muted links
count as absent, reroutes are looked through.
"""


def linked_socket(socket):
    """The output socket feeding ``socket`` through an unmuted link, or None."""
    if socket is None or not socket.is_linked:
        return None
    link = socket.links[0]
    return None if getattr(link, "is_muted", False) else link.from_socket


def source_node(socket):
    """The node feeding ``socket``, looking through reroutes; None when unlinked."""
    for _ in range(1000):
        linked = linked_socket(socket)
        if linked is None:
            return None
        node = linked.node
        if node.bl_idname != "NodeReroute":
            return node
        socket = node.inputs[0]
    return None


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
SHADER_SUMS = frozenset({"ShaderNodeMixShader", "ShaderNodeAddShader"})
# Unlinked Principled inputs that remove its diffuse base when at 1.
PRINCIPLED_NON_DIFFUSE_INPUTS = ("Metallic", "Transmission Weight", "Transmission")


def _surface_shaders(output):
    """The shader nodes the Surface of ``output`` sums (through reroutes, Mix and Add Shader).

    [] when the Surface is not connected.
    """
    leaves, stack, seen = [], [output.inputs["Surface"]], set()
    while stack:
        node = source_node(stack.pop())
        if node is None or node.as_pointer() in seen:
            continue
        seen.add(node.as_pointer())
        if node.bl_idname in SHADER_SUMS and not node.mute:
            stack.extend(s for s in node.inputs if s.type == "SHADER")
        else:
            leaves.append(node)
    return leaves


def _has_no_diffuse(node):
    if node.bl_idname in NO_DIFFUSE_SHADERS:
        return True
    if node.bl_idname != "ShaderNodeBsdfPrincipled" or node.mute:
        return False
    for name in PRINCIPLED_NON_DIFFUSE_INPUTS:
        socket = node.inputs.get(name)
        if socket is not None and not socket.is_linked and socket.default_value >= 1.0:
            return True
    return False


def no_diffuse_reason(active):
    """Why what Material Output ``active`` renders has no diffuse part, or None if it has one."""
    leaves = _surface_shaders(active)
    if not leaves:
        if linked_socket(active.inputs["Volume"]) is not None:
            return "volume only: no surface shader, so no diffuse part to light"
        return "no diffuse part: the Material Output's Surface is not connected"
    if all(_has_no_diffuse(node) for node in leaves):
        kinds = ", ".join(sorted({node.bl_idname for node in leaves}))
        return f"no diffuse base colour: the surface is only {kinds}, which has no diffuse part"
    return None
