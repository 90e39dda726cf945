"""The lightmap atlas (``core/lightmap``): faces laid flat at one texel size, apart, inside
the square, the texel at (0, 0) left empty."""

import numpy as np
import pytest

from sh_lighting.core import lightmap


def _quad(size, z=0.0, offset=(0.0, 0.0)):
    x0, y0 = offset
    positions = np.array([[x0, y0, z], [x0 + size, y0, z], [x0 + size, y0 + size, z],
                          [x0, y0 + size, z]])
    return positions, np.array([0]), np.array([4])


def _cube(size):
    """The six faces of an axis-aligned cube, corners per face (24)."""
    h = size / 2.0
    faces = []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            u, v = [a for a in range(3) if a != axis]
            quad = []
            for a, b in ((-h, -h), (h, -h), (h, h), (-h, h)):
                p = np.zeros(3)
                p[axis], p[u], p[v] = sign * h, a, b
                quad.append(p)
            faces.append(quad)
    positions = np.array(faces).reshape(-1, 3)
    return positions, np.arange(6) * 4, np.full(6, 4)


def test_a_flat_face_keeps_its_shape_at_the_texel_size():
    atlas = lightmap.pack([_quad(8.0)], texel=8.0 / 100)
    uv = atlas.uv[0] * atlas.size
    assert atlas.size == 128
    side = np.linalg.norm(uv[1] - uv[0])
    assert side == pytest.approx(100.0, rel=1e-12)
    assert np.linalg.norm(uv[2] - uv[1]) == pytest.approx(100.0, rel=1e-12)
    assert uv.min() >= lightmap.PAD - 1e-9 and uv.max() <= atlas.size
    assert atlas.covered == 100 * 100


def test_charts_do_not_overlap_and_leave_the_origin_empty():
    meshes = [_cube(1.0), _quad(8.0), _quad(0.3, offset=(5.0, 5.0))]
    atlas = lightmap.pack(meshes, texel=0.02)
    boxes = []
    for uv, (_, starts, totals) in zip(atlas.uv, meshes):
        for start, total in zip(starts, totals):
            corners = uv[start:start + total] * atlas.size
            boxes.append((corners.min(axis=0), corners.max(axis=0)))
    for i, (low, high) in enumerate(boxes):
        assert (low >= lightmap.PAD - 1e-9).all() and (high <= atlas.size + 1e-9).all()
        for other_low, other_high in boxes[i + 1:]:
            gap = np.maximum(other_low - high, low - other_high).max()
            assert gap >= 2 * lightmap.PAD - 1e-6, gap  # apart by both paddings


def test_the_texel_grows_until_the_charts_fit():
    atlas = lightmap.pack([_quad(100.0)], texel=0.01, max_size=256)
    assert atlas.size <= 256
    assert atlas.texels[0] >= 100.0 / (256 - 2 * lightmap.PAD)
    assert atlas.texels[0] < np.sqrt(2.0) * 100.0 / (256 - 2 * lightmap.PAD)


def test_a_warped_quad_and_a_degenerate_face_get_finite_coordinates():
    positions = np.array([[0, 0, 0], [1, 0, 0.2], [1, 1, 0], [0, 1, 0.2],
                          [2, 2, 0], [2, 2, 0], [2, 2, 0]], dtype=float)
    atlas = lightmap.pack([(positions, np.array([0, 4]), np.array([4, 3]))], texel=0.05)
    assert np.isfinite(atlas.uv[0]).all()


def test_texels_grow_together_to_the_budget():
    assert list(lightmap.within_budget([64.0, 1.0], [0.0625, 0.01], budget=1e6)) == [0.0625, 0.01]
    grown = lightmap.within_budget([64.0, 1.0], [0.0625, 0.01], budget=16384)
    assert grown[0] / grown[1] == pytest.approx(6.25)
    assert 64.0 / grown[0] ** 2 + 1.0 / grown[1] ** 2 == pytest.approx(16384)


def test_each_mesh_keeps_its_own_texel_size():
    atlas = lightmap.pack([_quad(8.0), _quad(1.0)], texel=[8.0 / 100, 1.0 / 50])
    assert np.linalg.norm(atlas.uv[0][1] - atlas.uv[0][0]) * atlas.size == pytest.approx(100.0)
    assert np.linalg.norm(atlas.uv[1][1] - atlas.uv[1][0]) * atlas.size == pytest.approx(50.0)


def test_push_pull_keeps_known_texels_and_fills_the_rest_from_them():
    values = np.zeros((8, 8, 2))
    known = np.zeros((8, 8), dtype=bool)
    values[2:4, 2:4] = (3.0, -1.0)
    known[2:4, 2:4] = True
    values[6, 6] = (5.0, 5.0)
    known[6, 6] = True
    filled = lightmap.push_pull(values, known)
    assert np.array_equal(filled[known], values[known])
    assert np.array_equal(filled[0, 0], (3.0, -1.0))  # only the block is near
    low, high = values[known].min(axis=0), values[known].max(axis=0)
    assert ((filled >= low) & (filled <= high)).all()  # means of known texels only
