"""Thermal and electrical contact conductance (roughcontact.transport.conduction).

Each test has a referee that shares no code with what it checks: Holm's
isothermal circular spot and Greenwood's cluster of spots (written here),
Barber's identity against the elastic half-space and the contact stage's
tangent stiffness, the exact bulk resistance ``L / (k A)`` of full contact, the
Fourier series of a uniform-flux source on a flux channel (Muzychka, Culham &
Yovanovich 2003, written here from the separation of variables), and the
flux-tube factor of Cooper, Mikic & Yovanovich (1969) for the periodic
half-space. Measured values quoted in comments come from the development
machine (docs/performance/conductance.md).
"""

import doctest

import numpy as np
import pytest

from roughcontact.contact.stiffness import tangent_stiffness
from roughcontact.elasticity.halfspace import halfspace_influence
from roughcontact.elasticity.influence import BlockGeometry
from roughcontact.transport import conduction
from roughcontact.transport.conduction import (
    SpotConductance,
    block_thermal_influence,
    free_thermal_halfspace,
    full_contact_resistance,
    halfspace_thermal_influence,
    in_series,
    periodic_thermal_halfspace,
    spot_conductance,
    unit_conductivity_influence,
)


def _circular_spot(radius_elements: int):
    """A grid just wider than a circle of ``radius_elements`` elements of unit-radius
    spot: (grid, size, element area, mask, dx)."""
    dx = 1.0 / radius_elements
    n = 2 * radius_elements + 2
    y, x = (np.mgrid[:n, :n] - (n - 1) / 2) * dx
    return (n, n), (n * dx, n * dx), dx * dx, np.hypot(x, y) < 1.0, dx


def holm_resistance(conductivity: float, radius: float) -> float:
    """Holm (1967): an isothermal circular spot of radius a on a half-space, 1 / (4 k a) [K/W]."""
    return 1.0 / (4.0 * conductivity * radius)


def test_holm_isothermal_spot_at_32_elements_per_radius():
    """C = 4 k a to 0.5 % at a = 32 dx (measured -0.19 %); the electrical resistance of two
    bodies in series is (rho1 + rho2) / (4 a) alike."""
    grid, size, area, mask, _ = _circular_spot(32)
    k = 45.0
    spot = spot_conductance(free_thermal_halfspace(grid, size, k), mask, element_area=area,
                            tol=1e-10)
    assert spot.converged
    assert spot.resistance == pytest.approx(holm_resistance(k, 1.0), rel=5e-3)
    rho1, rho2 = 1.7e-8, 2.8e-8  # copper, aluminium [Ohm m]
    pair = in_series(free_thermal_halfspace(grid, size, 1.0 / rho1),
                     free_thermal_halfspace(grid, size, 1.0 / rho2))
    electric = spot_conductance(pair, mask, element_area=area, quantity="electrical")
    assert electric.units["resistance"] == "Ohm"
    assert electric.resistance == pytest.approx((rho1 + rho2) / 4.0, rel=5e-3)


def test_holm_converges_at_first_order_in_dx_over_a():
    """From 4 to 32 elements per radius: against the radius of the staircase's own area,
    a_eq = sqrt(A / pi), the error C / (4 k a_eq) - 1 is negative and halves with dx
    (observed order within 0.85-1.2; measured -3.2, -1.5, -0.75, -0.36 %, about
    -0.12 dx / a); against the nominal radius it stays within 0.08 dx / a (measured
    1.5, 0.15, 0.28, 0.19 %: the staircase's area oscillates)."""
    errors = []
    for elements in (4, 8, 16, 32):
        grid, size, area, mask, dx = _circular_spot(elements)
        operator = halfspace_thermal_influence(grid, size, 1.0) if elements < 32 \
            else free_thermal_halfspace(grid, size, 1.0)
        spot = spot_conductance(operator, mask, element_area=area, tol=1e-12)
        assert abs(spot.conductance / 4.0 - 1.0) <= 0.08 * dx
        equal_area_radius = np.sqrt(mask.sum() * area / np.pi)
        errors.append(spot.conductance / (4.0 * equal_area_radius) - 1.0)
    errors = np.array(errors)
    assert np.all(errors < 0)
    orders = np.log2(errors[:-1] / errors[1:])
    assert np.all((orders > 0.85) & (orders < 1.2)), orders


