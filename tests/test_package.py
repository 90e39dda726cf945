"""`make package` with the standard library alone: the zip Blender installs, built without bpy
or .venv (tests/blender/test_extension_install.py installs it into Blender)."""

import subprocess
import sys
import zipfile

from tests.conftest import ROOT


def test_package_builds_without_bpy(tmp_path):
    code = ("import sys, tools.package as p; z = p.build(sys.argv[1]); "
            "assert 'bpy' not in sys.modules and 'numpy' not in sys.modules; print(z)")
    out = subprocess.run([sys.executable, "-c", code, str(tmp_path)], cwd=ROOT,
                         capture_output=True, text=True, check=True).stdout.strip()
    assert out.endswith("sh_lighting-0.1.0.zip")
    names = zipfile.ZipFile(out).namelist()
    assert {"blender_manifest.toml", "__init__.py", "LICENSE", "presets/forest.json",
            "blender/ui/panels.py", "core/sh.py"} <= set(names)
    assert not [n for n in names if "__pycache__" in n or n.endswith(".pyc")]
    # the make target needs no .venv (its stamp) either
    target = (ROOT / "Makefile").read_text().split("\npackage:")[1].split("\n")[0]
    assert "STAMP" not in target
