"""Tests of the per-cell statistics (Eq 33, 35-45 of Kumar et al. 2006).

The cell is a 12 x 12 finite block (nu = 0, clamped base, the paper's mesh),
whose influence rows sum exactly to L/E (Eq 38), so d_b = P L / E holds
exactly (Eq 44) and k_P = E at full contact.
"""

from dataclasses import replace

import numpy as np
import pytest
import scipy.stats
from approach_targets import target_grid

from roughcontact.contact import aggregate, nondim
from roughcontact.contact.nondim import CellOptions
from roughcontact.contact.probes import Column, ProbeColumns
from roughcontact.elasticity.influence import BlockGeometry, unit_modulus_influence
from roughcontact.surfaces.spec import SurfaceSpec
from roughcontact.surfaces.synthetic import generate_many

SIZE = 1.8e-3  # plan size [m]
GRID = 12
LENGTH = 2.0e-3  # block thickness L [m]
AREA = (SIZE / GRID) ** 2  # element area [m^2]
E = 5.11e8  # [Pa], Table 1
SIGMA = 24.5e-6  # [m]
SURFACES = 32


def block(nu):
    geom = BlockGeometry(size=(SIZE, SIZE), thickness=LENGTH, grid=(GRID, GRID), nu=nu)
    return unit_modulus_influence(geom)


def subset(nd, count):
    """The first ``count`` surfaces of a dimensionless sweep."""
    arrays = {name: getattr(nd, name)[:count] for name in nd.__dataclass_fields__
              if isinstance(getattr(nd, name), np.ndarray)}
    return replace(nd, **arrays)


@pytest.fixture(scope="module")
def heights():
    spec = SurfaceSpec(grid=GRID, size=SIZE, corr_length=4e-4)
    z = generate_many(spec, range(100, 100 + SURFACES))
    return z / z.std(axis=(1, 2), keepdims=True)


@pytest.fixture(scope="module")
def block_nu0():
    return block(0.0)


@pytest.fixture(scope="module")
def approaches(heights, block_nu0):
    return target_grid(heights, block_nu0, thickness=LENGTH, target_area=0.95, steps=24,
                       method="exact", start=1e-5)


@pytest.fixture(scope="module")
def nd_cell(heights, block_nu0, approaches):
    # block pivoting: on this block CG needs > 1000 iterations near full contact
    return nondim.solve_cell(block_nu0, heights, thickness=LENGTH, element_area=AREA,
                             approaches=approaches, options=CellOptions().with_(method="exact"))


@pytest.fixture(scope="module")
def cell(nd_cell):
    assert nd_cell.converged.all() and nd_cell.stiffness_converged.all()
    return nondim.to_physical(nd_cell, SIGMA, E)


def test_pressure_axis():
    axis = aggregate.pressure_axis(1e5, 1e7, 5)
    assert axis == pytest.approx([1e5, 10**5.5, 1e6, 10**6.5, 1e7])
    assert aggregate.pressure_axis(1.0, 3.0, 3, spacing="linear") == pytest.approx([1, 2, 3])
    with pytest.raises(ValueError, match="P_min < P_max"):
        aggregate.pressure_axis(0.0, 1e6, 4)
    with pytest.raises(ValueError, match="n must"):
        aggregate.pressure_axis(1e5, 1e6, 1)


def test_mean_plane_modulus_equals_E_for_nu0(cell):
    """Eq 44: every surface lies on d_b = P L / E."""
    per_surface = aggregate.mean_plane_modulus(cell)
    assert len(per_surface) == SURFACES
    assert (per_surface["steps_used"] == cell.approach.shape[1]).all()
    assert np.abs(per_surface["mean_plane_modulus"] / E - 1).max() < 1e-6
    assert per_surface["linearity_residual"].max() < 1e-9
    summary = aggregate.modulus_summary(per_surface, E)
    assert abs(summary["relative_deviation"]) < 1e-6
    assert summary["max_relative_deviation"] < 1e-6
    assert summary["min"] <= summary["mean"] <= summary["max"]


def test_mean_plane_modulus_deviates_for_nu03(heights, approaches):
    """For nu = 0.3 the rows no longer sum to L/E: E_u != E (paper: about 5 %)."""
    chat = block(0.3)
    nd = nondim.solve_cell(chat, heights[:4], thickness=LENGTH, element_area=AREA,
                           approaches=approaches[::4])
    per_surface = aggregate.mean_plane_modulus(nondim.to_physical(nd, SIGMA, E))
    summary = aggregate.modulus_summary(per_surface, E)
    assert summary["max_relative_deviation"] > 1e-2
    assert summary["std"] > 0


