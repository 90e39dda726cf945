"""Bake the transfer vectors T_lm of picked meshes with Cycles and store them in the meshes.

Precomputed radiance transfer (Sloan, Kautz and Snyder 2002, eq. 1-3): a diffuse point
receives E(p) = Σ_lm T_lm(p) L_lm, T_lm(p) the irradiance at p under a world emitting Y_lm
(Â_l Y_lm(n) where nothing occludes, eq. 13). Cycles' Diffuse bake (Direct + Indirect, no
Color) is that irradiance / π, so T_lm = π · bake of the world Y_lm (``basis``). Stored per
face corner in the colour attributes ``ATTRIBUTE_NAMES``, or per texel (``texels``) for meshes
too coarse to carry a shadow at their corners (``coverage``), with a ``RECORD`` for ``stale``;
the scene's world, engine, samples and selection are put back, its lights hidden and SH nodes
muted during the bake. With lamps in the scene, a tenth bake (world black, lamps on, Indirect
only) stores their bounce B (``BOUNCE_ATTRIBUTE``, ``stale.BOUNCE_IMAGE``), which EEVEE lacks:
its lamps light directly but bounce nothing. Details: docs/modules.md.
"""

import contextlib
import json
import os
import sys
import time
from typing import NamedTuple

import bpy
import numpy as np

from ...core.sh import COEFFICIENT_NAMES
from ..shading import materials
from . import basis, bounce, coverage, nodes, texels
from .stale import (  # noqa: F401 (re-exported: the bake's names in one place)
    ATTRIBUTE_NAMES, BOUNCE_ATTRIBUTE, IMAGE_NAMES, RECORD, RECORD_VERSION, SCRATCH_NAME, UV_NAME,
    drop_unused_atlas, evaluated_depsgraph, geometry_fingerprint, has_transfer, missing_parts,
    record, scene_fingerprint, status, view_layer_of,
)
from . import stale

#: Cycles samples per corner: measured on the test scene (plane and box, tests/blender/
#: test_transfer.py): the relative RMSE of T against a 1024-sample bake falls as 1/√samples
#: (benchmarks/REPORT.md, "Transfer").
DEFAULT_SAMPLES = 64
MAX_SAMPLES = 1 << 16
#: Cycles' bake (CPU) per corner, sample and basis function, and per basis bake: measured on
#: the project's 2-core machine at load 9 (a 60 × 60 ground and a box, 17304 corners, 64
#: samples: 12.6 s; 3168 corners: 2.6 s); ``estimate_seconds`` prefers the file's last bake.
SECONDS_PER_CORNER_SAMPLE = 1.2e-6
SECONDS_PER_BASIS = 0.05
#: Where T_lm is stored: "AUTO" per texel for meshes ``coverage`` finds too coarse, per corner
#: for the others; "CORNERS" or "TEXELS" for every mesh.
STORES = ("AUTO", "CORNERS", "TEXELS")
SCRATCH_UV = "sh_transfer_uv_bake"  # the atlas UV map while a bake runs
#: Modifiers that keep each face's UVs inside its own chart (they move or subdivide faces, make
#: none from nothing): a mesh with these is baked per texel on what Cycles renders. Others
#: (Mirror and Array overlap the charts, Bevel and Boolean make faces between them) are refused.
TEXEL_MODIFIERS = {
    "SUBSURF", "MULTIRES", "TRIANGULATE", "WEIGHTED_NORMAL", "DISPLACE", "SMOOTH",
    "CORRECTIVE_SMOOTH", "LAPLACIANSMOOTH", "SHRINKWRAP", "CAST", "SIMPLE_DEFORM", "WAVE",
    "ARMATURE", "LATTICE", "CURVE", "HOOK", "MESH_DEFORM", "SURFACE_DEFORM", "WARP",
}


class TransferError(ValueError):
    """Objects that cannot be baked, with what to do as the message; nothing was changed."""


