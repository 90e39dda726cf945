"""What Apply's mode does in the scene's render engine, and what goes wrong in this scene:
the lines the panel shows under Apply and the notes Apply reports (issue 21 item 2, issue 23
item 5). Whatever a mode cannot do is said where it matters, never silently dropped.
"""

import bpy

from . import world_diffuse
from .materials import mode_of, scene_materials

MODE_NOTES = {
    ("KEEP_BSDF", "CYCLES"): "Cycles: SH diffuse, lamps and reflections",
    ("KEEP_BSDF", "EEVEE"): "EEVEE: SH diffuse and lamps, no world reflections",
    ("EMISSION", "CYCLES"): "SH alone: no lamps, shadows or reflections",
    ("EMISSION", "EEVEE"): "SH alone: no lamps, shadows or reflections",
}


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
        lines.append(("ERROR", f"{len(lamps_of(scene))} lamp(s) will not light them"))
    warning = keep_bsdf_warning(scene)
    if warning is not None:
        lines.append(("ERROR", "Diffuse light counted twice: Apply again"))
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


