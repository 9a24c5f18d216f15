"""The preconditioned constrained CG (roughcontact.contact.pcg) against independent solves.

References: block principal pivoting on the same operator's dense matrix,
scipy's NNLS on the Cholesky-transformed problem (min 1/2 |L^T p - L^-1 b|^2
over p >= 0, C = L L^T, b = d - f, the same minimizer as Eq 27) and the
Hertz closed form.
"""

import logging

import numpy as np
import pytest
import scipy.linalg
import scipy.optimize

from roughcontact import contact
from roughcontact.contact import SolverOptions, pcg, stiffness
from roughcontact.contact.nondim import dimensionless_operator
from roughcontact.contact.products import Products
from roughcontact.elasticity import operators
from roughcontact.elasticity.halfspace import (
    PeriodicHalfSpace,
    SpectralHalfSpace,
    halfspace_influence,
)
from roughcontact.elasticity.protocol import DenseInfluence

E, NU = 1.0e9, 0.3
E_STAR = E / (1.0 - NU**2)
SIZE = (1.2e-3, 1.0e-3)


def rough_gap(shape, seed, sigma=1e-6):
    """A smooth random surface's initial separation ``max z - z`` [m]."""
    ny, nx = shape
    rng = np.random.default_rng(seed)
    q = np.hypot(*np.meshgrid(np.fft.rfftfreq(nx) * nx, np.fft.fftfreq(ny) * ny))
    z = np.fft.irfft2(np.fft.rfft2(rng.standard_normal(shape)) / (1.0 + q**2), s=shape)
    z *= sigma / z.std()
    return z.max() - z


def nnls_reference(C, gap0, approach):
    """Independent solution of Eq 27 by NNLS on the Cholesky factor of C."""
    factor = np.linalg.cholesky(C)
    target = scipy.linalg.solve_triangular(factor, approach - np.ravel(gap0), lower=True)
    pressure, _ = scipy.optimize.nnls(factor.T, target, maxiter=50 * C.shape[0])
    return pressure


def hybrid(grid=(24, 20)):
    """A block operator with a smooth symmetric positive correction."""
    rng = np.random.default_rng(0)
    a = rng.random((30, 30))
    return operators.BlockOperator(grid=grid, size=SIZE, nu=NU, correction=(a + a.T) * 1e-3,
                                   coarse_grid=(6, 5))


OPERATORS = {
    "halfspace": lambda: operators.halfspace_operator((24, 20), SIZE, NU),
    "hybrid": hybrid,
    "periodic": lambda: PeriodicHalfSpace((24, 20), SIZE, E, NU, images=1),
    "spectral": lambda: SpectralHalfSpace((24, 20), SIZE, E, NU),
}


@pytest.mark.parametrize("precision", ["mixed", "double"])
@pytest.mark.parametrize("name", list(OPERATORS))
def test_pcg_equals_pivoting_on_the_dense_matrix(name, precision):
    op = OPERATORS[name]()
    # the dense form keeps what the operator declares of its row sums: the periodic
    # one's zero mode (mean_compliance = 0) is certified as such, not by the sign of
    # its rounding-size last pivot (which differs between CPUs)
    dense = DenseInfluence(op.matvec(np.eye(op.shape[0])), op.element_area,
                           mean_compliance=getattr(op, "mean_compliance", None))
    gap = rough_gap((20, 24), seed=3)
    for fraction in (0.1, 0.3, 0.45):  # approaches below the mean gap (periodic operators)
        d = fraction * gap.mean() * 2.0
        ours = contact.solve(op, gap, d,
                             options=SolverOptions(method="pcg", tol=1e-10, precision=precision))
        reference = contact.solve(dense, gap, d, element_area=op.element_area,
                                  options=SolverOptions(method="pivot", tol=1e-13))
        assert ours.converged and ours.method == "pcg" and ours.residual <= 1e-10
        assert 0.01 < reference.real_area_fraction < 0.9
        np.testing.assert_array_equal(ours.contact_set, reference.contact_set)
        assert np.abs(ours.pressure - reference.pressure).max() <= 1e-7 * reference.max_pressure
        assert ours.approach == d


def test_pcg_equals_scipy_nnls():
    op = operators.halfspace_operator((16, 14), SIZE, NU)
    dense = op.matvec(np.eye(op.shape[0]))
    gap = rough_gap((14, 16), seed=5)
    d = 0.8 * gap.mean()
    ours = contact.solve(op, gap, d,
                         options=SolverOptions(method="pcg", tol=1e-11, precision="mixed"))
    reference = nnls_reference(dense, gap, d).reshape(gap.shape)
    np.testing.assert_array_equal(ours.pressure > 0, reference > 0)
    assert np.abs(ours.pressure - reference).max() <= 1e-7 * reference.max()


