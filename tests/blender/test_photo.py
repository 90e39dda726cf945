"""Match Photo on Cycles renders of a grey ball (albedo 0.18, Diffuse BSDF, no specular).

(a) A world that is exactly nine terms (an equirect EXR built from the SH), rendered
orthographic to EXR: the fit is within 0.5 % of the world's irradiance on the seen normals.
(b) A bundled HDRI (courtyard) rendered at 85 mm to an 8-bit sRGB PNG: within 1.25× of the
best nine-term fit to the world's true irradiance on the seen normals (floor 0.5 %), up to one
scale. Then the round trip in the user's order, the exposure against the world, and hostile
input through the operator (one line, nothing changed).
"""

import sys
from pathlib import Path

import bpy
import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from blender_files import SCRIPT, write_exr, write_png  # noqa: E402
from blender_scenes import read_exr, setup_render, unpack  # noqa: E402

from sh_lighting import api  # noqa: E402
from sh_lighting.blender import compat, scene_data  # noqa: E402
from sh_lighting.core.downsample import block_downsample  # noqa: E402
from sh_lighting.core.equirect import texel_directions  # noqa: E402
from sh_lighting.core.irradiance import irradiance, reference_irradiance  # noqa: E402
from sh_lighting.core.photo import best_nine_term_error, relative_rms, scaled_error  # noqa: E402
from sh_lighting.core.projection import project_equirect  # noqa: E402
from sh_lighting.core.sh import sh_basis, spread_normals  # noqa: E402

pytestmark = pytest.mark.blender

LIGHT = 0.5 * np.array(
    [[3.0, 2.5, 2.0], [0.5, 0.4, 0.2], [1.1, 1.0, 0.9], [-0.4, -0.2, 0.0], [0.2, 0.1, 0.0],
     [0.0, -0.2, 0.1], [0.3, 0.3, 0.2], [0.1, 0.1, 0.3], [-0.2, 0.0, 0.2]]
)  # non-negative radiance everywhere (min 0.049)
SIZE = 96
ORTHO_SCALE = 2.2  # the unit ball's radius is SIZE / 2.2 = 43.6 px
DISTANCE_85 = 5.5  # the 85 mm camera's distance: the ball's radius is ~40 px
SAMPLES = 32  # measured: 2.4 % noise per pixel, 0.10 % error of the fit (averaged)
EXACT_BOUND = 0.005  # the issue's: ≤ 0.5 % from a noise-free EXR of a nine-term world
HEADROOM = 1.25  # the issue's: within 1.25× of the best nine-term fit (floor 0.5 %)


def sh_world_pixels():
    return (sh_basis(texel_directions(128, 256)) @ LIGHT).astype(np.float32)


def grey_ball_scene(world_path, projection="ORTHO", strength=1.0):
    """A unit grey ball at the origin, the world an equirect image, a camera at −Y looking
    along +Y (orthographic, or 85 mm perspective); the scene's camera."""
    scene = bpy.context.scene
    world = bpy.data.worlds.new("Photo world")
    tree = compat.ensure_node_tree(world)
    texture = tree.nodes.new("ShaderNodeTexEnvironment")
    texture.image = bpy.data.images.load(str(world_path))
    background = tree.nodes["Background"]
    background.inputs["Strength"].default_value = strength
    tree.links.new(texture.outputs["Color"], background.inputs["Color"])
    scene.world = world
    bpy.ops.mesh.primitive_uv_sphere_add(segments=96, ring_count=48, radius=1.0)
    ball = bpy.context.object
    bpy.ops.object.shade_smooth()
    material = bpy.data.materials.new("Grey ball")
    mtree = compat.ensure_node_tree(material)
    for node in list(mtree.nodes):
        if node.type != "OUTPUT_MATERIAL":
            mtree.nodes.remove(node)
    diffuse = mtree.nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (0.18, 0.18, 0.18, 1.0)
    mtree.links.new(diffuse.outputs[0], mtree.nodes["Material Output"].inputs["Surface"])
    ball.data.materials.append(material)
    data = bpy.data.cameras.new("Photo camera")
    data.type = projection
    data.ortho_scale = ORTHO_SCALE
    data.lens, data.sensor_width, data.sensor_fit = 85.0, 36.0, "AUTO"
    camera = bpy.data.objects.new("Photo camera", data)
    scene.collection.objects.link(camera)
    camera.location = (0.0, -(DISTANCE_85 if projection == "PERSP" else 5.0), 0.0)
    camera.rotation_euler = (np.pi / 2, 0.0, 0.0)
    scene.camera = camera
    setup_render(scene, SIZE, samples=SAMPLES)
    scene.render.film_transparent = False
    return scene, material


