"""Presets: export/import through the operators and ``preset_io``, the four export formats,
overwrite refusal and atomic writes, malformed files, shipped and user presets, the menu.

User presets live in Blender's user preset folder, which ``bpy.utils.user_resource`` derives
from BLENDER_USER_RESOURCES each time it is called (checked on 4.2 and 5.0): the ``user_dir``
fixture points it into ``tmp_path`` and checks that it did, so the real folder is never used.
"""

import json
import math
import os
from datetime import date
from pathlib import Path
from types import SimpleNamespace

import bpy
import numpy as np
import pytest
from blender_files import SCRIPT, WORLD, write_constant_exr
from blender_scenes import environment_world
from numpy.testing import assert_allclose, assert_array_equal

from sh_lighting.blender.data import compat, scene_data
from sh_lighting.blender.ui import panels, presets as presets_ui
from sh_lighting.blender.presets import preset_io
from sh_lighting.formats import interop
from sh_lighting.formats.presets import PresetError, read_preset, write_preset
from tools import make_presets, package
from ui_layout import RecordingLayout

pytestmark = pytest.mark.blender

ROOT = Path(__file__).resolve().parents[3]
KNOWN = np.arange(27, dtype=np.float64).reshape(9, 3) / 10.0 - 1.0  # signed, some > 1
OTHER = np.linspace(-0.7, 2.3, 27).reshape(9, 3)
# The interop round trips are exact SH rotations (entries snapped to 0, ±½, ±√3/2, ±1) and
# one scale per band: a few float64 roundings.
ROUND_TRIP = 1e-13
FORMATS = ("SH_LIGHTING", "THREEJS", "GLTF", "FILAMENT")
# The presets tools/make_presets.py writes: the paper's three Figure 2 probes and the 8 HDRIs
# inside bpy (its lists, not a glob of the folder the test then reads back).
SHIPPED = sorted([*make_presets.FIGURE2_NAMES, *make_presets.HDRI_NAMES])


def read_back(path, fmt):
    """(9, 3) Blender-axes L_lm from an exported file, with the core's importers."""
    text = Path(path).read_text(encoding="utf-8")
    if fmt == "SH_LIGHTING":
        return read_preset(path)[0]
    if fmt == "FILAMENT":
        return interop.from_filament_sh_txt(text)
    data = json.loads(text)
    if fmt == "THREEJS":
        assert data["metadata"]["type"] == "Object"
        probe = data["object"]
        assert probe["type"] == "LightProbe" and probe["intensity"] == 1.0
        assert len(probe["sh"]) == 27
        return interop.from_threejs_sh(probe["sh"])
    (light,) = data["extensions"]["EXT_lights_image_based"]["lights"]
    assert light["intensity"] == 1.0 and light["rotation"] == [0.0, 0.0, 0.0, 1.0]
    assert len(light["specularImages"]) == 4 and light["specularImageSize"] == 64
    return interop.from_gltf_irradiance_coefficients(light["irradianceCoefficients"])


def leftovers(folder):
    """Hidden temporary files a failed write could have left behind."""
    return sorted(p.name for p in Path(folder).iterdir() if p.name.startswith("."))


@pytest.fixture
def scene(addon):
    scene = bpy.context.scene
    scene_data.store(scene, KNOWN, SCRIPT)
    return scene


@pytest.fixture
def user_dir(tmp_path, monkeypatch):
    resources = tmp_path / "user_resources"
    monkeypatch.setenv("BLENDER_USER_RESOURCES", str(resources))
    monkeypatch.delenv("BLENDER_USER_SCRIPTS", raising=False)
    folder = preset_io.user_preset_dir()
    assert folder == resources / "scripts" / "presets" / "sh_lighting"
    return folder


# --- export / import round trips -----------------------------------------------------------


