"""The world stays the camera's background but gives no diffuse light: what "KEEP_BSDF" needs.

The SH term (eq. 13) is then the material's diffuse light, so the world must not add it again.
Cycles: the world's diffuse ray visibility is switched off (glossy and transmission still see
it). EEVEE ignores ray visibility and lights with one capture of the world shader (made with
"Is Camera Ray" 0), so a World Output of target EEVEE with Mix(nothing, the world, Is Camera
Ray) is added: the camera sees the world, the capture black. The old visibility and the added
nodes are recorded in ``WORLD_MARKER`` / ``NODE_MARKER``; ``restore`` puts them back and
deletes only nodes both marked and named in the record (a user's duplicate copies the mark).
Details: docs/modules.md.
"""

import json

from ..data import compat

# Custom property of a world prepared here: JSON {"diffuse": original visibility, "nodes": [...]}.
WORLD_MARKER = "sh_lighting_world_diffuse"
# Custom property of the nodes added to a world's tree.
NODE_MARKER = "sh_lighting_world_node"
OUTPUT_NAME = "SH Lighting: EEVEE World Output"

ENGINE_NOTES = {
    "CYCLES": "Cycles: the world lights diffuse surfaces through SH only; lamps, shadows and "
              "the world's reflections as usual",
    "EEVEE": "EEVEE: the world lights diffuse surfaces through SH only, its reflections "
             "come from prefiltered maps (Principled BSDFs); lamps and shadows as usual",
}


class WorldError(ValueError):
    """A world that cannot be kept from giving diffuse light (the message says why)."""


def is_prepared(world):
    return world is not None and WORLD_MARKER in world


def problem(world):
    """Why ``world``'s diffuse light cannot be switched off, or None when it can be."""
    if world is None:
        return None
    if world.library is not None:
        return (f"world '{world.name}' is linked from library '{world.library.filepath}', so "
                "its diffuse light cannot be switched off: make it local (Object > Relations > "
                "Make Local) or use the Emission Only mode")
    if getattr(world, "override_library", None) is not None:
        return (f"world '{world.name}' is a library override: make it local or use the "
                "Emission Only mode")
    if compat.uses_nodes(world):
        own = [node for node in world.node_tree.nodes
               if node.bl_idname == "ShaderNodeOutputWorld" and node.target == "EEVEE"
               and NODE_MARKER not in node]
        if own:
            return (f"world '{world.name}' has a World Output of its own for EEVEE "
                    f"('{own[0].name}'): set its target to All or use the Emission Only mode")
    return None


def _eevee_source(tree):
    """The World Output EEVEE renders now (target All; active first) or None."""
    outputs = [node for node in tree.nodes
               if node.bl_idname == "ShaderNodeOutputWorld" and node.target == "ALL"
               and NODE_MARKER not in node]
    outputs.sort(key=lambda node: not node.is_active_output)
    return outputs[0] if outputs else None


def prepare(world):
    """Keep ``world`` from giving diffuse light in Cycles and EEVEE (module docstring).

    Already prepared: its EEVEE nodes are rebuilt (the world's surface may have been relinked).
    WorldError, nothing changed, for a world ``problem`` refuses.
    """
    reason = problem(world)
    if reason is not None:
        raise WorldError(reason)
    if world is None:
        return
    record = _record(world)
    if record is None:
        record = {"diffuse": bool(world.cycles_visibility.diffuse), "nodes": []}
    _remove_nodes(world, record)
    record["nodes"] = _add_eevee_nodes(world)
    world[WORLD_MARKER] = json.dumps(record)
    world.cycles_visibility.diffuse = False
    world.update_tag()


def _add_eevee_nodes(world):
    if not compat.uses_nodes(world):
        return []  # EEVEE then shows world.color: nothing to mix (4.2 only)
    tree = world.node_tree
    source = _eevee_source(tree)
    surface = source.inputs["Surface"] if source is not None else None
    linked = surface.links[0].from_socket if surface is not None and surface.is_linked else None
    output = tree.nodes.new("ShaderNodeOutputWorld")
    output.target = "EEVEE"
    output.name = output.label = OUTPUT_NAME
    path = tree.nodes.new("ShaderNodeLightPath")
    mix = tree.nodes.new("ShaderNodeMixShader")
    mix.label = "Camera sees the world, EEVEE's lighting does not"
    added = [output, path, mix]
    x, y = (source.location.x, source.location.y) if source is not None else (300.0, 300.0)
    output.location, mix.location, path.location = (x, y + 260), (x - 200, y + 260), (x - 400, y + 300)
    tree.links.new(path.outputs["Is Camera Ray"], mix.inputs["Fac"])
    if linked is not None:
        tree.links.new(linked, mix.inputs[2])
    tree.links.new(mix.outputs[0], output.inputs["Surface"])
    if source is not None and source.inputs["Volume"].is_linked:
        tree.links.new(source.inputs["Volume"].links[0].from_socket, output.inputs["Volume"])
    for node in added:
        node[NODE_MARKER] = True
    output.is_active_output = True
    if source is not None:
        source.is_active_output = True
    return [node.name for node in added]


def _record(world):
    if WORLD_MARKER not in world:
        return None
    try:
        record = json.loads(world[WORLD_MARKER])
        record["diffuse"] = bool(record["diffuse"])
    except (ValueError, KeyError, TypeError):
        record = {"diffuse": True}  # Blender's default
    record["nodes"] = [n for n in record.get("nodes", ()) if isinstance(n, str)]
    return record


def _ours(node, record):
    """Whether ``node`` is one ``prepare`` added: marked, and named in the world's record (a
    user's duplicate, which copies the mark, has another name)."""
    return NODE_MARKER in node and node.name in record["nodes"]


def _remove_nodes(world, record):
    """Delete the nodes ``prepare`` added (``_ours``: never a user's copy of one)."""
    if world.node_tree is None:
        return
    tree = world.node_tree
    for node in [node for node in tree.nodes if _ours(node, record)]:
        tree.nodes.remove(node)


def restore(world):
    """Undo ``prepare`` on ``world``; True if it was prepared."""
    if world is None or world.library is not None:
        return False
    record = _record(world)
    if record is None:
        return False
    _remove_nodes(world, record)
    world.cycles_visibility.diffuse = record["diffuse"]
    del world[WORLD_MARKER]
    world.update_tag()
    return True


def restore_worlds(worlds):
    """``restore`` every world of ``worlds``; the names of those restored."""
    return [world.name for world in worlds if restore(world)]


def engine_note(engine):
    """What "KEEP_BSDF" does in ``engine`` (a render engine id), one line."""
    return ENGINE_NOTES["CYCLES" if engine == "CYCLES" else "EEVEE"]
