"""Lighting design tools (design.py, design_ui.py, previews.py) in background mode.

Every edit must store exactly what the core computes from the stored coefficients, through
the operator (``bpy.ops``, undoable) and through ``design``. Worlds are small float EXRs:
a constant sky over a constant ground, optionally with a small bright disc (the sun), whose
split can be predicted texel by texel.
"""

import math
from types import SimpleNamespace

import bpy
import numpy as np
import pytest
from blender_files import SCRIPT, WORLD, write_exr
from blender_scenes import (
    EULER, STRENGTH, H, W, add_mapping,
    environment_world, run_execute, sky_map, sunny_map,
)
from numpy.testing import assert_allclose, assert_array_equal

import sh_lighting
from sh_lighting.blender.data import compat, scene_data
from sh_lighting.blender.design import edits as design
from sh_lighting.blender.ui import design as design_ui, lights as lights_ui, panels, previews
from sh_lighting.blender.world.reader import world_coefficients
from sh_lighting.core import edits, windowing
from sh_lighting.core.equirect import texel_solid_angles
from sh_lighting.core.irradiance import irradiance, reference_irradiance
from sh_lighting.core.minimum import irradiance_minimum, mean_irradiance, negative_light_warning
from sh_lighting.core.preview import (
    basis_sphere_images,
    fit_exposure,
    irradiance_sphere_image,
    sphere_normals,
)
from sh_lighting.core.rotation import euler_xyz_matrix
from sh_lighting.core.sh import sh_basis
from sh_lighting.core.sh import spread_normals
from ui_layout import RecordingLayout

pytestmark = pytest.mark.blender

# Signed, L00 > 0, E(n) < 0 somewhere (so every window changes something).
KNOWN = np.array(
    [
        [1.2, 1.0, 0.8],
        [0.3, -0.2, 0.1],
        [0.6, 0.5, 0.7],
        [-0.4, 0.2, 0.3],
        [0.1, -0.3, 0.2],
        [-0.2, 0.1, 0.25],
        [0.3, 0.2, -0.1],
        [0.05, -0.15, 0.1],
        [-0.1, 0.2, 0.3],
    ]
)
# The maps are float32 EXRs read back exactly; what is derived from them is float32 rounding
# away from a float64 prediction; Blender stores light values as float32.
FLOAT32 = 2e-6
# Preview pixels are stored as bytes: core's values to within half a step of 1/255.
BYTE = 0.5 / 255 + 1e-6


# -- worlds ------------------------------------------------------------------------------------




def solid_angles(mask):
    return np.broadcast_to(texel_solid_angles(*mask.shape)[:, None], mask.shape)[mask]


def stored():
    return scene_data.get_coefficients(bpy.context.scene)


# -- edits: operator = design function = core on the stored coefficients -----------------------

# Operator properties are float32: the values here are exact in float32, so the operator and
# the float64 calls compute on the same numbers.
EDITS = [
    ("rotate", {"yaw": 0.75, "pitch": -0.375, "roll": 1.875},
     lambda c: edits.rotate(c, 0.75, -0.375, 1.875),
     lambda s: design.rotate(s, 0.75, -0.375, 1.875)),
    ("exposure", {"stops": -1.5}, lambda c: edits.exposure(c, -1.5),
     lambda s: design.exposure(s, -1.5)),
    ("saturation", {"amount": 0.25}, lambda c: edits.saturation(c, 0.25),
     lambda s: design.saturation(s, 0.25)),
    ("saturation", {"amount": 1.625, "band": "DIRECTIONAL"},
     lambda c: edits.saturation(c, 1.625, (1,)), lambda s: design.saturation(s, 1.625, 1)),
    ("saturation", {"amount": 0.0, "band": "COLOURED"},
     lambda c: edits.saturation(c, 0.0, (1, 2)), lambda s: design.saturation(s, 0.0, (1, 2))),
    ("band_gains", {"ambient": 1.25, "directional": 0.375, "quadratic": 2.0},
     lambda c: edits.band_gains(c, 1.25, 0.375, 2.0),
     lambda s: design.band_gains(s, 1.25, 0.375, 2.0)),
    ("flip_vertical", {}, edits.flip_vertical, design.flip_vertical),
    ("window", {"kind": "HANNING", "width": 2.5},
     lambda c: windowing.apply_window(c, windowing.hanning_window(2.5)),
     lambda s: design.apply_window(s, "HANNING", 2.5).coefficients),
    ("window", {"kind": "LANCZOS"},
     lambda c: windowing.apply_window(c, windowing.lanczos_window(3.0)),
     lambda s: design.apply_window(s, "LANCZOS").coefficients),
    ("window", {"kind": "MINIMAL"},
     lambda c: windowing.minimal_nonnegative_window(c).coefficients,
     lambda s: design.apply_window(s, "MINIMAL").coefficients),
]