class BakeInfo(NamedTuple):
    objects: list  # names of the baked objects
    corners: int  # face corners baked, all objects
    vertices: int  # vertices of the baked meshes
    samples: int
    seconds: float  # wall time of the whole bake
    basis_seconds: list  # per bake of a basis world, in index order
    notes: list  # what the user should know about the result (one line each)
    texel_objects: list = []  # names of the objects baked per texel
    texels: int = 0  # texels baked (inside the atlas's charts)
    texel_seconds: float = 0.0  # of ``seconds``, Cycles' bakes of the texels

    def rates(self):
        """" (X s per 10k corners; per texel Y s, Z s per million texels)" for a report: the
        corners' and the texels' own time (a floor of 4 corners and 4096 texels is no 10k
        corners' worth), "" if nothing was baked."""
        parts = []
        if self.corners:
            per_corner = (self.seconds - self.texel_seconds) / self.corners * 1e4
            parts.append(f"{per_corner:.1f} s per 10k corners")
        if self.texels:
            parts.append(f"per texel {self.texel_seconds:.1f} s, "
                         f"{self.texel_seconds / self.texels * 1e6:.0f} s per million texels")
        return f" ({'; '.join(parts)})" if parts else ""


def _render_modifiers(obj):
    return [m for m in obj.modifiers if m.show_render]


def refusal(scene, obj, view_layer=None, store="AUTO"):
    """Why ``obj`` (a Blender object) cannot be baked in ``scene`` with ``store`` (one line:
    what is wrong and what to do), or None."""
    view_layer = view_layer or view_layer_of(scene)
    name = obj.name
    if obj.type != "MESH":
        return f"'{name}' is a {obj.type.lower()}, not a mesh: bake meshes only"
    if scene.objects.get(name) != obj:
        return f"'{name}' is not in scene '{scene.name}'"
    if obj.library is not None or obj.data.library is not None:
        return f"'{name}' is linked from a library: make it local to bake it"
    if obj.mode != "OBJECT":
        return f"'{name}' is in {obj.mode.title()} Mode: leave it to bake"
    if obj.hide_render:
        return f"'{name}' is hidden from renders: enable it for renders"
    if not obj.visible_get(view_layer=view_layer):
        return f"'{name}' is hidden in the view layer: unhide it to bake it"
    modifiers = [m.name for m in _render_modifiers(obj)
                 if store == "CORNERS" or m.type not in TEXEL_MODIFIERS]
    if modifiers:
        return (f"'{name}' has modifiers ({', '.join(modifiers)}): the transfer is stored on "
                "the mesh itself, so apply them (or disable them for renders) and bake again")
    if len(obj.data.polygons) == 0:
        return f"'{name}' has no faces: there is no surface to bake"
    sharing = [o.name for o in bpy.data.objects if o.data == obj.data and o != obj]
    if sharing:
        return (f"'{name}' shares its mesh with '{sharing[0]}' (a linked duplicate): the "
                "transfer depends on where each sits, so make it single user "
                "(Object > Relations > Make Single User) and bake again")
    instancers = [o.name for o in bpy.data.objects if o.instance_type == "COLLECTION"
                  and o.instance_collection is not None
                  and o.instance_collection.all_objects.get(name) == obj]
    if instancers:
        return (f"'{name}' is also drawn elsewhere by the collection instance "
                f"'{instancers[0]}': the transfer fits one place only, so make the instance "
                "real (Object > Apply > Make Instances Real) or bake a copy")
    return None


def remove_transfer(obj):
    """``stale.remove_transfer`` (attributes, UV map, record; the atlas once unused), the
    "SH Transfer" group rebuilt if the atlas went (its image nodes read no image)."""
    had_atlas = stale.atlas_images() is not None
    found = stale.remove_transfer(obj)
    if had_atlas and stale.atlas_images() is None and nodes.find_node_group() is not None:
        nodes.ensure_node_group()
    if had_atlas and stale.atlas_images() is None and bounce.find_group() is not None:
        bounce.ensure_group()
    return found


