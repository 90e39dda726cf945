"""The SH group fitted to the lighting: only the needed terms, scalar math for grey light, a
clamp only where E < 0, refitting over keyframed ranges, and Apply leaving alone what it
should. Renders are checked per pixel against ``core.irradiance`` as in test_node_group.py.
"""

from math import pi

import bpy
import numpy as np
import pytest
from blender.test_node_group import (
    COEFFS,
    add_camera,
    add_object,
    black_world,
    link_set,
    node_set,
    render,
    setup_render,
)

from sh_lighting.blender import compat, materials, nodes, operators, properties, scene_data
from sh_lighting.core import irradiance, pruning
from sh_lighting.core.irradiance import C4

pytestmark = pytest.mark.blender

# Pixels: float32 shading of E (a few ulps of the largest term) on top of the exact bound.
PIXEL_RTOL = 1e-4


def coefficients(**rows):
    """(9, 3) with the named rows set: coefficients(L00=1, L10=(0.1, 0.2, 0.3))."""
    c = np.zeros((9, 3))
    names = [name.replace("-", "m") for name in pruning.COEFFICIENT_NAMES]
    for key, value in rows.items():
        c[names.index(key)] = value
    return c


def white_material(name="White"):
    material = bpy.data.materials.new(name)
    compat.ensure_node_tree(material).nodes["Principled BSDF"].inputs[
        "Base Color"
    ].default_value = (1.0, 1.0, 1.0, 1.0)
    return material


def fitted_scene(coeffs, size=48, camera=(3.0, -4.0, 2.5)):
    """A sphere whose white material gets the group fitted to ``coeffs`` (set first)."""
    scene = bpy.context.scene
    scene_data.set_coefficients(scene, coeffs)
    material = white_material()
    add_object("sphere", material)
    assert materials.apply_to_materials([material], scene).changed == [material.name]
    add_camera(scene, camera)
    black_world(scene)
    setup_render(scene, size)
    return scene


def spec_of(group):
    return nodes.fit_info(group)["spec"]


def kinds(group):
    return sorted(node.bl_idname for node in group.nodes)


def attributes(group):
    return sorted(n.attribute_name for n in group.nodes if n.bl_idname == "ShaderNodeAttribute")


def check_render(rgb, alpha, normal, coeffs, what, atol=0.0, clamp=False):
    """Every covered pixel within ``atol`` (+ float32 slack) of irradiance(coeffs, n) / π."""
    covered = alpha > 0.999
    assert covered.sum() > 0.25 * alpha.size, f"{what}: object covers too few pixels"
    predicted = irradiance(coeffs, normal[covered]) / pi
    if clamp:
        predicted = np.maximum(predicted, 0.0)
    error = np.abs(rgb[covered] - predicted)
    allowed = atol / pi + PIXEL_RTOL * np.abs(predicted).max()
    print(f"\n{what}: {covered.sum()} pixels, max error {error.max():.3g} (allowed {allowed:.3g})")
    assert error.max() <= allowed, f"{what}: max error {error.max():.3g} > {allowed:.3g}"
    return predicted


# ---------------------------------------------------------------- what the group holds


def test_full_group_without_coefficients_and_with_tolerance_zero():
    scene = bpy.context.scene
    group = nodes.ensure_node_group(scene)  # no coefficients anywhere: the full group
    assert spec_of(group) == nodes.FULL_SPEC and len(group.nodes) == 38
    assert attributes(group) == sorted(scene_data.PROPERTY_NAMES)
    scene_data.set_coefficients(scene, coefficients(L00=1.0))
    assert nodes.refit_node_group(scene).node_count == 7  # fitted: ambient only, scalar


