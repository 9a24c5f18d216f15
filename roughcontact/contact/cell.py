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

import dataclasses
from typing import TYPE_CHECKING

import numpy as np

from roughcontact.contact import aggregate, nondim, validity
from roughcontact.contact.curves import NondimSweep, PhysicalSweep
from roughcontact.contact.cycles import cycle_sweep
from roughcontact.contact.interface import InterfaceGrid
from roughcontact.contact.methods import resolve_method

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "APPROACH_RANGE",
    "BULK_FACTOR",
    "VALIDITY_QUANTITIES",
    "aggregate_sweep",
    "approach_grid",
    "block_interface",
    "cycle_cell",
    "nondim_pressure",
    "sweep_and_aggregate",
    "sweep_cell",
    "validity_table",
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
    ``end / APPROACH_RANGE``, fine where the load grows fastest; first touch
    itself (``d = 0``, no load) is left out.

    Parameters
    ----------
    heights : ndarray, (m, ny, nx) or (m, n)
        Heights in units of sigma (checked as by
        :func:`~roughcontact.contact.nondim.initial_separation`).
    pressure_end : float
        ``P L / (E sigma)`` every surface must reach.
    steps : int
        Number of approaches.

    Returns
    -------
    ndarray, (steps,)
        Strictly increasing approaches [-] (units of sigma).
    """
    nondim.initial_separation(heights)  # a batch of heights in units of sigma
    if isinstance(steps, bool) or int(steps) != steps or steps < 1:
        raise ValueError(f"steps must be a positive integer, got {steps!r}")
    end = bulk_factor * pressure_end + float(np.max(heights))
    if not (np.isfinite(end) and end > 0.0):
        raise ValueError(f"end must be a finite positive number, got {end!r}")
    return np.geomspace(end / APPROACH_RANGE, end, int(steps))


def block_interface(geometry) -> InterfaceGrid:
    """The :class:`~roughcontact.contact.interface.InterfaceGrid` of a block's contact
    grid: elements of ``size / grid`` [m]; not periodic (the block's sides are its
    edges: nothing connects across them)."""
    (lx, ly), (nx, ny) = geometry.size, geometry.grid
    return InterfaceGrid((lx / nx, ly / ny), periodic=False)


#: The study's sweep (:func:`sweep_cell`): mixed precision, the pressure profiles and the
#: interface quantities on the block's grid recorded; a job's variant is
#: ``SWEEP_OPTIONS.with_(method=..., tol=...)``.
SWEEP_OPTIONS = nondim.CellOptions().with_(precision="mixed", profile=True, interface=True)


def sweep_cell(unit_influence, heights: np.ndarray, geometry, pressure_end: float, steps: int,
               *, options: nondim.CellOptions = SWEEP_OPTIONS, rows: slice | None = None,
               bulk_factor: float = BULK_FACTOR) -> NondimSweep:
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
    options : roughcontact.contact.nondim.CellOptions
        The sweep's settings (default :data:`SWEEP_OPTIONS`; a variant:
        :meth:`~roughcontact.contact.nondim.CellOptions.with_`). Its ``interface`` may be
        True: the grid of ``geometry`` (:func:`block_interface`: it then needs
        ``size`` and ``grid``), or an ``InterfaceGrid`` (e.g. with a counter body's
        deflection weights, :mod:`roughcontact.contact.counterface`).
    rows : slice, optional
        Solve only these surfaces, on the approach grid of the whole cell (the
        audit re-solves one stored batch this way).
    bulk_factor : float
        As in :func:`approach_grid` (larger for a pair of bodies).
    """
    approaches = approach_grid(heights, pressure_end, steps, bulk_factor)
    if rows is not None:
        heights = heights[rows]
    return nondim.solve_cell(unit_influence, heights, thickness=geometry.thickness,
                             element_area=geometry.element_area, approaches=approaches,
                             options=dataclasses.replace(
                                 options, interface=_interface_grid(options.interface,
                                                                    geometry)))


def cycle_cell(unit_influence, heights: np.ndarray, geometry, path, *,
               nondim_hardness: float, solver=nondim.CELL_SOLVER,
               interface: object = None):
    """Every surface of a cell along a loading ``path`` in the dimensionless variables of
    :func:`sweep_cell` (:func:`roughcontact.contact.cycles.cycle_sweep`: the cap's
    permanent set kept from step to step).

    ``unit_influence``, ``heights`` (units of sigma) and ``geometry`` as in
    :func:`sweep_cell`; ``path`` a :class:`~roughcontact.contact.cycles.LoadingPath` of
    ``P L / (E sigma)`` (or ``d / sigma``); ``nondim_hardness`` the cap ``H L / (E
    sigma)``; ``solver`` the :class:`~roughcontact.contact.problem.SolverOptions` of
    every step (``"auto"`` resolved for the operator); ``interface`` as the option of
    :func:`sweep_cell` (True: the block's grid), its probes measured at every step.
    Returns the dimensionless :class:`~roughcontact.contact.cycles.CycleResult`
    (:func:`~roughcontact.contact.cycles.cycle_to_physical` takes it to SI units).
    """
    gaps = nondim.initial_separation(heights)
    m, n = gaps.shape
    operator = nondim.cell_operator(unit_influence, geometry.thickness, geometry.element_area,
                                    n)
    solver = solver.with_(method=resolve_method(solver.method, operator, nondim_hardness))
    return cycle_sweep(operator, gaps.reshape(np.shape(heights)), path, nondim_hardness,
                       element_area=1.0 / n, options=solver,
                       interface=_interface_grid(interface, geometry))