def check_objects(scene, objects, store="AUTO"):
    """The objects as a list if every one can be baked, else a TransferError naming the first
    problem (one line: what is wrong and what to do)."""
    if scene is None:
        raise TransferError("no scene to bake in")
    picked = list(objects)
    if not picked:
        raise TransferError("no objects to bake: select the meshes to bake")
    view_layer = view_layer_of(scene)
    for obj in picked:
        if not isinstance(obj, bpy.types.Object):
            raise TransferError(f"{obj!r} is not an object: pass Blender objects")
        reason = refusal(scene, obj, view_layer, store)
        if reason:
            raise TransferError(reason)
    if len({o.as_pointer() for o in picked}) != len(picked):
        raise TransferError("an object is picked twice: pick each once")
    return picked


class Plan(NamedTuple):
    objects: list  # the objects that can be baked
    refused: list  # (name, why not) of the others
    vertices: int
    corners: int
    seconds: float  # estimated from ``SECONDS_PER_CORNER_SAMPLE`` or the file's last bake
    coarse: list  # one line per object baked per texel, why and at what size
    texels: int = 0  # texels to bake (inside the atlas's charts)


def plan(scene, objects, samples, store="AUTO"):
    """What a bake of ``objects`` at ``samples`` would do, before it runs (a ``Plan``)."""
    view_layer = view_layer_of(scene)
    bakeable, refused = [], []
    for obj in objects:
        reason = refusal(scene, obj, view_layer, store)
        if reason:
            refused.append((obj.name, reason))
        else:
            bakeable.append(obj)
    split = _split(scene, bakeable, store)
    corners = sum(len(o.data.loops) for o in split.corner_objects)
    vertices = sum(len(o.data.vertices) for o in bakeable)
    texel_count = split.atlas.covered if split.atlas else 0
    return Plan(bakeable, refused, vertices, corners,
                estimate_seconds(scene, corners + texel_count, samples), split.lines, texel_count)


class _Split(NamedTuple):
    corner_objects: list
    texel_objects: list
    atlas: object  # a ``core.lightmap.Atlas`` of ``texel_objects``, or None
    lines: list  # one per texel object: why, at what texel size


def _split(scene, picked, store):
    """Which of ``picked`` (bakeable meshes) to bake per corner and which per texel
    (``STORES``), with the texels' atlas."""
    if store not in STORES:
        raise TransferError(f"store {store!r}: use one of {', '.join(STORES)}")
    if store == "CORNERS" or not picked:
        return _Split(list(picked), [], None, [])
    found = {o.name: size for o, size, _ in coverage.coarse(scene, picked)}
    reasons = {}
    for obj in picked:
        modifiers = [m.name for m in _render_modifiers(obj)]
        if obj.name in found:
            reasons[obj.name] = "too coarse for a shadow at its corners"
        elif modifiers:
            reasons[obj.name] = f"its modifiers ({', '.join(modifiers)}) change it at render time"
        elif store == "TEXELS":
            reasons[obj.name] = "asked for"
    chosen = [o for o in picked if o.name in reasons]
    if not chosen:
        return _Split(list(picked), [], None, [])
    atlas = texels.layout(chosen, [_texel_size(o, found.get(o.name)) for o in chosen])
    lines = []
    for obj, texel in zip(chosen, atlas.texels):
        lines.append(f"'{obj.name}' is baked per texel ({reasons[obj.name]}): "
                     f"{texel * 100:.2g} cm texels, a {atlas.size} × {atlas.size} atlas")
    return _Split([o for o in picked if o not in chosen], chosen, atlas, lines)


def _texel_size(obj, occluder_size):
    """World units per texel for ``obj``: a sixteenth of the occluder it is too coarse for,
    else a quarter of its median edge (a face of its cage gets about 4 × 4 texels), at most
    a thirty-second of its size."""
    if occluder_size:
        return occluder_size / 16.0
    size = max(obj.dimensions) / 32.0
    edge = texels.median_edge(obj) / 4.0
    return min(edge, size) if edge > 0 else size