def greenwood_resistance(conductivity, centres, radii) -> float:
    """Greenwood (1966): a cluster of isothermal spots on one half-space [K/W],
    1 / (4 k sum a_i) + sum_{i != j} a_i a_j / s_ij / (2 pi k (sum a_i)^2), the double sum
    over ordered pairs (each spot's flux taken as if alone, its neighbours as points)."""
    a = np.asarray(radii, dtype=float)
    c = np.asarray(centres, dtype=float)
    distance = np.hypot(*(c[:, None, :] - c[None, :, :]).transpose(2, 0, 1))
    np.fill_diagonal(distance, np.inf)
    interaction = (np.outer(a, a) / distance).sum() / (2 * np.pi * conductivity * a.sum()**2)
    return 1.0 / (4.0 * conductivity * a.sum()) + interaction


def test_greenwood_cluster_of_spots():
    """Four isothermal circular spots (radii 0.8-1.5, 8 elements per unit length, 4.7 to
    11.5 apart) on a half-space: the resistance within 3 % of Greenwood's formula
    (measured +1.3 %, +0.37 % at 16 elements per unit length; the pair of equal spots 3
    radii apart +0.3 %)."""
    centres, radii, per_unit, k = [(3, 3), (8, 4), (5, 9), (12, 11)], [1.0, 1.5, 0.8, 1.2], 8, 3.0
    n, dx = 15 * per_unit, 1.0 / per_unit
    y, x = (np.mgrid[:n, :n] + 0.5) * dx
    spots = np.zeros((n, n), dtype=bool)
    for (cx, cy), radius in zip(centres, radii, strict=True):
        spots |= np.hypot(x - cx, y - cy) < radius
    spot = spot_conductance(free_thermal_halfspace((n, n), (n * dx, n * dx), k), spots,
                            element_area=dx * dx, tol=1e-10)
    assert spot.resistance == pytest.approx(greenwood_resistance(k, centres, radii), rel=3e-2)


def _clustered_contact(n: int, seed: int, fraction: float) -> np.ndarray:
    """A contact set of clusters: a smoothed random field above its quantile."""
    rng = np.random.default_rng(seed)
    field = rng.standard_normal((n, n))
    q = np.fft.fftfreq(n)
    smoothing = np.exp(-60.0 * (q[:, None] ** 2 + q[None, :] ** 2))
    field = np.fft.ifft2(np.fft.fft2(field) * smoothing).real
    return field > np.quantile(field, 1.0 - fraction)


@pytest.mark.parametrize("seed, fraction", [(1, 0.05), (2, 0.2), (3, 0.6)])
def test_barber_spot_conductance_is_twice_the_stiffness_over_e_star(seed, fraction):
    """Barber (2003): on half-spaces C = 2 K / (E* (rho1 + rho2)), K the tangent stiffness
    of the same contact set (the elastic influence and the contact stage's CG), to the
    solvers' tolerance (1e-11 each; the identity holds to 1e-9)."""
    n, size = 24, (2e-3, 2e-3)
    contact = _clustered_contact(n, seed, fraction)
    E1, nu1, E2, nu2 = 210e9, 0.3, 70e9, 0.33
    e_star = 1.0 / ((1 - nu1**2) / E1 + (1 - nu2**2) / E2)
    area = size[0] * size[1] / n**2
    elastic = halfspace_influence((n, n), size, E1, nu1) + halfspace_influence((n, n), size,
                                                                                E2, nu2)
    stiffness = tangent_stiffness(elastic, contact.astype(float).ravel(), element_area=area,
                                  tol=1e-11)
    k1, k2 = 45.0, 200.0
    thermal = in_series(halfspace_thermal_influence((n, n), size, k1),
                        halfspace_thermal_influence((n, n), size, k2), element_area=area)
    spot = spot_conductance(thermal, contact, tol=1e-11)
    barber = 2.0 * stiffness / (e_star * (1.0 / k1 + 1.0 / k2))
    assert spot.conductance == pytest.approx(barber, rel=1e-9)
    assert spot.bulk_share == 0.0


