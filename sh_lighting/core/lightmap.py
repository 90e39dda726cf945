"""A lightmap atlas: every face of some meshes laid flat in one square texture, the same
texel size everywhere (per-texel transfer, as production engines store SH lightmaps).

Each face is its own chart: its corners projected on the face's plane (the frame of its
normal), placed on shelves (tallest first) with ``PAD`` empty texels around it, so that a
bake's margin can dilate each chart without reaching the next. The texel at (0, 0) is
never covered: a mesh without the atlas's UV map reads (0, 0) and gets nothing.
"""

import math
from typing import NamedTuple

import numpy as np

PAD = 4  # texels around each chart (the bake's margin dilates 2 into it)
MAX_SIZE = 2048


class Atlas(NamedTuple):
    size: int  # texels across the square atlas
    texels: list  # world units per texel, per mesh
    uv: list  # per mesh, (corners, 2) UV coordinates in 0 … 1
    covered: int  # texels inside charts


def _frame(normal):
    """Two unit vectors spanning the plane of ``normal`` (n, 3): (n, 3) each."""
    helper = np.where(np.abs(normal[:, 2:3]) < 0.9, [[0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]])
    u = np.cross(helper, normal)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    return u, np.cross(normal, u)


def face_charts(positions, loop_starts, loop_totals):
    """Per face, its corners in the face's plane, minimum at 0: ((corners, 2) flat
    coordinates in world units, (faces, 2) extents). ``positions``: (corners, 3) the world
    position of each corner, faces given as Blender's polygons (loop_start, loop_total)."""
    face_of = np.repeat(np.arange(len(loop_starts)), loop_totals)
    centre = np.add.reduceat(positions, loop_starts, axis=0) / loop_totals[:, None]
    # Newell's normal: right for any planar polygon, a best fit for a warped one.
    following = np.arange(len(positions)) + 1
    last = loop_starts + loop_totals - 1
    following[last] = loop_starts
    a, b = positions - centre[face_of], positions[following] - centre[face_of]
    normal = np.add.reduceat(np.cross(a, b), loop_starts, axis=0)
    length = np.linalg.norm(normal, axis=1, keepdims=True)
    degenerate = length[:, 0] <= 0.0
    normal[degenerate] = (0.0, 0.0, 1.0)
    normal /= np.where(degenerate[:, None], 1.0, length)
    u, v = _frame(normal)
    flat = np.stack([np.einsum("ij,ij->i", a, u[face_of]), np.einsum("ij,ij->i", a, v[face_of])],
                    axis=1)
    low = np.minimum.reduceat(flat, loop_starts, axis=0)
    high = np.maximum.reduceat(flat, loop_starts, axis=0)
    return flat - low[face_of], high - low


def _shelves(sizes, width):
    """Offsets (n, 2) of rectangles ``sizes`` (n, 2 whole texels, padding included) on
    shelves of ``width`` texels starting at x = 0, tallest first; and the height used."""
    order = np.argsort(-sizes[:, 1], kind="stable")
    offsets = np.zeros_like(sizes)
    x = y = shelf = 0
    for index in order:
        w, h = sizes[index]
        if x + w > width:
            x, y, shelf = 0, y + shelf, 0
        offsets[index] = (x, y)
        x, shelf = x + w, max(shelf, h)
    return offsets, y + shelf


def pack(meshes, texel, max_size=MAX_SIZE):
    """Lay out ``meshes`` (each (positions, loop_starts, loop_totals) as ``face_charts``
    takes) at ``texel`` world units per texel (one for all, or one per mesh); an ``Atlas``
    (its ``texels``: each mesh's, as laid out). The texels grow together (by √2 steps) until the
    charts fit ``max_size``; the atlas is the smallest power of two that holds them."""
    charts = [face_charts(*mesh) for mesh in meshes]
    extents = np.concatenate([extent for _, extent in charts])
    scales = np.broadcast_to(np.asarray(texel, dtype=float), (len(meshes),))
    per_face = np.repeat(scales, [len(m[1]) for m in meshes])[:, None]
    grow = 1.0
    while True:
        sizes = np.ceil(extents / (per_face * grow)).astype(np.int64) + 2 * PAD
        size = 1 << max(4, math.ceil(math.log2(math.sqrt(float(np.prod(sizes, axis=1).sum()))
                                               + 1.0)))
        while size <= max_size:
            offsets, height = _shelves(sizes, size)
            if height <= size:
                break
            size *= 2
        if size <= max_size:
            break
        grow *= math.sqrt(2.0)
    uvs, first = [], 0
    for (flat, extent), (_, loop_starts, loop_totals), scale in zip(charts, meshes, scales):
        faces = len(loop_starts)
        face_of = np.repeat(np.arange(faces), loop_totals) + first
        texels = offsets[face_of] + PAD + flat / (scale * grow)
        uvs.append(texels / size)
        first += faces
    covered = int(np.prod(np.ceil(extents / (per_face * grow)), axis=1).sum())
    return Atlas(size, [float(s * grow) for s in scales], uvs, covered)


def within_budget(areas, texels, budget):
    """``texels`` (world units per texel, one per mesh of surface ``areas``) grown together
    so that the meshes cover at most ``budget`` texels."""
    texels = np.asarray(texels, dtype=float)
    covered = float(np.sum(np.asarray(areas, dtype=float) / texels ** 2))
    return texels * max(1.0, math.sqrt(covered / budget))


def fill_hidden(values, written, seen, steps=PAD):
    """``values`` (k, size, size, c) with the texels of ``written`` that are not ``seen``
    (texels under another object: hidden, black, and blurred into their visible neighbours by
    bilinear filtering) replaced by the mean of their seen 4-neighbours, ``steps`` rings deep;
    texels never written set to 0. Returns a new array."""
    values = np.where(written[None, :, :, None], values, 0.0)
    valid = written & seen
    for _ in range(steps):
        missing = written & ~valid
        if not missing.any():
            break
        total = np.zeros_like(values)
        count = np.zeros(valid.shape)
        for axis, shift in ((0, 1), (0, -1), (1, 1), (1, -1)):
            neighbour = np.roll(valid, shift, axis=axis)
            total += np.roll(np.where(valid[None, :, :, None], values, 0.0), shift, axis=axis + 1)
            count += neighbour
        fill = missing & (count > 0)
        values = np.where(fill[None, :, :, None], total / np.maximum(count, 1)[None, :, :, None],
                          values)
        valid = valid | fill
    return values


def push_pull(values, known):
    """``values`` (size, size, c), size a power of two, with the texels not ``known`` filled
    from the known ones around them (push-pull: averages of the known texels down a pyramid,
    read back up for the unknown ones), so that a filtered or mipmapped read of a chart's
    edge does not blend in empty texels. Returns a new array."""
    levels = [(np.where(known[..., None], values, 0.0), known.astype(float))]
    while levels[-1][0].shape[0] > 1:
        total, weight = levels[-1]
        h = total.shape[0] // 2
        summed = (total * weight[..., None]).reshape(h, 2, h, 2, -1).sum(axis=(1, 3))
        count = weight.reshape(h, 2, h, 2).sum(axis=(1, 3))
        mean = summed / np.maximum(count, 1e-30)[..., None]
        levels.append((mean, (count > 0).astype(float)))
    filled = levels[-1][0]
    for total, weight in reversed(levels[:-1]):
        coarse = np.repeat(np.repeat(filled, 2, axis=0), 2, axis=1)
        filled = np.where(weight[..., None] > 0, total, coarse)
    return filled
