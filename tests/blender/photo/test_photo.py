"""Match Photo on Cycles renders of a grey ball (albedo 0.18, Diffuse BSDF, no specular).

(a) A world that is exactly nine terms (an equirect EXR built from the SH), rendered
orthographic to EXR: the fit is within 0.5 % of the world's irradiance on the seen normals.
(b) A bundled HDRI (courtyard) rendered at 85 mm to an 8-bit sRGB PNG: within 1.25× of the
best nine-term fit to the world's true irradiance on the seen normals (floor 0.5 %), up to one
scale. Then the round trip in the user's order, the exposure against the world, and hostile
input through the operator (one line, nothing changed).
"""

from pathlib import Path

import bpy
import numpy as np
import pytest
from blender_files import SCRIPT, write_exr, write_png

from benchmarks.bench_photo import error_table
from benchmarks.photo_scene import (
    LIGHT,
    SIZE,
    circle_of,
    grey_ball_scene,
    linear,
    render_exr,
    render_png,
    sh_world_pixels,
    turn_camera,
)
from sh_lighting import api
from sh_lighting.blender.data import scene_data
from sh_lighting.core.downsample import block_downsample
from sh_lighting.core.irradiance import irradiance, reference_irradiance
from sh_lighting.core.mirror_ball import mirror_ball_image, project_mirror_ball
from sh_lighting.core.photo import (
    best_nine_term_error,
    relative_rms,
    scaled_error,
)
from sh_lighting.core.projection import project_equirect
from sh_lighting.core.sh import spread_normals

pytestmark = pytest.mark.blender

EXACT_BOUND = 0.005  # the goal: ≤ 0.5 % from a noise-free EXR of a nine-term world
HEADROOM = 1.25  # the goal: within 1.25× of the best nine-term fit (floor 0.5 %)


@pytest.fixture(scope="module")
def photos(tmp_path_factory):
    """The renders, made once: {name: path}, and the worlds' files."""
    folder = tmp_path_factory.mktemp("photo")
    out = {"sh_world": write_exr(folder / "sh_world.exr", sh_world_pixels())}
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene, _ = grey_ball_scene(out["sh_world"])
    out["sh_exr"] = render_exr(scene, folder / "sh_photo.exr")
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
    return linear(path)


def test_round_trip_photo_match_apply_render_matches_the_photo(photos, addon, tmp_path):
    scene, material = grey_ball_scene(photos["sh_world"])
    result = bpy.ops.shlight.match_photo(filepath=photos["sh_png"], circle=circle_of("ORTHO"))
    assert result == {"FINISHED"}
    api.apply_to_materials([material], scene)
    rendered = linear(render_exr(scene, tmp_path / "round_trip.exr"))
    photo = api_pixels(photos["sh_png"])[..., :3]
    cx, cy, r = circle_of("ORTHO")
    yy, xx = np.mgrid[:SIZE, :SIZE] + 0.5
    inside = np.hypot(xx - cx, yy - cy) < 0.9 * r

    def codes(v):
        v = np.clip(v, 0.0, 1.0)
        return 255.0 * np.where(v <= 0.0031308, 12.92 * v, 1.055 * v ** (1 / 2.4) - 0.055)

    difference = np.abs(codes(rendered[inside]) - codes(photo[inside]))
    # The photo's own render noise (32 spp, 2.4 % per pixel) is in it; the fit averages it
    # out, so the difference is the photo's noise; its mean (the bias) is within the 8-bit
    # quantisation.
    bias = float(np.mean(codes(rendered[inside]) - codes(photo[inside])))
    spread = float(np.sqrt(np.mean(difference ** 2)))
    print(f"\n  round trip, nine-term world: bias {bias:+.2f} codes, RMS {spread:.2f} codes")
    assert abs(bias) < 0.5
    assert spread < 1.5  # measured 0.87 (quantisation alone: 0.29)


