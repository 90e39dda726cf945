"""The JSON preset format: round trips, every refusal with its message, atomic writes."""

import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sh_lighting.formats import presets
from sh_lighting.core.coefficients import FLOAT32_MAX
from sh_lighting.formats.presets import (
    PresetError,
    preset_from_dict,
    preset_from_json,
    preset_to_dict,
    preset_to_json,
    read_preset,
    write_preset,
)
from sh_lighting.core.sh import COEFFICIENT_NAMES

REPO = Path(__file__).resolve().parents[2]
COEFFS = np.random.default_rng(0).normal(size=(9, 3))
META = {
    "name": "Test light",
    "source": "/tmp/some.hdr",
    "mapping": [0.0, 0.5, 1.25],
    "strength": 2.0,
    "created": "2025-01-31",
    "error_estimate": {"mean": 0.004, "max": 0.02},
    "notes": "made in a test",
    "future_key": {"kept": [1, "two"]},
}


def valid_dict():
    return json.loads(preset_to_json(COEFFS, META))


def text_of(d):
    return json.dumps(d)


# --- round trips ---------------------------------------------------------------------------


def test_file_round_trip_is_bit_exact_and_keeps_metadata(tmp_path):
    assert set(presets.METADATA_KEYS) < set(META)  # every documented key, and one unknown
    path = write_preset(tmp_path / "a.json", COEFFS, META)
    coeffs, meta = read_preset(path)
    assert np.array_equal(coeffs, COEFFS)
    assert meta == META


def test_dict_round_trip_and_layout():
    d = preset_to_dict(COEFFS)
    header = (d["format"], d["version"], d["frame"])
    assert header == ("sh_lighting.preset", 1, "blender_world_z_up")
    assert list(d["coefficients"]) == list(COEFFICIENT_NAMES)
    assert "metadata" not in d
    coeffs, meta = preset_from_dict(d)
    assert np.array_equal(coeffs, COEFFS) and meta == {}


def test_text_puts_each_rgb_triple_on_one_line():
    lines = preset_to_json(COEFFS, META).splitlines()
    for name, row in zip(COEFFICIENT_NAMES, COEFFS):
        expected = f'    "{name}": [{row[0]!r}, {row[1]!r}, {row[2]!r}]'
        assert expected in lines or expected + "," in lines
    assert '  "format": "sh_lighting.preset",' in lines


def test_key_order_in_the_file_does_not_matter():
    d = valid_dict()
    d["coefficients"] = dict(reversed(list(d["coefficients"].items())))
    d = {k: d[k] for k in reversed(list(d))}
    assert np.array_equal(preset_from_json(text_of(d))[0], COEFFS)


# Every float64 that float32 holds without overflow (Blender renders in float32).
finite = st.floats(min_value=-FLOAT32_MAX, max_value=FLOAT32_MAX, width=64)


@settings(max_examples=40, deadline=None)
@given(st.lists(finite, min_size=27, max_size=27))
def test_any_finite_floats_round_trip_exactly(values):
    c = np.array(values).reshape(9, 3)
    assert np.array_equal(preset_from_json(preset_to_json(c))[0], c)


# --- refusals ------------------------------------------------------------------------------


def modified(**changes):
    d = valid_dict()
    for key, value in changes.items():
        if value is KeyError:
            del d[key]
        else:
            d[key] = value
    return text_of(d)


def with_coefficient(name, value):
    d = valid_dict()
    d["coefficients"][name] = value
    return text_of(d)


def valid_text_with(old, new):
    text = preset_to_json(COEFFS)
    assert old in text
    return text.replace(old, new, 1)


L10_ROW = f'"L10": [{COEFFS[2, 0]!r}, {COEFFS[2, 1]!r}, {COEFFS[2, 2]!r}]'