@pytest.mark.parametrize("fmt", FORMATS)
def test_export_operator_writes_each_format_readable_back(scene, tmp_path, fmt):
    ext = preset_io.FORMATS[fmt.lower()][1]
    path = tmp_path / f"lighting{ext}"
    result = bpy.ops.shlight.export_preset("EXEC_DEFAULT", filepath=str(path), export_format=fmt)
    assert result == {"FINISHED"}
    assert_allclose(read_back(path, fmt), KNOWN, rtol=0, atol=ROUND_TRIP)
    assert leftovers(tmp_path) == []


def test_formats_differ_as_documented(scene, tmp_path):
    """three.js holds radiance in y-up axes, glTF irradiance with (−1)^|m|, Filament pre-scaled:
    spot checks that the files are not all the same numbers."""
    for fmt in ("threejs", "gltf", "filament"):
        preset_io.export_preset(scene, tmp_path / f"x_{fmt}", fmt)
    sh = json.loads((tmp_path / "x_threejs").read_text())["object"]["sh"]
    # y-up: (x, y, z)_gltf = (x, z, -y)_blender, so L1-1 (y) of three.js is Blender's L10.
    assert_allclose(sh[3:6], KNOWN[2], atol=ROUND_TRIP)
    gltf = json.loads((tmp_path / "x_gltf").read_text())["extensions"]
    gltf = gltf["EXT_lights_image_based"]["lights"][0]["irradianceCoefficients"]
    assert_allclose(gltf[0], math.pi * KNOWN[0], atol=ROUND_TRIP)  # Â_0 = π, sign +
    assert_allclose(gltf[3], -2.0 * math.pi / 3.0 * KNOWN[3], atol=ROUND_TRIP)  # L11: −Â_1
    lines = (tmp_path / "x_filament").read_text().splitlines()
    assert len(lines) == 9 and lines[0].startswith("(") and "// L00" in lines[0]


def test_import_operator_round_trip_with_undo(scene, tmp_path):
    path = preset_io.export_preset(scene, tmp_path / "known.json")
    scene_data.store(scene, OTHER, SCRIPT)
    bpy.ops.ed.undo_push(message="before import")
    assert bpy.ops.shlight.import_preset("EXEC_DEFAULT", True, filepath=str(path)) == {
        "FINISHED"
    }
    assert_array_equal(scene_data.get_coefficients(bpy.context.scene), KNOWN)
    bpy.ops.ed.undo()
    assert_array_equal(scene_data.get_coefficients(bpy.context.scene), OTHER)


def test_preset_io_round_trip_and_metadata(scene, tmp_path):
    path = preset_io.export_preset(scene, tmp_path / "mine.json", metadata={"notes": "hi"})
    coeffs, metadata = read_preset(path)
    assert_array_equal(coeffs, KNOWN)  # JSON floats are written exactly
    assert metadata["name"] == "mine" and metadata["notes"] == "hi"
    assert metadata["created"] == date.today().isoformat()
    assert "source" not in metadata  # the scene's values were not computed from its world
    scene_data.store(scene, OTHER, SCRIPT)
    assert_array_equal(preset_io.import_preset(scene, path), KNOWN)
    assert_array_equal(scene_data.get_coefficients(scene), KNOWN)


def test_import_keeps_the_reset_values(scene, tmp_path):
    scene_data.store(scene, OTHER, WORLD)
    path = write_preset(tmp_path / "p.json", KNOWN)
    preset_io.import_preset(scene, path)
    assert_array_equal(scene_data.get_coefficients(scene), KNOWN)
    assert_array_equal(scene_data.get_computed(scene), OTHER)


