"""Command line of SH Lighting: compute, apply, render and batch, headless.

Three ways to run it (``--help`` after any command shows its options):

* ``blender -c sh_lighting <command> ...`` (Blender 4.2+) with the extension installed and
  enabled: the command the extension registers (``cli/command.py``).

* ``python -m sh_lighting <command> ...`` with a Python where ``bpy`` (Blender as a module) and
  this package are importable, e.g. ``.venv/bin/python -m sh_lighting`` from the repository.
* ``blender -b [FILE.blend] -P /path/to/sh_lighting/cli/script.py -- <command> ...``: Blender
  runs that file as a plain script (no package), so it first finds the package: an enabled add-on
  or extension whose module is ``sh_lighting`` or ends in ``.sh_lighting``
  (``bl_ext.user_default.sh_lighting``), else ``import sh_lighting`` (a folder on
  PYTHONPATH), else an installed but disabled extension; without any it stops with a message
  saying what to install. The arguments are those after ``--``. With a .blend already opened
  by Blender, the BLEND argument of ``compute``, ``apply`` and ``render`` may be left out.
  Add ``--python-exit-code 1`` so that an unexpected Python error also fails the process.

Commands (all write their files atomically: a temporary file moved into place, so an
interrupted run never leaves a half-written output; a replaced file keeps its permissions,
a symbolic link is written through to its target, no output is ever one of the command's
inputs, and a path starting with ``//`` is relative to the .blend's folder, as in Blender):

* ``compute HDRI_OR_BLEND [--out PRESET] [--overwrite] [--capture-width N] [--format F]
  [--nonfinite raise|zero] [--filament-frame cmgen|gltf]``: the 9 coefficients of an
  equirectangular HDRI file, or of the world of a .blend (read only, not saved); prints the
  table and, with ``--out``, writes a preset (an HDRI's preset carries its 9-term error
  estimate) or a file for three.js, glTF (a .gltf environment with a specular cube from the
  image) or Filament.
* ``apply PRESET [BLEND] (--out NEW.blend | --in-place) [--objects NAME ...] [--overwrite]
  [--mode KEEP_BSDF|EMISSION] [--animation refuse|key|clear]``: sets the coefficients and
  applies the SH node group to the materials of all (or the named) objects of the scene
  (keeping their BSDF, or as emission only), then saves. Keyframed or driven coefficients
  or gains are refused by default (they would undo the preset at the next frame): ``key``
  keys the preset at the current frame, ``clear`` removes their animation. An output is
  required: ``--out`` (refused if it exists,
  unless ``--overwrite``; never the input itself) or ``--in-place`` (replaces the input).
* ``render [BLEND] --output PATH [--frame N | --frames A B | --frames A-B] [--engine E]
  [--samples N] [--skip-existing]``: renders frames headless; PATH follows Blender's ``-o``
  rules (``#`` → frame number, else 4 digits appended; the format's extension added). Existing
  frames are replaced, like Blender, or kept with ``--skip-existing`` (a rerun resumes).
* ``batch HDRI_DIR OUT_DIR [--force] [--pattern '*.exr,*.hdr'] [--nonfinite raise|zero]
  [--files A-B] [--expect-files N]``:
  one preset per HDRI, ``OUT_DIR/<stem>.json``, a progress line per file and a total;
  existing presets are kept unless ``--force`` (so an interrupted batch resumes; the
  temporary files a killed batch left are removed and reported); a bad file, and anything
  matching the pattern that is not a readable file (a folder, a broken link), is reported
  and the others are still processed. ``--files`` takes the A-th to B-th entry of the sorted
  list (one task of a farm job; only its own files' leftovers are removed, since other tasks
  may be writing theirs), ``--expect-files`` refuses a folder that does not hold the N
  entries the job was split for.

* ``bake-transfer [BLEND] (--out NEW.blend | --in-place) [--objects NAME ...] [--samples N]
  [--error-target PERCENT] [--apply [--mode KEEP_BSDF|EMISSION]] [--overwrite]``: bakes the transfer (shadows and
  bounce light, ``blender.transfer``) of the scene's meshes (or the named ones) with Cycles,
  a line per basis function with its time; ``--apply`` lights their materials by it; saves.

* ``from-photo IMAGE --circle CX CY R [--blend BLEND | --direction X Y Z [--roll DEG]
  [--projection ortho|persp --lens MM --sensor MM]] [--albedo A] [--margin M]
  [--prior mirror|ambient|none] [--clip V] [--out PRESET] [--format F] [--overwrite]``: the
  coefficients fitted to a grey ball in a photo (``api.coefficients_from_photo``), the camera
  the scene camera of the .blend or a view direction; prints them with the fit's residual,
  condition, poorly constrained terms and clipped pixels; ``--out`` writes a preset.

Exit status: 0 on success, 1 when a command (or any file of a batch) failed, 2 for wrong
arguments or when the package cannot be found. Errors go to stderr as ``sh_lighting: error:``.

The package: this module builds the parser from ``COMMANDS`` and runs one command; each
command is a module (``compute``, ``apply``, ``render``, ``batch``) with ``HELP``,
``add_arguments(parser, prog)`` and ``run(args)``, which parses nothing, calls the Blender
layer and prints (``report``); ``paths`` checks what is read and written, ``session`` opens,
picks and saves the .blend, ``options`` holds the shared argument types, ``script`` the
``blender -P`` entry point. A new command is a module and a line in ``COMMANDS``.
"""

import argparse
import sys

from . import apply, batch, compute, interrupts, photo, render, transfer
from .report import CommandError, error_line

PROG = "python -m sh_lighting"
# command name -> its module (HELP, add_arguments(parser, prog), run(args)), in --help order
COMMANDS = {
    "compute": compute,
    "apply": apply,
    "render": render,
    "batch": batch,
    "bake-transfer": transfer,
    "from-photo": photo,
}

__all__ = ["COMMANDS", "CommandError", "PROG", "build_parser", "main", "run_blender_command"]


def build_parser(prog=PROG):
    parser = argparse.ArgumentParser(
        prog=prog,
        description="SH Lighting: 9 spherical-harmonic lighting coefficients (Ramamoorthi and "
        "Hanrahan 2001) from HDRIs and .blend worlds, applied and rendered headless.",
        epilog="Run '<command> --help' for the options of a command.",
    )
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name, module in COMMANDS.items():
        p = commands.add_parser(name, help=module.HELP,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
        module.add_arguments(p, prog)
        p.set_defaults(run=module.run)
    return parser


def main(argv=None, prog=PROG):
    """Run one command; returns the exit status (0 ok, 1 failed, 2 wrong arguments)."""
    interrupts.install()
    try:
        parser = build_parser(prog)
        args = parser.parse_args(sys.argv[1:] if argv is None else argv)
        interrupts.import_bpy()
        return args.run(args)
    except CommandError as error:
        error_line(error)
        return 1
    except KeyboardInterrupt:
        print("sh_lighting: interrupted", file=sys.stderr, flush=True)
        return interrupts.exit_status()


def run_blender_command(argv):
    """``blender -c sh_lighting ARGS``: ``main`` on ARGS (registered by cli/command.py).

    argparse's own exits (``--help``, wrong arguments) become the return value, which Blender
    makes its exit status, instead of a SystemExit raised inside Blender's command runner.
    """
    try:
        return main(list(argv), prog="blender -c sh_lighting")
    except SystemExit as exit_:
        return exit_.code if isinstance(exit_.code, int) else 0 if exit_.code is None else 2