REFUSALS = [
    # (text, regular expression the message must match)
    ('{"format": "sh_lighting.preset",\n  "version": 1,\n}', r"not valid JSON at line 3, column 1"),
    ("", r"not valid JSON at line 1, column 1"),
    ("[1, 2, 3]", r"got a list.*not an sh_lighting preset"),
    (modified(format="three.js"), r"\"format\" is 'three.js', expected \"sh_lighting.preset\""),
    (modified(format=KeyError), r"no \"format\" key"),
    (modified(version=2), r"version 2 is not supported.*newer sh_lighting: update the add-on"),
    (modified(version=0), r"version 0 is not supported"),
    (modified(version="1"), r"\"version\" is '1': it must be the whole number 1"),
    (modified(version=True), r"\"version\" is True"),
    (modified(version=KeyError), r"no \"version\" key: write \"version\": 1"),
    (modified(frame="paper_y_up"), r"\"frame\" is 'paper_y_up'.*paper_to_blender"),
    (modified(frame=KeyError), r"no \"frame\" key, but presets.*y_up_to_blender"),
    (modified(extra=1), r"unknown top-level key\(s\) 'extra'.*\"metadata\""),
    (modified(coefficients=KeyError), r"no \"coefficients\" object"),
    (modified(coefficients=[[0, 0, 0]] * 9), r"\"coefficients\" is a list: it must be an object"),
    (with_coefficient("L3-1", [0, 0, 0]), r"unknown 'L3-1'.*exactly the nine coefficients"),
    (with_coefficient("L10", [1.0, 2.0]), r"coefficient L10 has 2 values, not 3: each row is \[r, g, b\]"),
    (with_coefficient("L10", [1.0, 2.0, 3.0, 4.0]), r"coefficient L10 has 4 values"),
    (with_coefficient("L10", 1.0), r"coefficient L10 is float \(1.0\), not \[r, g, b\]"),
    (with_coefficient("L10", [1.0, "2", 3.0]), r"L10 channel G is a string \('2'\), not a number"),
    (with_coefficient("L10", [1.0, None, 3.0]), r"L10 channel G is None \(null\)"),
    (with_coefficient("L10", [1.0, 2.0, True]), r"L10 channel B is a boolean"),
    (valid_text_with(L10_ROW, '"L10": [NaN, 0, 0]'), r"literal NaN, which is not valid JSON"),
    (valid_text_with(L10_ROW, '"L10": [0, Infinity, 0]'), r"literal Infinity"),
    (valid_text_with(L10_ROW, '"L10": [0, 0, -Infinity]'), r"literal -Infinity"),
    (valid_text_with(L10_ROW, '"L10": [1e999, 0, 0]'), r"L10 channel R is inf: NaN and infinite"),
    (valid_text_with(L10_ROW, f'"L10": [-{10**400}, 0, 0]'), r"L10 channel R is -inf"),
    (valid_text_with(L10_ROW, '"L10": [1e39, 0, 0]'), r"L10 channel R is 1e\+39, beyond the float32"),
    (valid_text_with(L10_ROW, '"L10": [0, -3.5e38, 0]'), r"L10 channel G is -3.5e\+38, beyond"),
    (valid_text_with(L10_ROW, f'{L10_ROW}, "L10": [0, 0, 0]'), r"key 'L10' appears twice"),
    (modified(metadata=[]), r"\"metadata\" is a list: it must be an object"),
    (modified(metadata={"name": 3}), r"metadata name is int: it must be a string"),
    (modified(metadata={"mapping": [0, 0]}), r"metadata mapping has 2 values"),
    (modified(metadata={"strength": "x"}), r"metadata strength is a string"),
    (modified(metadata={"created": "yesterday"}), r"metadata created is 'yesterday'.*ISO 8601"),
    (modified(metadata={"error_estimate": {"mean": 0.1}}), r"error_estimate.*\"mean\": m"),
    (modified(metadata={"error_estimate": {"mean": -1, "max": 0}}), r"cannot be negative"),
]


