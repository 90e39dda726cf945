"""What Apply's mode does in the scene's render engine, and what goes wrong in this scene:
the lines the panel shows under Apply and the notes Apply reports. Whatever a mode cannot
do is said where it matters, never silently dropped.
"""

import bpy

from ..data import scene_data
from . import glossy, world_diffuse
from .keep_bsdf import PRINCIPLED
from .materials import mode_of, scene_materials, surface_shaders

# One line each, read in full in the sidebar at its default width (MODE_NOTE_CHARACTERS).
MODE_NOTES = {
    ("KEEP_BSDF", "CYCLES"): "SH diffuse, lamps, reflections",
    ("KEEP_BSDF", "EEVEE"): "SH diffuse, lamps, reflection maps",
    ("EMISSION", "CYCLES"): "SH only: no lamps or reflections",
    ("EMISSION", "EEVEE"): "SH only: no lamps or reflections",
    ("TRANSFER", "CYCLES"): "Baked shadows, lamps, reflections",
    ("TRANSFER", "EEVEE"): "Baked shadows, lamps, refl. maps",
}
# Characters of a note line that the sidebar shows beside its icon at its default width
# (291 px, UI scale 1; "SH alone: no lamps, shadows or refl" was the most that showed).
MODE_NOTE_CHARACTERS = 34
LAMPS_LINE = "{count} lamp(s) will not light them"
TWICE_LINE = "Light counted twice: Apply again"


def lamps_of(scene):
    """Names of the lamps that render in ``scene``."""
    return [obj.name for obj in scene.objects if obj.type == "LIGHT" and not obj.hide_render]


def mode_note(mode, engine):
    """What ``mode`` does in render engine ``engine``, in a few words (for the panel)."""
    return MODE_NOTES[(mode, "CYCLES" if engine == "CYCLES" else "EEVEE")]


def emission_lamp_note(scene):
    """One line when Emission Only would leave the scene's lamps out, else None."""
    lamps = lamps_of(scene)
    if not lamps:
        return None
    return (f"the scene's {len(lamps)} lamp(s) ({', '.join(lamps[:2])}"
            f"{', ...' if len(lamps) > 2 else ''}) do not light Emission Only materials: "
            "use Keep BSDF to keep them")


def status_lines(scene, mode):
    """[(icon, line)] the panel shows under Apply: what ``mode`` does in the scene's engine,
    and what goes wrong in this scene (lamps Emission drops, light counted twice)."""
    lines = [("INFO", mode_note(mode, scene.render.engine))]
    if mode == "EMISSION" and lamps_of(scene):
        lines.append(("ERROR", LAMPS_LINE.format(count=len(lamps_of(scene)))))
    warning = keep_bsdf_warning(scene)
    if warning is not None:
        lines.append(("ERROR", TWICE_LINE))
    return lines


def keep_bsdf_warning(scene):
    """One line when ``scene`` shows "KEEP_BSDF" materials while its world still gives diffuse
    light (switched after Apply, or Apply ran in another scene), else None."""
    world = scene.world
    if world is None or world_diffuse.is_prepared(world):
        return None
    applied = [name for name in sorted(scene_materials(scene))
               if mode_of(bpy.data.materials.get(name)) == "KEEP_BSDF"]
    if not applied:
        return None
    reason = world_diffuse.problem(world)
    if reason is not None:
        return f"diffuse light counted twice: {reason}"
    return (f"World '{world.name}' still gives diffuse light, which {len(applied)} Keep BSDF "
            "material(s) also get from SH (counted twice): click Apply again")




def shared_scene_notes(scene, names):
    """One line per other scene that shows one of the "KEEP_BSDF" materials ``names``
    (applied from ``scene``), where that scene is not lit as it is in ``scene``.

    The materials' SH term reads the coefficients of the scene being rendered, and Apply has
    switched that scene's world's diffuse light off too (counted once): so a scene without
    coefficients gets no diffuse light from its world at all on them, and its other materials
    none on theirs. Nothing for scenes where both are in place. And a line per other scene
    with another world whose EEVEE reflections on these materials are now this world's maps
    (one material looks up one set: Apply in scene B switches scene A's).
    """
    wanted = set(names)
    lines = []
    for other in bpy.data.scenes:
        shown = sorted(wanted & scene_materials(other))
        if other == scene or not shown or other.world is None:
            continue
        reflecting = _reflecting_here(scene, other, shown)
        if reflecting:
            lines.append(
                f"scene '{other.name}' shows {len(reflecting)} of these material(s) "
                f"('{reflecting[0]}'{', ...' if len(reflecting) > 1 else ''}), whose EEVEE "
                f"reflections there are now of world '{scene.world.name}', not of its world "
                f"'{other.world.name}' (a material reflects one world: give scene "
                f"'{other.name}' its own copy of them, then Apply there)")
        missing = []
        if not scene_data.has_coefficients(other):
            missing.append("it has no SH coefficients (Compute there)")
        unlit = [name for name in sorted(scene_materials(other) - wanted)
                 if mode_of(bpy.data.materials.get(name)) != "KEEP_BSDF"]
        if unlit:
            missing.append(f"its {len(unlit)} other material(s) ('{unlit[0]}'"
                           f"{', ...' if len(unlit) > 1 else ''}) have no SH (Apply there)")
        if missing:
            lines.append(f"scene '{other.name}' shows {len(shown)} of these material(s), so its "
                         f"world '{other.world.name}' gives no diffuse light there either, but "
                         f"{' and '.join(missing)}")
    return lines


def _reflecting_here(scene, other, shown):
    """The materials of ``shown`` whose EEVEE reflections (``glossy``'s maps of ``scene``'s
    world) ``other``, whose world is another, shows instead of its own world's."""
    if other.world is None or scene.world is None or other.world == scene.world:
        return []
    maps = {image.as_pointer() for image in glossy.maps_of(scene.world) or ()}
    found = []
    for name in shown:
        material = bpy.data.materials.get(name)
        tree = getattr(material, "node_tree", None)
        if tree is not None and any(
                getattr(node, "image", None) is not None and node.image.as_pointer() in maps
                for node in tree.nodes):
            found.append(name)
    return found


def reflection_note(scene, names):
    """One line on the world's reflections EEVEE will not show on the Keep BSDF materials
    ``names`` (shaders and layers ``glossy`` does not model, or no maps: the world could not
    be read), else None."""
    parts, missing = [], False
    for name in names:
        leaves = surface_shaders(bpy.data.materials.get(name))
        missing = missing or any(leaf.node.bl_idname == PRINCIPLED for leaf in leaves)
        parts += [f"{what} in '{name}'" for what in glossy.unmodelled(leaves)]
    problem = glossy.reflection_problem(scene) if missing else None
    if problem is not None:
        return f"EEVEE shows no reflections of the world: {problem}"
    if not parts:
        return None
    more = f" and {len(parts) - 3} more" if len(parts) > 3 else ""
    return ("EEVEE does not show the world's reflections off " + ", ".join(parts[:3]) + more
            + " (Cycles does)")
