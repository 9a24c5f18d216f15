"""The solvers refuse an influence operator that is not symmetric positive definite.

On an indefinite symmetric C whose negative direction stays out of the
contact set, "cg" and "steepest" (and pivoting, which factors only the
contact set's block) met their tolerance and returned converged=True:
Eq 27 is then not convex, and the KKT point they found proves nothing. The
entry points now certify the operator once (Cholesky, spectrum or a Lanczos
estimate, roughcontact.elasticity.definiteness) and refuse it with
estimates of its extreme eigenvalues, checked here against numpy's.
"""

import dataclasses

import numpy as np
import pytest

from roughcontact import contact
from roughcontact.contact import SolverOptions, nondim
from roughcontact.contact.methods import METHODS, REGISTRY
from roughcontact.contact.nondim import dimensionless_operator
from roughcontact.contact.products import Products
from roughcontact.elasticity import definiteness
from roughcontact.elasticity.halfspace import (
    PeriodicHalfSpace,
    SpectralHalfSpace,
    halfspace_influence,
)
from roughcontact.elasticity.influence import BlockGeometry, unit_modulus_influence
from roughcontact.elasticity.operators import block_operator, halfspace_operator
from roughcontact.elasticity.protocol import DenseInfluence
from roughcontact.errors import IndefiniteOperator

SIZE = (1e-3, 1e-3)  # m
AREA = SIZE[0] * SIZE[1] / 100  # m^2, a 10 x 10 grid
APPROACH = 3e-7  # m


def indefinite_problem():
    """Love's half-space on 10 x 10 elements with elements 0 and 99 coupled at twice
    their self-compliance (one negative eigenvalue), and heights that keep both out of
    contact at APPROACH."""
    matrix = halfspace_influence((10, 10), SIZE, 1.0, 0.0)
    matrix[0, 99] = matrix[99, 0] = 2.0 * matrix[0, 0]
    gap = np.random.default_rng(0).random(100) * 1e-6
    gap[[0, 99]] = 5e-6
    return matrix, gap


def iterate(method, matrix, gap):
    """The method's own iteration at APPROACH, past the entry checks (as before the fix)."""
    chosen = REGISTRY[method]
    products = Products.of(DenseInfluence(matrix, AREA), "double", chosen.single_precision)
    gaps = gap[None]
    return chosen.solve(products, gaps, np.full(1, APPROACH), np.zeros_like(gaps), 1e-10,
                        chosen.max_iter(None, gap.size))


def test_the_iterations_alone_meet_their_tolerance_on_the_indefinite_matrix():
    # the case of the issue: a tolerance met, on a problem that is not convex
    matrix, gap = indefinite_problem()
    eigenvalues = np.linalg.eigvalsh(matrix)
    assert eigenvalues[0] < 0 < eigenvalues[1]
    for method in ("cg", "steepest", "pivot"):
        batch = iterate(method, matrix, gap)
        assert batch.converged.all() and batch.residual.max() < 1e-10


@pytest.mark.parametrize("method", METHODS)
def test_every_method_refuses_an_indefinite_symmetric_matrix_with_its_eigenvalues(method):
    matrix, gap = indefinite_problem()
    eigenvalues = np.linalg.eigvalsh(matrix)
    calls = {
        "solve": lambda: contact.solve(matrix, gap, APPROACH, element_area=AREA,
                                       options=SolverOptions(method=method)),
        "solve_many": lambda: contact.solve_many(matrix, gap[None], APPROACH, element_area=AREA,
                                                 options=SolverOptions(method=method)),
        "sweep": lambda: contact.sweep(matrix, gap[None], [APPROACH, 2 * APPROACH],
                                       element_area=AREA, options=SolverOptions(method=method)),
    }
    for call in calls.values():
        with pytest.raises(IndefiniteOperator, match="operator must be positive definite") as info:
            call()
        assert info.value.smallest == pytest.approx(eigenvalues[0], rel=1e-9)
        assert info.value.largest == pytest.approx(eigenvalues[-1], rel=1e-9)
        assert f"smallest about {eigenvalues[0]:.4g} m/Pa" in str(info.value)
        assert "Cholesky factorization fails" in str(info.value)