@pytest.mark.parametrize(("op", "props", "core", "function"), EDITS,
                         ids=[f"{e[0]}-{i}" for i, e in enumerate(EDITS)])
def test_edit_operator_and_function_store_cores_result_and_undo(addon, op, props, core,
                                                                function):
    scene = bpy.context.scene
    scene_data.store(scene, KNOWN, WORLD)
    expected = core(KNOWN)
    assert np.abs(expected - KNOWN).max() > 1e-3  # the edit changes something
    bpy.ops.ed.undo_push(message="before edit")
    # 'EXEC_DEFAULT', True: push an undo step as a button click does.
    assert getattr(bpy.ops.shlight, op)("EXEC_DEFAULT", True, **props) == {"FINISHED"}
    assert_array_equal(stored(), expected)
    assert_array_equal(scene_data.get_computed(bpy.context.scene), KNOWN)  # not a new Reset

    bpy.ops.ed.undo()
    assert_array_equal(stored(), KNOWN)

    scene = bpy.context.scene  # undo reloads the data
    returned = function(scene)
    assert_array_equal(stored(), expected)
    assert isinstance(returned, np.ndarray)
    assert_array_equal(returned, expected)


OPERATORS = [c for c in design_ui.classes if issubclass(c, bpy.types.Operator)]


@pytest.mark.parametrize("cls", OPERATORS, ids=lambda c: c.__name__)
def test_design_operators_are_undoable_and_described(addon, cls):
    assert {"REGISTER", "UNDO"} <= cls.bl_options
    assert cls.__doc__
    op = getattr(bpy.ops.shlight, cls.bl_idname.split(".")[1])
    assert "UNDO" in op.bl_options
    for prop in op.get_rna_type().properties:
        if prop.identifier != "rna_type":
            assert prop.description, f"{cls.__name__}.{prop.identifier}"


def test_rotate_angles_are_yaw_pitch_roll_in_radians(addon):
    """A light from +X, yawed by 90°, comes from +Y (core.edits' convention, Blender's units)."""
    scene = bpy.context.scene
    from_x = np.repeat(sh_basis(np.array([1.0, 0.0, 0.0]))[:, None], 3, axis=1)
    from_y = np.repeat(sh_basis(np.array([0.0, 1.0, 0.0]))[:, None], 3, axis=1)
    scene_data.store(scene, from_x, SCRIPT)
    bpy.ops.shlight.rotate(yaw=math.pi / 2)
    assert_allclose(stored(), from_y, atol=1e-7)  # π/2 as a float32 property
    rna = bpy.ops.shlight.rotate.get_rna_type().properties["yaw"]
    assert rna.subtype == "ANGLE"  # shown in degrees


@pytest.mark.parametrize(
    "op", ["rotate", "exposure", "saturation", "band_gains", "flip_vertical", "window"]
)
def test_edits_are_disabled_without_coefficients(addon, op):
    with pytest.raises(RuntimeError, match=design_ui.NO_COEFFICIENTS):
        getattr(bpy.ops.shlight, op)()
    assert not scene_data.has_coefficients(bpy.context.scene)


def test_describe_and_warning_read_the_lighting_with_its_gains(addon):
    """The panel's words and warning are of the lighting that renders, L = s·c, not of the
    channels alone: a gain the user dragged changes them."""
    scene = bpy.context.scene
    scene_data.store(scene, KNOWN, SCRIPT)
    scene[scene_data.GAIN_NAMES[2]] = -3.0  # L10 flipped and tripled
    lit = KNOWN.copy()
    lit[2] *= -3.0
    assert design.describe(scene) == edits.describe_coefficients(lit)
    assert design.describe(scene)[2] != edits.describe_coefficients(KNOWN)[2]
    assert design.negative_warning(scene) == negative_light_warning(lit)
    scene_data.store(scene, windowing.minimal_nonnegative_window(KNOWN).coefficients, SCRIPT)
    assert design.negative_warning(scene) is None


# -- Match Mapping -----------------------------------------------------------------------------


