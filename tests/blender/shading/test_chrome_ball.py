"""A fully metallic Principled BSDF (a chrome ball) under the default Apply (Keep BSDF).

It has no diffuse base, so it gets no SH diffuse term; but Keep BSDF hides the world from
EEVEE's lighting, so it must still get the world's reflections back from the prefiltered maps
(shading/glossy.py), else it renders black in EEVEE. Checked as tests/blender/shading/
test_glossy_lookup.py does: the nodes EEVEE renders are rendered by Cycles (its glossy rays
kept from the world, so only the maps reflect it) against Cycles path tracing of the world;
and once in EEVEE itself.
"""

import bpy
import numpy as np
import pytest

from benchmarks.shadow_scene import ShadowScene, covered, principled_material
from sh_lighting import api
from sh_lighting.blender.data import compat
from sh_lighting.blender.shading import glossy, materials

SIZE = 32


@pytest.fixture
def chrome(addon, hdri_dir, tmp_path):
    s = ShadowScene(hdri_dir / "sunrise.exr", SIZE, tmp_path)
    bpy.data.objects.remove(s.plane)
    s.material = principled_material("Chrome", Metallic=1.0, Roughness=0.15)
    s.sphere.data.materials[0] = s.material
    s.sphere.select_set(True)
    bpy.context.view_layer.objects.active = s.sphere
    api.compute_from_world(s.scene)
    _, s.reference = s.render(128)
    s.mask = covered(s.reference)
    return s


def _compare(s, image):
    """(mean |error|, brightness) over the ball, relative, both images clipped at 1 (the
    sun's highlight, a few pixels, is thousands bright and its noise would rule the mean)."""
    a = np.minimum(image[s.mask][:, :3].astype(np.float64), 1.0)
    b = np.minimum(s.reference[s.mask][:, :3], 1.0)
    return float(np.abs(a - b).mean() / b.mean()), float(a.mean() / b.mean())


def test_chrome_ball_keeps_the_worlds_reflections_in_eevees_nodes(chrome):
    """Applied (not skipped), with no SH diffuse (black albedo) and the maps' reflection in
    its EEVEE output; those nodes rendered by Cycles within 15 % in mean and in mean |error|
    of path tracing (measured 1.058, 8.3 %; skipped, the code before: black). Remove
    restores it exactly and deletes the maps."""
    s = chrome
    before = {(link.from_node.name, link.to_node.name) for link in s.material.node_tree.links}
    changed, skipped = materials.apply_to_materials([s.material], s.scene, "KEEP_BSDF")
    assert changed == [s.material.name] and not skipped
    (group,) = materials.added_nodes(s.material)
    assert not group.inputs["Albedo"].is_linked
    assert tuple(group.inputs["Albedo"].default_value)[:3] == (0.0, 0.0, 0.0)
    tree = s.material.node_tree
    outputs = [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial"]
    assert {n.target for n in outputs} == {"ALL", "EEVEE"}
    swap = {"EEVEE": "CYCLES", "ALL": "EEVEE"}
    for node in outputs:
        node.target = swap[node.target]
    s.world.cycles_visibility.glossy = False
    _, image = s.render(4)
    s.world.cycles_visibility.glossy = True
    for node in outputs:
        node.target = {"CYCLES": "EEVEE", "EEVEE": "ALL"}[node.target]
    error, ratio = _compare(s, image)
    print(f"\nchrome ball, EEVEE's nodes in Cycles: mean |error| {error:.4f}, "
          f"brightness {ratio:.4f}")
    assert abs(ratio - 1) < 0.15 and error < 0.15
    assert materials.remove_from_materials([s.material]).changed == [s.material.name]
    assert {(link.from_node.name, link.to_node.name) for link in tree.links} == before
    assert not [i.name for i in bpy.data.images if glossy.IMAGE_MARKER in i]


def test_chrome_ball_in_emission_only_is_still_skipped(chrome):
    """Emission Only renders the SH diffuse term alone: a metal has none, so it is left
    alone with the reason."""
    changed, skipped = materials.apply_to_materials([chrome.material], chrome.scene, "EMISSION")
    assert not changed and "no diffuse base colour" in skipped[0][1]


@pytest.mark.slow
def test_chrome_ball_is_not_black_in_eevee(chrome):
    """One tiny EEVEE render after the default Apply: the ball reflects the world (measured:
    brightness 1.057, mean |error| 8.2 % of path tracing; skipped, it rendered black)."""
    s = chrome
    s.scene.eevee.taa_render_samples = 1
    assert bpy.ops.shlight.apply() == {"FINISHED"}
    s.scene.render.engine = compat.eevee_engine_id()
    _, image = s.render()
    error, ratio = _compare(s, image)
    print(f"\nchrome ball, EEVEE: mean |error| {error:.4f}, brightness {ratio:.4f}")
    assert abs(ratio - 1) < 0.15 and error < 0.15
