"""Exports to three.js, glTF EXT_lights_image_based (as Babylon.js reads it) and Filament.

For each target the irradiance is evaluated twice on random normals: by our core (eq. 13,
Blender axes) and by an independent evaluation written here from the target's own source, in
the target's axes, at the same physical normal. A white Lambertian surface must show E(n)/π in
every target, to rounding.
"""

import re
from math import pi, sqrt

import numpy as np
import pytest
from quadrature import random_directions

from sh_lighting.core import irradiance, sh_basis, uv_to_direction
from sh_lighting.formats.interop import (
    BLENDER_TO_BABYLON_LOOKUP,
    BLENDER_TO_CMGEN,
    coefficients_from_filament_prescaled,
    filament_prescaled,
    from_filament_sh_txt,
    from_gltf_irradiance_coefficients,
    from_threejs_sh,
    to_filament_sh_txt,
    to_gltf_irradiance_coefficients,
    to_threejs_sh,
)

ROUNDING = 1e-12  # relative to the size of the values compared
COEFFS = np.random.default_rng(0).normal(size=(9, 3))
NORMALS = random_directions(400, seed=1)  # Blender axes


def close(a, b, tol=ROUNDING):
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    return np.abs(a - b).max() <= tol * max(1.0, np.abs(b).max())


def gltf(normals):
    """The same physical normals in glTF / three.js axes: (x, y, z)_blender -> (x, z, -y)."""
    return np.stack([normals[:, 0], normals[:, 2], -normals[:, 1]], axis=-1)


# --- three.js -----------------------------------------------------------------------------
# SphericalHarmonics3.getIrradianceAt / shader shGetIrradianceAt (three.js src), constants in
# closed form: 0.886227 = π Y00, 0.511664 = (2π/3) Y1 / 2, 0.429043 = (π/4) Y22,
# 0.743125 = 3 (π/4) Y20, 0.247708 = (π/4) Y20.
Y00, Y1, Y2 = sqrt(1 / pi) / 2, sqrt(3 / (4 * pi)), sqrt(15 / pi) / 2
Y20, Y22 = sqrt(5 / pi) / 4, sqrt(15 / pi) / 4
THREE_EXACT = (pi * Y00, pi / 3 * Y1, pi / 4 * Y22, 3 * pi / 4 * Y20, pi / 4 * Y20)
THREE_PRINTED = (0.886227, 0.511664, 0.429043, 0.743125, 0.247708)


def threejs_irradiance(sh27, n, constants=THREE_EXACT):
    c0, c1, c2, c3, c4 = constants
    s = np.asarray(sh27).reshape(9, 3)  # fromArray: coefficient i is array[3i : 3i + 3]
    x, y, z = (n[:, i, None] for i in range(3))
    return (
        s[0] * c0
        + s[1] * 2 * c1 * y + s[2] * 2 * c1 * z + s[3] * 2 * c1 * x
        + s[4] * 2 * c2 * x * y + s[5] * 2 * c2 * y * z + s[6] * (c3 * z * z - c4)
        + s[7] * 2 * c2 * x * z + s[8] * c2 * (x * x - y * y)
    )


def threejs_radiance(sh27, n):
    """SphericalHarmonics3.getAt: the radiance in direction n, the paper's basis table."""
    s = np.asarray(sh27).reshape(9, 3)
    x, y, z = (n[:, i, None] for i in range(3))
    basis = [Y00 + 0 * x, Y1 * y, Y1 * z, Y1 * x, Y2 * x * y, Y2 * y * z,
             Y20 * (3 * z * z - 1), Y2 * x * z, Y22 * (x * x - y * y)]
    return sum(b * s[i] for i, b in enumerate(basis))


def test_threejs_array_is_27_floats_coefficient_major():
    sh = to_threejs_sh(COEFFS)
    assert len(sh) == 27 and all(type(v) is float for v in sh)
    up_only = np.zeros((9, 3))
    up_only[2] = [1.0, 2.0, 3.0]  # L10 in Blender: light from above (+z)
    assert to_threejs_sh(up_only)[3:6] == [1.0, 2.0, 3.0]  # three.js L1-1: +y is up
    assert not any(to_threejs_sh(up_only)[:3] + to_threejs_sh(up_only)[6:])


def test_threejs_irradiance_matches_ours_at_the_same_normal():
    theirs = threejs_irradiance(to_threejs_sh(COEFFS), gltf(NORMALS))
    assert close(theirs, irradiance(COEFFS, NORMALS))


