"""Build the installable extension zip with the standard library alone (no bpy, no .venv).

The repository keeps ``blender_manifest.toml`` and the shipped ``presets/*.json`` at the top
level beside the ``sh_lighting`` package; Blender wants the manifest next to ``__init__.py``.
The zip holds, at its root, the package's files, the manifest, the licence and the presets
(in ``presets/``, where ``preset_io.shipped_preset_dir`` looks once installed), named
``<id>-<version>.zip`` from the manifest, as ``blender --command extension build`` names it.

``--check BLENDER`` also runs Blender's own ``blender --command extension validate`` on the
zip (optional: the release check; ``make package`` does not need a Blender).

Usage: python -m tools.package [OUTPUT_DIR] [--check BLENDER]   (default: dist)
"""

import argparse
import shutil
import subprocess
import tomllib
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SKIPPED = {"__pycache__"}


def manifest():
    with open(ROOT / "blender_manifest.toml", "rb") as f:
        return tomllib.load(f)


def members():
    """(path in the zip, file on disk), sorted: the package, the manifest, the licence and
    the presets."""
    found = []
    package = ROOT / "sh_lighting"
    for path in sorted(package.rglob("*")):
        if path.is_file() and not SKIPPED & set(path.parts) and path.suffix != ".pyc":
            found.append((path.relative_to(package).as_posix(), path))
    for name in ("blender_manifest.toml", "LICENSE"):
        found.append((name, ROOT / name))
    for preset in sorted((ROOT / "presets").glob("*.json")):
        found.append((f"presets/{preset.name}", preset))
    return found


def stage(destination):
    """The zip's contents written into the new folder ``destination`` (as Blender installs
    them); returns it."""
    destination = Path(destination)
    for name, source in members():
        target = destination / name
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(source, target)
    return destination


def build(output_dir):
    """Write the extension zip into ``output_dir``; returns its path."""
    info = manifest()
    output_dir = Path(output_dir).resolve()
    output_dir.mkdir(parents=True, exist_ok=True)
    path = output_dir / f"{info['id']}-{info['version']}.zip"
    temporary = path.with_suffix(".zip.part")
    with zipfile.ZipFile(temporary, "w", zipfile.ZIP_DEFLATED) as archive:
        for name, source in members():
            archive.write(source, name)
    temporary.replace(path)
    return path


def check(zip_path, blender):
    """Blender's own validation of the built zip (raises CalledProcessError if it fails)."""
    subprocess.run([blender, "--factory-startup", "--command", "extension", "validate",
                    str(zip_path)], check=True)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("output_dir", nargs="?", default=str(ROOT / "dist"))
    parser.add_argument("--check", metavar="BLENDER",
                        help="also validate the zip with this Blender (4.2 or later)")
    args = parser.parse_args()
    built = build(args.output_dir)
    if args.check:
        check(built, args.check)
    print(built)
