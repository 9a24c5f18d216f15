"""The share of an elastic solution above a hardness, read from stored profiles.

Checked against the full pressure fields of the same sweep (counted directly),
against a capped solve (where nothing exceeds H the elastic solution is also
the capped one; where it does, the capped solve's plastic area is close to
the elastic share above H), and the scaling rule: a capped sweep holds only
for the (sigma, E, H) of its H L / (E sigma).
"""

import numpy as np
import pytest

from roughcontact.contact import SolverOptions, nondim, sweep, validity
from roughcontact.contact import cell as cell_module
from roughcontact.contact.nondim import CellOptions
from roughcontact.elasticity.halfspace import halfspace_influence
from roughcontact.surfaces.spec import SurfaceSpec
from roughcontact.surfaces.synthetic import generate_many

SIZE, GRID, NU = 1.0e-3, 24, 0.3
LENGTH = 2.0e-3
AREA = (SIZE / GRID) ** 2


def counted(pressure, t):
    """Shares above ``t`` counted on full fields (..., n): the independent reference."""
    above = pressure > t
    total = pressure.sum(axis=-1)
    contact = np.count_nonzero(pressure > 0.0, axis=-1)
    return {
        "elements_above": np.count_nonzero(above, axis=-1).astype(float),
        "area_above": np.count_nonzero(above, axis=-1) / np.maximum(contact, 1),
        "load_above": np.where(above, pressure, 0.0).sum(axis=-1) / total,
        "excess_load": np.maximum(pressure - t, 0.0).sum(axis=-1) / total,
    }


@pytest.fixture(scope="module")
def heights():
    spec = SurfaceSpec(grid=GRID, size=SIZE, corr_length=1.5e-4)
    z = generate_many(spec, [3, 4, 5])
    return z / z.std(axis=(1, 2), keepdims=True)


@pytest.fixture(scope="module")
def unit_influence():
    return halfspace_influence((GRID, GRID), (SIZE, SIZE), 1.0, NU)


@pytest.fixture(scope="module")
def fields(heights, unit_influence):
    """A dimensionless sweep with its profiles and its full pressure fields."""
    gaps = nondim.initial_separation(heights)
    approaches = np.geomspace(0.05, 3.0, 8)
    result = sweep(unit_influence / LENGTH, gaps, approaches, element_area=1.0 / gaps.shape[1],
                   options=SolverOptions(method="pivot", tol=1e-10, return_fields=True,
                                         profile=True))
    return result, result.pressure.reshape(*result.pressure.shape[:2], -1)


def test_rank_grid_is_exact_then_geometric_and_ends_at_n():
    ranks = validity.rank_grid(3600)
    assert np.array_equal(ranks[:validity.EXACT_RANKS], np.arange(1, validity.EXACT_RANKS + 1))
    assert ranks[-1] == 3600 and (np.diff(ranks) > 0).all()
    ratios = ranks[validity.EXACT_RANKS + 1:-1] / ranks[validity.EXACT_RANKS:-2]
    assert ratios.max() <= validity.RANK_RATIO + 1.0 / validity.EXACT_RANKS
    assert np.array_equal(validity.rank_grid(50), np.arange(1, 51))
    with pytest.raises(ValueError, match="positive integer"):
        validity.rank_grid(0)


def test_profiles_are_the_sorted_pressures_and_cumulative_load(fields):
    result, pressure = fields
    ordered = -np.sort(-pressure, axis=-1)
    index = result.profile_ranks - 1
    assert np.array_equal(result.pressure_profile, ordered[..., index])
    shares = np.cumsum(ordered, axis=-1)[..., index] / ordered.sum(axis=-1, keepdims=True)
    np.testing.assert_allclose(result.load_profile, shares, rtol=1e-12)
    np.testing.assert_allclose(result.pressure_profile[..., 0], result.max_pressure)


