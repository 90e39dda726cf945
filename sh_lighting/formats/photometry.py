"""A luminaire's candela table I(θ, φ) in Blender's light axes, read from IES or EULUMDAT files.

Axes: a Blender light points down its local −Z, so θ is the angle from nadir (−Z) in degrees,
and φ the file's C-plane (IES horizontal angle, EULUMDAT C angle) in degrees, with

    d(θ, φ) = (−sin θ sin φ, −sin θ cos φ, −cos θ)          (light's local axes)

so C0 lies toward the light's −Y and C90 toward −X: what Blender's IES Texture node does with
its default vector (measured by rendering, docs/blender.md). φ covers 0..360 (symmetric forms
expanded); θ the file's range, and I = 0 outside it (as Cycles does above a downlight's 90°).

Readers: :func:`sh_lighting.formats.ies.parse_ies`, :func:`sh_lighting.formats.eulumdat.parse_ldt`,
and :func:`sh_lighting.formats.photometric_file.read_photometry` choosing by content. A bad file
raises :class:`PhotometryError` whose message is one line naming the file, line and value.
"""

from dataclasses import dataclass

import numpy as np


class PhotometryError(ValueError):
    """A photometric file that cannot be read; ``str()`` is one line naming where and why."""


@dataclass(frozen=True)
class CandelaTable:
    """Luminous intensity in candela on a (φ, θ) grid, plus what the file says about the lamp.

    ``candela[i, j]`` is I at azimuth ``phi_deg[i]`` and polar angle ``theta_deg[j]`` (from
    nadir). ``flux_lm`` is ∫ I dω over the sphere (the luminaire's luminous flux as tabulated);
    ``rated_lm`` what the file states (lamp lumens; 0 where the file gives none).
    ``opening_m`` is the luminous opening's (length along the C0–C180 axis, width along
    C90–C270, height) in metres, 0 for a point; negative length and width mean a circle of
    that diameter (the IES convention).
    """

    theta_deg: np.ndarray
    phi_deg: np.ndarray
    candela: np.ndarray
    rated_lm: float
    opening_m: tuple
    source: str

    @property
    def flux_lm(self):
        return float(integrate(self, self.candela))

    @property
    def peak_cd(self):
        return float(self.candela.max())

    def intensity(self, directions):
        """I (cd) toward unit ``directions`` (…, 3) in the light's local axes, bilinear in (θ, φ)."""
        d = np.asarray(directions, dtype=np.float64)
        theta = np.degrees(np.arccos(np.clip(-d[..., 2], -1.0, 1.0)))
        phi = np.degrees(np.arctan2(-d[..., 0], -d[..., 1])) % 360.0
        return self.at(theta, phi)

    def at(self, theta_deg, phi_deg):
        """I (cd) at polar angles ``theta_deg`` from nadir and azimuths ``phi_deg``, bilinear."""
        t = np.asarray(theta_deg, dtype=np.float64)
        p = np.asarray(phi_deg, dtype=np.float64) % 360.0
        ti, tw = _cell(self.theta_deg, t)
        pi, pw = _cell(self.phi_deg, p)
        c = self.candela
        row0 = c[pi, ti] * (1 - tw) + c[pi, ti + 1] * tw
        row1 = c[pi + 1, ti] * (1 - tw) + c[pi + 1, ti + 1] * tw
        inside = (t >= self.theta_deg[0]) & (t <= self.theta_deg[-1])
        return np.where(inside, row0 * (1 - pw) + row1 * pw, 0.0)


    def intensity_cubic(self, directions):
        """I (cd) toward ``directions`` as Cycles' IES node interpolates the same table:
        Catmull-Rom in θ then in φ (``kernel_ies_interp``: θ mirrored at the first angle, the
        last repeated; φ wrapped over 360°), negative results clamped to 0, 0 from the last θ."""
        d = np.asarray(directions, dtype=np.float64)
        theta = np.degrees(np.arccos(np.clip(-d[..., 2], -1.0, 1.0)))
        phi = np.degrees(np.arctan2(-d[..., 0], -d[..., 1])) % 360.0
        return self.at_cubic(theta, phi)

    def at_cubic(self, theta_deg, phi_deg):
        """I (cd) at (θ, φ) in degrees, interpolated as ``intensity_cubic``."""
        t = np.asarray(theta_deg, dtype=np.float64)
        p = np.asarray(phi_deg, dtype=np.float64) % 360.0
        nt, nphi = len(self.theta_deg), len(self.phi_deg)
        vi, vw = _cell(self.theta_deg, t)
        hi, hw = _cell(self.phi_deg, p)
        c = self.candela
        rows = [np.where(vi == 0, 1, vi - 1), vi, vi + 1, np.minimum(vi + 2, nt - 1)]

        def vertical(h):
            return _catmull_rom(*(c[h, r] for r in rows), vw)

        if nphi == 1:
            value = vertical(np.zeros_like(hi))
        else:  # φ's last plane is 360° = the first: wrap to the ones beside it
            before = np.where(hi == 0, max(nphi - 2, 0), hi - 1)
            after = np.where(hi + 2 >= nphi, np.minimum(1, nphi - 1), hi + 2)
            value = _catmull_rom(vertical(before), vertical(hi), vertical(hi + 1),
                                 vertical(after), hw)
        inside = (t >= self.theta_deg[0]) & (t < self.theta_deg[-1])
        return np.where(inside, np.maximum(value, 0.0), 0.0)


