"""Frame changes of lighting coefficients: the paper's y-up probes, Blender's z up, glTF's y up."""

import json
from math import sqrt
from pathlib import Path

import numpy as np
import pytest
from quadrature import random_directions

from sh_lighting.core import irradiance, sh_basis
from sh_lighting.core.frames import (
    BLENDER_TO_Y_UP,
    PAPER_TO_BLENDER,
    blender_to_y_up,
    change_frame,
    frame_sh_matrix,
    paper_to_blender,
    y_up_to_blender,
)
from sh_lighting.formats.presets import read_preset
from sh_lighting.core.rotation import sh_rotation_matrix

ROUNDING = 1e-14  # a few ulps of values of order 1: what an exact formula leaves in float64
REPO = Path(__file__).resolve().parents[2]
FIGURE2 = REPO / "tests" / "data" / "figure2_coefficients.json"
BANDS = (slice(0, 1), slice(1, 4), slice(4, 9))


def figure2_probes():
    return {k: np.array(v) for k, v in json.loads(FIGURE2.read_text())["probes"].items()}


def band_energies(c):
    return np.stack([(c[band] ** 2).sum(axis=0) for band in BANDS])


def test_figure2_data_is_in_the_repository():
    assert set(figure2_probes()) == {"grace_cathedral", "eucalyptus_grove", "st_peters_basilica"}


@pytest.mark.parametrize("matrix", [PAPER_TO_BLENDER, BLENDER_TO_Y_UP])
def test_frame_matrices_are_proper_rotations(matrix):
    assert np.array_equal(matrix @ matrix.T, np.eye(3))
    assert np.linalg.det(matrix) == pytest.approx(1.0, abs=1e-15)


def test_axes_go_where_reference_md_says():
    # (x, y, z)_blender = (x, -z, y)_paper: the paper's up (+y) is Blender's up (+z).
    assert np.array_equal(PAPER_TO_BLENDER @ [0, 1, 0], [0, 0, 1])
    assert np.array_equal(PAPER_TO_BLENDER @ [0, 0, 1], [0, -1, 0])
    # Blender's glTF exporter: (x, y, z)_blender -> (x, z, -y)_gltf.
    assert np.array_equal(BLENDER_TO_Y_UP @ [1.0, 2.0, 3.0], [1.0, 3.0, -2.0])


@pytest.mark.parametrize("name", ["grace_cathedral", "eucalyptus_grove", "st_peters_basilica"])
def test_figure2_conversion_keeps_band_energies_and_moves_the_vertical_moment(name):
    paper = figure2_probes()[name]
    blender = paper_to_blender(paper)
    assert np.abs(band_energies(blender) - band_energies(paper)).max() < ROUNDING
    assert np.array_equal(blender[0], paper[0])  # L00
    assert np.array_equal(blender[2], paper[1])  # L10 (Blender) = L1-1 (paper): the up moment
    assert np.array_equal(blender[1], -paper[2])  # L1-1 (Blender) = -L10 (paper)
    assert np.array_equal(blender[3], paper[3])  # L11: x is shared


@pytest.mark.parametrize("name", ["grace_cathedral", "eucalyptus_grove", "st_peters_basilica"])
def test_figure2_conversion_is_the_same_lighting_function(name):
    """Radiance Σ L_lm Y_lm at a direction equals the paper's at the same physical direction."""
    paper = figure2_probes()[name]
    omega_blender = random_directions(200, seed=1)
    omega_paper = omega_blender @ PAPER_TO_BLENDER  # p = Mᵀ b for each row b
    radiance_blender = sh_basis(omega_blender) @ paper_to_blender(paper)
    radiance_paper = sh_basis(omega_paper) @ paper
    assert np.abs(radiance_blender - radiance_paper).max() < ROUNDING


def test_band2_of_blender_to_y_up_matches_the_hand_derivation():
    """Substituting (x', y', z') = (x, z, -y) into the paper's table, using x² + y² + z² = 1."""
    c = np.random.default_rng(2).normal(size=(9, 3))
    L00, L1m1, L10, L11, L2m2, L2m1, L20, L21, L22 = c
    h = sqrt(3.0) / 2.0
    expected = np.stack([
        L00, L10, -L1m1, L11,
        L21, -L2m1, -0.5 * L20 - h * L22, -L2m2, -h * L20 + 0.5 * L22,
    ])
    assert np.abs(blender_to_y_up(c) - expected).max() < ROUNDING


def test_irradiance_is_the_same_at_the_same_physical_normal():
    c = np.random.default_rng(3).normal(size=(9, 3))
    n = random_directions(300, seed=4)
    y_up = irradiance(blender_to_y_up(c), n @ BLENDER_TO_Y_UP.T)
    assert np.abs(y_up - irradiance(c, n)).max() < ROUNDING


def test_round_trips_are_exact_to_rounding_and_exact_in_bands_0_and_1():
    c = np.random.default_rng(5).normal(size=(9, 3))
    back = y_up_to_blender(blender_to_y_up(c))
    assert np.array_equal(back[:4], c[:4])
    assert np.abs(back - c).max() < ROUNDING


def test_the_paper_frame_is_the_gltf_frame():
    c = np.random.default_rng(6).normal(size=(9, 3))
    assert np.array_equal(paper_to_blender(c), y_up_to_blender(c))


def test_snapped_matrix_agrees_with_least_squares_and_holds_exact_values():
    snapped = frame_sh_matrix(BLENDER_TO_Y_UP)
    assert np.abs(snapped - sh_rotation_matrix(BLENDER_TO_Y_UP)).max() < 1e-12
    assert set(np.unique(np.abs(snapped))) == {0.0, 0.5, sqrt(3.0) / 2.0, 1.0}
    assert np.abs(snapped @ snapped.T - np.eye(9)).max() < 1e-15


def test_general_rotations_and_higher_orders_go_through_unsnapped():
    r = np.array([[0.6, -0.8, 0.0], [0.8, 0.6, 0.0], [0.0, 0.0, 1.0]])
    assert np.array_equal(frame_sh_matrix(r), sh_rotation_matrix(r))
    c16 = np.random.default_rng(7).normal(size=(16, 3))
    back = change_frame(change_frame(c16, BLENDER_TO_Y_UP), BLENDER_TO_Y_UP.T)
    assert np.abs(back - c16).max() < 1e-12


def test_a_mirror_is_not_a_frame_change():
    with pytest.raises(ValueError, match="not a rotation"):
        change_frame(np.zeros((9, 3)), np.diag([-1.0, 1.0, 1.0]))


def test_bad_coefficients_are_refused():
    with pytest.raises(ValueError, match="shape"):
        paper_to_blender(np.zeros((9, 4)))
    with pytest.raises(ValueError, match="NaN"):
        blender_to_y_up(np.full((9, 3), np.nan))


@pytest.mark.parametrize("name", ["grace_cathedral", "eucalyptus_grove", "st_peters_basilica"])
def test_shipped_figure2_presets_equal_a_fresh_conversion(name):
    coeffs, metadata = read_preset(REPO / "presets" / f"{name}.json")
    assert np.abs(coeffs - paper_to_blender(figure2_probes()[name])).max() < ROUNDING
    assert metadata["source"] == "Ramamoorthi & Hanrahan 2001, Figure 2"
    assert "y-up" in metadata["notes"]
