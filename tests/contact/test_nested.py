"""Nested-grid continuation (roughcontact.contact.nested) gives the solution of a cold solve."""

import numpy as np
import pytest

from roughcontact import contact
from roughcontact.contact import SolverOptions, nested, pcg
from roughcontact.elasticity import operators
from roughcontact.elasticity.halfspace import SpectralHalfSpace

E, NU = 1.0e9, 0.3


def rough_gap(shape, seed, sigma=1e-6):
    ny, nx = shape
    rng = np.random.default_rng(seed)
    q = np.hypot(*np.meshgrid(np.fft.rfftfreq(nx) * nx, np.fft.fftfreq(ny) * ny))
    z = np.fft.irfft2(np.fft.rfft2(rng.standard_normal(shape)) / (1.0 + 0.05 * q**2), s=shape)
    z *= sigma / z.std()
    return z.max() - z


def hybrid(grid, size):
    a = np.random.default_rng(0).random((64, 64))
    return operators.BlockOperator(grid=grid, size=size, nu=NU, correction=(a + a.T) * 1e-3,
                                   coarse_grid=(8, 8))


def test_restriction_keeps_the_mean_and_injection_inverts_it():
    field = np.random.default_rng(1).random((6, 8))
    assert nested.restrict(field).mean() == pytest.approx(field.mean(), rel=1e-14)
    np.testing.assert_array_equal(nested.restrict(nested.prolong(field)), field)
    half = operators.halfspace_operator((128, 96), (1e-3, 1e-3), NU)
    assert nested.coarse_levels(half, 24) == 2 and nested.coarse_levels(half, 64) == 0


@pytest.mark.parametrize("control", ["approach", "mean_pressure"])
@pytest.mark.parametrize("build", [
    lambda g, s: operators.halfspace_operator(g, s, NU),
    lambda g, s: SpectralHalfSpace(g, s, E, NU),
    hybrid,
], ids=["halfspace", "spectral", "hybrid"])
def test_nested_and_cold_solves_agree(build, control):
    grid, size = (128, 96), (1.6e-3, 1.2e-3)
    op = build(grid, size)
    gap = rough_gap((96, 128), seed=2)
    value = {"approach": 0.5 * gap.mean(), "mean_pressure": None}[control]
    if value is None:  # a load giving about the same contact
        value = pcg.constrained_pcg(op, gap, approach=0.5 * gap.mean(), tol=1e-6).pressure.mean()

    def solve_level(level, level_gap, level_tol, start):
        return pcg.solve_steps(level, level_gap, tol=level_tol, pressure0=start,
                               **{control: value})

    cold = pcg.run_solves([solve_level(op, gap, 1e-10, None)])[0]
    levels = nested.level_operators(op, coarsest=24)
    assert [level.grid for level in levels] == [(128, 96), (64, 48), (32, 24)]
    warm, coarse_work = pcg.run_solves([nested.nested_solve(solve_level, levels, gap,
                                                            tol=1e-10)])[0]
    assert coarse_work > 0.0 and cold.residual <= 1e-10 and warm.residual <= 1e-10
    assert 0.01 < np.mean(cold.pressure > 0) < 0.5
    np.testing.assert_array_equal(warm.pressure > 0, cold.pressure > 0)
    assert np.abs(warm.pressure - cold.pressure).max() <= 1e-7 * cold.pressure.max()
    assert warm.approach == pytest.approx(cold.approach, rel=1e-7)


def test_solve_starts_large_cold_grids_from_coarse_levels():
    """Above NESTED_MIN_ELEMENTS contact.solve runs the nested solve: the same answer as a
    cold solve, the coarse products counted in matvecs."""
    grid, size = (192, 128), (2.4e-3, 1.6e-3)
    assert grid[0] * grid[1] > pcg.NESTED_MIN_ELEMENTS
    op = operators.halfspace_operator(grid, size, NU)
    gap = rough_gap((128, 192), seed=3)
    result = contact.solve(op, gap, 0.4 * gap.mean(),
                           options=SolverOptions(tol=1e-10, precision="mixed"))
    cold = pcg.constrained_pcg(op, gap, approach=0.4 * gap.mean(), tol=1e-10)
    assert result.method == "pcg" and result.converged
    np.testing.assert_array_equal(result.contact_set, cold.pressure > 0)
    assert np.abs(result.pressure - cold.pressure).max() <= 1e-7 * cold.pressure.max()
    assert result.matvecs >= result.iterations
