"""Presets in the UI: a preset menu, Save/Remove user presets, Import and Export.

Why not Blender's own preset machinery (``AddPresetBase`` + ``Menu.draw_preset`` +
``script.execute_preset``): those presets are Python files that Blender *executes*, which would
make a downloaded preset able to run any code, and they store property assignments, while
our lighting lives in scene custom properties and our preset format is a strict, versioned
JSON file (``core.presets``) that other tools and the command line read too. So the menu
follows Blender's conventions without executing anything:

* ``SHLIGHT_MT_presets`` lists the shipped presets (the package's ``presets`` folder) and, under
  them, the user's presets from Blender's user preset folder
  (``<user scripts>/presets/sh_lighting``, beside Blender's own presets); each entry runs
  ``shlight.load_preset`` with the file's path, and the menu's label is the name of the
  preset the scene's values were loaded from (its recorded provenance, while that file
  exists and no design edit followed), else "Presets". User entries have a "−" button
  (``shlight.preset_remove``, with a confirmation); shipped presets have none and
  ``preset_io.remove_user_preset`` refuses them anyway.
* "+" (``shlight.preset_add``) saves the current coefficients as a user preset under a
  sanitised file name (``preset_io.preset_file_name``), refusing to replace one unless
  Overwrite is ticked.
* Import and Export use the file browser: Import reads our JSON; Export writes our JSON or the
  three.js, glTF or Filament forms (``preset_io.FORMATS``), atomically, and refuses to replace
  an existing file unless Overwrite is ticked (the browser also flags existing files in red).

Operators that change the scene (load, import) are undoable; those that only touch files
(export, save, remove) are not. All work in background mode with ``'EXEC_DEFAULT'``; errors
become an ERROR report and ``{'CANCELLED'}`` with nothing changed. The "Presets" sub-panel is
drawn by ``draw_presets`` under both main panels (World Properties and the 3D Viewport
sidebar).
"""

import os
from pathlib import Path

import bpy
from bpy.props import BoolProperty, EnumProperty, StringProperty
from bpy_extras.io_utils import ExportHelper, ImportHelper

from ..core.presets import PresetError
from . import panels, preset_io, scene_data
from .polls import coefficients_poll, scene_poll

LOAD = "shlight.load_preset"
ADD = "shlight.preset_add"
REMOVE = "shlight.preset_remove"
IMPORT = "shlight.import_preset"
EXPORT = "shlight.export_preset"

FORMAT_ITEMS = tuple(
    (key.upper(), label, description)
    for key, label, description in (
        ("sh_lighting", preset_io.FORMATS["sh_lighting"][0],
         "SH Lighting preset: raw L_lm in Blender axes, with metadata (Import reads it)"),
        ("threejs", preset_io.FORMATS["threejs"][0],
         "A LightProbe for three.js (ObjectLoader JSON): radiance L_lm, y-up glTF axes"),
        ("gltf", preset_io.FORMATS["gltf"][0],
         "A .gltf environment for Babylon.js: irradiance coefficients and a specular cube "
         "prefiltered from the world image, y-up glTF axes"),
        ("filament", preset_io.FORMATS["filament"][0],
         "cmgen-style sh.txt for Filament: shader-ready pre-scaled irradiance"),
    )
)
KNOWN_EXTENSIONS = {ext for _label, ext in preset_io.FORMATS.values()}


def _coefficients_poll(cls, context):
    return coefficients_poll(
        cls, context, "No SH coefficients yet: run Compute from World or load a preset"
    )


def display_name(name, shipped):
    """Menu text of a preset file stem: "grace_cathedral" -> "Grace Cathedral" (shipped);
    user names keep their case."""
    return bpy.path.display_name(name, has_ext=False, title_case=shipped)


def load_preset_file(operator, scene, path):
    """Shared body of Load and Import: read, store, report; returns the operator result."""
    if not path:
        operator.report({"ERROR"}, "No preset file given")
        return {"CANCELLED"}
    try:
        preset_io.import_preset(scene, path)
    except (PresetError, OSError, ValueError) as error:
        operator.report({"ERROR"}, f"Preset not loaded, nothing changed: {error}")
        return {"CANCELLED"}
    name = os.path.splitext(os.path.basename(path))[0]
    operator.report({"INFO"}, f"Loaded SH lighting preset '{name}'")
    return {"FINISHED"}


