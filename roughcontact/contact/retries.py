"""Every solve meets its tolerances or says so: the retries of one that did not.

One rule for every entry point and every sweep (issue 42): a solution is
returned as converged only if it met its tolerances (the KKT residual of
:mod:`roughcontact.contact.kkt` at most ``tol`` and, under load control, the
load at most ``load_tol`` from its target). A surface whose solve stops
short is

1. solved again from zero pressure (a *cold* start) if it started from a
   given pressure (a sweep's previous or predicted step, a user's ``p0``):
   a warm start can lead an iteration into a cycle it does not leave (the
   32 x 32 paper-mesh block of issue 42: pcg under load control warm-started
   from the last step ended at KKT residual 0.55);
2. then by each *fallback* method in turn (block principal pivoting where the
   operator has or can form its dense matrix: finite, exact on its contact
   set, :mod:`roughcontact.contact.pivot`), from zero pressure;
3. and, if none converged, returned with ``converged`` False (the attempt
   with the smallest KKT residual), logged on the ``roughcontact.contact``
   logger with every attempt (method, start, iterations, KKT residual, load
   error). A sweep starts the next step of such a surface from zero, never
   from it (:mod:`roughcontact.contact.sweeps`).

Every row records the method whose solution it holds (the batch's ``solved_by``,
a result's ``method``, a sweep's per-step ``solved_by``): the method asked for,
or the fallback whose answer was taken, and a fallback's answer is a warning on
the same logger naming the surface, its step (approach or load), the method that
failed and the one used.

The work of every attempt is counted in ``iterations`` and ``matvecs``.
"""

from __future__ import annotations

import logging

import numpy as np

from roughcontact.contact.result import METHOD_NAME, Batch

__all__ = ["settle"]

logger = logging.getLogger("roughcontact.contact")


def _take(batch: Batch, approaches, rows, other: Batch, other_approaches, name: str) -> None:
    """Rows ``rows`` of ``batch`` from ``other`` (solved by the method ``name``) where it
    converged or, neither having converged, has the smaller residual; the work of both is
    summed."""
    better = other.converged | (~batch.converged[rows] & (other.residual < batch.residual[rows]))
    iterations = batch.iterations[rows] + other.iterations
    matvecs = batch.matvecs[rows] + other.matvecs
    chosen = rows[better]
    batch.pressure[chosen] = other.pressure[better]
    batch.displacement[chosen] = other.displacement[better]
    batch.residual[chosen] = other.residual[better]
    batch.converged[chosen] = other.converged[better]
    approaches[chosen] = other_approaches[better]
    batch.solved_by[chosen] = name
    batch.iterations[rows] = iterations
    batch.matvecs[rows] = matvecs


def _attempt(name: str, batch: Batch, control, r: int) -> str:
    """One attempt of row ``r`` of ``batch`` in words."""
    error = control.load_error(batch)[r]
    load = f", load error {error:.2g}" if error else ""
    return (f"{name} ({int(batch.iterations[r])} iterations, KKT residual "
            f"{batch.residual[r]:.3g}{load})")


def _retry(batch: Batch, approaches, rows, attempt, gaps, control, tol: float, hardness,
           tried: dict) -> None:
    """Solve the surfaces ``rows`` again from zero pressure with ``attempt`` (method,
    products, iteration limit, how), take its better results into ``batch`` and say
    what was tried in ``tried``; a method that cannot take the problem (ValueError)
    is recorded as refused."""
    method, products, limit, how = attempt
    subset = control.rows(rows)
    try:
        again, found = subset.solve(method, products, gaps[rows],
                                    np.zeros((rows.size, gaps.shape[1])), tol, limit, hardness)
    except ValueError as error:
        for j in rows:
            tried[int(j)].append(f"{method.name} {how}: refused ({error})")
        return
    for r, j in enumerate(rows):
        tried[int(j)].append(_attempt(f"{method.name} {how}", again, subset, r))
    _take(batch, approaches, rows, again, found, method.name)


def settle(method, products, gaps, control, start, tol: float, max_iter: int, hardness,
           fallbacks=(), retry: bool = True) -> tuple[Batch, np.ndarray]:
    """Solve the rows of ``gaps`` [m] under ``control`` with the retries of the module
    docstring; the batch (``converged`` False only where every attempt failed) and the
    approaches [m].

    Parameters
    ----------
    method : roughcontact.contact.methods.Method
        The method asked for.
    products : Products
        Its products with ``C`` [m/Pa].
    gaps : ndarray (m, n)
        Initial separations ``f`` [m].
    control : roughcontact.contact.controls.Approaches or Loads
        The approaches [m] or mean pressures [Pa] of the rows.
    start : ndarray (m, n)
        Starting pressures [Pa] (zero rows: cold).
    tol, max_iter, hardness
        KKT tolerance, iteration limit of ``method`` and cap [Pa] or None.
    fallbacks : sequence of (Method, Products)
        Methods tried in turn, from zero pressure with their own iteration
        limits, on the rows still unconverged.
    retry : bool
        False: no attempt after the first (the method's own result, flagged and
        logged where unconverged), for measuring a method.
    """
    m, n = gaps.shape
    batch, approaches = control.solve(method, products, gaps, start, tol, max_iter, hardness)
    batch.solved_by = np.full(m, method.name, dtype=METHOD_NAME)
    if batch.converged.all():
        return batch, approaches
    warm = start.any(axis=1)
    tried = {int(j): [_attempt(f"{method.name} from the given start" if warm[j] else
                               f"{method.name} cold", batch, control, j)]
             for j in np.flatnonzero(~batch.converged)}
    attempts = [(method, products, max_iter, "cold")] if warm[~batch.converged].any() else []
    attempts += [(fallback, fallback_products, fallback.max_iter(None, n), "cold")
                 for fallback, fallback_products in fallbacks]
    if not retry:
        attempts = []
    for attempt_method, attempt_products, limit, how in attempts:
        rows = np.flatnonzero(~batch.converged)
        if attempt_method is method:
            rows = rows[warm[rows]]
        if rows.size:
            _retry(batch, approaches, rows, (attempt_method, attempt_products, limit, how),
                   gaps, control, tol, hardness, tried)
    for j in np.flatnonzero(batch.converged & (batch.solved_by != method.name)):
        logger.warning("contact solve for surface %d at %s: %s fell short of tol %.3g; "
                       "fallback %s answered, recorded as the method; attempts: %s", j,
                       control.describe(j), method.name, tol, batch.solved_by[j],
                       "; ".join(tried[int(j)]))
    for j in np.flatnonzero(~batch.converged):
        logger.warning("contact solve did not converge for surface %d at %s (tol %.3g); "
                       "tried: %s; returned flagged (converged=False)", j,
                       control.describe(j), tol, "; ".join(tried[int(j)]))
    return batch, approaches