def _points(info):
    """The corners and texels a bake (record ``info``) baked."""
    return (info.get("corners") or 0) + (info.get("texels") or 0)


def lamps_of(scene):
    """Names of ``scene``'s lamps that render (their bounce is baked, ``Bake``)."""
    view_layer = view_layer_of(scene)
    return [o.name for o in scene.objects if o.type == "LIGHT" and not o.hide_render
            and o.visible_get(view_layer=view_layer)]


def _passes(lamps):
    """The Cycles bakes a bake makes: the nine basis worlds, and the bounce of ``lamps``
    (names, ``lamps_of``) when there are any."""
    return len(ATTRIBUTE_NAMES) + (1 if lamps else 0)


def estimate_seconds(scene, corners, samples):
    """Seconds a bake of ``corners`` corners and texels at ``samples`` takes: passes ×
    (overhead + corners · samples · rate), the rate measured by the scene's last bake if any
    (its record: its time over its corners, texels and passes), else
    ``SECONDS_PER_CORNER_SAMPLE``."""
    rate = SECONDS_PER_CORNER_SAMPLE
    latest = [r for r in (record(o) for o in scene.objects) if r and _points(r)]
    if latest:
        last = max(latest, key=lambda r: r.get("baked", 0))
        passes = _passes(last.get("bounce"))
        work = _points(last) * last["samples"] * passes
        measured = (last["seconds"] - passes * SECONDS_PER_BASIS) / work
        rate = measured if measured > 0 else rate
    return _passes(lamps_of(scene)) * (SECONDS_PER_BASIS + corners * samples * rate)


def bake_transfer(scene, objects, samples=DEFAULT_SAMPLES, report=None, error_target=None,
                  store="AUTO"):
    """Bake T_lm for ``objects`` in ``scene`` (see the module docstring); a ``BakeInfo``.

    ``report(text)`` is called with a line per basis function (its time); the window
    manager's progress bar counts the nine bakes. ``error_target`` (a fraction): the samples
    are chosen for that noise (``choose_samples``) instead of ``samples``. ``store``: per
    corner or per texel (``STORES``). A TransferError (nothing changed) if an object cannot be
    baked or ``samples`` is not a whole number in 1 … MAX_SAMPLES.
    """
    job = Bake(scene, objects, samples, report, error_target, store)
    window_manager = bpy.context.window_manager
    if window_manager is not None:
        window_manager.progress_begin(0, job.steps)
    try:
        while job.done < job.steps:
            job.step()
            if window_manager is not None:
                window_manager.progress_update(job.done)
    finally:
        if window_manager is not None:
            window_manager.progress_end()
    return job.finish()


