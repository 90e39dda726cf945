"""``blender -b [FILE.blend] -P /path/to/sh_lighting/cli/script.py -- <command> ...``.

Blender runs this file as a plain script, outside any package, so it first finds the
sh_lighting package (``find_package``: an enabled add-on or extension, else a plain
``import sh_lighting``, else an installed but disabled extension) and then runs its command
line (``sh_lighting.cli.main``) on the arguments after ``--``. Without a package it exits with
status 2 saying what to install.
"""

import importlib
import sys


def candidates(enabled, importable):
    """Package names to try, in order: enabled add-ons, a plain import, installed ones."""
    ours = [n for n in enabled if n == "sh_lighting" or n.endswith(".sh_lighting")]
    ours.append("sh_lighting")
    ours += [n for n in importable if n.endswith(".sh_lighting") and n not in ours]
    return ours


def find_package():
    """The name of an importable sh_lighting package whose ``cli`` module loads."""
    enabled, installed = [], []
    try:
        import addon_utils
        import bpy

        enabled = list(bpy.context.preferences.addons.keys())
        installed = [module.__name__ for module in addon_utils.modules()]
    except Exception:  # noqa: BLE001 - not inside Blender: only the plain import is tried
        pass
    for name in candidates(enabled, installed):
        try:
            importlib.import_module(f"{name}.cli")
        except ImportError:
            continue
        return name
    raise ImportError(
        "cannot find the sh_lighting package: install and enable the SH Lighting extension "
        "(Preferences > Get Extensions > Install from Disk), or put the folder that contains "
        "sh_lighting/ on PYTHONPATH"
    )


def _run_as_script():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    try:
        name = find_package()
    except ImportError as error:
        print(f"sh_lighting: error: {error}", file=sys.stderr, flush=True)
        return 2
    cli = importlib.import_module(f"{name}.cli")
    return cli.main(argv, prog="blender -b [FILE.blend] -P script.py --")


if __name__ == "__main__":
    sys.exit(_run_as_script())