@pytest.mark.parametrize("quantile", [0.5, 0.9, 0.99, 0.999])
def test_shares_above_a_threshold_match_the_full_fields(fields, quantile):
    result, pressure = fields
    positive = pressure[pressure > 0.0]
    t = float(np.quantile(positive, quantile))
    got = validity.fractions_above(result.profile_ranks, result.pressure_profile,
                                   result.load_profile, result.real_area_fraction,
                                   result.nominal_pressure, t)
    want = counted(pressure, t)
    n = pressure.shape[-1]
    # at most EXACT_RANKS elements above t: exact; beyond, within the rank spacing
    exact = want["elements_above"] <= validity.EXACT_RANKS
    np.testing.assert_allclose(got["elements_above"][exact], want["elements_above"][exact],
                               atol=1e-9)
    assert (np.abs(got["elements_above"] - want["elements_above"])
            <= (validity.RANK_RATIO - 1.0) * want["elements_above"] + 1.0).all()
    for name in ("area_above", "load_above", "excess_load"):
        np.testing.assert_allclose(got[name], want[name], atol=0.01 + 1.0 / n)
    np.testing.assert_allclose(got["excess_load"][exact], want["excess_load"][exact],
                               atol=1e-9)


def test_nothing_above_the_peak_and_everything_below_the_smallest(fields):
    result, pressure = fields
    above_all = validity.fractions_above(result.profile_ranks, result.pressure_profile,
                                         result.load_profile, result.real_area_fraction,
                                         result.nominal_pressure, 2 * pressure.max())
    for values in above_all.values():
        assert (values == 0.0).all()
    with pytest.raises(ValueError, match="positive"):
        validity.fractions_above(result.profile_ranks, result.pressure_profile,
                                 result.load_profile, result.real_area_fraction,
                                 result.nominal_pressure, 0.0)


def test_where_nothing_exceeds_H_the_capped_solve_is_the_elastic_one(heights, unit_influence):
    """The check is free because it is enough: below H the cap changes nothing."""
    approaches = np.geomspace(0.05, 1.0, 5)
    elastic = nondim.solve_cell(unit_influence, heights, thickness=LENGTH, element_area=AREA,
                                approaches=approaches,
                                options=CellOptions().with_(method="pivot", tol=1e-10,
                                                            profile=True))
    H = 1.01 * elastic.max_pressure.max()
    shares = validity.fractions_above(elastic.profile_ranks, elastic.pressure_profile,
                                      elastic.load_profile, elastic.real_area_fraction,
                                      elastic.nominal_pressure, H)
    assert (shares["area_above"] == 0.0).all()
    capped = nondim.solve_cell(unit_influence, heights, thickness=LENGTH, element_area=AREA,
                               approaches=approaches,
                               options=CellOptions().with_(method="pivot", tol=1e-10,
                                                           nondim_hardness=H))
    assert (capped.plastic_area_fraction == 0.0).all()
    np.testing.assert_allclose(capped.nominal_pressure, elastic.nominal_pressure, rtol=1e-9)
    np.testing.assert_allclose(capped.normalized_stiffness, elastic.normalized_stiffness,
                               rtol=1e-9)


def test_the_capped_plastic_area_follows_the_elastic_share_above_H(heights, unit_influence):
    """Above H, the elastic share is the first estimate of the saturated area."""
    approaches = np.geomspace(0.05, 1.0, 5)
    elastic = nondim.solve_cell(unit_influence, heights, thickness=LENGTH, element_area=AREA,
                                approaches=approaches,
                                options=CellOptions().with_(method="pivot", tol=1e-10,
                                                            profile=True))
    H = 0.5 * elastic.max_pressure[:, -1].min()
    capped = nondim.solve_cell(unit_influence, heights, thickness=LENGTH, element_area=AREA,
                               approaches=approaches,
                               options=CellOptions().with_(method="pivot", tol=1e-10,
                                                           nondim_hardness=H))
    shares = validity.fractions_above(elastic.profile_ranks, elastic.pressure_profile,
                                      elastic.load_profile, elastic.real_area_fraction,
                                      elastic.nominal_pressure, H)
    above = shares["elements_above"][:, -1]
    plastic = capped.plastic_area_fraction[:, -1] * capped.n_elements
    assert (above > 0).all() and (plastic > 0).all()
    # the excess load moves to neighbours, which saturate too: at least as many
    assert (plastic >= above - 1).all()
    assert capped.max_pressure.max() <= H * (1 + 1e-12)


