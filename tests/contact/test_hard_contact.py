"""Hard cases of the contact solver (Eq 16-27 of Kumar et al. 2006) on finite-block matrices.

Operators: the finite-element influence matrix of a 12 x 12 block over
1.8 mm, L = 2 mm, with the paper's mesh (5 trilinear layers; rows sum to
L/E exactly for nu = 0; condition number about 5e4) and with the "refined"
preset (condition number about 20). Expected values are closed forms or
dense linear solves on the known contact set.
"""

import logging

import numpy as np
import pytest
from approach_targets import target_grid

from roughcontact import contact
from roughcontact.contact import SolverOptions, cell, nondim
from roughcontact.contact.nondim import CellOptions
from roughcontact.elasticity.influence import BlockGeometry, influence_matrix

GRID = 12
N = GRID * GRID
SIZE = 1.8e-3  # [m]
LENGTH = 2e-3  # block thickness L [m]
MESHES = ("paper", "refined")


@pytest.fixture(scope="module", params=MESHES)
def block(request):
    """(geometry, C [m/Pa], element area [m^2]) of the 12 x 12 block."""
    geom = BlockGeometry(size=(SIZE, SIZE), thickness=LENGTH, grid=(GRID, GRID),
                         mesh=request.param)
    return geom, influence_matrix(geom), geom.spacing[0] * geom.spacing[1]


def rough_gap(seed, sigma):
    """Initial separation f = max(z) - z [m] of a white-noise surface of rms sigma [m]."""
    z = np.random.default_rng(seed).standard_normal((GRID, GRID)) * sigma
    return z.max() - z


def full_contact_approach(C, gap):
    """Smallest approach [m] at which C p = d - f has p >= 0 everywhere."""
    ones = np.linalg.solve(C, np.ones(N))
    p_f = np.linalg.solve(C, gap.ravel())
    return float(np.max(p_f / ones))


# --- first touch ---------------------------------------------------------------


@pytest.mark.parametrize("d", [1e-15, 1e-12])  # 1e-9 and 1e-6 sigma [m]
@pytest.mark.parametrize("method", contact.METHODS)
def test_first_touch_only_the_highest_elements(block, method, d):
    _, C, area = block
    gap = rough_gap(1, 1e-6)
    top = int(np.argmin(gap))
    result = contact.solve(C, gap, d, element_area=area, options=SolverOptions(method=method))
    assert result.converged
    assert list(np.flatnonzero(result.pressure)) == [top]
    assert 0.0 < result.load == pytest.approx(area * d / C[top, top], rel=1e-12)
    # a tie: two elements at the top (far apart), both touch; pressures from the 2 x 2
    # system. The KKT residual is scaled by max|d - f| (about 5 sigma here, not d), so
    # the pressure is only guaranteed to about tol * max(f) / d: measured errors up to
    # 8 % (steepest) and 4 % (cg) at d = 1e-9 sigma, bound 0.53; exact: 3e-16.
    tied = gap.copy()
    second = int(np.argsort(gap, axis=None)[1])
    tied.flat[second] = 0.0
    result = contact.solve(C, tied, d, element_area=area, options=SolverOptions(method=method))
    pair = [min(top, second), max(top, second)]
    assert result.converged
    assert list(np.flatnonzero(result.pressure)) == pair
    expected = np.linalg.solve(C[np.ix_(pair, pair)], [d, d])
    guaranteed = 2.0 * result.tol * tied.max() / d
    error = np.abs(result.pressure.ravel()[pair] / expected - 1.0).max()
    assert error <= (1e-12 if method == "exact" else guaranteed)
    assert result.load > 0.0


# --- full contact and beyond --------------------------------------------------