def test_match_mapping_equals_computing_with_the_mapping(addon, tmp_path):
    scene = bpy.context.scene
    pixels, _ = sunny_map()
    world = environment_world(scene, write_exr(tmp_path / "w.exr", pixels), STRENGTH)
    assert bpy.ops.shlight.compute_from_world() == {"FINISHED"}
    plain = stored()
    add_mapping(world, EULER)
    with_mapping, info = world_coefficients(scene)
    assert info.source == "image" and info.rotation == pytest.approx(EULER)
    assert np.abs(with_mapping - plain).max() > 0.1 * np.abs(plain).max()  # it does rotate

    bpy.ops.ed.undo_push(message="before match")
    assert bpy.ops.shlight.match_mapping("EXEC_DEFAULT", True) == {"FINISHED"}
    assert_allclose(stored(), with_mapping, rtol=0, atol=1e-12 * np.abs(plain).max())
    bpy.ops.ed.undo()
    assert_array_equal(stored(), plain)
    assert_allclose(design.match_mapping(bpy.context.scene), with_mapping, rtol=0,
                    atol=1e-12 * np.abs(plain).max())


def test_match_mapping_without_a_mapping_node_changes_nothing(addon, tmp_path):
    scene = bpy.context.scene
    environment_world(scene, write_exr(tmp_path / "w.exr", sky_map()))
    scene_data.store(scene, KNOWN, SCRIPT)
    # greyed out with the reason (poll), and the function refuses too
    assert "no rotation to match" in design_ui.mapping_problem(bpy.context)
    with pytest.raises(RuntimeError, match="no rotation to match"):
        bpy.ops.shlight.match_mapping()
    with pytest.raises(design.DesignError, match="no Mapping node"):
        design.match_mapping(scene)
    scene.world = None
    with pytest.raises(RuntimeError, match="has no world"):
        bpy.ops.shlight.match_mapping()
    assert_array_equal(stored(), KNOWN)


# -- windows -----------------------------------------------------------------------------------


def test_minimal_window_makes_a_single_sun_world_non_negative_and_reports_costs(addon, tmp_path):
    scene = bpy.context.scene
    dim = np.full((H, W, 3), 0.002, dtype=np.float32)  # one bright source, almost no sky
    pixels, _ = sunny_map(dim)
    environment_world(scene, write_exr(tmp_path / "w.exr", pixels), STRENGTH, EULER)
    assert bpy.ops.shlight.compute_from_world() == {"FINISHED"}
    before = stored()
    mean = mean_irradiance(before)
    assert (irradiance_minimum(before).value < -0.1 * mean).all()  # rings far below zero

    result, reports = run_execute(design_ui.SHLIGHT_OT_window, kind="MINIMAL", width=3.0)
    assert result == {"FINISHED"}
    minimal = windowing.minimal_nonnegative_window(before)
    assert_array_equal(stored(), minimal.coefficients)
    assert (irradiance_minimum(stored()).bound >= -1e-12 * mean).all()
    assert design.negative_warning(scene) is None

    # the costs of every window, from the world's pixels (rotated, scaled) at the same normals
    normals = spread_normals(design.COST_NORMALS)
    truth = reference_irradiance(pixels, normals @ euler_xyz_matrix(EULER).T) * STRENGTH
    windows = {"HANNING": windowing.hanning_window(3.0), "LANCZOS": windowing.lanczos_window(3.0),
               "MINIMAL": minimal.window}
    costs = {k: windowing.window_cost(before, w, normals, truth) for k, w in windows.items()}

    def percent(mean, largest):
        return f"{100 * mean.max():.2f} / {100 * largest.max():.2f}"

    c = costs["MINIMAL"]
    w = minimal.window
    expected = (
        f"Smoothing 'Just Enough' (Minimal window) applied: directional ×{w[1]:.2f}, "
        f"quadratic ×{w[2]:.2f}; error vs the "
        f"world image {100 * c.windowed_mean.max():.1f} % of its light (without: "
        f"{100 * c.plain_mean.max():.1f} %)"
    )
    [(kind, message)] = reports
    assert kind == {"INFO"}
    assert message == expected
    # the plain 9 terms of one small source: mean error near 3 % of its power (docs/reference.md §2)
    assert 0.02 < c.plain_mean.max() < 0.035

    # edited coefficients are not the world's: no costs, and the report says why
    result = design.apply_window(scene, "HANNING")
    assert result.cost is None and not result.costs
    assert "not the world's" in result.note
    assert result.note in design_ui.window_report(result)


