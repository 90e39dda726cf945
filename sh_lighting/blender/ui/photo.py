"""Match Photo in the UI: the operator (a dialog of its settings), its sub-panel, and a drag
in the Image Editor (Image > Match Photo: Drag the Ball's Circle) that gives the circle.

The settings are the operator's own properties (Blender remembers the last ones used in the
session): nothing transient is stored in the scene; what was fitted is recorded in the
stored coefficients' provenance ("PHOTO"). Choosing the photo finds the ball in it
(``core.ball_detect``, a suggestion) and the dialog shows the photo with that circle, which
the user accepts or corrects. Blender remembers an operator's settings only when it
succeeds: after a failure the photo and circle typed are kept on the window manager
(``TYPED``, not in the scene) for the next dialog.
"""

import os

import bpy

from ...core.ball_detect import detect_ball
from ...core.photo import DEFAULT_ALBEDO, DEFAULT_MARGIN, PRIORS
from ..photo import fit
from ..data import scene_data
from . import previews
from .panels import sub_panels
from .polls import scene_poll

TYPED = "sh_lighting_match_photo_typed"  # WindowManager: {"filepath", "circle"} of a failure
PHOTO_SCALE = 8.0  # the dialog's photo: UI units (160 px at scale 1)

PRIOR_ITEMS = (
    ("mirror", "Mirror", "The unseen side is the seen side mirrored through the plane "
                         "perpendicular to the view axis"),
    ("ambient", "Ambient", "The unseen side is lit by the seen side's mean, a constant"),
    ("chrome", "Chrome Ball", "The unseen side is lit as a chrome ball of the same place shows "
                              "(its mirror-ball image, or the world when that is one), scaled "
                              "to the grey ball"),
    ("photo", "Second Photo", "The unseen side is lit as a second photo of the ball from "
                              "another side shows (the same ball and exposure)"),
    ("none", "None", "No prior: the least-squares fit extrapolated (often far off and "
                     "negative on the unseen side; lifted to non-negative light)"),
)
assert tuple(item[0] for item in PRIOR_ITEMS) == PRIORS
CAMERA_ITEMS = (
    ("SCENE", "Scene Camera", "The photo was taken from the scene's camera: its orientation, "
                              "projection, lens and sensor"),
    ("DIRECTION", "Direction", "The photo was taken looking along a direction, with a roll"),
)
PROJECTION_ITEMS = (
    ("ORTHO", "Orthographic", "Parallel view rays (a long lens far away)"),
    ("PERSP", "Perspective", "View rays through a lens of the focal length and sensor below"),
)


def find_ball(props):
    """Find the ball in ``props.filepath``'s photo: its circle into ``props.circle`` and a line
    saying what was found (or why nothing) into ``props.detected``; the dialog's thumbnail
    made. Nothing raised: a photo that cannot be read says so in the line."""
    path = props.filepath
    if not path:
        props.detected = ""
        return
    try:
        source = fit.read_photo(path)
    except ValueError as error:
        props.detected = f"! {error}"
        return
    try:
        previews.photo(path, source.pixels, (0.0, 0.0, 0.0))
    except RuntimeError:  # the add-on's previews are not open (not registered)
        pass
    guess = detect_ball(source.pixels)
    if guess is None:
        props.detected = (f"! No ball found in '{os.path.basename(source.path)}': type its "
                          "circle, or drag it (Image Editor > Image > Match Photo)")
        return
    props.circle = guess.circle
    props.detected = guess.summary()[0].upper() + guess.summary()[1:]


def find_ball_keeping_circle(props):
    """The thumbnail and the line for a photo given with its circle (the Image Editor's drag
    or detection): the circle kept as given."""
    circle = tuple(props.circle)
    find_ball(props)
    if tuple(props.circle) != circle:
        props.circle = circle
        props.detected = "Circle as given (centre X, Y and radius in pixels)"


def _photo_chosen(self, _context):
    find_ball(self)


