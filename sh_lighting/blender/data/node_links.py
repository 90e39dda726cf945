"""The one walker through reroutes: which output socket feeds a node input.

Used by the world reader (``world/reader.py``) and by the material analysis
(``shading/diffuse_weight.py``).
"""


class MutedLink(ValueError):
    """A muted or invalid link where ``source_socket(..., strict=True)`` wants a real one."""


def source_socket(socket, strict=False):
    """The output socket feeding input ``socket``, looking through reroutes; None if unlinked.

    A muted or invalid link counts as absent, or raises ``MutedLink`` when ``strict``.
    """
    for _ in range(10000):  # reroute chains cannot loop, but a broken file might
        if socket is None or not socket.is_linked:
            return None
        link = socket.links[0]
        if getattr(link, "is_muted", False) or not link.is_valid:
            if strict:
                raise MutedLink(f"the link into '{socket.node.name}' is muted or invalid")
            return None
        if link.from_node.bl_idname != "NodeReroute":
            return link.from_socket
        socket = link.from_node.inputs[0]
    return None


# Custom property of the "SH World Edit" node group (``world_edit``): readers of the world see
# through a group node using it, to the colour the world had before the edit.
WORLD_EDIT_MARKER = "sh_lighting_world_edit"


def is_world_edit(node):
    """True for a group node whose tree is a World Edit group."""
    tree = getattr(node, "node_tree", None) if node.bl_idname == "ShaderNodeGroup" else None
    return tree is not None and WORLD_EDIT_MARKER in tree


def colour_source(socket, strict=False):
    """``source_socket`` of a world's colour input, looking through World Edit nodes too:
    the colour the world has without the edit (None: a plain colour)."""
    source = source_socket(socket, strict)
    for _ in range(100):
        if source is None or not is_world_edit(source.node):
            return source
        source = source_socket(source.node.inputs[0], strict)
    return source
