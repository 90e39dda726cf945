"""The Match Photo dialog as an artist meets it: choosing the photo finds the ball and shows
it (the photo with the circle drawn, and a line), a failure keeps what was typed for the next
dialog, and a circle never given (radius 0) is not blamed on the photo."""

from types import SimpleNamespace

import bpy
import numpy as np
import pytest
from blender_files import write_png
from blender_scenes import run_execute

from benchmarks.photo_scene import SIZE, circle_of, grey_ball_scene, render_png
from sh_lighting.blender.ui import photo as photo_ui
from sh_lighting.blender.ui import previews


@pytest.fixture
def ball_photo(addon, tmp_path, hdri_dir):
    scene, _ = grey_ball_scene(hdri_dir / "courtyard.exr", samples=8)
    return scene, render_png(scene, tmp_path / "ball.png")


def props(**values):
    base = dict(filepath="", circle=(0.0, 0.0, 0.0), detected="")
    base.update(values)
    return SimpleNamespace(**base)


def test_choosing_the_photo_finds_the_ball_and_shows_it(ball_photo):
    _, path = ball_photo
    chosen = props(filepath=path)
    photo_ui.find_ball(chosen)
    cx, cy, r = circle_of("ORTHO")
    assert np.hypot(chosen.circle[0] - cx, chosen.circle[1] - cy) < 0.75
    assert chosen.circle[2] == pytest.approx(r, abs=1.0)
    assert chosen.detected.startswith("Ball found at (")
    preview = previews.photo(path, None, chosen.circle)
    pixels = previews.from_preview(preview)
    assert pixels.shape[:2] == (SIZE, SIZE)
    ring = np.all(np.abs(pixels[..., :3] - previews.RING) < 0.01, axis=-1)
    y, x = np.nonzero(ring)
    # the ring's pixels lie on the circle, all around it
    assert np.abs(np.hypot(x + 0.5 - cx, y + 0.5 - cy) - r).max() < 1.5
    assert ring.sum() > 4 * r
    # the dialog draws the line, the photo and the circle's field under it
    from ui_layout import RecordingLayout

    dialog = SimpleNamespace(layout=RecordingLayout(), prior="mirror", camera="SCENE",
                             **vars(chosen))
    photo_ui.SHLIGHT_OT_match_photo.draw(dialog, bpy.context)
    calls = dialog.layout.calls
    kinds = [c[0] for c in calls]
    assert kinds[:4] == ["prop", "label", "icon", "prop"]
    assert calls[1][1].startswith("Ball found at") and calls[3][2] == "circle"


def test_a_photo_without_a_ball_says_so_and_leaves_the_circle(addon, tmp_path):
    noise = write_png(tmp_path / "noise.png",
                      np.random.default_rng(3).integers(0, 255, (SIZE, SIZE, 3)))
    chosen = props(filepath=noise, circle=(1.0, 2.0, 3.0))
    photo_ui.find_ball(chosen)
    assert chosen.circle == (1.0, 2.0, 3.0)
    assert chosen.detected.startswith("! No ball found in 'noise.png'")
    missing = props(filepath=str(tmp_path / "nothing.png"))
    photo_ui.find_ball(missing)
    assert missing.detected.startswith("! ") and "does not exist" in missing.detected


def test_radius_0_asks_for_the_circle_and_a_failure_keeps_what_was_typed(ball_photo):
    scene, path = ball_photo
    wm = bpy.context.window_manager
    result, reports = run_execute(photo_ui.SHLIGHT_OT_match_photo, filepath=path,
                                  circle=(48.0, 48.0, 0.0))
    [(kinds, message)] = reports
    assert result == {"CANCELLED"} and kinds == {"ERROR"}
    assert "no circle yet" in message and "larger" not in message and "photo where" not in message
    typed = wm[photo_ui.TYPED]
    assert typed["filepath"] == path and list(typed["circle"]) == [48.0, 48.0, 0.0]
    # the next dialog starts from what was typed, the ball found again
    opened = []

    def dialog(operator, width):
        opened.append(operator)
        return {"RUNNING_MODAL"}

    context = SimpleNamespace(window_manager=_WM(wm, dialog))
    reopened = _Operator(photo_ui.find_ball, **vars(props(
        properties=SimpleNamespace(is_property_set=lambda name: False))))
    photo_ui.SHLIGHT_OT_match_photo.invoke(reopened, context, None)
    assert reopened.filepath == path and opened == [reopened]
    assert reopened.circle[2] == pytest.approx(circle_of("ORTHO")[2], abs=1.0)  # found again
    assert reopened.detected.startswith("Ball found at")
    assert photo_ui.TYPED not in wm
    # a success forgets it
    result, _ = run_execute(photo_ui.SHLIGHT_OT_match_photo, filepath=path,
                            circle=circle_of("ORTHO"), albedo=0.18, margin=0.05,
                            prior="mirror", camera="SCENE", direction=(0.0, 1.0, 0.0),
                            roll=0.0, projection="ORTHO", focal_mm=85.0, sensor_mm=36.0,
                            clip=0.0, chrome_filepath="", second_filepath="",
                            second_circle=(0.0, 0.0, 0.0), second_direction=(0.0, -1.0, 0.0),
                            second_roll=0.0)
    assert result == {"FINISHED"} and photo_ui.TYPED not in wm


class _WM:
    """The window manager's ID properties, and a dialog that records what it opens."""

    def __init__(self, wm, dialog):
        self.wm, self.invoke_props_dialog = wm, dialog

    def get(self, key):
        return self.wm.get(key)

    def __delitem__(self, key):
        del self.wm[key]


class _Operator:
    """Stands in for the operator in ``invoke``: setting ``filepath`` runs its update, as
    Blender does for a property typed in the dialog."""

    def __init__(self, path_update, **values):
        object.__setattr__(self, "_update", path_update)
        self.__dict__.update(values)

    def __setattr__(self, name, value):
        self.__dict__[name] = value
        if name == "filepath":
            self._update(self)
