"""A measured luminaire (IES or EULUMDAT file) as Blender lights: exact in Cycles, fitted in EEVEE.

One object, the luminaire, is a point light the user moves and aims like a lamp (it shines
down its local −Z). Cycles renders it exactly: its node tree is Blender's own IES Texture node
(the file's text, packed as a Text datablock, converted to IES text for EULUMDAT and type B)
into the Emission Strength. EEVEE has no light node trees; its children, a few native spot
and point lights fitted to the candela table (``core.lamp_fit``, Granier et al. 2003), give
EEVEE the distribution and its shadow maps the shadows.

Which set renders follows the engine with switches each engine honours and the other ignores
(measured on 5.0, docs/blender.md): the luminaire's Diffuse/Specular/Volume/Transmission
factors are 0, which EEVEE obeys and Cycles ignores; the fitted lamps' node trees emit with
Strength 0, which Cycles obeys and EEVEE ignores. The lamps' power and colour are driven by the
luminaire's (simple-expression drivers, no scripts), so one Power and one Color set both;
so is Blender's Light Temperature where Blender has it (5.0), and ``set_colour_temperature``
sets either it or, before 5.0, the colour to the blackbody's (``core.blackbody``).

Near field (``core.near_field``): a surface closer than about 5 × the luminous opening
(``FitSettings.near_distance``, the distance to the nearest lit surface) sees its extent, not
a point. The opening is then cut into cells (at most 4 × 4) and each cell gets a copy of the
fitted EEVEE set at its centre, each lamp's power divided by the number of cells, its soft
shadow radius half the cell's size; Cycles gets one point light per cell with the same IES
node (the luminaire's own IES link is cut, so that its light is the cells'). Every copy is
driven by the luminaire's power and colour and listed in ``REGISTRY``.

The luminaire's nine (``luminaire_sh_at``): seen from a point p, it is a source of irradiance
E₀ = I(−s)/r² from the direction s toward it (r its distance, I in W/sr: the candela × the
power / 177.83, times its colour), whose radiance terms are L_lm = E₀ Y_lm(s), Blender world
axes: what it adds to the scene's nine at p (E(n) = Σ Â_l L_lm Y_lm(n), Ramamoorthi and
Hanrahan 2001).

Power: Blender's IES node gives v cd as Strength v·4π/177.83 (D65's 177.83 lm/W), so the
luminaire at 1 W renders the file's absolute candela; a fitted lamp of on-axis intensity c cd
has power 4π c / 177.83 × the luminaire's power.

Identity: the scene's ``REGISTRY`` property points at what each luminaire made (the light,
the lamps, the text); a duplicate (Shift+D) is not pointed to and is never changed or deleted.
"""

import math
from dataclasses import dataclass
from pathlib import Path

import bpy
import numpy as np
from mathutils import Vector

from ...core.blackbody import blackbody_rgb
from ...core.lamp_fit import (
    fit_lamps,
    lamp_intensity,
    plane_illuminance_error,
    sphere_samples,
    wall_illuminance_error,
)
from ...core.near_field import near_field_cells
from ...core.polar_plot import polar_curves
from ...core.sh import sh_basis
from ...formats.ies import parse_ies
from ...formats.photometric_file import read_with_ies_text
from ...formats.photometry import PhotometryError
from . import lights

__all__ = (
    "FitSettings",
    "LuminaireInfo",
    "PhotometryError",
    "add_luminaire",
    "cycles_cells_of",
    "ies_text_of",
    "is_luminaire",
    "lamps_of",
    "luminaire_of",
    "luminaire_sh",
    "luminaire_sh_at",
    "refit",
    "remove_luminaire",
    "set_colour_temperature",
)

REGISTRY = "sh_lighting_luminaires"  # scene property: {key: {"root", "lamps", "text", "cycles"}}
INFO = "sh_luminaire"  # the luminaire light's read-only summary (a custom property)
LUMENS_PER_WATT = lights.LUMENS_PER_WATT
FACTORS = lights.FACTORS