def _match(self, context):
    """Match Photo's work: the scene's coefficients from the photo; the operator result."""
    if not self.filepath:
        self.report({"ERROR"}, "No photo: give the path of the grey ball's photo")
        return {"CANCELLED"}
    if self.circle[2] <= 0.0:
        self.report({"ERROR"}, "Match Photo: no circle yet (its radius is 0 px): the "
                    "ball was not found in the photo; type its centre X, Y and radius in "
                    "pixels, or drag it (Image Editor > Image > Match Photo)")
        return {"CANCELLED"}
    direction = tuple(self.direction) if self.camera == "DIRECTION" else None
    chrome = self.chrome_filepath or None
    second = (fit.SecondPhoto(self.second_filepath, tuple(self.second_circle),
                              direction=tuple(self.second_direction),
                              roll=self.second_roll)
              if self.prior == "photo" and self.second_filepath else None)
    try:
        stored, result = fit.coefficients_from_photo(
            context.scene, self.filepath, tuple(self.circle), direction=direction,
            roll=self.roll, projection=self.projection, focal_mm=self.focal_mm,
            sensor_mm=self.sensor_mm, albedo=self.albedo, margin=self.margin,
            prior=self.prior, clip=self.clip if self.clip > 0.0 else None,
            chrome=chrome, second=second)
    except (LookupError, ValueError) as error:
        self.report({"ERROR"}, f"Match Photo: {error}")
        return {"CANCELLED"}
    warning = result.warning()  # first: a wrong circle reads as a poor fit
    kind = {"WARNING"} if warning else {"INFO"}
    first = f"Match Photo: {warning}; " if warning else ""
    exposure = scene_data.provenance(context.scene).get("exposure_summary")
    both = f"; {exposure}" if exposure else ""
    keyed = f"; SH lighting {stored.note}" if getattr(stored, "note", "") else ""
    self.report(kind, f"{first}SH lighting from the photo: {result.summary()}{both}{keyed}")
    return {"FINISHED"}