class Bake:
    """A bake in ``steps`` steps, one basis world each (and the lamps' bounce where the scene
    has lamps), the user's scene as it was between them: a window's modal operator draws its
    progress and takes Esc between steps (Cycles' bake itself cannot be stopped from Python).
    ``finish`` stores the transfer, unless the scene changed meanwhile; ``cancel`` drops what
    was baked. Nothing is stored before ``finish``."""

    def __init__(self, scene, objects, samples=DEFAULT_SAMPLES, report=None, error_target=None,
                 store="AUTO"):
        self.scene = scene
        self.picked = check_objects(scene, objects, store)
        self.notes = []
        if store != "CORNERS":  # one atlas per file: the others baked per texel join it
            view_layer = view_layer_of(scene)
            for obj in texels.texel_objects():
                if obj in self.picked:
                    continue
                if refusal(scene, obj, view_layer, store) is None:
                    self.picked.append(obj)
                    self.notes.append(f"'{obj.name}' is baked again: the objects baked per "
                                      "texel share one atlas")
        self.split = _split(scene, self.picked, store)
        if self.split.texel_objects:
            theirs = texels.foreign_image()
            if theirs:
                raise TransferError(f"the file has an image named '{theirs}' that the add-on "
                                    "did not make: rename it to bake per texel")
        self.report = report or (lambda text: None)
        self.lamps = lamps_of(scene)
        self.steps = _passes(self.lamps)
        self.started = time.perf_counter()
        if error_target is not None:
            samples, probe_noise = choose_samples(scene, self.picked, error_target,
                                                  store=store)
            chosen = (f"{samples} samples chosen for a noise of {100 * error_target:.2g} % "
                      f"(measured {100 * probe_noise:.2g} % at 16 samples)")
            self.notes.append(chosen)
            self.report(chosen)
        if (isinstance(samples, bool) or not isinstance(samples, int)
                or not 1 <= samples <= MAX_SAMPLES):
            raise TransferError(
                f"samples is {samples!r}: use a whole number from 1 to {MAX_SAMPLES}")
        self.samples = samples
        self.scene_print = scene_fingerprint(scene)
        self.bakes, self.basis_seconds = [], []
        self.texel_seconds = 0.0
        self.emission_materials = set()

    @property
    def done(self):
        return len(self.bakes)

    def step(self):
        """Bake the next basis world (the scene prepared for it and restored after)."""
        index = self.done
        lamps_pass = index == len(ATTRIBUTE_NAMES)
        began = time.perf_counter()
        saved = _Saved(self.scene, self.picked, self.split)
        try:
            saved.prepare(self.samples, lamps=lamps_pass)
            self.emission_materials |= saved.emission_materials
            self.bakes.append(_bake_basis(self.scene, saved, self.split, index))
            self.texel_seconds += saved.texel_seconds
        finally:
            saved.restore()
        self.basis_seconds.append(time.perf_counter() - began)
        what = "the lamps' bounce" if lamps_pass else COEFFICIENT_NAMES[index]
        self.report(f"Transfer {what}: {self.basis_seconds[-1]:.1f} s "
                    f"({index + 1}/{self.steps})")

    def cancel(self):
        self.bakes.clear()

    def finish(self):
        """Store the transfer and the records; a ``BakeInfo``. A TransferError (nothing
        stored) if a step is missing or the scene changed since the bake began."""
        if self.done != self.steps:
            raise TransferError(f"the bake is not complete ({self.done}/{self.steps}): bake again")
        scene, picked, notes = self.scene, self.picked, list(self.notes)
        try:
            changed = scene_fingerprint(scene) != self.scene_print
        except ReferenceError:  # an object was deleted
            changed = True
        if changed:
            self.cancel()
            raise TransferError("the scene changed during the bake: nothing stored; bake again")
        if self.emission_materials:
            notes.append("materials in Emission mode reflect no light into the bake: "
                         + ", ".join(sorted(self.emission_materials)))
        seconds = time.perf_counter() - self.started
        split, corners, vertices = self.split, 0, 0
        bounced = len(self.bakes) > len(ATTRIBUTE_NAMES)
        if bounced:
            notes.append(f"the bounce of {len(self.lamps)} lamp(s) is baked too, for EEVEE "
                         f"(lamps bounce no light there): {', '.join(self.lamps)}")
        for position, obj in enumerate(split.corner_objects):
            transfer = _finite(_transfer([bake[0][position] for bake in self.bakes]), obj, notes)
            _store(obj, transfer)
            corners += len(obj.data.loops)
            _drop_texels(obj)
        if split.texel_objects:
            atlas = split.atlas
            transfer = _finite(_transfer([bake[1] for bake in self.bakes]),
                               split.texel_objects[0], notes)
            texels.store(texels.fill_hidden(transfer, self.bakes[0][1], atlas.size), atlas.size)
            for obj, uv in zip(split.texel_objects, atlas.uv):
                texels.set_uv(obj, uv)
                for name in ATTRIBUTE_NAMES:
                    attribute = obj.data.color_attributes.get(name)
                    if attribute is not None:
                        obj.data.color_attributes.remove(attribute)
        for obj in picked:
            vertices += len(obj.data.vertices)
            obj.data.update()
        depsgraph = evaluated_depsgraph(scene)
        scene_print = scene_fingerprint(scene, depsgraph)
        notes.extend(split.lines)
        notes.extend(coverage.coarse_receivers(scene, split.corner_objects, depsgraph))
        for obj in picked:
            per_texel = obj in split.texel_objects
            obj[RECORD] = json.dumps({
                "version": RECORD_VERSION, "samples": self.samples, "seconds": round(seconds, 3),
                "corners": corners, "texels": split.atlas.covered if split.atlas else 0,
                "baked": time.time(), "geometry": geometry_fingerprint(obj, depsgraph),
                "scene": scene_print, "store": "TEXELS" if per_texel else "CORNERS",
                "bounce": bounced,
                "coarse": [line for line in notes if line.startswith(f"'{obj.name}' ")],
            })
        drop_unused_atlas()
        if split.texel_objects or nodes.find_node_group() is not None:
            nodes.ensure_node_group()  # the group reads the atlas only where there is one
        if bounce.find_group() is not None:
            bounce.ensure_group()  # its image may be new, or gone
        return BakeInfo([o.name for o in picked], corners, vertices, self.samples, seconds,
                        self.basis_seconds, notes, [o.name for o in split.texel_objects],
                        split.atlas.covered if split.atlas else 0, self.texel_seconds)


