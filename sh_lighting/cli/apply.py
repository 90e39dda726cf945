"""``apply PRESET [BLEND]``: a preset's coefficients set on a .blend's scene and applied as the
panel's Apply does (``--mode``, the default by the scene's render engine: Edit World or the SH
node group on its materials), saved to a new file or in place."""

from ..choices import APPLY_MODE_ITEMS, resolve_mode
from .options import add_apply_mode, add_blend_output, add_scene
from .paths import blend_relative, changed_alone, input_file
from .report import CommandError, say
from .session import open_blend, open_file, output_blend, pick_scene, save_and_say

HELP = "set a preset in a .blend and apply it (Edit World, or the SH group on its materials)"


def add_arguments(p, prog):
    p.description = (
        "Set the scene's coefficients from PRESET and apply them as the panel's Apply does: "
        "by default (--mode AUTO) Edit World in Cycles (the designed change added to the "
        "world; the materials untouched) and in EEVEE Keep BSDF with Shadows: the transfer "
        "(shadows) baked by Cycles where the file holds no current bake and it is estimated "
        "under 30 s, then the SH node group on the materials of all objects of the scene "
        "(or of --objects), through the transfer where baked; then save to --out (a new file) "
        "or over the input with --in-place.")
    p.epilog = f"example:\n  {prog} apply forest.json shot.blend --out shot_sh.blend"
    p.add_argument("preset", metavar="PRESET", help="SH Lighting preset (.json)")
    p.add_argument("blend", metavar="BLEND", nargs="?",
                   help=".blend file to change (under blender -P: default the open one)")
    add_blend_output(p)
    p.add_argument("--objects", nargs="+", metavar="NAME",
                   help="only the materials of these objects (default: every object; the "
                   "material modes only: Edit World lights every object)")
    add_scene(p, "scene to change")
    add_apply_mode(p)
    p.add_argument(
        "--animation", choices=("refuse", "key", "clear"), default="refuse",
        help="when the scene's sh_L.. coefficients or gains are keyframed or driven: refuse "
        "(default, nothing saved), key the preset's values at the scene's current frame "
        "(the rest of the animation kept; a driven one is refused), or clear their "
        "animation so that the preset renders at every frame")


def run(args):
    if args.blend is not None:
        blend = input_file(args.blend, ".blend file", "give the .blend file to change")
    else:
        blend = open_file()
    preset, _ = read_preset_argument(args.preset, blend)  # refused before Blender opens
    out = output_blend(args, blend, {"preset": preset})
    if args.in_place:
        with changed_alone(blend, ".blend file"):
            return apply_and_save(args, preset, out)
    return apply_and_save(args, preset, out)


def apply_and_save(args, preset, out):
    """Open the .blend, set the preset, apply the group, save to ``out``."""
    from .. import api
    from ..formats.presets import PresetError

    open_blend(args.blend, load_ui=True)  # saved again: keep the user's layout
    scene = pick_scene(args.scene)
    mode = resolve_mode(args.mode, scene.render.engine)
    if mode == "WORLD" and args.objects:
        raise CommandError(
            f"--objects picks materials, but --mode {args.mode} is Edit World here (scene "
            f"'{scene.name}' renders with {scene.render.engine}), which changes the world and "
            "lights every object: leave --objects out, or give --mode KEEP_BSDF or EMISSION")
    objects = objects_to_apply(scene, args.objects)
    try:  # what the UI's Load and Import do (the preset's name recorded from its metadata)
        note = api.import_preset(scene, preset, args.animation.upper()).note
    except (PresetError, OSError) as error:
        raise CommandError(str(error)) from None
    except api.AnimatedError as error:
        raise CommandError(str(error).replace("(animation='KEY', ", "(")
                           .replace("(animation='CLEAR', ", "(")) from None
    if note:
        say(f"SH lighting {note}")
    label = dict((key, name) for key, name, _text in APPLY_MODE_ITEMS)[mode]
    if args.mode != mode:
        say(f"mode {args.mode}: {label} (scene '{scene.name}' renders with "
            f"{scene.render.engine})")
    if mode == "WORLD":
        edit_world(scene)
    elif mode == "TRANSFER":
        apply_with_shadows(scene, objects, args.mode)
    else:
        apply_to_materials(scene, objects, mode)
    save_and_say(args, out)
    return 0


