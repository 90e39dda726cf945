"""Fixtures of every test that imports bpy: a clean Blender per test, the add-on on demand."""

import bpy
import pytest


@pytest.fixture(autouse=True)
def factory_blender():
    """Every Blender test starts from factory settings and leaves them behind."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    yield
    bpy.ops.wm.read_factory_settings(use_empty=True)


@pytest.fixture
def addon():
    """The add-on registered as the plain package ``sh_lighting`` for the test's duration."""
    import sh_lighting

    sh_lighting.register()
    yield sh_lighting
    sh_lighting.unregister()
