"""The .blend a command works on: opened (or the one Blender has open), its scene, saved."""

import os
import re
import sys
import tempfile
from contextlib import contextmanager
from pathlib import Path

from ..formats.atomic import atomic_destination
from . import interrupts
from .paths import (
    blend_relative,
    check_new_file,
    input_file,
    refuse_inputs,
    remove_own_leftovers,
)
from .report import CommandError, say


def open_file():
    """The path of the .blend Blender has open (under ``blender file.blend -P``), or None."""
    import bpy

    return Path(bpy.data.filepath) if bpy.data.filepath else None


def open_blend(path, load_ui=False):
    """Open the .blend at ``path`` (None: keep the file Blender has open); returns its path.

    ``load_ui``: also load its workspaces and screens (a file that is saved again keeps the
    user's layout).
    """
    import bpy

    if path is None:
        if not bpy.data.filepath:
            raise CommandError(
                "no .blend given and none is open: pass the .blend file as an argument"
            )
        return Path(bpy.data.filepath)
    path = input_file(path, ".blend file", "give a .blend file")
    with output_captured(1) as printed:  # Blender prints its reason too: ours is the one line
        try:
            bpy.ops.wm.open_mainfile(filepath=str(path), load_ui=load_ui)
        except RuntimeError as error:
            raise CommandError(
                f"Blender could not open '{path}': {blender_reason(error)}") from None
        finally:
            text = printed()
    if text:  # opened: Blender's own lines ("Read blend: ...") as it printed them
        sys.stdout.write(text)
        sys.stdout.flush()
    return path


def blender_reason(error):
    """The reason in a RuntimeError Blender raised, as one line: its first non-empty line,
    without Blender's "Error: " and 'Loading "<path>" failed: ' (Blender 4.3 and 5.0 add them
    to a report that may run over several lines)."""
    lines = [line.strip() for line in str(error).splitlines() if line.strip()]
    reason = lines[0] if lines else "no reason given"
    reason = re.sub(r"^Error:\s*", "", reason)
    return re.sub(r'^Loading ".*?" failed:\s*', "", reason)


@contextmanager
def output_captured(fd):
    """What is written to file descriptor ``fd`` (1: stdout, 2: stderr, C libraries included)
    during the block, kept in a temporary file instead; yields a function returning it."""
    stream = sys.stdout if fd == 1 else sys.stderr
    stream.flush()
    saved = os.dup(fd)
    with tempfile.TemporaryFile() as capture:
        os.dup2(capture.fileno(), fd)
        try:
            yield lambda: (stream.flush(), capture.seek(0),
                           capture.read().decode("utf-8", "replace"))[2]
        finally:
            stream.flush()
            os.dup2(saved, fd)
            os.close(saved)


def pick_scene(name):
    """The scene called ``name``, or the file's active scene."""
    import bpy

    if name is None:
        scene = bpy.context.scene
        if scene is None:
            raise CommandError("the file has no scene")
        return scene
    scene = bpy.data.scenes.get(name)
    if scene is None:
        names = ", ".join(s.name for s in bpy.data.scenes)
        raise CommandError(f"no scene '{name}' in the file (scenes: {names})")
    return scene


def save_blend(path, overwrite):
    """Save the open file as ``path`` atomically (a copy: the session keeps its file path)."""
    import bpy

    remove_own_leftovers(path)
    with atomic_destination(path, overwrite, suffix=".blend", what=".blend file",
                            hint="pass --overwrite") as temporary:
        bpy.ops.wm.save_as_mainfile(filepath=str(temporary), copy=True)
        interrupts.check()  # a Ctrl+C taken while Blender saved: the input stays as it was
    return Path(path)


def output_blend(args, blend, inputs=None):
    """Where a command that changes ``blend`` saves it: the input itself (--in-place) or --out
    (relative to the .blend; never the .blend or one of ``inputs``, {what: path}; refused if it
    exists without --overwrite)."""
    if args.in_place:
        return blend
    out = blend_relative(args.out, blend, "--out")
    refuse_inputs(out, "--out", {".blend file": blend}, advice="use --in-place to replace it")
    if inputs:
        refuse_inputs(out, "--out", inputs)
    check_new_file(out, args.overwrite, what="--out")
    return out


def save_and_say(args, out):
    """``save_blend`` to ``out`` (a CommandError naming it when that fails), then "Saved OUT"."""
    try:
        save_blend(out, overwrite=args.in_place or args.overwrite)
    except (OSError, RuntimeError) as error:
        raise CommandError(f"could not save '{out}': {error}") from None
    say(f"Saved {out}")