def plain_colour_world(scene):
    scene.world = bpy.data.worlds.new("Plain")
    compat.ensure_node_tree(scene.world)


def test_window_cost_needs_an_image_world(addon):
    scene = bpy.context.scene
    plain_colour_world(scene)
    scene_data.store(scene, KNOWN, SCRIPT)
    result = design.apply_window(scene, "LANCZOS", 2.0)
    assert result.cost is None
    assert "not an equirectangular world image" in result.note
    assert_array_equal(result.window, windowing.lanczos_window(2.0))


# -- previews ----------------------------------------------------------------------------------


def test_previews_hold_cores_images_and_follow_edits(addon, monkeypatch):
    scene = bpy.context.scene
    basis = previews.basis()
    assert len(basis) == 9
    expected = basis_sphere_images(previews.BASIS_SIZE)
    for preview, image in zip(basis, expected, strict=True):
        assert tuple(preview.image_size) == (previews.BASIS_SIZE, previews.BASIS_SIZE)
        assert_allclose(previews.from_preview(preview), premultiplied(image), rtol=0, atol=BYTE)
        assert (previews.from_preview(preview)[0, 0] == 0).all()  # no coloured square

    scene_data.store(scene, KNOWN, SCRIPT)
    scene.view_settings.exposure = -1.0  # the scene's exposure does not expose the sphere
    calls = []
    original = previews.irradiance_sphere_image
    monkeypatch.setattr(previews, "irradiance_sphere_image",
                        lambda *a, **k: calls.append(a) or original(*a, **k))
    panels.draw_main(RecordingLayout(), bpy.context)
    preview = previews.collection()[previews.IRRADIANCE_NAME]
    assert tuple(preview.image_size) == (previews.IRRADIANCE_SIZE, previews.IRRADIANCE_SIZE)
    stops = fit_exposure(KNOWN, previews.IRRADIANCE_SIZE)
    image = irradiance_sphere_image(KNOWN, previews.IRRADIANCE_SIZE, stops, show_negative=True)
    assert_allclose(previews.from_preview(preview), premultiplied(image), rtol=0, atol=BYTE)
    panels.draw_main(RecordingLayout(), bpy.context)
    assert len(calls) == 1  # same coefficients: not recomputed

    bpy.ops.shlight.exposure(stops=2.0)
    panels.draw_main(RecordingLayout(), bpy.context)
    assert len(calls) == 2
    # 4× the light: the same picture, shown 2 stops lower
    assert previews.irradiance(stored())[1] == pytest.approx(stops - 2.0, abs=1e-9)
    assert_allclose(previews.from_preview(preview), premultiplied(image), rtol=0, atol=BYTE)
    assert (previews.from_preview(preview)[0, 0] == 0).all()  # transparent corners: no square


def test_preview_of_a_sunlit_hdri_reads_at_the_default_exposure(addon, hdri_dir):
    """At exposure 0 the sphere of a sun-lit world was a white disc (forest:
    49 % of its pixels white). Now its brightest pixel is white and the rest shade: few
    pixels saturated, and the stored preview's bytes grow with the irradiance."""
    scene = bpy.context.scene
    environment_world(scene, str(hdri_dir / "forest.exr"))
    assert bpy.ops.shlight.compute_from_world() == {"FINISHED"}
    assert scene.view_settings.exposure == 0.0
    panels.draw_main(RecordingLayout(), bpy.context)
    pixels = previews.from_preview(previews.collection()[previews.IRRADIANCE_NAME])
    normals, alpha = sphere_normals(previews.IRRADIANCE_SIZE)
    inside = alpha == 1.0  # whole pixels of the disc (the rim is premultiplied)
    shown = pixels[inside][:, :3]
    assert (shown >= 254.5 / 255).any(axis=1).mean() < 0.01
    assert shown.max() >= 254.5 / 255  # the peak is white
    # monotone: per channel, brighter irradiance never shows darker (beyond a byte's rounding)
    e = irradiance(stored(), normals[inside])
    for channel in range(3):
        order = np.argsort(e[:, channel], kind="stable")
        steps = np.diff(shown[order, channel])
        assert steps.min() >= -1.0 / 255, channel
    assert shown[:, 0].max() - shown[:, 0].min() > 0.5  # it shades over half the range


def test_previews_collection_is_removed_on_unregister_without_leaks():
    open_before = set(bpy.utils.previews._uuid_open)
    for _ in range(20):
        sh_lighting.register()
        pcoll = previews.collection()
        assert len(pcoll) == 9
        sh_lighting.unregister()
        assert len(pcoll) == 0  # cleared by bpy.utils.previews.remove
        with pytest.raises(RuntimeError, match="not registered"):
            previews.collection()
    assert set(bpy.utils.previews._uuid_open) == open_before


