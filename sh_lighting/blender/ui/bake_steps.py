"""A ``transfer.bake.Bake`` run for an operator (Bake Transfer, Apply with Shadows): at once
from a script, in background mode or on a redo; in a window modally, one basis world per
timer event, with a progress bar, a status line and Esc (nothing stored when cancelled)."""

import os

import bpy

from ..transfer import bake

# OpenImageIO's debug channel (a Blender build with it on printed ~90 "OIIO DEBUG" lines per
# bake): sent nowhere unless the user chose a file for it. OIIO opens it at its first message.
OIIO_DEBUG_FILE = "OPENIMAGEIO_DEBUG_FILE"

# Events a running bake lets through to the viewport (to look around); it keeps the rest.
NAVIGATION_EVENTS = {"MIDDLEMOUSE", "WHEELUPMOUSE", "WHEELDOWNMOUSE", "TRACKPADPAN",
                     "TRACKPADZOOM", "MOUSEMOVE", "INBETWEEN_MOUSEMOVE", "NDOF_MOTION"}


def quiet_image_library():
    """Send OpenImageIO's debug messages to the null device (unless a file is set)."""
    if not os.environ.get(OIIO_DEBUG_FILE):
        os.environ[OIIO_DEBUG_FILE] = os.devnull


class BakeSteps:
    """Mixin of an operator: ``run_bake(context, job)`` runs ``job`` and then returns
    ``self.baked(context, info)`` (the operator's own ending). ``self._modal`` set by invoke
    asks for the modal run."""

    cancel_message = "Bake Transfer cancelled: nothing changed"

    def run_bake(self, context, job):
        self._job = job
        window_manager = context.window_manager
        window_manager.progress_begin(0, job.steps)
        modal, self._modal = getattr(self, "_modal", False), False  # a redo runs at once
        if not modal or bpy.app.background or context.window is None:
            try:
                while job.done < job.steps:
                    job.step()
                    window_manager.progress_update(job.done)
            finally:
                window_manager.progress_end()
            return self._finish_bake(context)
        self._timer = window_manager.event_timer_add(0.05, window=context.window)
        # A handler of the window: the region that ran execute (a dialog's) may close after it.
        with context.temp_override(area=None, region=None):
            window_manager.modal_handler_add(self)
        self._status(context)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        """One basis world per timer event; Esc stops between them (nothing stored)."""
        if event.type == "ESC":
            self._job.cancel()
            self._end(context)
            self.report({"WARNING"}, self.cancel_message)
            return {"CANCELLED"}
        if event.type != "TIMER":
            # the scene stays as it is while the bake runs; the view can still be moved
            return {"PASS_THROUGH"} if event.type in NAVIGATION_EVENTS else {"RUNNING_MODAL"}
        try:
            self._job.step()
        except (bake.TransferError, RuntimeError, ReferenceError) as error:
            self._end(context)
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        context.window_manager.progress_update(self._job.done)
        self._status(context)
        if self._job.done < self._job.steps:
            return {"RUNNING_MODAL"}
        self._end(context)
        return self._finish_bake(context)

    def _status(self, context):
        if context.workspace is not None:
            context.workspace.status_text_set(
                f"Baking the transfer: {self._job.done}/{self._job.steps} done. Esc to cancel")

    def _end(self, context):
        window_manager = context.window_manager
        if getattr(self, "_timer", None) is not None:
            window_manager.event_timer_remove(self._timer)
            self._timer = None
        window_manager.progress_end()
        if context.workspace is not None:
            context.workspace.status_text_set(None)

    def _finish_bake(self, context):
        try:
            info = self._job.finish()
        except (bake.TransferError, RuntimeError) as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        return self.baked(context, info)


def baked_line(info):
    """The bake's report: objects, vertices, corners, texels, samples, time and rates."""
    return (f"Baked the transfer of {len(info.objects)} object(s): {info.vertices} vertices, "
            f"{info.corners} corners, {info.texels} texels, {info.samples} samples, "
            f"{info.seconds:.1f} s{info.rates()}")
