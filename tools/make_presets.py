"""Write the bundled lighting presets under presets/ (python -m tools.make_presets [--no-hdri]).

The paper's Figure 2 probes from tests/data/figure2_coefficients.json, turned from its y-up
frame to Blender's by an exact SH rotation (``frames.paper_to_blender``; numpy only); the 8
HDRIs that ship with Blender, projected with ``project_equirect``, each with its 9-term error
estimate at 512 normals (needs bpy; skipped with ``--no-hdri``). Files carry no date, so
unchanged inputs give the same bytes.
"""

import json
import sys
from pathlib import Path

import numpy as np

from sh_lighting.core.frames import paper_to_blender
from sh_lighting.formats.presets import write_preset

ROOT = Path(__file__).resolve().parent.parent
PRESETS = ROOT / "presets"
FIGURE2 = ROOT / "tests" / "data" / "figure2_coefficients.json"
FIGURE2_NAMES = {
    "grace_cathedral": "Grace Cathedral",
    "eucalyptus_grove": "Eucalyptus Grove",
    "st_peters_basilica": "St. Peter's Basilica",
}
HDRI_NAMES = ("city", "courtyard", "forest", "interior", "night", "studio", "sunrise", "sunset")
ERROR_NORMALS = 512


def figure2_presets(path=FIGURE2):
    """{file stem: (coefficients in Blender axes, metadata)} for the paper's three probes."""
    data = json.loads(Path(path).read_text(encoding="utf-8"))
    out = {}
    for stem, rows in data["probes"].items():
        out[stem] = (
            paper_to_blender(np.array(rows, dtype=np.float64)),
            {
                "name": FIGURE2_NAMES.get(stem, stem.replace("_", " ").title()),
                "source": "Ramamoorthi & Hanrahan 2001, Figure 2",
                "notes": (
                    "Converted from the paper's y-up probe frame to Blender's z-up world axes, "
                    "(x, y, z)_blender = (x, -z, y)_paper, by an exact SH rotation; the paper "
                    "prints two decimals."
                ),
            },
        )
    return out


def hdri_presets():
    """{file stem: (coefficients, metadata)} for the 8 HDRIs that ship inside bpy."""
    import bpy

    from sh_lighting.blender.world.images import load_image_pixels
    from sh_lighting.core.irradiance import error_estimate
    from sh_lighting.core import project_equirect

    folder = Path(bpy.utils.system_resource("DATAFILES", path="studiolights/world"))
    out = {}
    for name in HDRI_NAMES:
        pixels = load_image_pixels(folder / f"{name}.exr")
        coeffs = project_equirect(pixels)
        out[name] = (
            coeffs,
            {
                "name": name.title(),
                "source": f"Blender datafiles: studiolights/world/{name}.exr",
                "mapping": [0.0, 0.0, 0.0],
                "strength": 1.0,
                "error_estimate": error_estimate(pixels, coeffs, ERROR_NORMALS),
                "notes": (
                    f"Projected exactly from the {pixels.shape[1]}x{pixels.shape[0]} EXR "
                    f"bundled with Blender {bpy.app.version_string}; error estimate at "
                    f"{ERROR_NORMALS} normals against the exact irradiance."
                ),
            },
        )
        print(f"  {name:10s} error mean {100 * out[name][1]['error_estimate']['mean']:.3f} %, "
              f"max {100 * out[name][1]['error_estimate']['max']:.3f} % of total power")
    return out


def main(argv):
    presets = figure2_presets()
    if "--no-hdri" not in argv:
        presets.update(hdri_presets())
    PRESETS.mkdir(exist_ok=True)
    for stem, (coeffs, metadata) in presets.items():
        path = write_preset(PRESETS / f"{stem}.json", coeffs, metadata, overwrite=True)
        print(f"wrote {path.relative_to(ROOT)}")


if __name__ == "__main__":
    main(sys.argv[1:])
