"""Load control (mean pressure given) against displacement control at the same mean pressure."""

import numpy as np
import pytest

from roughcontact import contact
from roughcontact.elasticity import operators
from roughcontact.elasticity.halfspace import SpectralHalfSpace

E, NU = 1.0e9, 0.3
SIZE = (1.2e-3, 1.0e-3)


def rough_gaps(count, shape, seed, sigma=1e-6):
    """Smooth random surfaces' initial separations ``max z - z`` [m], (count, ny, nx)."""
    ny, nx = shape
    rng = np.random.default_rng(seed)
    q = np.hypot(*np.meshgrid(np.fft.rfftfreq(nx) * nx, np.fft.fftfreq(ny) * ny))
    z = np.fft.irfft2(np.fft.rfft2(rng.standard_normal((count, ny, nx))) / (1 + q**2),
                      s=shape)
    z *= sigma / z.std(axis=(1, 2), keepdims=True)
    return z.max(axis=(1, 2), keepdims=True) - z


CASES = {
    "pcg-halfspace": (lambda: operators.halfspace_operator((24, 20), SIZE, NU), "pcg"),
    "pcg-spectral": (lambda: SpectralHalfSpace((24, 20), SIZE, E, NU), "pcg"),
    "cg-spectral": (lambda: SpectralHalfSpace((24, 20), SIZE, E, NU), "cg"),
    "pivot-dense": (lambda: operators.halfspace_operator((24, 20), SIZE, NU).to_dense(), "pivot"),
}


def _same(loaded, displaced, tol):
    np.testing.assert_array_equal(loaded.contact_set, displaced.contact_set)
    assert np.abs(loaded.pressure - displaced.pressure).max() <= tol * displaced.max_pressure
    assert loaded.approach == pytest.approx(displaced.approach, rel=tol)


@pytest.mark.parametrize("case", list(CASES))
def test_load_controlled_solve_equals_displacement_controlled(case):
    build, method = CASES[case]
    op = build()
    area = (SIZE[0] / 24) * (SIZE[1] / 20)
    gap = rough_gaps(1, (20, 24), seed=11)[0]
    for fraction in (0.2, 0.6):
        d = fraction * gap.mean()
        displaced = contact.solve(op, gap, d, method=method, tol=1e-11, element_area=area)
        loaded = contact.solve(op, gap, mean_pressure=displaced.nominal_pressure, method=method,
                               tol=1e-11, element_area=area)
        assert loaded.converged and loaded.method == method
        assert 0.005 < displaced.real_area_fraction < 0.9
        assert loaded.nominal_pressure == pytest.approx(displaced.nominal_pressure, rel=1e-9)
        _same(loaded, displaced, 1e-6)


@pytest.mark.parametrize("case", ["pcg-halfspace", "pivot-dense"])
def test_load_controlled_sweep_equals_displacement_controlled(case):
    build, method = CASES[case]
    op = build()
    area = (SIZE[0] / 24) * (SIZE[1] / 20)
    gaps = rough_gaps(2, (20, 24), seed=12)
    approaches = np.array([0.1, 0.3, 0.5]) * gaps.mean()
    displaced = contact.sweep(op, gaps, approaches, method=method, tol=1e-11, element_area=area,
                              return_fields=True)
    loaded = contact.sweep(op, gaps, mean_pressures=displaced.nominal_pressure, method=method,
                           tol=1e-11, element_area=area, return_fields=True)
    assert loaded.converged.all() and loaded.method == method
    np.testing.assert_array_equal(loaded.pressure > 0, displaced.pressure > 0)
    assert np.abs(loaded.pressure - displaced.pressure).max() <= 1e-6 * displaced.pressure.max()
    np.testing.assert_allclose(loaded.approach, displaced.approach, rtol=1e-6)
    np.testing.assert_allclose(loaded.contact_stiffness, displaced.contact_stiffness, rtol=1e-5)


def test_zero_load_touches_and_exactly_one_control_is_required():
    op = operators.halfspace_operator((8, 8), SIZE, NU)
    gap = rough_gaps(1, (8, 8), seed=13)[0]
    for method in ("pcg", "cg"):
        idle = contact.solve(op, gap, mean_pressure=0.0, method=method)
        assert idle.converged and idle.load == 0.0 and idle.approach == gap.min()
    with pytest.raises(ValueError, match="exactly one of approach"):
        contact.solve(op, gap)
    with pytest.raises(ValueError, match="exactly one of approach"):
        contact.solve(op, gap, 1e-7, mean_pressure=1e3)
    with pytest.raises(ValueError, match="exactly one of approaches"):
        contact.sweep(op, gap[None], [1e-7], mean_pressures=[1e3])
    with pytest.raises(ValueError, match="mean_pressure must be finite and non-negative"):
        contact.solve(op, gap, mean_pressure=-1.0)
