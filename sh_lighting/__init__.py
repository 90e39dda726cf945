"""SH Lighting: irradiance environment maps with spherical harmonics for Blender.

The math lives in ``sh_lighting.core`` (numpy only, importable without Blender); the Blender
layer in ``sh_lighting.blender`` is imported only when Blender registers the add-on, and the
command line ``blender -c sh_lighting`` (``cli.command``) is registered beside it.
"""


def register():
    from . import blender
    from .cli import command

    blender.register()
    command.register()


def unregister():
    from . import blender
    from .cli import command

    command.unregister()
    blender.unregister()
