"""Our sh.txt as Filament reads and shades it (no node: Filament's npm package does not run here).

Filament's npm package needs a browser (WebGL2), so its source is followed instead: the reader
(``libs/filamentapp/src/IBL.cpp``: ``sscanf(line, "(%f,%f,%f)")``, here the C library's own
sscanf through ctypes) and the shader ``Irradiance_SphericalHarmonics(n)`` = max(sh0 + sh1 y +
sh2 z + sh3 x + sh4 yx + sh5 yz + sh6 (3z² − 1) + sh7 zx + sh8 (x² − y²), 0), evaluated in
float32, at normals in the file's frame (cmgen's (y, z, x)_blender or glTF's).
"""

import ctypes
import ctypes.util

import numpy as np
import pytest
from lightings import NAMES, NORMALS, TOLERANCE, expected, lighting

from sh_lighting.blender.presets import preset_io
from sh_lighting.formats.interop import BLENDER_TO_CMGEN
from sh_lighting.core.frames import BLENDER_TO_Y_UP

LIBC = ctypes.CDLL(ctypes.util.find_library("c"))
FRAMES = {"cmgen": BLENDER_TO_CMGEN, "gltf": BLENDER_TO_Y_UP}


def filament_reads(text):
    """IBL.cpp's loop: 9 lines, each parsed by sscanf "(%f,%f,%f)" (3 conversions or fail)."""
    bands = []
    for line in text.splitlines()[:9]:
        r, g, b = ctypes.c_float(), ctypes.c_float(), ctypes.c_float()
        n = LIBC.sscanf(line.encode(), b"(%f,%f,%f)", ctypes.byref(r), ctypes.byref(g),
                        ctypes.byref(b))
        assert n == 3, f"Filament's sscanf read {n} values from {line!r}"
        bands.append([r.value, g.value, b.value])
    return np.array(bands, dtype=np.float32)


def filament_shades(sh, n):
    sh = sh.astype(np.float32)
    x, y, z = (n[:, i, None].astype(np.float32) for i in range(3))
    one, three = np.float32(1.0), np.float32(3.0)
    return np.maximum(
        sh[0] + sh[1] * y + sh[2] * z + sh[3] * x + sh[4] * (y * x) + sh[5] * (y * z)
        + sh[6] * (three * z * z - one) + sh[7] * (z * x) + sh[8] * (x * x - y * y),
        np.float32(0.0),
    )


@pytest.mark.parametrize("frame", FRAMES)
@pytest.mark.parametrize("name", NAMES)
def test_filament_reads_and_shades_our_sh_txt(tmp_path, name, frame):
    coeffs = lighting(name)[0]
    path = preset_io.export_coefficients(coeffs, tmp_path / "sh.txt", "filament",
                                         filament_frame=frame)
    shown = filament_shades(filament_reads(path.read_text()), NORMALS @ FRAMES[frame].T)
    ours = np.maximum(expected(coeffs), 0.0)
    d = float(np.abs(shown - ours).max() / np.abs(ours).max())
    print(f"Filament ({frame} frame) {name}: {d:.3g} of the peak")
    assert d <= TOLERANCE