@pytest.mark.parametrize("method", METHODS)
def test_every_method_refuses_a_non_symmetric_matrix_and_its_advice_works(method):
    matrix = halfspace_influence((10, 10), SIZE, 1.0, 0.0)
    gap = np.random.default_rng(1).random(100) * 1e-6
    lopsided = matrix.copy()
    lopsided[3, 40] *= 1.01
    with pytest.raises(ValueError, match=r"operator must be symmetric.*\(C \+ C\.T\) / 2"):
        contact.solve(lopsided, gap, APPROACH, element_area=AREA,
                      options=SolverOptions(method=method))
    with pytest.raises(ValueError, match="operator must be symmetric"):
        contact.sweep(lopsided, gap[None], [APPROACH], element_area=AREA,
                      options=SolverOptions(method=method))
    # the advice, followed literally
    result = contact.solve((lopsided + lopsided.T) / 2, gap, APPROACH, element_area=AREA,
                           options=SolverOptions(method=method))
    assert result.converged


class Wrapped:
    """A matrix-free view of ``matrix`` (optionally on a grid), as a user might pass."""

    def __init__(self, matrix, grid=None, mean_compliance=None):
        self._matrix = matrix
        self.shape = matrix.shape
        self.element_area = AREA
        self.grid = grid
        self.size = SIZE if grid is not None else None
        self.mean_compliance = mean_compliance
        self.products = 0

    def diagonal(self):
        return np.diag(self._matrix).copy()

    def matvec(self, pressure):
        self.products += 1 if np.ndim(pressure) == 1 else np.shape(pressure)[1]
        return self._matrix @ pressure


@pytest.mark.parametrize("grid", [(10, 10), None])
@pytest.mark.parametrize("method", ["cg", "steepest", "pcg", "auto"])
def test_a_matrix_free_indefinite_operator_is_refused_with_an_estimate(grid, method):
    matrix, gap = indefinite_problem()
    smallest = np.linalg.eigvalsh(matrix)[0]
    with pytest.raises(IndefiniteOperator, match="lanczos estimate") as info:
        contact.solve(Wrapped(matrix, grid), gap, APPROACH, options=SolverOptions(method=method))
    # a Rayleigh quotient: at least the smallest eigenvalue (to rounding), here within
    # 1e-6 of it
    assert smallest * (1 + 1e-12) <= info.value.smallest < 0
    assert info.value.smallest == pytest.approx(smallest, rel=1e-6)


@pytest.mark.parametrize("grid", [(10, 10), None])
def test_a_matrix_free_non_symmetric_operator_is_refused(grid):
    matrix = halfspace_influence((10, 10), SIZE, 1.0, 0.0)
    gap = np.random.default_rng(1).random(100) * 1e-6
    lopsided = matrix.copy()
    lopsided[:50, 50:] *= 1.01
    for method in ("cg", "pcg", "auto"):
        with pytest.raises(ValueError, match=r"operator must be symmetric.*x\.Cy - y\.Cx"):
            contact.solve(Wrapped(lopsided, grid), gap, APPROACH,
                          options=SolverOptions(method=method))
    assert contact.solve(Wrapped(matrix, grid), gap, APPROACH).converged


def test_a_slightly_indefinite_love_operator_is_found_at_256_x_256():
    # one pair of neighbours coupled at 1.01 times the self-compliance: an eigenvalue
    # of about -0.3 the smallest positive one, which plain Lanczos misses in 30 steps
    op = halfspace_operator((256, 256), (9e-3, 9e-3), 0.0)
    i = 128 * 256 + 128
    coupling = 1.01 * op.diagonal()[0]

    class Coupled:
        grid, size, shape, element_area = op.grid, op.size, op.shape, op.element_area

        def diagonal(self):
            return op.diagonal()

        def matvec(self, pressure):
            u = op.matvec(pressure)
            u[i] += coupling * pressure[i + 1]
            u[i + 1] += coupling * pressure[i]
            return u

    with pytest.raises(IndefiniteOperator) as info:
        definiteness.certify(Coupled())
    assert info.value.smallest < 0


def test_the_certificate_is_taken_once_and_kept_on_the_operator():
    matrix = halfspace_influence((10, 10), SIZE, 1.0, 0.0)
    gap = np.random.default_rng(2).random(100) * 1e-6
    operator = Wrapped(matrix, (10, 10))
    contact.solve(operator, gap, APPROACH, options=SolverOptions(method="cg"))
    certificate = operator.spd_certificate
    assert certificate.method == "preconditioned lanczos" and certificate.smallest > 0
    operator.products = 0
    result = contact.solve(operator, gap, APPROACH, options=SolverOptions(method="cg"))
    assert operator.products <= result.matvecs  # nothing spent on the certificate again
    dense = DenseInfluence(matrix, AREA)
    contact.solve(dense, gap, APPROACH)
    assert dense.spd_certificate.method == "cholesky"
    # the Cholesky pivots bound the smallest eigenvalue from above, the diagonal the largest
    eigenvalues = np.linalg.eigvalsh(matrix)
    assert eigenvalues[0] <= dense.spd_certificate.smallest
    assert dense.spd_certificate.largest <= eigenvalues[-1]


