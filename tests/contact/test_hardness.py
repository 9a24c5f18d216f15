"""Contact with a hardness cap, 0 <= p <= H (elastic-perfectly-plastic elements).

The capped solutions are checked against an independent bounded least-squares
solve: with C = L L^T and b = d - f, minimizing |L^T p - L^-1 b|^2 over
0 <= p <= H (scipy.optimize.lsq_linear, BVLS) has the same minimizer as
1/2 p.C p - p.b over the same box. Also: the limit H -> inf, a flat punch
that saturates everywhere (closed form), the tangent against a finite
difference, and that hardness=None leaves the uncapped solve untouched.
"""

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
from roughcontact.elasticity.halfspace import PeriodicHalfSpace, halfspace_influence

E, NU = 1.0e9, 0.3
N, SIZE = 16, 1e-3
AREA = (SIZE / N) ** 2


def bounded_reference(C, gap0, approach, hardness):
    """Independent solution of the capped problem by BVLS on the Cholesky factor of C."""
    factor = np.linalg.cholesky(C)
    target = scipy.linalg.solve_triangular(factor, approach - np.ravel(gap0), lower=True)
    result = scipy.optimize.lsq_linear(factor.T, target, bounds=(0.0, hardness), method="bvls",
                                       tol=1e-15, max_iter=50 * C.shape[0])
    return result.x


@pytest.fixture(scope="module")
def problem():
    """16 x 16 half-space matrix, three rough surfaces [m], approaches [m], a cap [Pa]."""
    C = halfspace_influence((N, N), (SIZE, SIZE), E, NU)
    rng = np.random.default_rng(5)
    z = rng.standard_normal((3, N * N)) * 1e-6
    gaps = z.max(axis=1, keepdims=True) - z
    approaches = np.linspace(0.4e-6, 3.0e-6, 5)
    elastic = solve(C, gaps[0], approaches[-1], element_area=AREA,
                    options=SolverOptions(method="exact"))
    # a third of the largest elastic pressure: a good share of the contact saturates
    return C, gaps, approaches, elastic.max_pressure / 3.0


def test_reference_is_a_kkt_point(problem):
    C, gaps, approaches, hardness = problem
    reference = bounded_reference(C, gaps[0], approaches[-1], hardness)
    assert kkt_residual(C, gaps[0], approaches[-1], reference, element_area=AREA,
                        hardness=hardness) < 1e-12
    # the cap is active and not everywhere
    assert 0 < np.count_nonzero(reference >= hardness) < np.count_nonzero(reference)


@pytest.mark.parametrize("method", ["cg", "exact", "steepest"])
def test_bounded_solve_matches_bvls(method, problem):
    C, gaps, approaches, hardness = problem
    results = solve_many(C, gaps, approaches[-1], element_area=AREA, hardness=hardness,
                         options=SolverOptions(method=method, tol=1e-11))
    for gap0, result in zip(gaps, results, strict=True):
        reference = bounded_reference(C, gap0, approaches[-1], hardness)
        assert result.converged and result.residual <= 1e-11
        assert result.max_pressure <= hardness
        assert np.abs(result.pressure - reference).max() <= 1e-7 * hardness
        assert result.plastic_area_fraction == np.count_nonzero(reference >= hardness) / N**2
        assert 0.0 < result.plastic_area_fraction < result.real_area_fraction
        assert result.hardness == hardness
        assert result.residual == pytest.approx(
            kkt_residual(C, gap0, approaches[-1], result.pressure, element_area=AREA,
                         hardness=hardness), abs=1e-13)


@pytest.mark.parametrize("method", ["cg", "pivot"])
def test_bounded_sweep_matches_bvls(method, problem):
    C, gaps, approaches, hardness = problem
    result = sweep(C, gaps, approaches, element_area=AREA, hardness=hardness,
                   options=SolverOptions(method=method, tol=1e-11, return_fields=True))
    assert result.converged.all() and result.stiffness_converged.all()
    assert result.hardness == hardness
    for j in range(gaps.shape[0]):
        for k, approach in enumerate(approaches):
            reference = bounded_reference(C, gaps[j], approach, hardness)
            pressure = result.pressure[j, k].ravel()
            assert np.abs(pressure - reference).max() <= 1e-7 * hardness
            assert result.load[j, k] == pytest.approx(reference.sum() * AREA, rel=1e-7)
            assert result.plastic_area_fraction[j, k] == np.mean(reference >= hardness)
    # the saturated share grows with the approach
    assert (np.diff(result.plastic_area_fraction, axis=1) >= 0).all()
    assert result.plastic_area_fraction[:, -1].min() > 0


