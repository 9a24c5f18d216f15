"""The industry's contact-conductance correlations, for comparison with the computed one.

Both are fits to Gaussian surfaces pressed into half-spaces, plain functions of
the nominal pressure ``P`` [Pa], the harmonic-mean conductivity ``k_s = 2 k1 k2 /
(k1 + k2)`` [W/(m K)] (:func:`harmonic_conductivity`; ``2 k1`` against a perfect
conductor), and the pair's rms height ``sigma = sqrt(sigma1^2 + sigma2^2)`` [m] and
slope ``m = sqrt(m1^2 + m2^2)`` [-]:

:func:`mikic_elastic`
    Mikic, B. B. (1974), Thermal contact conductance; theoretical considerations,
    Int. J. Heat Mass Transfer 17, 205-214: elastic asperities,
    ``h_c = 1.54 k_s (m / sigma) (sqrt(2) P / (E' m))^0.94`` with ``1/E' =
    (1 - nu1^2)/E1 + (1 - nu2^2)/E2`` (Hertz's composite modulus ``E*``);
:func:`cmy_plastic`
    Cooper, M. G., Mikic, B. B. & Yovanovich, M. M. (1969), Thermal contact
    conductance, Int. J. Heat Mass Transfer 12, 279-300: plastic asperities,
    ``h_c = 1.25 k_s (m / sigma) (P / H_c)^0.95``, ``H_c`` the microhardness (the
    pressure cap ``H`` here).

Both take ``m`` as the correlations' "mean absolute asperity slope"; for a Gaussian
profile the mean absolute slope is ``sqrt(2 / pi) = 0.80`` times the rms one. The
study uses :func:`rms_profile_slope`, the rms of the forward differences along each
grid axis at the grid's spacing, averaged over the two axes (the slope a profilometer
trace along x or y gives at that sampling); ``m`` depends on the sampling, so the
comparison does too (Mikic's ``h_c`` varies as ``m^0.06``, CMY's as ``m``).
"""

from __future__ import annotations

import numpy as np

__all__ = ["cmy_plastic", "harmonic_conductivity", "mikic_elastic", "rms_profile_slope"]


def harmonic_conductivity(k1: float, k2: float = np.inf) -> float:
    """``k_s = 2 k1 k2 / (k1 + k2)`` [W/(m K)]; ``k2`` infinite (a perfect conductor, the
    default): ``2 k1``."""
    if np.isinf(k2):
        return 2.0 * k1
    return 2.0 * k1 * k2 / (k1 + k2)


def mikic_elastic(pressure, conductivity_s: float, slope: float, sigma: float,
                  modulus: float):
    """Mikic's (1974) elastic ``h_c`` [W/(m^2 K)] at nominal ``pressure`` [Pa] (module
    docstring): ``conductivity_s`` the harmonic mean ``k_s``, ``slope`` ``m``, ``sigma``
    [m], ``modulus`` Hertz's ``E*`` [Pa]."""
    pressure = np.asarray(pressure, dtype=float)
    return (1.54 * conductivity_s * slope / sigma
            * (np.sqrt(2.0) * pressure / (modulus * slope)) ** 0.94)


def cmy_plastic(pressure, conductivity_s: float, slope: float, sigma: float,
                hardness: float):
    """Cooper, Mikic and Yovanovich's (1969) plastic ``h_c`` [W/(m^2 K)] at nominal
    ``pressure`` [Pa] (module docstring): ``hardness`` the microhardness [Pa]."""
    pressure = np.asarray(pressure, dtype=float)
    return 1.25 * conductivity_s * slope / sigma * (pressure / hardness) ** 0.95


def rms_profile_slope(heights, spacing) -> float:
    """The rms profile slope [-] of surfaces ``heights`` (..., ny, nx) [m] on elements of
    sides ``spacing`` (dx, dy) [m]: ``sqrt((mean(dz/dx)^2 + mean(dz/dy)^2) / 2)`` over
    every surface, by forward differences inside each surface (module docstring)."""
    heights = np.asarray(heights, dtype=float)
    dx, dy = spacing
    along_x = np.mean((np.diff(heights, axis=-1) / dx) ** 2)
    along_y = np.mean((np.diff(heights, axis=-2) / dy) ** 2)
    return float(np.sqrt(0.5 * (along_x + along_y)))