@pytest.mark.parametrize("method", contact.METHODS)
def test_full_contact_is_the_linear_solve(block, method):
    geom, C, area = block
    if method == "steepest" and geom.mesh == "paper":
        pytest.skip("steepest descent needs > 20000 iterations at condition number 5e4")
    gap = rough_gap(1, 1e-6)
    d = 2.0 * full_contact_approach(C, gap)
    result = contact.solve(C, gap, d, element_area=area, options=SolverOptions(method=method))
    expected = np.linalg.solve(C, d - gap.ravel())
    assert result.converged and result.real_area_fraction == 1.0
    # measured: exact 1e-12, cg 2e-8 (paper) / 3e-10 (refined), steepest 9e-10
    np.testing.assert_allclose(result.pressure.ravel(), expected, rtol=0,
                               atol=1e-6 * expected.max())
    assert np.abs(result.gap).max() <= 1e-9 * d


def test_beyond_full_contact_load_is_linear_in_approach(block):
    geom, C, area = block
    gap = rough_gap(2, 1e-6)
    approaches = full_contact_approach(C, gap) * np.array([1.5, 2.0, 3.0, 4.0])
    result = contact.sweep(C, gap[None], approaches, element_area=area,
                           options=SolverOptions(return_fields=True, stiffness_tol=1e-12))
    assert result.converged.all() and (result.real_area_fraction == 1.0).all()
    stiffness = area * np.linalg.solve(C, np.ones(N)).sum()  # dA 1^T C^-1 1 [N/m]
    slopes = np.diff(result.load[0]) / np.diff(approaches)
    np.testing.assert_allclose(slopes, stiffness, rtol=1e-7)
    np.testing.assert_allclose(result.contact_stiffness[0], stiffness, rtol=1e-9)
    if geom.mesh == "paper":  # rows sum to L/E (Eq 38): dp/dd = E/L uniformly
        assert stiffness == pytest.approx(geom.E * N * area / LENGTH, rel=1e-10)
        step = (result.pressure[0, 1] - result.pressure[0, 0]) / (approaches[1] - approaches[0])
        np.testing.assert_allclose(step, geom.E / LENGTH, rtol=1e-6)


# --- a single spike on a flat -------------------------------------------------


@pytest.mark.parametrize("method", contact.METHODS)
def test_single_spike_carries_the_load_until_the_flat_joins(block, method):
    # Only the spike k touches while the flat (height H below it) is held off by
    # the spike's own load: u_i = C_ik d / C_kk. Flat element i joins when
    # d - u_i > H, first where C_ik is smallest: d* = H / (1 - min_i C_ik / C_kk).
    _, C, area = block
    height = 1e-6
    gap = np.full((GRID, GRID), height)
    k = 5 * GRID + 6
    gap.flat[k] = 0.0
    ratio = C[k] / C[k, k]
    ratio[k] = np.inf
    first = int(np.argmin(ratio))  # the far corner (row 11, column 0)
    d_star = height / (1.0 - ratio[first])
    assert first == 11 * GRID and d_star > 1.01 * height  # measured 1.035 H / 1.015 H

    before = contact.solve(C, gap, 0.999 * d_star, element_area=area,
                           options=SolverOptions(method=method))
    assert before.converged
    assert list(np.flatnonzero(before.pressure)) == [k]  # although d > H: flat held off
    assert before.load == pytest.approx(area * 0.999 * d_star / C[k, k], rel=1e-10)
    flat_gap = np.delete(before.gap.ravel(), k)
    assert flat_gap.min() > 0.0

    after = contact.solve(C, gap, 1.001 * d_star, element_area=area,
                          options=SolverOptions(method=method))
    assert after.converged
    assert list(np.flatnonzero(after.pressure)) == [k, first]
    assert after.load > area * 1.001 * d_star / C[k, k]  # the flat now carries load too


# --- very high load -----------------------------------------------------------


