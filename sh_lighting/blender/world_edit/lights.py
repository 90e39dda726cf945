"""The sources Extract Lights took out of the world, found again so that the edited world no
longer emits them: the Sun lamps replace their part of the world (the sun lit once).

Extract Lights (``design.lights``, ``core.lights``) records in the Reset values' provenance
the lights it made, the size limit and error target; run again on the same image with those it
finds the same sources (the extraction is deterministic). Each source is its texels (a
connected region within the size limit) lowered to min(L, B), B the median around it. The node
group (``nodes``) reproduces that per source as: within the cone around its centre that holds
all its texels (and one texel more: Blender interpolates the image, and the source's rim is
spread over its neighbours), a colour brighter (luminance) than B becomes min(C, B). The
Reset values are those of the map without the sources, so with no edit the world renders as
that map, but for the texels next to a source that are brighter than B (lowered too).
"""

from dataclasses import dataclass
from math import acos, pi

import numpy as np

from ...core import lights as core_lights
from ...core.colour import luminance_weights
from ...core.equirect import texel_directions
from ...core.world_map import to_world_direction
from ..data import compat, scene_data
from ..world import reader

# Records without a size limit were written when every extraction used 24° across.
OLD_SIZE_LIMIT = float(np.radians(24.0))


@dataclass(frozen=True)
class Source:
    """direction: (3,) its centre in world axes; cos_radius: cos of the cone's half-angle;
    threshold: luminance (image units, before Strength) above which a texel is its; background:
    (3,) B, what its texels become."""

    direction: tuple
    cos_radius: float
    threshold: float
    background: tuple


def luminance():
    return luminance_weights(compat.working_space())


def extracted_sources(scene, world):
    """(``Source`` list, the image's map without them or None) of the sources Extract Lights
    took out of ``world`` (none when its Reset values record no lights from it)."""
    record = scene_data.computed_provenance(scene)
    names = record.get("lights") or []
    if not names or record.get("world") != world.name or record.get("method") != "IMAGE":
        return [], None
    source = reader.read_world(scene)
    if not isinstance(source, reader.ImageSource) or source.projection != "EQUIRECTANGULAR":
        return [], None
    pixels = source.pixels()
    size_limit = float(record.get("size_limit", OLD_SIZE_LIMIT))
    weights = luminance()
    extraction = core_lights.extract_lights(pixels, len(names), record.get("error_target"),
                                             max_radius=0.5 * size_limit, luminance=weights)
    height, width = pixels.shape[:2]
    texel = pi / height  # a texel's size: the cone reaches its rim's texels whole
    found = []
    for light in extraction.lights:
        rows, columns = np.nonzero(light.mask)
        directions = texel_directions(height, width, at=(rows, columns))
        centre = np.asarray(light.direction, dtype=np.float64)
        nearest = float(np.clip(np.min(directions @ centre), -1.0, 1.0))
        radius = min(acos(nearest) + texel, pi)
        background = np.asarray(light.background[:3], dtype=np.float64)
        found.append(Source(
            direction=tuple(float(v) for v in to_world_direction(centre, source.rotation)),
            cos_radius=float(np.cos(radius)),
            threshold=float(background @ weights),
            background=tuple(float(v) for v in background),
        ))
    return found, (extraction.rest, source.strength, source.rotation)