def edit_world(scene):
    """Edit World, and the SH taken out of the scene's materials (the edited world lights them:
    nothing counted twice), as the panel's Apply does."""
    from .. import api

    try:
        clamping = api.edit_world(scene)
    except (LookupError, ValueError) as error:
        raise CommandError(str(error)) from None
    message, clamped = api.edit_world_report(scene, clamping)
    say(message)
    taken = api.remove_from_materials(api.materials_of(scene.objects)).changed
    if taken:
        say(f"SH lighting taken out of {len(taken)} material(s): the edited world lights them")
    if clamped:
        say(f"warning: {clamped}")


def apply_with_shadows(scene, objects, asked):
    """Keep BSDF with Shadows: the transfer baked where missing or stale (the Default only
    when affordable), then Keep BSDF with it, as the panel's Apply does."""
    from .. import api
    from . import interrupts

    try:
        with interrupts.at_once():  # Cycles' bake would swallow a KeyboardInterrupt
            result, lit, info, notes = api.apply_with_shadows(scene, objects, asked, report=say)
    except api.TransferError as error:
        raise CommandError(f"{error}; nothing saved") from None
    except (LookupError, ValueError) as error:
        raise CommandError(str(error)) from None
    if info is not None:
        say(f"Baked the transfer of {len(info.objects)} object(s): {info.vertices} vertices, "
            f"{info.corners} corners, {info.texels} texels, {info.samples} samples, "
            f"{info.seconds:.1f} s{info.rates()}")
    for line in notes:
        say(f"note: {line}")
    for name, reason in result.skipped:
        say(f"skipped material '{name}': {reason}")
    for name in api.objects_without_material(objects):
        say(f"skipped object '{name}': it has no material (give it one to light it)")
    if not result.changed:
        raise CommandError(f"no material was changed ({len(result.skipped)} skipped): nothing "
                           "saved")
    if api.remove_world_edit(scene):
        say(f"World Edit taken out of world '{scene.world.name}': the materials light it now")
    say(f"SH lighting applied to {len(result.changed)} material(s), {len(lit)} with the "
        "transfer's shadows: " + ", ".join(result.changed))
    for line in api.shared_scene_notes(scene, result.changed):
        say(f"warning: {line}")


def apply_to_materials(scene, objects, mode):
    """The SH group on the materials of ``objects`` in ``mode`` (and any World Edit taken out
    of the world: the materials light it now)."""
    from .. import api

    result = api.apply_to_materials(api.materials_of(objects), scene, mode)
    for name, reason in result.skipped:
        say(f"skipped material '{name}': {reason}")
    for name in api.objects_without_material(objects):
        say(f"skipped object '{name}': it has no material (give it one to light it)")
    if not result.changed:
        raise CommandError(
            f"no material was changed ({len(result.skipped)} skipped): nothing saved"
        )
    if api.remove_world_edit(scene):
        say(f"World Edit taken out of world '{scene.world.name}': the materials light it now")
    say(f"SH lighting applied to {len(result.changed)} material(s): "
        + ", ".join(result.changed))
    if mode == "KEEP_BSDF":
        for line in api.shared_scene_notes(scene, result.changed):
            say(f"warning: {line}")


def read_preset_argument(text, blend):
    """(path, coefficients) of the PRESET argument (``//`` relative to ``blend``)."""
    from .. import api
    from ..formats.presets import PresetError

    path = blend_relative(text, blend, "PRESET")
    try:
        return path, api.read_preset_file(path)[0]
    except (PresetError, OSError) as error:
        raise CommandError(str(error)) from None


def objects_to_apply(scene, names):
    """The objects named ``names`` (all of the scene's when None), or a CommandError."""
    if not names:
        return list(scene.objects)
    missing = [name for name in names if scene.objects.get(name) is None]
    if missing:
        raise CommandError(
            f"no object(s) {', '.join(map(repr, missing))} in scene '{scene.name}'"
        )
    return [scene.objects[name] for name in names]
