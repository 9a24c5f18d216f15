"""Iterative contact solves refuse an influence matrix that is not positive definite.

Eq 27 is a convex problem only for a positive definite C. With one negative
eigenvalue, "cg" and "steepest" used to meet a search direction s with
s.C s <= 0, skip its step and still report converged=True without a warning,
while "exact" refuses (its Cholesky factorization fails). The entry points
now refuse such a matrix before any iteration (its certificate,
tests/contact/test_definiteness.py); the curvature the iterative methods
compute stays a second line (a Lanczos certificate is an estimate), tested
here on the methods themselves: they must raise the same kind of error
(ValueError, "operator must be positive definite") from that curvature.

The two 3 x 3 matrices below are symmetric with a positive diagonal (so they
pass the input checks) and one negative eigenvalue, checked here with numpy;
on them the search direction of the named method meets negative curvature.
"""

import logging

import numpy as np
import pytest

from roughcontact import contact
from roughcontact.contact import SolverOptions
from roughcontact.contact.methods import REGISTRY
from roughcontact.contact.products import Products
from roughcontact.elasticity.protocol import DenseInfluence

#: cg meets negative curvature at its third iteration (eigenvalues -0.37, 1.11, 4.26).
CG_MATRIX = np.array([[1.0, -0.5, 0.0], [-0.5, 1.0, 2.0], [0.0, 2.0, 3.0]])
CG_GAP = np.array([0.0, 1.0, 0.0])
#: steepest descent meets it (eigenvalues -1.15, 3, 4.15).
STEEPEST_MATRIX = np.array([[3.0, -1.5, 1.5], [-1.5, 2.0, 1.5], [1.5, 1.5, 1.0]])
STEEPEST_GAP = np.array([2.0, 0.0, 1.0])
APPROACH = 2.0  # m, with the gaps above: every element starts in interference

CASES = [("cg", CG_MATRIX, CG_GAP), ("steepest", STEEPEST_MATRIX, STEEPEST_GAP)]
REFUSAL = r"operator must be positive definite"


def test_the_matrices_are_symmetric_indefinite_with_a_positive_diagonal():
    for _, matrix, _ in CASES:
        assert np.array_equal(matrix, matrix.T)
        assert (np.diag(matrix) > 0).all()
        eigenvalues = np.linalg.eigvalsh(matrix)
        assert eigenvalues[0] < -0.3 and eigenvalues[1] > 0.0


@pytest.mark.parametrize(("method", "matrix", "gap"), CASES)
def test_exact_refuses_these_matrices(method, matrix, gap):
    with pytest.raises(ValueError, match=REFUSAL):
        contact.solve(matrix, gap, APPROACH, element_area=1.0,
                      options=SolverOptions(method="exact"))


def _iterate(method, matrix, gaps, approach=APPROACH, precision="double", p0=None,
             max_iter=1000):
    """The method's own iteration on ``gaps`` (rows) at ``approach``, past the entry checks."""
    chosen = REGISTRY[method]
    products = Products.of(DenseInfluence(matrix, 1.0), precision, chosen.single_precision)
    gaps = np.atleast_2d(np.asarray(gaps, dtype=float))
    pressure = np.zeros_like(gaps) if p0 is None else np.atleast_2d(p0).astype(float)
    d = np.full(gaps.shape[0], approach)
    return chosen.solve(products, gaps, d, pressure, 1e-10, max_iter)


@pytest.mark.parametrize(("method", "matrix", "gap"), CASES)
def test_iteration_refuses_negative_curvature(method, matrix, gap):
    with pytest.raises(ValueError, match=REFUSAL + r".*non-positive curvature") as info:
        _iterate(method, matrix, gap)
    assert method in str(info.value)


@pytest.mark.parametrize(("method", "matrix", "gap"), CASES)
def test_entry_points_refuse_these_matrices_before_iterating(method, matrix, gap):
    with pytest.raises(ValueError, match=REFUSAL + r".*smallest about -"):
        contact.solve(matrix, gap, APPROACH, element_area=1.0, options=SolverOptions(method=method))


