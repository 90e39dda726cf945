"""The exports as people make them — the Export operator on a Blender scene, ``compute
--format gltf`` on an HDRI — read by Babylon.js's loader in node.

The scene's world is the one-texel map shown through a Mapping rotation at Strength 2, so the
specular cube must follow the Mapping node and the Strength as Blender renders the world.
"""

import json
import os
import subprocess
import sys

import bpy
import numpy as np
import pytest
from blender_files import write_exr
from blender_scenes import environment_world
from lightings import GLTF_NORMALS, NORMALS, TOLERANCE, deviation, texel_map

from sh_lighting.blender.data import scene_data
from sh_lighting.core.frames import BLENDER_TO_Y_UP
from sh_lighting.core.world_map import to_world_direction

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ROTATION = (0.3, -0.2, 0.7)  # the Mapping node's XYZ Euler, radians
STRENGTH = 2.0


@pytest.fixture
def addon():
    import sh_lighting

    bpy.ops.wm.read_factory_settings(use_empty=True)
    sh_lighting.register()
    yield
    sh_lighting.unregister()
    bpy.ops.wm.read_factory_settings(use_empty=True)


def texel_world(folder):
    """A world showing the one-texel map through a Mapping rotation at Strength 2."""
    exr = write_exr(folder / "texel.exr", texel_map()[0].astype(np.float32))
    environment_world(bpy.context.scene, exr, STRENGTH, ROTATION, name="Texel")
    return exr


def test_export_operator_gltf_follows_the_world_as_blender_shows_it(addon, run_node, tmp_path):
    texel_world(tmp_path)
    assert bpy.ops.shlight.compute_from_world() == {"FINISHED"}
    coeffs = scene_data.get_coefficients(bpy.context.scene)
    path = tmp_path / "world.gltf"
    assert bpy.ops.shlight.export_preset(
        "EXEC_DEFAULT", filepath=str(path), export_format="GLTF"
    ) == {"FINISHED"}
    text = path.read_text()
    light = json.loads(text)["extensions"]["EXT_lights_image_based"]["lights"][0]
    assert light["extras"]["source"] == "texel.exr" and str(tmp_path) not in text
    assert light["extras"]["specular_source"] == "world image"

    out = run_node("babylon.mjs", {"file": str(path), "normals": GLTF_NORMALS.tolist(),
                                   "rightHanded": True, "turnLeftHanded": False})
    assert deviation(out["diffuse"], coeffs) <= TOLERANCE
    d = deviation(out["diffuseFromCube"], coeffs)
    print(f"rotated world: Babylon irradiance of our specular cube {d:.3g} of the peak")
    assert d <= 0.02
    seen = np.array(out["brightest"]) @ BLENDER_TO_Y_UP
    where = to_world_direction(texel_map()[1], ROTATION)
    angle = np.degrees(np.arccos(np.clip(seen @ where, -1.0, 1.0)))
    print(f"rotated world: bright texel seen {angle:.2f}° from where Blender shows it")
    assert angle <= 2 * np.degrees(np.pi / 2 / 64)


def test_compute_format_gltf_writes_an_environment_babylon_loads(run_node, tmp_path):
    hdri = tmp_path / "private folder" / "texel.exr"
    hdri.parent.mkdir()
    write_exr(hdri, texel_map()[0].astype(np.float32))
    out_file = tmp_path / "texel.gltf"
    env = {**os.environ, "PYTHONPATH": ROOT}
    done = subprocess.run(
        [sys.executable, "-m", "sh_lighting", "compute", str(hdri), "--out", str(out_file),
         "--format", "gltf"], cwd=ROOT, env=env, capture_output=True, text=True, timeout=300,
    )
    assert done.returncode == 0, done.stderr
    assert f"Wrote glTF environment (EXT_lights_image_based) {out_file}" in done.stdout
    text = out_file.read_text()
    assert "private folder" not in text and str(tmp_path) not in text  # the file name only
    light = json.loads(text)["extensions"]["EXT_lights_image_based"]["lights"][0]
    assert light["extras"]["source"] == "texel.exr"
    from sh_lighting.formats.interop import from_gltf_irradiance_coefficients
    from sh_lighting.core.projection import project_equirect

    coeffs = project_equirect(texel_map()[0].astype(np.float32))
    stored = from_gltf_irradiance_coefficients(light["irradianceCoefficients"])
    np.testing.assert_allclose(stored * light["intensity"], coeffs, rtol=1e-6, atol=1e-9)
    out = run_node("babylon.mjs", {"file": str(out_file), "normals": GLTF_NORMALS.tolist(),
                                   "rightHanded": True, "turnLeftHanded": False})
    assert deviation(out["diffuse"], coeffs, NORMALS) <= TOLERANCE
    assert deviation(out["diffuseFromCube"], coeffs, NORMALS) <= 0.02
