"""Issue 21: the reflection maps Keep BSDF gives EEVEE, their lookup checked by rendering the
nodes EEVEE renders with Cycles (no EEVEE shader compile; the same node math) against Cycles
path tracing of the world.

A lone glossy sphere (metallic 0.8, roughness 0.5) under sunrise.exr, whose low sun makes a
small highlight: where the split sum looks the maps up decides where it lands. The sphere's
EEVEE Material Output is made Cycles' (the world hidden from glossy rays, so only the maps
reflect it) and its render compared with path tracing of the original world.
"""

import bpy
import numpy as np

from benchmarks.shadow_scene import ShadowScene, covered, principled_material
from sh_lighting import api
from sh_lighting.blender.shading import glossy, materials

SIZE = 32


def _glossy_error(s, material):
    """Relative RMSE over the sphere of its EEVEE output rendered by Cycles after Keep BSDF;
    everything put back (targets, the world's glossy visibility, Remove) after."""
    materials.apply_to_materials([material], s.scene, "KEEP_BSDF")
    assert not any(image.use_half_precision for image in glossy.maps_of(s.world))
    swap = {"EEVEE": "CYCLES", "ALL": "EEVEE"}
    outputs = [n for n in material.node_tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial"]
    saved = [n.target for n in outputs]
    for node in outputs:
        node.target = swap[node.target]
    s.world.cycles_visibility.glossy = False
    image = s.render(4)[1]
    s.world.cycles_visibility.glossy = True
    for node, target in zip(outputs, saved):
        node.target = target
    materials.remove_from_materials([material])
    a, b = image[s.mask][:, :3].astype(np.float64), s.reference[s.mask][:, :3]
    return float(np.sqrt(np.mean((a - b) ** 2)) / b.mean())


def test_maps_looked_up_toward_the_lobes_dominant_direction(addon, hdri_dir, tmp_path,
                                                          monkeypatch):
    """At the mirror direction R (the code before) the highlight lands too far toward the rim;
    at the dominant direction (core.glossy.dominant_factor) nearer. Measured, relative RMSE:
    5.0 20.7 % at R, 19.7 % leaned; 4.2 20.9 %, 20.5 % (the rest is the split sum's lobe:
    too peaked, its tails short at grazing view; in the real-scene benchmark's sphere,
    22.8 % → 20.4 %). The maps are full float (no half-float clipping of a sun)."""
    s = ShadowScene(hdri_dir / "sunrise.exr", SIZE, tmp_path)
    bpy.data.objects.remove(s.plane)
    material = principled_material("Glossy", Metallic=0.8, Roughness=0.5)
    s.sphere.data.materials[0] = material
    api.compute_from_world(s.scene)
    _, s.reference = s.render(256)
    s.mask = covered(s.reference)
    leaned = _glossy_error(s, material)
    with monkeypatch.context() as patch:
        patch.setattr(glossy, "_dominant", lambda b, reflected, normal, roughness: reflected)
        mirror = _glossy_error(s, material)
    print(f"\nglossy sphere, the maps' nodes in Cycles: at R {mirror:.4f}, leaned {leaned:.4f}")
    assert leaned < mirror - 0.002 and leaned < 0.21