def test_exposure_against_the_world(photos, addon):
    scene, _ = grey_ball_scene(photos["hdri"], "PERSP")
    _, fit = api.coefficients_from_photo(scene, photos["hdri_png"], circle_of("PERSP"))
    match = api.photo_exposure(scene, fit)
    # Albedo 0.18 and the world's own strength: on the seen side the exposure is 1.
    assert match.seen_scale == pytest.approx(1.0, abs=0.02)
    # The chrome ball's L00 calibration is as good as one photo fixes L00: poorly (the fit names
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
    ("no camera", "no camera: set the scene's camera"),
    ("no second photo", "the second-photo prior needs a second photo"),
    ("no chrome ball", "chrome ball '"),
    ("black second photo", "second photo 'black.png': the ball is black"),
])
def test_hostile_input_one_line_and_nothing_changed(case, message, photos, addon, tmp_path):
    scene, _ = grey_ball_scene(photos["sh_world"])
    scene_data.store(scene, LIGHT, SCRIPT)
    before = scene_data.get_coefficients(scene).copy()
    paths = hostile_photos(tmp_path)
    cx, cy, r = circle_of("ORTHO")
    path, circle = photos["sh_png"], (cx, cy, r)
    prior, chrome, second = "mirror", "", ""
    if case == "no second photo":
        prior = "photo"
    elif case == "black second photo":
        prior, second = "photo", paths["black"]
    elif case == "no chrome ball":
        prior, chrome = "chrome", str(tmp_path / "no_chrome.exr")
    elif case == "outside":
        circle = (500.0, 48.0, 20.0)
    elif case.startswith("radius"):
        circle = (cx, cy, float(case[-1]))
    elif case == "missing":
        path = str(tmp_path / "nothing.png")
    elif case == "no camera":
        scene.camera = None
    else:
        path = paths[case]
    from sh_lighting.blender.ui.photo import SHLIGHT_OT_match_photo
    from blender_scenes import run_execute

    result, reports = run_execute(
        SHLIGHT_OT_match_photo, filepath=path, circle=circle, albedo=0.18, margin=0.05,
        prior=prior, camera="SCENE", direction=(0.0, 1.0, 0.0), roll=0.0,
        projection="ORTHO", focal_mm=85.0, sensor_mm=36.0, clip=0.0, chrome_filepath=chrome,
        second_filepath=second, second_circle=(cx, cy, r), second_direction=(0.0, -1.0, 0.0),
        second_roll=0.0)
    assert result == {"CANCELLED"}
    (kinds, text), = reports
    assert kinds == {"ERROR"} and message in text and "\n" not in text, text
    assert np.array_equal(scene_data.get_coefficients(scene), before)
    assert scene_data.provenance(scene) == SCRIPT


def match_photo(path, circle):
    """The Match Photo operator's execute on ``path`` and ``circle`` (scene camera, ORTHO)."""
    from blender_scenes import run_execute

    from sh_lighting.blender.ui.photo import SHLIGHT_OT_match_photo

    return run_execute(
        SHLIGHT_OT_match_photo, filepath=str(path), circle=circle, albedo=0.18, margin=0.05,
        prior="mirror", camera="SCENE", direction=(0.0, 1.0, 0.0), roll=0.0,
        projection="ORTHO", focal_mm=85.0, sensor_mm=36.0, clip=0.0, chrome_filepath="",
        second_filepath="", second_circle=circle, second_direction=(0.0, -1.0, 0.0),
        second_roll=0.0)


@pytest.mark.parametrize("where", ["centred on the rim", "twice the radius"])
def test_a_wrong_circle_is_told_first_with_what_to_check(where, photos, addon):
    """A circle centred on the ball's rim, or twice its radius, fits its pixels far worse than
    a matte ball's (L00 0.5x / 2.3x the right one): refused, or a warning that comes first."""
    scene, _ = grey_ball_scene(photos["sh_world"])
    cx, cy, r = circle_of("ORTHO")
    circle = (cx + r, cy, r) if where == "centred on the rim" else (cx, cy, 2.0 * r)
    result, reports = match_photo(photos["sh_png"], circle)
    (kinds, text), = reports
    if result == {"CANCELLED"}:
        assert kinds == {"ERROR"} and "circle" in text, text
        return
    assert kinds == {"WARNING"}, text
    assert text.startswith("Match Photo: poor fit:"), text
    assert "check that the circle" in text
    _, right = match_photo(photos["sh_png"], (cx, cy, r))
    assert right[0][0] == {"INFO"} and "poor fit" not in right[0][1]


