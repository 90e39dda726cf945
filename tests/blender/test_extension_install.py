"""Build the extension zip with Blender's own tool, install it, enable it, disable it.

The install runs in a separate Python process with HOME and BLENDER_USER_RESOURCES pointed at a
fresh temporary folder, so the real user configuration is never touched and the add-on is
imported as ``bl_ext.user_default.sh_lighting``, the way users get it. The check is generic:
whatever modules the add-on registers, disabling it must leave Blender's registered classes,
ID properties and handlers exactly as they were before the install.
"""

import json
import os
import subprocess
import sys
import zipfile

import pytest

from tools import package

pytestmark = pytest.mark.blender

MODULE = "bl_ext.user_default.sh_lighting"

SCRIPT = r'''
import json, sys
import bpy
import addon_utils  # importable once bpy is

zip_path, module = sys.argv[1], sys.argv[2]
ID_TYPES = ("Scene", "World", "Object", "Material", "WindowManager", "ViewLayer", "Image")


def registered_classes():
    """Registered RNA classes (operators, panels, menus, preferences, property groups, ...)."""
    found, seen, stack = set(), set(), [bpy.types.bpy_struct]
    while stack:
        for sub in stack.pop().__subclasses__():
            if sub not in seen:
                seen.add(sub)
                stack.append(sub)
                if getattr(sub, "is_registered", False):
                    found.add(sub.__module__ + "." + sub.__qualname__)
    return found


def state():
    return {
        "types": sorted(dir(bpy.types)),
        "classes": sorted(registered_classes()),
        "properties": {
            name: sorted(p.identifier for p in getattr(bpy.types, name).bl_rna.properties)
            for name in ID_TYPES
        },
        "handlers": {
            name: len(getattr(bpy.app.handlers, name))
            for name in dir(bpy.app.handlers)
            if isinstance(getattr(bpy.app.handlers, name), list)
        },
    }


report = {"before": state()}
report["user_extensions"] = bpy.utils.user_resource("EXTENSIONS")
report["install"] = sorted(bpy.ops.extensions.package_install_files(
    filepath=zip_path, repo="user_default", enable_on_install=True))
report["enabled_pref"] = module in bpy.context.preferences.addons
report["enabled_check"] = list(addon_utils.check(module))
report["during"] = state()
report["disable"] = sorted(bpy.ops.preferences.addon_disable(module=module))
report["disabled_pref"] = module in bpy.context.preferences.addons
report["disabled_check"] = list(addon_utils.check(module))
report["after"] = state()
print("REPORT=" + json.dumps(report))
'''


@pytest.fixture(scope="module")
def built_zip(tmp_path_factory):
    # Runs ``blender_ext.py validate`` then ``build``; either failing raises CalledProcessError.
    return package.build(tmp_path_factory.mktemp("dist"))


def test_zip_holds_manifest_and_package(built_zip):
    assert built_zip.name.startswith("sh_lighting-") and built_zip.suffix == ".zip"
    with zipfile.ZipFile(built_zip) as archive:
        names = set(archive.namelist())
    assert "blender_manifest.toml" in names
    assert "__init__.py" in names
    assert "core/equirect.py" in names
    assert "blender/data/preferences.py" in names
    # The shipped presets, where preset_io.shipped_preset_dir looks once installed.
    assert "presets/forest.json" in names
    shipped = {f"presets/{p.name}" for p in (package.ROOT / "presets").glob("*.json")}
    assert len(shipped) >= 11 and shipped <= names
    assert not any("__pycache__" in name or name.endswith(".pyc") for name in names)


def test_install_enable_disable_leaves_no_trace(built_zip, tmp_path):
    home = tmp_path / "home"
    resources = tmp_path / "resources"
    home.mkdir()
    resources.mkdir()
    env = dict(os.environ, HOME=str(home), BLENDER_USER_RESOURCES=str(resources))
    for name in ("BLENDER_USER_CONFIG", "BLENDER_USER_SCRIPTS", "BLENDER_USER_EXTENSIONS",
                 "BLENDER_USER_DATAFILES"):
        env.pop(name, None)
    process = subprocess.run(
        [sys.executable, "-c", SCRIPT, str(built_zip), MODULE],
        env=env, cwd=tmp_path, capture_output=True, text=True, timeout=120,
    )
    assert process.returncode == 0, process.stderr
    assert "Traceback" not in process.stderr and "rror" not in process.stderr, process.stderr
    lines = [line for line in process.stdout.splitlines() if line.startswith("REPORT=")]
    assert len(lines) == 1, process.stdout + process.stderr
    report = json.loads(lines[0][len("REPORT="):])

    # Installed into the temporary user folder, not the real one.
    assert report["user_extensions"] == str(resources / "extensions")
    assert (resources / "extensions" / "user_default" / "sh_lighting" / "__init__.py").is_file()
    assert report["install"] == ["FINISHED"]

    # Enabled on install, under the extension module name.
    assert report["enabled_pref"] is True
    assert report["enabled_check"] == [True, True]
    during_classes = set(report["during"]["classes"]) - set(report["before"]["classes"])
    assert f"{MODULE}.blender.data.preferences.SHLIGHT_AddonPreferences" in during_classes
    assert all(name.startswith(MODULE + ".") for name in during_classes), during_classes

    # Disabled cleanly: nothing registered by the add-on is left behind.
    assert report["disable"] == ["FINISHED"]
    assert report["disabled_pref"] is False
    assert report["disabled_check"] == [False, False]
    before, after = report["before"], report["after"]
    assert set(after["types"]) == set(before["types"]), set(after["types"]) ^ set(before["types"])
    assert set(after["classes"]) == set(before["classes"]), (
        set(after["classes"]) ^ set(before["classes"])
    )
    assert after["properties"] == before["properties"]
    assert after["handlers"] == before["handlers"]