@pytest.mark.parametrize("sigma_over_length", [0.025, 5e-4])
def test_nominal_pressure_a_tenth_of_E(block, sigma_over_length):
    # P / E = 0.1 (10 % nominal strain): partial contact for sigma = L/40, full
    # contact for sigma = L/2000. Measured P/E at the last step 0.1003-0.1008.
    geom, C, area = block
    unit = C * geom.E
    heights = np.random.default_rng(5).standard_normal((2, GRID, GRID))
    sigma = sigma_over_length * LENGTH
    target = 0.1 * LENGTH / sigma  # Phat = P L / (E sigma)
    grid = target_grid(heights, unit, thickness=LENGTH, target_pressure=target, steps=6)
    nd = nondim.solve_cell(unit, heights, thickness=LENGTH, element_area=area, approaches=grid,
                           options=CellOptions().with_(tol=1e-10))
    assert nd.converged.all() and nd.stiffness_converged.all()
    physical = nondim.to_physical(nd, sigma, 1e9)
    fields = [physical.nominal_pressure, physical.max_pressure, physical.normalized_stiffness,
              physical.mean_plane_deflection, nd.residual]
    assert all(np.isfinite(f).all() for f in fields)
    pressure_ratio = physical.nominal_pressure[:, -1] / 1e9
    assert (pressure_ratio >= 0.1).all() and (pressure_ratio < 0.11).all()
    assert (np.diff(physical.load, axis=1) > 0).all()
    if sigma_over_length > 0.01:
        assert (nd.real_area_fraction[:, -1] < 1.0).all()
    elif geom.mesh == "refined":  # full contact: k_P = E dA 1^T K^-1 1, about E
        assert (nd.real_area_fraction[:, -1] == 1.0).all()
        assert physical.normalized_stiffness[:, -1] == pytest.approx(1e9, rel=0.01)
    else:  # the paper's locally stiff mesh is still in partial contact (measured 69-71 %)
        assert (nd.real_area_fraction[:, -1] > 0.6).all()
    # the SI solve at the last approach agrees and meets its own KKT check
    gap = sigma * nondim.initial_separation(heights)[0]
    result = contact.solve(unit / 1e9, gap, sigma * grid[-1], element_area=area)
    assert result.converged
    assert contact.kkt_residual(unit / 1e9, gap, sigma * grid[-1], result.pressure) <= 1e-10
    assert result.nominal_pressure == pytest.approx(physical.nominal_pressure[0, -1], rel=1e-7)


# --- scale invariance ---------------------------------------------------------


@pytest.mark.parametrize("method", ["cg", "exact"])
def test_sigma_and_E_over_twelve_decades_give_identical_nondimensional_results(method):
    # Measured largest relative difference 4e-12 (max pressure, cg, paper mesh).
    geom = BlockGeometry(size=(SIZE, SIZE), thickness=LENGTH, grid=(GRID, GRID), mesh="paper")
    unit = influence_matrix(geom) * geom.E
    area = geom.spacing[0] * geom.spacing[1]
    heights = np.random.default_rng(5).standard_normal((2, GRID, GRID))
    grid = target_grid(heights, unit, thickness=LENGTH, target_area=0.5, steps=8)
    options = SolverOptions(method=method, tol=1e-12, stiffness_tol=1e-12)
    nd = nondim.solve_cell(unit, heights, thickness=LENGTH, element_area=area,
                           approaches=grid, options=CellOptions(options))
    fhat = nondim.initial_separation(heights)
    for sigma, E in [(1e-9, 1e3), (1e-9, 1e12), (1e-3, 1e3), (1e-3, 1e12), (1e-6, 5e8)]:
        si = contact.sweep(unit / E, sigma * fhat, sigma * grid, element_area=area,
                           options=options)
        assert si.converged.all() and si.stiffness_converged.all()
        physical = nondim.to_physical(nd, sigma, E)
        pairs = [
            (si.load, physical.load),
            (si.nominal_pressure * LENGTH / (E * sigma), nd.nominal_pressure),
            (si.mean_plane_deflection / sigma, nd.mean_plane_deflection),
            (si.max_pressure * LENGTH / (E * sigma), nd.max_pressure),
            (si.contact_stiffness, physical.contact_stiffness),
        ]
        for direct, scaled in pairs:
            np.testing.assert_allclose(direct, scaled, rtol=1e-10, atol=0)
        np.testing.assert_array_equal(si.real_area_fraction, nd.real_area_fraction)