@pytest.mark.parametrize("mesh", ["paper", "refined"])
def test_block_full_contact_gives_k_a_over_t(mesh):
    """Full contact of a block with an isothermal base: C = k A / L exactly (to the CG's
    tolerance), and two blocks in series 1 / (L1 / (k1 A) + L2 / (k2 A))."""
    grid, size = (8, 6), (1.2e-3, 0.9e-3)
    first = BlockGeometry(size=size, thickness=0.6e-3, grid=grid, mesh=mesh)
    second = BlockGeometry(size=size, thickness=1.0e-3, grid=grid, mesh=mesh)
    k1, k2 = 15.0, 120.0
    r1 = block_thermal_influence(first, k1)
    area = first.element_area
    nominal = size[0] * size[1]
    full = np.ones(grid[0] * grid[1], dtype=bool)
    spot = spot_conductance(r1, full, element_area=area, tol=1e-13)
    assert spot.conductance == pytest.approx(k1 * nominal / first.thickness, rel=1e-10)
    pair = in_series(r1, block_thermal_influence(second, k2), element_area=area)
    series = 1.0 / (first.thickness / (k1 * nominal) + second.thickness / (k2 * nominal))
    assert full_contact_resistance(pair) == pytest.approx(1.0 / series, rel=1e-10)


def test_block_influence_is_symmetric_positive_definite_with_rows_summing_to_l():
    """k R of the refined (coarsened, hanging-node) mesh: symmetric, positive definite,
    every row summing to the thickness (the uniform flux's linear field)."""
    geom = BlockGeometry(size=(1.2e-3, 1.2e-3), thickness=0.9e-3, grid=(8, 8), mesh="refined")
    unit = unit_conductivity_influence(geom)
    np.testing.assert_allclose(unit, unit.T, rtol=0, atol=1e-14 * unit.max())
    np.testing.assert_allclose(unit.sum(axis=1), geom.thickness, rtol=1e-12)
    assert np.linalg.eigvalsh(unit).min() > 0.0


def muzychka_source_resistance(channel, source, thickness, conductivity, terms=600):
    """Mean-temperature resistance [K/W] of a centred uniform-flux source c x d on a flux
    channel a x b of thickness t, insulated sides, isothermal base (Muzychka, Culham &
    Yovanovich 2003, Eq 27-32 with h -> infinity: phi(zeta) = tanh(zeta t)).

    Written from the separation of variables: the flux q on the source has the cosine
    coefficients Q_mn = q eps_m eps_n / (a b) S_m(c, a) S_n(d, b), S_m = int_source
    cos(lambda_m x) dx = 2 cos(lambda_m a / 2) sin(lambda_m c / 2) / lambda_m (c for
    m = 0), eps_0 = 1, eps_m = 2; each mode rises at the top by Q_mn tanh(beta t) /
    (k beta) (t / k for beta = 0), beta = sqrt(lambda_m^2 + delta_n^2).
    """
    a, b = channel
    c, d = source
    m = np.arange(terms)
    lam, dlt = m * np.pi / a, m * np.pi / b

    def overlap(wave, width, side):
        safe = np.where(wave > 0, wave, 1.0)
        return np.where(wave > 0, 2 * np.cos(wave * side / 2) * np.sin(wave * width / 2) / safe,
                        width)

    sx, sy = overlap(lam, c, a), overlap(dlt, d, b)
    eps = np.where(m > 0, 2.0, 1.0)
    beta = np.hypot(lam[None, :], dlt[:, None])
    rise = np.where(beta > 0, np.tanh(beta * thickness) / np.where(beta > 0, beta, 1.0),
                    thickness) / conductivity
    coefficient = eps[None, :] * eps[:, None] / (a * b) * sx[None, :] * sy[:, None]  # per q
    mean_temperature = np.sum(coefficient * rise * sx[None, :] * sy[:, None]) / (c * d)
    return mean_temperature / (c * d)  # q = 1: the source carries c d watts


def test_muzychka_series_is_converged_and_has_its_limits():
    """The referee itself: 1-D limit (source = channel: t / (k A)) and its truncation."""
    r = muzychka_source_resistance((2e-3, 1e-3), (2e-3, 1e-3), 0.5e-3, 10.0)
    assert r == pytest.approx(0.5e-3 / (10.0 * 2e-6), rel=1e-12)
    coarse = muzychka_source_resistance((2e-3, 1e-3), (0.5e-3, 0.25e-3), 0.5e-3, 10.0, 300)
    fine = muzychka_source_resistance((2e-3, 1e-3), (0.5e-3, 0.25e-3), 0.5e-3, 10.0, 1200)
    assert coarse == pytest.approx(fine, rel=2e-4)