# -- the panels --------------------------------------------------------------------------------


def premultiplied(rgba):
    """What an ImagePreview holds of core's straight-alpha image."""
    out = np.array(rgba, dtype=np.float64)
    out[..., :3] *= out[..., 3:]
    return out


def test_design_and_basis_panels_are_under_both_main_panels(addon):
    for name, label in (("design", "Design"), ("basis", "Basis Functions")):
        for where in ("world", "view3d"):
            cls = getattr(bpy.types, f"SHLIGHT_PT_{where}_{name}")
            assert cls.bl_parent_id == f"SHLIGHT_PT_{where}"
            assert cls.bl_label == label
            assert "DEFAULT_CLOSED" in cls.bl_options  # the chart is folded until asked for


def test_basis_panel_draws_the_nine_functions_in_order(addon, monkeypatch):
    basis = tuple(SimpleNamespace(icon_id=101 + k) for k in range(9))
    monkeypatch.setattr(previews, "basis", lambda: basis)
    layout = RecordingLayout()
    design_ui.draw_basis(layout, bpy.context)
    icons = layout.of("icon")
    assert [c[1] for c in icons] == list(range(101, 110))  # in order l(l+1) + m
    assert len({c[2] for c in icons}) == 1  # one size for every row (l = 2 is not smaller)


def test_main_panel_shows_the_sphere_and_one_warning_line(addon, monkeypatch):
    scene = bpy.context.scene
    sphere = SimpleNamespace(icon_id=200)
    drawn = []
    monkeypatch.setattr(previews, "irradiance",
                        lambda coeffs: drawn.append(coeffs) or (sphere, -1.25))
    layout = RecordingLayout()
    panels.draw_main(layout, bpy.context)
    assert not layout.of("icon") and not drawn  # no coefficients: no sphere

    scene_data.store(scene, KNOWN, SCRIPT)  # E < 0 behind its main light
    layout = RecordingLayout()
    panels.draw_main(layout, bpy.context)
    assert [c[1] for c in layout.of("icon")] == [200]
    assert layout.calls[0][0] == "icon"  # the sphere comes first
    assert_array_equal(drawn[0], stored())
    warning = [c for c in layout.of("operator") if c[1] == "shlight.window"]
    assert len(warning) == 1 and warning[0][2].kind == "MINIMAL" and warning[0][3]["alert"]
    tooltip = design_ui.SHLIGHT_OT_window.description(bpy.context, SimpleNamespace(kind="MINIMAL"))
    assert tooltip.startswith(negative_light_warning(KNOWN))

    scene_data.store(scene, windowing.minimal_nonnegative_window(KNOWN).coefficients, SCRIPT)
    layout = RecordingLayout()
    panels.draw_main(layout, bpy.context)
    assert "shlight.window" not in layout.operators()
    # the same one line, no warning: what the sphere shows and how it is exposed
    assert "White ball, auto-exposed (-1.2 EV)" in layout.text()


def test_design_panel_draws_every_design_operator(addon):
    scene_data.store(bpy.context.scene, KNOWN, SCRIPT)
    layout = RecordingLayout()
    design_ui.draw_design(layout, bpy.context)
    ops = [(c[1], dict(vars(c[2]))) for c in layout.of("operator")]
    idnames = {name for name, _ in ops}
    assert idnames == {cls.bl_idname for cls in (*design_ui.classes, *lights_ui.classes)
                       if hasattr(cls, "bl_idname") and cls.bl_idname.startswith("shlight.")}
    assert {p.get("kind") for name, p in ops if name == "shlight.window"} == set(design.WINDOWS)
    for name, props in ops:  # every button's operator and settings exist
        op = getattr(bpy.ops.shlight, name.split(".")[1])
        rna = op.get_rna_type().properties
        for key in props:
            assert key in rna


def test_rotate_and_exposure_are_live_popups_with_redo(addon):
    for op in ("rotate", "exposure", "saturation", "band_gains"):
        cls = getattr(design_ui, f"SHLIGHT_OT_{op}")
        assert issubclass(cls, design_ui._Live)
        assert {"REGISTER", "UNDO"} <= cls.bl_options  # redo panel and F9
    assert bpy.ops.shlight.exposure.get_rna_type().properties["stops"].default == 0.0
