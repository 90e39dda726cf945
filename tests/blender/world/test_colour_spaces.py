"""Colour: every path decodes an image as Blender renders it, in the file's working space.

References are Cycles captures of the image used as the world (what Blender renders), never a
formula of ours. Blender 5.0 lets a file choose its working space (``bpy.data.colorspace``);
4.2 always renders in linear Rec.709, so the cases needing a choice are skipped there.
"""

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import bpy
import mathutils
import numpy as np
import pytest
from blender_files import write_png
from blender_scenes import environment_world

from sh_lighting.blender.data import compat
from sh_lighting.blender.world.capture import capture_world
from sh_lighting.blender.world.images import DecodeError, load_image_pixels
from sh_lighting.blender.world.reader import world_coefficients
from sh_lighting.core import colour
from sh_lighting.core.projection import project_equirect

pytestmark = pytest.mark.blender

ROOT = Path(__file__).resolve().parents[3]
HAS_WORKING_SPACES = hasattr(bpy.data, "colorspace")
needs_working_spaces = pytest.mark.skipif(
    not HAS_WORKING_SPACES, reason="Blender before 5.0 has no working colour space choice"
)
SQRT4PI = 2.0 * math.sqrt(math.pi)  # L00 of a constant sky of radiance 1


def set_working_space(name):
    if compat.working_space() != name:  # the operator cancels when nothing changes
        assert bpy.ops.wm.set_working_color_space(working_space=name) == {"FINISHED"}
    assert compat.working_space() == name


def image_world(image):
    """``image`` as the scene's world, read texel by texel ("Closest": the capture then shows
    the decoded texels exactly)."""
    return environment_world(bpy.context.scene, image, interpolation="Closest")


def cycles(world, width):
    return project_equirect(capture_world(world, width, samples=1, refine=False))


def rel_err(a, b):
    return np.abs(np.asarray(a) - np.asarray(b)).max() / np.abs(b).max()


def random_bytes(height=16, width=32, seed=7):
    return np.random.default_rng(seed).integers(0, 256, (height, width, 3))


# -- core's colour spaces are Blender's --------------------------------------------------------


@pytest.mark.parametrize("space", list(colour.WORKING_SPACES))
def test_core_matrices_and_luminance_are_blenders(space):
    """core.colour from primaries vs Blender's own conversions in that working space
    (measured 6e-7 on 5.0: Blender's are float32)."""
    if space != "Linear Rec.709" and not HAS_WORKING_SPACES:
        pytest.skip("Blender before 5.0 has no working colour space choice")
    set_working_space(space)
    eye = np.eye(3)
    from_rec709 = np.array(
        [tuple(mathutils.Color(tuple(e)).from_rec709_linear_to_scene_linear()) for e in eye]
    ).T
    to_xyz = np.array(
        [tuple(mathutils.Color(tuple(e)).from_scene_linear_to_xyz_d65()) for e in eye]
    ).T
    tolerance = 2e-6 if HAS_WORKING_SPACES else 1e-5
    assert np.abs(colour.conversion_matrix("Linear Rec.709", space) - from_rec709).max() < tolerance
    # 4.2's configuration defines XYZ by a rounded matrix: 2.3e-4 from the exact primaries.
    xyz_tolerance = 2e-6 if HAS_WORKING_SPACES else 3e-4
    assert np.abs(colour.rgb_to_xyz_matrix(space) - to_xyz).max() < xyz_tolerance
    assert np.abs(colour.luminance_weights(space) - to_xyz[1]).max() < xyz_tolerance


# -- 8-bit images: the one decoding, against Cycles --------------------------------------------


