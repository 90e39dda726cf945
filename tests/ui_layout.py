"""A stand-in for ``bpy.types.UILayout`` (headless Blender has no UI): records what a draw
function draws, in order, so tests can check the buttons, fields and texts of a panel."""


class Props:
    """What ``layout.operator`` returns: keeps the properties the panel sets on it."""


class RecordingLayout:
    """Records ("prop", data, path, kwargs), ("operator", idname, props, kwargs),
    ("label", text, icon), ("icon", icon_value, scale), ("popover", panel, kwargs) and
    ("menu", menu, kwargs); every sub-layout records into the same list. Layout attributes
    (alert, active, alignment, scale_y, ...) can be set and are kept."""

    def __init__(self, calls=None):
        self.calls = [] if calls is None else calls
        self.use_property_split = False
        self.use_property_decorate = True
        self.active = True
        self.alert = False

    def _child(self, *args, **kwargs):
        child = RecordingLayout(self.calls)
        child.alert = self.alert
        return child

    column = row = box = split = _child

    def prop(self, data, path, **kwargs):
        self.calls.append(("prop", data, path, kwargs))

    def operator(self, idname, **kwargs):
        props = Props()
        self.calls.append(("operator", idname, props, dict(kwargs, alert=self.alert)))
        return props

    def label(self, text="", icon="NONE", **_kwargs):
        self.calls.append(("label", text, icon))

    def template_icon(self, icon_value=0, scale=1.0):
        self.calls.append(("icon", icon_value, scale))

    def popover(self, panel, **kwargs):
        self.calls.append(("popover", panel, kwargs))

    def menu(self, menu, **kwargs):
        self.calls.append(("menu", menu, kwargs))

    def separator(self, **_kwargs):
        pass

    # what the records say
    def of(self, kind):
        return [c for c in self.calls if c[0] == kind]

    def text(self):
        """Every label's text joined by spaces (wrapped lines read as one text)."""
        return " ".join(c[1] for c in self.of("label"))

    def operators(self):
        return [c[1] for c in self.of("operator")]
