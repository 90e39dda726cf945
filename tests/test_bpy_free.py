"""sh_lighting.core and sh_lighting.formats work in a plain Python process where Blender cannot
be imported."""

import re
import subprocess
import sys
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "sh_lighting"
CORE = PACKAGE / "core"
BLENDER_MODULES = ("bpy", "mathutils", "bmesh", "gpu", "bl_math")


def test_core_imports_and_computes_with_bpy_unimportable():
    blocked = "; ".join(f"sys.modules[{m!r}] = None" for m in BLENDER_MODULES)
    script = (
        f"import sys; {blocked}\n"
        "import numpy as np\n"
        "from sh_lighting.core import project_equirect, irradiance\n"
        "import sh_lighting.formats.presets, sh_lighting.formats.gltf, sh_lighting.formats.interop\n"
        "import sh_lighting.formats.exr, sh_lighting.formats.png, sh_lighting.formats.atomic\n"
        "c = project_equirect(np.ones((4, 8, 3)))\n"
        "print(float(irradiance(c, np.array([0.0, 0.0, 1.0]))[0]))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", script], cwd=CORE.parents[1], capture_output=True, text=True
    )
    assert out.returncode == 0, out.stderr
    assert abs(float(out.stdout) - 3.141592653589793) < 1e-12


def test_no_core_or_formats_module_imports_blender():
    pattern = re.compile(rf"^\s*(import|from)\s+({'|'.join(BLENDER_MODULES)})\b", re.M)
    offenders = [p.name for part in ("core", "formats") for p in (PACKAGE / part).glob("*.py")
                 if pattern.search(p.read_text())]
    assert offenders == []