class SHLIGHT_OT_load_preset(bpy.types.Operator):
    """Set the scene's SH coefficients from this preset"""

    bl_idname = LOAD
    bl_label = "Load SH Preset"
    bl_options = {"REGISTER", "UNDO", "INTERNAL"}

    filepath: StringProperty(
        name="File Path",
        description="Preset file (SH Lighting JSON) to load",
        subtype="FILE_PATH",
        options={"SKIP_SAVE", "HIDDEN"},
    )

    @classmethod
    def poll(cls, context):
        return scene_poll(cls, context)

    def execute(self, context):
        return load_preset_file(self, context.scene, self.filepath)


class SHLIGHT_OT_import_preset(bpy.types.Operator, ImportHelper):
    """Set the scene's SH coefficients from an SH Lighting preset file (JSON)"""

    bl_idname = IMPORT
    bl_label = "Import SH Preset"
    bl_options = {"REGISTER", "UNDO"}

    filename_ext = ".json"
    filter_glob: StringProperty(default="*.json", options={"HIDDEN"})

    @classmethod
    def poll(cls, context):
        return scene_poll(cls, context)

    def execute(self, context):
        return load_preset_file(self, context.scene, self.filepath)


FILAMENT_FRAME_ITEMS = tuple(
    (key.upper(), key, f"Line up with {what}")
    for key, what in preset_io.FILAMENT_FRAMES.items()
)