@dataclass(frozen=True)
class FitSettings:
    """How the EEVEE lamps are fitted and checked."""

    error_target: float = 0.03  # relative RMSE of I over the sphere that ends the search
    max_lamps: int = 8
    check_distance: float = 2.0  # metres: the floor and walls whose illuminance errors are reported
    near_distance: float = 0.0  # metres to the nearest lit surface; 0: far field (one set)


@dataclass(frozen=True)
class LuminaireInfo:
    root: object
    lamps: tuple
    intensity_error: float
    plane_error: float  # the floor's (a plane below at the check distance)
    wall_error: float  # the worst wall's (at the check distance)
    flux_lm: float
    cycles_cells: tuple = ()  # the near field's Cycles lights (none in the far field)

    def report(self):
        cells = f" over {len(self.cycles_cells)} near-field cells" if self.cycles_cells else ""
        return (f"Measured luminaire '{self.root.name}': {self.flux_lm:.0f} lm, "
                f"{len(self.lamps)} EEVEE lamp(s){cells}, "
                f"intensity error {100 * self.intensity_error:.1f} %, "
                f"illuminance error {100 * self.plane_error:.1f} % on the floor, "
                f"{100 * self.wall_error:.1f} % on the walls")


def add_luminaire(scene, path, collection=None, location=(0.0, 0.0, 3.0),
                  rotation=(0.0, 0.0, 0.0), settings=FitSettings(), power=1.0):
    """Read ``path`` and make the luminaire; nothing is created if the file is bad.

    Raises ``formats.photometry.PhotometryError`` (one line naming the file's line, a
    ValueError) or ValueError.
    """
    path = Path(path)
    table, text = read_with_ies_text(path)
    fit, plane = _fit(table, settings)
    cells = near_field_cells(table.opening_m, settings.near_distance)
    collection = collection or scene.collection
    name = path.stem
    ies_text = bpy.data.texts.new(f"{name}.ies")
    ies_text.from_string(text)
    data = bpy.data.lights.new(name, type="POINT")
    data.energy = power
    data.shadow_soft_size = _radius(table)
    for factor in FACTORS:
        if hasattr(data, factor):
            setattr(data, factor, 0.0)
    lights.ies_nodes(data, ies_text)
    root = bpy.data.objects.new(name, data)
    root.location = location
    root.rotation_euler = rotation
    collection.objects.link(root)
    lamps, cycles = lights.make_all(root, collection, fit.lamps, cells, ies_text,
                                    data.shadow_soft_size)
    _store_info(root, table, fit, plane, settings, path.name, cells)
    registry = dict(_registry(scene))
    key = str(1 + max((int(k) for k in registry), default=0))
    registry[key] = {"root": root, "lamps": list(lamps), "text": ies_text, "cycles": list(cycles)}
    scene[REGISTRY] = registry
    return LuminaireInfo(root, tuple(lamps), fit.intensity_error, *plane, table.flux_lm,
                         tuple(cycles))


def refit(scene, root, settings=FitSettings()):
    """Fit the EEVEE lamps of the luminaire ``root`` again (other target, count or distance)."""
    entry = _entry(scene, root)
    if entry is None:
        raise ValueError(f"'{root.name}' is not a measured luminaire this add-on made")
    table = parse_ies(entry["text"].as_string(), entry["text"].name)
    fit, plane = _fit(table, settings)
    cells = near_field_cells(table.opening_m, settings.near_distance)
    lights.delete_lights(entry["lamps"])
    lights.delete_lights(entry.get("cycles", []))
    collection = root.users_collection[0] if root.users_collection else scene.collection
    lamps, cycles = lights.make_all(root, collection, fit.lamps, cells, entry["text"],
                              root.data.shadow_soft_size)
    _store_info(root, table, fit, plane, settings, root.data[INFO]["source"], cells)
    entry["lamps"] = list(lamps)
    entry["cycles"] = list(cycles)
    return LuminaireInfo(root, tuple(lamps), fit.intensity_error, *plane, table.flux_lm,
                         tuple(cycles))


