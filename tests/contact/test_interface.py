"""Spots, perimeter, corrected area and gap of a contact interface.

Checked against things this module does not compute: scipy.ndimage.label on the
same masks (and, for periodic grids, on a rolled copy whose spots do not cross the
edges), the perimeter of rectangles, Hertz's area (the perimeter-corrected count of
Yastrebov et al. 2017 closer to it than the element count, which overestimates it to
first order), the peaks of a doubly sinusoidal surface (one spot each, across the
periodic edges too), and the mean of the gap field recomputed from the pressure.
"""

import math

import numpy as np
import pytest
import scipy.ndimage

from roughcontact.contact import SolverOptions, interface, solve
from roughcontact.contact.nondim import CellOptions
from roughcontact.elasticity.halfspace import PeriodicHalfSpace

E, NU, SIZE = 210e9, 0.3, 1.0e-3
CROSS = [[0, 1, 0], [1, 1, 1], [0, 1, 0]]  # 4-connectivity


@pytest.mark.parametrize("density", [0.2, 0.45, 0.6, 0.8])
def test_spot_count_equals_ndimage_label(density):
    rng = np.random.default_rng(int(density * 100))
    masks = rng.random((5, 37, 53)) < density
    labels, counts = interface.label_spots(masks)
    for mask, label, count in zip(masks, labels, counts, strict=True):
        reference, expected = scipy.ndimage.label(mask, structure=CROSS)
        assert count == expected
        # the same partition: each of our spots is exactly one of theirs
        assert (label > 0).sum() == mask.sum()
        pairs = {(a, b) for a, b in zip(label[mask], reference[mask], strict=True)}
        assert len(pairs) == expected


def test_periodic_spots_merge_across_the_edges():
    rng = np.random.default_rng(7)
    for _ in range(20):
        mask = rng.random((30, 41)) < 0.35
        mask[0, :] = False  # an empty row and column: no spot crosses them
        mask[:, 0] = False
        _, expected = scipy.ndimage.label(mask, structure=CROSS)
        shift = (int(rng.integers(1, 30)), int(rng.integers(1, 41)))
        rolled = np.roll(mask, shift, axis=(0, 1))  # now spots cross the edges
        _, (count,) = interface.label_spots(rolled[None], periodic=True)
        assert count == expected
        _, (cut,) = interface.label_spots(rolled[None], periodic=False)
        assert cut >= expected


def test_a_spot_across_a_corner_is_one_spot_only_when_periodic():
    mask = np.zeros((10, 12), dtype=bool)
    mask[[0, 0, -1, -1], [0, -1, 0, -1]] = True
    assert interface.label_spots(mask, periodic=True)[1] == 1
    assert interface.label_spots(mask, periodic=False)[1] == 4
    # touching at a corner only: two spots (4-connectivity)
    diagonal = np.zeros((6, 6), dtype=bool)
    diagonal[2, 2] = diagonal[3, 3] = True
    assert interface.label_spots(diagonal)[1] == 2


def test_perimeter_of_rectangles():
    dx, dy = 2.0e-6, 3.0e-6
    mask = np.zeros((20, 30), dtype=bool)
    mask[3:8, 4:15] = True  # 5 rows x 11 columns
    mask[12:14, 20:29] = True  # 2 rows x 9 columns
    grid = interface.InterfaceGrid((dx, dy))
    summary = interface.describe(mask.astype(float), np.zeros(mask.shape), grid)
    expected = 2 * (5 * dy + 11 * dx) + 2 * (2 * dy + 9 * dx)
    assert summary.perimeter == pytest.approx(expected, rel=1e-12)
    assert summary.spot_count == 2
    assert summary.mean_spot_area == pytest.approx((55 + 18) / 2 * dx * dy, rel=1e-12)
    np.testing.assert_allclose(summary.spot_area_quantiles, [18 * dx * dy] * 3
                               + [55 * dx * dy] * 3, rtol=1e-12)
    switches = 2 * (5 + 11) + 2 * (2 + 9)
    assert summary.corrected_real_area_fraction == pytest.approx(
        (73 - interface.PERIMETER_CORRECTION * switches) / 600, rel=1e-12)
    # a rectangle touching a periodic edge has no switch there
    edge = np.zeros((8, 8), dtype=bool)
    edge[:, 2:5] = True  # a full-height strip: periodic in y, no y-switches
    sx, sy = interface.perimeter_switches(edge, periodic=True)
    assert (sx, sy) == (16, 0)
    sx, sy = interface.perimeter_switches(edge, periodic=False)
    assert (sx, sy) == (16, 0)


def test_perimeter_correction_as_written():
    assert interface.PERIMETER_CORRECTION == pytest.approx((math.pi - 1 + math.log(2)) / 24)
    assert 0.118 < interface.PERIMETER_CORRECTION < 0.1182


