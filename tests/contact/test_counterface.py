"""Two rough, elastic bodies reduced to one (Eq 17-18): checked against closed forms.

A rigid smooth counter body changes nothing (bit for bit); two half-spaces sum to
one with the composite modulus (Love's coefficients scale with (1 - nu^2)/E); two
spheres on two half-spaces give Hertz with the composite modulus and radius;
swapping the bodies changes nothing but the per-body displacements; the sum of a
matrix-free and a dense operator solves as the dense sum does.
"""

import math

import numpy as np
import pytest

from roughcontact.contact import SolverOptions, counterface, solve
from roughcontact.contact.interface import InterfaceGrid, describe
from roughcontact.contact.nondim import CellOptions
from roughcontact.elasticity.halfspace import halfspace_influence
from roughcontact.elasticity.protocol import DenseInfluence, MatrixFreeInfluence

SIZE = 1.0e-3


def love(n, E, nu):
    return DenseInfluence(halfspace_influence((n, n), (SIZE, SIZE), E, nu), (SIZE / n) ** 2,
                          (n, n))


def sphere(n, radius):
    x = (np.arange(n) + 0.5) * SIZE / n - SIZE / 2
    X, Y = np.meshgrid(x, x)
    return -(X**2 + Y**2) / (2 * radius)  # heights: a cap protruding towards the other body


def test_a_rigid_smooth_counter_body_changes_nothing():
    op = love(16, 200e9, 0.3)
    heights = sphere(16, 5e-3)
    assert counterface.equivalent_operator(op, None) is op
    assert counterface.equivalent_heights(heights, None) is heights


def test_two_half_spaces_sum_to_the_composite_modulus():
    n = 20
    E1, nu1, E2, nu2 = 210e9, 0.3, 70e9, 0.33
    pair = counterface.equivalent_operator(love(n, E1, nu1), love(n, E2, nu2))
    e_star = 1.0 / ((1 - nu1**2) / E1 + (1 - nu2**2) / E2)
    one = love(n, e_star, 0.0)  # Love's coefficients depend on E / (1 - nu^2) only
    np.testing.assert_allclose(pair.matrix, one.matrix, rtol=1e-12)
    twin = counterface.equivalent_operator(love(n, E1, nu1), love(n, E1, nu1))
    np.testing.assert_allclose(twin.matrix, love(n, E1 / 2, nu1).matrix, rtol=1e-12)


def test_two_spheres_on_two_half_spaces_give_hertz():
    n, R1, R2 = 48, 4e-3, 12e-3
    E1, nu1, E2, nu2 = 210e9, 0.3, 110e9, 0.34
    e_star = 1.0 / ((1 - nu1**2) / E1 + (1 - nu2**2) / E2)
    radius = 1.0 / (1 / R1 + 1 / R2)
    a = 0.15e-3  # contact radius: 14 elements across
    load = 4 * e_star * a**3 / (3 * radius)
    operator = counterface.equivalent_operator(love(n, E1, nu1), love(n, E2, nu2))
    heights = counterface.equivalent_heights(sphere(n, R1), sphere(n, R2))
    result = solve(operator, heights.max() - heights, mean_pressure=load / SIZE**2,
                   options=SolverOptions(tol=1e-10))
    assert result.converged
    summary = describe(result.pressure, result.gap, InterfaceGrid((SIZE / n, SIZE / n)))
    assert summary.spot_count == 1
    # measured: element count +0.7 %, corrected -3.4 % (one centre position; a flip of
    # an edge element is 0.6 %)
    for fraction in (result.real_area_fraction, summary.corrected_real_area_fraction):
        assert fraction * SIZE**2 == pytest.approx(math.pi * a**2, rel=0.05)
    # Hertz's peak pressure 3F / (2 pi a^2), on elements of 1/14 of the diameter
    assert result.max_pressure == pytest.approx(3 * load / (2 * math.pi * a**2), rel=0.05)
    # each body deflects by its share of the compliance at the centre
    u1, u2 = counterface.body_displacements(love(n, E1, nu1), love(n, E2, nu2),
                                            result.pressure)
    share = ((1 - nu1**2) / E1) / ((1 - nu1**2) / E1 + (1 - nu2**2) / E2)
    np.testing.assert_allclose(u1, share * (u1 + u2), rtol=1e-10)


