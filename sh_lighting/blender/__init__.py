"""The Blender layer: translates between Blender data and ``sh_lighting.core``; no math here.

Each module exports ``register()``/``unregister()``; they are called in ``MODULES`` order
and undone in reverse.

The UI modules (panels, operators, popovers) are imported on first use of ``MODULES`` (by
``register``), not with this package: a command line run (``python -m sh_lighting
compute``) reads an image through ``blender.world`` and draws no panel, and importing the UI
cost it about 0.1 s of its start (benchmarks/fragments/commands.md).
"""

import importlib

# (module path under this package, in register order)
_MODULE_NAMES = (
    "data.preferences", "data.settings", "ui.operators", "ui.panels", "ui.presets",
    "ui.design", "ui.lights", "ui.transfer", "ui.photo", "ui.luminaire",
)


def __getattr__(name):
    """``MODULES``: the modules registered, imported on first use (PEP 562)."""
    if name == "MODULES":
        modules = tuple(importlib.import_module(f"{__name__}.{path}") for path in _MODULE_NAMES)
        globals()["MODULES"] = modules
        return modules
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def register():
    for module in __getattr__("MODULES"):
        module.register()


def unregister():
    for module in reversed(__getattr__("MODULES")):
        module.unregister()
