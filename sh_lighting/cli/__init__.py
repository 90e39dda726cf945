"""Command line of SH Lighting: compute, apply, render, batch, bake-transfer, from-photo and luminaire,
headless (``python -m sh_lighting``, ``blender -c sh_lighting``, ``blender -P cli/script.py``;
what each command does and guarantees: docs/cli.md).

This module builds the parser from ``COMMANDS`` and runs one command. Each command is a module
with ``HELP``, ``add_arguments(parser, prog)`` and ``run(args)``, which calls ``api`` and prints
(``report``); ``paths`` checks what is read and written, ``session`` opens, picks and saves the
.blend, ``options`` holds the shared arguments. Exit status 0 done, 1 failed, 2 wrong arguments.
"""

import argparse
import sys

from . import apply, batch, compute, interrupts, luminaire, photo, render, transfer
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
    "luminaire": luminaire,
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
