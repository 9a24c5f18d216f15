"""Tests of the contact solver (Eq 16-27 of Kumar et al. 2006).

Expected values come from closed forms (Hertz, diagonal operator, single
element, full contact) or from an independent solve: scipy's NNLS on the
Cholesky-transformed problem, min 1/2 |L^T p - L^-1 b|^2 over p >= 0 with
C = L L^T, b = d - f, which has the same minimizer as Eq 27.
"""

import dataclasses
import logging

import numpy as np
import pytest
import scipy.linalg
import scipy.optimize

from roughcontact.contact import (
    SolverOptions,
    kkt_residual,
    solve,
    solve_many,
    sweep,
    tangent_stiffness,
)
from roughcontact.contact.references import hertz
from roughcontact.elasticity.halfspace import PeriodicHalfSpace, halfspace_influence

E = 1.0e9
NU = 0.3
E_STAR = E / (1.0 - NU**2)


def nnls_reference(C, gap0, approach):
    """Independent solution of Eq 27 by NNLS on the Cholesky factor of C."""
    factor = np.linalg.cholesky(C)
    rhs = approach - np.ravel(gap0)
    target = scipy.linalg.solve_triangular(factor, rhs, lower=True)
    pressure, _ = scipy.optimize.nnls(factor.T, target, maxiter=50 * C.shape[0])
    return pressure


@pytest.fixture(scope="module")
def small_problem():
    """20 x 20 half-space matrix and three random rough surfaces [m]."""
    n, size = 20, 1e-3
    C = halfspace_influence((n, n), (size, size), E, NU)
    rng = np.random.default_rng(7)
    z = rng.standard_normal((3, n, n)) * 1e-6
    gaps = z.max(axis=(1, 2), keepdims=True) - z
    return C, gaps, (size / n) ** 2


