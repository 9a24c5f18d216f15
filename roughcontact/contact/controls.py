"""The two controls of a contact solve: the approach given, or the mean pressure.

Displacement control (:class:`Approaches`) gives each surface its rigid-body
approach ``d`` [m]; load control (:class:`Loads`) its mean pressure ``P``
[Pa], met to ``|mean p - P| <= load_tol P`` with the approach found with the
solution (:mod:`roughcontact.contact.loads`). Both solve a batch of surfaces
with a method alike, so the retries of an unconverged solve
(:mod:`roughcontact.contact.retries`) and the sweeps take either without
asking which it is.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from roughcontact.contact.loads import load_errors, solve_at_loads
from roughcontact.contact.result import Batch

__all__ = ["Approaches", "Loads"]


@dataclass(frozen=True)
class Approaches:
    """Displacement control: the approach ``d`` [m] of each surface, (m,)."""

    approach: np.ndarray

    def rows(self, index) -> Approaches:
        """The control of the surfaces ``index``."""
        return Approaches(self.approach[index])

    def solve(self, method, products, gaps, start, tol: float, max_iter: int,
              hardness) -> tuple[Batch, np.ndarray]:
        """``method`` on the rows of ``gaps`` [m] from ``start`` [Pa]; the batch and the
        approaches [m]."""
        batch = method.solve(products, gaps, self.approach.copy(), start, tol, max_iter,
                             hardness)
        return batch, self.approach.copy()

    def describe(self, j: int) -> str:
        """Surface ``j``'s target, for a log line."""
        return f"approach {self.approach[j]:.6g} m"

    def load_error(self, batch: Batch) -> np.ndarray:
        """Zeros: no load is prescribed."""
        return np.zeros(batch.pressure.shape[0])


@dataclass(frozen=True)
class Loads:
    """Load control: the mean pressure ``P`` [Pa] of each surface, (m,), met to
    ``load_tol`` (relative) besides the KKT tolerance."""

    mean_pressure: np.ndarray
    load_tol: float

    def rows(self, index) -> Loads:
        """The control of the surfaces ``index``."""
        return Loads(self.mean_pressure[index], self.load_tol)

    def solve(self, method, products, gaps, start, tol: float, max_iter: int,
              hardness) -> tuple[Batch, np.ndarray]:
        """``method`` at the loads (:func:`~roughcontact.contact.loads.solve_at_loads`);
        ``converged`` where both tolerances are met."""
        return solve_at_loads(method, products, gaps, self.mean_pressure.copy(), start, tol,
                              max_iter, hardness, self.load_tol)

    def describe(self, j: int) -> str:
        """Surface ``j``'s target, for a log line."""
        return f"mean pressure {self.mean_pressure[j]:.6g} Pa"

    def load_error(self, batch: Batch) -> np.ndarray:
        """``|mean p - P| / P`` of each row of ``batch`` [-]."""
        return load_errors(batch.pressure, self.mean_pressure)
