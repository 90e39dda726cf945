"""Add-on preferences, keyed by ``__package__`` of the add-on so they work as an extension."""

import bpy

# "bl_ext.user_default.sh_lighting" when installed as an extension, "sh_lighting" in tests.
ADDON_ID = __package__.rpartition(".blender")[0]


def addon_preferences():
    """The add-on's preferences, or None when it is not enabled (e.g. registered by tests)."""
    addon = bpy.context.preferences.addons.get(ADDON_ID)
    return addon.preferences if addon is not None else None


class SHLIGHT_AddonPreferences(bpy.types.AddonPreferences):
    bl_idname = ADDON_ID

    capture_resolution: bpy.props.IntProperty(
        name="World Capture Width",
        description=(
            "Width in pixels of the equirectangular image rendered to capture procedural "
            "worlds (Sky Texture, gradients, mixes); the height is half of it"
        ),
        default=256,
        min=16,
        soft_max=2048,
        subtype="PIXEL",
    )

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.prop(self, "capture_resolution")


classes = (SHLIGHT_AddonPreferences,)
register, unregister = bpy.utils.register_classes_factory(classes)
