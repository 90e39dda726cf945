"""Extract Lights' default: as many lights as the world needs (an error target), not a fixed
count; one sun makes one Sun lamp, not three overlapping shadows.

Measured on Blender's eight bundled HDRIs (mean error of SH + lights against the world's
irradiance, % of its light, after 0, 1, 2, ... lights): city 0.98, 0.31; courtyard 0.99, 0.99
(a soft 10° source, then one wider than the size limit); forest 0.79, 0.59, 0.43; interior 0.72,
0.47; night 0.82, 0.59, 0.34; studio 2.05, 1.36, 1.24, 0.36, ...; sunrise 2.2, 0.40, 0.34;
sunset 0.53, 0.36. The default target, 0.5 %, stops sunrise after its sun (the next light
would take 0.06 points off) and gives the counts below.
"""

import bpy
import pytest
from blender_scenes import environment_world

from sh_lighting.blender.design import lights

COUNTS = {"city": 1, "courtyard": 1, "forest": 2, "interior": 1, "night": 2, "studio": 3,
          "sunrise": 1, "sunset": 1}
if bpy.app.version < (5, 0, 0):
    # Blender 4.2 ships other images under the same names: its interior's brightest source
    # lowers no error (test_sun_split), its studio and sunrise need one light more
    COUNTS |= {"interior": 0, "studio": 4, "sunrise": 2}


@pytest.mark.parametrize("name", sorted(COUNTS))
def test_default_extract_lights_makes_the_lights_the_world_needs(addon, hdri_dir, name):
    scene = bpy.context.scene
    environment_world(scene, str(hdri_dir / f"{name}.exr"))
    assert bpy.ops.shlight.compute_from_world() == {"FINISHED"}
    assert bpy.ops.shlight.extract_lights() == {"FINISHED"}
    made = lights.extracted_lights(scene)
    print(f"\n{name}: {len(made)} light(s) {[round(o.data.energy, 2) for o in made]}")
    assert len(made) == COUNTS[name]
