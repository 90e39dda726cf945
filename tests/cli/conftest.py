"""A clean Blender per test (tests/blender_fixtures.py)."""

from blender_fixtures import addon, factory_blender  # noqa: F401