def test_metadata_names_the_world_image_while_the_values_are_the_computed_ones(addon, tmp_path):
    scene = bpy.context.scene
    exr = write_constant_exr(tmp_path / "sky.exr", (0.5, 1.0, 2.0))
    background = environment_world(scene, exr, 3.0, name="W").node_tree.nodes["Background"]
    assert bpy.ops.shlight.compute_from_world() == {"FINISHED"}

    metadata = read_preset(preset_io.export_preset(scene, tmp_path / "a.json"))[1]
    assert metadata["source"] == "sky.exr"  # the file name only: no local path in shared files
    assert metadata["strength"] == 3.0 and metadata["mapping"] == [0.0, 0.0, 0.0]
    background.inputs["Strength"].default_value = 5.0  # changed since, not recomputed:
    metadata = read_preset(preset_io.export_preset(scene, tmp_path / "a2.json"))[1]
    assert metadata["strength"] == 3.0  # what the values were computed from (provenance)

    coeffs = scene_data.get_coefficients(scene)
    coeffs[0, 0] += 0.25  # an edit: the image is no longer the whole story
    scene_data.store(scene, coeffs, SCRIPT)
    metadata = read_preset(preset_io.export_preset(scene, tmp_path / "b.json"))[1]
    assert "source" not in metadata and "strength" not in metadata


def test_gltf_export_refuses_to_pair_one_image_s_coefficients_with_another_s_cube(
        addon, tmp_path):
    """Computed from A, the world switched to B: the cube was B's, the
    metadata A's. Now the export says so and writes nothing; computed again, it pairs B
    with B."""
    from sh_lighting.blender.world import compute

    scene = bpy.context.scene
    world = environment_world(scene, write_constant_exr(tmp_path / "a.exr", (1,) * 3), name="W")
    texture = world.node_tree.nodes["Environment Texture"]
    assert bpy.ops.shlight.compute_from_world() == {"FINISHED"}
    assert compute.world_match(scene).source is not None
    texture.image = bpy.data.images.load(str(write_constant_exr(tmp_path / "b.exr", (4,) * 3)))
    match = compute.world_match(scene)
    assert match.source is None and match.stale
    assert "image 'b.exr' now, 'a.exr' then" in match.reason
    out = tmp_path / "env.gltf"
    with pytest.raises(ValueError, match=(
            r"^the coefficients were computed from image 'a.exr' of world 'W', and it changed "
            r"since Compute from World: image 'b.exr' now, 'a.exr' then.*: the specular cube "
            r"would not match them; press Compute from World")):
        preset_io.export_preset(scene, out, "gltf")
    assert not out.exists()
    assert bpy.ops.shlight.compute_from_world() == {"FINISHED"}
    text = preset_io.export_preset(scene, out, "gltf").read_text()
    assert '"specular_source": "world image"' in text and "b.exr" in text


# --- refusals ---------------------------------------------------------------------------


@pytest.mark.parametrize("fmt", FORMATS)
def test_export_refuses_to_overwrite_unless_asked(scene, tmp_path, fmt):
    path = tmp_path / "taken.json"
    path.write_text("keep me")
    with pytest.raises(RuntimeError, match="already exists"):
        bpy.ops.shlight.export_preset(filepath=str(path), export_format=fmt)
    assert path.read_text() == "keep me"
    with pytest.raises(FileExistsError):
        preset_io.export_preset(scene, path, fmt.lower())
    assert path.read_text() == "keep me"
    assert bpy.ops.shlight.export_preset(
        filepath=str(path), export_format=fmt, overwrite=True
    ) == {"FINISHED"}
    assert_allclose(read_back(path, fmt), KNOWN, atol=ROUND_TRIP)
    assert leftovers(tmp_path) == []


def test_export_without_coefficients_is_refused_with_a_reason(addon, tmp_path):
    with pytest.raises(RuntimeError, match="No SH coefficients yet"):
        bpy.ops.shlight.export_preset(filepath=str(tmp_path / "x.json"))
    with pytest.raises(LookupError):
        preset_io.export_preset(bpy.context.scene, tmp_path / "x.json")
    assert list(tmp_path.iterdir()) == []


def _forest_with_nan():
    """forest.json with its first L00 value replaced by NaN (what json.dumps writes for it)."""
    data = json.loads((ROOT / "presets" / "forest.json").read_text())
    data["coefficients"]["L00"][0] = math.nan
    return json.dumps(data)


