"""Where a contact seals: the surfaces' sealing points and a cell's threshold.

Referees: hand-made sweeps whose brackets are known, the exact binomial coverage of
a median's order-statistic interval computed here with math.comb (not scipy), and
numpy's median.
"""

import math

import numpy as np
import pytest

from roughcontact.transport.percolation import (
    ABOVE,
    BELOW,
    INSIDE,
    _median_ranks,
    sealing_points,
    threshold,
)


def _sweep(first_sealed, k=6, m=None):
    """Connected until step first_sealed (None: never sealed), areas 0.1, 0.2, ..."""
    m = len(first_sealed)
    connected = np.ones((m, k), bool)
    for j, s in enumerate(first_sealed):
        if s is not None:
            connected[j, s:] = False
    area = np.tile(0.1 * np.arange(1, k + 1), (m, 1))
    pressure = np.tile(np.geomspace(1.0, 32.0, k), (m, 1))
    return connected, area, pressure, np.ones((m, k), bool)


def test_a_sealing_point_is_the_middle_of_its_bracket():
    points = sealing_points(*_sweep([3, None, 0, 1]))
    assert list(points.where) == [INSIDE, ABOVE, BELOW, INSIDE]
    np.testing.assert_allclose(points.area[[0, 3]], [0.35, 0.15])
    np.testing.assert_allclose(points.area_low[[0, 3]], [0.3, 0.1])
    np.testing.assert_allclose(points.area_high[[0, 3]], [0.4, 0.2])
    np.testing.assert_allclose(points.pressure[0], math.sqrt(4.0 * 8.0))  # geometric
    assert np.isnan(points.area[[1, 2]]).all()


def test_unconverged_steps_are_skipped_and_reopenings_counted():
    connected, area, pressure, converged = _sweep([2])
    converged[0, 2] = False  # the first sealed step is not a result
    connected[0, 4] = True  # connects again later
    points = sealing_points(connected, area, pressure, converged)
    # the bracket closes at the next converged sealed step (index 3) after step 1
    np.testing.assert_allclose([points.area_low[0], points.area_high[0]], [0.2, 0.4])
    assert points.reopened[0] == 1


def _coverage(n, low):
    """P(X_(low) <= median <= X_(n+1-low)) = 1 - 2 P(B <= low - 1), B ~ binomial(n, 1/2)."""
    tail = sum(math.comb(n, i) for i in range(low)) / 2**n
    return 1.0 - 2.0 * tail


@pytest.mark.parametrize("n", [6, 10, 20, 59, 60, 61, 200])
def test_the_median_band_has_its_coverage_and_is_the_narrowest(n):
    low, high = _median_ranks(n, 0.95)
    assert high == n + 1 - low
    assert _coverage(n, low) >= 0.95
    assert _coverage(n, low + 1) < 0.95  # one rank narrower would not cover


def test_the_threshold_is_the_median_of_the_points_with_a_band():
    rng = np.random.default_rng(3)
    m = 60
    firsts = rng.integers(1, 6, size=m)
    points = sealing_points(*_sweep(list(firsts)))
    found = threshold(points)
    np.testing.assert_allclose(found.area, np.median(points.area))
    ordered = np.sort(points.area)
    assert found.area_low == ordered[21] and found.area_high == ordered[38]  # ranks 22, 39
    assert (found.surfaces, found.sealed_inside, found.above, found.below) == (60, 60, 0, 0)
    assert found.note == "inside the swept range"


def test_surfaces_beyond_the_range_count_in_the_median_but_give_no_number():
    # 4 of 6 never seal: the median lies above the swept range
    found = threshold(sealing_points(*_sweep([2, 3, None, None, None, None])))
    assert np.isnan(found.area) and "above the swept range" in found.note
    assert found.above == 4
    # 1 of 7 seals at once, the rest inside: the median is still found
    found = threshold(sealing_points(*_sweep([0, 2, 2, 3, 3, 4, 5])))
    assert found.below == 1
    np.testing.assert_allclose(found.area, 0.35)  # 4th of [below, .25, .25, .35, .35, ...]


def test_too_few_surfaces_have_no_band():
    found = threshold(sealing_points(*_sweep([2, 3, 3, 4])))
    assert np.isfinite(found.area) and np.isnan(found.area_low)
    assert "too few surfaces" in found.note


def test_mismatched_shapes_are_refused():
    connected, area, pressure, converged = _sweep([2, 3])
    with pytest.raises(ValueError, match="one shape"):
        sealing_points(connected[:1], area, pressure, converged)
