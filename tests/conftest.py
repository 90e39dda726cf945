"""Shared test helpers: paths of the reference data and of the HDRIs that ship inside bpy."""

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
