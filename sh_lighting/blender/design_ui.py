"""Placeholder: filled in by the design work (classes registered through MODULES)."""

import bpy

classes = ()
register, unregister = bpy.utils.register_classes_factory(classes)