def test_threejs_printed_constants_agree_to_their_six_digits():
    ours = irradiance(COEFFS, NORMALS)
    theirs = threejs_irradiance(to_threejs_sh(COEFFS), gltf(NORMALS), THREE_PRINTED)
    assert close(theirs, ours, tol=2e-6)


def test_threejs_radiance_is_the_same_lighting_function():
    assert close(threejs_radiance(to_threejs_sh(COEFFS), gltf(NORMALS)), sh_basis(NORMALS) @ COEFFS)


def test_threejs_round_trip():
    assert close(from_threejs_sh(to_threejs_sh(COEFFS)), COEFFS, tol=1e-15)


# --- glTF EXT_lights_image_based, as Babylon.js reads it -----------------------------------
# Babylon's loader: SphericalHarmonics.FromArray(rows), scaleInPlace(intensity),
# convertIrradianceToLambertianRadiance() (÷ π); default shading (SPHERICAL_HARMONICS):
# preScaleForRendering() multiplies by SH3ylmBasisConstants, the shader sums the polynomials.
BABYLON_BASIS = [sqrt(1 / (4 * pi)), -sqrt(3 / (4 * pi)), sqrt(3 / (4 * pi)), -sqrt(3 / (4 * pi)),
                 sqrt(15 / (4 * pi)), -sqrt(15 / (4 * pi)), sqrt(5 / (16 * pi)),
                 -sqrt(15 / (4 * pi)), sqrt(15 / (16 * pi))]


def babylon_diffuse(rows, n, intensity=1.0):
    h = np.asarray(rows) * intensity / pi
    h = h * np.array(BABYLON_BASIS)[:, None]
    x, y, z = (n[:, i, None] for i in range(3))
    return (h[0] + h[1] * y + h[2] * z + h[3] * x + h[4] * y * x + h[5] * y * z
            + h[6] * (3 * z * z - 1) + h[7] * z * x + h[8] * (x * x - y * y))


def test_gltf_rows_shown_by_babylon_give_lambertian_shading():
    """At Babylon's lookup vector of a glTF normal in a right-handed scene, (x, y, −z): the
    z flip of REFLECTIONMAP_OPPOSITEZ (Babylon's own loader and shader code are run on the
    exported file in tests/interop)."""
    rows = to_gltf_irradiance_coefficients(COEFFS)
    assert len(rows) == 9 and all(len(r) == 3 for r in rows)
    lookup = gltf(NORMALS) * np.array([1.0, 1.0, -1.0])
    assert close(babylon_diffuse(rows, lookup), irradiance(COEFFS, NORMALS) / pi)
    assert close(lookup, NORMALS @ BLENDER_TO_BABYLON_LOOKUP.T)
    # at the raw glTF normal it would be the mirror image: the z flip matters
    assert not close(babylon_diffuse(rows, gltf(NORMALS)), irradiance(COEFFS, NORMALS) / pi)


def test_gltf_rows_are_condon_shortley_signed_irradiance():
    up_only = np.zeros((9, 3))
    up_only[2] = 1.0  # Blender L10 -> y-up L1-1, which Babylon's basis negates
    rows = np.array(to_gltf_irradiance_coefficients(up_only))
    assert close(rows[1], [-2 * pi / 3] * 3) and not np.delete(rows, 1, axis=0).any()
    constant = np.zeros((9, 3))
    constant[0] = 2 * sqrt(pi)  # radiance 1 everywhere: E = π
    assert close(np.array(to_gltf_irradiance_coefficients(constant))[0], [2 * pi * sqrt(pi)] * 3)


def test_gltf_round_trip():
    rows = to_gltf_irradiance_coefficients(COEFFS)
    assert close(from_gltf_irradiance_coefficients(rows), COEFFS, 1e-15)


# --- Filament -----------------------------------------------------------------------------
# Irradiance_SphericalHarmonics (Filament shaders): the plain polynomial of the pre-scaled
# values, = E(n)/π, clamped at 0 (not applied here: our E9 may be negative).
LINE = re.compile(r"^\(\s*(\S+),\s*(\S+),\s*(\S+)\); // (L\d-?\d), irradiance, pre-scaled base$")


def parse_sh_txt(text):
    rows = [LINE.match(line) for line in text.splitlines()]
    assert all(rows) and [m.group(4) for m in rows] == [
        "L00", "L1-1", "L10", "L11", "L2-2", "L2-1", "L20", "L21", "L22"
    ]
    return np.array([[float(v) for v in m.groups()[:3]] for m in rows])


def filament_diffuse(sh, n):
    x, y, z = (n[:, i, None] for i in range(3))
    return (sh[0] + sh[1] * y + sh[2] * z + sh[3] * x + sh[4] * y * x + sh[5] * y * z
            + sh[6] * (3 * z * z - 1) + sh[7] * z * x + sh[8] * (x * x - y * y))