def _interface_grid(interface, geometry) -> InterfaceGrid | None:
    if isinstance(interface, InterfaceGrid):
        return interface
    return block_interface(geometry) if interface else None


def aggregate_sweep(sweep: NondimSweep, sigma: float, E: float, pressures,
                    hardness: float | None = None,
                    ) -> tuple[PhysicalSweep, pd.DataFrame]:
    """The sweep in SI units for ``sigma`` [m] and ``E`` [Pa], averaged at ``pressures`` [Pa].

    ``hardness`` [Pa] is the cap of a capped sweep (checked by
    :func:`~roughcontact.contact.nondim.to_physical`). Returns the
    :class:`~roughcontact.contact.curves.PhysicalSweep` and the table of
    :func:`roughcontact.contact.aggregate.aggregate_cell`.
    """
    physical = nondim.to_physical(sweep, sigma, E, hardness=hardness)
    return physical, aggregate.aggregate_cell(physical, pressures)


def validity_table(sweep: NondimSweep, sigma: float, E: float, hardness: float,
                   pressures, *, confidence: float = 0.95) -> pd.DataFrame:
    """How much of an elastic cell lies above a hardness, per nominal-pressure level.

    For every surface and step, the share of the real contact area, of the
    load, and the excess load ``sum (p - H)_+ / sum p`` above ``H`` [Pa] are
    read from the stored profiles (:func:`roughcontact.contact.validity.fractions_above`,
    no extra solve), interpolated onto ``pressures`` [Pa] like every other
    quantity (:func:`roughcontact.contact.aggregate.interpolate`) and averaged
    over the surfaces with the Student-t band.

    Returns
    -------
    pandas.DataFrame
        One row per level: ``nominal_pressure`` [Pa], ``hardness`` [Pa], and
        for ``area_above``, ``load_above`` and ``excess_load`` the
        ``_mean``, ``_half_width`` and ``_count`` columns.

    Raises
    ------
    ValueError
        If the sweep has no profiles (solved without ``profile``) or is capped.
    """
    if sweep.pressure_profile is None or sweep.profile_ranks is None:
        raise ValueError("the sweep has no pressure profiles (solved with profile=False, or "
                         "stored by an older version): solve it again with profile=True")
    if sweep.nondim_hardness is not None:
        raise ValueError("the sweep is capped: its saturated share is plastic_area_fraction")
    physical = nondim.to_physical(sweep, sigma, E)
    shares = validity.fractions_above(sweep.profile_ranks, sweep.pressure_profile,
                                      sweep.load_profile, sweep.real_area_fraction,
                                      sweep.nominal_pressure,
                                      # H L / (E sigma): the threshold in the sweep's units
                                      nondim_pressure(hardness, thickness=sweep.thickness,
                                                      E=E, sigma=sigma))
    levels = np.asarray(pressures, dtype=float)
    columns = {"nominal_pressure": levels, "hardness": np.full(levels.size, float(hardness))}
    for name in VALIDITY_QUANTITIES:
        samples = aggregate.interpolate(physical, shares[name], levels)
        mean, half_width, count = aggregate.statistics(samples, confidence)
        columns.update({f"{name}_mean": mean, f"{name}_half_width": half_width,
                        f"{name}_count": count})
    import pandas as pd

    return pd.DataFrame(columns)


#: Shares above a hardness in :func:`validity_table` (all [-]).
VALIDITY_QUANTITIES = ("area_above", "load_above", "excess_load")


def sweep_and_aggregate(unit_influence, heights: np.ndarray, geometry, *, sigma: float,
                        pressures, steps: int, reach: float = 1.0,
                        options: nondim.CellOptions = SWEEP_OPTIONS,
                        ) -> tuple[NondimSweep, PhysicalSweep, pd.DataFrame]:
    """Sweep a cell and average it at ``pressures`` [Pa]: :func:`sweep_cell` then
    :func:`aggregate_sweep`.

    ``geometry`` also gives Young's modulus ``E`` [Pa]; the sweep ends at
    ``reach`` times the largest of ``pressures``; ``sigma`` [m] is the height scale
    of ``heights``. ``options`` as in :func:`sweep_cell`.
    """
    pressures = np.asarray(pressures, dtype=float)
    end = reach * nondim_pressure(pressures.max(), thickness=geometry.thickness, E=geometry.E,
                                  sigma=sigma)
    sweep = sweep_cell(unit_influence, heights, geometry, end, steps, options=options)
    physical, table = aggregate_sweep(sweep, sigma, geometry.E, pressures)
    return sweep, physical, table
