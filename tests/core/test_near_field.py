"""The near field's cells: their count from the five-times rule, the cap, their centres."""

import numpy as np
import pytest

from sh_lighting.core.near_field import MAX_HALF_SIZE, is_near, near_field_cells

LINEAR = (1.195, 0.21, 0.0)  # Prolicht E30-0019's opening (length along Y, width along X)


@pytest.mark.parametrize("distance, counts", [
    (0.0, (1, 1)),  # off: the far field
    (None, (1, 1)),
    (6.0, (1, 1)),  # ≥ 5 × 1.195 m: far
    (5.9, (2, 1)),  # just inside: the length is cut in two, the width (1.05 m ≤ 5.9) is not
    (2.0, (3, 1)),  # ⌈5 × 1.195 / 2⌉ = 3
    (0.45, (4, 3)),  # 14 capped at 4; ⌈5 × 0.21 / 0.45⌉ = 3
    (0.01, (4, 4)),
])
def test_count_from_the_five_times_rule(distance, counts):
    cells = near_field_cells(LINEAR, distance)
    assert cells.counts == counts
    assert cells.count == counts[0] * counts[1]
    assert cells.near == (counts != (1, 1))
    assert is_near(LINEAR, distance) == cells.near


def test_each_uncapped_cell_is_in_its_own_far_field():
    for distance in np.linspace(0.8, 7.0, 40):
        cells = near_field_cells(LINEAR, distance)
        n_y, n_x = cells.counts
        assert LINEAR[0] / n_y <= distance / 5 + 1e-9 or n_y == 4
        assert LINEAR[1] / n_x <= distance / 5 + 1e-9 or n_x == 4


def test_centres_tile_the_opening():
    cells = near_field_cells(LINEAR, 0.45)
    x, y, z = cells.centres.T
    assert np.allclose(z, 0.0)
    assert np.allclose(sorted(set(np.round(y, 9))), [-0.448125, -0.149375, 0.149375, 0.448125])
    assert np.allclose(sorted(set(np.round(x, 9))), [-0.07, 0.0, 0.07])
    assert cells.half_size == pytest.approx(0.5 * 1.195 / 4)
    far = near_field_cells(LINEAR, 0.0)
    assert np.allclose(far.centres, 0.0) and far.half_size == MAX_HALF_SIZE  # as the far radius


def test_circle_and_point_openings():
    circle = (-0.662, -0.662, 0.0)  # IES: a circle of that diameter, cut as its square
    assert near_field_cells(circle, 1.0).counts == (4, 4)
    assert near_field_cells(circle, 3.4).counts == (1, 1)  # ≥ 3.31 m
    assert near_field_cells((0.0, 0.0, 0.0), 0.01).counts == (1, 1)  # a point is never near
    assert near_field_cells((0.0, -0.12, 0.0), 0.3).counts == (2, 2)  # BEGA's 12 cm disc