def test_swapping_the_bodies_changes_nothing_but_their_displacements():
    n = 24
    rng = np.random.default_rng(5)
    h1, h2 = 1e-6 * rng.standard_normal((2, n, n))
    b1, b2 = love(n, 210e9, 0.3), love(n, 3e9, 0.45)
    one = solve(counterface.equivalent_operator(b1, b2),
                -counterface.equivalent_heights(h1, h2) + (h1 + h2).max(), approach=1e-6)
    two = solve(counterface.equivalent_operator(b2, b1),
                -counterface.equivalent_heights(h2, h1) + (h2 + h1).max(), approach=1e-6)
    np.testing.assert_array_equal(one.pressure, two.pressure)
    u1, u2 = counterface.body_displacements(b1, b2, one.pressure)
    v2, v1 = counterface.body_displacements(b2, b1, two.pressure)
    np.testing.assert_array_equal(u1, v1)
    assert np.abs(u2).mean() > 10 * np.abs(u1).mean()  # the polymer deflects, not the steel


def test_a_matrix_free_body_sums_without_a_dense_matrix():
    n = 20
    dense1, dense2 = love(n, 210e9, 0.3), love(n, 70e9, 0.33)
    free = MatrixFreeInfluence(dense2, dense2.element_area, dense2.diagonal())
    pair = counterface.equivalent_operator(dense1, free)
    assert isinstance(pair, counterface.SumInfluence) and pair.matrix is None
    p = np.random.default_rng(2).random(n * n)
    np.testing.assert_allclose(pair.matvec(p), dense1.matrix @ p + dense2.matrix @ p,
                               rtol=1e-12)
    gap0 = -sphere(n, 5e-3)
    gap0 -= gap0.min()
    reference = solve(counterface.equivalent_operator(dense1, dense2), gap0, approach=2e-6,
                      options=SolverOptions(tol=1e-10))
    result = solve(pair, gap0, approach=2e-6, options=SolverOptions(method="cg", tol=1e-10))
    np.testing.assert_allclose(result.pressure, reference.pressure,
                               atol=1e-6 * reference.pressure.max())


def test_bodies_on_other_grids_are_refused_with_both_named():
    with pytest.raises(ValueError, match=r"\(400, 400\) and \(576, 576\)"):
        counterface.equivalent_operator(love(20, 1e9, 0.3), love(24, 1e9, 0.3))
    big = DenseInfluence(love(20, 1e9, 0.3).matrix, 4 * (SIZE / 20) ** 2, (20, 20))
    with pytest.raises(ValueError, match="differ in area"):
        counterface.equivalent_operator(love(20, 1e9, 0.3), big)
    with pytest.raises(ValueError, match=r"grid \(24, 24\) does not match"):
        counterface.equivalent_heights(np.zeros((20, 20)), np.zeros((24, 24)))


def test_two_finite_blocks_with_nu0_give_eq44_with_the_combined_modulus():
    """Two finite blocks (nu = 0, clamped): a uniform pressure P deflects the pair's
    mean plane by P (L1/E1 + L2/E2) (Eq 38 and 44 of each block, added), and under a
    rough contact each block's mean-plane deflection is its share L_i/E_i of it."""
    from roughcontact.elasticity.influence import BlockGeometry, unit_modulus_influence

    size, n = 3e-3, 12
    (L1, E1), (L2, E2) = (10e-3, 200e9), (4e-3, 5e9)
    area = (size / n) ** 2
    blocks = [DenseInfluence(unit_modulus_influence(
        BlockGeometry(size=(size, size), grid=(n, n), thickness=L, mesh="refined", nu=0.0))
        / E, area, (n, n)) for L, E in ((L1, E1), (L2, E2))]
    pair = counterface.equivalent_operator(*blocks)
    combined = L1 / E1 + L2 / E2
    # the finite-element rows sum to L / E within the mesh's 0.5 % (Eq 38)
    np.testing.assert_allclose(pair.matrix.sum(axis=1), combined, rtol=5e-3)
    rng = np.random.default_rng(8)
    heights = 2e-6 * rng.standard_normal((n, n))
    result = solve(pair, heights.max() - heights, mean_pressure=1e6,
                   options=SolverOptions(tol=1e-10))
    u1, u2 = counterface.body_displacements(*blocks, result.pressure)
    assert u1.mean() + u2.mean() == pytest.approx(1e6 * combined, rel=5e-3)  # Eq 44
    assert u1.mean() / u2.mean() == pytest.approx((L1 / E1) / (L2 / E2), rel=1e-2)


def _matrix_free(op):
    return MatrixFreeInfluence(op, op.element_area, op.diagonal(), op.grid)


@pytest.mark.parametrize("kind", ["dense", "matrix-free"])
def test_the_deflection_weights_give_the_mean_displacement(kind):
    op = love(12, 70e9, 0.33)
    body = op if kind == "dense" else _matrix_free(op)
    pressure = np.random.default_rng(3).uniform(0.0, 1e6, size=(5, op.shape[0]))
    weights = counterface.deflection_weights(body)
    np.testing.assert_allclose(pressure @ weights, (pressure @ op.matrix.T).mean(axis=1),
                               rtol=1e-12)