def test_normalized_stiffness_tends_to_E(cell):
    """k_P -> E as contact becomes full (nu = 0, Eq 33 with Eq 38)."""
    low, high = aggregate.covered_range(cell)
    table = aggregate.aggregate_cell(cell, aggregate.pressure_axis(low, high, 12))
    k_P = table["normalized_stiffness_mean"].to_numpy()
    assert (table["normalized_stiffness_count"] == SURFACES).all()
    assert (np.diff(k_P) >= 0).all() and k_P[-1] > 2 * k_P[0]
    assert k_P[0] < 0.8 * E  # far from E at low load
    # real area >= 0.95 on every surface at the last step: k_P within 1e-4 of E
    assert (cell.real_area_fraction[:, -1] >= 0.95).all()
    assert np.abs(cell.normalized_stiffness[:, -1] / E - 1).max() < 1e-4
    assert k_P[-1] == pytest.approx(E, rel=1e-4)
    # asperity deflection dominates at low load, bulk at high load (Eq 45, Fig 9)
    d_a = table["asperity_deflection_mean"].to_numpy()
    d_b = table["mean_plane_deflection_mean"].to_numpy()
    assert d_a[0] > d_b[0] and d_b[-1] > d_a[-1]
    assert table["approach_mean"].to_numpy() == pytest.approx(d_a + d_b, rel=1e-12)


def test_averaged_curves_keep_eq36_and_eq45_between_the_solved_steps(cell):
    """d_b = P L / E (Eq 44, nu = 0) and d = d_a + d_b (Eq 45) at levels between steps.

    Linear interpolation in log P sags below the straight line d_b(P)
    between steps whose pressures differ by a large ratio (up to 4 on this
    sweep; measured 7.6 % at worst).
    """
    low, high = aggregate.covered_range(cell)
    levels = aggregate.pressure_axis(low, high, 37)  # not the solved steps
    table = aggregate.aggregate_cell(cell, levels)
    d_b = table["mean_plane_deflection_mean"].to_numpy()
    np.testing.assert_allclose(d_b, levels * LENGTH / E, rtol=1e-9)
    np.testing.assert_allclose(table["approach_mean"].to_numpy(),
                               (table["asperity_deflection_mean"] + d_b).to_numpy(), rtol=1e-12)
    linear = np.array([np.interp(np.log(levels), np.log(P), db) for P, db in
                       zip(cell.nominal_pressure, cell.mean_plane_deflection, strict=True)])
    assert np.abs(linear.mean(axis=0) / (levels * LENGTH / E) - 1).max() > 1e-2


def test_half_width_is_student_t(cell):
    """Independent recomputation: a power law between steps, t s / sqrt(n)."""
    low, high = aggregate.covered_range(cell)
    levels = aggregate.pressure_axis(low, high, 5)
    table = aggregate.aggregate_cell(cell, levels, confidence=0.9)
    samples = np.array([np.exp(np.interp(np.log(levels), np.log(P), np.log(area)))
                        for P, area in zip(cell.nominal_pressure, cell.real_area_fraction,
                                           strict=True)])
    t = scipy.stats.t.ppf(0.95, SURFACES - 1)
    expected = t * samples.std(axis=0, ddof=1) / np.sqrt(SURFACES)
    assert table["real_area_fraction_mean"].to_numpy() == pytest.approx(samples.mean(axis=0))
    assert table["real_area_fraction_half_width"].to_numpy() == pytest.approx(expected)
    assert table.attrs["units"]["max_pressure_mean"] == "Pa"


def test_band_shrinks_like_inverse_sqrt_m(nd_cell):
    few, many = 8, SURFACES
    sweeps = {m: nondim.to_physical(subset(nd_cell, m), SIGMA, E) for m in (few, many)}
    low, high = aggregate.covered_range(sweeps[many])
    levels = aggregate.pressure_axis(low, high, 10)[:-1]
    tables = {m: aggregate.aggregate_cell(s, levels) for m, s in sweeps.items()}
    t_ratio = scipy.stats.t.ppf(0.975, few - 1) / scipy.stats.t.ppf(0.975, many - 1)
    expected = t_ratio * np.sqrt(many / few)  # 2.32
    for name in ("normalized_stiffness", "real_area_fraction", "max_pressure"):
        ratio = (tables[few][f"{name}_half_width"] / tables[many][f"{name}_half_width"])
        assert 0.6 * expected < np.median(ratio) < 1.6 * expected, name


