"""``luminaire FILE BLEND``: the luminaire added, coloured and saved; bad files and arguments
refused in one line with nothing written."""

from pathlib import Path

import bpy
import numpy as np
import pytest
from cli_runs import make_inputs, run

pytestmark = pytest.mark.blender
DATA = Path(__file__).resolve().parents[1] / "data" / "photometry"


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    return make_inputs(tmp_path_factory.mktemp("cli_luminaire"))


def test_adds_colours_and_saves(inputs, tmp_path):
    out = tmp_path / "lit.blend"
    result = run("luminaire", DATA / "ugr_sample_05.ldt", inputs["blend"], "--out", out,
                 "--location", "0", "0", "2.5", "--temperature", "3000", "--lamps", "2",
                 "--power", "2")
    assert result.returncode == 0, result.stderr
    assert "Measured luminaire 'ugr_sample_05'" in result.stdout and "lm" in result.stdout
    assert f"Saved {out}" in result.stdout
    bpy.ops.wm.open_mainfile(filepath=str(out))
    root = bpy.data.objects["ugr_sample_05"]
    assert tuple(root.location) == pytest.approx((0.0, 0.0, 2.5))
    assert root.data.energy == pytest.approx(2.0)
    from sh_lighting.blender.luminaire import build
    from sh_lighting.core.blackbody import blackbody_rgb

    assert build.is_luminaire(bpy.context.scene, root)
    assert np.allclose(build.light_colour(root.data), blackbody_rgb(3000.0), rtol=1e-5)
    assert 1 <= len(build.lamps_of(bpy.context.scene, root)) <= 2


@pytest.mark.parametrize("extra, expected", [
    ((), "line 7: candela values: 'nan' is not a finite"),
    (("--temperature", "100"), "--temperature 100.0: from 800 to 20000 K"),
    (("--lamps", "9"), "--lamps 9: from 1 to 8"),
])
def test_refused_in_one_line_nothing_written(inputs, tmp_path, extra, expected):
    bad = tmp_path / "bad.ies"
    bad.write_text("IESNA:LM-63-2002\nTILT=NONE\n1 1 1 2 1 1 2 0 0 0\n1 1 1\n0 90\n0\n5 nan\n")
    source = bad if not extra else DATA / "bega_50988_lm63_1995.ies"
    out = tmp_path / "never.blend"
    result = run("luminaire", source, inputs["blend"], "--out", out, *extra)
    assert result.returncode == 1
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and expected in lines[0], result.stderr
    assert not out.exists()
