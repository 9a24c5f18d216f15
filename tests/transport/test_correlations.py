"""The contact-conductance correlations (Mikic 1974, Cooper, Mikic & Yovanovich 1969), the
slope they read, and the conductance figure's use of them."""

import math

import numpy as np
import pandas as pd
import pytest

from roughcontact.reports.conductance_figure import conductance_at, with_correlations
from roughcontact.transport.conduction.correlations import (
    cmy_plastic,
    harmonic_conductivity,
    mikic_elastic,
    rms_profile_slope,
)


def test_mikic_and_cmy_at_a_worked_point():
    # steel on a perfect conductor: k_s = 2 x 50; m = 0.1, sigma = 1 um, E* = 230.8 GPa,
    # P = 10 MPa; H = 3 GPa (arithmetic written out, not the module's)
    k_s, m, sigma, modulus, pressure, hardness = 100.0, 0.1, 1e-6, 230.8e9, 10e6, 3e9
    elastic = 1.54 * 100.0 * 1e5 * math.exp(0.94 * math.log(1.41421356237 * 1e7 / 2.308e10))
    plastic = 1.25 * 100.0 * 1e5 * math.exp(0.95 * math.log(1e7 / 3e9))
    assert mikic_elastic(pressure, k_s, m, sigma, modulus) == pytest.approx(elastic, rel=1e-10)
    assert cmy_plastic(pressure, k_s, m, sigma, hardness) == pytest.approx(plastic, rel=1e-10)
    # their exponents: doubling P multiplies h by 2^0.94 and 2^0.95
    assert (mikic_elastic(2 * pressure, k_s, m, sigma, modulus)
            / mikic_elastic(pressure, k_s, m, sigma, modulus)) == pytest.approx(2**0.94)
    assert (cmy_plastic(2 * pressure, k_s, m, sigma, hardness)
            / cmy_plastic(pressure, k_s, m, sigma, hardness)) == pytest.approx(2**0.95)


def test_the_harmonic_mean_conductivity():
    assert harmonic_conductivity(50.0, 50.0) == pytest.approx(50.0)
    assert harmonic_conductivity(50.0) == 100.0  # against a perfect conductor
    assert harmonic_conductivity(20.0, 380.0) == pytest.approx(2 * 20 * 380 / 400)


def test_the_rms_profile_slope_of_a_plane_and_a_sinusoid():
    y, x = np.mgrid[:16, :24] * 1e-4  # dx = dy = 0.1 mm
    plane = 0.02 * x - 0.01 * y
    assert rms_profile_slope(plane, (1e-4, 1e-4)) == pytest.approx(
        math.sqrt((0.02**2 + 0.01**2) / 2), rel=1e-12)
    # a sinusoid along x, 200 samples a wavelength: rms slope along x A k / sqrt(2), 0
    # along y; the forward difference's error (k dx)^2 / 24 ~ 4e-5, and the 799 differences
    # of 4 whole wavelengths average cos^2 to 1/2 within 1/800
    n, amplitude, wavelength = 800, 1e-6, 2e-3
    x = np.arange(n) * wavelength / 200
    wave = np.tile(amplitude * np.sin(2 * np.pi * x / wavelength), (3, 1))
    expected = math.sqrt((amplitude * 2 * math.pi / wavelength) ** 2 / 2 / 2)
    assert rms_profile_slope(wave, (wavelength / 200, 1e-4)) == pytest.approx(expected,
                                                                              rel=1.5e-3)


def _table(cell: int, cap) -> pd.DataFrame:
    pressures = np.array([1e6, 1e7])
    return pd.DataFrame({
        "cell": cell, "contact_key": f"surf{cell}__geom", "sigma_um": 2.0, "E_MPa": 2.1e5,
        "nu": 0.3, "cap_MPa": cap, "skew": 0.0, "kurt": 3.0, "thickness_mm": 10.0,
        "nominal_pressure": pressures, "nominal_pressure_MPa": pressures / 1e6,
        "thermal_conductance_per_area_mean": [1e3, 1e4],
        "thermal_conductance_per_area_half_width": [10.0, 100.0],
        "constriction_conductance_per_area_mean": [2e3, 2e4],
        "constriction_conductance_per_area_half_width": [20.0, 200.0],
        "conduction_bulk_share_mean": [0.5, 0.5],
        "conduction_bulk_share_half_width": [0.01, 0.01]})


def test_each_cell_gets_its_correlation_from_its_slope_and_sigma():
    table = pd.concat([_table(0, np.nan), _table(1, 3000.0)], ignore_index=True)
    slopes = {"surf0": 5e3, "surf1": 5e3}  # per unit sigma [1/m]: m = 0.01 at sigma 2 um
    found = with_correlations(table, slopes, conductivity=50.0)
    elastic, plastic = found[found["cell"] == 0], found[found["cell"] == 1]
    assert set(elastic["correlation"]) == {"Mikic elastic"}
    assert set(plastic["correlation"]) == {"CMY plastic"}
    np.testing.assert_allclose(elastic["slope"], 0.01)
    modulus = 2.1e11 / (1 - 0.09)
    np.testing.assert_allclose(
        elastic["correlation_h"],
        1.54 * 100.0 * 0.01 / 2e-6 * (math.sqrt(2) * np.array([1e6, 1e7]) / (modulus * 0.01))
        ** 0.94, rtol=1e-12)
    np.testing.assert_allclose(
        plastic["correlation_h"], 1.25 * 100.0 * 0.01 / 2e-6 * (np.array([1e6, 1e7]) / 3e9)
        ** 0.95, rtol=1e-12)
    np.testing.assert_allclose(found["h_s_ratio"],
                               found["constriction_conductance_per_area_mean"]
                               / found["correlation_h"], rtol=1e-12)
    picked = conductance_at(found, [1.0, 10.0])
    assert picked["P_MPa"].tolist() == [1.0, 10.0, 1.0, 10.0]
    assert picked["h_c"].tolist() == [1e3, 1e4, 1e3, 1e4]
