"""Presets on disk: export and import a scene's coefficients, shipped and user presets.

Plain functions (the scene an argument, never ``bpy.context``) for the operators, the command
line and the API. ``export_preset`` writes our JSON, three.js, glTF (with a specular cube from
the world image) or Filament's sh.txt (``FORMATS``), atomically, in linear Rec.709
(``to_export_space``); ``import_preset`` reads our JSON into the scene's current values (not
the Reset values). Shipped presets: the package's ``presets`` folder; user presets:
``<user scripts>/presets/sh_lighting``. Formats and metadata in detail: docs/modules.md.
"""

import json
import os
import re
import unicodedata
from datetime import date
from pathlib import Path

import bpy

from ...choices import FILAMENT_FRAMES, FORMATS
from ...core.coefficients import check_coefficients
from ...core.colour import REC709, conversion_matrix, convert_coefficients
from ...formats import atomic
from ...formats.gltf import gltf_text
from ...formats.interop import to_filament_sh_txt, to_threejs_json
from ...formats.presets import PresetError, preset_to_json, read_preset
from ..data import compat, scene_data
from ..world import reader
from ..world.compute import world_match

PRESET_SUBDIR = "sh_lighting"
PRESET_EXTENSION = ".json"
MAX_NAME_LENGTH = 64
MAX_NAME_BYTES = 200  # of UTF-8: file systems allow 255 bytes per name, ".json" included
GENERATOR = "sh_lighting"
# Every format holds linear Rec.709 RGB (three.js's, glTF's and Filament's linear space; our
# presets too, so a preset means the same light in a file of any working space).
EXPORT_SPACE = REC709
OVERWRITE_HINT = "enable Overwrite (overwrite=True) to replace it"

_PACKAGE_DIR = Path(__file__).resolve().parents[2]


# --- folders -------------------------------------------------------------------------------


def shipped_preset_dir():
    """The folder of the presets shipped with the add-on, or None if there is none."""
    for folder in (_PACKAGE_DIR / "presets", _PACKAGE_DIR.parent / "presets"):
        if folder.is_dir():
            return folder
    return None


def user_preset_dir():
    """Blender's user preset folder of this add-on, ``<user scripts>/presets/sh_lighting``
    (it may not exist yet), or None if Blender gives no absolute user scripts folder: an empty
    path would otherwise be the current working directory.
    """
    folder = bpy.utils.user_resource("SCRIPTS", path=f"presets/{PRESET_SUBDIR}")
    if not folder or not os.path.isabs(folder):
        return None
    return Path(folder)


def _json_files(folder):
    if folder is None or not folder.is_dir():
        return {}
    files = [
        p for p in folder.iterdir()
        if p.suffix.lower() == PRESET_EXTENSION and not p.name.startswith(".") and p.is_file()
    ]
    return {p.stem: p for p in sorted(files, key=lambda p: p.stem.lower())}


def shipped_presets():
    """{name: Path} of the shipped presets (file stems, sorted case-insensitively)."""
    return _json_files(shipped_preset_dir())


def user_presets():
    """{name: Path} of the user's presets (file stems, sorted case-insensitively)."""
    return _json_files(user_preset_dir())


def preset_file_name(name):
    """The file name of a user preset called ``name``: letters and digits of any script
    ("Студия", "スタジオ", "Ümlaut"), ``-`` and ``_`` kept (NFC-normalised), every other run
    of characters (spaces, path separators, punctuation) replaced by one ``_``; at most
    MAX_NAME_LENGTH characters and MAX_NAME_BYTES bytes; ValueError if nothing is left.
    """
    if not isinstance(name, str):
        raise ValueError(f"a preset name is text, got {type(name).__name__}")
    text = unicodedata.normalize("NFC", name.strip())
    stem = re.sub(r"[^\w-]+", "_", text).strip("_")[:MAX_NAME_LENGTH]
    while len(stem.encode("utf-8")) > MAX_NAME_BYTES:
        stem = stem[:-1]
    if not stem:
        raise ValueError(
            f"preset name {name!r} has no letters or digits: give it a name such as 'Studio Warm'"
        )
    return stem + PRESET_EXTENSION


# --- metadata ------------------------------------------------------------------------------


def scene_metadata(scene):
    """What is known about where the scene's current coefficients came from (may be empty
    apart from ``created``): the provenance ``store`` recorded when they were computed from a
    world image (its file, Mapping rotation and Strength), while the values are still exactly
    those (nothing is read from the world now, which may have changed since).
    """
    metadata = {"created": date.today().isoformat()}
    record = world_match(scene).record  # {} when edited or loaded since: not the world's
    if record.get("source") != "WORLD" or "edit" in record or record.get("method") != "IMAGE":
        return metadata
    # the file name only: an absolute local path would leak into files people share
    name = os.path.basename(record["path"]) if record.get("path") else ""
    metadata["source"] = name or f"image '{record.get('image')}'"
    metadata["mapping"] = list(record.get("rotation", (0.0, 0.0, 0.0)))
    metadata["strength"] = record.get("strength")
    if record.get("sun"):
        metadata["notes"] = f"the sun was split off as the light '{record['sun']}'"
    return metadata