def test_levels_beyond_a_surface_are_not_extrapolated(cell):
    last = cell.nominal_pressure[:, -1]
    first = cell.nominal_pressure[:, 0]
    order = np.sort(last)
    levels = np.array([0.5 * first.min(), np.median(first), 0.5 * (order[0] + order[1]),
                       0.5 * (order[-2] + order[-1]), 2.0 * order[-1]])
    table = aggregate.aggregate_cell(cell, levels)
    covers = (first[:, None] <= levels) & (levels <= last[:, None])
    expected_count = covers.sum(axis=0)
    # at the median first step: the surfaces whose first step is at or below it (half,
    # or more where first steps tie)
    assert list(expected_count) == [0, int(np.sum(first <= np.median(first))), SURFACES - 1,
                                    1, 0]
    assert expected_count[1] >= SURFACES // 2
    for name in aggregate.QUANTITIES:
        assert (table[f"{name}_count"].to_numpy() == expected_count).all(), name
    area = np.array([np.exp(np.interp(np.log(levels), np.log(P), np.log(a))) for P, a in
                     zip(cell.nominal_pressure, cell.real_area_fraction, strict=True)])
    mean = np.where(covers, area, 0).sum(axis=0)[1:4] / expected_count[1:4]
    assert table["real_area_fraction_mean"].to_numpy()[1:4] == pytest.approx(mean)
    assert table[["real_area_fraction_mean", "max_pressure_mean"]].iloc[[0, -1]].isna().all(
        axis=None)
    assert np.isnan(table["approach_half_width"].iloc[3])  # one surface: no band
    assert (table["surfaces"] == SURFACES).all()
    # an empty row says why: below every surface's first step, above every last one
    assert list(table["coverage"]) == ["below the first solved step", "some surfaces",
                                       "some surfaces", "some surfaces",
                                       "above the last solved step"]
    inside = np.array([first.max(), np.sqrt(first.max() * order[0])])
    assert list(aggregate.coverage(cell, inside)) == ["all surfaces"] * 2


def test_unconverged_steps_are_excluded_and_counted(heights, block_nu0, approaches):
    nd = nondim.solve_cell(block_nu0, heights[:6], thickness=LENGTH, element_area=AREA,
                           approaches=approaches,
                           options=CellOptions().with_(method="exact", max_iter=3))
    bad = ~nd.converged
    assert bad.any() and (~bad).sum(axis=1).min() >= 2
    physical = nondim.to_physical(nd, SIGMA, E)
    spoiled = replace(physical, **{
        name: np.where(bad, 1e30, getattr(physical, name))
        for name in ("normalized_stiffness", "mean_plane_deflection", "real_area_fraction",
                     "max_pressure")})
    levels = aggregate.pressure_axis(*aggregate.covered_range(physical), 6)
    table = aggregate.aggregate_cell(physical, levels)
    assert (table["unconverged_steps"] == bad.sum()).all()
    assert np.isfinite(table["real_area_fraction_mean"]).all()
    spoiled_table = aggregate.aggregate_cell(spoiled, levels)
    assert spoiled_table.equals(table)
    assert aggregate.mean_plane_modulus(spoiled).equals(aggregate.mean_plane_modulus(physical))
    # the unconverged steps alone would have given other values
    trusted = replace(physical, converged=np.ones_like(bad))
    assert not aggregate.aggregate_cell(trusted, levels)["real_area_fraction_mean"].equals(
        table["real_area_fraction_mean"])


def test_unconverged_stiffness_is_excluded_from_k_P_only(cell):
    flags = cell.stiffness_converged.copy()
    flags[0, :] = False
    table = aggregate.aggregate_cell(replace(cell, stiffness_converged=flags),
                                     aggregate.pressure_axis(*aggregate.covered_range(cell), 4))
    assert (table["normalized_stiffness_count"] == SURFACES - 1).all()
    assert (table["real_area_fraction_count"] == SURFACES).all()
    assert (table["unconverged_stiffness_steps"] == cell.approach.shape[1]).all()


class _StillOpen:
    """A probe of one yes/no column (a stand-in for the flow's percolation); its values
    are given to the record by hand."""

    kind = "still_open"
    columns = (Column("still_open", "1", "share of surfaces still open", dtype=bool),)

    def params(self):
        return {}

    def measure(self, fields):
        raise AssertionError("not swept here")


def test_still_leaking_is_read_at_the_nearest_step_not_interpolated(cell):
    """A yes/no state (a probe's bool column, e.g. the flow's percolation) is each
    surface's state at its step nearest in log P: the share over surfaces counts whole
    surfaces, computed here by hand."""
    m, k = cell.nominal_pressure.shape
    sealed_from = np.arange(m) % (k - 2) + 1  # each surface seals at its own step
    connected = np.arange(k)[None, :] < sealed_from[:, None]
    swept = replace(cell, probe_columns=ProbeColumns((_StillOpen(),),
                                                     {"still_open": connected}))
    levels = np.geomspace(cell.nominal_pressure[:, 0].max(),
                          cell.nominal_pressure[:, -1].min(), 9)
    curves = aggregate.surface_curves(swept, levels, "still_open")
    assert set(np.unique(curves[np.isfinite(curves)])) <= {0.0, 1.0}
    for j in range(m):
        log_p = np.log(cell.nominal_pressure[j])
        nearest = np.abs(log_p[None, :] - np.log(levels)[:, None]).argmin(axis=1)
        np.testing.assert_array_equal(curves[j], connected[j, nearest])
    table = aggregate.aggregate_cell(swept, levels)
    np.testing.assert_allclose(table["still_open_mean"], curves.mean(axis=0))
    assert table.attrs["units"]["still_open_mean"] == "1"
    # the probe's column comes last, after every quantity of the sweep itself
    assert list(table.columns[-7:-4]) == ["still_open_mean", "still_open_half_width",
                                          "still_open_count"]