def byte_values(path):
    """The 8-bit file's own values (0-255, rows top to bottom), as Blender loads them."""
    image = bpy.data.images.load(str(path), check_existing=False)
    width, height = image.size
    flat = np.empty(width * height * 4, dtype=np.float32)
    image.pixels.foreach_get(flat)
    bpy.data.images.remove(image)
    return np.round(flat.reshape(height, width, 4)[::-1, :, :3] * 255.0)


def test_a_cut_out_rgba_png_is_fitted_where_the_ball_is_opaque(photos, addon, tmp_path):
    """An 8-bit RGBA PNG with the ball opaque on a transparent background (how a cut-out is
    saved) gives what the same photo without alpha gives; only transparent texels inside the
    circle are a problem, said in one line."""
    scene, _ = grey_ball_scene(photos["sh_world"])
    cx, cy, r = circle_of("ORTHO")
    values = byte_values(photos["sh_png"])
    height, width = values.shape[:2]
    y, x = np.mgrid[0:height, 0:width] + 0.5
    inside = (x - cx) ** 2 + (y - cy) ** 2 <= (r + 1.0) ** 2
    values[~inside] = 0.0  # a cut-out: nothing kept around the ball
    cut = write_png(tmp_path / "cut_out.png", values, alpha=np.where(inside, 255.0, 0.0))
    _, plain = api.coefficients_from_photo(scene, photos["sh_png"], (cx, cy, r), store=False)
    _, fit = api.coefficients_from_photo(scene, cut, (cx, cy, r), store=False)
    assert fit.used == plain.used
    assert np.abs(fit.coefficients - plain.coefficients).max() < 1e-6
    with pytest.raises(ValueError, match=r"transparent.*check the circle"):
        api.coefficients_from_photo(scene, cut, (cx, cy, 1.5 * r), store=False)


def test_a_16bit_png_is_read_as_blender_reads_it(photos, addon, tmp_path):
    scene, _ = grey_ball_scene(photos["sh_world"])
    image = bpy.data.images.load(photos["sh_png"])
    settings = scene.render.image_settings
    if hasattr(settings, "media_type"):
        settings.media_type = "IMAGE"
    settings.file_format, settings.color_mode, settings.color_depth = "PNG", "RGB", "16"
    image.save_render(str(tmp_path / "sixteen.png"), scene=scene)
    bpy.data.images.remove(image)
    assert bpy.data.images.load(str(tmp_path / "sixteen.png")).is_float  # really 16-bit
    _, eight = api.coefficients_from_photo(scene, photos["sh_png"], circle_of("ORTHO"),
                                           store=False)
    _, sixteen = api.coefficients_from_photo(scene, tmp_path / "sixteen.png",
                                             circle_of("ORTHO"), store=False)
    assert sixteen.used == eight.used
    assert np.abs(sixteen.coefficients - eight.coefficients).max() < 0.01 * LIGHT[0].max()


def test_error_against_added_noise_and_a_hidden_quarter(photos, addon):
    """The numbers benchmarks/bench_photo.py plots: the fit's error on the seen normals and
    over all normals (against the world's nine terms) with Gaussian noise added to the EXR
    photo (σ a fraction of each pixel), with the whole ball seen and a quarter hidden."""
    scene, _ = grey_ball_scene(photos["sh_world"])
    errors = error_table(photos["sh_exr"], scene, (0.0, 0.05, 0.2))
    # Measured by the bench (other noise draws; the photo already has the render's 2.4 %):
    # seen 0.20 / 0.36 / 1.07 % at σ 0 / 5 / 20 % (full ball), 0.21 / 0.37 / 0.82 % (a
    # quarter hidden, fewer normals to be wrong on); condition 67 against 74.
    full, quarter = errors["full"], errors["quarter"]
    assert full[0.0][0] < EXACT_BOUND and full[0.05][0] < 0.006 and full[0.2][0] < 0.02
    assert full[0.0][0] < full[0.05][0] < full[0.2][0]
    assert quarter[0.0][0] < EXACT_BOUND and quarter[0.2][0] < 0.02
    assert quarter[0.0][2] > full[0.0][2] > 10.0  # the condition number