def test_a_zero_mean_operator_passes_on_the_complement_of_the_uniform_pressure():
    periodic = PeriodicHalfSpace((8, 8), SIZE, 1.0, 0.3)  # C 1 = 0
    kernel = periodic.matvec(np.eye(64))
    assert np.linalg.eigvalsh(kernel)[0] == pytest.approx(0.0, abs=1e-12 * kernel.max())
    certificate = definiteness.certify(Wrapped(kernel, (8, 8), mean_compliance=0.0))
    assert certificate.smallest > 0
    with pytest.raises(IndefiniteOperator):  # without the zero mode declared: singular
        definiteness.certify(Wrapped(kernel, (8, 8)))


def tiny_block(mesh):
    return BlockGeometry(size=(1.2e-3, 1.2e-3), thickness=2e-3, grid=(8, 8), mesh=mesh,
                         nu=0.3)


def study_operators():
    """Every kind of influence operator the study builds, on tiny grids."""
    return {
        "dense paper": unit_modulus_influence(tiny_block("paper")),
        "dense refined": unit_modulus_influence(tiny_block("refined")),
        "hybrid": block_operator(tiny_block("refined"), coarse_grid=(4, 4)),
        "halfspace": halfspace_operator((8, 8), (1.2e-3, 1.2e-3), 0.3),
        "love dense": halfspace_influence((8, 8), (1.2e-3, 1.2e-3), 1.0, 0.3),
        "periodic": PeriodicHalfSpace((8, 8), (1.2e-3, 1.2e-3), 1.0, 0.3),
        "periodic with mean": PeriodicHalfSpace((8, 8), (1.2e-3, 1.2e-3), 1.0, 0.3,
                                                mean_compliance=1e-3),
        "spectral": SpectralHalfSpace((8, 8), (1.2e-3, 1.2e-3), 1.0, 0.3),
    }


def test_every_operator_the_study_builds_is_certified():
    methods = {}
    for name, operator in study_operators().items():
        certificate = definiteness.certify(operator, name=name)
        assert certificate.smallest > 0, name
        methods[name] = certificate.method
        if not isinstance(operator, np.ndarray):
            assert operator.spd_certificate is certificate
            # the dimensionless view K = E C / L keeps it, scaled
            scaled = dimensionless_operator(operator, 2e-3)
            assert scaled.spd_certificate.smallest == pytest.approx(certificate.smallest / 2e-3)
    assert methods["dense paper"] == methods["dense refined"] == "cholesky"
    assert methods["hybrid"] == methods["halfspace"] == "preconditioned lanczos"
    assert methods["periodic"] == methods["spectral"] == "spectrum"


def test_a_dense_influence_keeps_its_certificate_under_another_element_area():
    matrix = halfspace_influence((10, 10), SIZE, 1.0, 0.0)
    dense = DenseInfluence(matrix, AREA)
    first = definiteness.certify(dense)
    other = contact.checks.as_operator(dense, 2 * AREA)
    assert other.element_area == 2 * AREA and other.spd_certificate is first
    assert dataclasses.replace(dense, element_area=2 * AREA).spd_certificate is None


def test_a_cell_sweep_refuses_an_indefinite_unit_influence_in_its_unit():
    matrix, _ = indefinite_problem()  # E = 1: E C [m]
    smallest = np.linalg.eigvalsh(matrix)[0]
    heights = np.random.default_rng(3).standard_normal((2, 10, 10))
    with pytest.raises(IndefiniteOperator, match="unit-modulus influence operator E C") as info:
        nondim.solve_cell(matrix, heights, thickness=2e-3, element_area=AREA,
                          approaches=[0.5, 1.0])
    assert f"smallest about {smallest:.4g} m," in str(info.value)


def test_a_periodic_operator_is_certified_by_its_spectrum_exactly():
    periodic = SpectralHalfSpace((8, 8), SIZE, 1.0, 0.3)
    spectrum = periodic.spectrum.copy()
    assert definiteness.certify(periodic).smallest == pytest.approx(spectrum.ravel()[1:].min())
    broken = SpectralHalfSpace((8, 8), SIZE, 1.0, 0.3)
    spectrum[2, 3] = -0.5 * spectrum.max()  # one negative eigenvalue
    object.__setattr__(broken, "spectrum", spectrum)
    with pytest.raises(IndefiniteOperator, match="its spectrum") as info:
        definiteness.certify(broken)
    assert info.value.smallest == spectrum[2, 3]


