"""Load control: the solution of Eq 27 at a prescribed mean pressure.

Under load control the mean pressure ``P = sum p / n`` [Pa] is given and the
approach ``d`` [m] is unknown: it is the Lagrange multiplier of the load
constraint added to Eq 27 (Polonsky & Keer 1999; Tamaas, ContactMechanics
and ASPHER take loads this way). A method that handles the constraint
inside its iteration says so (``Method.load``, the mean-gap shift of
:mod:`roughcontact.contact.pcg`); for the others :func:`solve_at_loads`
finds ``d`` by an outer solve on the load-approach curve ``P(d)``, which is
continuous and non-decreasing (strictly increasing once in contact) from
``P = 0`` at first touch ``d = min f``: a bracket is grown from first touch
(for an operator with zero mean displacement, towards the mean initial
separation, where ``P`` grows without bound), then closed by the Illinois
variant of regula falsi, each inner solve warm-started from the last
pressure, until ``|P(d) - P| <= tol P``. It costs several solves (3x the
inner iteration's work was measured against the mean-gap shift).

Units: pressures in Pa, approaches and gaps in m.
"""

from __future__ import annotations

import logging

import numpy as np

from roughcontact.contact.result import Batch

__all__ = ["MAX_OUTER", "solve_at_loads"]

logger = logging.getLogger("roughcontact.contact")

#: Largest number of inner solves of the outer solve on the approach, per surface.
MAX_OUTER = 100


class _Curve:
    """Solves of one surface at trial approaches: the load-approach curve ``P(d)``."""

    def __init__(self, method, products, gap, pressure, tol, max_iter, hardness):
        self.method, self.products, self.gap = method, products, gap[None]
        self.pressure = pressure[None].copy()
        self.tol, self.max_iter, self.hardness = tol, max_iter, hardness
        self.solves = self.iterations = 0
        self.matvecs = 0.0
        self.batch = None

    def __call__(self, d: float) -> float:
        """Mean pressure [Pa] at approach ``d`` [m]; the solve is kept."""
        batch = self.method.solve(self.products, self.gap, np.array([d]), self.pressure,
                                  self.tol, self.max_iter, self.hardness)
        self.solves += 1
        self.iterations += int(batch.iterations[0])
        self.matvecs += float(batch.matvecs[0])
        self.pressure = batch.pressure.copy()
        self.batch = batch
        return float(batch.pressure.mean())


def _bracket(curve: _Curve, target: float, first_touch: float, ceiling: float | None,
             scale: float):
    """``(d_lo, P_lo, d_hi, P_hi)`` with ``P_lo < target <= P_hi``, grown from first touch."""
    d_lo, p_lo = first_touch, 0.0
    step = scale
    while curve.solves < MAX_OUTER:
        d_hi = first_touch + step if ceiling is None else \
            ceiling - (ceiling - first_touch) * 0.5 ** (step / scale)
        p_hi = curve(d_hi)
        if p_hi >= target:
            return d_lo, p_lo, d_hi, p_hi
        d_lo, p_lo = d_hi, p_hi
        step *= 4.0
    return d_lo, p_lo, d_lo, p_lo


def _illinois(curve: _Curve, target: float, bracket, tol: float) -> float:
    """The approach [m] with ``|P(d) - target| <= tol target`` inside ``bracket``."""
    d_lo, p_lo, d_hi, p_hi = bracket
    side = 0
    d, p = d_hi, p_hi
    while abs(p - target) > tol * target and curve.solves < MAX_OUTER and d_hi > d_lo:
        d = d_lo + (target - p_lo) * (d_hi - d_lo) / (p_hi - p_lo)
        if not d_lo < d < d_hi:
            d = 0.5 * (d_lo + d_hi)
        p = curve(d)
        if p < target:
            d_lo, p_lo = d, p
            if side == -1:
                p_hi = target + 0.5 * (p_hi - target)  # Illinois: halve the stale end
            side = -1
        else:
            d_hi, p_hi = d, p
            if side == 1:
                p_lo = target - 0.5 * (target - p_lo)
            side = 1
    if abs(p - target) > tol * target:
        curve.batch.converged[:] = False
    return d


def solve_at_loads(method, products, gaps, mean_pressures, pressure, tol: float,
                   max_iter: int, hardness=None):
    """Solve the rows of ``gaps`` at mean pressures ``P`` [Pa] (load control).

    Parameters
    ----------
    method : roughcontact.contact.methods.Method
        Its ``load`` when it has one, else an outer solve on the approach
        (module docstring) with its ``solve``.
    products : Products
        The products with ``C`` [m/Pa].
    gaps : ndarray (m, n)
        Initial separations ``f`` [m].
    mean_pressures : ndarray (m,)
        Targets ``P >= 0`` [Pa].
    pressure : ndarray (m, n)
        Starting pressures [Pa] (zeros: cold).
    tol, max_iter, hardness
        Of every solve; ``tol`` also bounds ``|P(d) - P| / P`` of the outer solve.

    Returns
    -------
    (Batch, ndarray)
        The solutions (``converged`` False where the load was not reached;
        iterations and products summed over the inner solves) and the
        approaches [m] found.
    """
    if method.load is not None:
        return method.load(products, gaps, mean_pressures, pressure, tol, max_iter, hardness)
    m, n = gaps.shape
    out = Batch.empty(m, n)
    approaches = np.zeros(m)
    diagonal = np.asarray(products.operator.diagonal(), dtype=float)
    bounded = products.operator.mean_compliance == 0.0
    for j in range(m):
        curve = _Curve(method, products, gaps[j], pressure[j], tol, max_iter, hardness)
        first_touch = float(gaps[j].min())
        target = float(mean_pressures[j])
        if target > 0.0:
            ceiling = float(gaps[j].mean()) if bounded else None
            # a single element carrying the whole load deflects n P C_ii: an upper scale
            scale = target * float(diagonal.mean()) * np.sqrt(n)
            d = _illinois(curve, target, _bracket(curve, target, first_touch, ceiling, scale),
                          tol)
        else:
            d = first_touch
            curve(d)
        batch = curve.batch
        out.store(j, batch.pressure[0], batch.displacement[0], curve.iterations,
                  curve.matvecs, batch.residual[0], tol)
        out.converged[j] &= bool(batch.converged[0])
        approaches[j] = d
    return out, approaches