class SHLIGHT_OT_match_photo(bpy.types.Operator):
    """Compute the SH lighting from a photo of a grey (matte) ball: the nine coefficients
    that best reproduce the ball's pixels, the unseen side filled by the chosen prior"""

    bl_idname = "shlight.match_photo"
    bl_label = "Match Photo"
    bl_options = {"REGISTER", "UNDO"}

    filepath: bpy.props.StringProperty(
        name="Photo", subtype="FILE_PATH", update=_photo_chosen,
        description="The photo of the grey ball (8-bit sRGB PNG or JPEG, or linear EXR/HDR); "
                    "choosing it finds the ball")
    detected: bpy.props.StringProperty(
        name="Found", options={"HIDDEN", "SKIP_SAVE"},
        description="What finding the ball in the photo gave")
    circle: bpy.props.FloatVectorProperty(
        name="Circle", size=3, default=(0.0, 0.0, 0.0), min=0.0, soft_max=8192.0,
        description="The ball in the photo: centre X and Y (pixels from the top-left "
                    "corner) and radius, in pixels")
    albedo: bpy.props.FloatProperty(
        name="Albedo", default=DEFAULT_ALBEDO, min=0.001, max=1.0, subtype="FACTOR",
        description="The ball's diffuse reflectance (a grey card ball: 0.18)")
    margin: bpy.props.FloatProperty(
        name="Rim Margin", default=DEFAULT_MARGIN, min=0.0, max=0.5, subtype="FACTOR",
        description="Fraction of the radius left out at the rim (pixels there mix ball and "
                    "background)")
    prior: bpy.props.EnumProperty(
        name="Unseen Side", items=PRIOR_ITEMS, default="mirror",
        description="What lights the side of the ball the photo does not see")
    camera: bpy.props.EnumProperty(
        name="Camera", items=CAMERA_ITEMS, default="SCENE",
        description="Where the photo was taken from")
    direction: bpy.props.FloatVectorProperty(
        name="View Direction", size=3, default=(0.0, 1.0, 0.0), subtype="DIRECTION",
        description="World direction the photo looks along (towards the ball)")
    roll: bpy.props.FloatProperty(
        name="Roll", default=0.0, subtype="ANGLE", description="Roll about the view direction")
    projection: bpy.props.EnumProperty(
        name="Projection", items=PROJECTION_ITEMS, default="ORTHO",
        description="How the photo projects the ball (with a view direction)")
    focal_mm: bpy.props.FloatProperty(
        name="Focal Length", default=85.0, min=1.0, soft_max=600.0, unit="CAMERA",
        description="Lens focal length in mm (perspective, with a view direction)")
    sensor_mm: bpy.props.FloatProperty(
        name="Sensor", default=36.0, min=1.0, soft_max=100.0, unit="CAMERA",
        description="Sensor size along the photo's longer side, in mm")
    chrome_filepath: bpy.props.StringProperty(
        name="Chrome Ball", subtype="FILE_PATH",
        description="The chrome ball's mirror-ball image (empty: the scene's world, e.g. the "
                    "chrome ball set as the world with the Mirror Ball projection)")
    second_filepath: bpy.props.StringProperty(
        name="Second Photo", subtype="FILE_PATH",
        description="A photo of the same grey ball from another side, same exposure")
    second_circle: bpy.props.FloatVectorProperty(
        name="Second Circle", size=3, default=(0.0, 0.0, 0.0), min=0.0, soft_max=8192.0,
        description="The ball in the second photo: centre X and Y (pixels from the top-left "
                    "corner) and radius, in pixels")
    second_direction: bpy.props.FloatVectorProperty(
        name="Second Direction", size=3, default=(0.0, -1.0, 0.0), subtype="DIRECTION",
        description="World direction the second photo looks along (its lens and projection: "
                    "the first photo's)")
    second_roll: bpy.props.FloatProperty(
        name="Second Roll", default=0.0, subtype="ANGLE",
        description="Roll of the second photo about its view direction")
    clip: bpy.props.FloatProperty(
        name="Clip Above", default=0.0, min=0.0, soft_max=100.0,
        description="Also leave out pixels with a linear channel at or above this (0: only "
                    "the file's own clipping, a byte of 255 in an 8-bit photo)")

    @classmethod
    def poll(cls, context):
        return scene_poll(cls, context)

    def invoke(self, context, event):
        typed = context.window_manager.get(TYPED)
        if typed is not None:  # what the last, failed, dialog was given
            typed = typed.to_dict()  # a copy: the property is deleted next
            del context.window_manager[TYPED]
            if not self.properties.is_property_set("filepath"):
                self.filepath = str(typed.get("filepath", ""))  # finds the ball again
                circle = tuple(typed.get("circle", (0.0, 0.0, 0.0)))
                if len(circle) == 3 and circle[2] > 0.0:  # a circle typed wins over the found
                    self.circle = circle
        elif self.filepath and not self.properties.is_property_set("circle"):
            find_ball(self)
        elif self.filepath:
            find_ball_keeping_circle(self)
        return context.window_manager.invoke_props_dialog(self, width=360)

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.prop(self, "filepath")
        if self.detected:
            failed = self.detected.startswith("! ")
            row = layout.row()
            row.alert = failed
            row.label(text=self.detected[2:] if failed else self.detected,
                      icon="ERROR" if failed else "CHECKMARK")
        try:
            preview = previews.photo(self.filepath, None, tuple(self.circle))
        except RuntimeError:
            preview = None
        if preview is not None:
            row = layout.row()
            row.alignment = "CENTER"
            row.template_icon(icon_value=preview.icon_id, scale=PHOTO_SCALE)
        layout.prop(self, "circle")
        layout.prop(self, "albedo")
        layout.prop(self, "margin")
        layout.prop(self, "prior")
        if self.prior == "chrome":
            layout.prop(self, "chrome_filepath")
        elif self.prior == "photo":
            for name in ("second_filepath", "second_circle", "second_direction", "second_roll"):
                layout.prop(self, name)
        layout.prop(self, "clip")
        layout.prop(self, "camera")
        if self.camera == "DIRECTION":
            layout.prop(self, "direction")
            layout.prop(self, "roll")
            layout.prop(self, "projection")
            if self.projection == "PERSP":
                layout.prop(self, "focal_mm")
                layout.prop(self, "sensor_mm")

    def execute(self, context):
        result = _match(self, context)
        wm = context.window_manager
        if result == {"CANCELLED"} and wm is not None:
            wm[TYPED] = {"filepath": self.filepath, "circle": list(self.circle)}
        elif wm is not None and TYPED in wm:
            del wm[TYPED]
        return result


def circle_from_drag(size, start_uv, end_uv):
    """(cx, cy, r) in pixels from the top-left corner of a ``size`` (width, height) image, of
    a drag from the ball's centre ``start_uv`` to its rim ``end_uv`` (Image Editor view
    coordinates: u right, v up, both 0 to 1 across the image)."""
    width, height = size
    cx, cy = start_uv[0] * width, (1.0 - start_uv[1]) * height
    ex, ey = end_uv[0] * width, (1.0 - end_uv[1]) * height
    return cx, cy, ((ex - cx) ** 2 + (ey - cy) ** 2) ** 0.5


