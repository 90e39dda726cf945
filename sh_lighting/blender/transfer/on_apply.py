"""Apply's "Keep BSDF with Shadows" (mode "TRANSFER", EEVEE's Default): the transfer baked
where it is missing or stale, then Keep BSDF with it.

EEVEE has no shadows of the world's light; the transfer (``bake``) gives them, and measured
best of EEVEE's candidates (benchmarks/REPORT.md, "Per-texel transfer"). ``needed`` says what
Apply would bake and what it costs; the Default starts a bake only when estimated at most
``AFFORDABLE_SECONDS`` (the mode named, always). ``apply_with_transfer`` lights every material
of the scene by Keep BSDF, those of baked objects through the transfer. The window's modal run
of the bake is the UI's; ``bake_and_apply`` runs it at once (scripts, the command line).
"""

from typing import NamedTuple

from ..shading import materials
from . import apply as transfer_apply
from . import bake

#: The longest estimated bake the Default starts by itself (the panel's Apply, `apply`)
AFFORDABLE_SECONDS = 30.0


class Applied(NamedTuple):
    result: object  # ``materials.Result`` of every material Apply changed
    lit: list  # names of the materials lit by the transfer
    info: object  # the bake's ``bake.BakeInfo``, or None (none ran)
    notes: list  # why meshes got no shadows (refused, the Default's bake too long)


class Need(NamedTuple):
    objects: list  # the meshes to bake (an empty list: every mesh's bake is current)
    plan: object  # the ``bake.Plan`` of ``objects``, or None
    refused: list  # (name, why) of meshes that cannot be baked


def needed(scene, objects, samples=bake.DEFAULT_SAMPLES):
    """What a bake before Apply would do for ``objects``: nothing when every bakeable mesh
    among them has a current bake, else all of them (one bake sees one scene)."""
    meshes = [o for o in objects if o.type == "MESH"]
    view_layer = bake.view_layer_of(scene)
    refused = [(o.name, bake.refusal(scene, o, view_layer)) for o in meshes]
    bakeable = [o for o, (_name, why) in zip(meshes, refused) if why is None]
    refused = [(name, why) for name, why in refused if why is not None]
    if not bakeable:
        return Need([], None, refused)
    depsgraph = bake.evaluated_depsgraph(scene)
    scene_print = bake.scene_fingerprint(scene, depsgraph)
    if all(bake.status(scene, o, scene_print, depsgraph)[0] == "OK" for o in bakeable):
        return Need([], None, refused)
    return Need(bakeable, bake.plan(scene, bakeable, samples), refused)


def starts_bake(need, mode_asked):
    """Whether Apply bakes: the mode named always, the Default when affordable."""
    return bool(need.objects) and (mode_asked != "AUTO"
                                   or need.plan.seconds <= AFFORDABLE_SECONDS)


def cost_line(need):
    """"bakes the shadows of N object(s) first, about S s" (an empty string: nothing)."""
    if not need.objects:
        return ""
    return (f"bakes the shadows of {len(need.objects)} object(s) first, about "
            f"{need.plan.seconds:.0f} s")


def skipped_bake_line(need):
    """Why the Default did not bake (over ``AFFORDABLE_SECONDS``), what to do."""
    return (f"no shadows: their bake would take about {need.plan.seconds:.0f} s (over "
            f"{AFFORDABLE_SECONDS:.0f} s): choose Keep BSDF with Shadows, or Bake Transfer")


def apply_with_transfer(scene, objects):
    """Keep BSDF on every material of ``scene``; those of the baked ``objects`` lit by the
    transfer. (``materials.Result`` of all, names lit by the transfer)."""
    baked = transfer_apply.baked_objects(objects)
    lit = (transfer_apply.apply_transfer(baked, scene, "KEEP_BSDF") if baked
           else transfer_apply.Result([], []))
    done = set(lit.changed)
    rest = [m for m in materials.materials_of(scene.objects) if m.name_full not in done]
    result, kept = transfer_apply.apply_keeping_transfer(rest, scene, "KEEP_BSDF")
    shared = [(name, why) for name, why in lit.skipped if why != "no transfer bake"]
    return (materials.Result(list(lit.changed) + list(result.changed),
                             list(result.skipped) + shared),
            list(lit.changed) + list(kept))


def bake_and_apply(scene, objects, mode_asked="TRANSFER", report=None):
    """``needed``, the bake when ``starts_bake``, then ``apply_with_transfer``; ``Applied``.
    A ``bake.TransferError`` from the bake leaves the materials as they were."""
    need = needed(scene, objects)
    notes = [f"no shadows on '{name}': {why}" for name, why in need.refused]
    info = None
    if starts_bake(need, mode_asked):
        info = bake.bake_transfer(scene, need.objects, report=report)
    elif need.objects:
        notes.append(skipped_bake_line(need))
    result, lit = apply_with_transfer(scene, objects)
    return Applied(result, lit, info, notes)
