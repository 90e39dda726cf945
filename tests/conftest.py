"""Shared test helpers: paths of the reference data and of the HDRIs that ship inside bpy."""

import atexit
import os
import shutil
import sys
import tempfile
from pathlib import Path

import pytest

# Nothing a test runs may touch the real Blender configuration: Blender's user folder (config,
# scripts, presets, extensions) is a temporary folder for the whole session, set before bpy
# is first imported. Tests that need their own point BLENDER_USER_RESOURCES elsewhere; the
# command-line tests also give their processes a temporary HOME (tests/cli_runs.py).
USER_SANDBOX = tempfile.mkdtemp(prefix="sh_lighting_test_user_")
atexit.register(shutil.rmtree, USER_SANDBOX, ignore_errors=True)
os.environ["BLENDER_USER_RESOURCES"] = USER_SANDBOX
for _name in ("BLENDER_USER_CONFIG", "BLENDER_USER_SCRIPTS", "BLENDER_USER_DATAFILES",
              "BLENDER_USER_EXTENSIONS"):
    os.environ.pop(_name, None)

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "tests" / "data"  # facts the tests need, each file naming its source
HDRI_NAMES = ("city", "courtyard", "forest", "interior", "night", "studio", "sunrise", "sunset")


def bundled_hdri_dir():
    """Blender's studiolights/world folder inside the installed bpy wheel (8 CC0 EXRs)."""
    import bpy

    return Path(bpy.utils.system_resource("DATAFILES", path="studiolights/world"))


@pytest.fixture(scope="session")
def hdri_dir():
    return bundled_hdri_dir()


def pytest_collection_modifyitems(config, items):
    """Under pytest-xdist (``make test``: ``--dist loadfile``), the files with slow tests first.

    Each worker takes the next whole file when it is done; a minute-long file taken last
    would leave the other worker idle meanwhile. The order within a file is kept.
    """
    if not os.environ.get("PYTEST_XDIST_WORKER"):
        return
    slow = {item.path for item in items if item.get_closest_marker("slow")}
    items.sort(key=lambda item: item.path not in slow)


def pytest_sessionfinish(session, exitstatus):
    session.config.stash[EXIT_STATUS] = int(exitstatus)


EXIT_STATUS = pytest.StashKey[int]()


@pytest.hookimpl(trylast=True)
def pytest_unconfigure(config):
    """Leave without interpreter shutdown under bpy 4.2, which crashes there.

    The bpy 4.2.x Python module (not Blender itself) dies with SIGSEGV while Python shuts down
    once any property with a Python callback (get/set/update) has been registered, even after
    unregistering it; 5.0 does not. The tests have all run and reported by now, so the process
    ends with pytest's own exit status instead of that crash's 139.
    """
    bpy = sys.modules.get("bpy")
    if bpy is not None and bpy.app.version < (5, 0, 0):
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(config.stash.get(EXIT_STATUS, 0))
