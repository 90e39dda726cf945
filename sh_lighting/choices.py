"""Ids shared by the Blender layer and the command line, importable without bpy or numpy
(the command line's ``--help`` lists them before Blender is loaded).

``blender.presets.preset_io`` and ``blender.shading.materials`` take theirs from here.
"""

from typing import NamedTuple


class Format(NamedTuple):
    """An export format: its label, file extension, the ending of its default file name
    (after the .blend's name; each format its own, so that exporting one never proposes the
    file of another) and what it holds (the Export operator's tooltips)."""

    label: str
    extension: str
    default_suffix: str
    description: str


# export format id -> Format: the one table of the formats (CLI, API, Export operator)
FORMATS = {
    "sh_lighting": Format(
        "SH Lighting preset", ".json", "_sh_preset",
        "SH Lighting preset: raw L_lm in Blender axes, with metadata (Import reads it)"),
    "threejs": Format(
        "three.js LightProbe JSON", ".json", "_threejs_lightprobe",
        "A LightProbe for three.js (ObjectLoader JSON): radiance L_lm, y-up glTF axes"),
    "gltf": Format(
        "glTF environment (EXT_lights_image_based)", ".gltf", "_environment",
        "A .gltf environment for Babylon.js: irradiance coefficients and a specular cube "
        "prefiltered from the world image, y-up glTF axes"),
    "filament": Format(
        "Filament sh.txt", ".txt", "_sh",
        "cmgen-style sh.txt for Filament: shader-ready pre-scaled irradiance"),
}
# Filament frame id -> what it lines up with (formats.interop); the first is the default
FILAMENT_FRAMES = {
    "cmgen": "cmgen's own output (its specular KTX) for the same equirect image",
    "gltf": "a glTF export of the Blender scene",
}
# What Apply does (blender.ui.operators); the first is the default: "AUTO" resolves per render
# engine at Apply time (``resolve_mode``): Edit World in Cycles, Keep BSDF with Shadows in EEVEE
# (measured: benchmarks/bench_eevee_default.py and bench_texel.py; the transfer is EEVEE's most
# accurate on every HDRI measured, its own world lighting the least on two of three)
APPLY_MODES = ("AUTO", "WORLD", "TRANSFER", "KEEP_BSDF", "EMISSION")
# The number a .blend file stores for each mode (the settings' enum): never renumbered
APPLY_MODE_VALUES = {"AUTO": 0, "WORLD": 1, "KEEP_BSDF": 2, "EMISSION": 3, "TRANSFER": 4}
# The modes that change materials (blender.shading.materials; the command line's --mode)
MATERIAL_MODES = ("KEEP_BSDF", "EMISSION")
# (id, name, description) of each Apply mode, for the Mode menus
APPLY_MODE_ITEMS = (
    ("AUTO", "Default",
     "Edit World in Cycles (path-traced shadows, bounces and reflections of the edited "
     "world), Keep BSDF with Shadows in EEVEE (the bake started when it takes seconds)"),
    ("WORLD", "Edit World",
     "Add the designed change to the world itself; the materials stay as they are (Cycles: "
     "every shadow, bounce and reflection)"),
    ("TRANSFER", "Keep BSDF with Shadows",
     "Bake the transfer (the scene's shadows and bounce light, by Cycles) where it is missing "
     "or stale, then Keep BSDF with it (EEVEE's contact shadows)"),
    ("KEEP_BSDF", "Keep BSDF",
     "Keep the material's BSDF (lamps, shadows, reflections); SH replaces the world's diffuse "
     "light (Cycles)"),
    ("EMISSION", "Emission Only",
     "Drive the surface by the SH emission alone: exact and noise free, no lamps or "
     "reflections"),
)
# What "AUTO" is in each render engine (any other engine: Keep BSDF)
AUTO_MODES = {"CYCLES": "WORLD", "BLENDER_EEVEE": "TRANSFER", "BLENDER_EEVEE_NEXT": "TRANSFER"}


def resolve_mode(mode, engine):
    """The mode Apply uses for ``mode`` in render engine ``engine`` ("AUTO" resolved)."""
    return AUTO_MODES.get(engine, "KEEP_BSDF") if mode == "AUTO" else mode


# What lights the unseen side of a grey ball in Match Photo (core.photo.PRIORS); the first
# is the default
PHOTO_PRIORS = ("mirror", "ambient", "chrome", "photo", "none")