def test_a_known_spectrum_certifies_as_cholesky_does_and_refuses_alike():
    """from_eigenvalues (the build's spectrum, no second factorization): a definite
    matrix passes with numpy's extreme eigenvalues; the indefinite one and an
    asymmetric one are refused as certify refuses them."""
    matrix = halfspace_influence((10, 10), SIZE, 1.0, 0.0)
    values = np.linalg.eigvalsh(matrix)
    found = definiteness.from_eigenvalues(matrix, values)
    assert found.method == "spectrum" and found.smallest == values[0] > 0
    assert definiteness.certify(matrix).method == "cholesky"
    bad, _ = indefinite_problem()
    bad_values = np.linalg.eigvalsh(bad)
    with pytest.raises(IndefiniteOperator, match="its spectrum") as info:
        definiteness.from_eigenvalues(bad, bad_values, name="model X")
    assert "model X" in str(info.value) and info.value.smallest == bad_values[0] < 0
    lopsided = matrix.copy()
    lopsided[3, 40] *= 1.01
    with pytest.raises(ValueError, match="operator must be symmetric"):
        definiteness.from_eigenvalues(lopsided, values)


def test_a_singular_dense_matrix_is_refused_whatever_the_sign_of_its_last_pivot():
    """A matrix singular to rounding: the Cholesky factorization may succeed with a
    last pivot of either sign (it depends on the CPU's BLAS and FFT kernels); both
    are refused, with the same message. Built here with a zero mode of either sign
    of rounding size, so that both paths run on every CPU."""
    rng = np.random.default_rng(1)
    basis, _ = np.linalg.qr(rng.standard_normal((40, 40)))
    values = np.linspace(1.0, 2.0, 40)
    for last in (1e-14, -1e-14, 0.0):
        values[0] = last
        matrix = (basis * values) @ basis.T
        matrix = 0.5 * (matrix + matrix.T)
        with pytest.raises(IndefiniteOperator, match="Cholesky factorization") as info:
            definiteness.certify(matrix)
        assert abs(info.value.smallest) <= 1e-12 * info.value.largest


def periodic_dense(grid=(12, 10)):
    op = PeriodicHalfSpace(grid, SIZE, 1.0, 0.3, images=1)
    return op, op.matvec(np.eye(op.shape[0]))


def test_the_dense_form_of_a_periodic_operator_is_certified_without_its_zero_mode():
    """C 1 = 0 for the periodic half-space: its dense form is singular and refused
    as a plain matrix, but certified when it declares its zero mode
    (mean_compliance = 0), with the smallest eigenvalue on the complement of the
    uniform pressure (numpy's second smallest) as the bound from Cholesky."""
    op, matrix = periodic_dense()
    values = np.linalg.eigvalsh(matrix)
    assert abs(values[0]) <= 1e-12 * values[-1] < values[1]  # one zero mode, the rest > 0
    with pytest.raises(IndefiniteOperator):
        definiteness.certify(matrix)
    declared = DenseInfluence(matrix, op.element_area, mean_compliance=0.0)
    found = definiteness.certify(declared)
    assert found.method == "cholesky"
    assert values[1] * (1 - 1e-9) <= found.smallest  # the squared pivots bound it from above
    assert found.largest <= values[-1]


def test_a_declared_zero_mode_that_is_not_one_is_refused():
    matrix = halfspace_influence((6, 6), SIZE, 1.0, 0.0)  # rows sum to > 0
    with pytest.raises(ValueError, match="declared to have the uniform pressure as its zero"):
        definiteness.certify(DenseInfluence(matrix, AREA, mean_compliance=0.0))
    # an indefinite matrix whose rows do sum to zero stays refused: P - t v v^T with
    # v = e0 - e1 orthogonal to the uniform pressure, t beyond v.P v / |v|^4
    op, periodic = periodic_dense()
    v = np.zeros(periodic.shape[0])
    v[:2] = 1.0, -1.0
    bad = periodic - (v @ periodic @ v) * np.outer(v, v)
    assert np.linalg.eigvalsh(bad)[0] < -0.1 * np.abs(bad).max()
    with pytest.raises(IndefiniteOperator):
        definiteness.certify(DenseInfluence(bad, op.element_area, mean_compliance=0.0))

