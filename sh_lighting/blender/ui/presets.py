"""Presets in the UI: a preset menu, Save/Remove user presets, Import and Export.

Not Blender's preset machinery, whose presets are Python files that Blender executes: ours
are strict JSON (``formats.presets``), read, never run. The popover in the header of the main
panels lists shipped then user presets (``<user scripts>/presets/sh_lighting``), with "+" and
"−" for user presets; Import reads our JSON, Export is one operator with a Format choice and a
default file name per format, refusing to replace a file unless Overwrite is ticked. Scene
changes are undoable; errors are an ERROR report with nothing changed. Details:
docs/modules.md.
"""

import os
from pathlib import Path

import bpy
from bpy.props import BoolProperty, EnumProperty, StringProperty
from bpy_extras.io_utils import ExportHelper, ImportHelper

from ...formats.presets import PresetError
from ..data import scene_data
from ..design import lights
from ..presets import preset_io
from .polls import coefficients_poll, scene_poll

LOAD = "shlight.load_preset"
ADD = "shlight.preset_add"
REMOVE = "shlight.preset_remove"
IMPORT = "shlight.import_preset"
EXPORT = "shlight.export_preset"

FORMAT_ITEMS = tuple(
    (key.upper(), fmt.label, fmt.description) for key, fmt in preset_io.FORMATS.items()
)
KNOWN_EXTENSIONS = {fmt.extension for fmt in preset_io.FORMATS.values()}
UNTITLED = "untitled"


def default_file_name(blend_path, key):
    """The file name Export proposes for format ``key``: the .blend's name (else "untitled")
    and the format's own ending and extension ("shot_threejs_lightprobe.json"), never the
    name another format proposes."""
    stem = Path(blend_path).stem if blend_path else UNTITLED
    fmt = preset_io.FORMATS[key]
    return stem + fmt.default_suffix + fmt.extension


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
        note = preset_io.import_preset(scene, path).note
    except (PresetError, OSError, ValueError) as error:
        operator.report({"ERROR"}, f"Preset not loaded, nothing changed: {error}")
        return {"CANCELLED"}
    # Lamps Extract Lights took out of the old world would light the preset's lighting
    deleted = lights.remove_lights(scene)
    if deleted:
        note = "; ".join(filter(None, (note, (
            f"{len(deleted)} Sun light(s) extracted from the previous world deleted "
            f"({', '.join(deleted)}); the world still shows as the background"))))
    operator.report({"INFO"}, f"Loaded SH lighting preset '{loaded_name(path)}'"
                    + (f"; {note}" if note else ""))
    return {"FINISHED"}


def loaded_name(path):
    """The name the preset menu shows for the preset file at ``path``:
    "Grace Cathedral" for the shipped ``grace_cathedral.json``, a user preset's file stem as
    it is."""
    path = Path(path)
    shipped_dir = preset_io.shipped_preset_dir()
    try:
        shipped = shipped_dir is not None and path.resolve().parent == shipped_dir.resolve()
    except OSError:
        shipped = False
    return display_name(path.stem, shipped)


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

    def invoke(self, context, _event):
        """Open the file browser in the .blend file's folder (when it is saved)."""
        if not self.filepath and bpy.data.filepath:
            self.filepath = os.path.join(os.path.dirname(bpy.data.filepath), "")
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        return load_preset_file(self, context.scene, self.filepath)


FILAMENT_FRAME_ITEMS = tuple(
    (key.upper(), key, f"Line up with {what}")
    for key, what in preset_io.FILAMENT_FRAMES.items()
)