def circle_of(projection):
    if projection == "ORTHO":
        return (SIZE / 2, SIZE / 2, SIZE / ORTHO_SCALE)
    # on the axis: tan(angular radius) · f / (sensor / SIZE) pixels
    alpha = np.arcsin(1.0 / DISTANCE_85)
    return (SIZE / 2, SIZE / 2, np.tan(alpha) * 85.0 / (36.0 / SIZE))


def render_exr(scene, path):
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    return unpack(read_exr(path), scene.view_layers[0].name)[0]


def render_png(scene, path):
    """The render as an 8-bit sRGB PNG (Standard view), RGB only."""
    settings = scene.render.image_settings
    if hasattr(settings, "media_type"):
        settings.media_type = "IMAGE"
    settings.file_format, settings.color_mode, settings.color_depth = "PNG", "RGB", "8"
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    return str(path)


@pytest.fixture(scope="module")
def photos(tmp_path_factory):
    """The renders, made once: {name: path}, and the worlds' files."""
    folder = tmp_path_factory.mktemp("photo")
    out = {"sh_world": write_exr(folder / "sh_world.exr", sh_world_pixels())}
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene, _ = grey_ball_scene(out["sh_world"])
    rgb = render_exr(scene, folder / "sh_render.exr")
    out["sh_exr"] = write_exr(folder / "sh_photo.exr", rgb)
    out["sh_png"] = render_png(scene, folder / "sh_photo.png")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    hdri = Path(bpy.utils.system_resource("DATAFILES", path="studiolights/world")) / "courtyard.exr"
    out["hdri"] = str(hdri)
    scene, _ = grey_ball_scene(hdri, "PERSP", strength=1.0)
    out["hdri_png"] = render_png(scene, folder / "hdri_photo.png")
    return out


def test_exact_nine_term_world_from_an_exr_is_fitted_within_half_a_percent(photos, addon):
    scene, _ = grey_ball_scene(photos["sh_world"])
    truth = project_equirect(sh_world_pixels())
    for prior in ("none", "mirror", "ambient"):
        coeffs, fit = api.coefficients_from_photo(scene, photos["sh_exr"], circle_of("ORTHO"),
                                                  prior=prior)
        seen = relative_rms(irradiance(coeffs, fit.normals), irradiance(truth, fit.normals))
        assert seen <= EXACT_BOUND, (prior, seen, fit.summary())
        assert fit.clipped == 0 and fit.used > 5000
    assert scene_data.provenance(scene)["source"] == "PHOTO"
    assert scene_data.provenance(scene)["file"] == "sh_photo.exr"
    assert scene_data.provenance(scene)["camera"] == "Photo camera"


def test_bundled_hdri_from_an_8bit_png_is_within_the_nine_term_limit(photos, addon, capsys):
    scene, _ = grey_ball_scene(photos["hdri"], "PERSP")
    pixels = api_pixels(photos["hdri"])
    small = block_downsample(pixels[..., :3], 4)[0]  # 256×128: the reference's cost, same light
    world = project_equirect(pixels[..., :3])
    everywhere = spread_normals(512)
    rows = []
    for prior in ("none", "mirror", "ambient"):
        _, fit = api.coefficients_from_photo(scene, photos["hdri_png"], circle_of("PERSP"),
                                             prior=prior)
        normals = fit.normals[::3]
        truth = reference_irradiance(small, normals)
        limit = best_nine_term_error(normals, truth)
        seen, _ = scaled_error(irradiance(fit.coefficients, normals), truth)
        unseen, _ = scaled_error(irradiance(fit.coefficients, everywhere),
                                 irradiance(world, everywhere))
        rows.append((prior, seen, limit, unseen, fit.clipped))
        assert seen <= max(HEADROOM * limit, 0.005), (prior, seen, limit)
    with capsys.disabled():
        for prior, seen, limit, unseen, clipped in rows:
            print(f"\n  courtyard 8-bit 85 mm, prior {prior:7s}: seen {100 * seen:.2f} % (limit "
                  f"{100 * limit:.2f} %), all normals vs the world's nine terms "
                  f"{100 * unseen:.1f} %, {clipped} clipped")


def api_pixels(path):
    from sh_lighting.blender.world.images import load_image_pixels

    return load_image_pixels(path).astype(np.float64)