def hertz_errors(n, offsets, radius=5.0e-3, a=0.1e-3):
    """Relative area errors (element count, corrected) of a sphere on a periodic
    half-space of period SIZE, at the Hertz load of contact radius ``a``, for
    sub-element offsets of the sphere's centre."""
    e_star = E / (1 - NU**2)
    load = 4 * e_star * a**3 / (3 * radius)
    exact = math.pi * a**2 / SIZE**2
    dx = SIZE / n
    op = PeriodicHalfSpace((n, n), (SIZE, SIZE), E, NU)
    grid = interface.InterfaceGrid.of(op, (SIZE, SIZE))
    assert grid.periodic
    x = (np.arange(n) + 0.5) * dx - SIZE / 2
    count, corrected = [], []
    for ox, oy in offsets:
        X, Y = np.meshgrid(x - ox * dx, x - oy * dx)
        result = solve(op, (X**2 + Y**2) / (2 * radius), mean_pressure=load / SIZE**2,
                       options=SolverOptions(tol=1e-10))
        assert result.converged
        summary = interface.describe(result.pressure, result.gap, grid)
        assert summary.spot_count == 1
        count.append(result.real_area_fraction / exact - 1)
        corrected.append(summary.corrected_real_area_fraction / exact - 1)
    return np.mean(count), np.mean(corrected)


def test_hertz_area_corrected_by_the_perimeter_is_closer_than_the_count():
    offsets = np.random.default_rng(1).random((6, 2))
    errors = {n: hertz_errors(n, offsets) for n in (32, 64, 128)}
    for n, (count, corrected) in errors.items():
        # the count overestimates, to first order in the element size
        assert count > 0.01, (n, errors)
        # (a margin of several elements flipping at the contact edge on another CPU)
        assert abs(corrected) < 0.8 * count, (n, errors)
    # first order: the count's error halves with the element size (within noise)
    assert errors[128][0] < 0.75 * errors[64][0] < 0.75**2 * errors[32][0]
    # periodic images make the fine-grid area slightly smaller than Hertz's
    assert abs(errors[128][1]) < 0.01


def test_doubly_sinusoidal_surface_has_one_spot_per_peak_across_periodic_edges():
    n, periods = 60, 3  # 20 elements a period: every peak on an element
    dx = SIZE / n
    x = np.arange(n) * dx  # peaks at x = 0: the spots at the edges wrap around
    X, Y = np.meshgrid(x, x)
    k = 2 * math.pi * periods / SIZE
    heights = 1e-6 * np.cos(k * X) * np.cos(k * Y)
    op = PeriodicHalfSpace((n, n), (SIZE, SIZE), E, NU)
    result = solve(op, heights.max() - heights, mean_pressure=1e8, options=SolverOptions(tol=1e-10))
    assert result.converged
    grid = interface.InterfaceGrid.of(op, (SIZE, SIZE))
    summary = interface.describe(result.pressure, result.gap, grid)
    # cos x cos y has maxima at (0, 0) and (pi, pi) of each period: 2 per period cell
    assert summary.spot_count == 2 * periods**2
    cut = interface.describe(result.pressure, result.gap,
                             interface.InterfaceGrid(grid.spacing, periodic=False))
    assert cut.spot_count > summary.spot_count  # the edge spots come apart
    # all spots alike (up to an element at a spot's edge whose pressure is round-off)
    q = summary.spot_area_quantiles
    assert q[0] > 8 * dx * dx and q[-1] - q[0] <= 4 * dx * dx
    assert summary.mean_spot_area == pytest.approx(
        result.real_area_fraction * SIZE**2 / (2 * periods**2), rel=1e-12)


def test_mean_gap_and_gap_quantiles_of_a_solution():
    rng = np.random.default_rng(3)
    n = 32
    heights = scipy.ndimage.gaussian_filter(rng.standard_normal((n, n)), 2.0, mode="wrap")
    heights *= 1e-6 / heights.std()
    op = PeriodicHalfSpace((n, n), (SIZE, SIZE), E, NU, mean_compliance=1e-12)
    f = heights.max() - heights
    d = 1.5e-6
    result = solve(op, f, approach=d, options=SolverOptions(tol=1e-12))
    grid = interface.InterfaceGrid.of(op, (SIZE, SIZE))
    assert not grid.periodic  # a positive mean compliance: not taken as a periodic cell
    # the gap recomputed from the pressure, independently of the result's gap field
    gap = (op.matvec(result.pressure.ravel()) + f.ravel() - d).reshape(n, n)
    summary = interface.describe(result.pressure, gap, grid)
    assert summary.mean_gap == pytest.approx(gap.mean(), rel=1e-12)
    assert summary.mean_gap > 0
    np.testing.assert_allclose(
        summary.gap_quantiles,
        np.quantile(gap.ravel(), interface.GAP_PROBABILITIES, method="inverted_cdf"),
        rtol=0, atol=0)
    contact = result.real_area_fraction
    # elements in contact have zero gap (to the solver's tolerance)
    assert abs(summary.gap_quantiles[0]) < 1e-9 * d if contact > 0.05 else True