def choose_samples(scene, objects, error_target, probe=16, store="AUTO"):
    """(samples, probe error): the bake samples for which the noise of T_00 (relative RMS over
    the corners and texels, stored as ``store`` says) is about ``error_target`` (a fraction,
    e.g. 0.01).

    Two bakes of the constant world at ``probe`` samples with different Cycles seeds give the
    noise at ``probe`` (RMS of their difference / √2, relative to the RMS of their mean);
    Monte Carlo noise falls as 1/√samples, so samples = probe · (noise / target)², clamped to
    1 … MAX_SAMPLES. The other eight transfers are differences of bakes of the same noise, so
    their noise is of the same size (benchmarks/REPORT.md, "Transfer", measures the result).
    """
    picked = check_objects(scene, objects, store)
    if not (isinstance(error_target, (int, float)) and 0.0 < error_target < 1.0):
        raise TransferError(f"error target {error_target!r}: use a fraction between 0 and 1")
    split = _split(scene, picked, store)
    saved = _Saved(scene, picked, split)
    seed = scene.cycles.seed
    try:
        saved.prepare(probe)
        runs = []
        for offset in (0, 1):
            scene.cycles.seed = seed + offset
            rows, atlas = _bake_basis(scene, saved, split, 0)
            if atlas is not None:
                rows.append(atlas[(atlas != texels.UNWRITTEN).all(axis=1)])
            runs.append(np.concatenate(rows))
    finally:
        scene.cycles.seed = seed
        saved.restore()
    mean = 0.5 * (runs[0] + runs[1])
    scale = float(np.sqrt(np.mean(mean ** 2)))
    noise = float(np.sqrt(np.mean((runs[0] - runs[1]) ** 2) / 2.0)) / max(scale, 1e-30)
    samples = int(np.ceil(probe * (noise / error_target) ** 2))
    return max(1, min(MAX_SAMPLES, samples)), noise


def _finite(transfer, obj, notes):
    bad = int(np.count_nonzero(~np.isfinite(transfer)))
    if bad:
        notes.append(f"'{obj.name}': {bad} values were not finite (degenerate faces?), set to 0")
        transfer = np.nan_to_num(transfer, nan=0.0, posinf=0.0, neginf=0.0)
    return transfer


@contextlib.contextmanager
def _quiet_stdout():
    """In background mode, Blender prints the image bake's "Baking map saved to internal
    image, save it externally or pack it" (the add-on packs it) to standard output once per
    basis; sent to the null device for the bake call. Errors still raise."""
    if not bpy.app.background:
        yield
        return
    sys.stdout.flush()
    saved = os.dup(1)
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, 1)
        yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)
        os.close(null)


