"""The Blender layer: translates between Blender data and ``sh_lighting.core``; no math here.

Each module exports ``register()``/``unregister()``; they are called in ``MODULES`` order
and undone in reverse.
"""

from . import command, design_ui, lights_ui, operators, panels, preferences, presets_ui, properties

MODULES = (preferences, properties, operators, panels, presets_ui, design_ui, lights_ui, command)


def register():
    for module in MODULES:
        module.register()


def unregister():
    for module in reversed(MODULES):
        module.unregister()
