"""An HDRI's error estimate says what its exact irradiance was computed from."""

import numpy as np
from blender_files import write_exr

from sh_lighting.blender.world.hdri import hdri_metadata, read_hdri
from sh_lighting.core.irradiance import bounded_error_estimate


def test_a_wide_hdri_notes_its_downsampled_reference_and_the_bound(tmp_path):
    rng = np.random.default_rng(2)
    pixels = (0.5 + rng.random((256, 1024, 3))).astype(np.float32)
    pixels[40:44, 100:104] = 200.0
    stages = []
    hdri = read_hdri(write_exr(tmp_path / "wide.exr", pixels),
                     progress=lambda name, s: stages.append(name))
    assert stages == ["decode", "projection", "error estimate"]
    notes = hdri_metadata(hdri)["notes"]
    assert "box-downsampled to 512x128" in notes and "% of the power" in notes
    full = bounded_error_estimate(hdri.pixels, hdri.coefficients, 256, reference_width=None)
    bound = bounded_error_estimate(hdri.pixels, hdri.coefficients, 256)["bound"]
    assert abs(hdri.estimate["mean"] - full["mean"]) <= bound
    assert abs(hdri.estimate["max"] - full["max"]) <= bound


def test_a_small_hdri_is_its_own_reference(tmp_path):
    pixels = np.full((64, 128, 3), 0.25, dtype=np.float32)
    hdri = read_hdri(write_exr(tmp_path / "small.exr", pixels))
    notes = hdri_metadata(hdri)["notes"]
    assert notes.endswith("against the exact irradiance.") and hdri.estimate["max"] < 1e-9
