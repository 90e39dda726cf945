"""IES and EULUMDAT readers: real files against a second reader, symmetric forms, hostile files."""

from pathlib import Path

import numpy as np
import pytest
from pyldt import LdtReader

from sh_lighting.formats.eulumdat import parse_ldt
from sh_lighting.formats.ies import blender_reads_as_is, parse_ies
from sh_lighting.formats.photometric_file import read_photometry
from sh_lighting.formats.photometry import PhotometryError, to_ies_text

DATA = Path(__file__).resolve().parents[1] / "data" / "photometry"
LDT_FILES = sorted(p.name for p in DATA.glob("*.ldt"))
IES_FILES = sorted(p.name for p in DATA.glob("*.ies"))
SAME = 1e-6  # relative: two readers of the same numbers agree to rounding


@pytest.mark.parametrize("name", LDT_FILES)
def test_ldt_equals_pyldt(name):
    """Every stored and mirrored C-plane, all Isym 0-4, equals eulumdat-py's expansion."""
    table = read_photometry(DATA / name)
    other = LdtReader.read(DATA / name)
    h = other.header
    reference = np.array(other.intensities) * h.lamp_flux[0] / 1000.0 * h.conv_factor
    gamma = np.array(h.g_angles)
    ours = np.stack([table.at(gamma, np.full_like(gamma, c)) for c in h.c_angles])
    assert np.abs(ours - reference).max() <= SAME * reference.max()


def test_ldt_files_cover_every_symmetry():
    """The real files are Isym 0, 1 and 4; 2 and 3 are made in the test below."""
    assert {LdtReader.read(DATA / n).header.isym for n in LDT_FILES} == {0, 1, 4}