@pytest.mark.parametrize("kind", ["dense", "matrix-free"])
def test_a_scaled_body_is_the_body_times_its_factor(kind):
    op = love(10, 70e9, 0.33)
    body = op if kind == "dense" else _matrix_free(op)
    half = counterface.scaled(body, 0.5)
    p = np.random.default_rng(4).uniform(0.0, 1e6, op.shape[0])
    np.testing.assert_allclose(half.matvec(p), 0.5 * op.matrix @ p, rtol=1e-12)
    np.testing.assert_allclose(half.diagonal(), 0.5 * op.matrix.diagonal(), rtol=1e-12)
    with pytest.raises(ValueError, match="factor"):
        counterface.scaled(body, 0.0)


def test_the_compliance_share_of_two_half_spaces_is_that_of_their_moduli():
    # Love's coefficients scale with (1 - nu^2) / E: the share is exact whatever the
    # pressure, on the mean plane and on the diagonal alike
    E1, E2, nu = 100e9, 300e9, 0.3
    share = counterface.compliance_share(love(12, E1, nu), love(12, E2, nu))
    assert share == pytest.approx((1 / E2) / (1 / E1 + 1 / E2), rel=1e-12)
    twin = counterface.compliance_share(love(12, E1, nu), love(12, E1, nu))
    assert twin == pytest.approx(0.5, rel=1e-12)


def test_a_sweep_records_the_counter_body_deflection():
    """The sweep's counter_deflection equals mean(C2 p) recomputed from its pressure
    fields, and the first body's is what remains of the mean-plane deflection."""
    from roughcontact.contact import sweep

    n = 16
    first, second = love(n, 5e9, 0.3), love(n, 20e9, 0.25)
    pair = counterface.equivalent_operator(first, second)
    rng = np.random.default_rng(5)
    gaps = 1e-6 * rng.standard_normal((3, n, n))
    gaps -= gaps.min(axis=(1, 2), keepdims=True)
    grid = InterfaceGrid((SIZE / n, SIZE / n),
                         counter_weights=counterface.deflection_weights(second))
    result = sweep(pair, gaps, np.linspace(0.3e-6, 2e-6, 4), interface=grid,
                   options=SolverOptions(method="cg", tol=1e-10, return_fields=True))
    fields = result.pressure.reshape(3, 4, n * n)
    u2 = (fields @ second.matrix.T).mean(axis=-1)
    u1 = (fields @ first.matrix.T).mean(axis=-1)
    np.testing.assert_allclose(result.counter_deflection, u2, rtol=1e-10)
    np.testing.assert_allclose(result.mean_plane_deflection - result.counter_deflection, u1,
                               rtol=1e-9)
    # the stiffer counter body deflects less: its share is between 0 and a half
    share = result.counter_deflection / result.mean_plane_deflection
    assert ((share > 0.0) & (share < 0.5)).all()


def test_a_densified_body_is_its_matrix():
    op = love(12, 70e9, 0.33)
    dense = counterface.densified(_matrix_free(op))
    np.testing.assert_allclose(dense.matrix, op.matrix, rtol=1e-14, atol=0)
    assert dense.grid == op.grid and dense.element_area == op.element_area
    assert counterface.densified(op) is op


def test_a_matrix_free_pair_sweeps_by_cg_with_each_bodys_share():
    """Two matrix-free half-space operators (E2 = 2 E1) sum without a dense matrix; the
    non-dimensional sweep records the counter body's share, 1/3 at every step."""
    from roughcontact.contact import nondim
    from roughcontact.elasticity import operators

    n, size, thickness = 16, (2.4e-3, 2.4e-3), 10e-3
    first = operators.halfspace_operator((n, n), size, 0.3)
    second = counterface.scaled(operators.halfspace_operator((n, n), size, 0.3), 0.5)
    pair = counterface.equivalent_operator(first, second)
    assert isinstance(pair, counterface.SumInfluence)
    grid = InterfaceGrid((size[0] / n, size[1] / n),
                         counter_weights=counterface.deflection_weights(second) / thickness)
    heights = np.random.default_rng(1).standard_normal((2, n, n))
    result = nondim.solve_cell(pair, heights, thickness=thickness, element_area=(size[0] / n) ** 2,
                               approaches=np.geomspace(0.05, 3.0, 6),
                               options=CellOptions().with_(method="auto", interface=grid))
    assert result.method == "cg" and result.converged.all()
    np.testing.assert_allclose(result.counter_deflection / result.mean_plane_deflection,
                               1 / 3, rtol=1e-6)