@pytest.mark.parametrize(
    ("rows", "kept", "scalar", "clamp", "count"),
    [
        # Pure ambient: no normal, no band 1 or 2 node at all.
        ({"L00": 2.0}, ("sh_L00",), True, False, 7),
        ({"L00": (2.0, 1.0, 0.5)}, ("sh_L00",), False, False, 7),
        # Ambient and directional (band 1 only): no band 2 node.
        ({"L00": 1.0, "L10": (0.3, 0.2, 0.1)}, ("sh_L00", "sh_L10"), False, False, 16),
        ({"L00": 1.0, "L10": 0.3, "L11": 0.2}, ("sh_L00", "sh_L10", "sh_L11"), True, False, 18),
        # Grey light from below, strong enough for E < 0 on top: scalar and clamped.
        ({"L00": 1.0, "L10": -1.2, "L20": 0.6}, ("sh_L00", "sh_L10", "sh_L20"), True, True, 21),
    ],
)
def test_group_holds_only_what_the_lighting_needs(rows, kept, scalar, clamp, count):
    scene = bpy.context.scene
    scene_data.set_coefficients(scene, coefficients(**rows))
    group = nodes.ensure_node_group(scene)
    spec = spec_of(group)
    assert attributes(group) == sorted(kept)
    assert (spec.scalar, spec.clamp) == (scalar, clamp)
    assert len(group.nodes) == count == nodes.fit_info(group)["nodes"]
    vector_math = [n for n in group.nodes if n.bl_idname == "ShaderNodeVectorMath"]
    clamps = [n for n in group.nodes if getattr(n, "operation", "") == "MAXIMUM"]
    assert len(clamps) == int(clamp)
    if len(kept) == 1:
        assert "ShaderNodeNewGeometry" not in kinds(group)  # no normal needed
    if not {"sh_L20", "sh_L22", "sh_L2m2", "sh_L2m1", "sh_L21"} & set(kept):
        assert not [n for n in vector_math if n.label.startswith(("x²", "xy"))]
    if scalar:  # every term and the clamp are Math nodes, fed by the attributes' Fac output
        labels = ("term", "c4 L00", "max(E, 0)")
        terms = [n for n in group.nodes if n.label.endswith(labels)]
        assert terms and all(n.bl_idname == "ShaderNodeMath" for n in terms)
        for attribute in (n for n in group.nodes if n.bl_idname == "ShaderNodeAttribute"):
            (link,) = attribute.outputs[2].links
            assert not attribute.outputs[1].is_linked


def test_tiny_terms_are_left_out_with_an_exact_bound():
    coeffs = COEFFS.copy()
    coeffs[5] = [2e-4, -1e-4, 1e-4]  # L2-1
    coeffs[8] = [-1e-4, 2e-4, 0.0]  # L22
    scene = bpy.context.scene
    scene_data.set_coefficients(scene, coeffs)
    report = nodes.refit_node_group(scene)
    assert report.group is None  # no group in the file: nothing created
    group = nodes.ensure_node_group(scene)
    info = nodes.fit_info(group)
    # Two Attribute and two term nodes less, and the c1 (x² − y²) factor.
    assert info["omitted"] == ["L2-1", "L22"] and len(group.nodes) == 38 - 5
    exact = pruning.omitted_max_abs(coeffs, (5, 8)).max()
    assert info["bound_absolute"] == pytest.approx(exact)
    assert info["bound"] == pytest.approx(exact / (C4 * coeffs[0].max()))
    assert 0 < info["bound"] < pruning.DEFAULT_RELATIVE_TOLERANCE


# ---------------------------------------------------------------- renders


def test_scalar_clamped_group_renders_max_of_e_and_zero(tmp_path):
    coeffs = coefficients(L00=1.0, L10=-1.2, L20=0.6)
    scene = fitted_scene(coeffs)
    spec = spec_of(nodes.find_node_group())
    assert spec.scalar and spec.clamp
    rgb, alpha, normal = render(scene, tmp_path / "grey.exr")
    predicted = check_render(rgb, alpha, normal, coeffs, "scalar + clamp", clamp=True)
    assert (predicted == 0.0).mean() > 0.05, "the view must show the clamped region"
    assert (predicted > 0.05).mean() > 0.3
    assert np.array_equal(rgb[..., 0], rgb[..., 1]) and np.array_equal(rgb[..., 0], rgb[..., 2])


def test_pruned_rgb_group_renders_within_its_bound(tmp_path):
    coeffs = COEFFS.copy()
    coeffs[5] = [2e-4, -1e-4, 1e-4]
    coeffs[8] = [-1e-4, 2e-4, 0.0]
    scene = fitted_scene(coeffs)
    info = nodes.fit_info(nodes.find_node_group())
    assert info["omitted"] == ["L2-1", "L22"] and not info["spec"].scalar
    rgb, alpha, normal = render(scene, tmp_path / "pruned.exr")
    # Against the full lighting: off by at most the exact bound of what was left out.
    check_render(rgb, alpha, normal, coeffs, "pruned vs full", atol=info["bound_absolute"])