def test_no_contact_and_bad_input():
    summary = interface.describe(np.zeros((2, 4, 5)), np.ones((2, 4, 5)),
                                 interface.InterfaceGrid((1.0, 1.0)))
    np.testing.assert_array_equal(summary.spot_count, [0, 0])
    assert np.isnan(summary.mean_spot_area).all()
    assert np.isnan(summary.spot_area_quantiles).all()
    np.testing.assert_array_equal(summary.perimeter, [0.0, 0.0])
    with pytest.raises(ValueError, match="spacing"):
        interface.InterfaceGrid((0.0, 1.0))
    with pytest.raises(ValueError, match="same shape"):
        interface.describe(np.zeros((4, 5)), np.zeros((5, 4)), interface.InterfaceGrid((1, 1)))
    with pytest.raises(ValueError, match=r"\(\.\.\., ny, nx\)"):
        interface.describe(np.zeros(5), np.zeros(5), interface.InterfaceGrid((1, 1)))


@pytest.mark.parametrize("method", ["pivot", "cg"])
def test_a_sweep_records_the_interface_of_every_step(method):
    """The sweep's columns equal the quantities of its pressure fields, the gap
    recomputed from them; block principal pivoting records the surfaces one at a time
    (described together once a step is complete), CG all at once."""
    from roughcontact.contact import sweep
    from roughcontact.elasticity.halfspace import halfspace_influence

    n, size = 20, 1.0e-3
    rng = np.random.default_rng(11)
    heights = scipy.ndimage.gaussian_filter(rng.standard_normal((3, n, n)), (0, 2, 2),
                                            mode="wrap")
    heights *= 1e-6 / heights.std()
    f = heights.max(axis=(1, 2), keepdims=True) - heights
    C = halfspace_influence((n, n), (size, size), E, NU)
    d = np.linspace(0.5e-6, 2.5e-6, 5)
    grid = interface.InterfaceGrid((size / n, size / n))
    result = sweep(C, f, d, element_area=(size / n) ** 2, interface=grid,
                   options=SolverOptions(method=method, return_fields=True, tol=1e-12))
    p = result.pressure.reshape(3, 5, n * n)
    gap = (np.einsum("ij,mkj->mki", C, p) + f.reshape(3, 1, -1)
           - d[None, :, None]).reshape(3, 5, n, n)
    expected = interface.describe(result.pressure, gap, grid)
    np.testing.assert_array_equal(result.spot_count, expected.spot_count)
    np.testing.assert_array_equal(result.perimeter, expected.perimeter)
    np.testing.assert_array_equal(result.corrected_real_area_fraction,
                                  expected.corrected_real_area_fraction)
    np.testing.assert_allclose(result.mean_gap, expected.mean_gap, rtol=1e-9)
    np.testing.assert_allclose(result.gap_quantiles, expected.gap_quantiles, rtol=1e-9,
                               atol=1e-9 * d.max())
    np.testing.assert_array_equal(result.spot_area_quantiles, expected.spot_area_quantiles)
    assert (result.spot_count[:, -1] >= 1).all()


def test_aggregates_read_the_distributions_at_the_solved_steps():
    """At a pressure level that is a solved step of a single surface, the aggregated
    points of the distributions are the stored quantiles of that step."""
    from roughcontact.contact import aggregate, nondim
    from roughcontact.elasticity.halfspace import halfspace_influence

    n, size = 16, 1.0e-3
    rng = np.random.default_rng(4)
    heights = scipy.ndimage.gaussian_filter(rng.standard_normal((1, n, n)), (0, 2, 2),
                                            mode="wrap")
    heights /= heights.std()
    unit = halfspace_influence((n, n), (size, size), 1.0, 0.0)
    grid = interface.InterfaceGrid((size / n, size / n))
    nd = nondim.solve_cell(unit, heights, thickness=size, element_area=(size / n) ** 2,
                           approaches=np.linspace(0.5, 2.5, 6),
                           options=CellOptions().with_(method="pivot", tol=1e-12, interface=grid))
    sigma = 2e-6
    physical = nondim.to_physical(nd, sigma=sigma, E=1e9)
    steps = physical.nominal_pressure[0, 1:5]
    table = aggregate.aggregate_cell(physical, steps)
    median = interface.GAP_PROBABILITIES.index(0.5)
    np.testing.assert_allclose(table["gap_median_mean"], sigma * nd.gap_quantiles[0, 1:5, median],
                               rtol=1e-9)
    np.testing.assert_allclose(table["largest_spot_area_mean"],
                               nd.spot_area_quantiles[0, 1:5, -1], rtol=1e-9)
    np.testing.assert_allclose(table["mean_gap_mean"], sigma * nd.mean_gap[0, 1:5], rtol=1e-9)
    assert (table["gap_p10_mean"] <= table["gap_median_mean"]).all()
    assert (table["gap_median_mean"] <= table["gap_p90_mean"]).all()