def test_mixed_precision_and_a_start_above_the_cap(problem):
    C, gaps, approaches, hardness = problem
    result = sweep(C, gaps, approaches, element_area=AREA, hardness=hardness,
                   options=SolverOptions(method="cg", precision="mixed", tol=1e-10))
    assert result.converged.all() and result.residual.max() <= 1e-10
    reference = bounded_reference(C, gaps[1], approaches[2], hardness)
    start = np.full(N * N, 10.0 * hardness)  # clipped to H before the solve
    for method in ("cg", "exact"):
        warm = solve(C, gaps[1], approaches[2], element_area=AREA, hardness=hardness, p0=start,
                     options=SolverOptions(method=method, tol=1e-11))
        assert warm.converged
        assert np.abs(warm.pressure - reference).max() <= 1e-7 * hardness


def test_tangent_with_saturation_is_the_load_derivative(problem):
    # dF/dd at fixed free and saturated sets, against a central difference of
    # exact capped solves (small enough a step that no element changes set)
    C, gaps, approaches, hardness = problem
    result = sweep(C, gaps[:1], approaches, element_area=AREA, hardness=hardness,
                   options=SolverOptions(method="pivot", return_fields=True))
    step = 1e-6 * approaches[-1]
    for k, approach in enumerate(approaches):
        loads = [solve(C, gaps[0], approach + s, element_area=AREA, hardness=hardness,
                       options=SolverOptions(method="exact", tol=1e-14)).load
                 for s in (-step, step)]
        difference = (loads[1] - loads[0]) / (2 * step)
        assert result.contact_stiffness[0, k] == pytest.approx(difference, rel=1e-6)
        from_cg = tangent_stiffness(C, result.pressure[0, k], element_area=AREA,
                                    hardness=hardness)
        assert from_cg == pytest.approx(result.contact_stiffness[0, k], rel=1e-8)
    # saturated elements do not count: the uncapped tangent of the same field is stiffer
    uncapped = tangent_stiffness(C, result.pressure[0, -1], element_area=AREA)
    assert uncapped > 1.05 * result.contact_stiffness[0, -1]


@pytest.mark.parametrize("method", ["cg", "pivot"])
def test_infinite_hardness_limit_is_the_elastic_solve(method, problem):
    C, gaps, approaches, _ = problem
    elastic = sweep(C, gaps, approaches, element_area=AREA,
                    options=SolverOptions(method=method, tol=1e-12, return_fields=True))
    hardness = 1e6 * elastic.max_pressure.max()
    capped = sweep(C, gaps, approaches, element_area=AREA, hardness=hardness,
                   options=SolverOptions(method=method, tol=1e-12, return_fields=True))
    np.testing.assert_array_equal(capped.pressure > 0, elastic.pressure > 0)
    np.testing.assert_allclose(capped.pressure, elastic.pressure, rtol=1e-9,
                               atol=1e-9 * elastic.max_pressure.max())
    np.testing.assert_allclose(capped.contact_stiffness, elastic.contact_stiffness, rtol=1e-9)
    assert (capped.plastic_area_fraction == 0).all()


@pytest.mark.parametrize("method", ["cg", "exact", "pivot"])
def test_flat_punch_saturates_everywhere(method):
    # A flat rigid punch on a central 6 x 6 patch (far from everything else):
    # its elastic pressure at this approach exceeds H on every element (least
    # at the centre), so the capped solution is p = H on the punch, 0 off it.
    C = halfspace_influence((N, N), (SIZE, SIZE), E, NU)
    punch = np.zeros((N, N), dtype=bool)
    punch[5:11, 5:11] = True
    gap0 = np.where(punch, 0.0, 1e-3)
    approach = 1e-6
    elastic = solve(C, gap0, approach, element_area=AREA, options=SolverOptions(method="exact"))
    assert (elastic.pressure[punch] > 0).all()
    hardness = 0.5 * elastic.pressure[punch].min()
    if method == "pivot":
        result = sweep(C, gap0[None], [approach], element_area=AREA, hardness=hardness,
                       options=SolverOptions(method=method, return_fields=True))
        pressure, load = result.pressure[0, 0], result.load[0, 0]
        plastic, real = result.plastic_area_fraction[0, 0], result.real_area_fraction[0, 0]
        assert result.contact_stiffness[0, 0] == 0.0
    else:
        result = solve(C, gap0, approach, element_area=AREA, hardness=hardness,
                       options=SolverOptions(method=method))
        pressure, load = result.pressure, result.load
        plastic, real = result.plastic_area_fraction, result.real_area_fraction
    assert result.converged if method != "pivot" else result.converged.all()
    assert (pressure[punch] == hardness).all() and (pressure[~punch] == 0).all()
    assert load == pytest.approx(hardness * punch.sum() * AREA, rel=1e-14)
    assert plastic == real == punch.mean()


