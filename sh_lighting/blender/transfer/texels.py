"""Per-texel transfer for meshes too coarse to carry a shadow at their corners.

A 4-vertex floor under a cube has no corner where the shadow falls; its T_lm are baked instead
into an atlas (``core.lightmap``: every face flat, one texel size) on a UV map the add-on adds,
``UV_NAME`` (the user's UV maps untouched): nine float images ``IMAGE_NAMES``, packed in the
.blend. One atlas per file holds every object baked per texel. The "SH Transfer" group reads
``UV_NAME`` with an Attribute node: a mesh without it reads (0, 0), an empty texel.
"""

import bpy
import numpy as np

from ...core import lightmap
from ..data import compat
from .stale import BOUNCE_IMAGE, IMAGE_MARKER, IMAGE_NAMES, RECORD, UV_NAME, record

SCRATCH_IMAGE = "SH Transfer bake (temporary)"
SCRATCH_NODE = "sh_transfer_bake_target"
MARGIN = 2  # texels the bake extends each chart by (``lightmap.PAD`` leaves room)
UNWRITTEN = -1.0  # the scratch image before a bake: texels the bake leaves so are no chart's
ORIGIN = 2  # texels across the atlas's corner at (0, 0) kept 0 (``lightmap.PAD`` leaves room)
HIDDEN = 0.02  # texels getting less of a constant world than this are under another object
BUDGET = 1 << 18  # texels the atlas may cover before its texel grows (~2 min at 64 samples)


def is_texel_bake(obj):
    info = record(obj)
    return bool(info) and info.get("store") == "TEXELS"


def world_corners(obj):
    """(positions (corners, 3) in world space, loop_starts, loop_totals) of ``obj``'s mesh."""
    mesh = obj.data
    coordinates = np.empty(len(mesh.vertices) * 3)
    mesh.vertices.foreach_get("co", coordinates)
    matrix = np.array(obj.matrix_world, dtype=float)
    points = coordinates.reshape(-1, 3) @ matrix[:3, :3].T + matrix[:3, 3]
    corners = np.empty(len(mesh.loops), dtype=np.int64)
    mesh.loops.foreach_get("vertex_index", corners)
    starts = np.empty(len(mesh.polygons), dtype=np.int64)
    totals = np.empty(len(mesh.polygons), dtype=np.int64)
    mesh.polygons.foreach_get("loop_start", starts)
    mesh.polygons.foreach_get("loop_total", totals)
    return points[corners], starts, totals


def layout(objects, texel_sizes):
    """A ``lightmap.Atlas`` of ``objects`` at ``texel_sizes`` (world units per texel, one per
    object), all coarser together if they would cover more than ``BUDGET`` texels."""
    meshes = [world_corners(o) for o in objects]
    areas = [float(np.sum(extent[:, 0] * extent[:, 1]))
             for extent in (lightmap.face_charts(*m)[1] for m in meshes)]
    return lightmap.pack(meshes, lightmap.within_budget(areas, texel_sizes, BUDGET))


def median_edge(obj):
    """The median edge length of ``obj``'s mesh in world units (its scale applied)."""
    mesh = obj.data
    coordinates = np.empty(len(mesh.vertices) * 3)
    mesh.vertices.foreach_get("co", coordinates)
    edges = np.empty(len(mesh.edges) * 2, dtype=np.int64)
    mesh.edges.foreach_get("vertices", edges)
    points = coordinates.reshape(-1, 3) @ np.array(obj.matrix_world, dtype=float)[:3, :3].T
    pairs = points[edges.reshape(-1, 2)]
    if len(pairs) == 0:
        return 0.0
    return float(np.median(np.linalg.norm(pairs[:, 0] - pairs[:, 1], axis=1)))


def set_uv(obj, uv, name=UV_NAME):
    """Write ``uv`` (corners, 2) into the UV map ``name`` (made if missing, the active and
    render UV maps kept)."""
    layers = obj.data.uv_layers
    active = layers.active.name if layers.active else None
    render = next((layer.name for layer in layers if layer.active_render), None)
    layer = layers.get(name) or layers.new(name=name, do_init=False)
    layer.data.foreach_set("uv", uv.astype(np.float32).ravel())
    if active and layers.get(active) is not None:
        layers.active = layers[active]
    if render and layers.get(render) is not None:
        layers[render].active_render = True


def fill_hidden(transfer, constant, size):
    """``transfer`` (9, size², 3) with the texels under other objects filled from their
    neighbours (``lightmap.fill_hidden``): those the constant world's bake ``constant``
    (size², 3; 1 where nothing occludes) lit less than ``HIDDEN``; the texels outside the
    charts from the charts around them."""
    written = (constant != UNWRITTEN).all(axis=1).reshape(size, size)
    seen = (constant.mean(axis=1) >= HIDDEN).reshape(size, size)
    grid = lightmap.fill_hidden(transfer.reshape(len(transfer), size, size, -1), written, seen)
    # Every other texel from the charts (push-pull): EEVEE mipmaps the images, and a mip
    # level that averaged in empty texels would darken the charts' edges; the texels at (0, 0)
    # stay 0 for the meshes without the UV map.
    stacked = np.moveaxis(grid, 0, 2).reshape(size, size, -1)
    stacked = lightmap.push_pull(stacked, written)
    stacked[:ORIGIN, :ORIGIN] = 0.0
    grid = np.moveaxis(stacked.reshape(size, size, len(transfer), -1), 2, 0)
    return grid.reshape(transfer.shape)