def lit_distance(scene, root, depsgraph=None, reach=1000.0):
    """Metres from the luminaire ``root`` along its axis (local −Z) to the first surface of
    ``scene`` a ray meets (its evaluated geometry), or None within ``reach``: the distance the
    near field's five-times rule is read at."""
    depsgraph = depsgraph or bpy.context.evaluated_depsgraph_get()
    matrix = root.matrix_world
    origin = matrix.translation
    axis = (matrix.to_3x3() @ Vector((0.0, 0.0, -1.0))).normalized()
    hit, location, *_ = scene.ray_cast(depsgraph, origin, axis, distance=reach)
    return (location - origin).length if hit else None


def settings_of(root):
    """The ``FitSettings`` the luminaire ``root`` was last fitted with."""
    info = root.data.get(INFO, {})
    return FitSettings(info.get("error_target", 0.03), info.get("max_lamps", 8),
                       info.get("check_distance", 2.0), info.get("near_distance", 0.0))


def remove_luminaire(scene, root):
    """Delete the luminaire ``root`` made by the add-on: its lamps, light data and text."""
    key = _key(scene, root)
    if key is None:
        raise ValueError(f"'{root.name}' is not a measured luminaire this add-on made")
    entry = scene[REGISTRY][key]
    lights.delete_lights(entry["lamps"])
    lights.delete_lights(entry.get("cycles", []))
    text = entry["text"]
    data = root.data
    bpy.data.objects.remove(root)
    if data is not None and data.users == 0:
        bpy.data.lights.remove(data)
    if text is not None and not _text_in_use(text):
        bpy.data.texts.remove(text)
    del scene[REGISTRY][key]
    if not scene[REGISTRY].keys():
        del scene[REGISTRY]


def _text_in_use(text):
    """Whether any light's IES node (a copy the user made, say) still reads ``text``."""
    return any(node.type == "TEX_IES" and node.ies == text
               for light in bpy.data.lights if light.node_tree is not None
               for node in light.node_tree.nodes)


def is_luminaire(scene, obj):
    """Whether ``obj`` is a luminaire the add-on made in ``scene`` (a duplicate is not)."""
    return obj is not None and _key(scene, obj) is not None


def luminaire_of(scene, obj):
    """The luminaire ``obj`` is (or is a fitted lamp of), or None."""
    for entry in _registry(scene).values():
        if entry.get("root") is not None and (entry["root"] == obj or obj in entry["lamps"]
                                              or obj in entry.get("cycles", [])):
            return entry["root"]
    return None


def lamps_of(scene, root):
    """The luminaire's EEVEE lamps (every near-field cell's copy)."""
    entry = _entry(scene, root)
    return [lamp for lamp in entry["lamps"] if lamp is not None] if entry else []


def ies_text_of(scene, root):
    """The luminaire's packed IES text (the Text every IES node of it reads), or None."""
    entry = _entry(scene, root)
    return entry["text"] if entry else None


def cycles_cells_of(scene, root):
    """The luminaire's near-field Cycles lights (none in the far field)."""
    entry = _entry(scene, root)
    return [light for light in entry.get("cycles", []) if light is not None] if entry else []


def _registry(scene):
    value = scene.get(REGISTRY)
    return value if hasattr(value, "to_dict") else {}


def _key(scene, obj):
    for key, entry in _registry(scene).items():
        if entry.get("root") == obj:
            return key
    return None


def _entry(scene, obj):
    key = _key(scene, obj)
    return None if key is None else scene[REGISTRY][key]


def _fit(table, settings):
    if not 1 <= settings.max_lamps <= 8:
        raise ValueError(f"lamps: {settings.max_lamps} (from 1 to 8)")
    if not (math.isfinite(settings.near_distance) and settings.near_distance >= 0):
        raise ValueError(f"near field distance: {settings.near_distance!r} (0 or more metres)")
    fit = fit_lamps(table.intensity_cubic, settings.max_lamps, settings.error_target,
                    room=settings.check_distance)
    plane = (plane_illuminance_error(table.intensity_cubic, fit.lamps, settings.check_distance),
             wall_illuminance_error(table.intensity_cubic, fit.lamps, settings.check_distance))
    return fit, plane