class SHLIGHT_OT_export_preset(bpy.types.Operator, ExportHelper):
    """Write the scene's SH lighting as a preset, or for three.js, glTF or Filament"""

    bl_idname = EXPORT
    bl_label = "Export"  # the file browser's button: short enough never to be cut
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

    @classmethod
    def description(cls, _context, props):
        """The chosen format's description (the Export menu has an entry per format)."""
        return preset_io.FORMATS[props.export_format.lower()].description

    def invoke(self, context, _event):
        """The file browser in the .blend's folder, on the format's own default name."""
        if not self.filepath:
            folder = os.path.dirname(bpy.data.filepath) if bpy.data.filepath else ""
            self.filepath = os.path.join(
                folder, default_file_name(bpy.data.filepath, self.export_format.lower()))
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def check(self, _context):
        """Follow the chosen format: a default name becomes that format's default name, any
        other name gets the format's extension (.json, .gltf or .txt)."""
        path = self.filepath
        name = os.path.basename(path)
        if not name:
            return False
        key = self.export_format.lower()
        defaults = {default_file_name(bpy.data.filepath, k) for k in preset_io.FORMATS}
        if name in defaults:
            wanted = os.path.join(os.path.dirname(path), default_file_name(bpy.data.filepath, key))
        else:
            stem, ext = os.path.splitext(path)
            extension = preset_io.FORMATS[key].extension
            wanted = path if ext.lower() == extension else (
                (stem if ext.lower() in KNOWN_EXTENSIONS else path) + extension)
        if wanted == path:
            return False
        self.filepath = wanted
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
        label = preset_io.FORMATS[self.export_format.lower()].label
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
        """Save at once under the name typed in the popover, else ask for one."""
        if self.name.strip():
            return self.execute(context)
        return context.window_manager.invoke_props_dialog(self)

    def draw(self, _context):
        layout = self.layout
        layout.activate_init = True  # the name field is ready for typing
        layout.prop(self, "name")
        layout.prop(self, "overwrite")

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
        return context.window_manager.invoke_confirm(
            self, event, title="Remove SH Preset",
            message=f"Delete the preset '{display_name(self.name, shipped=False)}'?",
            confirm_text="Delete")

    def execute(self, _context):
        try:
            path = preset_io.remove_user_preset(self.name)
        except (OSError, ValueError) as error:
            self.report({"ERROR"}, f"Preset not removed: {error}")
            return {"CANCELLED"}
        self.report({"INFO"}, f"Removed SH lighting preset file {path}")
        return {"FINISHED"}


class SHLIGHT_MT_export(bpy.types.Menu):
    """Export the scene's SH coefficients"""

    bl_label = "Export"

    def draw(self, _context):
        for key, fmt in preset_io.FORMATS.items():  # one operator, its format chosen here
            op = self.layout.operator(EXPORT, text=f"{fmt.label} ({fmt.extension})")
            op.export_format = key.upper()


def draw_preset_menu(layout):
    """Shipped presets, then user presets with "−" on their right; then a name field with
    "+" (Blender's preset popovers), Import and Export."""
    layout.emboss = "PULLDOWN_MENU"
    shipped = preset_io.shipped_presets()
    user = preset_io.user_presets()
    col = layout.column(align=True)
    for name, path in shipped.items():
        op = col.operator(LOAD, text=display_name(name, shipped=True), translate=False)
        op.filepath = str(path)
    if user:
        col.separator()
    for name, path in user.items():
        row = col.row(align=True)
        op = row.operator(LOAD, text=display_name(name, shipped=False), translate=False)
        op.filepath = str(path)
        row.operator(REMOVE, text="", icon="REMOVE").name = name
    layout.separator()
    row = layout.row()
    sub = row.row()
    sub.emboss = "NORMAL"
    wm = bpy.context.window_manager
    sub.prop(wm, PRESET_NAME, text="")
    row.operator(ADD, text="", icon="ADD").name = getattr(wm, PRESET_NAME)
    layout.separator()
    layout.operator(IMPORT, text="Import…", icon="IMPORT")
    layout.menu(SHLIGHT_MT_export.__name__, text="Export", icon="EXPORT")


PRESET_NAME = "sh_lighting_preset_name"  # WindowManager: the name typed in the popover
PRESETS_LABEL = "Presets"


def menu_label(scene):
    """The name of the preset the scene's values were loaded from (its recorded provenance),
    while that file exists and no design edit or Compute followed, else "Presets"."""
    record = scene_data.provenance(scene)
    path = record.get("path")
    if record.get("source") != "PRESET" or "edit" in record or not path:
        return PRESETS_LABEL
    if not Path(path).is_file():
        return PRESETS_LABEL
    return loaded_name(path)


class SHLIGHT_PT_presets(bpy.types.Panel):
    """The presets popover of the SH Lighting panels' header (not a panel of its own)."""

    bl_label = "SH Lighting Presets"
    bl_space_type = "PROPERTIES"
    bl_region_type = "HEADER"

    def draw(self, _context):
        draw_preset_menu(self.layout)


classes = (
    SHLIGHT_OT_load_preset,
    SHLIGHT_OT_import_preset,
    SHLIGHT_OT_export_preset,
    SHLIGHT_OT_preset_add,
    SHLIGHT_OT_preset_remove,
    SHLIGHT_MT_export,
    SHLIGHT_PT_presets,
)
_register_classes, _unregister_classes = bpy.utils.register_classes_factory(classes)


def register():
    setattr(bpy.types.WindowManager, PRESET_NAME, StringProperty(
        name="Preset Name", description="Name of the preset that + saves",
        maxlen=preset_io.MAX_NAME_LENGTH, options=set()))
    _register_classes()


def unregister():
    _unregister_classes()
    delattr(bpy.types.WindowManager, PRESET_NAME)