# --- flat surface -------------------------------------------------------------


def test_flat_surface_is_rejected_by_the_dimensionless_path(block):
    geom, C, area = block
    flat = np.full((1, GRID, GRID), 0.7)  # its std is rounding noise, 1e-16
    message = r"all equal \(a flat surface, standard deviation 0\)"
    with pytest.raises(ValueError, match=message):
        nondim.solve_cell(C * geom.E, flat, thickness=LENGTH, element_area=area,
                          approaches=[0.1, 0.2])
    with pytest.raises(ValueError, match=message):
        cell.approach_grid(flat, 1.0, 4)
    # sigma = 0 on the way back to SI units is refused too
    rough = np.random.default_rng(0).standard_normal((1, N))
    nd = nondim.solve_cell(C * geom.E, rough, thickness=LENGTH, element_area=area,
                           approaches=[0.5])
    with pytest.raises(ValueError, match="sigma must be a finite positive number"):
        nondim.to_physical(nd, 0.0, geom.E)


@pytest.mark.parametrize("method", contact.METHODS)
def test_flat_punch_in_si_units_is_full_contact(block, method):
    # In SI units a flat gap is well posed: a rigid flat punch. For d > 0 every
    # element touches and C p = d 1; for the paper mesh (rows sum to L/E, nu = 0)
    # the pressure is uniform, p = E d / L. At d = 0 nothing is loaded.
    geom, C, area = block
    flat = np.zeros((GRID, GRID))
    d = 1e-6
    result = contact.solve(C, flat, d, element_area=area, options=SolverOptions(method=method))
    expected = np.linalg.solve(C, np.full(N, d))
    assert result.converged and result.real_area_fraction == 1.0
    np.testing.assert_allclose(result.pressure.ravel(), expected, rtol=1e-7)  # measured 1e-9
    if geom.mesh == "paper":
        np.testing.assert_allclose(result.pressure, geom.E * d / LENGTH, rtol=1e-7)
    idle = contact.solve(C, flat, 0.0, element_area=area, options=SolverOptions(method=method))
    assert idle.converged and idle.load == 0.0 and idle.residual == 0.0
    assert np.isfinite(idle.gap).all() and not idle.pressure.any()


# --- non-convergence ----------------------------------------------------------


@pytest.mark.parametrize("max_iter", [0, 1, 2])
@pytest.mark.parametrize("method", contact.METHODS)
def test_tiny_iteration_limit_is_reported_not_hidden(block, method, max_iter, caplog):
    # retries=False: the method's own result as it stopped (with the retries an
    # iterative method's failure is solved again by pivoting: the next test)
    _, C, area = block
    gap = rough_gap(1, 1e-6)
    d = float(np.quantile(gap, 0.3))  # about 6-10 % contact at the solution
    with caplog.at_level(logging.WARNING, logger="roughcontact.contact"):
        result = contact.solve(C, gap, d, element_area=area,
                               options=SolverOptions(method=method, max_iter=max_iter,
                                                     retries=False))
    assert not result.converged
    assert result.iterations <= max_iter
    for name in ("pressure", "displacement", "gap"):
        assert np.isfinite(getattr(result, name)).all()
    assert (result.pressure >= 0.0).all()
    assert np.isfinite(result.residual) and result.residual > result.tol
    # the reported residual is that of the returned pressure
    assert result.residual == pytest.approx(
        contact.kkt_residual(C, gap, d, result.pressure), rel=1e-9)
    assert any("did not converge" in r.getMessage() for r in caplog.records)


def _stopped_after_one_iteration(block, method, caplog):
    """``(C, area, gap, d, result)``: a rough gap at its 30 % quantile solved by
    ``method`` limited to one iteration, the warnings captured."""
    _, C, area = block
    gap = rough_gap(1, 1e-6)
    d = float(np.quantile(gap, 0.3))
    with caplog.at_level(logging.WARNING, logger="roughcontact.contact"):
        result = contact.solve(C, gap, d, element_area=area,
                               options=SolverOptions(method=method, max_iter=1))
    return C, area, gap, d, result


