"""One contact cell from heights to averaged curves: the recipe every caller shares.

A cell is ``m`` surfaces (heights in units of sigma) on one elastic body. The
workflow's contact job, the audit's re-solve and the reports all sweep a cell
the same way:

1. :func:`approach_grid`: geometric approaches ``d / sigma`` up to an end that
   reaches the non-dimensional nominal pressure ``P L / (E sigma)``
   (:func:`nondim_pressure`) on every surface without a trial solve;
2. :func:`sweep_cell`: :func:`roughcontact.contact.nondim.solve_cell` on
   those approaches (warm starts, tangent stiffness at every step);
3. :func:`aggregate_sweep`: back to SI units for one (sigma, E) (Eq 28-32)
   and the surfaces averaged at equal nominal pressure
   (:func:`roughcontact.contact.aggregate.aggregate_cell`).

:func:`sweep_and_aggregate` runs all three.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pandas as pd

from roughcontact.contact import aggregate, nondim

__all__ = [
    "APPROACH_RANGE",
    "BULK_FACTOR",
    "aggregate_sweep",
    "approach_grid",
    "nondim_pressure",
    "sweep_and_aggregate",
    "sweep_cell",
]

#: Ratio of the sweep's last to its first approach (the grid is geometric).
APPROACH_RANGE = 64.0
#: Upper bound of E / E_u used to place the sweep's end (E_u = E for nu = 0).
BULK_FACTOR = 1.1


def nondim_pressure(pressure: float, *, thickness: float, E: float, sigma: float) -> float:
    """Non-dimensional nominal pressure ``P L / (E sigma)`` of ``pressure`` P [Pa].

    ``thickness`` L [m], Young's modulus ``E`` [Pa], height scale ``sigma`` [m].
    """
    return float(pressure) * thickness / (E * sigma)


def approach_grid(heights: np.ndarray, pressure_end: float, steps: int,
                  bulk_factor: float = BULK_FACTOR) -> np.ndarray:
    """Approaches ``d / sigma`` of a sweep: geometric, up to a guaranteed end.

    The end reaches the non-dimensional pressure ``pressure_end`` on every
    surface without a trial solve: averaging the gap over the nominal area
    gives ``d - d_b <= mean(f) = max(h)`` (heights of zero mean), and
    ``d_b = P L / E_u`` with ``E_u >= E / bulk_factor`` (``E_u = E`` for nu = 0,
    rows of ``E C`` summing to L; a few percent above E for nu > 0), so
    ``d = bulk_factor * P_end + max(h)`` is enough. The grid is geometric from
    ``end / APPROACH_RANGE``, fine where the load grows fastest.

    Parameters
    ----------
    heights : ndarray, (m, ny, nx) or (m, n)
        Heights in units of sigma.
    pressure_end : float
        ``P L / (E sigma)`` every surface must reach.
    steps : int
        Number of approaches.

    Returns
    -------
    ndarray, (steps,)
        Strictly increasing approaches [-] (units of sigma).
    """
    end = bulk_factor * pressure_end + float(np.max(heights))
    return nondim.approach_grid(heights, end=end, steps=steps, start=1.0 / APPROACH_RANGE)


def sweep_cell(unit_influence, heights: np.ndarray, geometry, pressure_end: float, steps: int,
               *, method: str = "cg", tol: float = 1e-8, precision: str = "mixed",
               stiffness_tol: float = 1e-6, max_iter: int | None = None,
               batch_size: int | None = None,
               progress: Callable[[nondim.SweepProgress], None] | None = None,
               rows: slice | None = None) -> nondim.NondimSweep:
    """Sweep every surface of a cell to ``pressure_end`` on :func:`approach_grid`.

    Parameters
    ----------
    unit_influence : ndarray (n, n) or operator
        ``E C`` [m] of the body (:func:`roughcontact.contact.nondim.solve_cell`).
    heights : ndarray, (m, ny, nx)
        Heights in units of sigma.
    geometry
        The body: anything with ``thickness`` L [m] and ``element_area`` [m^2]
        (a :class:`~roughcontact.elasticity.influence.BlockGeometry`).
    pressure_end, steps
        As in :func:`approach_grid`.
    method, tol, precision, stiffness_tol, max_iter, batch_size, progress
        As in :func:`roughcontact.contact.nondim.solve_cell`.
    rows : slice, optional
        Solve only these surfaces, on the approach grid of the whole cell (the
        audit re-solves one stored batch this way).
    """
    approaches = approach_grid(heights, pressure_end, steps)
    if rows is not None:
        heights = heights[rows]
    return nondim.solve_cell(unit_influence, heights, thickness=geometry.thickness,
                             element_area=geometry.element_area, approaches=approaches,
                             method=method, tol=tol, max_iter=max_iter,
                             stiffness_tol=stiffness_tol, precision=precision,
                             batch_size=batch_size, progress=progress)


def aggregate_sweep(sweep: nondim.NondimSweep, sigma: float, E: float,
                    pressures) -> tuple[nondim.PhysicalSweep, pd.DataFrame]:
    """The sweep in SI units for ``sigma`` [m] and ``E`` [Pa], averaged at ``pressures`` [Pa].

    Returns the :class:`~roughcontact.contact.nondim.PhysicalSweep` and the
    table of :func:`roughcontact.contact.aggregate.aggregate_cell`.
    """
    physical = nondim.to_physical(sweep, sigma, E)
    return physical, aggregate.aggregate_cell(physical, pressures)


def sweep_and_aggregate(unit_influence, heights: np.ndarray, geometry, *, sigma: float,
                        pressures, steps: int, reach: float = 1.0, **options,
                        ) -> tuple[nondim.NondimSweep, nondim.PhysicalSweep, pd.DataFrame]:
    """Sweep a cell and average it at ``pressures`` [Pa]: :func:`sweep_cell` then
    :func:`aggregate_sweep`.

    ``geometry`` also gives Young's modulus ``E`` [Pa]; the sweep ends at
    ``reach`` times the largest of ``pressures``. ``options`` go to
    :func:`sweep_cell`.
    """
    pressures = np.asarray(pressures, dtype=float)
    end = reach * nondim_pressure(pressures.max(), thickness=geometry.thickness, E=geometry.E,
                                  sigma=sigma)
    sweep = sweep_cell(unit_influence, heights, geometry, end, steps, **options)
    physical, table = aggregate_sweep(sweep, sigma, geometry.E, pressures)
    return sweep, physical, table