@pytest.fixture(scope="module")
def both_balls(photos, tmp_path_factory):
    """Both balls on set: a chrome ball's mirror-ball image of courtyard (256 px, made from the
    equirect map) as the world, Mirror Ball projection; the grey ball photographed in it one
    stop under (view exposure −1), 85 mm, 8-bit, from −Y and again from +Y."""
    folder = tmp_path_factory.mktemp("both_balls")
    courtyard = linear(photos["hdri"])
    out = {"chrome": write_exr(folder / "chrome.exr", mirror_ball_image(courtyard, 256)),
           "courtyard": courtyard}
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene, _ = grey_ball_scene(out["chrome"], "PERSP", world_projection="MIRROR_BALL")
    scene.view_settings.exposure = -1.0
    out["front"] = render_png(scene, folder / "front.png")
    turn_camera(scene)
    out["back"] = render_png(scene, folder / "back.png")
    return out


def test_both_balls_the_chrome_ball_calibrates_the_exposure_and_fills_the_unseen_side(
        both_balls, addon, capsys):
    scene, _ = grey_ball_scene(both_balls["chrome"], "PERSP", world_projection="MIRROR_BALL")
    world = project_mirror_ball(linear(both_balls["chrome"]))  # what the world's light is
    everywhere = spread_normals(512)
    second = api.SecondPhoto(both_balls["back"], circle_of("PERSP"), direction=(0.0, -1.0, 0.0))
    small = block_downsample(both_balls["courtyard"], 4)[0]
    rows = {}
    for prior in ("mirror", "chrome", "photo"):
        coeffs, fit = api.coefficients_from_photo(scene, both_balls["front"], circle_of("PERSP"),
                                                  prior=prior, second=second)
        normals = fit.normals[::3]
        truth = reference_irradiance(small, normals)
        limit = best_nine_term_error(normals, truth)
        seen, _ = scaled_error(irradiance(coeffs, normals), truth)
        error, _ = scaled_error(irradiance(coeffs, everywhere), irradiance(world, everywhere))
        rows[prior] = (seen, limit, error, fit)
        assert seen <= max(HEADROOM * limit, 0.005), (prior, seen, limit)
        assert fit.negative is None
    with capsys.disabled():
        for prior, (seen, limit, error, fit) in rows.items():
            print(f"\n  chrome-ball world, prior {prior:6s}: seen {100 * seen:.2f} % (limit "
                  f"{100 * limit:.2f} %), all normals {100 * error:.1f} %, weight "
                  f"{fit.prior_weight:.3g}, residual {100 * fit.residual:.1f} % (noise "
                  f"{100 * fit.noise:.1f} %)")
    record = scene_data.provenance(scene)
    assert record["prior"] == "photo" and record["second_file"] == "back.png"
    # Measured over all normals, Blender 5.0: mirror 27.2 %, chrome 9.4 %, second photo 9.7 %
    # (seen: 1.06, 1.13, 1.12× the nine-term limit). Blender 4.2's render: 20.9 / 19.6 /
    # 19.6 %: its pixel noise is estimated above the residual (11.2 % against 11.0 %), the
    # misfit is then taken as the 0.5 % floor and the measured prior barely weighs (0.0005).
    assert rows["chrome"][2] < rows["mirror"][2]
    assert rows["photo"][2] < rows["mirror"][2]
    # Both balls: the grey ball is one stop under the chrome ball (albedo 0.18 known).
    _, fit = api.coefficients_from_photo(scene, both_balls["front"], circle_of("PERSP"),
                                         prior="chrome")
    record = scene_data.provenance(scene)
    assert record["chrome"] == "WORLD" and len(record["prior_scale"]) == 3
    match = api.photo_exposure(scene, fit)
    assert match.scale == pytest.approx(record["exposure_scale"], rel=1e-9)
    assert match.scale == pytest.approx(2.0, rel=0.05), match.summary()
    # Measured (5.0): × 2.008 (L00), × 1.996 (seen side); they then differ by 3.3 % on the
    # seen side, 9.9 % over all normals (the prior's limited weight: the photo's own light
    # wins; 4.2: × 1.993, 4.1 % and 20.0 %).
    assert match.seen < 0.05 and match.everywhere < 0.3, match.summary()
    # The same chrome ball from its file, not the world: the same numbers.
    from_file = api.photo_exposure(scene, fit, both_balls["chrome"])
    assert from_file.scale == pytest.approx(match.scale, rel=1e-6)
    print(f"\n  both balls: {match.summary()}")