def _drop_texels(obj):
    """Take an earlier per-texel bake's UV map off ``obj`` (now baked per corner)."""
    layer = obj.data.uv_layers.get(UV_NAME)
    if layer is not None:
        obj.data.uv_layers.remove(layer)


def _transfer(bakes):
    """(9, n, 3) T_lm from the nine bakes (each (n, 3) per corner or texel, basis worlds
    0-8), and a tenth row B = π · the lamps' bounce bake when there is one."""
    constant = bakes[0]
    rows = [np.pi * basis.CONSTANT_SCALE * constant]
    for index in range(1, len(ATTRIBUTE_NAMES)):
        rows.append(np.pi * (bakes[index] - basis.OFFSETS[index] * constant))
    rows += [np.pi * lamps for lamps in bakes[len(ATTRIBUTE_NAMES):]]
    return np.stack(rows)


def _bake_basis(scene, saved, split, index):
    """Bake basis world ``index`` (index 9: the lamps' bounce, a black world, Indirect only)
    into the corner objects' scratch attribute and the texel objects' scratch image; (their
    RGB per corner object, the atlas's RGB or None)."""
    lamps_pass = index == len(ATTRIBUTE_NAMES)
    world = basis.new_basis_world(0 if lamps_pass else index)
    passes = {}
    if lamps_pass:  # no light from the world: what the lamps give after a bounce
        world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
        passes = {"pass_filter": {"INDIRECT"}}
    try:
        scene.world = world
        if split.corner_objects:
            _cycles_bake(scene, saved, split.corner_objects, index, target="VERTEX_COLORS",
                         **passes)
        if split.texel_objects:
            began = time.perf_counter()
            _cycles_bake(scene, saved, split.texel_objects, index, target="IMAGE_TEXTURES",
                         uv_layer=SCRATCH_UV, margin=texels.MARGIN, margin_type="EXTEND",
                         use_clear=False, **passes)
            saved.texel_seconds += time.perf_counter() - began
    finally:
        scene.world = saved.world
        bpy.data.worlds.remove(world)
    rows = []
    for obj in split.corner_objects:
        attribute = obj.data.color_attributes[SCRATCH_NAME]
        values = np.empty(len(attribute.data) * 4, dtype=np.float32)
        attribute.data.foreach_get("color", values)
        rows.append(values.reshape(-1, 4)[:, :3].astype(np.float64))
    return rows, saved.target.pixels() if split.texel_objects else None


def _cycles_bake(scene, saved, objects, index, **options):
    with _quiet_stdout(), bpy.context.temp_override(
        scene=scene, view_layer=saved.view_layer, active_object=objects[0],
        object=objects[0], selected_objects=objects, selected_editable_objects=objects,
    ):
        result = bpy.ops.object.bake(
            type="DIFFUSE", use_selected_to_active=False,
            **{"pass_filter": {"DIRECT", "INDIRECT"}, "margin": 0, "use_clear": True, **options},
        )
    if "FINISHED" not in result:
        what = COEFFICIENT_NAMES[index] if index < len(COEFFICIENT_NAMES) else "the lamps' bounce"
        raise TransferError(f"the Cycles bake of {what} was cancelled")


def _store(obj, transfer):
    """Write (9, corners, 3) ``transfer`` into the nine attributes (alpha 1), a tenth row
    (the lamps' bounce) into ``BOUNCE_ATTRIBUTE``, which goes when there is none."""
    mesh = obj.data
    rgba = np.ones((transfer.shape[1], 4), dtype=np.float32)
    old = mesh.color_attributes.get(BOUNCE_ATTRIBUTE)
    if old is not None and len(transfer) == len(ATTRIBUTE_NAMES):
        mesh.color_attributes.remove(old)
    for name, values in zip(ATTRIBUTE_NAMES + (BOUNCE_ATTRIBUTE,), transfer):
        attribute = mesh.color_attributes.get(name)
        if attribute is not None and (attribute.domain != "CORNER"
                                      or attribute.data_type != "FLOAT_COLOR"):
            mesh.color_attributes.remove(attribute)
            attribute = None
        if attribute is None:
            attribute = mesh.color_attributes.new(name, "FLOAT_COLOR", "CORNER")
        rgba[:, :3] = values
        attribute.data.foreach_set("color", rgba.ravel())


