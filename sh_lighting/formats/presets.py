"""Lighting presets: the 9 RGB coefficients L_lm in a small, strict JSON file (version 1).

{"format": "sh_lighting.preset", "version": 1, "frame": "blender_world_z_up", "coefficients":
{"L00": [r, g, b], ..., "L22": [r, g, b]}, "metadata": {...}}: raw radiance
L_lm = ∫ L(ω) Y_lm(ω) dω in the paper's real basis, Blender world axes, linear RGB. Reading
refuses anything else (bad JSON, unknown keys or frame, NaN, Infinity, 1e999) with one
``PresetError`` naming the problem; writing is atomic. Fields and refusals: docs/formats.md.
"""

import json
import math
import os
import re
import stat
from datetime import date, datetime
from pathlib import Path

from ..core.coefficients import check_coefficients, real_number
from ..core.sh import COEFFICIENT_NAMES
from .atomic import write_text_atomic

# A preset is about 1 KB; a file larger than this is not one (and is never read whole).
MAX_PRESET_BYTES = 1 << 20
FORMAT_NAME = "sh_lighting.preset"
FORMAT_VERSION = 1
FRAME = "blender_world_z_up"
TOP_LEVEL_KEYS = ("format", "version", "frame", "coefficients", "metadata")
METADATA_KEYS = ("name", "source", "mapping", "strength", "created", "error_estimate", "notes")


class PresetError(ValueError):
    """A preset that cannot be read or written; the message names the problem and the fix."""


# --- reading and checking values -----------------------------------------------------------


def _type_name(value):
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, str):
        return "a string"
    if isinstance(value, (list, tuple)):
        return "a list"
    if isinstance(value, dict):
        return "an object"
    return type(value).__name__


def _finite_number(value, what):
    """``value`` as a float, or a PresetError if it is not a finite real number."""
    return real_number(value, what, PresetError, limit=math.inf)


def _number_list(value, count, what):
    if not isinstance(value, (list, tuple)):
        raise PresetError(f"{what} is {_type_name(value)}, not a list of {count} numbers")
    if len(value) != count:
        raise PresetError(f"{what} has {len(value)} values: give exactly {count}")
    return value


def _closest_name(name):
    """The coefficient name a misspelt key probably means ("l1_1", "L1m1" -> "L1-1"), or None."""
    s = str(name).strip().upper()
    s = re.sub(r"(?<=\d)[_MN](?=\d)", "-", s)  # Babylon's l1_1, or m/n for minus
    s = re.sub(r"[^L0-9-]", "", s)
    s = s if s.startswith("L") else "L" + s
    return s if s in COEFFICIENT_NAMES else None


def _check_coefficient_block(block):
    """The (9, 3) float64 array of a ``coefficients`` object, or a PresetError."""
    if not isinstance(block, dict):
        raise PresetError(
            f'"coefficients" is {_type_name(block)}: it must be an object mapping each of '
            f"{', '.join(COEFFICIENT_NAMES)} to [r, g, b]"
        )
    missing = [n for n in COEFFICIENT_NAMES if n not in block]
    extra = [n for n in block if n not in COEFFICIENT_NAMES]
    if missing or extra:
        parts = []
        if missing:
            parts.append(f"missing {', '.join(missing)}")
        if extra:
            hints = [
                f"{e!r} (did you mean {_closest_name(e)!r}?)" if _closest_name(e) else repr(e)
                for e in extra
            ]
            parts.append(f"unknown {', '.join(hints)}")
        raise PresetError(
            f"coefficients: {'; '.join(parts)}. A preset holds exactly the nine coefficients "
            f"{', '.join(COEFFICIENT_NAMES)} (index l(l+1)+m, so L1-1 is l=1, m=-1)"
        )
    rows = [block[name] for name in COEFFICIENT_NAMES]
    return check_coefficients(rows, error=PresetError)


def _check_metadata(metadata):
    """A checked copy of a metadata object (documented keys type-checked, others kept)."""
    if metadata is None:
        return {}
    if not isinstance(metadata, dict):
        raise PresetError(f'"metadata" is {_type_name(metadata)}: it must be an object')
    out = dict(metadata)
    for key in ("name", "source", "notes"):
        if key in out and not isinstance(out[key], str):
            raise PresetError(f"metadata {key} is {_type_name(out[key])}: it must be a string")
    if "mapping" in out:
        values = _number_list(out["mapping"], 3, "metadata mapping")
        out["mapping"] = [
            _finite_number(v, f"metadata mapping {axis}") for v, axis in zip(values, "XYZ")
        ]
    if "strength" in out:
        out["strength"] = _finite_number(out["strength"], "metadata strength")
    if "created" in out:
        created = out["created"]
        if not isinstance(created, str) or not _is_iso_date(created):
            raise PresetError(
                f"metadata created is {created!r}: write an ISO 8601 date or date-time, "
                'e.g. "2025-01-31" or "2025-01-31T14:05:00"'
            )
    if "error_estimate" in out:
        estimate = out["error_estimate"]
        if not isinstance(estimate, dict) or set(estimate) != {"mean", "max"}:
            raise PresetError(
                f"metadata error_estimate is {estimate!r}: it must be an object "
                '{"mean": m, "max": x} (fractions of the total power)'
            )
        checked = {k: _finite_number(estimate[k], f"metadata error_estimate {k}") for k in estimate}
        if min(checked.values()) < 0:
            raise PresetError("metadata error_estimate values are errors: they cannot be negative")
        out["error_estimate"] = {"mean": checked["mean"], "max": checked["max"]}
    return out