def test_round_trip_under_a_real_hdri_is_within_the_nine_term_limit(photos, addon, tmp_path):
    """photo (courtyard, 8-bit, 85 mm) → Match Photo → Apply → render from the photo's camera:
    the render differs from the photo by the nine-term limit and the photo's own noise.
    Compared on 4×4 pixel blocks inside 0.9 r (block means: the photo's noise / 4), the noise
    (``PhotoFit.noise`` / 4) taken out in quadrature."""
    scene, material = grey_ball_scene(photos["hdri"], "PERSP")
    result = bpy.ops.shlight.match_photo(filepath=photos["hdri_png"], circle=circle_of("PERSP"),
                                         prior="none")
    assert result == {"FINISHED"}
    _, fit = api.coefficients_from_photo(scene, photos["hdri_png"], circle_of("PERSP"),
                                         prior="none", store=False)
    api.apply_to_materials([material], scene)
    rendered = linear(render_exr(scene, tmp_path / "round_trip.exr"))
    photo = linear(photos["hdri_png"])
    cx, cy, r = circle_of("PERSP")
    yy, xx = np.mgrid[:SIZE, :SIZE] + 0.5
    inside = np.hypot(xx - cx, yy - cy) < 0.9 * r
    blocks = inside.reshape(SIZE // 4, 4, SIZE // 4, 4).all(axis=(1, 3))

    def block_means(image):
        return image.reshape(SIZE // 4, 4, SIZE // 4, 4, 3).mean(axis=(1, 3))[blocks]

    difference = relative_rms(block_means(rendered), block_means(photo))
    misfit = np.sqrt(max(difference**2 - (fit.noise / 4.0) ** 2, 0.0))
    pixels = linear(photos["hdri"])
    normals = fit.normals[::3]
    limit = best_nine_term_error(normals, reference_irradiance(block_downsample(pixels, 4)[0],
                                                               normals))
    print(f"\n  round trip under courtyard: blocks differ {100 * difference:.2f} %, less the noise "
          f"{100 * misfit:.2f} %, nine-term limit {100 * limit:.2f} %")
    assert misfit <= HEADROOM * limit, (difference, misfit, limit, fit.noise)


def test_the_image_editor_drag_gives_the_circle_in_pixels(addon):
    from sh_lighting.blender.ui.photo import circle_from_drag

    # a 200×100 image: centre at u 0.25, v 0.75 (a quarter from the left, a quarter from the
    # top), rim 30 px to the right
    cx, cy, r = circle_from_drag((200, 100), (0.25, 0.75), (0.25 + 30 / 200, 0.75))
    assert (cx, cy) == pytest.approx((50.0, 25.0)) and r == pytest.approx(30.0)
    assert circle_from_drag((200, 100), (0.5, 0.5), (0.5, 0.3))[2] == pytest.approx(20.0)
    assert not bpy.ops.shlight.photo_circle.poll()  # no Image Editor in background mode


def test_the_ball_is_detected_in_renders_as_a_suggestion(photos, addon, tmp_path):
    """core.ball_detect on Cycles renders (the world behind the ball): the circle the scene
    gives, to a fraction of a pixel; a photo with no ball gives none, in one line."""
    for name, projection in (("sh_png", "ORTHO"), ("hdri_png", "PERSP")):
        guess = api.detect_photo_ball(photos[name])
        cx, cy, r = circle_of(projection)
        # Measured: within 0.3 px (the render's 32 spp noise, the rim's antialiasing).
        assert np.hypot(guess.cx - cx, guess.cy - cy) < 0.5, (name, guess)
        assert guess.r == pytest.approx(r, abs=0.75), (name, guess)
        assert guess.score > 0.8, (name, guess)
        print(f"\n  {name}: {guess.summary()} (scene: {cx:.1f}, {cy:.1f}, {r:.2f})")
    with pytest.raises(ValueError, match="no ball found in 'noise.png'") as info:
        api.detect_photo_ball(hostile_photos(tmp_path)["noise"])
    assert "\n" not in str(info.value)
    assert not bpy.ops.shlight.photo_detect.poll()  # no Image Editor in background mode
