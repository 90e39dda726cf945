"""Compute from World, the button: the world's coefficients stored (``world.compute``), the
lights Extract Lights made deleted (the whole world is in the SH again), and the world's
prefiltered reflection maps, if Apply made them, rewritten from the same read."""

from ..shading import glossy
from ..world import compute
from . import lights


def compute_from_world(scene, capture_width=None, error_normals=0, nonfinite="raise"):
    """Compute from World on ``scene``: ``compute.compute_and_store``, then the extracted
    lights removed and the reflection maps followed. Returns the stored (9, 3) copy and the
    ``WorldInfo``; a ValueError leaves the scene unchanged."""
    reflected = glossy.maps_of(scene.world) is not None  # Apply made the world's maps
    stored, info = compute.compute_and_store(scene, capture_width, error_normals, nonfinite,
                                             keep_radiance=reflected)
    lights.remove_lights(scene)
    if reflected:  # the prefiltered reflections of an applied Keep BSDF follow, same read
        glossy.follow_world(scene, info.radiance)
    return stored, info


def take_lights_back(scene):
    """Remove's part once no material is lit by SH: the lights Extract Lights made deleted and
    the whole world in the SH again (Compute from World; if the world cannot be read now, the
    lights are deleted all the same). Returns the names of the lights deleted ([] when none:
    nothing else changes)."""
    names = [obj.name for obj in lights.extracted_lights(scene)]
    if not names:
        return []
    try:
        compute_from_world(scene)
    except ValueError:
        lights.remove_lights(scene)
    return names