@pytest.mark.slow
def test_eevee_renders_the_scalar_clamped_group(tmp_path):
    coeffs = coefficients(L00=1.0, L10=-1.2, L20=0.6)
    scene = fitted_scene(coeffs, size=48)
    scene.render.engine = compat.eevee_engine_id()
    scene.eevee.taa_render_samples = 1
    scene.render.filter_size = 0.0
    rgb, alpha, normal = render(scene, tmp_path / "eevee.exr")
    covered = alpha > 0.999
    predicted = np.maximum(irradiance(coeffs, normal[covered]) / pi, 0.0)
    assert np.abs(rgb[covered] - predicted).max() < 2e-3 * predicted.max()


# ---------------------------------------------------------------- keyframes


def keyframe_l10(scene, values):
    for frame, value in values.items():
        scene["sh_L10"] = value
        scene.keyframe_insert(data_path='["sh_L10"]', frame=frame)


def test_a_term_animated_from_tiny_to_large_is_kept(tmp_path):
    scene = fitted_scene(coefficients(L00=1.0))
    scene.frame_start, scene.frame_end = 1, 40
    keyframe_l10(scene, {1: [1e-7] * 3, 40: [0.6, 0.5, 0.2]})
    scene.frame_set(1)
    # At frame 1 the value is tiny: the current values alone do not need L10 ...
    assert pruning.fit_terms(scene_data.get_coefficients(scene)).kept == (0,)
    # ... but the animation does.
    report = nodes.refit_node_group(scene)
    assert report.rebuilt and "sh_L10" in attributes(report.group)
    # At every frame of the range, what is left out stays below the tolerance.
    for frame in range(scene.frame_start, scene.frame_end + 1):
        scene.frame_set(frame)
        values = scene_data.get_coefficients(scene)
        tolerance = pruning.DEFAULT_RELATIVE_TOLERANCE * C4 * values[0].max()
        assert _left_out_error(values, report) < tolerance
    scene.frame_set(40)
    rgb, alpha, normal = render(scene, tmp_path / "end.exr")
    check_render(rgb, alpha, normal, scene_data.get_coefficients(scene), "frame 40")


def _left_out_error(values, report):
    omitted = [i for i in range(9) if i not in report.spec.terms]
    return pruning.omitted_max_abs(values, omitted).max() if omitted else 0.0


def test_bezier_overshoot_between_zero_keys_is_seen():
    scene = bpy.context.scene
    scene_data.set_coefficients(scene, coefficients(L00=1.0))
    keyframe_l10(scene, {1: [0.0] * 3, 21: [0.0] * 3})
    for curve in compat.action_fcurves(scene):
        first, last = curve.keyframe_points
        first.handle_right_type = last.handle_left_type = "FREE"
        first.handle_right = (8.0, 3.0)
        last.handle_left = (14.0, 3.0)
        curve.update()
        assert curve.evaluate(1.0) == 0.0 == curve.evaluate(21.0)
        assert curve.evaluate(11.0) > 1.0
    group = nodes.ensure_node_group(scene)
    assert "sh_L10" in attributes(group)
    # A group fitted to the keys alone would have dropped it.
    assert pruning.fit_terms(coefficients(L00=1.0)).kept == (0,)


def test_keyframes_outside_the_frame_range_do_not_count():
    scene = bpy.context.scene
    scene_data.set_coefficients(scene, coefficients(L00=1.0))
    scene.frame_start, scene.frame_end = 1, 10
    keyframe_l10(scene, {20: [0.0] * 3, 30: [0.8] * 3})  # constant 0 before frame 20
    scene.frame_set(1)
    assert attributes(nodes.ensure_node_group(scene)) == ["sh_L00"]
    scene.frame_end = 25  # now the rising part is rendered
    assert "sh_L10" in attributes(nodes.refit_node_group(scene).group)


def test_driven_coefficient_keeps_every_term():
    scene = bpy.context.scene
    scene_data.set_coefficients(scene, coefficients(L00=1.0))
    driver = scene.driver_add('["sh_L10"]', 0).driver
    driver.expression = "0.0"
    group = nodes.ensure_node_group(scene)
    spec = spec_of(group)
    assert spec.terms == pruning.ALL_TERMS and not spec.scalar and spec.clamp


