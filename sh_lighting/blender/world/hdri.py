"""An HDRI file read for its lighting: decoded by Blender, projected, its 9-term error
estimated, its bright sources taken out as lights.

The one pipeline of the command line's ``compute`` and ``batch`` (and of scripts): the file is
decoded as Blender renders it (``images.load_image_pixels``), projected exactly onto the 9
coefficients (``core.projection.project_equirect``, Ramamoorthi and Hanrahan 2001, eq. 10),
and the 9-term irradiance (eq. 12-13) compared with the exact one at ``ERROR_NORMALS`` normals
(``core.irradiance.error_estimate``).
"""

import os
import sys
import tempfile
import time
from contextlib import contextmanager
from datetime import date
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ...core.coefficients import check_coefficients
from ...core.equirect import zero_nonfinite
from ...core.irradiance import bounded_error_estimate
from ...core.lights import extract_lights
from ...core.mirror_ball import project_mirror_ball
from ...core.projection import project_equirect
from . import images

# Normals at which an HDRI's 9-term irradiance is compared with the exact one (a Fibonacci
# lattice): enough for a mean to ~1e-4, cheap next to loading the image.
ERROR_NORMALS = 256


PROJECTIONS = ("equirect", "mirror_ball")


class Hdri(NamedTuple):
    """An HDRI file's ``pixels`` (H, W, 4) float32 (non-finite texels zeroed if asked), its
    ``coefficients`` (9, 3) and its ``estimate`` ({"mean", "max"}, or None: a channel without
    light); ``downsample``: the estimate's (map, bound) downsample of the pixels, for the
    lights' reference (``hdri_lights``; None at full resolution or without an estimate)."""

    path: Path
    pixels: np.ndarray
    coefficients: np.ndarray
    estimate: dict | None
    reference: str = ""  # what the estimate's exact irradiance was computed from
    projection: str = "equirect"  # how the image was read: "equirect" or "mirror_ball"
    downsample: tuple | None = None


@contextmanager
def library_output_captured():
    """Send what C libraries print on stderr (file descriptor 2) during the block to a
    temporary file instead of the terminal ("EXR_ERR_READ_IO", "libpng error" beside the
    caller's own one-line message); yields a function returning that text."""
    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile() as capture:
        os.dup2(capture.fileno(), 2)
        try:
            yield lambda: (capture.seek(0), capture.read().decode("utf-8", "replace"))[1]
        finally:
            sys.stderr.flush()
            os.dup2(saved, 2)
            os.close(saved)


def read_hdri(path, nonfinite="raise", progress=None, projection="equirect"):
    """The ``Hdri`` of the image file at ``path``, an equirectangular map (``projection``
    "equirect") or a mirror ball filling the image ("mirror_ball": ``core.mirror_ball``, no
    error estimate).

    ``nonfinite``: "raise" refuses NaN/Inf texels (``core.equirect.NonFiniteError``), "zero"
    treats them as black, in the projection and the estimate alike. A ValueError says why a
    file cannot be read or projected. ``progress``: called as progress(stage, seconds) after
    each stage ("decode", "projection", "error estimate").
    """
    clock = time.perf_counter()

    def done(stage):
        nonlocal clock
        now = time.perf_counter()
        if progress is not None:
            progress(stage, now - clock)
        clock = now

    with library_output_captured():
        pixels = images.load_image_pixels(path)
    if nonfinite == "zero":
        pixels = zero_nonfinite(pixels)
    done("decode")
    if projection not in PROJECTIONS:
        raise ValueError(f"unknown projection {projection!r}: use one of {', '.join(PROJECTIONS)}")
    if projection == "mirror_ball":
        coeffs = check_coefficients(project_mirror_ball(pixels, nonfinite=nonfinite))
        done("projection")
        return Hdri(Path(path), pixels, coeffs, None, projection=projection)
    coeffs = check_coefficients(project_equirect(pixels, nonfinite=nonfinite))
    done("projection")
    bounded = bounded_error_estimate(pixels, coeffs, ERROR_NORMALS)
    done("error estimate")
    if bounded is None:
        return Hdri(Path(path), pixels, coeffs, None)
    height, width = bounded["reference_size"]
    reference = "" if (height, width) == pixels.shape[:2] else (
        f" (of the image box-downsampled to {width}x{height}: within "
        f"{100 * bounded['bound']:.2g} % of the power of the full-resolution values)")
    estimate = {"mean": bounded["mean"], "max": bounded["max"]}
    return Hdri(Path(path), pixels, coeffs, estimate, reference,
                downsample=bounded["downsample"])


def hdri_metadata(hdri):
    """The preset metadata of an ``Hdri``: its name, the file name (never a local absolute
    path), today, and its error estimate when there is one."""
    height, width = hdri.pixels.shape[:2]
    metadata = {
        "name": hdri.path.stem,
        "source": hdri.path.name,
        "mapping": [0.0, 0.0, 0.0],
        "strength": 1.0,
        "created": date.today().isoformat(),
        "notes": (f"Projected exactly from the {width}x{height} image."
                  if hdri.projection == "equirect" else
                  f"Projected from the {width}x{height} mirror-ball image."),
    }
    if hdri.estimate is not None:
        metadata["error_estimate"] = hdri.estimate
        metadata["notes"] += (
            f" Error estimate at {ERROR_NORMALS} normals against the exact irradiance"
            f"{hdri.reference}."
        )
    return metadata


def hdri_lights(hdri, count):
    """(``core.lights.Extraction``, the rest's (9, 3) coefficients): up to ``count`` compact
    bright sources of the HDRI taken out as lights (``core.lights.extract_lights``), from the
    coefficients and the downsample ``read_hdri`` made, without a copy of the map
    (``Extraction.rest`` None)."""
    extraction = extract_lights(hdri.pixels, count, coefficients=hdri.coefficients,
                                keep_rest=False, downsample=hdri.downsample)
    return extraction, check_coefficients(extraction.coefficients)  # the rest's, projected