MALFORMED = {
    "not_json": '{"format": "sh_lighting.preset", ',
    "missing_coefficient": json.dumps({
        "format": "sh_lighting.preset", "version": 1, "frame": "blender_world_z_up",
        "coefficients": {f"L{i}": [0, 0, 0] for i in range(8)},
    }),
    "nan": _forest_with_nan(),
    "other_frame": (ROOT / "presets" / "forest.json").read_text().replace(
        "blender_world_z_up", "gltf_y_up"),
    "three_js_file": json.dumps({"sh": list(range(27))}),
}


@pytest.mark.parametrize("case", [*MALFORMED, "binary", "folder", "missing"])
@pytest.mark.parametrize("operator", ["import_preset", "load_preset"])
def test_malformed_preset_is_an_error_and_changes_nothing(scene, tmp_path, case, operator):
    scene_data.store(scene, KNOWN, WORLD)
    path = tmp_path / f"{case}.json"
    if case in MALFORMED:
        path.write_text(MALFORMED[case])
    elif case == "binary":
        path.write_bytes(b"\x89PNG\r\n\x1a\n\xff\xfe")
    elif case == "folder":
        path.mkdir()
    with pytest.raises(RuntimeError, match="Preset not loaded, nothing changed"):
        getattr(bpy.ops.shlight, operator)(filepath=str(path))
    with pytest.raises((PresetError, OSError)):
        preset_io.import_preset(scene, path)
    assert_array_equal(scene_data.get_coefficients(scene), KNOWN)
    assert_array_equal(scene_data.get_computed(scene), KNOWN)


# --- shipped and user presets --------------------------------------------------------------


def test_shipped_presets_are_listed_and_load(scene):
    shipped = preset_io.shipped_presets()
    assert len(SHIPPED) == 11
    assert sorted(p.stem for p in (ROOT / "presets").glob("*.json")) == SHIPPED  # all made
    assert list(shipped) == sorted(shipped, key=str.lower)
    assert list(shipped) == sorted(SHIPPED, key=str.lower)
    path = shipped["forest"]
    assert bpy.ops.shlight.load_preset(filepath=str(path)) == {"FINISHED"}
    assert_array_equal(scene_data.get_coefficients(scene), read_preset(path)[0])
    assert presets_ui.menu_label(scene) == "Forest"  # shipped names are title-cased
    assert scene_data.provenance(scene)["source"] == "PRESET"


def test_preset_menu_label_belongs_to_the_scene_and_its_values(scene, user_dir, tmp_path):
    forest = preset_io.shipped_presets()["forest"]
    assert presets_ui.menu_label(scene) == "Presets"
    assert bpy.ops.shlight.load_preset(filepath=str(forest)) == {"FINISHED"}
    assert presets_ui.menu_label(scene) == "Forest"
    other = bpy.data.scenes.new("New scene")  # a new scene has loaded no preset
    assert presets_ui.menu_label(other) == "Presets"
    assert presets_ui.menu_label(scene) == "Forest"
    bpy.ops.shlight.exposure(stops=1.0)  # a design edit: the values are no longer the preset
    assert presets_ui.menu_label(scene) == "Presets"
    user_dir.mkdir(parents=True)
    mine = write_preset(user_dir / "mine.json", KNOWN)
    assert bpy.ops.shlight.load_preset(filepath=str(mine)) == {"FINISHED"}
    assert presets_ui.menu_label(scene) == "mine"
    assert bpy.ops.shlight.preset_remove(name="mine") == {"FINISHED"}
    assert presets_ui.menu_label(scene) == "Presets"  # a deleted preset is not shown
    scene.world = bpy.data.worlds.new("Lit")
    compat.ensure_node_tree(scene.world).nodes["Background"].inputs["Color"].default_value = (
        1.0, 1.0, 1.0, 1.0
    )
    assert bpy.ops.shlight.load_preset(filepath=str(forest)) == {"FINISHED"}
    tmp_path.joinpath("c").mkdir()
    image = write_constant_exr(tmp_path / "c" / "white.exr", (1.0, 1.0, 1.0))
    env = scene.world.node_tree.nodes.new("ShaderNodeTexEnvironment")
    env.image = bpy.data.images.load(image)
    scene.world.node_tree.links.new(
        env.outputs["Color"], scene.world.node_tree.nodes["Background"].inputs["Color"]
    )
    assert bpy.ops.shlight.compute_from_world() == {"FINISHED"}
    assert presets_ui.menu_label(scene) == "Presets"  # Compute replaced the preset's values