def test_mid_grey_srgb_png_is_0216_on_every_path(tmp_path):
    """Byte 128 of an sRGB PNG: 0.2159 (not 0.502) for Compute from World, the command line's
    compute and batch, and Cycles; an RGBA PNG with opaque alpha gives the same."""
    grey = np.full((8, 16, 3), 128)
    rgb = write_png(tmp_path / "grey.png", grey)
    rgba = write_png(tmp_path / "grey_rgba.png", grey, alpha=np.full((8, 16), 255))
    world = image_world(bpy.data.images.load(rgb))
    coeffs, info = world_coefficients(bpy.context.scene)
    reference = cycles(world, 32)
    assert info.source == "image"
    assert rel_err(coeffs, reference) < 1e-5
    assert abs(reference[0, 0] / SQRT4PI - 0.21586) < 1e-4  # what Cycles renders
    for path in (rgb, rgba):
        assert np.abs(load_image_pixels(path)[..., :3] - reference[0, 0] / SQRT4PI).max() < 1e-5
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    out = tmp_path / "grey.json"
    done = subprocess.run([sys.executable, "-m", "sh_lighting", "compute", rgba, "--out", out],
                          env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    written = json.loads(out.read_text())["coefficients"]["L00"]
    assert rel_err(written, reference[0]) < 1e-5
    batch = tmp_path / "batch"
    done = subprocess.run([sys.executable, "-m", "sh_lighting", "batch", tmp_path, batch,
                           "--pattern", "*.png"],
                          env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    for name in ("grey", "grey_rgba"):
        written = json.loads((batch / f"{name}.json").read_text())["coefficients"]["L00"]
        assert rel_err(written, reference[0]) < 1e-5


WORKING = ["Linear Rec.709", "ACEScg"]


@pytest.mark.parametrize("working", WORKING)
@pytest.mark.parametrize("space", [*colour.BYTE_SPACES, "Non-Color"])
def test_8bit_colour_spaces_agree_with_cycles(tmp_path, working, space):
    """Random bytes in each decodable colour space, in a Rec.709 and an ACEScg file: the image
    path against Cycles (measured in relative error of the largest coefficient: ≤ 1e-6 where
    Cycles decodes in float32, ≤ 4e-4 where it converts the texture to half floats)."""
    if working != "Linear Rec.709" and not HAS_WORKING_SPACES:
        pytest.skip("Blender before 5.0 has no working colour space choice")
    set_working_space(working)
    image = bpy.data.images.load(write_png(tmp_path / "bytes.png", random_bytes()))
    image.colorspace_settings.name = space
    world = image_world(image)
    coeffs, info = world_coefficients(bpy.context.scene, capture_width=32)
    assert info.source == "image" and info.working_space == working
    # Cycles keeps the bytes and decodes in float32 for sRGB (in Rec.709 files), for data and
    # for the working space itself; it converts every other case to half floats on load.
    exact = space in ("Non-Color", working) or (space, working) == ("sRGB", "Linear Rec.709")
    error = rel_err(coeffs, cycles(world, 32))
    print(f"{space} in {working}: {error:.2e}")
    assert error < (1e-5 if exact else 1e-3)


@needs_working_spaces
def test_red_srgb_png_in_an_acescg_file_is_what_cycles_renders(tmp_path):
    """Pure red sRGB in ACEScg is (0.613, 0.070, 0.021), not (1, 0, 0)."""
    set_working_space("ACEScg")
    red = np.zeros((8, 16, 3))
    red[..., 0] = 255
    world = image_world(bpy.data.images.load(write_png(tmp_path / "red.png", red)))
    coeffs, info = world_coefficients(bpy.context.scene)
    reference = cycles(world, 32)
    assert info.source == "image" and info.working_space == "ACEScg"
    assert np.abs(coeffs[0] / SQRT4PI - reference[0] / SQRT4PI).max() < 1e-3
    assert np.abs(reference[0] / SQRT4PI - (0.613, 0.070, 0.021)).max() < 1e-3


def test_transparent_8bit_texels_are_left_to_cycles(tmp_path):
    """Cycles shows 8-bit texels with alpha < 1 premultiplied (rounded in the encoded bytes on
    the Rec.709 path): not modelled, so the world is captured and the command line refuses."""
    alpha = np.full((8, 16), 255)
    alpha[:, :3] = 90
    path = write_png(tmp_path / "half.png", random_bytes(8, 16), alpha=alpha)
    world = image_world(bpy.data.images.load(path))
    coeffs, info = world_coefficients(bpy.context.scene, capture_width=32)
    assert info.source == "capture" and "transparent" in info.reason
    assert rel_err(coeffs, cycles(world, 32)) < 1e-3  # the capture is refined, the other not
    with pytest.raises(DecodeError, match="transparent texels.*save it without alpha"):
        load_image_pixels(path)
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    done = subprocess.run([sys.executable, "-m", "sh_lighting", "compute", path], env=env,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 1
    assert done.stderr.count("\n") == 1 and "transparent texels" in done.stderr


# -- exports, presets, the cache and luminance follow the working space --------------------------


def blender_luminance():
    """Blender's own luminance weights of the working space (Y of its XYZ conversion)."""
    return np.array(
        [mathutils.Color(tuple(e)).from_scene_linear_to_xyz_d65()[1] for e in np.eye(3)]
    )


def red_world_coefficients(tmp_path, working):
    set_working_space(working)
    red = np.zeros((8, 16, 3))
    red[..., 0] = 255
    red[:4, :, 1] = 128  # not constant: every band carries colour
    image_world(bpy.data.images.load(write_png(tmp_path / f"red_{working[-3:]}.png", red)))
    return world_coefficients(bpy.context.scene)[0]


@needs_working_spaces
def test_exports_are_linear_rec709_and_presets_come_back(tmp_path, addon):
    """An ACEScg file exports what the same image gives in a Rec.709 file (in every format),
    and importing its preset gives back its ACEScg values."""
    from sh_lighting import api
    from sh_lighting.blender.data import scene_data
    from sh_lighting.blender.presets import preset_io
    from sh_lighting.formats.interop import to_threejs_sh

    rec709 = red_world_coefficients(tmp_path, "Linear Rec.709")
    acescg = red_world_coefficients(tmp_path, "ACEScg")
    assert rel_err(acescg, rec709) > 0.1  # the spaces differ
    scene = bpy.context.scene
    api.set_coefficients(scene, acescg)
    path = preset_io.export_preset(scene, tmp_path / "p.json")
    written, _ = preset_io.read_preset_file(path)
    assert rel_err(written, rec709) < 1e-6
    three = json.loads(preset_io.export_preset(scene, tmp_path / "t.json", "threejs").read_text())
    assert np.abs(np.array(three["object"]["sh"]) - to_threejs_sh(rec709)).max() < 1e-6 * np.abs(rec709).max()
    api.set_coefficients(scene, np.zeros((9, 3)))
    preset_io.import_preset(scene, path)
    assert rel_err(scene_data.get_coefficients(scene), acescg) < 1e-9


class Untouchable:
    """World pixels that fail the test when anything reads them."""

    def __array__(self, *args, **kwargs):
        raise AssertionError("the world image was read for a format that carries none")

    def __getitem__(self, key):
        raise AssertionError("the world image was read for a format that carries none")


@pytest.mark.parametrize("fmt", ["sh_lighting", "threejs", "filament"])
def test_formats_without_an_image_never_read_the_world_image(tmp_path, fmt):
    """The formats that carry 9 numbers only cost nothing per texel (``compute --out a.json``
    of an 8K map spent 1.8 s and 800 MB converting the whole map's colour space for them)."""
    from sh_lighting.blender.presets import preset_io

    coeffs = np.arange(27, dtype=float).reshape(9, 3) / 27 + 0.1
    path = preset_io.export_coefficients(coeffs, tmp_path / f"p.{fmt}", fmt,
                                         environment=(Untouchable(), 1.0, None))
    assert path.stat().st_size > 0


@needs_working_spaces
def test_gltf_specular_cube_of_an_acescg_file_is_the_rec709_images(tmp_path):
    """The cube's colour conversion, done on its downsampled source, gives what converting the
    whole image first gives (both are linear)."""
    from sh_lighting.blender.presets import preset_io
    from sh_lighting.formats.gltf import gltf_text

    set_working_space("ACEScg")
    rng = np.random.default_rng(3)
    pixels = (rng.random((128, 256, 4)) * [1.0, 0.5, 0.2, 1.0]).astype(np.float32)
    pixels[20:30, 40:60, :3] = [30.0, 5.0, 1.0]
    coeffs = project_equirect(pixels)
    path = preset_io.export_coefficients(coeffs, tmp_path / "e.gltf", "gltf",
                                         environment=(pixels, 2.0, (0.1, 0.2, 0.3)))
    matrix = colour.conversion_matrix("ACEScg", "Linear Rec.709")
    expected = json.loads(gltf_text(
        colour.convert_coefficients(coeffs, "ACEScg"), pixels[..., :3] @ matrix.T, 2.0,
        (0.1, 0.2, 0.3)))
    written = json.loads(path.read_text())
    assert written["images"] == expected["images"]
    set_working_space("Linear Rec.709")


@needs_working_spaces
def test_compute_again_follows_a_switched_working_space(tmp_path):
    """Compute has no cache (benchmarks/REPORT.md, "the world cache"): computing again after
    switching the working space gives that space's coefficients."""
    from sh_lighting.blender.world import reader as world

    set_working_space("Linear Rec.709")
    red = np.zeros((8, 16, 3))
    red[..., 0] = 255
    image_world(bpy.data.images.load(write_png(tmp_path / "red.png", red)))
    first, info = world.world_coefficients(bpy.context.scene)
    assert bpy.ops.wm.set_working_color_space(working_space="ACEScg",
                                              convert_colors=False) == {"FINISHED"}
    second, info = world.world_coefficients(bpy.context.scene)
    assert info.working_space == "ACEScg"
    assert abs(second[0, 0] / first[0, 0] - 0.6131) < 1e-3


@needs_working_spaces
def test_saturation_greys_with_the_working_spaces_luminance(addon):
    from sh_lighting import api
    from sh_lighting.blender.data import scene_data
    from sh_lighting.blender.design import edits as design

    set_working_space("ACEScg")
    scene = bpy.context.scene
    coeffs = np.random.default_rng(3).normal(size=(9, 3))
    api.set_coefficients(scene, coeffs)
    design.saturation(scene, 0.0)
    grey = coeffs @ blender_luminance()
    # Blender's weights are float32 (6e-7 from the exact ones), the coefficients up to ~3.
    assert np.abs(scene_data.get_coefficients(scene) - grey[:, None]).max() < 5e-6
    assert np.abs(grey - coeffs @ [0.2126, 0.7152, 0.0722]).max() > 1e-3  # not Rec.709's


@needs_working_spaces
def test_command_line_compute_and_apply_in_an_acescg_file(tmp_path):
    """`compute` of an ACEScg .blend writes Rec.709 (what the same image gives in a Rec.709
    file); `apply` of that preset stores the ACEScg values in the .blend."""
    rec709 = red_world_coefficients(tmp_path, "Linear Rec.709")
    acescg = red_world_coefficients(tmp_path, "ACEScg")
    scene = bpy.context.scene
    material = bpy.data.materials.new("Grey")
    if material.node_tree is None:
        material.use_nodes = True
    mesh = bpy.data.meshes.new("Plane")
    mesh.from_pydata([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [], [(0, 1, 2)])
    mesh.materials.append(material)
    scene.collection.objects.link(bpy.data.objects.new("Plane", mesh))
    blend = tmp_path / "aces.blend"
    scene.world.node_tree.nodes["Environment Texture"].image.pack()  # travels with the file
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    env = {**os.environ, "PYTHONPATH": str(ROOT)}

    def run(*args):
        done = subprocess.run([sys.executable, "-m", "sh_lighting", *map(str, args)], env=env,
                              capture_output=True, text=True, timeout=120)
        assert done.returncode == 0, done.stderr

    preset = tmp_path / "aces.json"
    run("compute", blend, "--out", preset)
    written = json.loads(preset.read_text())["coefficients"]
    assert rel_err([written[k] for k in written], rec709) < 1e-6
    out = tmp_path / "applied.blend"
    run("apply", preset, blend, "--out", out)
    bpy.ops.wm.open_mainfile(filepath=str(out))
    from sh_lighting.blender.data import scene_data

    assert compat.working_space() == "ACEScg"
    assert rel_err(scene_data.get_coefficients(bpy.context.scene), acescg) < 1e-6
