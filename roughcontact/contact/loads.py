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
(for an uncapped operator with zero mean displacement, towards the mean
initial separation, where ``P`` grows without bound), then closed by the
Illinois variant of regula falsi, each inner solve warm-started from the last
pressure. It costs several solves (3x the inner iteration's work was
measured against the mean-gap shift).

Two tolerances, each met and each checked: every solve's KKT residual
(:mod:`roughcontact.contact.kkt`) at most ``tol``, and the load at most
``load_tol`` from the target, ``|P(d) - P| <= load_tol P``. The second is not
the first: an inner solve that meets ``tol`` knows its pressures only to a gap
error of about ``tol`` times the gap scale, so its load only to about that
times the slope ``dP/dd``; the outer solve therefore takes its inner solves to
``min(tol, load_tol P / (10 scale dP/dd))`` (the slope from the bracket), and
to 100 times less again while the load is still missed. Near full contact of
an uncapped operator with zero mean displacement (``C 1 = 0``) the curve is
vertical at the ceiling ``d = mean f``: there every solution is full contact
``C p = d - f`` up to a uniform pressure, which moves no element, and the load
is met by adding it (:func:`_at_ceiling`).

Units: pressures in Pa, approaches and gaps in m.
"""

from __future__ import annotations

import logging

import numpy as np

from roughcontact.contact.kkt import gap_scale, kkt_residuals
from roughcontact.contact.result import Batch

__all__ = ["LOAD_TOL", "MAX_OUTER", "TOL_FLOOR", "load_errors", "solve_at_loads"]

logger = logging.getLogger("roughcontact.contact")

#: Largest number of inner solves of the outer solve on the approach, per surface.
MAX_OUTER = 100
#: Default tolerance on the load, ``|P(d) - P| <= LOAD_TOL P`` [-].
LOAD_TOL = 1e-8
#: The tightest KKT tolerance the outer solve asks of an inner solve (double rounding).
TOL_FLOOR = 1e-14


def load_errors(pressure: np.ndarray, mean_pressures: np.ndarray) -> np.ndarray:
    """``|mean p - P| / P`` per row [-] (``|mean p|`` [Pa] where ``P = 0``)."""
    error = np.abs(pressure.mean(axis=1) - mean_pressures)
    return np.divide(error, mean_pressures, out=error.copy(), where=mean_pressures > 0.0)


class _Curve:
    """Solves of one surface at trial approaches: the load-approach curve ``P(d)``.

    ``tol`` is the KKT tolerance of the next solve (at most the caller's), lowered
    by the outer solve where the load needs it (module docstring).
    """

    def __init__(self, method, products, gap, pressure, tol, max_iter, hardness):
        self.method, self.products, self.gap = method, products, gap[None]
        self.pressure = pressure[None].copy()
        self.tol, self.max_iter, self.hardness = tol, max_iter, hardness
        self.f_min, self.f_max = float(gap.min()), float(gap.max())
        self.solves = self.iterations = 0
        self.matvecs = 0.0
        self.batch = None
        self.approach = None

    def __call__(self, d: float) -> float:
        """Mean pressure [Pa] at approach ``d`` [m]; the solve is kept."""
        batch = self.method.solve(self.products, self.gap, np.array([d]), self.pressure,
                                  self.tol, self.max_iter, self.hardness)
        self.solves += 1
        self.iterations += int(batch.iterations[0])
        self.matvecs += float(batch.matvecs[0])
        self.pressure = batch.pressure.copy()
        self.batch, self.approach = batch, d
        return float(batch.pressure.mean())

    @property
    def failed(self) -> bool:
        """The last solve stopped short of its tolerance: the outer solve ends there (its
        loads are not to be trusted; the retries of
        :mod:`roughcontact.contact.retries` take over)."""
        return self.batch is not None and not bool(self.batch.converged[0])

    def resolve_load(self, load_tol: float, target: float, slope: float, d: float) -> None:
        """Lower ``tol`` so that a solve at ``d`` [m] knows its load to a tenth of
        ``load_tol`` of ``target`` [Pa], given the slope ``dP/dd`` [Pa/m] near it."""
        scale = max(abs(d - self.f_min), abs(self.f_max - d)) or 1.0
        if slope > 0.0 and np.isfinite(slope):
            needed = 0.1 * load_tol * target / (slope * scale)
            self.tol = min(self.tol, max(needed, TOL_FLOOR))


def _bracket(curve: _Curve, target: float, first_touch: float, ceiling: float | None,
             scale: float):
    """``(d_lo, P_lo, d_hi, P_hi)`` with ``P_lo < target <= P_hi``, grown from first touch;
    towards a ``ceiling`` the last trial is the ceiling itself (``P_hi`` may stay below
    the target there: :func:`_at_ceiling`)."""
    d_lo, p_lo = first_touch, 0.0
    step = scale
    while curve.solves < MAX_OUTER:
        if ceiling is None:
            d_hi = first_touch + step
        else:
            d_hi = ceiling - (ceiling - first_touch) * 0.5 ** (step / scale)
            if not d_hi < ceiling:
                d_hi = ceiling
        p_hi = curve(d_hi)
        if p_hi >= target or d_hi == ceiling or curve.failed:
            return d_lo, p_lo, d_hi, p_hi
        d_lo, p_lo = d_hi, p_hi
        step *= 4.0
    return d_lo, p_lo, d_lo, p_lo


def _start_approach(products, gap: np.ndarray, start: np.ndarray, hardness) -> float | None:
    """The approach [m] at which the starting pressure ``start`` [Pa] would be a solution
    (the mean of ``(C p)_i + f_i`` over its elements in contact below the cap, where the
    gap closes), or None where it has none (a cold start)."""
    free = (start > 0.0) if hardness is None else (start > 0.0) & (start < hardness)
    if not free.any():
        return None
    displacement = np.asarray(products.operator.matvec(start), dtype=float)
    return float(np.mean((displacement + gap)[free]))


def _warm_bracket(curve: _Curve, target: float, first_touch: float, start: float,
                  ceiling: float | None):
    """``(d_lo, P_lo, d_hi, P_hi)`` with ``P_lo < target <= P_hi`` from the approach of a
    warm start (:func:`_start_approach`): a solve there, then below it down to first
    touch (``P = 0``), or above it by the secant's step from first touch (at most the
    step needed on a load that stiffens with the approach), doubled until the target is
    passed. None where it cannot bracket (a failed solve, a ceiling in the way): the
    cold bracket then."""
    if not start > first_touch or (ceiling is not None and not start < ceiling):
        return None
    p_start = curve(start)
    if curve.failed or not p_start > 0.0:
        return None
    if p_start >= target:
        return first_touch, 0.0, start, p_start
    step = (target - p_start) * (start - first_touch) / p_start
    d_lo, p_lo = start, p_start
    while curve.solves < MAX_OUTER // 2:
        d_hi = d_lo + step
        if ceiling is not None and not d_hi < ceiling:
            return None
        p_hi = curve(d_hi)
        if curve.failed:
            return None
        if p_hi >= target:
            return d_lo, p_lo, d_hi, p_hi
        d_lo, p_lo, step = d_hi, p_hi, 2.0 * step
    return None


def _illinois(curve: _Curve, target: float, bracket, load_tol: float) -> float:
    """The approach [m] with ``|P(d) - target| <= load_tol target`` inside ``bracket``.

    Each solve is taken to the KKT tolerance the load needs
    (:meth:`_Curve.resolve_load`, the slope from the bracket); where the bracket
    closes on the solves' rounding with the load still missed, the solve is
    repeated 100 times more exactly, down to :data:`TOL_FLOOR`.
    """
    d_lo, p_lo, d_hi, p_hi = bracket
    side = 0
    d, p = d_hi, p_hi
    while abs(p - target) > load_tol * target and curve.solves < MAX_OUTER \
            and not curve.failed:
        if not d_hi > d_lo or not p_hi > p_lo:
            if curve.tol <= TOL_FLOOR:
                break
            curve.tol = max(0.01 * curve.tol, TOL_FLOOR)
            p = curve(d)
            continue
        curve.resolve_load(load_tol, target, (p_hi - p_lo) / (d_hi - d_lo), d)
        d = d_lo + (target - p_lo) * (d_hi - d_lo) / (p_hi - p_lo)
        if not d_lo < d < d_hi:
            d = 0.5 * (d_lo + d_hi)
            if not d_lo < d < d_hi:  # adjacent floats
                d_hi = d_lo
                continue
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
    if curve.approach != d and not curve.failed:
        curve(d)
    return d


def _at_ceiling(curve: _Curve, target: float, diagonal) -> None:
    """Full contact at the ceiling ``d = mean f`` of an operator with ``C 1 = 0``: add the
    uniform pressure that meets ``target`` [Pa] to the last solve (at the ceiling).

    There ``sum g = n (mean u + mean f - d) = 0`` with ``g >= 0``, so every gap is
    closed (to the solve's tolerance) and ``p + c 1`` with ``c >= 0`` is a solution
    with the same displacement. The gaps left open within the tolerance add up, so
    the shifted pressure is solved again at the ceiling: the gradient ``g`` then has
    zero mean, so the iteration keeps the mean pressure while it closes them. The
    mean is set once more (rounding) and the KKT residual computed anew.
    """
    curve.pressure = curve.batch.pressure + (target - float(curve.batch.pressure.mean()))
    curve(curve.approach)
    batch = curve.batch
    batch.pressure += target - float(batch.pressure.mean())
    rigid = curve.gap - curve.approach
    batch.residual[:] = kkt_residuals(batch.pressure, batch.displacement + rigid, diagonal,
                                      gap_scale(rigid))
    batch.converged[:] = batch.residual <= curve.tol


def solve_at_loads(method, products, gaps, mean_pressures, pressure, tol: float,
                   max_iter: int, hardness=None, load_tol: float = LOAD_TOL):
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
        Of every solve: the KKT tolerance, the iteration limit, the cap [Pa] or None.
    load_tol : float
        Tolerance on the load, ``|P(d) - P| <= load_tol P`` (default :data:`LOAD_TOL`).

    Returns
    -------
    (Batch, ndarray)
        The solutions (``converged`` where both the KKT residual and the load met
        their tolerances; iterations and products summed over the inner solves)
        and the approaches [m] found.
    """
    if method.load is not None:
        batch, approaches = method.load(products, gaps, mean_pressures, pressure, tol,
                                        max_iter, hardness)
    else:
        batch, approaches = _outer_solves(method, products, gaps, mean_pressures, pressure,
                                          tol, max_iter, hardness, load_tol)
    batch.converged &= load_errors(batch.pressure, mean_pressures) <= load_tol
    return batch, approaches


def _outer_solves(method, products, gaps, mean_pressures, pressure, tol, max_iter, hardness,
                  load_tol):
    """:func:`solve_at_loads` by an outer solve on the approach, surface by surface."""
    m, n = gaps.shape
    out = Batch.empty(m, n)
    approaches = np.zeros(m)
    diagonal = np.asarray(products.operator.diagonal(), dtype=float)
    # a ceiling where P(d) grows without bound: C 1 = 0 and no cap (with one, every
    # approach has a solution)
    bounded = products.operator.mean_compliance == 0.0 and hardness is None
    for j in range(m):
        curve = _Curve(method, products, gaps[j], pressure[j], tol, max_iter, hardness)
        first_touch = float(gaps[j].min())
        target = float(mean_pressures[j])
        if target > 0.0:
            ceiling = float(gaps[j].mean()) if bounded else None
            # a single element carrying the whole load deflects n P C_ii: an upper scale
            scale = target * float(diagonal.mean()) * np.sqrt(n)
            start = _start_approach(products, gaps[j], pressure[j], hardness)
            bracket = None if start is None else _warm_bracket(curve, target, first_touch,
                                                               start, ceiling)
            if bracket is None:
                bracket = _bracket(curve, target, first_touch, ceiling, scale)
            if bracket[2] == ceiling and bracket[3] < target and not curve.failed:
                _at_ceiling(curve, target, diagonal)
            else:  # (ends at once after a failed solve)
                _illinois(curve, target, bracket, load_tol)
        else:
            curve(first_touch)
        batch = curve.batch
        out.store(j, batch.pressure[0], batch.displacement[0], curve.iterations,
                  curve.matvecs, batch.residual[0], tol)
        out.converged[j] &= bool(batch.converged[0])
        approaches[j] = curve.approach
    return out, approaches
