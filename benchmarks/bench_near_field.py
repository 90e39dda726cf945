"""A measured luminaire's near field: the far-field fit against the cells, on a floor close by.

``python -m benchmarks.bench_near_field`` (Blender's bpy, Cycles CPU): Prolicht E30-0019, a
real linear luminaire (1.195 × 0.21 m opening), over a floor at 0.45 m and 1.0 m; each
representation rendered in Cycles light by light (exact, no noise, ``tests/near_field_scene``)
against the file's distribution spread over the opening (a 16 × 4 grid of Blender's IES
light, checked against 32 × 8). Writes the ``near_field`` fragment of benchmarks/REPORT.md.
"""

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import bpy

from sh_lighting.blender.luminaire import build

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from tests.near_field_scene import (  # noqa: E402
    FILE,
    SIZE,
    SPAN,
    reference_lights,
    relative_rmse,
    render_each,
)
from tests.near_field_scene import measure as measure_scene  # noqa: E402

from . import fragments  # noqa: E402

CASES = ((0.45, 8), (0.45, 2), (1.0, 8))  # (height m, most fitted lamps)


def measure(folder, height, lamps):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    started = time.perf_counter()
    result = measure_scene(folder, lamps=lamps, height=height)
    scene = bpy.context.scene
    text = build.ies_text_of(scene, result["root"])
    dense = reference_lights(scene, result["root"], text, grid=(32, 8))
    fine = render_each(scene, dense, folder, "dense")
    result["grid_error"] = relative_rmse(result["maps"]["reference"], fine)
    result["seconds"] = time.perf_counter() - started
    return result


def section(rows, load, seconds):
    lines = [
        "## Measured luminaire: near field (cells over the opening) against the far-field fit",
        "",
        f"`python -m benchmarks.bench_near_field` ({SIZE}×{SIZE} px of floor, {SPAN:g} m square, "
        f"Cycles CPU, 2 shared cores, load {load}; {seconds:.0f} s in all). Luminaire: "
        f"{FILE.name} (real, 1.195 × 0.21 m opening) shining down over a white floor. Every "
        "representation is rendered in Cycles, so only the representation differs: each light "
        "a point (radius 0) rendered alone with one sample (its exact direct light) and the "
        "maps summed. Reference: the file's distribution spread evenly over the opening, a "
        "16 × 4 grid of Blender's IES light of 1/64 the power each (its own error against a "
        "32 × 8 grid in the last column). Error: relative RMSE of the floor's illuminance "
        "against the reference.",
        "",
        "| height | cells | fitted lamps | EEVEE lamps (near) | one IES light | far-field fit | "
        "near-field cells (EEVEE) | Cycles cells | reference's own |",
        "|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for height, r in rows:
        e = r["errors"]
        lines.append(
            f"| {height:.2f} m | {r['cells'][0]} × {r['cells'][1]} | {r['fit_lamps']} | "
            f"{r['near_lamps']} | {e['ies']:.1%} | {e['far']:.1%} | {e['near']:.1%} | "
            f"{e['cycles_cells']:.1%} | {r['grid_error']:.2%} |")
    lines += [
        "",
        "The five-times rule: a surface closer than 5 × the opening (6 m for this luminaire) "
        "sees its extent. One point source, exact in direction (Blender's IES light) or fitted "
        "(the EEVEE lamps), puts the whole fixture's light at its centre and overshoots under "
        "it; cutting the opening into cells (at most 4 × 4, each under a fifth of the "
        "distance where the cap allows) takes most of that error away. What is left in the "
        "EEVEE column is mostly the fit's own error (the few spots against the table) and the "
        "cells' coarseness; Cycles' cells, the exact IES light per cell, show the coarseness "
        "alone. The cost: EEVEE renders lamps × cells lights, each with a shadow map.",
        "",
    ]
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.parse_args(argv)
    started = time.perf_counter()
    load = ", ".join(f"{v:.1f}" for v in os.getloadavg())
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for height, lamps in CASES:
            result = measure(folder, height, lamps)
            print(height, lamps, {k: round(100 * v, 2) for k, v in result["errors"].items()},
                  result["cells"], f"{result['seconds']:.0f} s")
            rows.append((height, result))
    text = section(rows, load, time.perf_counter() - started)
    print(text)
    fragments.write("near_field", text)
    print("wrote the near_field fragment of benchmarks/REPORT.md")


if __name__ == "__main__":
    main()