def foreign_image():
    """The name of an image not the add-on's that has an atlas image's name, or None."""
    for index, name in enumerate(IMAGE_NAMES + (BOUNCE_IMAGE,)):
        image = bpy.data.images.get(name)
        if image is not None and (image.library is not None or image.get(IMAGE_MARKER) != index):
            return name
    return None


def store(transfer, size):
    """Write (9, size², 3) ``transfer`` into the nine atlas images (made or resized), and a
    tenth row, the lamps' bounce, into ``BOUNCE_IMAGE`` (deleted when there is none), packed
    in the .blend as float EXR; the images."""
    stored = []
    rgba = np.ones((size * size, 4), dtype=np.float32)
    names = IMAGE_NAMES + (BOUNCE_IMAGE,)
    if len(transfer) == len(IMAGE_NAMES):
        old = bpy.data.images.get(BOUNCE_IMAGE)  # the add-on's (``foreign_image`` checked)
        if old is not None:
            bpy.data.images.remove(old)
    for index, (name, values) in enumerate(zip(names, transfer)):
        image = bpy.data.images.get(name)  # the add-on's (``foreign_image`` checked first)
        if image is not None and tuple(image.size) != (size, size):
            bpy.data.images.remove(image)
            image = None
        if image is None:
            image = bpy.data.images.new(name, size, size, alpha=False, float_buffer=True,
                                        is_data=True)
            image[IMAGE_MARKER] = index
        rgba[:, :3] = values
        image.pixels.foreach_set(rgba.ravel())
        image.file_format = "OPEN_EXR"
        image.pack()
        stored.append(image)
    return stored


def texel_objects():
    """Local objects of the file holding a per-texel bake."""
    return [o for o in bpy.data.objects if o.library is None and RECORD in o
            and is_texel_bake(o)]


class BakeTarget:
    """The scratch image and the temporary nodes, slots and materials Cycles' image bake
    needs (an active Image Texture node in every material of each object); ``restore``
    takes them all out again."""

    def __init__(self, objects, size):
        self.image = bpy.data.images.new(SCRATCH_IMAGE, size, size, alpha=False,
                                         float_buffer=True, is_data=True)
        self.image.pixels.foreach_set(np.full(size * size * 4, UNWRITTEN, dtype=np.float32))
        self.nodes, self.slots, self.appended, self.materials = [], [], [], []
        seen = set()
        for obj in objects:
            if len(obj.material_slots) == 0:
                obj.data.materials.append(self._material())
                self.appended.append(obj.data)
            for slot in obj.material_slots:
                if slot.material is None:
                    self.slots.append((obj, slot.slot_index))
                    slot.material = self._material()
                material = slot.material
                if material.as_pointer() in seen:
                    continue
                seen.add(material.as_pointer())
                tree = compat.ensure_node_tree(material)
                node = tree.nodes.new("ShaderNodeTexImage")
                node.name = SCRATCH_NODE
                node.image = self.image
                self.nodes.append((material, node.name, tree.nodes.active))
                tree.nodes.active = node

    def _material(self):
        """A stand-in for no material: Blender renders a missing one as diffuse grey 0.8."""
        material = bpy.data.materials.new("SH Transfer bake (temporary)")
        tree = compat.ensure_node_tree(material)
        tree.nodes.clear()
        diffuse = tree.nodes.new("ShaderNodeBsdfDiffuse")
        diffuse.inputs["Color"].default_value = (0.8, 0.8, 0.8, 1.0)
        output = tree.nodes.new("ShaderNodeOutputMaterial")
        tree.links.new(diffuse.outputs["BSDF"], output.inputs["Surface"])
        self.materials.append(material)
        return material

    def pixels(self):
        """The scratch image as (size², 3) float64."""
        size = self.image.size[0]
        values = np.empty(size * size * 4, dtype=np.float32)
        self.image.pixels.foreach_get(values)
        return values.reshape(-1, 4)[:, :3].astype(np.float64)

    def restore(self):
        for material, name, active in self.nodes:
            tree = material.node_tree
            node = tree.nodes.get(name) if tree else None
            if node is not None:
                tree.nodes.remove(node)
            if tree is not None and active is not None:
                try:
                    tree.nodes.active = active
                except ReferenceError:
                    pass
        for obj, index in self.slots:
            obj.material_slots[index].material = None
        for mesh in self.appended:
            mesh.materials.clear()  # it had none (``__init__``)
        for material in self.materials:
            bpy.data.materials.remove(material)
        bpy.data.images.remove(self.image)