# --- export / import -----------------------------------------------------------------------


def file_path(path):
    """``path`` as a Path, a leading ``//`` taken relative to the open .blend's folder (as
    Blender's own paths); a ValueError when the file was never saved (nothing to be relative
    to)."""
    text = os.fspath(path)
    if not text.startswith("//"):
        return Path(text)
    if not bpy.data.filepath:
        raise ValueError(
            f"'{text}' is relative to the .blend file (//), but this file was never saved: "
            "save it first, or give a path without //"
        )
    return Path(bpy.path.abspath(text))


def _format_id(format):
    key = str(format).lower()
    if key not in FORMATS:
        raise ValueError(f"unknown preset format {format!r}: use one of {', '.join(FORMATS)}")
    return key


def _filament_frame_id(frame):
    key = str(frame).lower()
    if key not in FILAMENT_FRAMES:
        raise ValueError(
            f"unknown Filament frame {frame!r}: use one of {', '.join(FILAMENT_FRAMES)}"
        )
    return key


def world_environment(scene):
    """(pixels, strength, Mapping Euler) of ``scene``'s world image (pixels in the file's
    working space) when its coefficients are exactly the ones computed from the world as it
    is now (``compute.world_match``) and it is an equirect image; None when they are not the
    world's (edited, loaded, a capture: the glTF specular cube then comes from the 9 terms).
    A ValueError when they were computed from a world image that has changed since
    (the cube would be the new image's, the coefficients the old one's).
    """
    match = world_match(scene)
    if match.stale:
        raise ValueError(
            f"the coefficients were computed from image '{match.record.get('image')}' of "
            f"world '{match.record.get('world')}', and {match.reason.replace('the world', 'it', 1)}"
            ": the specular cube would not match them; press Compute from World (or switch "
            "the world back) and export again"
        )
    source = match.source
    if source is None or source.projection != "EQUIRECTANGULAR":
        return None
    try:
        return source.pixels(), source.strength, source.rotation
    except reader.WorldError:  # no pixel data: no image
        return None


def export_text(coeffs, format="sh_lighting", metadata=None, environment=None,
                filament_frame="cmgen"):
    """The text of ``coeffs`` (9, 3) in ``format`` (see ``FORMATS``), with ``metadata``.

    ``environment``: (pixels, strength, euler) of the world image for the glTF specular cube
    (``world_environment``), or (pixels, strength, euler, colour) with ``colour`` the 3×3
    matrix from the pixels' RGB to the coefficients' space, or None (only glTF reads it);
    ``filament_frame``: a key of ``FILAMENT_FRAMES``.
    """
    key = _format_id(format)
    metadata = dict(metadata or {})
    if key == "sh_lighting":
        return preset_to_json(coeffs, metadata)
    if key == "filament":
        return to_filament_sh_txt(coeffs, _filament_frame_id(filament_frame))
    extras = {"generator": GENERATOR, "frame": "gltf_y_up", **metadata}
    if key == "threejs":
        d = to_threejs_json(coeffs, metadata.get("name", ""), extras)
        return json.dumps(d, indent=2, ensure_ascii=False, allow_nan=False) + "\n"
    pixels, strength, euler, *colour = environment or (None, 1.0, None)
    extras["specular_source"] = "world image" if pixels is not None else "9-term lighting"
    return gltf_text(coeffs, pixels, strength, euler, metadata.get("name", ""), extras,
                     colour=colour[0] if colour else None)


def to_export_space(coeffs, error=ValueError):
    """``coeffs`` (9, 3) of the file's working colour space in ``EXPORT_SPACE``, the space
    of every format written (``core.colour.convert_coefficients``); checked first (``error``
    names the problem)."""
    checked = check_coefficients(coeffs, error=error)
    return convert_coefficients(checked, compat.working_space(), EXPORT_SPACE)


def from_preset_space(coeffs):
    """Coefficients read from a preset (``EXPORT_SPACE``) in the file's working space."""
    return convert_coefficients(coeffs, EXPORT_SPACE, compat.working_space())


def export_coefficients(coeffs, path, format="sh_lighting", overwrite=False, metadata=None,
                        environment=None, filament_frame="cmgen"):
    """Write ``coeffs`` (9, 3, in the file's working space) to ``path`` in ``format``,
    converted to ``EXPORT_SPACE`` (``to_export_space``; so is the specular cube made from
    ``environment``'s pixels, for glTF, the only format that reads them), atomically;
    returns the Path.

    ``environment`` and ``filament_frame`` as for :func:`export_text`. FileExistsError if
    ``path`` exists and ``overwrite`` is false (nothing written); ValueError (PresetError for
    our format) for coefficients or metadata that cannot be written.
    """
    path = Path(path)
    metadata = dict(metadata or {})
    metadata.setdefault("name", path.stem)
    error = PresetError if _format_id(format) == "sh_lighting" else ValueError
    coeffs = to_export_space(coeffs, error)
    if environment is not None and _format_id(format) == "gltf":
        pixels, strength, euler = environment  # converted on the cube's small source
        colour = conversion_matrix(compat.working_space(), EXPORT_SPACE)
        environment = (pixels, strength, euler, colour)
    else:
        environment = None  # the other formats carry no image: nothing per texel
    # every check happens before any write
    text = export_text(coeffs, format, metadata, environment, filament_frame)
    return atomic.write_text_atomic(path, text, overwrite, what="file", hint=OVERWRITE_HINT)