@pytest.mark.parametrize(
    "frame, normals", [("gltf", gltf(NORMALS)), ("cmgen", NORMALS @ BLENDER_TO_CMGEN.T)]
)
def test_filament_sh_txt_gives_lambertian_shading(frame, normals):
    text = to_filament_sh_txt(COEFFS, frame)
    assert text.endswith("\n") and len(text.splitlines()) == 9
    assert close(filament_diffuse(parse_sh_txt(text), normals), irradiance(COEFFS, NORMALS) / pi)


def test_filament_values_are_prescaled_not_radiance():
    constant = np.zeros((9, 3))
    constant[0] = 2 * sqrt(pi)  # radiance 1 everywhere: a white surface shows 1
    assert close(filament_prescaled(constant)[0], [1.0, 1.0, 1.0])


@pytest.mark.parametrize("frame", ["gltf", "cmgen"])
def test_filament_round_trips(frame):
    assert close(from_filament_sh_txt(to_filament_sh_txt(COEFFS, frame), frame), COEFFS, 1e-15)
    values = filament_prescaled(COEFFS, frame)
    assert close(coefficients_from_filament_prescaled(values, frame), COEFFS, 1e-15)


def test_filament_reader_accepts_cmgen_spacing_and_refuses_other_text():
    cmgen_style = "\n".join(
        f"({r:18.15f}, {g:18.15f}, {b:18.15f}); // L{i}, irradiance, pre-scaled base"
        for i, (r, g, b) in enumerate(filament_prescaled(COEFFS))
    ) + "\n\n"
    assert close(from_filament_sh_txt(cmgen_style), COEFFS, 1e-13)  # 15 decimals
    with pytest.raises(ValueError, match="holds 8 coefficient lines, expected 9"):
        from_filament_sh_txt("\n".join(cmgen_style.splitlines()[:8]))
    with pytest.raises(ValueError, match=r"line 2 is not '\(r, g, b\); // comment'"):
        from_filament_sh_txt("(1, 2, 3);\nhello\n")
    with pytest.raises(ValueError, match="unknown Filament frame 'unity'"):
        to_filament_sh_txt(COEFFS, "unity")


def cmgen_reads(directions, mirror=True):
    """Where cmgen (tools/cmgen, libs/ibl) reads an equirect image for a cubemap direction.

    mirrorCubemap: the texel at N takes the source's value at (-N.x, N.y, N.z);
    equirectangularToCubemap: xf = atan2(s.x, s.z)/π, yf = asin(s.y)·2/π, image x from
    (xf + 1)/2, image y from (1 - yf)/2 counted from the top row.
    """
    s = directions * np.array([-1.0 if mirror else 1.0, 1.0, 1.0])
    u = (np.arctan2(s[:, 0], s[:, 2]) / pi + 1.0) / 2.0
    v_from_top = (1.0 - np.arcsin(np.clip(s[:, 1], -1, 1)) * 2.0 / pi) / 2.0
    return u, v_from_top


def test_cmgen_frame_follows_from_its_equirect_lookup_and_mirror():
    n_cmgen = random_directions(300, seed=2)
    u, v_from_top = cmgen_reads(n_cmgen)
    seen_by_blender = uv_to_direction(u, 1.0 - v_from_top)  # Blender's v counts from the bottom
    assert close(seen_by_blender @ BLENDER_TO_CMGEN.T, n_cmgen)
    assert np.linalg.det(BLENDER_TO_CMGEN) == pytest.approx(1.0)
    # With --no-mirror the axes are a reflection of Blender's: no rotation of coefficients
    # can express it, which is why only the default (mirrored) cmgen frame is offered.
    u, v_from_top = cmgen_reads(n_cmgen, mirror=False)
    unmirrored, *_ = np.linalg.lstsq(uv_to_direction(u, 1.0 - v_from_top), n_cmgen, rcond=None)
    assert np.linalg.det(unmirrored) == pytest.approx(-1.0)


def test_exports_need_exactly_nine_coefficients():
    for export in (to_threejs_sh, to_gltf_irradiance_coefficients, to_filament_sh_txt):
        with pytest.raises(ValueError, match="exactly 9 RGB coefficients"):
            export(np.zeros((16, 3)))
    with pytest.raises(ValueError, match="must hold 27 numbers, got 26"):
        from_threejs_sh([0.0] * 26)
    with pytest.raises(ValueError, match="NaN or Inf"):
        from_gltf_irradiance_coefficients([[float("inf")] * 3] * 9)
