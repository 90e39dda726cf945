"""SH Lighting: irradiance environment maps with spherical harmonics for Blender.

The math lives in ``sh_lighting.core`` (numpy only, importable without Blender); the Blender
layer in ``sh_lighting.blender`` is imported only when Blender registers the add-on.
"""


def register():
    from . import blender

    blender.register()


def unregister():
    from . import blender

    blender.unregister()
