"""Whether a baked mesh has corners where the shadows fall on it.

The transfer is stored per face corner and interpolated across each face, so a shadow shows
only where the receiver has vertices: a plain 4-vertex floor under a cube keeps its four far
corners unoccluded and gets no contact shadow at all. An occluder of size s (the largest side
of its bounding box) darkens its surroundings most within about s/4 of it; where the faces of
the receiver that pass there (the separating axis test) have a median longest edge over s/2,
the shadow falls between their corners: the receiver is called too coarse, with the edge
length that resolves it (s/4, four edges across the occluder). Only occluders at most half
the receiver's size count (a local shadow: the floor under a cube darkens the cube's sides
smoothly, which its corners can carry).
"""

import bpy
import numpy as np

from .stale import RENDERED_TYPES, rendered_objects, view_layer_of

COARSE = 0.5  # faces whose longest edge exceeds this fraction of the occluder's size
REACH = 0.25  # the contact shadow: this fraction of the occluder's size around it
EDGES_ACROSS = 4  # the suggested edge: the occluder's size over this
LOCAL = 0.5  # occluders at most this fraction of the receiver's size cast a local shadow


def _world_box(obj, depsgraph):
    evaluated = obj.evaluated_get(depsgraph) if depsgraph is not None else obj
    corners = np.array([tuple(c) + (1.0,) for c in evaluated.bound_box], dtype=float)
    world = corners @ np.array(evaluated.matrix_world, dtype=float).T
    return world[:, :3].min(axis=0), world[:, :3].max(axis=0)


def _world_mesh(obj, depsgraph):
    """(vertices (n, 3), triangles (m, 3) vertex indices) of ``obj`` in world space."""
    evaluated = obj.evaluated_get(depsgraph) if depsgraph is not None else obj
    mesh = evaluated.data if isinstance(evaluated.data, bpy.types.Mesh) else obj.data
    coordinates = np.empty(len(mesh.vertices) * 3, dtype=float)
    mesh.vertices.foreach_get("co", coordinates)
    matrix = np.array(evaluated.matrix_world, dtype=float)
    vertices = coordinates.reshape(-1, 3) @ matrix[:3, :3].T + matrix[:3, 3]
    mesh.calc_loop_triangles()
    triangles = np.empty(len(mesh.loop_triangles) * 3, dtype=np.int64)
    mesh.loop_triangles.foreach_get("vertices", triangles)
    return vertices, triangles.reshape(-1, 3)


def _touching(triangles, low, high):
    """Which of ``triangles`` (m, 3, 3) meet the box ``low``-``high`` (the separating axis
    test of Akenine-Möller 2001: the box's axes, the triangle's normal, the nine edge
    crossings); a boolean mask."""
    centre, half = (low + high) / 2.0, (high - low) / 2.0
    points = triangles - centre
    mask = np.all((points.min(axis=1) <= half) & (points.max(axis=1) >= -half), axis=1)
    points = points[mask]
    edges = [points[:, 1] - points[:, 0], points[:, 2] - points[:, 1], points[:, 0] - points[:, 2]]
    axes = [np.cross(edges[0], edges[1])]
    axes += [np.cross(np.eye(3)[i], edge) for i in range(3) for edge in edges]
    inside = np.ones(len(points), dtype=bool)
    for axis in axes:
        projected = np.einsum("mkj,mj->mk", points, axis)
        radius = np.abs(axis) @ half
        inside &= (projected.min(axis=1) <= radius) & (projected.max(axis=1) >= -radius)
    mask[mask] = inside
    return mask


def coarse_receivers(scene, receivers, depsgraph=None):
    """One line per mesh of ``receivers`` too coarse for the shadow an occluder casts on it
    (the occluder with the fewest of its vertices in reach named), with what to do."""
    return [line for _, _, line in coarse(scene, receivers, depsgraph)]


def coarse(scene, receivers, depsgraph=None):
    """(receiver, occluder size, line) for each mesh of ``receivers`` too coarse for the
    shadow an occluder casts on it (``coarse_receivers``)."""
    if depsgraph is None:
        depsgraph = bpy.context.evaluated_depsgraph_get() if bpy.context.scene == scene else None
    occluders = [o for o in rendered_objects(view_layer_of(scene))
                 if o.type in RENDERED_TYPES and o.visible_shadow]
    boxes = {o.name: _world_box(o, depsgraph) for o in occluders}
    lines = []
    for receiver in receivers:
        if receiver.type != "MESH" or len(receiver.data.vertices) == 0:
            continue
        vertices, triangles = _world_mesh(receiver, depsgraph)
        low, high = vertices.min(axis=0), vertices.max(axis=0)
        receiver_size = float((high - low).max())
        worst = None
        for occluder in occluders:
            if occluder == receiver:
                continue
            box_low, box_high = boxes[occluder.name]
            size = float((box_high - box_low).max())
            if not 0.0 < size <= LOCAL * receiver_size:
                continue
            reach = REACH * size
            near_low, near_high = box_low - reach, box_high + reach
            if (near_low > high).any() or (near_high < low).any():
                continue  # too far from the receiver to shadow it
            corners = vertices[triangles]
            touching = corners[_touching(corners, near_low, near_high)]
            if len(touching) == 0:
                continue  # none of the receiver's faces passes where the shadow falls
            longest = np.linalg.norm(touching - np.roll(touching, 1, axis=1), axis=2).max(axis=1)
            if np.median(longest) <= COARSE * size:
                continue  # faces small enough to carry the shadow
            inside = np.all((vertices >= near_low) & (vertices <= near_high), axis=1)
            count = int(np.count_nonzero(inside))
            if worst is None or (count, size) < worst[:2]:
                worst = (count, size, occluder.name, reach)
        if worst is not None:
            count, size, name, reach = worst
            lines.append((receiver, size,
                f"'{receiver.name}' is too coarse for the shadow '{name}' casts on it: {count} "
                f"of its vertices lie within {reach:.2g} m of it (the transfer is stored per "
                "corner, so the shadow falls between them): subdivide it to edges of about "
                f"{size / EDGES_ACROSS:.2g} m where the shadow falls (Edit Mode > Subdivide) "
                "and bake again"))
    return lines