def test_package_ships_the_presets_where_preset_io_looks(tmp_path, monkeypatch):
    staged = package.stage(tmp_path / "sh_lighting")
    assert sorted(p.stem for p in (staged / "presets").glob("*.json")) == SHIPPED
    monkeypatch.setattr(preset_io, "_PACKAGE_DIR", staged)
    assert preset_io.shipped_preset_dir() == staged / "presets"
    assert list(preset_io.shipped_presets()) == SHIPPED


def test_user_presets_add_list_and_remove(scene, user_dir):
    assert preset_io.user_presets() == {}
    assert bpy.ops.shlight.preset_add(name="  My warm / studio! ") == {"FINISHED"}
    path = user_dir / "My_warm_studio.json"
    coeffs, metadata = read_preset(path)
    assert_array_equal(coeffs, KNOWN)
    assert metadata["name"] == "My warm / studio!"
    assert preset_io.user_presets() == {"My_warm_studio": path}

    scene_data.store(scene, OTHER, SCRIPT)
    with pytest.raises(RuntimeError, match="already exists"):
        bpy.ops.shlight.preset_add(name="My warm / studio!")
    assert_array_equal(read_preset(path)[0], KNOWN)
    assert bpy.ops.shlight.preset_add(name="My warm / studio!", overwrite=True) == {"FINISHED"}
    assert_array_equal(read_preset(path)[0], OTHER)

    with pytest.raises(RuntimeError, match="no letters or digits"):
        bpy.ops.shlight.preset_add(name=" /// ")
    assert bpy.ops.shlight.preset_remove(name="My_warm_studio") == {"FINISHED"}
    assert not path.exists() and preset_io.user_presets() == {}
    with pytest.raises(RuntimeError, match="no user preset"):
        bpy.ops.shlight.preset_remove(name="My_warm_studio")


def test_a_preset_dropped_in_by_hand_keeps_its_name_and_can_be_removed(scene, user_dir):
    user_dir.mkdir(parents=True)
    path = write_preset(user_dir / "Sky blue.json", KNOWN)
    assert preset_io.user_presets() == {"Sky blue": path}
    assert bpy.ops.shlight.load_preset(filepath=str(path)) == {"FINISHED"}
    assert presets_ui.menu_label(scene) == "Sky blue"  # user names keep their case
    assert preset_io.remove_user_preset("Sky blue") == path
    assert not path.exists()


def test_shipped_presets_cannot_be_removed(scene, user_dir):
    shipped = preset_io.shipped_presets()["forest"]
    with pytest.raises(RuntimeError, match="shipped presets cannot be removed"):
        bpy.ops.shlight.preset_remove(name="forest")
    with pytest.raises(PermissionError):
        preset_io.remove_user_preset("forest")
    assert shipped.is_file()


