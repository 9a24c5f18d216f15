"""The pivoting sweep: every surface through its own steps, one product per round.

Checked against things it does not use: scipy's NNLS on the Cholesky factor of
C (the same problem solved independently), the constrained CG sweep, and the
free-set CG of ``tangent_stiffness``.
"""

import numpy as np
import pytest
from test_solver import nnls_reference  # scipy NNLS on the Cholesky factor of C

from roughcontact.contact import (
    SolverOptions,
    resolve_method,
    solve,
    solve_many,
    sweep,
    tangent_stiffness,
)
from roughcontact.elasticity.halfspace import PeriodicHalfSpace, halfspace_influence
from roughcontact.elasticity.protocol import DenseInfluence, MatrixFreeInfluence

E, NU = 2.1e11, 0.3


@pytest.fixture(scope="module")
def problem():
    """24 x 24 half-space matrix, four rough surfaces [m] and per-surface approaches."""
    n, size = 24, 1e-3
    C = halfspace_influence((n, n), (size, size), E, NU)
    rng = np.random.default_rng(11)
    z = rng.standard_normal((4, n * n)) * 1e-6
    gaps = z.max(axis=1, keepdims=True) - z
    # different approach schedules per surface: the surfaces are at different
    # steps in the same round
    approaches = np.array([np.geomspace(0.05, 2.5, 6) * s * 1e-6 for s in (1.0, 0.5, 1.7, 3.0)])
    return C, gaps, approaches, (size / n) ** 2


def test_every_step_matches_nnls(problem):
    C, gaps, approaches, area = problem
    result = sweep(C, gaps, approaches, element_area=area,
                   options=SolverOptions(method="pivot", tol=1e-10, return_fields=True))
    assert result.method == "pivot"
    assert result.converged.all() and result.residual.max() < 1e-12
    for j in range(gaps.shape[0]):
        for k in range(approaches.shape[1]):
            reference = nnls_reference(C, gaps[j], approaches[j, k])
            pressure = result.pressure[j, k]
            assert pressure == pytest.approx(reference, abs=1e-9 * reference.max())
            assert result.load[j, k] == pytest.approx(reference.sum() * area, rel=1e-10)


def test_agrees_with_the_cg_sweep_and_costs_fewer_products(problem):
    C, gaps, approaches, area = problem
    pivot = sweep(C, gaps, approaches, element_area=area,
                  options=SolverOptions(method="pivot", tol=1e-10))
    cg = sweep(C, gaps, approaches, element_area=area,
               options=SolverOptions(method="cg", tol=1e-10))
    assert np.array_equal(pivot.real_area_fraction, cg.real_area_fraction)
    assert pivot.load == pytest.approx(cg.load, rel=1e-7)
    assert pivot.contact_stiffness == pytest.approx(cg.contact_stiffness, rel=1e-5)
    assert pivot.matvecs.sum() < cg.matvecs.sum()


def test_tangent_from_the_factor_equals_the_free_set_cg(problem):
    C, gaps, approaches, area = problem
    result = sweep(C, gaps[:1], approaches[:1], element_area=area,
                   options=SolverOptions(method="pivot", tol=1e-10, return_fields=True))
    for k in (1, 3, 5):
        expected = tangent_stiffness(C, result.pressure[0, k], element_area=area, tol=1e-13)
        assert result.contact_stiffness[0, k] == pytest.approx(expected, rel=1e-9)
    assert result.stiffness_converged.all()


def test_ill_conditioned_matrix_is_solved_to_rounding():
    """A checkerboard near-null mode (condition number ~1e9, like the paper mesh's):
    the factorization is backward stable, so the KKT residual stays at rounding."""
    n = 12
    base = halfspace_influence((n, n), (1e-3, 1e-3), E, NU)
    checker = np.indices((n, n)).sum(axis=0) % 2 * 2.0 - 1.0
    mode = checker.ravel() / n  # unit vector
    eigen = float(mode @ base @ mode)
    project = np.eye(n * n) - np.outer(mode, mode)
    # the checkerboard keeps 1e-9 of its curvature: a near-null mode
    C = project @ base @ project + 1e-9 * eigen * np.outer(mode, mode)
    C = 0.5 * (C + C.T)
    assert np.linalg.cond(C) > 1e8
    rng = np.random.default_rng(3)
    z = rng.standard_normal((2, n * n)) * 1e-6
    gaps = z.max(axis=1, keepdims=True) - z
    result = sweep(C, gaps, np.geomspace(0.1, 2.0, 5) * 1e-6, element_area=(1e-3 / n) ** 2,
                   options=SolverOptions(method="pivot", tol=1e-8))
    assert result.converged.all() and result.residual.max() < 1e-10