@pytest.mark.parametrize("method", ["steepest", "cg", "pcg"])
def test_tiny_iteration_limit_is_retried_by_pivoting(block, method, caplog):
    # an iterative method stopped by its limit is solved again by block principal
    # pivoting on the dense matrix; the log names both attempts
    C, area, gap, d, result = _stopped_after_one_iteration(block, method, caplog)
    reference = contact.solve(C, gap, d, element_area=area, options=SolverOptions(method="exact"))
    assert result.converged and result.residual <= result.tol
    np.testing.assert_array_equal(result.pressure, reference.pressure)
    assert result.residual == pytest.approx(
        contact.kkt_residual(C, gap, d, result.pressure), rel=1e-9, abs=1e-15)
    assert not any("did not converge" in r.getMessage() for r in caplog.records)


def test_pivoting_that_cannot_settle_is_flagged_with_its_attempts(block, caplog):
    # pivoting is the last resort: a step it cannot settle in its limit, from the
    # previous step's prediction and then cold, is returned flagged and logged
    _, C, area = block
    gap = rough_gap(1, 1e-6)
    d = float(np.quantile(gap, 0.3))
    with caplog.at_level(logging.WARNING, logger="roughcontact.contact"):
        result = contact.sweep(C, gap[None], [0.5 * d, d], element_area=area,
                               options=SolverOptions(method="exact", max_iter=1))
    assert not result.converged[0, 1]
    messages = [r.getMessage() for r in caplog.records if "did not converge" in r.getMessage()]
    assert len(messages) == (~result.converged).sum()
    assert "exact from the given start" in messages[-1] and "exact cold" in messages[-1]


def test_tiny_iteration_limit_in_a_sweep_is_flagged(block, caplog):
    _, C, area = block
    gap = rough_gap(1, 1e-6)
    d = float(np.quantile(gap, 0.3))
    with caplog.at_level(logging.WARNING, logger="roughcontact.contact"):
        result = contact.sweep(C, np.stack([gap, gap]), [0.5 * d, d, 2 * d], element_area=area,
                               options=SolverOptions(method="cg", max_iter=1, retries=False))
    assert not result.converged.any()
    for name in ("load", "mean_plane_deflection", "max_pressure", "residual",
                 "contact_stiffness"):
        assert np.isfinite(getattr(result, name)).all()
    assert sum("did not converge" in r.getMessage() for r in caplog.records) == 6


@pytest.mark.parametrize("method", ["steepest", "cg"])
def test_a_fallbacks_answer_names_its_method_and_is_logged(block, method, caplog):
    # the pivoting fallback's answer is recorded as its own, not the method asked for,
    # in a single solve and per step of a sweep, and a warning names both methods
    C, area, gap, d, result = _stopped_after_one_iteration(block, method, caplog)
    assert result.converged and result.method == "exact"
    fell_back = [r.getMessage() for r in caplog.records if "fallback" in r.getMessage()]
    assert len(fell_back) == 1
    assert f"surface 0 at approach {d:.6g} m: {method} fell short" in fell_back[0]
    assert "fallback exact answered" in fell_back[0]
    # a sweep: every step answered by the fallback, each recorded and logged
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="roughcontact.contact"):
        swept = contact.sweep(C, np.stack([gap, gap]), [0.5 * d, d], element_area=area,
                              options=SolverOptions(method=method, max_iter=1,
                                                    stiffness=False))
    assert swept.method == method and swept.converged.all()
    assert swept.solved_by.shape == (2, 2) and (swept.solved_by == "exact").all()
    assert sum("fallback exact answered" in r.getMessage() for r in caplog.records) == 4
    # the method's own answer, where it converges, is recorded as its own, silently
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="roughcontact.contact"):
        own = contact.sweep(C, gap[None], [0.5 * d, d], element_area=area,
                            options=SolverOptions(method=method, stiffness=False))
    assert (own.solved_by == method).all() and not caplog.records