def test_every_scene_of_the_file_is_served():
    scene = bpy.context.scene
    scene_data.set_coefficients(scene, coefficients(L00=1.0))
    other = bpy.data.scenes.new("Other")
    scene_data.set_coefficients(other, coefficients(L00=1.0, L22=(0.5, 0.0, 0.0)))
    group = nodes.ensure_node_group(scene)
    assert attributes(group) == ["sh_L00", "sh_L22"] and not spec_of(group).scalar
    bpy.data.scenes.remove(other)
    assert attributes(nodes.refit_node_group(scene).group) == ["sh_L00"]


# ---------------------------------------------------------------- rebuild only when needed


def test_refit_rebuilds_only_when_the_set_changes_and_repairs_hand_edits():
    scene = bpy.context.scene
    scene_data.set_coefficients(scene, coefficients(L00=1.0, L10=0.3))
    group = nodes.ensure_node_group(scene)
    group.nodes[0]["probe"] = True  # a rebuild would delete this node
    scene_data.set_coefficients(scene, coefficients(L00=2.0, L10=-0.7))  # same set
    report = nodes.refit_node_group(scene)
    assert not report.rebuilt and "probe" in group.nodes[0]
    scene_data.set_coefficients(scene, coefficients(L00=2.0, L10=-0.7, L21=0.2))
    report = nodes.refit_node_group(scene)
    assert report.rebuilt and "sh_L21" in attributes(group)
    assert not any("probe" in node for node in group.nodes)
    attribute = next(n for n in group.nodes if n.bl_idname == "ShaderNodeAttribute")
    attribute.attribute_name = "something_else"  # a hand edit: repaired
    assert nodes.refit_node_group(scene).rebuilt
    assert "something_else" not in attributes(group)
    assert not nodes.refit_node_group(scene).rebuilt


def test_refit_hint_tells_when_the_current_values_need_more():
    scene = bpy.context.scene
    scene_data.set_coefficients(scene, coefficients(L00=1.0, L10=0.3))
    nodes.ensure_node_group(scene)
    assert nodes.refit_hint(scene) is None
    scene["sh_L11"] = [0.2, 0.2, 0.2]  # a raw custom-property drag: no Python runs
    assert "L11" in nodes.refit_hint(scene)
    nodes.refit_node_group(scene)
    assert nodes.refit_hint(scene) is None
    scene["sh_L10"] = [0.3, 0.31, 0.3]  # the scalar group would render this grey
    assert "no longer grey" in nodes.refit_hint(scene)
    nodes.refit_node_group(scene)
    scene["sh_L00"] = [0.1, 0.1, 0.1]  # now E < 0 somewhere, no clamp in the group
    assert "negative" in nodes.refit_hint(scene)
    nodes.refit_node_group(scene)
    assert nodes.refit_hint(scene) is None
    keyframe_l10(scene, {1: [0.3, 0.31, 0.3], 9: [0.3, 0.31, 0.3]})  # same values, new keys
    assert "Keyframes" in nodes.refit_hint(scene)
    nodes.refit_node_group(scene)
    assert nodes.refit_hint(scene) is None


# ---------------------------------------------------------------- operators and settings


def test_coefficient_writes_and_settings_refit_the_group(addon):
    scene = bpy.context.scene
    properties.store_coefficients(scene, coefficients(L00=1.0), computed=True)
    material = white_material()
    add_object("sphere", material)  # selected: Apply's default target
    assert bpy.ops.shlight.apply() == {"FINISHED"}
    group = nodes.find_node_group()
    assert attributes(group) == ["sh_L00"]
    scene.sh_lighting.row_L22 = 0.4  # the row slider: store_coefficients, refit
    assert attributes(group) == ["sh_L00", "sh_L22"]
    assert bpy.ops.shlight.reset() == {"FINISHED"}
    assert attributes(group) == ["sh_L00"]
    scene.sh_lighting.fit_tolerance = 0.0
    assert attributes(group) == sorted(scene_data.PROPERTY_NAMES)
    assert not spec_of(group).clamp
    scene.sh_lighting.clamp_mode = "ALWAYS"
    assert spec_of(group).clamp
    scene.sh_lighting.fit_tolerance = 1e-3
    scene.sh_lighting.clamp_mode = "NEVER"
    assert spec_of(group) == nodes.GroupSpec((0,), True, False)
    scene["sh_L1m1"] = [0.5, 0.5, 0.5]
    result, reports = run_refit()
    assert result == {"FINISHED"}
    [(kind, message)] = reports
    assert "rebuilt" in message and "7 nodes" not in message
    assert attributes(group) == ["sh_L00", "sh_L1m1"]