def test_round_trip_photo_match_apply_render_matches_the_photo(photos, addon, tmp_path):
    scene, material = grey_ball_scene(photos["sh_world"])
    result = bpy.ops.shlight.match_photo(filepath=photos["sh_png"], circle=circle_of("ORTHO"))
    assert result == {"FINISHED"}
    api.apply_to_materials([material], scene)
    rendered = render_exr(scene, tmp_path / "round_trip.exr")
    photo = api_pixels(photos["sh_png"])[..., :3]
    cx, cy, r = circle_of("ORTHO")
    yy, xx = np.mgrid[:SIZE, :SIZE] + 0.5
    inside = np.hypot(xx - cx, yy - cy) < 0.9 * r

    def codes(v):
        v = np.clip(v, 0.0, 1.0)
        return 255.0 * np.where(v <= 0.0031308, 12.92 * v, 1.055 * v ** (1 / 2.4) - 0.055)

    difference = np.abs(codes(rendered[inside]) - codes(photo[inside]))
    # The photo's own render noise (32 spp, 2.4 % per pixel) is in it; the fit averages it
    # out. Measured: RMS 2.2 codes, mean 0.3 codes (the bias: within 8-bit quantisation).
    assert np.mean(codes(rendered[inside]) - codes(photo[inside])) == pytest.approx(0.0, abs=0.5)
    assert np.sqrt(np.mean(difference ** 2)) < 4.0


def test_exposure_against_the_world(photos, addon):
    scene, _ = grey_ball_scene(photos["hdri"], "PERSP")
    _, fit = api.coefficients_from_photo(scene, photos["hdri_png"], circle_of("PERSP"))
    match = api.photo_exposure(scene, fit)
    # Albedo 0.18 and the world's own strength: on the seen side the exposure is 1.
    assert match.seen_scale == pytest.approx(1.0, abs=0.02)
    # The L00 calibration is as good as one photo fixes L00: poorly (the fit names
    # L1-1+L00 among its weak terms; the mirror prior puts the bright front on the back).
    # Measured: × 1.19 (mirror), 0.97 (no prior).
    assert "L1-1+L00" in fit.weak_terms
    assert 0.9 < match.scale < 1.3
    assert match.seen < 0.25 and match.everywhere < 0.35
    assert "exposure ×" in match.summary()


def hostile_photos(folder):
    return {
        "white": write_png(folder / "white.png", np.full((SIZE, SIZE, 3), 255.0)),
        "black": write_png(folder / "black.png", np.zeros((SIZE, SIZE, 3))),
        "noise": write_png(folder / "noise.png",
                           np.random.default_rng(3).integers(0, 255, (SIZE, SIZE, 3))),
    }


@pytest.mark.parametrize("case, message", [
    ("outside", "outside the 96×96 image"),
    ("radius0", "radius is 0 px"),
    ("radius1", "radius is 1 px"),
    ("white", "clipped"),
    ("black", "black"),
    ("noise", "away from any diffuse ball"),
    ("missing", "does not exist"),
])
def test_hostile_input_one_line_and_nothing_changed(case, message, photos, addon, tmp_path):
    scene, _ = grey_ball_scene(photos["sh_world"])
    scene_data.store(scene, LIGHT, SCRIPT)
    before = scene_data.get_coefficients(scene).copy()
    paths = hostile_photos(tmp_path)
    cx, cy, r = circle_of("ORTHO")
    path, circle = photos["sh_png"], (cx, cy, r)
    if case == "outside":
        circle = (500.0, 48.0, 20.0)
    elif case.startswith("radius"):
        circle = (cx, cy, float(case[-1]))
    elif case == "missing":
        path = str(tmp_path / "nothing.png")
    else:
        path = paths[case]
    from sh_lighting.blender.ui.photo import SHLIGHT_OT_match_photo
    from blender_scenes import run_execute

    result, reports = run_execute(
        SHLIGHT_OT_match_photo, filepath=path, circle=circle, albedo=0.18, margin=0.05,
        prior="mirror", camera="SCENE", direction=(0.0, 1.0, 0.0), roll=0.0,
        projection="ORTHO", focal_mm=85.0, sensor_mm=36.0, clip=0.0)
    assert result == {"CANCELLED"}
    (kinds, text), = reports
    assert kinds == {"ERROR"} and message in text and "\n" not in text, text
    assert np.array_equal(scene_data.get_coefficients(scene), before)
    assert scene_data.provenance(scene) == SCRIPT


def test_a_16bit_png_is_read_as_blender_reads_it(photos, addon, tmp_path):
    scene, _ = grey_ball_scene(photos["sh_world"])
    image = bpy.data.images.load(photos["sh_png"])
    settings = scene.render.image_settings
    if hasattr(settings, "media_type"):
        settings.media_type = "IMAGE"
    settings.file_format, settings.color_mode, settings.color_depth = "PNG", "RGB", "16"
    image.save_render(str(tmp_path / "sixteen.png"), scene=scene)
    bpy.data.images.remove(image)
    _, eight = api.coefficients_from_photo(scene, photos["sh_png"], circle_of("ORTHO"),
                                           store=False)
    _, sixteen = api.coefficients_from_photo(scene, tmp_path / "sixteen.png",
                                             circle_of("ORTHO"), store=False)
    assert sixteen.used == eight.used
    assert np.abs(sixteen.coefficients - eight.coefficients).max() < 0.01 * LIGHT[0].max()
