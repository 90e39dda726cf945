"""Argument types and the options several commands share (no bpy: ``--help`` stays fast)."""

import argparse
import re

from ..choices import APPLY_MODES, MATERIAL_MODES


def whole_range(text):
    """(first, last) of "A-B" or "A", the form of an Open Job Description chunk ("1-8")."""
    match = re.fullmatch(r"(-?\d+)(?:-(-?\d+))?", text.strip())
    if match is None:
        raise argparse.ArgumentTypeError(f"{text!r} is not a range A-B or a whole number")
    return int(match[1]), int(match[2] if match[2] is not None else match[1])


class FrameRange(argparse.Action):
    """``--frames A B`` or ``--frames A-B``, stored as (A, B)."""

    def __call__(self, parser, namespace, values, option_string=None):
        try:
            if len(values) == 1:
                value = whole_range(values[0])
            elif len(values) == 2:
                value = tuple(int(v) for v in values)
            else:
                raise ValueError
        except (ValueError, argparse.ArgumentTypeError):
            parser.error(f"{option_string} {' '.join(values)}: give frames A B, or A-B")
        setattr(namespace, self.dest, value)


def positive(text):
    """A whole number above 0, or an argparse error saying what was given."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value <= 0:
        raise argparse.ArgumentTypeError(f"{text!r} is not a positive whole number")
    return value


def add_nonfinite(parser):
    parser.add_argument("--nonfinite", choices=("raise", "zero"), default="raise",
                        help="NaN or infinite texels: refuse the image (raise, the default) "
                        "or treat them as black (zero)")


def add_blend_output(p):
    """Where a command that changes a .blend saves it: --out NEW.blend or --in-place
    (one of them), and --overwrite for an existing --out file."""
    where = p.add_mutually_exclusive_group(required=True)
    where.add_argument("--out", metavar="NEW.blend", help="save the result to this new file")
    where.add_argument("--in-place", action="store_true", help="replace the input .blend")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out file")


def add_scene(parser, what="scene of the .blend"):
    parser.add_argument("--scene", metavar="NAME", help=f"{what} (default: active)")


def add_mode(parser):
    """``bake-transfer --mode``: keep the BSDF (default) or drive the surface by the SH emission."""
    parser.add_argument(
        "--mode", choices=MATERIAL_MODES, default=MATERIAL_MODES[0],
        help="KEEP_BSDF (default): materials keep their BSDF (lamps, shadows, reflections) and "
        "SH replaces the world's diffuse light, which the world then no longer gives to "
        "diffuse rays (Cycles); EMISSION: the SH emission alone drives the surface")


def add_apply_mode(parser):
    """``apply --mode``: the panel's Apply modes (``choices.APPLY_MODES``), its default first."""
    parser.add_argument(
        "--mode", choices=APPLY_MODES, default=APPLY_MODES[0],
        help="AUTO (default): as the panel's Default, by the scene's render engine: WORLD in "
        "Cycles, TRANSFER in EEVEE (its bake only when estimated under 30 s); WORLD (Edit "
        "World): the designed change is added to the world itself, the materials stay as they "
        "are (path-traced shadows, bounces and reflections); TRANSFER (Keep BSDF with "
        "Shadows): the transfer baked by Cycles where missing or stale, then KEEP_BSDF with "
        "it; KEEP_BSDF: materials keep their BSDF (lamps, shadows, reflections) and "
        "SH replaces the world's diffuse light; EMISSION: the SH emission alone drives the "
        "surface")
