"""The few places where Blender 4.2 LTS and 5.0 differ, in one module (REFERENCE.md §3b)."""

import bpy

BLENDER_VERSION = bpy.app.version


def eevee_engine_id():
    """'BLENDER_EEVEE_NEXT' in 4.2-4.5, 'BLENDER_EEVEE' from 5.0 on."""
    return "BLENDER_EEVEE" if BLENDER_VERSION >= (5, 0, 0) else "BLENDER_EEVEE_NEXT"


def ensure_node_tree(datablock):
    """The node tree of a material or world, creating it the way this Blender version wants.

    ``use_nodes`` is deprecated in 5.0, where new materials and worlds already have trees.
    """
    if datablock.node_tree is None:
        datablock.use_nodes = True
    return datablock.node_tree