@pytest.mark.parametrize("method", ["cg", "pivot"])
def test_no_hardness_is_the_uncapped_solve(method, problem):
    C, gaps, approaches, _ = problem
    base = sweep(C, gaps, approaches, element_area=AREA,
                 options=SolverOptions(method=method, return_fields=True))
    for hardness in (None, np.inf):
        other = sweep(C, gaps, approaches, element_area=AREA, hardness=hardness,
                      options=SolverOptions(method=method, return_fields=True))
        for name in ("pressure", "load", "residual", "iterations", "matvecs",
                     "contact_stiffness", "real_area_fraction"):
            np.testing.assert_array_equal(getattr(other, name), getattr(base, name))
        assert other.hardness is None and (other.plastic_area_fraction == 0).all()
    single = "cg" if method == "cg" else "exact"
    plain = solve(C, gaps[0], approaches[-1], element_area=AREA,
                  options=SolverOptions(method=single))
    none = solve(C, gaps[0], approaches[-1], element_area=AREA, hardness=None,
                 options=SolverOptions(method=single))
    np.testing.assert_array_equal(none.pressure, plain.pressure)
    assert none.iterations == plain.iterations and none.residual == plain.residual
    assert none.plastic_area_fraction == 0.0 and none.hardness is None


def test_periodic_operator_with_cap_matches_bvls():
    op = PeriodicHalfSpace((N, N), (SIZE, SIZE), E, NU, mean_compliance=1e-11)
    dense = op @ np.eye(N * N)
    dense = 0.5 * (dense + dense.T)
    rng = np.random.default_rng(13)
    z = rng.standard_normal((N, N)) * 1e-6
    gap0 = z.max() - z
    approach = 1.5e-6
    hardness = solve(op, gap0, approach).max_pressure / 3.0
    result = solve(op, gap0, approach, hardness=hardness,
                   options=SolverOptions(method="cg", tol=1e-12))
    assert result.converged and result.plastic_area_fraction > 0
    assert kkt_residual(op, gap0, approach, result.pressure, hardness=hardness) <= 1e-12
    reference = bounded_reference(dense, gap0, approach, hardness)
    assert np.abs(result.pressure.ravel() - reference).max() <= 1e-7 * hardness


def test_capped_residual_sees_each_violation(problem):
    C, gaps, approaches, hardness = problem
    good = solve(C, gaps[0], approaches[-1], element_area=AREA, hardness=hardness,
                 options=SolverOptions(method="exact")).pressure.ravel()

    def score(pressure):
        return kkt_residual(C, gaps[0], approaches[-1], pressure, element_area=AREA,
                            hardness=hardness)

    assert score(good) < 1e-14
    saturated = np.flatnonzero(good >= hardness)[0]
    free = np.flatnonzero((good > 0) & (good < hardness))[0]
    for index, value in ((saturated, 1.01 * hardness), (saturated, 0.99 * hardness),
                         (free, 0.99 * good[free])):
        changed = good.copy()
        changed[index] = value
        assert score(changed) > 1e-6
    # without the cap the same field is far from the elastic solution
    assert kkt_residual(C, gaps[0], approaches[-1], good, element_area=AREA) > 1e-3


@pytest.mark.parametrize("bad", [0.0, -1e9, np.nan, -np.inf, "1e9", True, [1e9], object()])
def test_bad_hardness_names_argument(bad, problem):
    C, gaps, approaches, _ = problem
    calls = [
        lambda: solve(C, gaps[0], 1e-6, element_area=AREA, hardness=bad),
        lambda: solve_many(C, gaps, 1e-6, element_area=AREA, hardness=bad),
        lambda: sweep(C, gaps, approaches, element_area=AREA, hardness=bad),
        lambda: kkt_residual(C, gaps[0], 1e-6, np.zeros(N * N), element_area=AREA,
                             hardness=bad),
        lambda: tangent_stiffness(C, np.zeros(N * N), element_area=AREA, hardness=bad),
    ]
    for call in calls:
        with pytest.raises(ValueError, match="hardness"):
            call()
