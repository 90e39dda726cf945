"""Which lights are the add-on's: only the lights Extract Lights made are ever
changed or deleted by it. A duplicate (Shift+D copies the object's custom properties), a light
linked from a library, or a look-alike an older file marked but whose name its record does not
hold, is the artist's; a light of ours that the artist renamed is still ours."""

import bpy
import numpy as np
import pytest
from blender_files import write_exr
from blender_scenes import environment_world, sunny_map

from sh_lighting import api
from sh_lighting.blender.data import scene_data
from sh_lighting.blender.design import lights

pytestmark = pytest.mark.blender
BLUE = (0.1, 0.2, 1.0)


@pytest.fixture
def sunny(addon, tmp_path):
    scene = bpy.context.scene
    pixels, _ = sunny_map()
    environment_world(scene, write_exr(tmp_path / "sun.exr", pixels), 1.5)
    return scene


def duplicate(obj, name=None):
    """What Shift+D does to a light: the object and its data copied (custom properties too),
    linked to the same collections."""
    copy = obj.copy()
    copy.data = obj.data.copy()
    for collection in obj.users_collection:
        collection.objects.link(copy)
    if name is not None:
        copy.name = name
    return copy


def test_a_duplicate_is_never_deleted_nor_taken_over(sunny):
    scene = sunny
    [name] = api.extract_lights(scene, count=1).lights
    fill = duplicate(scene.objects[name])
    fill.data.color, fill.data.energy = BLUE, 3.0
    fill.rotation_euler = (1.0, 0.5, 0.0)
    assert lights.extracted_lights(scene) == [scene.objects[name]]
    api.compute_from_world(scene)  # the whole world in the SH again: our light goes, not hers
    assert name not in scene.objects and fill.name in scene.objects
    again = api.extract_lights(scene, count=1)
    assert len(again.created) == 1 and fill.name not in again.lights
    assert tuple(fill.data.color) == pytest.approx(BLUE) and fill.data.energy == 3.0
    assert tuple(fill.rotation_euler) == pytest.approx((1.0, 0.5, 0.0))
    assert bpy.ops.shlight.compute_from_world() == {"FINISHED"}  # the operator too
    assert [o.name for o in bpy.context.scene.objects if o.type == "LIGHT"] == [fill.name]


def test_bpy_ops_duplicate_and_rename(sunny, tmp_path):
    scene = sunny
    [name] = api.extract_lights(scene, count=1).lights
    ours = scene.objects[name]
    bpy.ops.object.select_all(action="DESELECT")
    ours.select_set(True)
    bpy.context.view_layer.objects.active = ours
    assert bpy.ops.object.duplicate() == {"FINISHED"}
    [copy] = [o for o in scene.objects if o.type == "LIGHT" and o != ours]
    copy.data.energy = 7.0
    ours.name = "Key"  # the artist renames ours: it is still ours
    again = api.extract_lights(scene, count=1)
    assert again.lights == ["Key"] and again.created == [] and again.removed == []
    assert copy.data.energy == 7.0
    copy_name = copy.name
    # a saved and reopened file knows the same
    path = str(tmp_path / "lights.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.open_mainfile(filepath=path)
    scene = bpy.context.scene
    assert [o.name for o in lights.extracted_lights(scene)] == ["Key"]
    assert api.extract_lights(scene, count=1).created == []
    api.compute_from_world(scene)
    assert [o.name for o in scene.objects if o.type == "LIGHT"] == [copy_name]


def legacy_light(scene, name, marker, value):
    """A light as an older version left it: marked by a custom property, no registry."""
    obj = bpy.data.objects.new(name, bpy.data.lights.new(name, type="SUN"))
    obj[marker] = value
    scene.collection.objects.link(obj)
    return obj


def test_an_old_files_lights_are_recognised_by_name_not_their_duplicates(sunny):
    scene = sunny
    pixels_record = {"source": "WORLD", "world": scene.world.name, "method": "IMAGE",
                     "image": "sun.exr"}
    old = legacy_light(scene, "SH Light 1", "sh_lighting_light", 0)
    old_copy = duplicate(old, "SH Light 1.001")  # a Shift+D in the old version: marker copied
    scene_data.store(scene, np.ones((9, 3)), {**pixels_record, "lights": [old.name],
                                              "sun": old.name})
    assert lights.extracted_lights(scene) == [old]
    info = api.extract_lights(scene, count=1)
    assert info.lights == [old.name] and info.created == []  # updated in place
    assert old_copy.data.energy == 10.0  # Blender's default: untouched
    api.compute_from_world(scene)
    assert [o.name for o in scene.objects if o.type == "LIGHT"] == [old_copy.name]


def test_an_old_split_sun_is_the_one_light(sunny):
    scene = sunny
    sun = legacy_light(scene, "SH Sun", "sh_lighting_sun", True)
    scene_data.store(scene, np.ones((9, 3)), {"source": "WORLD", "sun": sun.name})
    info = api.split_sun(scene)
    assert info.lights == ["SH Sun"] and info.created == [] and "sh_lighting_sun" not in sun
    assert sun.data.energy != 10.0  # the sun's strength now


def test_a_library_light_is_never_changed(sunny, tmp_path):
    scene = sunny
    library = legacy_light(scene, "SH Sun", "sh_lighting_sun", True)
    path = str(tmp_path / "library.blend")
    bpy.data.libraries.write(path, {library})
    bpy.data.objects.remove(library)
    with bpy.data.libraries.load(path, link=True) as (source, target):
        target.objects = ["SH Sun"]
    [linked] = target.objects
    scene.collection.objects.link(linked)
    assert linked.library is not None
    scene_data.store(scene, np.ones((9, 3)), {"source": "WORLD", "sun": "SH Sun"})
    assert lights.extracted_lights(scene) == []
    info = api.extract_lights(scene, count=1)
    assert len(info.created) == 1 and linked.data.energy == 10.0
    api.compute_from_world(scene)
    assert [o for o in scene.objects if o.type == "LIGHT"] == [linked]


def test_a_linked_duplicate_keeps_its_light_data(sunny):
    """Alt+D shares the light data: updating ours must not change the artist's copy."""
    scene = sunny
    [name] = api.extract_lights(scene, count=1).lights
    ours = scene.objects[name]
    linked = ours.copy()  # the object copied, its light data shared
    scene.collection.objects.link(linked)
    linked.data.energy = 2.0
    shared = linked.data
    again = api.extract_lights(scene, count=1)
    assert again.lights == [name] and ours.data != shared and linked.data == shared
    assert shared.energy == 2.0 and ours.data.energy != 2.0
    api.compute_from_world(scene)
    assert [o.name for o in scene.objects if o.type == "LIGHT"] == [linked.name]
    assert linked.data.energy == 2.0


@pytest.mark.parametrize("garbage", ["abc", {"lights": [1, 2], "collection": 3}],
                         ids=["text", "not objects"])
def test_a_broken_registry_touches_nothing(sunny, garbage):
    scene = sunny
    artist = bpy.data.objects.new("Lamp", bpy.data.lights.new("Lamp", type="POINT"))
    scene.collection.objects.link(artist)
    scene[lights.REGISTRY] = garbage
    assert lights.extracted_lights(scene) == []
    info = api.extract_lights(scene, count=1)
    assert len(info.created) == 1 and artist.name in scene.objects
    api.compute_from_world(scene)
    assert [o.name for o in scene.objects if o.type == "LIGHT"] == ["Lamp"]