def export_preset(scene, path, format="sh_lighting", overwrite=False, metadata=None,
                  filament_frame="cmgen"):
    """Write ``scene``'s coefficients to ``path`` in ``format`` (see ``FORMATS``); the Path.

    ``metadata`` entries are added to (and win over) ``scene_metadata(scene)``; a glTF
    environment's specular cube comes from ``world_environment(scene)``. LookupError if the
    scene has no coefficients, FileExistsError if ``path`` exists and ``overwrite`` is
    false; in every error case nothing is written.
    """
    path = file_path(path)
    coeffs = scene_data.get_coefficients(scene)
    merged = scene_metadata(scene)
    merged.update(metadata or {})
    environment = world_environment(scene) if _format_id(format) == "gltf" else None
    return export_coefficients(
        coeffs, path, format, overwrite, merged, environment, filament_frame
    )


def read_preset_file(path):
    """(coefficients (9, 3), metadata) of our preset JSON at ``path``; PresetError if invalid,
    OSError (FileNotFoundError, ...) if unreadable; ``//`` as in ``file_path``."""
    return read_preset(file_path(path))


def import_preset(scene, path, animation=scene_data.DEFAULT_ANIMATION):
    """Set ``scene``'s coefficients from our preset JSON at ``path``; returns them (9, 3).

    Reads and checks the whole file first: on PresetError / OSError the scene is unchanged.
    The values do not become the Reset values (module docstring). ``animation``: what
    ``scene_data.store`` does when a written property is animated. The Load and Import
    operators and the command line's ``apply`` all read a preset through here.
    """
    coeffs, metadata = read_preset_file(path)
    return scene_data.store(scene, from_preset_space(coeffs), preset_provenance(path, metadata),
                            animation)


def preset_provenance(path, metadata):
    """What ``store`` records for a preset read from ``path``: its name (the metadata's, else
    the file's stem) and the file."""
    path = Path(path)
    name = metadata.get("name") if isinstance(metadata.get("name"), str) else ""
    return {"source": "PRESET", "preset": name or path.stem, "path": str(path.resolve())}


# --- user presets --------------------------------------------------------------------------


def save_user_preset(scene, name, overwrite=False):
    """Save ``scene``'s coefficients as the user preset ``name``; returns the Path.

    The file is ``user_preset_dir() / preset_file_name(name)`` (the folder is created);
    FileExistsError if it exists and ``overwrite`` is false; OSError if Blender gives no user
    preset folder or it cannot be created (nothing is written anywhere else).
    """
    file_name = preset_file_name(name)
    folder = user_preset_dir()
    if folder is None:
        raise OSError(
            "Blender gives no user scripts folder, so there is nowhere to save user presets: "
            "export the preset to a file instead"
        )
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise OSError(f"cannot create the user preset folder '{folder}': {error}") from error
    return export_preset(
        scene, folder / file_name, "sh_lighting", overwrite, {"name": name.strip()}
    )


def _user_preset_path(folder, name):
    """The file of user preset ``name`` in ``folder``: its exact file stem if such a file
    exists (files put there by hand may have any name), else the sanitised name."""
    if (
        isinstance(name, str) and name and not name.startswith(".")
        and os.path.basename(name) == name
    ):
        exact = folder / (name + PRESET_EXTENSION)
        try:
            if exact.is_file():
                return exact
        except OSError:  # e.g. a name too long to be a file name: not a file of ours
            pass
    return folder / preset_file_name(name)


def remove_user_preset(name):
    """Delete the user preset ``name`` (a name from ``user_presets()`` or as given to
    ``save_user_preset``); returns the deleted Path.

    FileNotFoundError if there is no such user preset; PermissionError for a shipped preset
    (shipped presets are never deleted).
    """
    folder = user_preset_dir()
    path = None if folder is None else _user_preset_path(folder, name)
    if path is None or not path.is_file():
        shipped = shipped_presets()
        if name in shipped or Path(preset_file_name(name)).stem in shipped:
            raise PermissionError(
                f"'{name}' is a shipped preset: shipped presets cannot be removed"
            )
        where = f"in '{folder}'" if folder is not None else "(Blender gives no user folder)"
        raise FileNotFoundError(f"there is no user preset '{name}' {where}")
    path.unlink()
    return path
