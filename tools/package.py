"""Build the installable extension zip with Blender's own extension tool.

The repository keeps ``blender_manifest.toml`` at the top level beside the ``sh_lighting``
package; Blender wants the manifest next to ``__init__.py``. This stages both into
``build/extension``, runs ``blender_ext.py validate`` and ``build`` on it, and prints the zip.

Usage: python -m tools.package [OUTPUT_DIR]   (default: dist)
"""

import shutil
import subprocess
import sys
from pathlib import Path

import bpy

ROOT = Path(__file__).resolve().parent.parent
STAGE = ROOT / "build" / "extension"


def blender_ext_command():
    scripts = Path(bpy.utils.system_resource("SCRIPTS"))
    tool = scripts / "addons_core" / "bl_pkg" / "cli" / "blender_ext.py"
    tags = scripts / "modules" / "_bpy_internal" / "extensions" / "tags.py"
    return [sys.executable, str(tool)], tags


def stage(destination=STAGE):
    """Copy the package, manifest and licence into ``destination`` (emptied first)."""
    if destination.exists():
        shutil.rmtree(destination)
    shutil.copytree(
        ROOT / "sh_lighting", destination, ignore=shutil.ignore_patterns("__pycache__", "*.pyc")
    )
    for name in ("blender_manifest.toml", "LICENSE"):
        shutil.copy2(ROOT / name, destination / name)
    return destination


def build(output_dir):
    """Validate and build the extension; returns the path of the zip."""
    output_dir = Path(output_dir).resolve()
    output_dir.mkdir(parents=True, exist_ok=True)
    source = stage()
    command, tags = blender_ext_command()
    subprocess.run(
        command + ["validate", str(source), "--valid-tags", str(tags)], check=True
    )
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
