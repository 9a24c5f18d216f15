"""The closed forms of roughcontact.contact.references against their own defining laws."""

import numpy as np
import pytest

from roughcontact.contact.references import hertz, sphere_gap, westergaard_pressure


def test_hertz_satisfies_its_force_law_and_pressure_integral():
    # F = 4/3 E* R^1/2 d^3/2 (Johnson Eq 4.23) and the integral of
    # p0 sqrt(1 - r^2/a^2) over the contact is F
    solution = hertz(load=2.0, radius=5e-3, e_star=1.1e11)
    force = 4.0 / 3.0 * 1.1e11 * np.sqrt(5e-3) * solution.d**1.5
    assert force / 2.0 == pytest.approx(1.0, rel=1e-12)
    r = np.linspace(0.0, solution.a, 200001)
    integrand = solution.p0 * np.sqrt(np.clip(1 - (r / solution.a) ** 2, 0, None)) * r
    assert 2 * np.pi * np.trapezoid(integrand, r) / 2.0 == pytest.approx(1.0, rel=1e-6)


@pytest.mark.parametrize("fraction", [0.1, 0.5, 0.9])
def test_westergaard_pressure_carries_its_mean_and_vanishes_outside(fraction):
    wavelength, mean_pressure = 1e-3, 3e6
    half_width = fraction * wavelength / 2
    s = np.linspace(-wavelength / 2, wavelength / 2, 400001)
    p = westergaard_pressure(s, wavelength, half_width, mean_pressure)
    assert np.trapezoid(p, s) / wavelength / mean_pressure == pytest.approx(1.0, rel=1e-4)
    assert (p[np.abs(s) > half_width] == 0.0).all()
    assert (p[np.abs(s) < half_width * (1 - 1e-6)] > 0).all()


def test_sphere_gap_is_centred_and_parabolic():
    gap = sphere_gap(4, 1e-6, 1e-2)
    assert gap[1, 1] == gap[2, 2] == gap[1, 2]
    assert gap[0, 0] / ((1.5e-6) ** 2 * 2 / 2e-2) == pytest.approx(1.0, rel=1e-12)
