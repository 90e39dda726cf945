"""The Blender layer: translates between Blender data and ``sh_lighting.core``; no math here.

Each module exports ``register()``/``unregister()``; they are called in ``MODULES`` order
and undone in reverse.
"""

from .data import preferences, settings
from .ui import design as design_ui
from .ui import lights as lights_ui
from .ui import luminaire as luminaire_ui
from .ui import operators, panels
from .ui import photo as photo_ui
from .ui import presets as presets_ui
from .ui import transfer as transfer_ui

MODULES = (
    preferences, settings, operators, panels, presets_ui, design_ui, lights_ui, transfer_ui,
    photo_ui, luminaire_ui,
)


def register():
    for module in MODULES:
        module.register()


def unregister():
    for module in reversed(MODULES):
        module.unregister()