@pytest.mark.parametrize("isym", [0, 1, 2, 3, 4])
def test_synthetic_ldt_every_symmetry_equals_pyldt(isym, tmp_path):
    """A made-up distribution, different in every stored plane and angle, in each symmetry."""
    mc, ng = 8, 5
    planes = {0: mc, 1: 1, 2: mc // 2 + 1, 3: mc // 2 + 1, 4: mc // 4 + 1}[isym]
    values = [f"{100 + 10 * k + j * (j + 1):.1f}" for k in range(planes) for j in range(ng)]
    path = tmp_path / f"isym{isym}.ldt"
    path.write_text(ldt(isym=isym, mc=mc, ng=ng, intensities=values))  # γ 0, 45, ..., 180
    other = LdtReader.read(path)
    assert other.header.isym == isym
    table = read_photometry(path)
    h = other.header
    reference = np.array(other.intensities) * h.lamp_flux[0] / 1000.0 * h.conv_factor
    gamma = np.array(h.g_angles)
    ours = np.stack([table.at(gamma, np.full_like(gamma, c)) for c in h.c_angles])
    assert reference.std() > 0
    assert np.abs(ours - reference).max() <= SAME * reference.max()


def test_real_files_known_values():
    """Numbers read off the files by eye: nadir, 1995 and 2002 headers, TILT=INCLUDE."""
    bega = read_photometry(DATA / "bega_50988_lm63_1995.ies")
    assert bega.at(0.0, 123.0) == pytest.approx(2225.9)
    assert bega.at(90.0, 0.0) == pytest.approx(0.0)
    assert bega.at(100.0, 0.0) == 0.0  # above the last vertical angle: dark, as in Cycles
    example = read_photometry(DATA / "lm63_2002_example_tilt.ies")  # the standard's example
    assert example.at(0.0, 0.0) == pytest.approx(100000.0)
    assert example.at(22.5, 45.0) == pytest.approx(35000.0)
    assert example.at(90.0, 90.0) == pytest.approx(1000.0)
    cie = read_photometry(DATA / "ugr_sample_11.ldt")  # CIE 190 example, 1000 lm lamp
    assert cie.at(0.0, 0.0) == pytest.approx(264.0, rel=SAME)
    prolicht = read_photometry(DATA / "prolicht_e30_0019.ldt")
    assert prolicht.flux_lm == pytest.approx(5134, rel=0.01)  # integrates to line 29's 5134 lm


@pytest.mark.parametrize("name", IES_FILES + LDT_FILES)
def test_every_file_reads_and_round_trips_through_ies_text(name):
    table = read_photometry(DATA / name)
    assert np.isfinite(table.candela).all() and table.peak_cd > 0
    again = parse_ies(to_ies_text(table), "converted.ies")
    theta = np.linspace(0, 180, 37)
    for phi in (0.0, 37.0, 90.0, 200.0, 359.0):
        a = table.at(theta, np.full_like(theta, phi))
        b = again.at(theta, np.full_like(theta, phi))
        assert np.abs(a - b).max() <= SAME * table.peak_cd
    assert again.flux_lm == pytest.approx(table.flux_lm, rel=SAME)


def ies(vertical, horizontal, rows, kind=1, tilt="TILT=NONE", head="IESNA:LM-63-2002"):
    lines = [head, "[TEST] made in the test", tilt,
             f"1 1000 1 {len(vertical)} {len(horizontal)} {kind} 2 0.1 0.2 0",
             "1 1 10", " ".join(map(str, vertical)), " ".join(map(str, horizontal))]
    lines += [" ".join(map(str, row)) for row in rows]
    return "\n".join(lines) + "\n"


V = [0, 30, 60, 90]


def test_ies_symmetric_forms_expand():
    one = parse_ies(ies(V, [0], [[4, 3, 2, 1]]))
    assert one.at(30.0, 77.0) == pytest.approx(3.0)
    quarter = parse_ies(ies(V, [0, 45, 90], [[1, 1, 1, 1], [2, 2, 2, 2], [3, 3, 3, 3]]))
    for phi, want in ((0, 1), (45, 2), (90, 3), (135, 2), (180, 1), (225, 2), (270, 3), (315, 2)):
        assert quarter.at(60.0, float(phi)) == pytest.approx(want)
    half = parse_ies(ies(V, [0, 90, 180], [[1] * 4, [2] * 4, [3] * 4]))
    assert [half.at(30.0, p) for p in (0.0, 90.0, 180.0, 270.0)] == pytest.approx([1, 2, 3, 2])
    # 90..270: symmetric about the C90-C270 plane, I(180 - C) = I(C)
    other = parse_ies(ies(V, [90, 180, 270], [[1] * 4, [2] * 4, [3] * 4]))
    assert [other.at(30.0, p) for p in (0.0, 90.0, 180.0, 270.0)] == pytest.approx([2, 1, 2, 3])
    assert not blender_reads_as_is(ies(V, [90, 180, 270], [[1] * 4, [2] * 4, [3] * 4]))
    assert blender_reads_as_is(ies(V, [0, 90, 180], [[1] * 4, [2] * 4, [3] * 4]))
    # versions 1991 and 2019 and TILT=INCLUDE read the same numbers
    for head in ("IESNA91", "IES:LM-63-2019", "IESNA:LM-63-1995"):
        assert parse_ies(ies(V, [0], [[4, 3, 2, 1]], head=head)).at(0.0, 0.0) == 4.0
    tilt = "TILT=INCLUDE\n1\n3\n0 45 90\n1 0.9 0.8"
    assert parse_ies(ies(V, [0], [[4, 3, 2, 1]], tilt=tilt)).at(60.0, 0.0) == 2.0


def test_uniform_sphere_flux_and_type_b():
    """An isotropic 100 cd source has 400π lm as type C; type B's H −90..90 is one half."""
    vertical = list(range(0, 181, 10))
    c = parse_ies(ies(vertical, [0], [[100] * len(vertical)]))
    assert c.flux_lm == pytest.approx(400 * np.pi, rel=SAME)
    b_angles = list(range(-90, 91, 10))
    b = parse_ies(ies(b_angles, b_angles, [[100] * len(b_angles)] * len(b_angles), kind=2))
    # resampled on a 1° type C grid: the edge at the horizon ramps over 1° (+0.9 %)
    assert b.flux_lm == pytest.approx(200 * np.pi, rel=1e-2)


def test_type_b_axes():
    """Type B: bright only at H = 30° (about the horizontal axis) lands at C0, θ = 30°."""
    angles = list(range(-90, 91, 10))
    rows = [[100.0 if h == 30 else 0.0 for _ in angles] for h in angles]
    table = parse_ies(ies(angles, angles, rows, kind=2))
    assert table.at(30.0, 0.0) == pytest.approx(100.0)
    assert table.at(30.0, 180.0) == pytest.approx(0.0)
    assert table.at(30.0, 90.0) == pytest.approx(0.0)


def ldt(isym=1, mc=1, ng=3, intensities=None, flux="1000"):
    planes = {0: mc, 1: 1, 2: mc // 2 + 1, 3: mc // 2 + 1, 4: mc // 4 + 1}[isym]
    values = intensities if intensities is not None else [100] * (planes * ng)
    lines = ["Test", "1", str(isym), str(mc), str(360 // max(mc, 1)), str(ng), "45",
             "r", "n", "", "f", "d", "100", "0", "50", "80", "0", "0", "0", "0", "0",
             "100", "100", "1", "0", "1", "1", "LED", flux, "3000", "80", "10"]
    lines += ["0.5"] * 10
    lines += [str(k * 360 // max(mc, 1)) for k in range(mc)]
    lines += [str(45 * k) for k in range(ng)]
    lines += [str(v) for v in values]
    return "\n".join(lines) + "\n"


def test_ldt_synthetic_and_decimal_comma():
    table = parse_ldt(ldt(intensities=["100", "50,5", "0"]))
    assert table.at(45.0, 10.0) == pytest.approx(50.5)
    assert table.opening_m[:2] == (-0.08, -0.08)  # width 0: a circle of 80 mm


HOSTILE_IES = {
    "empty": ("", "line 1: the file is empty"),
    "truncated": (ies(V, [0], [[4, 3, 2, 1]])[:-6], "line 8: the file ends after 1 of 4 candela"),
    "nan": (ies(V, [0], [[4, "nan", 2, 1]]), "line 8: candela values: 'nan' is not a finite"),
    "negative count": (ies(V, [0], [[4, 3, 2, 1]]).replace("1 1000 1 4 1", "1 1000 1 -4 1"),
                       "line 4: number of vertical angles is -4"),
    "extra values": (ies(V, [0], [[4, 3, 2, 1, 7]]), "line 8: 1 numbers left over"),
    "word": (ies(V, [0], [[4, "x", 2, 1]]), "line 8: candela values: 'x' is not a number"),
    "no tilt": ("IESNA:LM-63-2002\n[TEST] x\n1 2 3\n", "line 3: no TILT= line"),
    "tilt file": (ies(V, [0], [[1] * 4], tilt="TILT=lamp.tlt"), "line 3: TILT=lamp.tlt"),
    "type A": (ies(V, [0], [[1] * 4], kind=3), "line 4: photometric type A"),
    "decreasing": (ies([0, 60, 30, 90], [0], [[1] * 4]), "line 6: vertical angles must increase"),
    "negative candela": (ies(V, [0], [[4, -3, 2, 1]]), "line 8: candela value -3 is negative"),
    "odd planes": (ies(V, [0, 100], [[1] * 4] * 2), "line 7: horizontal angles: planes from 0"),
}


@pytest.mark.parametrize("case", sorted(HOSTILE_IES))
def test_hostile_ies_one_line_naming_the_line(case):
    text, expected = HOSTILE_IES[case]
    with pytest.raises(PhotometryError) as caught:
        parse_ies(text, "bad.ies")
    message = str(caught.value)
    assert "\n" not in message and message.startswith("bad.ies line ")
    assert expected in message, message


HOSTILE_LDT = {
    "empty": ("", "line 1: the file is empty"),
    "truncated": (ldt()[:-8], "the file ends after 1 of 3 intensities"),
    "nan": (ldt(intensities=["100", "nan", "0"]), "line 48: intensities: 'nan' is not a finite"),
    "negative count": (ldt().replace("Test\n1\n1\n1\n", "Test\n1\n1\n-1\n"),
                       "line 4: number of C-planes Mc is -1"),
    "extra values": (ldt(intensities=["1", "2", "3", "4"]), "line 50: text after the 3"),
    "bad isym": (ldt().replace("Test\n1\n1\n", "Test\n1\n7\n"), "line 3: symmetry indicator"),
    "zero flux": (ldt(flux="0"), "line 29: lamp flux is 0"),
}


@pytest.mark.parametrize("case", sorted(HOSTILE_LDT))
def test_hostile_ldt_one_line_naming_the_line(case):
    text, expected = HOSTILE_LDT[case]
    with pytest.raises(PhotometryError) as caught:
        parse_ldt(text, "bad.ldt")
    message = str(caught.value)
    assert "\n" not in message and message.startswith("bad.ldt line ")
    assert expected in message, message


def test_unreadable_path(tmp_path):
    with pytest.raises(PhotometryError, match="cannot read"):
        read_photometry(tmp_path / "missing.ies")


def test_cubic_reading_as_cycles():
    """Catmull-Rom: the table's values at its angles, linear data kept linear, φ wrapped over
    360°, 0 from the last θ, never negative (Cycles' kernel_ies_interp)."""
    vertical = list(range(0, 91, 10))
    rows = [[1000 - 10 * v for v in vertical], [500 - 5 * v for v in vertical],
            [1000 - 10 * v for v in vertical]]
    table = parse_ies(ies(vertical, [0, 90, 180], rows))
    theta = np.array([0.0, 10.0, 40.0, 80.0])
    assert table.at_cubic(theta, np.zeros(4)) == pytest.approx(table.at(theta, np.zeros(4)))
    assert table.at_cubic(np.array([35.0]), np.array([0.0])) == pytest.approx([650.0])
    left = table.at_cubic(np.array([30.0]), np.array([350.0]))  # between 270° and 360° = 0°
    assert left == pytest.approx(table.at_cubic(np.array([30.0]), np.array([10.0])))
    assert table.at_cubic(np.array([90.0, 120.0]), np.zeros(2)) == pytest.approx([0.0, 0.0])
    spike = parse_ies(ies(vertical, [0], [[0, 0, 0, 100, 0, 0, 0, 0, 0, 0]]))
    dips = spike.at_cubic(np.linspace(0.0, 89.0, 300), np.zeros(300))
    assert dips.min() == 0.0 and dips.max() > 0  # the spline's undershoot clamped
    assert spike.at(np.array([25.0]), np.array([0.0]))[0] != pytest.approx(
        spike.at_cubic(np.array([25.0]), np.array([0.0]))[0])
