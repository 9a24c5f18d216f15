"""The KKT residual of Eq 27, the stopping criterion every contact method shares.

Without a cap the optimality (KKT) conditions of Eq 27 (Eq 19-22 of Kumar et
al. 2006) are ``p >= 0``, ``g >= 0`` and ``p_i g_i = 0`` with the gap
``g = C p + f - d``. Every method stops on the same dimensionless residual,

    r = max_i | min(C_ii p_i, g_i) | / max_i |d - f_i|,

the max-norm of the projected-gradient (natural) residual with the diagonal
scaling ``C_ii``, in units of the largest rigid interference. It is zero
exactly at the solution; a negative pressure, a penetration (negative gap)
and a gap left open under positive pressure all raise it. With a cap ``H``
it is the natural residual of the box-constrained problem ``0 <= p <= H``,

    r = max_i | C_ii p_i - clip(C_ii p_i - g_i, 0, C_ii H) | / max_i |d - f_i|,

zero exactly at its KKT point (``g = 0`` where ``0 < p < H``, ``g >= 0``
where ``p = 0``, ``g <= 0`` where ``p = H``), and the uncapped residual for
``H = inf``.
"""

from __future__ import annotations

import numpy as np

from roughcontact.contact.checks import (
    as_operator,
    check_approach,
    check_hardness,
    check_pressure,
    check_surfaces,
)
from roughcontact.contact.products import rows_product

__all__ = ["free_set", "gap_scale", "kkt_residual", "kkt_residuals", "plastic_fraction"]


def gap_scale(rigid: np.ndarray) -> np.ndarray:
    """Largest rigid interference ``max_i |d - f_i|`` per surface [m] (1 if zero)."""
    scale = np.abs(rigid).max(axis=1)
    return np.where(scale > 0.0, scale, 1.0)


def kkt_residuals(pressure, gap, diagonal, scale, hardness=None) -> np.ndarray:
    """Per-surface KKT residual (module docstring), rows = surfaces.

    ``max_i |min(C_ii p_i, g_i)| / scale`` without a cap; with ``hardness``
    ``H``, ``max_i |C_ii p_i - clip(C_ii p_i - g_i, 0, C_ii H)| / scale``,
    which is the same expression when ``H`` is infinite.
    """
    natural = pressure * diagonal
    if hardness is None:
        np.minimum(natural, gap, out=natural)
    else:
        natural -= np.clip(natural - gap, 0.0, hardness * diagonal)
    return np.maximum(natural.max(axis=1), -natural.min(axis=1)) / scale + 0.0


def free_set(pressure: np.ndarray, hardness: float | None) -> np.ndarray:
    """The free set: elements free to move with ``d``, ``p > 0`` and, with a cap, ``p < H``."""
    if hardness is None:
        return pressure > 0.0
    return (pressure > 0.0) & (pressure < hardness)


def plastic_fraction(pressure: np.ndarray, hardness: float | None) -> np.ndarray:
    """Fraction of elements at the cap ``p = H`` [-] per row (0 without a cap)."""
    if hardness is None:
        return np.zeros(pressure.shape[:-1])
    return np.count_nonzero(pressure >= hardness, axis=-1) / pressure.shape[-1]


def kkt_residual(operator, gap0, approach, pressure, *, element_area=None,
                 hardness=None) -> float:
    """Dimensionless KKT residual of a pressure field for Eq 27.

    ``r = max_i |min(C_ii p_i, g_i)| / max_i |d - f_i|`` with
    ``g = C p + f - d``; zero exactly at the solution. With a cap
    ``0 <= p <= H`` the residual of the bounded problem,
    ``r = max_i |C_ii p_i - clip(C_ii p_i - g_i, 0, C_ii H)| / max_i |d - f_i|``
    (module docstring), zero exactly at its KKT point.

    Parameters
    ----------
    operator : ndarray (n, n) or operator object
        Influence coefficients [m/Pa].
    gap0 : ndarray, (ny, nx) or (n,)
        Initial separation ``f`` [m] (Eq 21).
    approach : float
        Rigid-body approach ``d`` [m].
    pressure : ndarray
        Pressure [Pa], same shape as ``gap0``.
    element_area : float, optional
        Element area [m^2]; not used by the residual, accepted for symmetry
        with :func:`roughcontact.contact.solve`.
    hardness : float, optional
        Pressure cap ``H`` [Pa] of the problem the pressure is scored
        against; default None (no cap).

    Returns
    -------
    float
        The residual [-].
    """
    hardness = check_hardness(hardness)
    op = as_operator(operator, 1.0 if element_area is None else element_area)
    gaps, _ = check_surfaces(gap0, op, "gap0", batched=False)
    d = check_approach(approach, 1)
    p = check_pressure(pressure, op.shape[0])
    rigid = gaps - d[:, None]
    gap = rows_product(op, p) + rigid
    return float(kkt_residuals(p, gap, op.diagonal(), gap_scale(rigid), hardness)[0])