def test_mixed_precision_refuses_negative_curvature():
    # Single-precision products take another path; where it meets the negative
    # direction the refusal is confirmed in double precision.
    with pytest.raises(ValueError, match=REFUSAL):
        _iterate("cg", CG_MATRIX, CG_GAP, precision="mixed")
    # From this warm start the first steepest direction is (-1, 1), curvature -2.
    matrix = np.array([[1.0, 2.0], [2.0, 1.0]])
    with pytest.raises(ValueError, match=REFUSAL + r".*s\.C s / s\.s = -1 "):
        _iterate("steepest", matrix, np.array([0.0, 3.0]), 3.0, p0=np.array([0.0, 1.0]),
                 precision="mixed", max_iter=50)


@pytest.mark.parametrize(("method", "matrix", "gap"), CASES)
def test_batched_iteration_names_the_surface_with_negative_curvature(method, matrix, gap):
    # surface 0 stays clear of the matrix's negative direction (one element in contact)
    clear = np.array([0.0, 5.0, 5.0])
    with pytest.raises(ValueError, match=REFUSAL + r".*surface 1 "):
        _iterate(method, matrix, np.stack([clear, gap]))


@pytest.mark.parametrize(("method", "matrix", "gap"), CASES)
def test_sweep_refuses_negative_curvature(method, matrix, gap):
    with pytest.raises(ValueError, match=REFUSAL):
        contact.sweep(matrix, gap[None], [APPROACH, 1.5 * APPROACH], element_area=1.0,
                      options=SolverOptions(method=method))


class _CountingOperator:
    """A matrix-free view of a dense matrix that counts the pressure fields it is applied to."""

    def __init__(self, matrix):
        self.matrix = matrix
        self.shape = matrix.shape
        self.element_area = 1.0
        self.products = 0

    def diagonal(self):
        return np.diag(self.matrix).copy()

    def matvec(self, pressure):
        self.products += 1 if pressure.ndim == 1 else pressure.shape[1]
        return self.matrix @ pressure


@pytest.mark.parametrize(("method", "condition"), [("cg", 1e6), ("steepest", 1e2)])
def test_positive_definite_solves_are_unchanged(method, condition, caplog):
    # An SPD matrix: no refusal, no warning, the "exact" solution, and no
    # product beyond those the solver reports (the certificate of the
    # operator, taken by its first solve, is not taken again).
    rng = np.random.default_rng(7)
    n = 40
    basis, _ = np.linalg.qr(rng.standard_normal((n, n)))
    matrix = (basis * np.logspace(0.0, -np.log10(condition), n)) @ basis.T
    matrix = 0.5 * (matrix + matrix.T)
    gaps = rng.uniform(0.0, 1.0, (3, n))
    reference = contact.solve_many(matrix, gaps, 0.5, element_area=1.0,
                                   options=SolverOptions(method="exact"))
    operator = _CountingOperator(matrix)
    # certified once
    contact.solve_many(operator, gaps[:1], 0.5, options=SolverOptions(method=method, tol=1e-9))
    operator.products = 0
    with caplog.at_level(logging.WARNING, logger="roughcontact.contact"):
        results = contact.solve_many(operator, gaps, 0.5,
                                     options=SolverOptions(method=method, tol=1e-9))
        mixed = contact.solve_many(matrix, gaps, 0.5, element_area=1.0,
                                   options=SolverOptions(method=method, tol=1e-9,
                                                         precision="mixed"))
    assert not caplog.records
    for result, fast, exact in zip(results, mixed, reference, strict=True):
        assert result.converged and fast.converged
        scale = np.abs(exact.pressure).max()
        np.testing.assert_allclose(result.pressure, exact.pressure, rtol=0, atol=1e-5 * scale)
        np.testing.assert_allclose(fast.pressure, exact.pressure, rtol=0, atol=1e-5 * scale)
    assert operator.products <= sum(r.matvecs for r in results)