@pytest.mark.parametrize("text, message", REFUSALS)
def test_refusals_name_the_problem(text, message):
    with pytest.raises(PresetError, match=message):
        preset_from_json(text)


@pytest.mark.parametrize(
    "key, hint",
    [("L1_1", "L1-1"), ("l2m2", "L2-2"), ("l00", "L00")],
)
def test_misspelt_coefficient_names_get_a_suggestion(key, hint):
    d = valid_dict()
    d["coefficients"][key] = d["coefficients"].pop(hint)
    message = rf"missing {hint}; unknown '{key}' \(did you mean '{hint}'\?\)"
    with pytest.raises(PresetError, match=message):
        preset_from_dict(d)


def test_preset_error_is_a_value_error():
    assert issubclass(PresetError, ValueError)


def test_read_errors_name_the_file(tmp_path):
    path = tmp_path / "broken.json"
    path.write_text('{"format": ')
    with pytest.raises(PresetError, match=rf"preset file '{path}': not valid JSON at line 1"):
        read_preset(path)
    path.write_bytes(b"\xff\xfe{}")
    with pytest.raises(PresetError, match=r"is not UTF-8 text"):
        read_preset(path)
    with pytest.raises(FileNotFoundError):
        read_preset(tmp_path / "absent.json")


@pytest.mark.parametrize(
    "coeffs, message",
    [
        (np.zeros((8, 3)), r"9 RGB coefficients \(shape \(9, 3\)\), got shape \(8, 3\)"),
        (np.zeros(27), r"got shape \(27,\)"),
        (np.where(np.eye(9, 3) > 0, np.nan, 0.0), r"coefficient L00 channel R is nan"),
        ([["a", 1, 2]] * 9, r"coefficient L00 channel R is a string \('a'\), not a number"),
        (np.full((9, 3), 1e39), r"coefficient L00 channel R is 1e\+39, beyond the float32"),
    ],
)
def test_writing_refuses_bad_coefficients_before_touching_the_disk(tmp_path, coeffs, message):
    with pytest.raises(PresetError, match=message):
        write_preset(tmp_path / "x.json", coeffs)
    assert list(tmp_path.iterdir()) == []


def test_writing_refuses_unwritable_metadata(tmp_path):
    with pytest.raises(PresetError, match="metadata cannot be written as JSON"):
        write_preset(tmp_path / "x.json", COEFFS, {"extra": float("nan")})
    with pytest.raises(PresetError, match="metadata cannot be written as JSON"):
        write_preset(tmp_path / "x.json", COEFFS, {"extra": object()})
    assert list(tmp_path.iterdir()) == []


# --- the presets shipped in the repository -------------------------------------------------

SHIPPED = sorted((REPO / "presets").glob("*.json"))
HDRI_NAMES = ("city", "courtyard", "forest", "interior", "night", "studio", "sunrise", "sunset")


def test_all_bundled_presets_are_shipped():
    stems = {p.stem for p in SHIPPED}
    assert stems >= {"grace_cathedral", "eucalyptus_grove", "st_peters_basilica", *HDRI_NAMES}


@pytest.mark.parametrize("path", SHIPPED, ids=[p.stem for p in SHIPPED])
def test_shipped_presets_read_back_and_are_written_canonically(path):
    coeffs, meta = read_preset(path)
    assert meta["name"] and meta["source"]
    assert path.read_text(encoding="utf-8") == preset_to_json(coeffs, meta)


@pytest.mark.parametrize("name", HDRI_NAMES)
def test_hdri_presets_carry_an_error_estimate_within_the_universal_bounds(name):
    """For non-negative lighting, max ≤ 3/32 and mean ≤ 0.0307 of the power (docs/reference.md
    §2)."""
    _, meta = read_preset(REPO / "presets" / f"{name}.json")
    estimate = meta["error_estimate"]
    assert 0.0 < estimate["mean"] <= estimate["max"] <= 3 / 32
    assert estimate["mean"] <= 0.0307