def _is_iso_date(text):
    for parse in (date.fromisoformat, datetime.fromisoformat):
        try:
            parse(text)
            return True
        except ValueError:
            pass
    return False


def check_preset_coefficients(coeffs):
    """(9, 3) float64 copy of ``coeffs``, or a PresetError (``coefficients.check_coefficients``:
    wrong shape, not numbers, NaN, Inf, beyond float32)."""
    return check_coefficients(coeffs, error=PresetError)


# --- dict <-> coefficients -----------------------------------------------------------------


def preset_to_dict(coeffs, metadata=None):
    """The JSON-ready dict of a preset: ``coeffs`` (9, 3) in Blender axes plus ``metadata``.

    Checks everything a reader checks, so a written preset always reads back.
    """
    c = check_preset_coefficients(coeffs)
    d = {
        "format": FORMAT_NAME,
        "version": FORMAT_VERSION,
        "frame": FRAME,
        "coefficients": {name: [float(v) for v in row] for name, row in zip(COEFFICIENT_NAMES, c)},
    }
    meta = _check_metadata(metadata)
    if meta:
        d["metadata"] = meta
    return d


def preset_from_dict(d):
    """(coefficients (9, 3) float64 in Blender axes, metadata dict) from a parsed preset."""
    if not isinstance(d, dict):
        raise PresetError(
            f"a preset is a JSON object with a \"format\" key, got {_type_name(d)}: "
            "this is not an sh_lighting preset file"
        )
    fmt = d.get("format")
    if fmt != FORMAT_NAME:
        found = "no \"format\" key" if "format" not in d else f'"format" is {fmt!r}'
        raise PresetError(
            f'{found}, expected "{FORMAT_NAME}": this is not an sh_lighting preset file'
        )
    if "version" not in d:
        raise PresetError(f'no "version" key: write "version": {FORMAT_VERSION}')
    version = d["version"]
    if isinstance(version, bool) or not isinstance(version, int):
        raise PresetError(
            f'"version" is {version!r}: it must be the whole number {FORMAT_VERSION}'
        )
    if version != FORMAT_VERSION:
        advice = (
            "it was written by a newer sh_lighting: update the add-on to read it"
            if version > FORMAT_VERSION
            else "no such version was ever written: fix the file"
        )
        raise PresetError(
            f"preset version {version} is not supported (this add-on reads version "
            f"{FORMAT_VERSION}): {advice}"
        )
    frame = d.get("frame")
    if frame != FRAME:
        found = 'no "frame" key' if "frame" not in d else f'"frame" is {frame!r}'
        raise PresetError(
            f'{found}, but presets are stored in Blender world axes, '
            f'"{FRAME}": convert the coefficients first (sh_lighting.core.frames, e.g. '
            "y_up_to_blender for glTF/three.js data or paper_to_blender for the paper's "
            f'probes) and write frame "{FRAME}"'
        )
    unknown = [k for k in d if k not in TOP_LEVEL_KEYS]
    if unknown:
        raise PresetError(
            f"unknown top-level key(s) {', '.join(map(repr, unknown))}: a version "
            f"{FORMAT_VERSION} preset has only {', '.join(TOP_LEVEL_KEYS)}; put extra "
            'information under "metadata"'
        )
    if "coefficients" not in d:
        raise PresetError('no "coefficients" object: the preset has no lighting to load')
    return _check_coefficient_block(d["coefficients"]), _check_metadata(d.get("metadata"))


# --- text ----------------------------------------------------------------------------------


def _reject_constant(literal):
    raise PresetError(
        f"the file contains the literal {literal}, which is not valid JSON and not a usable "
        "coefficient: recompute the lighting or write a finite number"
    )


def _no_duplicate_keys(pairs):
    out = {}
    for key, value in pairs:
        if key in out:
            raise PresetError(f"key {key!r} appears twice in one object: keep one of them")
        out[key] = value
    return out