def run_refit():
    recorded = []

    class Recorder:
        def report(self, kind, message):
            recorded.append((set(kind), message))

    return operators.SHLIGHT_OT_refit.execute(Recorder(), bpy.context), recorded


def test_refit_operator_explains_why_it_is_disabled(addon):
    with pytest.raises(RuntimeError, match="Apply to materials first"):
        bpy.ops.shlight.refit()


# ---------------------------------------------------------------- Apply: only where needed


def surface_of(material, *shader_kinds, volume=None):
    """Replace the material's surface by the sum (Add Shader) of ``shader_kinds``."""
    tree = compat.ensure_node_tree(material)
    output = tree.nodes["Material Output"]
    for link in list(output.inputs["Surface"].links):
        tree.links.remove(link)
    made = [tree.nodes.new(kind) for kind in shader_kinds]
    if len(made) == 1:
        tree.links.new(made[0].outputs[0], output.inputs["Surface"])
    elif made:
        add = tree.nodes.new("ShaderNodeAddShader")
        tree.links.new(made[0].outputs[0], add.inputs[0])
        tree.links.new(made[1].outputs[0], add.inputs[1])
        tree.links.new(add.outputs[0], output.inputs["Surface"])
    if volume:
        node = tree.nodes.new(volume)
        tree.links.new(node.outputs[0], output.inputs["Volume"])
    return material


def test_materials_without_a_diffuse_part_are_skipped_untouched():
    scene = bpy.context.scene
    scene_data.set_coefficients(scene, coefficients(L00=1.0))
    no_diffuse = {
        "emission": surface_of(bpy.data.materials.new("E"), "ShaderNodeEmission"),
        "glass": surface_of(bpy.data.materials.new("G"), "ShaderNodeBsdfGlass"),
        "clear": surface_of(
            bpy.data.materials.new("T"), "ShaderNodeBsdfTransparent", "ShaderNodeBsdfRefraction"
        ),
        "holdout": surface_of(bpy.data.materials.new("H"), "ShaderNodeHoldout"),
        "volume": surface_of(
            bpy.data.materials.new("V"), volume="ShaderNodeVolumePrincipled"
        ),
    }
    metal = bpy.data.materials.new("M")
    compat.ensure_node_tree(metal).nodes["Principled BSDF"].inputs["Metallic"].default_value = 1.0
    no_diffuse["metal"] = metal
    mixed = bpy.data.materials.new("Glass and paint")
    tree = compat.ensure_node_tree(mixed)
    glass = tree.nodes.new("ShaderNodeBsdfGlass")
    mix = tree.nodes.new("ShaderNodeMixShader")
    tree.links.new(glass.outputs[0], mix.inputs[1])
    tree.links.new(tree.nodes["Principled BSDF"].outputs[0], mix.inputs[2])
    tree.links.new(mix.outputs[0], tree.nodes["Material Output"].inputs["Surface"])
    before = {key: (link_set(m), node_set(m)) for key, m in no_diffuse.items()}

    result = materials.apply_to_materials([*no_diffuse.values(), mixed], scene)
    assert result.changed == [mixed.name]
    reasons = dict(result.skipped)
    assert set(reasons) == {m.name for m in no_diffuse.values()}
    for key, material in no_diffuse.items():
        assert "diffuse" in reasons[material.name], reasons[material.name]
        assert (link_set(material), node_set(material)) == before[key], f"{key} was touched"
    assert "volume only" in reasons["V"]
    assert "ShaderNodeBsdfRefraction, ShaderNodeBsdfTransparent" in reasons["T"]


def test_apply_touches_only_the_materials_asked_for():
    scene = bpy.context.scene
    scene_data.set_coefficients(scene, coefficients(L00=1.0, L10=0.3))
    first, second = white_material("First"), white_material("Second")
    materials.apply_to_materials([first], scene)
    group = nodes.find_node_group()
    group.nodes[0]["probe"] = True
    untouched = (link_set(first), node_set(first))
    assert materials.apply_to_materials([second], scene).changed == ["Second"]
    assert (link_set(first), node_set(first)) == untouched
    assert "probe" in group.nodes[0], "the group was rebuilt though the lighting is the same"
