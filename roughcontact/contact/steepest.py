"""Projected steepest descent for Eq 27, the paper's method (Fig 6 of Kumar et al. 2006).

The search direction is the gap on the free set (``p > 0`` or ``g < 0``),
the step the exact line search of :mod:`roughcontact.contact.iteration`,
then the projection onto ``p >= 0``. With a cap ``H`` the elements at ``H``
with ``g < 0`` are held and the projection is onto ``[0, H]``. Kept as a
slow baseline: it needs many more products than :mod:`.cg`.
"""

from __future__ import annotations

import numpy as np

from roughcontact.contact.iteration import clip_to_bounds, iterate
from roughcontact.contact.products import Products
from roughcontact.contact.result import Batch

__all__ = ["SteepestDescent", "default_max_iter", "solve"]


def default_max_iter(n: int) -> int:
    """Iteration limit for ``n`` unknowns: ``max(20000, 20n)``."""
    return max(20000, 20 * n)


class SteepestDescent:
    """The search direction and projection of projected steepest descent (a
    :class:`~.iteration.Rule`); it carries no state between iterations."""

    name = "steepest"

    def __init__(self, hardness: float | None):
        self.hardness = hardness

    def keep(self, keep: np.ndarray) -> None:
        pass

    def search(self, pressure, gap):
        """The gap on the free set, which is also the search direction."""
        free = (pressure > 0.0) | (gap < 0.0)
        if self.hardness is not None:
            free &= ~((pressure >= self.hardness) & (gap < 0.0))
        gap_free = gap * free
        return gap_free, gap_free

    def project(self, pressure, gap, step, diagonal):
        """Projection onto ``[0, H]`` (``p >= 0`` without a cap)."""
        changed = pressure < 0.0
        if self.hardness is not None:
            changed |= pressure > self.hardness
        return clip_to_bounds(pressure, changed, self.hardness)


def solve(products: Products, gaps, d, pressure, tol: float, max_iter: int,
          hardness=None) -> Batch:
    """Projected steepest descent on the rows of ``gaps`` (see :func:`~.iteration.iterate`)."""
    return iterate(products, gaps, d, pressure, tol, max_iter, SteepestDescent(hardness),
                   hardness)