def test_auto_picks_pivot_for_dense_pcg_for_grid_operators_cg_for_matrix_free(problem):
    C, gaps, approaches, area = problem
    assert resolve_method("auto", C) == "pivot"
    assert resolve_method("auto", DenseInfluence(C, area)) == "pivot"
    periodic = PeriodicHalfSpace((16, 16), (1e-3, 1e-3), E, NU)
    assert resolve_method("auto", periodic) == "pcg"
    assert resolve_method("auto", periodic, 1e6) == "cg"  # capped
    assert resolve_method("auto", MatrixFreeInfluence(DenseInfluence(C, area), area,
                                                      np.diag(C).copy())) == "cg"
    assert resolve_method("steepest", C) == "steepest"
    # "auto" is the default of the entry points: the study's solver
    assert solve(C, gaps[0], approaches[0, 2], element_area=area).method == "pivot"
    assert sweep(C, gaps[:1], approaches[:1, :2], element_area=area).method == "pivot"
    ramp = np.linspace(0.0, 1e-6, 256).reshape(16, 16)
    assert solve(periodic, ramp, 1e-7).method == "pcg"


def test_single_solves_and_the_sweep_share_the_pivoting(problem):
    """solve_many("pivot"/"exact") runs the rounds of the sweep for one step: the same
    solutions to rounding, a dense matrix passed plain or wrapped alike."""
    C, gaps, approaches, area = problem
    swept = sweep(C, gaps, approaches, element_area=area,
                  options=SolverOptions(method="pivot", tol=1e-10, return_fields=True))
    for k in (0, 3, 5):
        for method, operator, given in (("pivot", C, area), ("exact", DenseInfluence(C, area),
                                                            None)):
            results = solve_many(operator, gaps, approaches[:, k], element_area=given,
                                 options=SolverOptions(method=method, tol=1e-10))
            for j, result in enumerate(results):
                assert result.method == method and result.converged
                assert result.matvecs == result.iterations + 2  # rounds, then C p
                expected = swept.pressure[j, k]
                assert np.array_equal(result.contact_set, expected > 0)
                np.testing.assert_allclose(result.pressure, expected, rtol=0,
                                           atol=1e-12 * expected.max())


def test_not_positive_definite_is_refused(problem):
    C, gaps, approaches, area = problem
    bad = C.copy()
    bad[0, 0] = -bad[0, 0]
    with pytest.raises(ValueError, match="positive"):
        sweep(bad, gaps[:1], approaches[:1], element_area=area,
              options=SolverOptions(method="pivot"))


def test_a_factor_kept_in_part_and_extended_is_the_cholesky_factor_of_the_new_set():
    """PivotState keeps its factor up to the first element that left the free set and
    appends the rest: the result is the Cholesky factor of C on the new set in the
    factor's order (checked against numpy's), with the elements of highest priority
    first; when the first element leaves it factors anew."""
    from roughcontact.contact.pivot import PivotState

    matrix = halfspace_influence((10, 10), (1e-3, 1e-3), 1.0, 0.3)
    operator = DenseInfluence(matrix, 1e-8)
    rng = np.random.default_rng(4)
    priority = rng.random(100)
    free = priority > 0.4
    state = PivotState(free.copy(), None, priority)
    assert state.refactor(operator) == "new"
    assert (np.diff(priority[state.index]) <= 0).all()  # decreasing priority
    for _ in range(5):
        lowest = state.index[-3:]  # the last three of the factor leave, four others enter
        state.free[lowest] = False
        state.free[rng.choice(np.flatnonzero(~state.free), 4, replace=False)] = True
        assert state.refactor(operator) == "extended"
        block = matrix[np.ix_(state.index, state.index)]
        np.testing.assert_allclose(state.factor, np.linalg.cholesky(block), rtol=1e-10,
                                   atol=1e-12 * np.abs(state.factor).max())
        assert set(state.index) == set(np.flatnonzero(state.free))
    state.free[state.index[0]] = False
    assert state.refactor(operator) == "new"
    np.testing.assert_allclose(state.factor @ state.factor.T,
                               matrix[np.ix_(state.index, state.index)], rtol=1e-12)


def test_the_saturated_load_kept_up_to_date_is_the_sum_of_the_saturated_columns():
    from roughcontact.contact.pivot import PivotState

    matrix = halfspace_influence((10, 10), (1e-3, 1e-3), 1.0, 0.3)
    rng = np.random.default_rng(5)
    state = PivotState(np.zeros(100, dtype=bool), rng.random(100) < 0.3)
    for _ in range(8):  # a few elements enter and leave: updated, not summed anew
        load = state._saturated_load(matrix)
        np.testing.assert_allclose(load, matrix[:, state.upper].sum(axis=1), rtol=1e-13)
        flip = rng.choice(100, 3, replace=False)
        state.upper = state.upper.copy()
        state.upper[flip] = ~state.upper[flip]
    state.upper = ~state.upper  # all changed: summed anew
    np.testing.assert_allclose(state._saturated_load(matrix),
                               matrix[:, state.upper].sum(axis=1), rtol=1e-13)
