"""Closed forms the flow solver is checked against, and Patir & Cheng's fitted flow factors.

Pure functions of their arguments, SI units (gaps m, conductances m^3). The
effective conductance ``K`` [m^3] is that of :mod:`roughcontact.transport.flow`:
the cube of the flat gap that carries the same flow, ``K = 12 eta Q L / (W dp)``.
None of these functions calls the flow solver or shares code with it.

- :func:`flat_channel_conductance`: a flat gap ``h``, ``K = h^3``;
- :func:`series_conductance`: a gap varying along the flow only, the
  conductances ``g^3`` in series, ``K = 1 / mean(1 / g^3)`` (the harmonic mean
  of ``g^3``). Exact for the continuous equation, and for the finite-volume
  scheme with the harmonic face rule on a field constant across the flow
  (each row a chain of resistances ``dx / g_i^3``);
- :func:`parallel_conductance`: a gap varying across the flow only, the
  conductances in parallel, ``K = mean(g^3)``. Exact for the continuous
  equation and for the scheme under either face rule (the pressure is then
  linear along every row and no flow crosses between rows);
- :func:`checkerboard_conductance`: the infinite two-phase checkerboard of
  conductances ``k1`` and ``k2``, ``K = sqrt(k1 k2)`` (Dykhne 1970; Keller
  1964's reciprocity ``K(k) K(1/k rotated) = 1`` with the checkerboard's
  symmetries). Exact for the infinite (or fully periodic) checkerboard only:
  a strip with the pressure given at its ends has boundary layers there
  (``tests/transport/test_flow.py`` measures how fast they fade);
- :func:`patir_cheng_phi_x`: the pressure flow factor ``phi_x`` fitted by Patir &
  Cheng (1978) to their numerical flow simulations on Gaussian surfaces.

References
----------
J. B. Keller, "A theorem on the conductivity of a composite medium",
J. Math. Phys. 5 (1964) 548-549.

A. M. Dykhne, "Conductivity of a two-dimensional two-phase system",
Sov. Phys. JETP 32 (1971) 63-65 (Zh. Eksp. Teor. Fiz. 59 (1970) 110-115).

N. Patir, H. S. Cheng, "An average flow model for determining effects of
three-dimensional roughness on partial hydrodynamic lubrication", ASME J.
Lubr. Technol. 100 (1978) 12-17.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from types import MappingProxyType

import numpy as np

__all__ = [
    "PATIR_CHENG_PRESSURE_FLOW",
    "PatirChengFit",
    "checkerboard_conductance",
    "flat_channel_conductance",
    "parallel_conductance",
    "patir_cheng_phi_x",
    "series_conductance",
]


def flat_channel_conductance(gap) -> np.ndarray:
    """``K = h^3`` [m^3] of a flat channel of gap ``h`` [m] (the plane Poiseuille flow
    ``Q = h^3 W dp / (12 eta L)``)."""
    return np.asarray(gap, dtype=float) ** 3


def series_conductance(gap) -> float:
    """``K = 1 / mean(1 / g^3)`` [m^3] of a gap ``g`` [m] (1-D, elements of equal length
    along the flow) that varies along the flow only; 0 if any element is closed."""
    g = np.asarray(gap, dtype=float).ravel()
    if np.any(g == 0.0):
        return 0.0
    return float(1.0 / np.mean(1.0 / g**3))


def parallel_conductance(gap) -> float:
    """``K = mean(g^3)`` [m^3] of a gap ``g`` [m] (1-D, elements of equal width across
    the flow) that varies across the flow only."""
    return float(np.mean(np.asarray(gap, dtype=float) ** 3))


def checkerboard_conductance(k1: float, k2: float) -> float:
    """``K = sqrt(k1 k2)`` [m^3] of the infinite checkerboard of square tiles of local
    conductances ``k1`` and ``k2`` [m^3] (Dykhne 1970), in either direction."""
    return float(np.sqrt(k1 * k2))


@dataclass(frozen=True)
class PatirChengFit:
    """One row of Patir & Cheng's (1978) fits of the pressure flow factor.

    ``phi_x = 1 - C exp(-r H)`` for ``gamma <= 1`` and ``phi_x = 1 + C H^-r`` for
    ``gamma > 1``, ``H = h / sigma`` the nominal separation of the mean planes
    over the composite rms roughness, valid for ``H >= smallest_h``.

    Attributes
    ----------
    gamma : Fraction
        Peklenik's surface pattern parameter: the ratio of the lengths at which the
        autocorrelation along x (the flow) and across it falls to 0.5 [-].
    c, r : float
        The fit's constants [-].
    smallest_h : float
        The smallest ``H`` the fit covers [-].
    verified : str
        How the constants were checked (module and function docstrings).
    """

    gamma: Fraction
    c: float
    r: float
    smallest_h: float
    verified: str

    def __call__(self, separation_ratio) -> np.ndarray:
        h = np.asarray(separation_ratio, dtype=float)
        if self.gamma <= 1:
            return 1.0 - self.c * np.exp(-self.r * h)
        return 1.0 + self.c * h ** (-self.r)


_DIRECT = ("read in two independent public implementations of Patir & Cheng's "
           "isotropic fit (1 - 0.9 exp(-0.56 H))")
_INDIRECT = ("the value as the fit's table is usually reproduced; not read from the "
             "paper: a public code's smooth fit of C(gamma) and r(gamma) to the table "
             "reproduces it to within 4 %")

#: Patir & Cheng's (1978) pressure flow factor fits by ``gamma`` (see :func:`patir_cheng_phi_x`).
PATIR_CHENG_PRESSURE_FLOW = MappingProxyType({
    fit.gamma: fit for fit in (
        PatirChengFit(Fraction(1, 9), 1.48, 0.42, 0.5, _INDIRECT),
        PatirChengFit(Fraction(1, 6), 1.38, 0.42, 0.5, _INDIRECT),
        PatirChengFit(Fraction(1, 3), 1.18, 0.42, 0.5, _INDIRECT),
        PatirChengFit(Fraction(1), 0.90, 0.56, 0.5, _DIRECT),
        PatirChengFit(Fraction(3), 0.225, 1.5, 0.5, _INDIRECT),
        PatirChengFit(Fraction(6), 0.520, 1.5, 1.0, _INDIRECT),
        PatirChengFit(Fraction(9), 0.870, 1.5, 1.0, _INDIRECT),
    )
})


def patir_cheng_phi_x(separation_ratio, gamma=1) -> np.ndarray:
    """Patir & Cheng's (1978) fitted pressure flow factor ``phi_x`` [-].

    ``phi_x = K / h^3`` (:meth:`roughcontact.transport.flow.FlowResult.patir_cheng_factor`)
    of two rough surfaces at the nominal separation ``h`` of their mean planes,
    ``H = h / sigma`` (``separation_ratio``), with ``sigma`` the rms of the
    composite roughness (Gaussian heights), flow along x:

    - ``gamma <= 1``: ``phi_x = 1 - C exp(-r H)``;
    - ``gamma > 1``: ``phi_x = 1 + C H^-r``.

    ``gamma = 1`` (isotropic): ``C = 0.90``, ``r = 0.56``, ``H >= 0.5``; these two
    constants were read in two independent public implementations of the fit.
    The other rows (:data:`PATIR_CHENG_PRESSURE_FLOW`: gamma 1/9, 1/6, 1/3 with
    ``r = 0.42`` and ``C = 1.48, 1.38, 1.18``; gamma 3, 6, 9 with ``r = 1.5`` and
    ``C = 0.225, 0.520, 0.870``, ``H >= 0.5`` for gamma <= 3 and ``H >= 1`` above)
    are the table as it is usually reproduced: they could not be read from the
    paper itself here. A public code's smooth fit of the table,
    ``C = 0.89679 - 0.26591 ln(gamma)``, ``r = 0.43006 - 0.10828 gamma + 0.23821
    gamma^2`` (gamma < 1) and ``C = -0.10667 + 0.1075 gamma``, ``r = 1.5``
    (gamma > 1), reproduces every one of them to within 4 %, which corroborates
    but does not verify them; each row's ``verified`` says which it is.

    Parameters
    ----------
    separation_ratio : array_like
        ``H = h / sigma`` [-], at least the row's ``smallest_h``.
    gamma : int, Fraction or float
        One of the table's gammas: 1/9, 1/6, 1/3, 1, 3, 6, 9 [-].

    Returns
    -------
    ndarray
        ``phi_x`` [-].
    """
    key = Fraction(gamma).limit_denominator(100)
    if key not in PATIR_CHENG_PRESSURE_FLOW:
        raise ValueError(f"gamma must be one of Patir & Cheng's "
                         f"{[str(g) for g in PATIR_CHENG_PRESSURE_FLOW]}, got {gamma!r}")
    fit = PATIR_CHENG_PRESSURE_FLOW[key]
    h = np.asarray(separation_ratio, dtype=float)
    if np.any(h < fit.smallest_h):
        raise ValueError(f"separation_ratio must be >= {fit.smallest_h:g} for gamma = "
                         f"{key} (the fit's range), got a minimum of {h.min():.6g}")
    return fit(h)