class SHLIGHT_OT_export_preset(bpy.types.Operator, ExportHelper):
    """Write the scene's SH lighting as a preset, or for three.js, glTF or Filament"""

    bl_idname = EXPORT
    bl_label = "Export SH Lighting"
    bl_options = {"REGISTER"}

    filename_ext = ".json"
    filter_glob: StringProperty(default="*.json;*.txt;*.gltf", options={"HIDDEN"})
    export_format: EnumProperty(
        name="Format",
        description="What to write: our preset, or the form another renderer reads",
        items=FORMAT_ITEMS,
        default="SH_LIGHTING",
    )
    filament_frame: EnumProperty(
        name="Axes",
        description="Filament sh.txt axes: cmgen's (its specular KTX of the same image) or glTF's",
        items=FILAMENT_FRAME_ITEMS,
        default=FILAMENT_FRAME_ITEMS[0][0],
    )
    overwrite: BoolProperty(
        name="Overwrite",
        description="Replace the file if it exists (otherwise Export refuses and writes nothing)",
        default=False,
    )

    @classmethod
    def poll(cls, context):
        return _coefficients_poll(cls, context)

    def check(self, _context):
        """Give the file name the extension of the chosen format (.json, .gltf or .txt)."""
        wanted = preset_io.FORMATS[self.export_format.lower()][1]
        path = self.filepath
        if not os.path.basename(path):
            return False
        stem, ext = os.path.splitext(path)
        if ext.lower() == wanted:
            return False
        self.filepath = (stem if ext.lower() in KNOWN_EXTENSIONS else path) + wanted
        return True

    def draw(self, _context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(self, "export_format")
        if self.export_format == "FILAMENT":
            layout.prop(self, "filament_frame")
        layout.prop(self, "overwrite")

    def execute(self, context):
        try:
            path = preset_io.export_preset(
                context.scene, self.filepath, self.export_format.lower(), self.overwrite,
                filament_frame=self.filament_frame.lower(),
            )
        except (LookupError, OSError, ValueError) as error:  # PresetError is a ValueError
            self.report({"ERROR"}, f"Nothing exported: {error}")
            return {"CANCELLED"}
        label = preset_io.FORMATS[self.export_format.lower()][0]
        self.report({"INFO"}, f"Exported {label} to {path}")
        return {"FINISHED"}


class SHLIGHT_OT_preset_add(bpy.types.Operator):
    """Save the scene's SH coefficients as a user preset"""

    bl_idname = ADD
    bl_label = "Save SH Preset"
    bl_options = {"REGISTER"}

    name: StringProperty(
        name="Name",
        description="Name of the preset; its file name keeps letters, digits, - and _",
        default="",
        maxlen=preset_io.MAX_NAME_LENGTH,
    )
    overwrite: BoolProperty(
        name="Overwrite",
        description="Replace a user preset of the same file name",
        default=False,
    )

    @classmethod
    def poll(cls, context):
        return _coefficients_poll(cls, context)

    def invoke(self, context, _event):
        return context.window_manager.invoke_props_dialog(self)

    def execute(self, context):
        try:
            path = preset_io.save_user_preset(context.scene, self.name, self.overwrite)
        except (LookupError, OSError, ValueError) as error:
            self.report({"ERROR"}, f"Preset not saved: {error}")
            return {"CANCELLED"}
        self.report({"INFO"}, f"Saved SH lighting preset '{self.name.strip()}' to {path}")
        return {"FINISHED"}


class SHLIGHT_OT_preset_remove(bpy.types.Operator):
    """Delete this user preset file (shipped presets cannot be deleted)"""

    bl_idname = REMOVE
    bl_label = "Remove SH Preset"
    bl_options = {"REGISTER", "INTERNAL"}

    name: StringProperty(
        name="Name",
        description="User preset to delete (its file name without .json)",
        default="",
        options={"SKIP_SAVE"},
    )

    def invoke(self, context, event):
        return context.window_manager.invoke_confirm(self, event)

    def execute(self, _context):
        try:
            path = preset_io.remove_user_preset(self.name)
        except (OSError, ValueError) as error:
            self.report({"ERROR"}, f"Preset not removed: {error}")
            return {"CANCELLED"}
        self.report({"INFO"}, f"Removed SH lighting preset file {path}")
        return {"FINISHED"}


def draw_preset_menu(layout):
    """Shipped presets, then user presets with a remove button each, then Save."""
    shipped = preset_io.shipped_presets()
    user = preset_io.user_presets()
    if shipped:
        layout.label(text="Shipped")
        for name, path in shipped.items():
            op = layout.operator(LOAD, text=display_name(name, shipped=True), translate=False)
            op.filepath = str(path)
        layout.separator()
    layout.label(text="User")
    for name, path in user.items():
        row = layout.row(align=True)
        op = row.operator(LOAD, text=display_name(name, shipped=False), translate=False)
        op.filepath = str(path)
        row.operator(REMOVE, text="", icon="REMOVE").name = name
    if not user:
        layout.label(text="None yet: save one with +")
    layout.separator()
    layout.operator(ADD, text="Save Current as Preset...", icon="ADD")


def menu_label(scene):
    """The preset menu's label for ``scene``: the preset its values were loaded from, while
    that file exists and no design edit or Compute followed, else "Presets"."""
    record = scene_data.provenance(scene)
    path = record.get("path")
    if record.get("source") != "PRESET" or "edit" in record or not path:
        return SHLIGHT_MT_presets.bl_label
    path = Path(path)
    if not path.is_file():
        return SHLIGHT_MT_presets.bl_label
    shipped_dir = preset_io.shipped_preset_dir()
    shipped = shipped_dir is not None and path.parent == shipped_dir.resolve()
    return display_name(path.stem, shipped)


class SHLIGHT_MT_presets(bpy.types.Menu):
    bl_label = "Presets"

    def draw(self, _context):
        draw_preset_menu(self.layout)


def draw_presets(layout, context):
    """The Presets sub-panel: the menu with Save, then Import and Export."""
    row = layout.row(align=True)
    row.menu(SHLIGHT_MT_presets.__name__, text=menu_label(context.scene))
    row.operator(ADD, text="", icon="ADD")
    row = layout.row(align=True)
    row.operator(IMPORT, text="Import", icon="IMPORT")
    row.operator(EXPORT, text="Export", icon="EXPORT")


SHLIGHT_PT_world_presets, SHLIGHT_PT_view3d_presets = panels.sub_panels(
    "presets", "Presets", draw_presets
)


classes = (
    SHLIGHT_OT_load_preset,
    SHLIGHT_OT_import_preset,
    SHLIGHT_OT_export_preset,
    SHLIGHT_OT_preset_add,
    SHLIGHT_OT_preset_remove,
    SHLIGHT_MT_presets,
    SHLIGHT_PT_world_presets,
    SHLIGHT_PT_view3d_presets,
)
register, unregister = bpy.utils.register_classes_factory(classes)