class _Saved:
    """What the bake changes in the user's scene, and its restoration."""

    def __init__(self, scene, picked, split):
        self.scene = scene
        self.picked = picked
        self.split = split
        self.target = None  # the texels' ``texels.BakeTarget`` while prepared
        self.texel_seconds = 0.0  # Cycles' image bakes of the texel objects
        self.view_layer = view_layer_of(scene)
        self.world = scene.world
        self.render = {"engine": scene.render.engine}
        cycles = scene.cycles
        self.cycles = {key: getattr(cycles, key) for key in (
            "samples", "use_adaptive_sampling", "sample_clamp_direct", "sample_clamp_indirect",
        ) if hasattr(cycles, key)}
        self.active_colour = {o.name: o.data.color_attributes.active_color_name for o in picked}
        self.render_colour = {o.name: o.data.color_attributes.render_color_index for o in picked}
        self.muted = []
        self.emission_materials = set()
        self.lamps = []  # names of the lights hidden for the bake

    def prepare(self, samples, lamps=False):
        """The scene as a bake sees it: Cycles, ``samples``, the scratch targets, the SH nodes
        muted, the lamps hidden unless ``lamps`` (the bounce bake)."""
        self.scene.render.engine = "CYCLES"
        cycles = self.scene.cycles
        cycles.samples = samples
        cycles.use_adaptive_sampling = False
        cycles.sample_clamp_direct = 0.0
        cycles.sample_clamp_indirect = 0.0
        for obj in self.split.corner_objects:
            colours = obj.data.color_attributes
            scratch = colours.get(SCRATCH_NAME) or colours.new(SCRATCH_NAME, "FLOAT_COLOR", "CORNER")
            colours.active_color = scratch
        if self.split.texel_objects:
            for obj, uv in zip(self.split.texel_objects, self.split.atlas.uv):
                texels.set_uv(obj, uv, SCRATCH_UV)
            self.target = texels.BakeTarget(self.split.texel_objects, self.split.atlas.size)
        for obj in self.scene.objects:
            if obj.type == "LIGHT" and not obj.hide_render and not lamps:
                obj.hide_render = True
                self.lamps.append(obj.name)
        for material in bpy.data.materials:
            for node in materials.added_nodes(material):
                if not node.mute:
                    node.mute = True
                    self.muted.append((material.name, node.name))
                    if materials.mode_of(material) == "EMISSION":
                        self.emission_materials.add(material.name)

    def restore(self):
        scene = self.scene
        scene.world = self.world
        scene.render.engine = self.render["engine"]
        for key, value in self.cycles.items():
            setattr(scene.cycles, key, value)
        for name in self.lamps:
            lamp = self.scene.objects.get(name)
            if lamp is not None:
                lamp.hide_render = False
        for material_name, node_name in self.muted:
            material = bpy.data.materials.get(material_name)
            node = material.node_tree.nodes.get(node_name) if material else None
            if node is not None:
                node.mute = False
        if self.target is not None:
            self.target.restore()
            self.target = None
        for obj in self.split.texel_objects:
            layer = obj.data.uv_layers.get(SCRATCH_UV)
            if layer is not None:
                obj.data.uv_layers.remove(layer)
        for obj in self.picked:
            colours = obj.data.color_attributes
            scratch = colours.get(SCRATCH_NAME)
            if scratch is not None:
                colours.remove(scratch)
            active = self.active_colour[obj.name]
            if active and colours.get(active) is not None:
                colours.active_color_name = active
            if 0 <= self.render_colour[obj.name] < len(colours):
                colours.render_color_index = self.render_colour[obj.name]