@pytest.mark.parametrize(
    "resource", ["", os.path.join("presets", "sh_lighting")], ids=["empty", "relative"]
)
def test_no_user_folder_from_blender_writes_nothing_in_the_working_directory(
    scene, tmp_path, monkeypatch, resource
):
    """``user_resource`` gives "" when it fails; that (or any relative path) is no folder, not
    the working directory: nothing is listed, saved or removed there."""
    monkeypatch.chdir(tmp_path)
    decoy = write_preset(tmp_path / "Late_Sun.json", OTHER)  # what "." would hold
    monkeypatch.setattr(bpy.utils, "user_resource", lambda *args, **kwargs: resource)
    assert preset_io.user_preset_dir() is None
    assert preset_io.user_presets() == {}
    with pytest.raises(OSError, match="no user scripts folder"):
        preset_io.save_user_preset(scene, "Late Sun", overwrite=True)
    with pytest.raises(RuntimeError, match="Preset not saved: .*no user scripts folder"):
        bpy.ops.shlight.preset_add(name="Late Sun", overwrite=True)
    with pytest.raises(FileNotFoundError, match="no user preset"):
        preset_io.remove_user_preset("Late_Sun")
    assert list(tmp_path.iterdir()) == [decoy]
    assert_array_equal(read_preset(decoy)[0], OTHER)


def test_a_user_folder_that_cannot_be_created_is_a_clear_error(scene, user_dir):
    user_dir.parent.mkdir(parents=True)
    user_dir.write_text("a file where the folder should be")
    with pytest.raises(OSError, match="cannot create the user preset folder"):
        preset_io.save_user_preset(scene, "Late Sun")
    assert user_dir.read_text() == "a file where the folder should be"


# --- the menu and panels -------------------------------------------------------------------


def test_menu_lists_shipped_then_user_presets_with_remove_buttons(scene, user_dir):
    preset_io.save_user_preset(scene, "Late Sun")
    layout = RecordingLayout()
    presets_ui.draw_preset_menu(layout)
    operators = layout.of("operator")
    loads = [(kw["text"], props.filepath) for _k, op, props, kw in operators
             if op == presets_ui.LOAD]
    removes = [props.name for _k, op, props, _kw in operators if op == presets_ui.REMOVE]
    shipped = preset_io.shipped_presets()
    assert [text for text, _path in loads[: len(shipped)]] == [
        "City", "Courtyard", "Eucalyptus Grove", "Forest", "Grace Cathedral", "Interior",
        "Night", "St Peters Basilica", "Studio", "Sunrise", "Sunset",
    ]
    assert [path for _text, path in loads[: len(shipped)]] == [str(p) for p in shipped.values()]
    assert loads[len(shipped):] == [("Late Sun", str(user_dir / "Late_Sun.json"))]
    assert removes == ["Late_Sun"]  # never one for a shipped preset
    # Blender's preset popovers: each user preset's "−" right after it, then a name field + "+".
    order = [op for _k, op, _p, _kw in operators]
    assert order[order.index(presets_ui.REMOVE) - 1] == presets_ui.LOAD
    name_field = [c for c in layout.of("prop") if c[2] == presets_ui.PRESET_NAME]
    assert len(name_field) == 1 and order[len(loads) + 1] == presets_ui.ADD
    assert order[-1] == presets_ui.IMPORT
    assert [c[1] for c in layout.of("menu")] == ["SHLIGHT_MT_export"]
    for _kind, idname, props, _kw in operators:  # what the menu sets exists on the operator
        rna = getattr(bpy.ops.shlight, idname.split(".")[1]).get_rna_type()
        assert set(vars(props)) <= set(rna.properties.keys()), idname


def test_presets_sit_in_the_header_of_both_main_panels(addon):
    layout = RecordingLayout()
    panels.draw_presets_header(layout, bpy.context)
    assert [c[1] for c in layout.of("popover")] == ["SHLIGHT_PT_presets"]
    assert layout.of("popover")[0][2]["icon"] == "PRESET"
    assert presets_ui.SHLIGHT_PT_presets.bl_region_type == "HEADER"
    for cls in (panels.SHLIGHT_PT_world, panels.SHLIGHT_PT_view3d):
        assert hasattr(cls, "draw_header_preset")