def test_uniform_flux_source_on_a_flux_channel_matches_muzychka():
    """A uniform flux on a centred 8 x 4 source of a 16 x 8 block (2 x 1 mm, 0.5 mm thick),
    converged mesh: the source's mean temperature per watt against the series to 0.5 %
    (measured -0.12 %; the paper's 5 layers -2.8 %)."""
    grid, size, thickness, k = (16, 8), (2e-3, 1e-3), 0.5e-3, 20.0
    geom = BlockGeometry(size=size, thickness=thickness, grid=grid, mesh="converged")
    resistance = block_thermal_influence(geom, k)
    iy, ix = np.divmod(np.arange(grid[0] * grid[1]), grid[0])
    source = (ix >= 4) & (ix < 12) & (iy >= 2) & (iy < 6)
    heat = source.sum() * geom.element_area  # q = 1 W/m^2
    mean_temperature = resistance[np.ix_(source, source)].sum() / source.sum()
    expected = muzychka_source_resistance(size, (1e-3, 0.5e-3), thickness, k, terms=1200)
    assert mean_temperature / heat == pytest.approx(expected, rel=5e-3)


def test_isothermal_spot_on_the_block_converges_with_the_grid():
    """A centred square isothermal spot (1/4 of the side) on a block half as thick as
    wide, refined mesh, 8, 16 and 32 elements per side: the conductance converges
    monotonically with an observed order between 0.5 and 1.5 (measured 0.84; the
    spot's edge singularity, flux ~ distance^-1/2, makes it about first order), and the
    bulk share stays below 1/2 (measured 0.30-0.31)."""
    values = []
    for n in (8, 16, 32):
        geom = BlockGeometry(size=(1e-3, 1e-3), thickness=0.5e-3, grid=(n, n), mesh="refined")
        resistance = block_thermal_influence(geom, 1.0)
        iy, ix = np.divmod(np.arange(n * n), n)
        spot_set = (ix >= 3 * n // 8) & (ix < 5 * n // 8) & (iy >= 3 * n // 8) & (iy < 5 * n // 8)
        bulk = full_contact_resistance(resistance, element_area=geom.element_area)
        assert bulk == pytest.approx(0.5e-3 / 1e-6, rel=1e-10)
        spot = spot_conductance(resistance, spot_set, bulk_resistance=bulk,
                                element_area=geom.element_area, tol=1e-12)
        assert 0.0 < spot.bulk_share < 0.5
        values.append(spot.conductance)
    first, second = values[1] - values[0], values[2] - values[1]
    assert first > 0 and second > 0
    assert 0.5 < np.log2(first / second) < 1.5


@pytest.mark.parametrize("cells", [36, 72])
def test_periodic_spot_is_a_flux_tube(cells):
    """A spot of radius a = 8 dx in a periodic cell of side L (the mean temperature the
    reference): its constriction resistance is that of an isothermal spot in a flux tube
    of the same area, psi / (4 k a) with psi = (1 - eps)^1.5, eps = a / b, b = L /
    sqrt(pi) (Cooper, Mikic & Yovanovich 1969), against the lone spot on the dense
    half-space: the ratio of the two conductances within 3 % of psi (measured 1.1 % and
    1.6 % for L = 4.5 a and 9 a)."""
    grid, size, area, mask, dx = _circular_spot(8)
    lone = spot_conductance(halfspace_thermal_influence(grid, size, 2.0), mask,
                            element_area=area)
    periodic = periodic_thermal_halfspace((cells, cells), (cells * dx, cells * dx), 2.0)
    wide = np.zeros((cells, cells), dtype=bool)
    wide[:mask.shape[0], :mask.shape[1]] = mask
    eps = np.sqrt(mask.sum() * area / np.pi) / (cells * dx / np.sqrt(np.pi))
    ratio = lone.conductance / spot_conductance(periodic, wide).conductance
    assert ratio == pytest.approx((1.0 - eps) ** 1.5, rel=3e-2)


def test_no_contact_and_bad_input():
    resistance = halfspace_thermal_influence((4, 4), (1e-3, 1e-3), 1.0)
    none = spot_conductance(resistance, np.zeros(16, dtype=bool), element_area=1e-3**2 / 16)
    assert none.conductance == 0.0 and none.resistance == np.inf
    with pytest.raises(ValueError, match="conductivity must be a finite positive"):
        halfspace_thermal_influence((4, 4), (1e-3, 1e-3), -1.0)
    with pytest.raises(ValueError, match="contact must have 16 elements"):
        spot_conductance(resistance, np.ones(15, dtype=bool), element_area=1e-3**2 / 16)
    with pytest.raises(ValueError, match="quantity must be one of"):
        SpotConductance(1.0, 1.0, 0.0, 1, True, 1, quantity="acoustic")


def test_the_package_walk_runs():
    """The docstring of roughcontact.transport.conduction, a doctest."""
    assert doctest.testmod(conduction, raise_on_error=False).failed == 0
