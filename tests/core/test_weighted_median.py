"""The background's weighted median of large maps (core.lights): a bracket instead of a sort."""

import numpy as np
import pytest

from sh_lighting.core import lights
from sh_lighting.core.equirect import texel_solid_angles


def sorted_median(values, weights):
    order = np.argsort(values, axis=None)
    cumulative = np.cumsum(np.broadcast_to(weights, values.shape).ravel()[order])
    return float(values.ravel()[order][np.searchsorted(cumulative, 0.5 * cumulative[-1])])


@pytest.mark.parametrize("kind", ["lognormal", "ties", "one bright row"])
def test_the_bracketed_median_is_the_sorted_one(monkeypatch, kind):
    monkeypatch.setattr(lights, "MEDIAN_SORT_LIMIT", 1 << 10)  # take the bracket at 256x512
    rng = np.random.default_rng(7)
    values = rng.lognormal(size=(256, 512))
    weights = texel_solid_angles(256, 512)[:, None]
    if kind == "ties":
        values = np.round(values, 1)  # many equal values around the median
    elif kind == "one bright row":  # half the weight in one row the subsample may miss
        weights = np.ones((256, 512))
        weights[101] = 1e6
        values[101] = 1e3 + np.arange(512)
    assert lights.weighted_median(values, weights) == sorted_median(values, weights)
    assert lights._bracketed_median(values, np.broadcast_to(weights, values.shape)) in (
        None, sorted_median(values, weights))