def test_pcg_hertz_on_a_fine_halfspace_grid():
    """Rigid sphere on Love's half-space: contact radius, peak pressure and load of Hertz
    at the approach d = a^2 / R (nested grids from 64^2 up to 256^2)."""
    n, dx, radius = 256, 0.5e-6, 1e-2
    a = 48 * dx
    op = operators.halfspace_operator((n, n), (n * dx, n * dx), NU)  # E = 1 Pa
    x = (np.arange(n) - n // 2 + 0.5) * dx
    gap = (x[None, :] ** 2 + x[:, None] ** 2) / (2.0 * radius)
    result = contact.solve(op, gap, a**2 / radius,
                           options=SolverOptions(tol=1e-9, precision="mixed"))
    assert result.method == "pcg" and result.converged
    e_star = 1.0 / (1.0 - NU**2)
    load = 4.0 / 3.0 * e_star * np.sqrt(radius) * (a**2 / radius) ** 1.5
    area = np.count_nonzero(result.pressure) * dx * dx
    assert np.sqrt(area / np.pi) == pytest.approx(a, rel=0.01)
    assert result.load == pytest.approx(load, rel=0.01, abs=0.0)  # [N] at E = 1 Pa: ~2e-12
    assert result.max_pressure == pytest.approx(3 * load / (2 * np.pi * a**2), rel=0.01)


def test_pcg_reports_non_convergence(caplog):
    op = operators.halfspace_operator((24, 20), SIZE, NU)
    gap = rough_gap((20, 24), seed=4)
    with caplog.at_level(logging.WARNING, logger="roughcontact.contact"):
        result = contact.solve(op, gap, gap.mean(),
                               options=SolverOptions(method="pcg", tol=1e-12, max_iter=2,
                                                     retries=False))
    assert not result.converged and result.iterations == 2
    assert result.residual > 1e-12
    assert result.residual == pytest.approx(
        contact.kkt_residual(op, gap, result.approach, result.pressure), rel=1e-6)
    assert "did not converge" in caplog.text


def test_auto_chooses_pcg_for_grid_operators_only():
    half = operators.halfspace_operator((8, 8), SIZE, NU)
    resolve = contact.resolve_method
    assert resolve("auto", half) == "pcg"
    assert resolve("auto", hybrid()) == "pcg"
    assert resolve("auto", SpectralHalfSpace((8, 8), SIZE, E, NU)) == "pcg"
    assert resolve("auto", dimensionless_operator(hybrid(), 1e-2)) == "pcg"
    assert resolve("auto", half.to_dense()) == "pivot"
    assert resolve("auto", half, 1e6) == "cg"  # capped: CG takes the cap
    assert resolve("auto", half, np.inf) == "pcg"


def test_pcg_refuses_a_cap_and_solves_a_dense_matrix_unpreconditioned():
    half = operators.halfspace_operator((8, 8), SIZE, NU)
    gap = rough_gap((8, 8), seed=1)
    with pytest.raises(ValueError, match="method='cg'"):
        contact.solve(half, gap, gap.mean(), hardness=1e-6, options=SolverOptions(method="pcg"))
    dense = contact.solve(half.to_dense(), gap.ravel(), gap.mean(), element_area=half.element_area,
                          options=SolverOptions(method="pcg", tol=1e-11, precision="mixed"))
    reference = nnls_reference(half.to_dense(), gap, gap.mean())
    assert dense.converged
    np.testing.assert_array_equal(dense.pressure > 0, reference > 0)
    assert np.abs(dense.pressure - reference).max() <= 1e-7 * reference.max()
    # auto on a capped problem is CG, which honours the cap
    capped = contact.solve(half, gap, gap.mean(), hardness=1e-6, options=SolverOptions(tol=1e-9))
    assert capped.method == "cg" and capped.converged and capped.max_pressure <= 1e-6


def test_constrained_pcg_at_zero_load_touches_the_highest_point():
    op = operators.halfspace_operator((8, 8), SIZE, NU)
    gap = rough_gap((8, 8), seed=2)
    solution = pcg.constrained_pcg(op, gap, mean_pressure=0.0)
    assert not solution.pressure.any() and solution.approach == gap.min()


@pytest.mark.parametrize("name", ["halfspace", "hybrid", "spectral"])
def test_preconditioned_tangent_stiffness_equals_the_dense_solve(name):
    """dF/dd = dA 1^T (C_AA)^-1 1: the stencil-preconditioned free-set CG of a grid operator
    against a dense linear solve on the contact set."""
    op = OPERATORS[name]()
    gap = rough_gap((20, 24), seed=8)
    result = contact.solve(op, gap, 0.6 * gap.mean(), options=SolverOptions(tol=1e-10))
    stiffness = contact.tangent_stiffness(op, result.pressure, tol=1e-12)
    contact_set = np.flatnonzero(result.pressure.ravel() > 0)
    dense = op.matvec(np.eye(op.shape[0]))[np.ix_(contact_set, contact_set)]
    expected = op.element_area * np.linalg.solve(dense, np.ones(contact_set.size)).sum()
    assert stiffness == pytest.approx(expected, rel=1e-9)


@pytest.mark.parametrize("name", ["halfspace", "hybrid", "periodic", "spectral", "dense"])
@pytest.mark.parametrize("tol", [1e-3, 1e-5, 1e-7])
def test_stiffness_tol_bounds_the_stiffness_error(name, tol):
    """stiffness_tol is the relative error of dF/dd: at each tol the tangent stiffness
    of a grid operator (stencil estimate) and of its dense matrix (no preconditioner,
    diagonal estimate) is below the dense linear solve's and within tol of it, on the
    contact set of a rough contact at 7 % contact."""
    op = OPERATORS["hybrid" if name == "dense" else name]()
    gap = rough_gap((20, 24), seed=8)
    result = contact.solve(op, gap, 0.6 * gap.mean(), options=SolverOptions(tol=1e-10))
    contact_set = np.flatnonzero(result.pressure.ravel() > 0)
    matrix = op.matvec(np.eye(op.shape[0]))
    expected = op.element_area * np.linalg.solve(matrix[np.ix_(contact_set, contact_set)],
                                                 np.ones(contact_set.size)).sum()
    body = DenseInfluence(0.5 * (matrix + matrix.T), op.element_area) if name == "dense" \
        else op
    found = contact.tangent_stiffness(body, result.pressure, tol=tol)
    assert -1e-12 * expected <= expected - found <= tol * expected


@pytest.fixture(scope="module")
def paper_mesh_contact():
    """The paper mesh's finite-element E * C (24 x 24 over 4.8 mm, 10 mm thick, nu 0),
    whose strongly coupled neighbours defeat a diagonal error estimate, and a rough
    contact on it (3 % contact, the approach at the mean gap)."""
    from roughcontact.elasticity.influence import BlockGeometry, unit_modulus_influence

    geometry = BlockGeometry(size=(4.8e-3, 4.8e-3), thickness=1e-2, grid=(24, 24), E=1.0,
                             nu=0.0, mesh="paper")
    unit = unit_modulus_influence(geometry)
    unit = 0.5 * (unit + unit.T)
    body = DenseInfluence(unit, geometry.element_area)
    gap = rough_gap((24, 24), seed=0)
    result = contact.solve(body, gap.ravel(), gap.mean(), options=SolverOptions(tol=1e-12))
    return body, unit, result.pressure


@pytest.mark.parametrize("tol", [1e-3, 1e-5, 1e-7])
def test_stiffness_tol_bounds_the_stiffness_error_on_the_paper_mesh(paper_mesh_contact, tol):
    """The diagonal error estimate of a dense matrix without a preconditioner, with its
    safety factor, keeps dF/dd within tol of the dense solve on a finite-element matrix
    (a factor 4 let the error reach 1.7 tol here)."""
    body, unit, pressure = paper_mesh_contact
    contact_set = np.flatnonzero(pressure > 0)
    expected = body.element_area * np.linalg.solve(unit[np.ix_(contact_set, contact_set)],
                                                   np.ones(contact_set.size)).sum()
    found = contact.tangent_stiffness(body, pressure, tol=tol)
    assert -1e-12 * expected <= expected - found <= tol * expected


def _dense_products(grid=(8, 8), precision="double"):
    """The dense Love matrix (exactly symmetric, equal diagonal) and its products."""
    matrix = halfspace_influence(grid, SIZE[:1] * 2, E, NU)
    area = (SIZE[0] / grid[0]) ** 2
    return matrix, Products.of(DenseInfluence(matrix, area, grid), precision)


@pytest.mark.parametrize("precision", ["double", "mixed"])
def test_degenerate_steps_in_a_batch_end_at_the_nnls_solution(precision, monkeypatch):
    """A batch whose first surface starts on two equal summits with equal pressures (the
    residual is constant on the free set: the preconditioned residual z vanishes and the
    step only activates the penetrating elements), whose second starts from one element
    (a one-element free set) and whose third is a plain warm start: every surface ends
    converged at the NNLS solution."""
    matrix, products = _dense_products(precision=precision)
    gaps = np.stack([rough_gap((8, 8), seed=s) for s in (11, 12, 13)])
    summits = [(2, 2), (5, 5)]  # the two highest points, exactly as high
    for iy, ix in summits:
        gaps[0, iy, ix] = 0.0
    d = 0.5 * gaps.mean(axis=(1, 2))
    start = np.zeros((3, 64))
    start[0, [8 * iy + ix for iy, ix in summits]] = 1.0
    start[1, int(np.argmin(gaps[1]))] = 1.0
    start[2] = nnls_reference(matrix, gaps[2], 0.9 * d[2])  # the solution at a lower approach
    vanished = []
    descend = pcg._Iteration._descend

    def recorded(self):
        out = yield from descend(self)
        vanished.append(out is None)
        return out

    monkeypatch.setattr(pcg._Iteration, "_descend", recorded)
    batch = pcg.solve(products, gaps.reshape(3, -1), d, start, 1e-11, 1000)
    assert any(vanished)  # the degenerate step was taken
    assert batch.converged.all() and (batch.residual <= 1e-11).all()
    for j in range(3):
        reference = nnls_reference(matrix, gaps[j], d[j])
        np.testing.assert_array_equal(batch.pressure[j] > 0, reference > 0)
        assert np.abs(batch.pressure[j] - reference).max() <= 1e-7 * reference.max()
        assert (reference > 0).sum() > 2  # contact spread beyond the starting elements


def test_surfaces_solved_together_equal_surfaces_solved_alone():
    """The batched products change nothing per surface: each keeps its iterations,
    products, residual and contact set, and the pressures agree to rounding."""
    op = operators.halfspace_operator((24, 20), SIZE, NU)
    products = Products.of(op, "mixed")
    gaps = np.stack([rough_gap((20, 24), seed=s).ravel() for s in (21, 22, 23, 24)])
    d = np.array([0.2, 0.4, 0.6, 0.8]) * gaps.mean(axis=1)
    start = np.zeros_like(gaps)
    together = pcg.solve(products, gaps, d, start, 1e-10, 1000)
    for j in range(4):
        alone = pcg.solve(products, gaps[j:j + 1], d[j:j + 1], start[j:j + 1], 1e-10, 1000)
        assert together.iterations[j] == alone.iterations[0]
        assert together.matvecs[j] == alone.matvecs[0] and together.converged[j]
        np.testing.assert_array_equal(together.pressure[j] > 0, alone.pressure[0] > 0)
        assert np.abs(together.pressure[j] - alone.pressure[0]).max() <= \
            1e-12 * alone.pressure[0].max()


def test_free_set_cg_keeps_each_surface_s_own_test():
    """The stiffness CG solves C_FF x = 1 on each surface's free set, the surfaces
    together: each surface's total 1^T C_FF^-1 1 meets tol (relative) against the
    dense solve, from below (the variational estimate errs by r^T C_FF^-1 r >= 0), or,
    out of iterations, the surface reports that it did not; an empty free set has
    x = 0 and counts as met."""
    op = operators.halfspace_operator((24, 20), SIZE, NU)
    dense = op.to_dense()
    rng = np.random.default_rng(7)
    free = np.zeros((3, op.shape[0]), dtype=bool)
    free[0, rng.choice(op.shape[0], 60, replace=False)] = True
    free[1, 5] = True  # one element: x = 1 / C_ii in one step
    products = Products.of(op, "mixed")
    x, converged, count, total = stiffness.free_set_cg(products, free, np.zeros(free.shape),
                                                       1e-9, 1000)
    assert converged.all() and count[2] == 0 and not x[2].any() and total[2] == 0.0
    for j in range(2):
        cells = np.flatnonzero(free[j])
        expected = np.linalg.solve(dense[np.ix_(cells, cells)], np.ones(cells.size))
        assert 0.0 <= expected.sum() - total[j] <= 1e-9 * expected.sum() + 1e-12 * total[j]
        assert np.abs(x[j, cells] - expected).max() <= 1e-3 * np.abs(expected).max()
        assert not x[j, ~free[j]].any()
    x, converged, count, _ = stiffness.free_set_cg(products, free, np.zeros(free.shape), 1e-9,
                                                   2)
    assert list(converged) == [False, True, True] and count[0] <= 4
