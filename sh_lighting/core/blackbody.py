"""A blackbody's colour at a temperature, as Blender's Blackbody node and Light Temperature.

Blender (Cycles ``svm_math_blackbody_color_rec709``, the same in ``IMB_colormanagement``) fits
the Planckian locus in linear Rec.709 piecewise between knots t₀ < … < t₅ (K):

    R = a_r / T + b_r T + c_r,   G = a_g / T + b_g T + c_g,   B = ((a_b T + b_b) T + c_b) T + d_b

constant below 800 K and from 12000 K, negative values clamped to 0 (wider than Rec.709).
The coefficients below are Blender's; ``blackbody_rgb`` is linear Rec.709 (Blender's default
scene-linear space), about 1 at 6500 K; convert with ``core.colour`` for other working spaces.
"""

import numpy as np

KNOTS = (965.0, 1167.0, 1449.0, 1902.0, 3315.0, 6365.0)
_R = ((1.61919106e+03, -2.05010916e-03, 5.02995757e+00),
      (2.48845471e+03, -1.11330907e-03, 3.22621544e+00),
      (3.34143193e+03, -4.86551192e-04, 1.76486769e+00),
      (4.09461742e+03, -1.27446582e-04, 7.25731635e-01),
      (4.67028036e+03, 2.91258199e-05, 1.26703442e-01),
      (4.59509185e+03, 2.87495649e-05, 1.50345020e-01),
      (3.78717450e+03, 9.35907826e-06, 3.99075871e-01))
_G = ((-4.88999748e+02, 6.04330754e-04, -7.55807526e-02),
      (-7.55994277e+02, 3.16730098e-04, 4.78306139e-01),
      (-1.02363977e+03, 1.20223470e-04, 9.36662319e-01),
      (-1.26571316e+03, 4.87340896e-06, 1.27054498e+00),
      (-1.42529332e+03, -4.01150431e-05, 1.43972784e+00),
      (-1.17554822e+03, -2.16378048e-05, 1.30408023e+00),
      (-5.00799571e+02, -4.59832026e-06, 1.09098763e+00))
_B = ((5.96945309e-11, -4.85742887e-08, -9.70622247e-05, -4.07936148e-03),
      (2.40430366e-11, 5.55021075e-08, -1.98503712e-04, 2.89312858e-02),
      (-1.40949732e-11, 1.89878968e-07, -3.56632824e-04, 9.10767778e-02),
      (-3.61460868e-11, 2.84822009e-07, -4.93211319e-04, 1.56723440e-01),
      (-1.97075738e-11, 1.75359352e-07, -2.50542825e-04, -2.22783266e-02),
      (-1.61997957e-13, -1.64216008e-08, 3.86216271e-04, -7.38077418e-01),
      (6.72650283e-13, -2.73078809e-08, 4.24098264e-04, -7.52335691e-01))
ABOVE = (0.8262954810464208, 0.9945080501520986, 1.566307710274283)  # T ≥ 12000 K
BELOW = (5.413294490189271, -0.20319390035873933, -0.0822535242887164)  # T < 800 K


def blackbody_rgb(kelvin):
    """Linear Rec.709 (…, 3) of a blackbody at ``kelvin`` (scalar or array, finite)."""
    t = np.asarray(kelvin, dtype=np.float64)
    if not np.isfinite(t).all():
        raise ValueError("colour temperature must be a finite number of kelvin")
    piece = np.searchsorted(KNOTS, t, side="right")  # 0 below 965 K … 6 from 6365 K
    r, g, b = (np.asarray(table)[piece] for table in (_R, _G, _B))
    inverse = 1.0 / np.maximum(t, 1.0)
    rgb = np.stack([r[..., 0] * inverse + r[..., 1] * t + r[..., 2],
                    g[..., 0] * inverse + g[..., 1] * t + g[..., 2],
                    ((b[..., 0] * t + b[..., 1]) * t + b[..., 2]) * t + b[..., 3]], axis=-1)
    rgb = np.where((t >= 12000.0)[..., None], ABOVE, rgb)
    rgb = np.where((t < 800.0)[..., None], BELOW, rgb)
    return np.maximum(rgb, 0.0)
