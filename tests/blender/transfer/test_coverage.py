"""Whether a receiving mesh has corners where the shadows fall (``blender/transfer/coverage``):
a plain 4-vertex floor under a cube gets no contact shadow per corner, and the bake says so,
with what to do; a floor gridded finely enough is not warned about."""

import bmesh
import bpy

import transfer_scenes as ts
from sh_lighting.blender.transfer import bake, coverage


def _floor_and_cube(cuts):
    floor = ts.mesh_object("Floor", lambda bm: bmesh.ops.create_grid(
        bm, x_segments=cuts, y_segments=cuts, size=4.0))
    cube = ts.mesh_object("Cube", lambda bm: bmesh.ops.create_cube(bm, size=1.0),
                          (0.5, 0.0, 0.5))
    bpy.context.view_layer.update()
    return floor, cube


def test_a_plain_floor_under_a_cube_is_warned_about_with_what_to_do():
    floor, cube = _floor_and_cube(1)  # the 4-vertex plane artists use
    assert len(floor.data.vertices) == 4
    scene = bpy.context.scene
    warnings = coverage.coarse_receivers(scene, [floor, cube])
    assert len(warnings) == 1, warnings
    text = warnings[0]
    assert text.startswith("'Floor' is too coarse for the shadow 'Cube' casts on it: 0 of its "
                           "vertices lie within "), text
    assert "subdivide it to edges of about 0.25 m" in text and "\n" not in text
    info = bake.bake_transfer(scene, [floor, cube], samples=1, store="CORNERS")
    assert warnings[0] in info.notes
    assert bake.record(floor)["coarse"] == warnings
    # By default such a floor is baked per texel instead, and the bake says so
    info = bake.bake_transfer(scene, [floor, cube], samples=1)
    assert info.texel_objects == ["Floor"] and not any("too coarse for the" in n
                                                       for n in info.notes)
    assert bake.record(floor)["coarse"] == [
        "'Floor' is baked per texel (too coarse for a shadow at its corners): 6.2 cm texels, "
        "a 256 × 256 atlas"]


def test_a_floor_gridded_finely_enough_is_not_warned_about():
    floor, cube = _floor_and_cube(32)  # 0.25 m edges
    assert coverage.coarse_receivers(bpy.context.scene, [floor, cube]) == []


def test_an_occluder_inside_the_receivers_box_but_away_from_its_faces_is_not_counted():
    """Two dense patches 6 m apart (one mesh) with a cube between them: the cube's shadow
    falls on neither."""
    def patches(bm):
        for x in (-3.0, 3.0):
            grid = bmesh.ops.create_grid(bm, x_segments=8, y_segments=8, size=0.5)
            bmesh.ops.translate(bm, verts=grid["verts"], vec=(x, 0.0, 0.0))

    ts.mesh_object("Patches", patches)
    ts.mesh_object("Cube", lambda bm: bmesh.ops.create_cube(bm, size=1.0), (0.0, 0.0, 0.5))
    bpy.context.view_layer.update()
    receiver = bpy.data.objects["Patches"]
    assert coverage.coarse_receivers(bpy.context.scene, [receiver]) == []


def test_a_dense_mesh_grazing_an_occluders_reach_is_not_warned_about():
    """Suzanne beside a sphere: a few of her faces cross the edge of the sphere's reach with
    no vertex inside it; her faces are small, so the shadow is carried."""
    ts.mesh_object("Sphere", lambda bm: bmesh.ops.create_uvsphere(
        bm, u_segments=32, v_segments=16, radius=0.5), (0.2, 1.2, 0.5))
    monkey = ts.mesh_object("Suzanne", lambda bm: bmesh.ops.create_monkey(bm), (1.2, -0.6, 0.45))
    monkey.rotation_euler = (0.0, 0.0, 0.5)
    bpy.context.view_layer.update()
    assert coverage.coarse_receivers(bpy.context.scene, [monkey]) == []
