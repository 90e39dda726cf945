"""Shared test helpers: paths of the reference data and of the HDRIs that ship inside bpy."""

import os
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SHARED_DATA = ROOT.parent / "shared" / "data"
HDRI_NAMES = ("city", "courtyard", "forest", "interior", "night", "studio", "sunrise", "sunset")


def bundled_hdri_dir():
    """Blender's studiolights/world folder inside the installed bpy wheel (8 CC0 EXRs)."""
    import bpy

    return Path(bpy.utils.system_resource("DATAFILES", path="studiolights/world"))


@pytest.fixture(scope="session")
def hdri_dir():
    return bundled_hdri_dir()


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
