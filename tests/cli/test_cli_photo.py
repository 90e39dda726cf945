"""``python -m sh_lighting from-photo``: a thin call of api.coefficients_from_photo, run as a
user runs it (a fresh process), on a computed photo of a grey ball (core.photo.ball_picture)."""

import numpy as np
import pytest
from blender_files import write_exr, write_png
from cli_runs import run

from sh_lighting.choices import PHOTO_PRIORS
from sh_lighting.cli import photo as cli_photo
from sh_lighting.core import photo as core_photo
from sh_lighting.core.ball_camera import camera_looking
from sh_lighting.formats.presets import read_preset

pytestmark = pytest.mark.blender
LIGHT = np.array(
    [[3.0, 2.5, 2.0], [0.5, 0.4, 0.2], [1.1, 1.0, 0.9], [-0.4, -0.2, 0.0], [0.2, 0.1, 0.0],
     [0.0, -0.2, 0.1], [0.3, 0.3, 0.2], [0.1, 0.1, 0.3], [-0.2, 0.0, 0.2]]
)


def test_the_command_line_shares_the_cores_choices():
    assert PHOTO_PRIORS == core_photo.PRIORS
    assert (cli_photo.DEFAULT_ALBEDO, cli_photo.DEFAULT_MARGIN) == (
        core_photo.DEFAULT_ALBEDO, core_photo.DEFAULT_MARGIN)


def test_from_photo_prints_the_report_and_writes_the_preset(tmp_path):
    camera = camera_looking((0.0, 1.0, 0.0))
    picture = core_photo.ball_picture(LIGHT, 64, 64, (32, 32, 30), camera)
    photo = write_exr(tmp_path / "ball.exr", picture)
    out = tmp_path / "ball.json"
    result = run("from-photo", photo, "--circle", 32, 32, 30, "--direction", 0, 1, 0,
                 "--prior", "none", "--out", out)
    assert result.returncode == 0, result.stderr
    assert "residual 0.00 % of the mean" in result.stdout
    assert "poorly constrained: L1-1+L00" in result.stdout
    stored, metadata = read_preset(out)
    assert "Fitted to a grey ball in ball.exr" in metadata["notes"]
    assert np.abs(stored - LIGHT).max() < 1e-4 * np.abs(LIGHT).max()


def test_from_photo_warns_first_of_a_circle_off_the_ball(tmp_path):
    """A circle centred on the ball's rim: its first line says the fit is poor and what to
    check (the command cannot know which circle is right; the preset is still written)."""
    camera = camera_looking((0.0, 1.0, 0.0))
    picture = core_photo.ball_picture(LIGHT, 128, 128, (64, 64, 30), camera, background=0.2)
    photo = write_exr(tmp_path / "ball.exr", picture)
    result = run("from-photo", photo, "--circle", 94, 64, 30, "--direction", 0, 1, 0)
    assert result.returncode == 0, result.stderr
    first = result.stdout.splitlines()[0]
    assert first.startswith(f"warning: {photo}: poor fit: the pixels in the circle are "), first
    assert "check that the circle sits on the ball's outline" in first
    right = run("from-photo", photo, "--circle", 64, 64, 30, "--direction", 0, 1, 0)
    assert right.returncode == 0 and "warning" not in right.stdout


def test_from_photo_takes_a_cut_out_rgba_png(tmp_path):
    """An 8-bit RGBA PNG, the ball opaque on a transparent background: fitted from the ball
    (the command line has no Alpha mode to set)."""
    camera = camera_looking((0.0, 1.0, 0.0))
    picture = core_photo.ball_picture(LIGHT, 96, 96, (48, 48, 40), camera)
    codes = np.round(255.0 * np.clip(picture / picture.max(), 0.0, 1.0) ** (1 / 2.2))
    y, x = np.mgrid[0:96, 0:96] + 0.5
    inside = (x - 48) ** 2 + (y - 48) ** 2 <= 41.0**2
    codes[~inside] = 0.0
    cut = write_png(tmp_path / "cut.png", codes, alpha=np.where(inside, 255.0, 0.0))
    plain = write_png(tmp_path / "plain.png", codes)
    results = [run("from-photo", path, "--circle", 48, 48, 40, "--direction", 0, 1, 0,
                   "--prior", "none") for path in (cut, plain)]
    assert [r.returncode for r in results] == [0, 0], results[0].stderr
    table = [r.stdout[r.stdout.index("L00"):] for r in results]
    assert table[0] == table[1]
    wide = run("from-photo", cut, "--circle", 48, 48, 47, "--direction", 0, 1, 0)
    assert wide.returncode == 1 and "transparent" in wide.stderr, wide.stderr


def test_from_photo_refuses_bad_input_in_one_line(tmp_path):
    photo = write_exr(tmp_path / "ball.exr", np.zeros((64, 64, 3)))
    for extra, message in [
        (("--circle", 500, 32, 10, "--direction", 0, 1, 0), "outside the 64×64 image"),
        (("--circle", 32, 32, 20, "--direction", 0, 1, 0), "black"),
        (("--circle", 32, 32, 20), "no camera"),
        (("--detect", "--direction", 0, 1, 0), "no ball found in 'ball.exr'"),
    ]:
        result = run("from-photo", photo, *extra)
        assert result.returncode == 1
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1 and message in lines[0], result.stderr


def test_from_photo_with_both_balls_and_a_second_photo(tmp_path):
    """--chrome (a mirror-ball image of the same nine-term world, 0.5× exposure) prints the
    exposure match; --prior photo with --second fills the unseen side from the back."""
    from sh_lighting.core.equirect import texel_directions
    from sh_lighting.core.mirror_ball import mirror_ball_image
    from sh_lighting.core.sh import sh_basis

    front, back = camera_looking((0.0, 1.0, 0.0)), camera_looking((0.0, -1.0, 0.0))
    photo = write_exr(tmp_path / "front.exr",
                      core_photo.ball_picture(LIGHT, 64, 64, (32, 32, 30), front))
    second = write_exr(tmp_path / "back.exr",
                       core_photo.ball_picture(LIGHT, 64, 64, (32, 32, 30), back))
    world = sh_basis(texel_directions(64, 128)) @ LIGHT
    chrome = write_exr(tmp_path / "chrome.exr", 0.5 * mirror_ball_image(world, 128))
    out = tmp_path / "ball.json"
    result = run("from-photo", photo, "--circle", 32, 32, 30, "--direction", 0, 1, 0,
                 "--prior", "photo", "--second", second, "--second-circle", 32, 32, 30,
                 "--second-direction", 0, -1, 0, "--chrome", chrome, "--out", out)
    assert result.returncode == 0, result.stderr
    assert "unseen side: second photo" in result.stdout
    # The chrome ball's image is half as bright: × 0.5 (nearest texels: within 1 %).
    line, = [x for x in result.stdout.splitlines() if x.startswith("Both balls: exposure ×")]
    assert float(line.split("×")[1].split()[0]) == pytest.approx(0.5, rel=0.01), line
    stored, _ = read_preset(out)
    assert np.abs(stored - LIGHT).max() < 1e-3 * np.abs(LIGHT).max()
    refused = run("from-photo", photo, "--circle", 32, 32, 30, "--direction", 0, 1, 0,
                  "--prior", "photo")
    assert refused.returncode == 1 and "--prior photo needs --second" in refused.stderr