def preset_from_json(text):
    """Parse preset text: (coefficients (9, 3), metadata). PresetError on any problem."""
    try:
        d = json.loads(
            text, parse_constant=_reject_constant, object_pairs_hook=_no_duplicate_keys
        )
    except PresetError:
        raise
    except json.JSONDecodeError as error:
        raise PresetError(
            f"not valid JSON at line {error.lineno}, column {error.colno}: {error.msg}. "
            "Fix the file there (a missing comma or quote, a trailing comma, ...)"
        ) from None
    except RecursionError:
        raise PresetError(
            "its JSON is nested too deeply to read (lists or objects inside each other "
            "hundreds of times): this is not a preset; a preset nests three levels"
        ) from None
    except ValueError as error:  # e.g. an integer of more than 4300 digits
        raise PresetError(f"its JSON cannot be read ({error}): write plain numbers") from None
    return preset_from_dict(d)


def preset_to_json(coeffs, metadata=None):
    """The text of a preset: indented JSON, one [r, g, b] per line, floats written exactly."""
    d = preset_to_dict(coeffs, metadata)
    try:
        text = json.dumps(d, indent=2, ensure_ascii=False, allow_nan=False)
    except (TypeError, ValueError) as error:
        raise PresetError(
            f"metadata cannot be written as JSON ({error}): use strings, numbers, lists and "
            "objects of finite values"
        ) from None
    return _collapse_number_lists(text) + "\n"


def _collapse_number_lists(text):
    """Put each innermost list of plain numbers on one line: [\n  1.0,\n  2.0\n] -> [1.0, 2.0]."""
    number = r"-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?"
    pattern = re.compile(rf"\[\s*({number}(?:,\s*{number})*)\s*\]")
    return pattern.sub(lambda m: "[" + ", ".join(re.split(r",\s*", m.group(1))) + "]", text)


# --- files ---------------------------------------------------------------------------------


def read_preset(path):
    """(coefficients (9, 3) in Blender axes, metadata) of the preset file at ``path``.

    PresetError (a ValueError) for a file that is not a valid preset, naming the file;
    FileNotFoundError / OSError when it cannot be read at all.
    """
    path = Path(path)
    try:
        text = _read_small_file(path).decode("utf-8")
    except UnicodeDecodeError as error:
        raise PresetError(
            f"preset file '{path}' is not UTF-8 text ({error.reason} at byte {error.start}): "
            "is it really a preset? Presets are JSON text files"
        ) from None
    try:
        return preset_from_json(text)
    except PresetError as error:
        raise PresetError(f"preset file '{path}': {error}") from None


def _read_small_file(path):
    """The bytes of the regular file ``path`` if it holds at most MAX_PRESET_BYTES.

    A folder, device (``/dev/zero``), FIFO or socket is refused before it is opened (a FIFO
    would block the open), larger files before they are read: PresetError. A missing file is
    a FileNotFoundError, an unreadable one an OSError, each naming the file.
    """
    try:
        info = os.stat(path)
    except FileNotFoundError:
        raise FileNotFoundError(f"preset file '{path}' does not exist: check the path") from None
    except OSError as error:
        raise OSError(f"cannot read preset file '{path}': {error.strerror}") from None
    if stat.S_ISDIR(info.st_mode):
        raise PresetError(f"'{path}' is a folder: choose a preset file (.json)")
    if not stat.S_ISREG(info.st_mode):
        raise PresetError(
            f"preset file '{path}' is not a regular file (a device, FIFO or socket): choose "
            "a preset file (.json)"
        )
    if info.st_size > MAX_PRESET_BYTES:
        raise PresetError(
            f"preset file '{path}' holds {info.st_size} bytes, more than a preset ever does "
            f"({MAX_PRESET_BYTES} at most): is it really a preset?"
        )
    try:  # O_NONBLOCK: should the file have been swapped for a FIFO since, never wait
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except OSError as error:
        raise OSError(f"cannot read preset file '{path}': {error.strerror}") from None
    with os.fdopen(fd, "rb") as stream:
        if not stat.S_ISREG(os.fstat(stream.fileno()).st_mode):
            raise PresetError(f"preset file '{path}' is not a regular file: choose a preset")
        data = stream.read(MAX_PRESET_BYTES + 1)
    if len(data) > MAX_PRESET_BYTES:
        raise PresetError(f"preset file '{path}' grew beyond {MAX_PRESET_BYTES} bytes while "
                          "it was read: is it really a preset?")
    return data


def write_preset(path, coeffs, metadata=None, overwrite=False):
    """Write a preset file atomically (``core.atomic``); returns the path written.

    The whole text is built and checked first, so bad coefficients never touch the disk. An
    existing ``path`` raises FileExistsError unless ``overwrite=True``; on any error ``path``
    keeps its previous content (or stays absent) and no temporary file is left.
    """
    text = preset_to_json(coeffs, metadata)
    return write_text_atomic(path, text, overwrite=overwrite, what="preset file")