def paraboloid(n, dx, radius):
    """Initial separation r^2 / (2R) [m], apex at the centre of element (n//2, n//2)."""
    x = (np.arange(n) - n // 2) * dx
    return (x[None, :] ** 2 + x[:, None] ** 2) / (2.0 * radius)


# --- Hertz ------------------------------------------------------------------


def test_hertz_periodic_half_space():
    # Large periodic domain (period 6.4 contact radii), 40 elements across the
    # contact diameter. Compared at the computed load, so the zero-mean
    # convention of the periodic operator (which shifts d) does not enter.
    n, dx, radius = 128, 1e-6, 1e-2
    op = PeriodicHalfSpace((n, n), (n * dx, n * dx), E, NU)
    result = solve(op, paraboloid(n, dx, radius), 3e-8, options=SolverOptions(tol=1e-10))
    assert result.converged
    expected = hertz(result.load, radius, E_STAR)
    a_hertz, p0_hertz = expected.a, expected.p0
    a = np.sqrt(np.count_nonzero(result.pressure) * dx * dx / np.pi)
    assert 2 * a / dx >= 30
    assert a == pytest.approx(a_hertz, rel=0.02)
    assert result.max_pressure == pytest.approx(p0_hertz, rel=0.02)


@pytest.mark.parametrize("method", ["cg", "exact"])
def test_hertz_dense_half_space(method):
    # Dense Love matrix on a 40 x 40 grid just larger than the contact
    # (32 elements across its diameter): the half-space itself, no images,
    # so the approach d = a^2 / R of Hertz is checked as well.
    n, dx, radius = 40, 1e-6, 1e-2
    C = halfspace_influence((n, n), (n * dx, n * dx), E, NU)
    approach = (16 * dx) ** 2 / radius
    result = solve(C, paraboloid(n, dx, radius), approach, element_area=dx * dx,
                   options=SolverOptions(method=method))
    assert result.converged
    expected = hertz(result.load, radius, E_STAR)
    a_hertz, p0_hertz = expected.a, expected.p0
    a = np.sqrt(np.count_nonzero(result.pressure) * dx * dx / np.pi)
    assert 2 * a / dx >= 30
    assert a == pytest.approx(a_hertz, rel=0.02)
    assert result.max_pressure == pytest.approx(p0_hertz, rel=0.02)
    assert a_hertz**2 / radius == pytest.approx(approach, rel=0.02)


# --- closed forms -----------------------------------------------------------


@pytest.mark.parametrize("method", ["cg", "steepest", "exact"])
def test_diagonal_operator(method):
    rng = np.random.default_rng(3)
    compliance = rng.uniform(1e-12, 5e-12, 50)
    gap0 = rng.uniform(0.0, 2e-6, 50)
    approach = 1e-6
    result = solve(np.diag(compliance), gap0, approach, element_area=1e-8,
                   options=SolverOptions(method=method, tol=1e-14))
    expected = np.maximum(approach - gap0, 0.0) / compliance
    np.testing.assert_allclose(result.pressure, expected, rtol=1e-12, atol=0.0)
    assert result.converged


@pytest.mark.parametrize("method", ["cg", "steepest", "exact"])
def test_first_touch_single_element(method, small_problem):
    C, gaps, area = small_problem
    gap0 = gaps[0].ravel()
    second = np.sort(gap0)[1]  # gap of the next-highest element
    approach = 0.5 * second
    result = solve(C, gap0, approach, element_area=area, options=SolverOptions(method=method))
    k = int(np.argmin(gap0))
    assert result.converged
    assert np.count_nonzero(result.pressure) == 1
    assert result.pressure[k] == pytest.approx(approach / C[k, k], rel=1e-9)
    assert result.real_area_fraction == pytest.approx(1 / 400)
    assert result.load == pytest.approx(result.pressure[k] * area, rel=1e-12)


def test_zero_approach_is_no_contact(small_problem):
    C, gaps, area = small_problem
    result = solve(C, gaps[0], 0.0, element_area=area)
    assert result.converged and result.load == 0.0 and result.residual == 0.0


@pytest.mark.parametrize("method", ["cg", "steepest", "exact"])
def test_full_contact(method, small_problem):
    C, gaps, area = small_problem
    gap0 = gaps[1].ravel()
    approach = 30 * gap0.max()
    expected = np.linalg.solve(C, approach - gap0)
    assert (expected > 0).all()
    result = solve(C, gap0, approach, element_area=area,
                   options=SolverOptions(method=method, tol=1e-10))
    assert result.converged
    assert result.real_area_fraction == 1.0
    np.testing.assert_allclose(result.pressure, expected, rtol=1e-7)
    np.testing.assert_allclose(result.gap, 0.0, atol=1e-9 * approach)


# --- agreement with an independent solve -------------------------------------


@pytest.mark.parametrize("method", ["cg", "exact"])
@pytest.mark.parametrize("approach", [0.8e-6, 2e-6, 4e-6])
def test_random_problems_match_nnls(method, approach, small_problem):
    C, gaps, area = small_problem
    for gap0 in gaps:
        reference = nnls_reference(C, gap0, approach)
        result = solve(C, gap0, approach, element_area=area,
                       options=SolverOptions(method=method, tol=1e-12))
        assert result.converged
        error = np.abs(result.pressure.ravel() - reference).max() / reference.max()
        assert error < 1e-8
        assert result.pressure.shape == gap0.shape


def test_periodic_operator_matches_nnls():
    n = 16
    op = PeriodicHalfSpace((n, n), (1e-3, 1e-3), E, NU, mean_compliance=1e-11)
    dense = op @ np.eye(n * n)
    dense = 0.5 * (dense + dense.T)
    rng = np.random.default_rng(11)
    z = rng.standard_normal((n, n)) * 1e-6
    gap0 = z.max() - z
    reference = nnls_reference(dense, gap0, 1.5e-6)
    result = solve(op, gap0, 1.5e-6, options=SolverOptions(tol=1e-12))
    error = np.abs(result.pressure.ravel() - reference).max() / reference.max()
    assert result.converged and error < 1e-8


def test_mixed_precision_meets_tolerance(small_problem):
    C, gaps, area = small_problem
    double = solve(C, gaps[2], 3e-6, element_area=area,
                   options=SolverOptions(method="cg", tol=1e-11))
    mixed = solve(C, gaps[2], 3e-6, element_area=area,
                  options=SolverOptions(method="cg", tol=1e-11, precision="mixed"))
    assert mixed.converged and mixed.residual <= 1e-11
    assert kkt_residual(C, gaps[2], 3e-6, mixed.pressure) <= 1e-11
    np.testing.assert_allclose(mixed.pressure, double.pressure, rtol=0,
                               atol=1e-8 * double.max_pressure)


# --- result fields, warm starts, batches --------------------------------------


def test_result_fields_consistent(small_problem):
    C, gaps, area = small_problem
    approach = 2e-6
    result = solve(C, gaps[0], approach, element_area=area)
    p = result.pressure.ravel()
    np.testing.assert_allclose(result.displacement.ravel(), C @ p, rtol=1e-10,
                               atol=1e-12 * approach)
    np.testing.assert_allclose(result.gap, result.displacement + gaps[0] - approach, rtol=0,
                               atol=1e-15 * approach)
    assert result.load == pytest.approx(p.sum() * area)
    assert result.nominal_pressure == pytest.approx(result.load / (400 * area))
    assert result.max_pressure == p.max()
    assert result.mean_plane_deflection == pytest.approx(result.displacement.mean())
    assert result.real_area_fraction == np.count_nonzero(p) / 400
    assert result.residual == pytest.approx(kkt_residual(C, gaps[0], approach, p), abs=1e-14)
    assert (result.gap[result.pressure > 0] == pytest.approx(0.0, abs=1e-9 * approach))
    assert (result.gap > -1e-9 * approach).all()
    assert result.matvecs >= result.iterations > 0


def test_load_increases_with_approach(small_problem):
    C, gaps, area = small_problem
    approaches = np.linspace(0.2e-6, 6e-6, 12)
    loads = [solve(C, gaps[1], d, element_area=area).load for d in approaches]
    assert np.all(np.diff(loads) > 0)


def test_warm_start_agrees_with_cold(small_problem):
    C, gaps, area = small_problem
    first = solve(C, gaps[0], 2e-6, element_area=area)
    for method in ("cg", "steepest", "exact"):
        cold = solve(C, gaps[0], 2.5e-6, element_area=area,
                     options=SolverOptions(method=method, tol=1e-10))
        warm = solve(C, gaps[0], 2.5e-6, element_area=area, p0=first.pressure,
                     options=SolverOptions(method=method, tol=1e-10))
        assert cold.converged and warm.converged
        np.testing.assert_allclose(warm.pressure, cold.pressure, rtol=0,
                                   atol=1e-7 * cold.max_pressure)


@pytest.mark.parametrize("method", ["cg", "steepest", "exact"])
def test_solve_many_equals_loop(method, small_problem):
    C, gaps, area = small_problem
    approaches = np.array([1e-6, 3e-6, 0.0])
    batch = solve_many(C, gaps, approaches, element_area=area, options=SolverOptions(method=method))
    assert len(batch) == 3
    for j, result in enumerate(batch):
        single = solve(C, gaps[j], approaches[j], element_area=area,
                       options=SolverOptions(method=method))
        assert result.converged == single.converged
        assert result.approach == approaches[j]
        np.testing.assert_allclose(result.pressure, single.pressure, rtol=0,
                                   atol=1e-8 * max(single.max_pressure, 1.0))
        assert result.pressure.shape == (20, 20)


def test_solve_many_flat_and_scalar_approach(small_problem):
    C, gaps, area = small_problem
    batch = solve_many(C, gaps.reshape(3, -1), 2e-6, element_area=area)
    assert all(result.pressure.shape == (400,) for result in batch)
    assert all(result.converged for result in batch)


def test_sweep_matches_solve_and_is_monotone(small_problem):
    C, gaps, area = small_problem
    approaches = np.linspace(0.5e-6, 5e-6, 6)
    result = sweep(C, gaps, approaches, element_area=area,
                   options=SolverOptions(return_fields=True))
    assert result.load.shape == (3, 6)
    assert result.pressure.shape == (3, 6, 20, 20)
    assert result.converged.all() and result.stiffness_converged.all()
    assert (np.diff(result.load, axis=1) > 0).all()
    assert (np.diff(result.real_area_fraction, axis=1) >= 0).all()
    for j in (0, 2):
        for step in (1, 5):
            single = solve(C, gaps[j], approaches[step], element_area=area)
            assert result.load[j, step] == pytest.approx(single.load, rel=1e-8)
            assert result.max_pressure[j, step] == pytest.approx(single.max_pressure, rel=1e-7)
            assert result.mean_plane_deflection[j, step] == pytest.approx(
                single.mean_plane_deflection, rel=1e-8)
    # The stiffness grows as contact spreads and bounds the secant slope from
    # below at the end of each interval (load convex in d for these surfaces).
    assert (result.contact_stiffness > 0).all()
    secant = np.diff(result.load, axis=1) / np.diff(approaches)
    assert (result.contact_stiffness[:, 1:] >= secant * (1 - 1e-9)).all()


# --- tangent stiffness --------------------------------------------------------


def test_tangent_stiffness_matches_finite_difference(small_problem):
    C, gaps, area = small_problem
    approach, h = 3e-6, 1e-12
    below = solve(C, gaps[0], approach - h, element_area=area,
                  options=SolverOptions(method="exact"))
    above = solve(C, gaps[0], approach + h, element_area=area,
                  options=SolverOptions(method="exact"))
    centre = solve(C, gaps[0], approach, element_area=area, options=SolverOptions(method="exact"))
    # Same contact set at both ends, so the load is linear in d in between.
    assert np.array_equal(below.pressure > 0, above.pressure > 0)
    finite_difference = (above.load - below.load) / (2 * h)
    stiffness = tangent_stiffness(C, centre.pressure, element_area=area, tol=1e-12)
    assert stiffness == pytest.approx(finite_difference, rel=1e-5)
    swept = sweep(C, gaps[:1], [approach], element_area=area,
                  options=SolverOptions(stiffness_tol=1e-10))
    assert swept.contact_stiffness[0, 0] == pytest.approx(finite_difference, rel=1e-5)


def test_tangent_stiffness_full_contact_is_closed_form(small_problem):
    C, gaps, area = small_problem
    expected = area * np.linalg.solve(C, np.ones(400)).sum()
    assert tangent_stiffness(C, np.ones(400), element_area=area) == pytest.approx(
        expected, rel=1e-8)
    assert tangent_stiffness(C, np.zeros(400), element_area=area) == 0.0


# --- robustness and input checks ----------------------------------------------


def test_non_convergence_warns_and_returns(small_problem, caplog):
    C, gaps, area = small_problem
    with caplog.at_level(logging.WARNING, logger="roughcontact.contact"):
        result = solve(C, gaps[0], 4e-6, element_area=area, options=SolverOptions(max_iter=2))
    assert not result.converged
    assert np.isfinite(result.residual) and result.residual > result.tol
    assert np.isfinite(result.pressure).all() and (result.pressure >= 0).all()
    assert result.iterations == 2
    assert any("did not converge" in record.message for record in caplog.records)


@pytest.mark.parametrize(
    "change, name",
    [
        (dict(gap0=np.zeros((20, 19))), "gap0"),
        (dict(gap0=np.full((20, 20), np.nan)), "gap0"),
        (dict(gap0=np.full(400, np.inf)), "gap0"),
        (dict(approach=-1e-9), "approach"),
        (dict(approach=np.nan), "approach"),
        (dict(element_area=None), "element_area"),
        (dict(element_area=-1.0), "element_area"),
        (dict(method="newton"), "method"),
        (dict(tol=0.0), "tol"),
        (dict(max_iter=-3), "max_iter"),
        (dict(p0=-np.ones((20, 20))), "p0"),
        (dict(p0=np.ones(7)), "p0"),
        (dict(precision="half"), "precision"),
    ],
)
def test_bad_input_names_argument(change, name, small_problem):
    C, gaps, area = small_problem
    fields = {field.name for field in dataclasses.fields(SolverOptions)}
    arguments = dict(gap0=gaps[0], approach=1e-6, element_area=area)
    arguments.update({key: value for key, value in change.items() if key not in fields})
    options = {key: value for key, value in change.items() if key in fields}
    with pytest.raises(ValueError, match=name):
        solve(C, **arguments, options=SolverOptions(**options))


def test_bad_operator_rejected(small_problem):
    C, gaps, area = small_problem
    skewed = C.copy()
    skewed[0, 1] *= 1.01
    with pytest.raises(ValueError, match="operator must be symmetric"):
        solve(skewed, gaps[0], 1e-6, element_area=area)
    negative = C.copy()
    negative[5, 5] = -negative[5, 5]
    with pytest.raises(ValueError, match="operator must have a positive diagonal"):
        solve(negative, gaps[0], 1e-6, element_area=area)
    indefinite = np.eye(400) * C[0, 0]
    indefinite[0, 1] = indefinite[1, 0] = 2 * C[0, 0]
    gap0 = np.zeros(400)
    with pytest.raises(ValueError, match="operator must be positive definite"):
        solve(indefinite, gap0, 1e-6, element_area=area, options=SolverOptions(method="exact"))
    with pytest.raises(ValueError, match="operator must be a square"):
        solve(C[:, :399], gaps[0], 1e-6, element_area=area)
    bad = C.copy()
    bad[3, 4] = bad[4, 3] = np.inf
    with pytest.raises(ValueError, match="operator must contain only finite"):
        solve(bad, gaps[0], 1e-6, element_area=area)


def test_batch_inputs_rejected(small_problem):
    C, gaps, area = small_problem
    with pytest.raises(ValueError, match="gaps0"):
        solve_many(C, gaps[0], 1e-6, element_area=area)
    with pytest.raises(ValueError, match="approach"):
        solve_many(C, gaps, [1e-6, 2e-6], element_area=area)
    with pytest.raises(ValueError, match="approaches"):
        sweep(C, gaps, [1e-6, -1e-6], element_area=area)
    op = PeriodicHalfSpace((20, 20), (1e-3, 1e-3), E, NU)
    with pytest.raises(ValueError, match="gap0"):
        solve(op, np.zeros((10, 40)), 1e-6)


def test_zero_mean_operator_limits_approach(small_problem):
    # With zero mean displacement the load is unbounded once d >= mean(f).
    _, gaps, _ = small_problem
    op = PeriodicHalfSpace((20, 20), (1e-3, 1e-3), E, NU)
    mean_gap = gaps[0].mean()
    with pytest.raises(ValueError, match="approach must be below the mean"):
        solve(op, gaps[0], 1.01 * mean_gap)
    assert solve(op, gaps[0], 0.5 * mean_gap).converged
    stiff = PeriodicHalfSpace((20, 20), (1e-3, 1e-3), E, NU, mean_compliance=1e-11)
    assert solve(stiff, gaps[0], 1.01 * mean_gap).converged


# --- sweep predictor (extrapolate) ----------------------------------------------


@pytest.mark.parametrize("stiffness", [True, False])
def test_sweep_extrapolation_same_solution_fewer_iterations(small_problem, stiffness):
    """The predictor (tangent or secant dp/dd) changes the start, not the solution."""
    C, gaps, area = small_problem
    approaches = np.linspace(0.5e-6, 5e-6, 10)
    runs = [sweep(C, gaps, approaches, element_area=area,
                  options=SolverOptions(method="cg", tol=1e-10, stiffness=stiffness,
                                        stiffness_tol=1e-10, extrapolate=flag, return_fields=True))
            for flag in (True, False)]
    predicted, plain = runs
    assert predicted.converged.all() and plain.converged.all()
    assert predicted.residual.max() <= 1e-10
    np.testing.assert_allclose(predicted.load, plain.load, rtol=1e-8)
    np.testing.assert_array_equal(predicted.pressure > 0, plain.pressure > 0)
    for j in range(3):
        reference = nnls_reference(C, gaps[j], approaches[-1])
        np.testing.assert_allclose(predicted.pressure[j, -1].ravel(), reference,
                                   atol=1e-7 * reference.max())
    # Warm starts along the sweep: the extrapolated start needs fewer products.
    assert predicted.matvecs[:, 1:].sum() < plain.matvecs[:, 1:].sum()


def test_predict_is_exact_on_a_fixed_contact_set(small_problem):
    """Full contact never changes the set, so the tangent prediction is the solution."""
    from roughcontact.contact.sweeps import predict

    C, gaps, area = small_problem
    f = gaps[0].ravel()
    first, second = 1e-3, 2e-3  # [m], a thousand times the roughness: full contact
    p1 = np.linalg.solve(C, first - f)
    p2 = np.linalg.solve(C, second - f)
    assert (p1 > 0).all()
    rate = np.linalg.solve(C, np.ones_like(f))
    predicted = predict(p1[None], np.array([second]), np.array([first]), rate[None])
    np.testing.assert_allclose(predicted[0], p2, rtol=1e-9)
    # No rate yet (NaN): the start stays the last solution; negatives are clipped.
    kept = predict(p1[None], np.array([second]), np.array([first]), np.full((1, 400), np.nan))
    np.testing.assert_array_equal(kept[0], p1)
    clipped = predict(p1[None], np.array([0.0]), np.array([first]), rate[None])
    assert (clipped >= 0).all()


def test_sweep_extrapolation_nonconvergence_is_flagged_not_nan(small_problem, caplog):
    C, gaps, area = small_problem
    approaches = np.linspace(0.5e-6, 5e-6, 4)
    with caplog.at_level(logging.WARNING, logger="roughcontact.contact"):
        result = sweep(C, gaps, approaches, element_area=area,
                       options=SolverOptions(method="cg", max_iter=2, stiffness=False,
                                             retries=False))
    assert not result.converged[:, 1:].all()
    assert np.isfinite(result.load).all() and np.isfinite(result.residual).all()
    assert "did not converge" in caplog.text
