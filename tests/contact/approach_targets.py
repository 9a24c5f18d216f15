"""Approaches that reach a target real area or nominal pressure, for the tests' sweeps.

The library's grid (:func:`roughcontact.contact.cell.approach_grid`) ends at a
guaranteed nominal pressure without a trial solve; some tests need a sweep
that ends where the real area (or the pressure) just reaches a value. This
finds that end by bisection on dimensionless solves.
"""

import logging

import numpy as np

from roughcontact import contact
from roughcontact.contact import SolverOptions
from roughcontact.contact.nondim import dimensionless_operator, initial_separation

logger = logging.getLogger(__name__)


def target_grid(heights, unit_influence, *, thickness: float, steps: int,
                target_area: float | None = None, target_pressure: float | None = None,
                start: float = 1e-3, rtol: float = 1e-2, method: str = "cg",
                tol: float = 1e-6) -> np.ndarray:
    """``steps`` geometric approaches ``d / sigma`` from ``start * end`` to ``end``.

    ``end`` is the smallest approach at which every surface reaches
    ``target_area`` (real area fraction) or ``target_pressure`` (``P L / (E
    sigma)``), to relative width ``rtol`` (the upper end of the bracket, so
    every surface does reach it). Solves of tolerance ``tol`` by ``method``,
    each warm-started from the previous one, on ``unit_influence / thickness``.
    """
    gaps = initial_separation(heights)
    m, n = gaps.shape
    operator = dimensionless_operator(unit_influence, thickness)
    if target_area is not None:
        target, quantity = float(target_area), "real_area_fraction"
        guess = np.quantile(gaps, target, axis=1)  # the rigid bearing-area approach
    else:
        target, quantity = float(target_pressure), "nominal_pressure"
        guess = np.ones(m)
    last = {"pressure": None}

    def reached(d):
        results = contact.solve_many(operator, gaps, d, element_area=1.0 / n, p0=last["pressure"],
                                     options=SolverOptions(method=method, tol=tol))
        last["pressure"] = np.stack([r.pressure for r in results])
        if any(not r.converged for r in results):
            logger.warning("target_grid: a solve did not reach tol %.3g", tol)
        return np.array([getattr(r, quantity) for r in results]) >= target

    end = _bisect_ends(reached, np.where(guess > 0.0, guess, 1.0), rtol).max()
    return np.geomspace(end * start, end, int(steps))


def _bisect_ends(reached, guess: np.ndarray, rtol: float, max_doublings: int = 60):
    """Smallest ``d`` per surface with ``reached(d)`` (monotone in ``d``), to relative
    width ``rtol``: the upper end of each final bracket."""
    low = np.zeros_like(guess)
    high = np.full_like(guess, np.inf)
    d = guess.copy()
    for _ in range(max_doublings):
        ok = reached(d)
        high = np.where(ok, d, high)
        low = np.where(ok, low, d)
        if np.isfinite(high).all():
            break
        d = np.where(np.isfinite(high), high, 2.0 * d)
    else:
        raise RuntimeError(f"target not reached after doubling the approach {max_doublings} "
                           "times")
    while ((high - low) > rtol * high).any():
        d = 0.5 * (low + high)
        ok = reached(d)
        high = np.where(ok, d, high)
        low = np.where(ok, low, d)
    return high