def _radius(table):
    """Half the luminous opening's largest side (a circle's radius), at most 0.25 m."""
    length, width, _ = table.opening_m
    return float(min(0.5 * max(abs(length), abs(width)), 0.25))


TEMPERATURE_RANGE = (800.0, 20000.0)  # kelvin, Blender's Light Temperature's range


def set_colour_temperature(root, kelvin):
    """The luminaire's colour: a blackbody at ``kelvin``, in both engines (see above)."""
    low, high = TEMPERATURE_RANGE
    if not isinstance(kelvin, (int, float)) or not low <= kelvin <= high:
        raise ValueError(f"colour temperature {kelvin!r} K: from {low:.0f} to {high:.0f} K")
    data = root.data
    if hasattr(data, "temperature"):
        data.use_temperature = True
        data.temperature = float(kelvin)
    else:
        data.color = tuple(float(v) for v in blackbody_rgb(kelvin))


def light_colour(data):
    """The RGB a light emits per unit power: its colour × its temperature's where it has one."""
    colour = np.array(data.color, dtype=np.float64)
    if getattr(data, "use_temperature", False):
        colour = colour * blackbody_rgb(data.temperature)
    return colour


def luminaire_sh_at(scene, root, point):
    """The nine (9, 3) the luminaire ``root`` adds at ``point`` (world), see above; zeros
    where it is at the point itself."""
    entry = _entry(scene, root)
    if entry is None:
        raise ValueError(f"'{root.name}' is not a measured luminaire this add-on made")
    table = parse_ies(entry["text"].as_string(), entry["text"].name)
    world = root.matrix_world
    to_point = Vector(point) - world.translation
    r = to_point.length
    if r < 1e-6:
        return np.zeros((9, 3))
    local = world.to_3x3().normalized().inverted() @ (to_point / r)
    watts_per_sr = float(table.intensity_cubic(np.array([tuple(local)]))[0]) * root.data.energy
    e0 = watts_per_sr / LUMENS_PER_WATT / (r * r)
    toward = -np.array(to_point / r)
    return e0 * np.outer(sh_basis(toward[None, :], 2)[0], light_colour(root.data))


def luminaire_sh(table, n_theta=90, n_phi=180):
    """The nine L_lm = ∫ I(ω) Y_lm(ω) dω of the intensity in the light's own axes (cd·sr)."""
    dirs, weights = sphere_samples(n_theta, n_phi)
    return (weights * table.intensity_cubic(dirs)) @ sh_basis(dirs, 2)


def _store_info(root, table, fit, plane, settings, source, cells):
    root.data[INFO] = {
        "near_distance": settings.near_distance,
        "cells": list(cells.counts),
        "opening_m": [float(v) for v in table.opening_m],
        "source": source,
        "flux_lm": table.flux_lm,
        "peak_cd": table.peak_cd,
        "lamps": len(fit.lamps),
        "intensity_error": fit.intensity_error,
        "plane_error": plane[0],
        "wall_error": plane[1],
        "check_distance": settings.check_distance,
        "error_target": settings.error_target,
        "max_lamps": settings.max_lamps,
        "sh": [float(v) for v in luminaire_sh(table)],
        # the polar diagram's curves (core.polar_plot), the file's and the fitted lamps'
        "polar_file": [float(v) for v in polar_curves(table.intensity_cubic).ravel()],
        "polar_fit": [float(v) for v in polar_curves(
            lambda dirs: lamp_intensity(fit.lamps, dirs)).ravel()],
    }


def polar_of(root):
    """(the file's, the fit's) polar curves (2, 2, 181) stored with the luminaire, or None."""
    info = root.data.get(INFO, {})
    if "polar_file" not in info or "polar_fit" not in info:
        return None
    shape = (2, 2, -1)
    return (np.array(info["polar_file"], dtype=np.float64).reshape(shape),
            np.array(info["polar_fit"], dtype=np.float64).reshape(shape))

