"""Build the installable extension zip with Blender's own extension tool.

The repository keeps ``blender_manifest.toml`` and the shipped ``presets/*.json`` at the top
level beside the ``sh_lighting`` package; Blender wants the manifest next to ``__init__.py``.
This stages them (the presets into the package's ``presets/``) in a temporary folder, runs
``blender_ext.py validate`` and ``build`` on it, and prints the zip.

Usage: python -m tools.package [OUTPUT_DIR]   (default: dist)
"""

import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import bpy

ROOT = Path(__file__).resolve().parent.parent


def blender_ext_command():
    scripts = Path(bpy.utils.system_resource("SCRIPTS"))
    tool = scripts / "addons_core" / "bl_pkg" / "cli" / "blender_ext.py"
    tags = scripts / "modules" / "_bpy_internal" / "extensions" / "tags.py"
    return [sys.executable, str(tool)], tags


def stage(destination):
    """Copy the package, manifest, licence and shipped presets into the new folder
    ``destination``; the presets go to ``presets/`` inside the package, where
    ``sh_lighting.blender.presets.preset_io.shipped_preset_dir`` looks once installed.
    """
    shutil.copytree(
        ROOT / "sh_lighting", destination, ignore=shutil.ignore_patterns("__pycache__", "*.pyc")
    )
    for name in ("blender_manifest.toml", "LICENSE"):
        shutil.copy2(ROOT / name, destination / name)
    presets = destination / "presets"
    presets.mkdir(exist_ok=True)
    for preset in sorted((ROOT / "presets").glob("*.json")):
        shutil.copy2(preset, presets / preset.name)
    return destination


def build(output_dir):
    """Validate and build the extension; returns the path of the zip."""
    output_dir = Path(output_dir).resolve()
    output_dir.mkdir(parents=True, exist_ok=True)
    command, tags = blender_ext_command()
    with tempfile.TemporaryDirectory() as tmp:
        source = stage(Path(tmp) / "sh_lighting")
        subprocess.run(command + ["validate", str(source), "--valid-tags", str(tags)], check=True)
        subprocess.run(
            command
            + ["build", "--source-dir", str(source), "--output-dir", str(output_dir),
               "--valid-tags", str(tags)],
            check=True,
        )
    zips = sorted(output_dir.glob("sh_lighting-*.zip"), key=lambda p: p.stat().st_mtime)
    return zips[-1]


if __name__ == "__main__":
    print(build(sys.argv[1] if len(sys.argv) > 1 else ROOT / "dist"))
