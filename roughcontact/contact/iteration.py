"""The projected iteration shared by steepest descent and constrained CG, batched over surfaces.

Each surface (row) is an independent problem (Eq 27) with its own free set,
search direction and convergence; finished surfaces leave the batch so the
products ``P C`` shrink as the solve proceeds. An iteration takes the
method's search direction ``s`` (a :class:`Rule`: :mod:`.steepest`,
:mod:`.cg`), the exact line search ``alpha = (g_F . s) / (s . C s)``, the
step ``p -= alpha s`` and the method's projection onto ``0 <= p (<= H)``.

The gap ``g = C p + f - d`` is updated from the product with the search
direction and a sparse correction for the elements the projection changed;
it is recomputed exactly every ``REFRESH_EVERY`` iterations and before a
surface is accepted as converged. With single-precision search products
(``precision="mixed"``, :class:`~roughcontact.contact.products.Products`)
the rounding this leaves in ``g`` is removed by the exact recomputations
(the first when the residual estimate reaches ``MIXED_FLOOR``), so the
returned solution meets ``tol`` in double precision all the same.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from roughcontact.contact.kkt import gap_scale, kkt_residuals
from roughcontact.contact.products import Products
from roughcontact.contact.result import Batch

__all__ = ["MIXED_FLOOR", "REFRESH_EVERY", "Rule", "clip_to_bounds", "iterate"]

#: Iterations between exact recomputations of u = C p (rounding-drift control).
REFRESH_EVERY = 100
#: Residual at which single-precision products hand over to an exact check.
MIXED_FLOOR = 1e-5


class Rule(Protocol):
    """What a projected method adds to the shared iteration (one instance per solve).

    ``name`` names the method in messages. :meth:`search` returns the gap on
    the free set ``g_F`` (rows = surfaces) and the search direction;
    :meth:`project` the changes of the projection after the step, as
    ``(rows, cols, trial, new)``: the elements changed, their pressures after
    the step and after the projection. :meth:`keep` drops the rows of
    finished surfaces from any state the rule carries.
    """

    name: str

    def search(self, pressure, gap) -> tuple[np.ndarray, np.ndarray]: ...

    def project(self, pressure, gap, step, diagonal): ...

    def keep(self, keep: np.ndarray) -> None: ...


def clip_to_bounds(pressure, changed, hardness):
    """``(rows, cols, trial, new)`` of the elements ``changed``: their pressures and those
    pressures clipped onto ``[0, H]`` (0 without a cap)."""
    rows, cols = np.nonzero(changed)
    trial = pressure[rows, cols]
    new = np.zeros_like(trial) if hardness is None else np.clip(trial, 0.0, hardness)
    return rows, cols, trial, new


def check_curvature(products: Products, direction, curvature, surfaces, method: str,
                    iteration: int) -> None:
    """Refuse a non-convex problem: a search direction with ``s . C s <= 0``.

    Eq 27 is a convex problem only for a positive definite ``C``; a non-zero
    direction ``s`` with non-positive curvature proves that ``C`` is not,
    and the line search along it has no minimum (``"exact"`` refuses such a
    ``C`` when its Cholesky factorization fails). Called only when some
    curvature is ``<= 0``, so the normal iteration pays nothing: zero
    directions (nothing left to move) pass, and with single-precision
    products the curvature is confirmed with a double-precision product
    before refusing.

    Raises
    ------
    ValueError
        Naming the surface (row of the batch), the iteration and the curvature.
    """
    rows = np.flatnonzero((curvature <= 0.0) & direction.any(axis=1))
    if not rows.size:
        return
    if products.mixed:
        exact = np.einsum("ij,ij->i", products.exact(direction[rows]), direction[rows])
        bent = exact <= 0.0
        rows, values = rows[bent], exact[bent]
        if not rows.size:
            return
    else:
        values = curvature[rows]
    norm = float(np.einsum("i,i->", direction[rows[0]], direction[rows[0]]))
    raise ValueError(
        f"operator must be positive definite: the {method} search direction s of surface "
        f"{int(surfaces[rows[0]])} at iteration {iteration} has non-positive curvature "
        f"s.C s / s.s = {values[0] / norm:.6g} m/Pa <= 0, so C has a negative or zero "
        f"eigenvalue and Eq 27 has no unique minimum; check the influence matrix "
        f"(symmetric positive definite, Eq 39)"
    )


class _Iterates:
    """The unfinished surfaces of a batched solve: pressures, gaps and bookkeeping."""

    def __init__(self, products: Products, gaps, d, pressure, tol: float):
        m = gaps.shape[0]
        self.products = products
        self.rigid = gaps - d[:, None]
        self.scale = gap_scale(self.rigid)
        self.surfaces = np.arange(m)
        self.p = pressure.copy()
        self.cost = np.zeros(m)
        self.gap = self.rigid.copy()
        loaded = np.flatnonzero(self.p.any(axis=1))
        if loaded.size:
            self.gap[loaded] += products.exact(self.p[loaded])
            self.cost[loaded] += 1.0
        self.stale = np.zeros(m, dtype=bool)
        self.verify_at = np.full(m, max(tol, MIXED_FLOOR) if products.mixed else tol)

    def residuals(self, diagonal, hardness, last: bool, tol: float) -> np.ndarray:
        """The KKT residual of each surface, recomputed on an exact gap where it
        would accept the surface."""
        res = kkt_residuals(self.p, self.gap, diagonal, self.scale, hardness)
        check = self.stale & ((res <= self.verify_at) | last)
        if check.any():
            # Accept only on an exactly recomputed gap.
            idx = np.flatnonzero(check)
            self.gap[idx] = self.products.exact(self.p[idx]) + self.rigid[idx]
            self.cost[idx] += 1.0
            res[idx] = kkt_residuals(self.p[idx], self.gap[idx], diagonal, self.scale[idx],
                                     hardness)
            self.stale[idx] = False
            self.verify_at[idx] = tol
        return res

    def finish(self, finished, res, out: Batch, iteration: int, tol: float, rule) -> None:
        """Store the ``finished`` surfaces in ``out`` and drop them from the batch."""
        idx = np.flatnonzero(finished)
        out.store(self.surfaces[idx], self.p[idx], self.gap[idx] - self.rigid[idx], iteration,
                  self.cost[idx], res[idx], tol)
        keep = ~finished
        self.surfaces = self.surfaces[keep]
        self.p, self.gap, self.rigid = self.p[keep], self.gap[keep], self.rigid[keep]
        self.scale, self.cost = self.scale[keep], self.cost[keep]
        self.stale, self.verify_at = self.stale[keep], self.verify_at[keep]
        rule.keep(keep)

    def update_gap(self, iteration: int, rows, cols, change) -> None:
        """The gap after the projection: exact every ``REFRESH_EVERY`` iterations, else
        corrected for the elements the projection changed by ``change``."""
        if iteration % REFRESH_EVERY == 0:
            self.gap = self.products.exact(self.p) + self.rigid
            self.cost += 1.0
            self.stale[:] = False
        else:
            self.gap += self.products.correction(rows, cols, change, self.p.shape[0], self.cost)
            self.stale[:] = True


def _line_search(products: Products, state: _Iterates, gap_free, direction, method: str,
                 iteration: int):
    """Exact step lengths ``alpha`` along ``direction`` and the product ``C s``."""
    product = products.search(direction)
    state.cost += 1.0
    numerator = np.einsum("ij,ij->i", gap_free, direction)
    denominator = np.einsum("ij,ij->i", product, direction)
    if (denominator <= 0.0).any():
        check_curvature(products, direction, denominator, state.surfaces, method, iteration)
    step = np.divide(numerator, denominator, out=np.zeros_like(numerator),
                     where=denominator > 0.0)
    step[~(np.isfinite(step) & (step > 0.0))] = 0.0
    return step, product


def iterate(products: Products, gaps, d, pressure, tol: float, max_iter: int, rule: Rule,
            hardness=None) -> Batch:
    """Solve Eq 27 (capped at ``hardness`` [Pa] if given) on the rows of ``gaps``.

    Parameters
    ----------
    products : Products
        The products with ``C`` [m/Pa] (double or mixed precision).
    gaps : ndarray (m, n)
        Initial separations ``f`` [m].
    d : ndarray (m,)
        Approaches [m].
    pressure : ndarray (m, n)
        Starting pressures [Pa], within ``[0, H]``.
    tol, max_iter
        Tolerance on the KKT residual and iteration limit.
    rule : Rule
        The method's search direction and projection.

    Returns
    -------
    Batch
        Pressures, displacements and work of each surface.
    """
    m, n = gaps.shape
    out = Batch.empty(m, n)
    diagonal = products.operator.diagonal()
    state = _Iterates(products, gaps, d, pressure, tol)
    iteration = 0
    while state.surfaces.size:
        last = iteration >= max_iter
        res = state.residuals(diagonal, hardness, last, tol)
        finished = ~state.stale & ((res <= tol) | last)
        if finished.any():
            state.finish(finished, res, out, iteration, tol, rule)
            if not state.surfaces.size:
                break
        gap_free, direction = rule.search(state.p, state.gap)
        step, product = _line_search(products, state, gap_free, direction, rule.name,
                                     iteration)
        state.p -= step[:, None] * direction
        rows, cols, trial, new = rule.project(state.p, state.gap, step, diagonal)
        state.p[rows, cols] = new
        state.gap -= step[:, None] * product
        iteration += 1
        state.update_gap(iteration, rows, cols, new - trial)
    out.count_whole_products()
    return out