def test_one_export_operator_with_a_format_choice_and_a_default_name_per_format(
        scene, tmp_path):
    """One operator (was five); three.js proposed the SH preset's file name (the field
    turned red, nothing written) and its button label was cut."""
    assert not [name for name in dir(bpy.types) if name.startswith("SHLIGHT_OT_export_")
                and name != "SHLIGHT_OT_export_preset"]
    assert presets_ui.SHLIGHT_OT_export_preset.bl_label == "Export"
    layout = RecordingLayout()
    presets_ui.SHLIGHT_MT_export.draw(SimpleNamespace(layout=layout), bpy.context)
    entries = layout.of("operator")
    assert [c[1] for c in entries] == [presets_ui.EXPORT] * 4
    assert [c[2].export_format for c in entries] == ["SH_LIGHTING", "THREEJS", "GLTF", "FILAMENT"]
    assert [c[3]["text"] for c in entries] == [
        f"{fmt.label} ({fmt.extension})" for fmt in preset_io.FORMATS.values()]

    blend = str(tmp_path / "shot.blend")
    names = {key: presets_ui.default_file_name(blend, key) for key in preset_io.FORMATS}
    assert names == {"sh_lighting": "shot_sh_preset.json",
                     "threejs": "shot_threejs_lightprobe.json",
                     "gltf": "shot_environment.gltf", "filament": "shot_sh.txt"}
    # the user picks SH preset, exports, then picks three.js: a name of its own, both written
    for key in preset_io.FORMATS:
        path = tmp_path / presets_ui.default_file_name("", key)
        assert bpy.ops.shlight.export_preset(
            filepath=str(path), export_format=key.upper()) == {"FINISHED"}
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        presets_ui.default_file_name("", key) for key in preset_io.FORMATS)
    fake = SimpleNamespace(export_format="THREEJS",
                           filepath=str(tmp_path / "untitled_sh_preset.json"))
    assert presets_ui.SHLIGHT_OT_export_preset.check(fake, None)
    assert fake.filepath == str(tmp_path / "untitled_threejs_lightprobe.json")


def test_operators_that_change_the_scene_are_undoable_and_file_ones_are_not(addon):
    for idname in (presets_ui.LOAD, presets_ui.IMPORT):
        assert "UNDO" in getattr(bpy.ops.shlight, idname.split(".")[1]).bl_options
    for idname in (presets_ui.EXPORT, presets_ui.ADD, presets_ui.REMOVE):
        assert "UNDO" not in getattr(bpy.ops.shlight, idname.split(".")[1]).bl_options
    for cls in presets_ui.classes:
        assert cls.is_registered, cls.__name__
        if issubclass(cls, bpy.types.Operator):
            assert cls.__doc__, cls.__name__  # the operator's tooltip


@pytest.mark.parametrize(
    "fmt, given, expected",
    [
        ("FILAMENT", "/x/light.json", "/x/light.txt"),
        ("THREEJS", "/x/light.txt", "/x/light.json"),
        ("GLTF", "/x/light", "/x/light.gltf"),
        ("GLTF", "/x/light.json", "/x/light.gltf"),
        ("SH_LIGHTING", "/x/light.v2", "/x/light.v2.json"),
        ("SH_LIGHTING", "/x/light.json", "/x/light.json"),
    ],
)
def test_file_browser_gives_the_format_its_extension(fmt, given, expected):
    fake = SimpleNamespace(export_format=fmt, filepath=given)
    changed = presets_ui.SHLIGHT_OT_export_preset.check(fake, None)
    assert fake.filepath == expected
    assert changed == (given != expected)


def test_a_loaded_preset_is_reported_by_the_name_the_menu_shows(scene):
    """The name "Grace Cathedral", not the file stem "grace_cathedral"."""
    from blender_scenes import run_execute

    path = preset_io.shipped_presets()["grace_cathedral"]
    result, reports = run_execute(presets_ui.SHLIGHT_OT_load_preset, filepath=str(path))
    assert result == {"FINISHED"}
    assert reports == [({"INFO"}, "Loaded SH lighting preset 'Grace Cathedral'")]
