"""Ids shared by the Blender layer and the command line, importable without bpy or numpy
(the command line's ``--help`` lists them before Blender is loaded).

``blender.presets.files`` and ``blender.shading.materials`` take theirs from here.
"""

# export format id -> (label, file extension)
FORMATS = {
    "sh_lighting": ("SH Lighting preset", ".json"),
    "threejs": ("three.js LightProbe JSON", ".json"),
    "gltf": ("glTF environment (EXT_lights_image_based)", ".gltf"),
    "filament": ("Filament sh.txt", ".txt"),
}
# Filament frame id -> what it lines up with (formats.interop); the first is the default
FILAMENT_FRAMES = {
    "cmgen": "cmgen's own output (its specular KTX) for the same equirect image",
    "gltf": "a glTF export of the Blender scene",
}
# How Apply drives a material (blender.shading.materials); the first is the default
APPLY_MODES = ("KEEP_BSDF", "EMISSION")
# What lights the unseen side of a grey ball in Match Photo (core.photo.PRIORS); the first
# is the default
PHOTO_PRIORS = ("mirror", "ambient", "none")