def _catmull_rom(a, b, c, d, x):
    """Cycles' ``cubic_interp``: the Catmull-Rom spline through b (x = 0) and c (x = 1)."""
    return 0.5 * (((d + 3.0 * (b - c) - a) * x + (2.0 * a - 5.0 * b + 4.0 * c - d)) * x
                  + (c - a)) * x + b


def _cell(grid, x):
    """Index i and weight w of x in the increasing ``grid`` (x = grid[i]·(1−w) + grid[i+1]·w)."""
    i = np.clip(np.searchsorted(grid, x, side="right") - 1, 0, len(grid) - 2)
    span = grid[i + 1] - grid[i]
    w = np.where(span > 0, (x - grid[i]) / np.where(span > 0, span, 1.0), 0.0)
    return i, np.clip(w, 0.0, 1.0)


def sphere_grid(n_theta=90, n_phi=180):
    """Cell-centred directions on the sphere (n_theta·n_phi, 3) and their exact solid angles."""
    edges = np.linspace(0.0, np.pi, n_theta + 1)
    theta = 0.5 * (edges[:-1] + edges[1:])
    phi = (np.arange(n_phi) + 0.5) * (2 * np.pi / n_phi)
    band = (np.cos(edges[:-1]) - np.cos(edges[1:])) * (2 * np.pi / n_phi)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    dirs = np.stack([-np.sin(t) * np.sin(p), -np.sin(t) * np.cos(p), -np.cos(t)], axis=-1)
    weights = np.repeat(band, n_phi)
    return dirs.reshape(-1, 3), weights


def integrate(table, values):
    """∫ f dω of a function tabulated on ``table``'s grid, exact for its bilinear interpolant.

    Per θ interval [t0, t1] of width h, f linear in θ: ∫ f sinθ dθ = f0·(c − W) + f1·W with
    c = cos t0 − cos t1 and W = (sin t1 − sin t0 − h cos t1) / h; then the trapezoid in φ
    (exact for f linear in φ).
    """
    t = np.radians(table.theta_deg)
    p = np.radians(table.phi_deg)
    t0, t1 = t[:-1], t[1:]
    h = t1 - t0
    safe = np.where(h > 0, h, 1.0)
    w1 = np.where(h > 0, (np.sin(t1) - np.sin(t0) - h * np.cos(t1)) / safe, 0.0)
    w0 = (np.cos(t0) - np.cos(t1)) - w1
    weights = np.zeros(len(t))
    np.add.at(weights, np.arange(len(t) - 1), w0)
    np.add.at(weights, np.arange(1, len(t)), w1)
    over_theta = np.asarray(values, dtype=np.float64) @ weights
    return float(np.sum(0.5 * (over_theta[:-1] + over_theta[1:]) * np.diff(p)))


