"""Constrained conjugate gradients (Polonsky & Keer 1999) for Eq 27, batched over surfaces.

The displacement-controlled form (no load constraint, so no mean-gap
shift): conjugate gradients on the free set ``F`` (``p > 0``; with a cap
``H``, ``0 < p < H``), the exact line search of
:mod:`roughcontact.contact.iteration`, and a projection onto ``p >= 0``
(``[0, H]``) in which elements out of contact that penetrate (``p = 0``,
``g < 0``) join the contact set with ``p = -alpha g`` (a Jacobi step
``-g / C_ii`` if there is no step); conjugacy then restarts. With a cap,
elements at ``H`` with a positive gap are released the same way, with
``p = H - alpha g``. ``precision="mixed"`` takes the search-direction
products in single precision (:class:`~roughcontact.contact.products.Products`);
convergence is still decided on double-precision residuals.

References
----------
I. A. Polonsky, L. M. Keer, "A numerical method for solving rough contact
problems based on the multi-level multi-summation and conjugate gradient
techniques", Wear 231 (1999) 206-219.
"""

from __future__ import annotations

import numpy as np

from roughcontact.contact.iteration import clip_to_bounds, iterate
from roughcontact.contact.kkt import free_set
from roughcontact.contact.products import Products
from roughcontact.contact.result import Batch

__all__ = ["ConjugateGradient", "default_max_iter", "solve"]


def default_max_iter(n: int) -> int:
    """Iteration limit for ``n`` unknowns: ``max(1000, 2n)``."""
    return max(1000, 2 * n)


class ConjugateGradient:
    """The search direction and projection of constrained CG (a :class:`~.iteration.Rule`)."""

    name = "cg"

    def __init__(self, m: int, n: int, hardness: float | None):
        self.hardness = hardness
        self.direction = np.zeros((m, n))
        self.previous_norm = np.zeros(m)
        self.conjugate = np.zeros(m, dtype=bool)
        # with a cap: elements that joined or left a bound at the last projection
        self.moved = np.zeros((m, n), dtype=bool) if hardness is not None else None

    def keep(self, keep: np.ndarray) -> None:
        self.direction = self.direction[keep]
        self.previous_norm, self.conjugate = self.previous_norm[keep], self.conjugate[keep]
        if self.moved is not None:
            self.moved = self.moved[keep]

    def search(self, pressure, gap):
        """Conjugate direction on the free set; its norm restarts where conjugacy broke."""
        free = free_set(pressure, self.hardness)
        if self.moved is not None:
            # Polonsky & Keer: a joining element is in the contact set. One
            # that joined at the cap (or left it for 0) would otherwise stay
            # out of the search direction; when all join at once (no step
            # yet) their Jacobi values can all exceed H and then all be
            # released again, without end.
            free |= self.moved
        gap_free = gap * free
        norm = np.einsum("ij,ij->i", gap_free, gap_free)
        ratio = np.divide(norm, self.previous_norm, out=np.zeros_like(norm),
                          where=self.conjugate & (self.previous_norm > 0.0))
        self.direction *= ratio[:, None]
        self.direction += gap_free
        self.direction *= free
        self.previous_norm = norm
        return gap_free, self.direction

    def project(self, pressure, gap, step, diagonal):
        """Projection onto ``[0, H]``; penetrating elements out of contact join it and,
        with a cap, elements at the cap with a positive gap leave it (conjugacy restarts)."""
        hardness = self.hardness
        changed = pressure < 0.0
        if hardness is not None:
            changed |= pressure > hardness
        overlap = (pressure <= 0.0) & (gap < 0.0)
        changed |= overlap
        if hardness is not None:
            release = (pressure >= hardness) & (gap > 0.0)
            changed |= release
            overlap |= release
        self.conjugate = ~overlap.any(axis=1)
        rows, cols, trial, new = clip_to_bounds(pressure, changed, hardness)
        joins = overlap[rows, cols]
        g_join = gap[rows[joins], cols[joins]]
        s_join = step[rows[joins]]
        new[joins] = np.where(s_join > 0.0, -s_join * g_join, -g_join / diagonal[cols[joins]])
        if hardness is not None:
            # released elements start from H, joining ones from 0
            new[joins] += np.where(g_join > 0.0, hardness, 0.0)
            new[joins] = np.clip(new[joins], 0.0, hardness)
            self.moved[:] = False
            self.moved[rows[joins], cols[joins]] = True
        return rows, cols, trial, new


def solve(products: Products, gaps, d, pressure, tol: float, max_iter: int,
          hardness=None) -> Batch:
    """Constrained CG on the rows of ``gaps`` (see :func:`~.iteration.iterate`)."""
    rule = ConjugateGradient(*gaps.shape, hardness)
    return iterate(products, gaps, d, pressure, tol, max_iter, rule, hardness)