def test_validity_table_reads_physical_hardness(heights, unit_influence):
    geometry = type("Body", (), {"thickness": LENGTH, "element_area": AREA,
                                 "size": (SIZE, SIZE), "grid": (GRID, GRID)})()
    nd = cell_module.sweep_cell(unit_influence, heights, geometry, 0.3, 8,
                                options=cell_module.SWEEP_OPTIONS.with_(method="pivot"))
    sigma, E = 20e-6, 200e6
    scale = E * sigma / LENGTH
    levels = np.array([nd.nominal_pressure[:, -1].min() * scale])
    # H well below every surface's peak pressure near that level
    H = 0.2 * nd.max_pressure[:, -2].min() * scale
    table = cell_module.validity_table(nd, sigma, E, H, levels)
    assert table["hardness"].iloc[0] == H
    assert 0.0 < table["area_above_mean"].iloc[0] <= 1.0
    assert table["area_above_count"].iloc[0] == heights.shape[0]
    # the same H on a twice stiffer body is half the dimensionless threshold: more above it
    softer = cell_module.validity_table(nd, sigma, 2 * E, H, levels * 2)
    assert softer["load_above_mean"].iloc[0] >= table["load_above_mean"].iloc[0]
    elastic_only = nondim.solve_cell(unit_influence, heights[:1], thickness=LENGTH,
                                     element_area=AREA, approaches=[0.1, 0.2])
    with pytest.raises(ValueError, match="no pressure profiles"):
        cell_module.validity_table(elastic_only, sigma, E, H, levels)


def test_a_capped_sweep_refuses_a_rescaling_that_changes_its_cap(heights, unit_influence):
    sigma, E, H = 20e-6, 200e6, 30e6
    cap = cell_module.nondim_pressure(H, thickness=LENGTH, E=E, sigma=sigma)
    nd = nondim.solve_cell(unit_influence, heights[:1], thickness=LENGTH, element_area=AREA,
                           approaches=[0.2, 0.5],
                           options=CellOptions().with_(nondim_hardness=cap, method="pivot"))
    physical = nondim.to_physical(nd, sigma, E, hardness=H)
    assert physical.hardness == H and physical.max_pressure.max() <= H * (1 + 1e-9)
    # doubling sigma and E quadruples E sigma: the same H is a quarter of the cap, refused
    with pytest.raises(ValueError, match="solve it anew"):
        nondim.to_physical(nd, 2 * sigma, 2 * E, hardness=H)
    # sigma halved and E doubled keep E sigma, hence the cap: allowed
    assert nondim.to_physical(nd, sigma / 2, 2 * E, hardness=H).hardness == H
    with pytest.raises(ValueError, match="give the hardness"):
        nondim.to_physical(nd, sigma, E)
    elastic = nondim.solve_cell(unit_influence, heights[:1], thickness=LENGTH,
                                element_area=AREA, approaches=[0.2, 0.5])
    with pytest.raises(ValueError, match="the sweep is elastic"):
        nondim.to_physical(elastic, sigma, E, hardness=H)


def test_plastic_load_is_the_saturated_elements_times_H_over_the_load(heights, unit_influence):
    sigma, E, H = 20e-6, 200e6, 30e6
    cap = cell_module.nondim_pressure(H, thickness=LENGTH, E=E, sigma=sigma)
    gaps = nondim.initial_separation(heights)
    nd = nondim.solve_cell(unit_influence, heights, thickness=LENGTH, element_area=AREA,
                           approaches=[0.3, 1.0],
                           options=CellOptions().with_(nondim_hardness=cap, method="pivot"))
    physical = nondim.to_physical(nd, sigma, E, hardness=H)
    # counted on the fields of the same capped problem, solved in SI units
    result = sweep(unit_influence / E, gaps * sigma, np.array([0.3, 1.0]) * sigma,
                   element_area=AREA, hardness=H,
                   options=SolverOptions(method="pivot", return_fields=True, tol=1e-10))
    p = result.pressure.reshape(*result.pressure.shape[:2], -1)
    saturated = np.where(p >= H * (1 - 1e-12), p, 0.0).sum(axis=-1) / p.sum(axis=-1)
    np.testing.assert_allclose(physical.plastic_load_fraction, saturated, rtol=1e-9, atol=1e-12)
    assert (physical.plastic_load_fraction > 0).any()
    elastic = nondim.to_physical(nondim.solve_cell(unit_influence, heights, thickness=LENGTH,
                                                   element_area=AREA, approaches=[0.3]),
                                 sigma, E)
    assert (elastic.plastic_load_fraction == 0).all()