def full_table(theta_deg, phi_deg, candela, rated_lm, opening_m, source):
    """A read-only :class:`CandelaTable`; φ given as one plane (rotational symmetry) or 0..360."""
    theta = np.array(theta_deg, dtype=np.float64)
    phi = np.array(phi_deg, dtype=np.float64)
    cd = np.array(candela, dtype=np.float64)
    if len(theta) == 1:  # one vertical angle: a ring of no width, as good as dark
        theta = np.array([theta[0], theta[0]])
        cd = np.concatenate([cd, cd], axis=1)
    if len(phi) == 1:  # rotationally symmetric
        phi = np.array([0.0, 360.0])
        cd = np.concatenate([cd, cd], axis=0)
    for array in (theta, phi, cd):
        array.setflags(write=False)
    return CandelaTable(theta, phi, cd, float(rated_lm), tuple(float(x) for x in opening_m), source)


def mirror_to_circle(phi_deg, candela):
    """Planes given on 0, 0..90, 0..180, 90..270 or 0..360 expanded to 0..360 by symmetry.

    0..90: symmetric about the C0–C180 and C90–C270 planes; 0..180: about C0–C180
    (I(360 − φ) = I(φ)); 90..270: about C90–C270 (I(180 − φ) = I(φ)), mirrored as the
    standard says (Blender's reader instead turns these by 90°). A full circle may omit 360
    when its spacing shows it (as Blender accepts). Raises ValueError naming the range.
    """
    phi = np.asarray(phi_deg, dtype=np.float64)
    cd = np.asarray(candela, dtype=np.float64)
    if len(phi) == 1:
        return phi, cd
    first, last = phi[0], phi[-1]
    if first == 0.0 and last == 90.0:
        reflections = (lambda a: 180.0 - a, lambda a: 180.0 + a, lambda a: 360.0 - a)
    elif first == 0.0 and last == 180.0:
        reflections = (lambda a: 360.0 - a,)
    elif first == 90.0 and last == 270.0:
        reflections = (lambda a: (180.0 - a) % 360.0,)
    elif first == 0.0 and (last == 360.0 or np.isclose(360.0 - last, last - phi[-2])):
        reflections = ()
    else:
        raise ValueError(f"planes from {first:g} to {last:g} degrees: expected one plane, "
                         "0-90, 0-180, 90-270 or 0-360")
    planes = {}
    for angle, row in zip(phi, cd):
        planes[float(angle)] = row
        for reflect in reflections:
            planes.setdefault(float(reflect(angle)), row)
    planes[360.0] = planes[0.0]
    angles = np.array(sorted(planes))
    return angles, np.stack([planes[a] for a in angles])


def to_ies_text(table, label="sh_lighting"):
    """LM-63-2002 text of ``table`` (type C, absolute candela) that Blender's IES node reads.

    Used for EULUMDAT and type B files, which Blender cannot read: the grid is written as is
    (θ as vertical angles 0..180, φ as horizontal angles 0..360), so Cycles interpolates the
    same samples the file gave.
    """
    length, width, height = table.opening_m
    lines = [
        "IESNA:LM-63-2002",
        f"[TEST] converted by sh_lighting from {label}",
        "[MANUFAC] sh_lighting",
        "TILT=NONE",
        # lamps, lumens (-1: absolute photometry), multiplier, #vertical, #horizontal,
        # type C (1), metres (2), width, length, height
        (f"1 -1 1 {len(table.theta_deg)} {len(table.phi_deg)} 1 2 "
         f"{width!r} {length!r} {height!r}"),
        "1 1 0",
    ]
    lines += _rows(table.theta_deg)
    lines += _rows(table.phi_deg)
    for row in table.candela:
        lines += _rows(row)
    return "\n".join(lines) + "\n"


def _rows(values, per_line=8):
    values = [repr(float(v)) for v in values]
    return [" ".join(values[i:i + per_line]) for i in range(0, len(values), per_line)]
