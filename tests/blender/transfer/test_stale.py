"""Stale means stale (``blender/transfer/stale``): every change to what the bake saw makes the
status stale at once, also from a script that has not updated the view layer; changes the
bake did not see (a lamp, the camera) leave it OK."""

import bpy
import pytest

import transfer_scenes as ts
from sh_lighting.blender.transfer import bake


def _scene():
    """Ground and box baked (one sample: only the record matters here), the box in its own
    collection, a Sun and a camera besides."""
    scene = bpy.context.scene
    ground, box = ts.ground_and_box(4, 0)
    props = bpy.data.collections.new("Props")
    scene.collection.children.link(props)
    props.objects.link(box)
    scene.collection.objects.unlink(box)
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    scene.collection.objects.link(sun)
    ts.camera(scene)
    bpy.context.view_layer.update()
    bake.bake_transfer(scene, [ground], samples=1)
    assert bake.status(scene, ground)[0] == "OK"
    return scene, ground, box, props, sun


def _layer_collection(name):
    return bpy.context.view_layer.layer_collection.children[name]


def _shape_key_lift(box):
    box.shape_key_add(name="Basis")
    key = box.shape_key_add(name="Lift", from_mix=False)
    for point in key.data:
        point.co.z += 1.0
    key.value = 1.0


def _keyframes(box):
    box.keyframe_insert("location", frame=1)
    box.location.x += 1.0
    box.keyframe_insert("location", frame=10)
    box.location.x -= 1.0


# (what the user or a script does, how it is undone): each makes the bake stale at once.
CHANGES = {
    "object hidden from renders": (lambda s, b, c: setattr(b, "hide_render", True),
                                   lambda s, b, c: setattr(b, "hide_render", False)),
    "collection disabled in renders": (lambda s, b, c: setattr(c, "hide_render", True),
                                       lambda s, b, c: setattr(c, "hide_render", False)),
    "collection excluded from the view layer": (
        lambda s, b, c: setattr(_layer_collection(c.name), "exclude", True),
        lambda s, b, c: setattr(_layer_collection(c.name), "exclude", False)),
    "Shadow ray visibility off": (lambda s, b, c: setattr(b, "visible_shadow", False),
                                  lambda s, b, c: setattr(b, "visible_shadow", True)),
    "Diffuse ray visibility off": (lambda s, b, c: setattr(b, "visible_diffuse", False),
                                   lambda s, b, c: setattr(b, "visible_diffuse", True)),
    "moved by a script, no view layer update": (
        lambda s, b, c: setattr(b.location, "x", b.location.x + 0.5),
        lambda s, b, c: setattr(b.location, "x", b.location.x - 0.5)),
    "shape key lifting it 1 m": (lambda s, b, c: _shape_key_lift(b),
                                 lambda s, b, c: b.shape_key_clear()),
    "Displace modifier": (
        lambda s, b, c: setattr(b.modifiers.new("Displace", "DISPLACE"), "strength", 1.0),
        lambda s, b, c: b.modifiers.remove(b.modifiers["Displace"])),
    "animated: another frame": (lambda s, b, c: (_keyframes(b), s.frame_set(10)),
                                lambda s, b, c: (s.frame_set(1), b.animation_data_clear())),
}


@pytest.mark.parametrize("name", list(CHANGES))
def test_each_change_to_what_the_bake_saw_makes_it_stale_at_once(name):
    scene, ground, box, props, sun = _scene()
    change, undo = CHANGES[name]
    change(scene, box, props)
    assert bake.status(scene, ground)[0] == "STALE", name
    undo(scene, box, props)
    assert bake.status(scene, ground)[0] == "OK", name


def test_the_baked_objects_own_shape_key_makes_it_stale():
    scene, ground, box, props, sun = _scene()
    _shape_key_lift(ground)
    state, message = bake.status(scene, ground)
    assert state == "STALE" and "edited or moved" in message, message


def test_lamps_the_camera_and_the_frame_do_not_make_it_stale():
    scene, ground, box, props, sun = _scene()
    sun.location = (3.0, 2.0, 5.0)
    sun.rotation_euler.x = 0.7
    sun.hide_render = True
    scene.camera.location.z += 1.0
    scene.frame_set(7)  # nothing is animated
    assert bake.status(scene, ground)[0] == "OK"


def test_api_transfer_status_sees_a_script_move_at_once():
    from sh_lighting import api

    scene, ground, box, props, sun = _scene()
    box.location.z += 1.0  # matrix_world is not evaluated yet
    assert api.transfer_status(scene, ground)[0] == "STALE"