class SHLIGHT_OT_photo_circle(bpy.types.Operator):
    """Drag from the ball's centre to its rim in the Image Editor, then Match Photo with that
    circle and the image's file"""

    bl_idname = "shlight.photo_circle"
    bl_label = "Match Photo: Drag the Ball's Circle"
    bl_options = {"REGISTER"}

    @classmethod
    def poll(cls, context):
        space = context.space_data
        if space is None or space.type != "IMAGE_EDITOR" or space.image is None:
            cls.poll_message_set("Open the ball's photo in an Image Editor first")
            return False
        if not space.image.filepath:
            cls.poll_message_set("The image has no file: save it, Match Photo reads a file")
            return False
        return True

    def invoke(self, context, event):
        self._start = None
        context.window_manager.modal_handler_add(self)
        context.area.header_text_set("Drag from the ball's centre to its rim (Esc: cancel)")
        return {"RUNNING_MODAL"}

    def _uv(self, context, event):
        return context.region.view2d.region_to_view(event.mouse_region_x, event.mouse_region_y)

    def modal(self, context, event):
        if event.type in {"ESC", "RIGHTMOUSE"}:
            context.area.header_text_set(None)
            return {"CANCELLED"}
        if event.type == "LEFTMOUSE" and event.value == "PRESS":
            self._start = self._uv(context, event)
        elif event.type == "MOUSEMOVE" and self._start is not None:
            circle = circle_from_drag(context.space_data.image.size, self._start,
                                      self._uv(context, event))
            context.area.header_text_set("Circle: centre ({:.0f}, {:.0f}), radius {:.0f} px"
                                         .format(*circle))
        elif event.type == "LEFTMOUSE" and event.value == "RELEASE" and self._start:
            context.area.header_text_set(None)
            image = context.space_data.image
            circle = circle_from_drag(image.size, self._start, self._uv(context, event))
            bpy.ops.shlight.match_photo("INVOKE_DEFAULT", filepath=image.filepath,
                                        circle=circle)
            return {"FINISHED"}
        return {"RUNNING_MODAL"}


class SHLIGHT_OT_photo_detect(bpy.types.Operator):
    """Find the ball's circle in the Image Editor's photo, then Match Photo with it (check the
    suggested circle in the dialog, correct it if it is not the grey ball)"""

    bl_idname = "shlight.photo_detect"
    bl_label = "Match Photo: Detect the Ball"
    bl_options = {"REGISTER"}

    @classmethod
    def poll(cls, context):
        return SHLIGHT_OT_photo_circle.poll(context)

    def execute(self, context):
        image = context.space_data.image
        try:
            guess = fit.detect_circle(image.filepath)
        except ValueError as error:
            self.report({"ERROR"}, f"Match Photo: {error}")
            return {"CANCELLED"}
        self.report({"INFO"}, f"Match Photo: {guess.summary()}")
        bpy.ops.shlight.match_photo("INVOKE_DEFAULT", filepath=image.filepath,
                                    circle=guess.circle)
        return {"FINISHED"}


def draw_image_menu(self, context):
    self.layout.operator(SHLIGHT_OT_photo_circle.bl_idname, icon="IMAGE_DATA")
    self.layout.operator(SHLIGHT_OT_photo_detect.bl_idname, icon="VIEWZOOM")


def draw_photo(layout, context):
    """The Match Photo button and where the current values came from, if a photo."""
    layout.operator(SHLIGHT_OT_match_photo.bl_idname, icon="IMAGE_DATA")
    record = scene_data.provenance(context.scene) if context.scene else {}
    if record.get("source") == "PHOTO":
        layout.label(text=f"From {record.get('file', '?')}, residual "
                          f"{100.0 * float(record.get('residual', 0.0)):.1f} %", icon="INFO")
        if record.get("warning"):  # a poor fit (a wrong circle?), in red
            row = layout.row()
            row.alert = True
            row.label(text="Poor fit: check the circle", icon="ERROR")


SHLIGHT_PT_world_photo, SHLIGHT_PT_view3d_photo = sub_panels(
    "photo", "Photo", draw_photo, options=("DEFAULT_CLOSED",))

classes = (SHLIGHT_OT_match_photo, SHLIGHT_OT_photo_circle, SHLIGHT_OT_photo_detect,
           SHLIGHT_PT_world_photo,
           SHLIGHT_PT_view3d_photo)
_register_classes, _unregister_classes = bpy.utils.register_classes_factory(classes)


def register():
    _register_classes()
    bpy.types.IMAGE_MT_image.append(draw_image_menu)  # Image Editor > Image


def unregister():
    bpy.types.IMAGE_MT_image.remove(draw_image_menu)
    _unregister_classes()
