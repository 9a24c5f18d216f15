"""Loading, unloading, reloading: the pressure cap's permanent set along a loading path.

The capped problem (``0 <= p <= H``, :func:`~roughcontact.contact.solve`) is elastic
and perfectly plastic at the surface: where the pressure sits at the cap the elements
interpenetrate the flat (their gap ``g = u + f - d`` is negative), and nothing of that
is kept from one solve to the next. Here it is kept. After every converged step the
surface yields where it is saturated, by the interpenetration:

    w <- w + max(0, -g)  on the elements with p = H,

``w >= 0`` [m] the accumulated plastic displacement (the surface flattened), and the
next step is solved on the flattened surface, ``f + w`` in place of ``f`` (the
separation; the heights lowered by ``w``). So the gap closes where the surface
yielded; ``w`` never falls (on unloading the contact is elastic with the flattened
surface); and the approach keeps its origin, the original surface's first touch, through
every cycle. This is the penetration-hardness model of Almqvist et al. (2007) and of
the plastic systems of Weber et al. (2018) (ContactMechanics' ``PlasticSystem`` adds
the saturated elements' gaps to its plastic displacement after each successful
minimisation, alike).

A :class:`LoadingPath` is the sequence of approaches [m] or mean pressures [Pa] the
surfaces go through, which may rise and fall (:meth:`LoadingPath.cycles`: load to a
peak, unload, reload, several times); :func:`cycle_sweep` solves it on every surface
with any operator and solver path of :func:`~roughcontact.contact.solve_many` (the same
problem, options and retries), and returns a :class:`CycleResult`: per step the
approach, the load, the real and plastic areas, the plastic volume ``sum w dA``, the
permanent set ``min(f + w) - min(f)`` (the approach at which the flattened surface
first touches: the residual approach once unloaded), the tangent stiffness on the
free set (:mod:`roughcontact.contact.stiffness`: elements in contact below the cap),
and the final ``w``. :func:`loop_work` is the work of the load along the path,
``sum 1/2 (F_i + F_{i+1}) (d_{i+1} - d_i)``: over a closed cycle, the energy it
dissipates, which is the plastic work ``H dV_p`` to the steps' accuracy.

A surface whose step does not converge (after the solver's retries) is not flattened
by it: its later steps are flagged too (their numbers NaN), since they would rest on
a surface that was never solved, and a warning names it.

References
----------
A. Almqvist, F. Sahlin, R. Larsson, S. Glavatskih, "On the dry elasto-plastic contact of
nominally flat surfaces", Tribology International 40 (2007) 574-579.
B. Weber, T. Suhina, T. Junge, L. Pastewka, A. M. Brouwer, D. Bonn, "Molecular probes
reveal deviations from Amontons' law in multi-asperity frictional contacts", Nature
Communications 9 (2018) 888.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from dataclasses import dataclass

import numpy as np

from roughcontact.contact import probes as probe_columns
from roughcontact.contact.cg import default_max_iter
from roughcontact.contact.checks import as_operator
from roughcontact.contact.interface import InterfaceGrid
from roughcontact.contact.kkt import free_set
from roughcontact.contact.methods import solve_many
from roughcontact.contact.problem import DEFAULT_OPTIONS, SolverOptions
from roughcontact.contact.products import Products
from roughcontact.contact.stiffness import free_set_cg

__all__ = ["CONTROLS", "SHAKEDOWN_RTOL", "CycleResult", "LoadingPath", "cycle_summary",
           "cycle_sweep", "cycle_to_physical", "legs", "loop_work"]

logger = logging.getLogger("roughcontact.contact")

#: A cycle that adds less than this share of the plastic volume has shaken down: each
#: step's yield closes the interpenetration left by a solve of tolerance ``tol`` (1e-8 by
#: default), so an elastic cycle still adds volume of the order of ``tol`` (measured:
#: 1e-9-1e-8 of the first cycle's on the finite block of config/cycles.yaml).
SHAKEDOWN_RTOL = 1e-6

#: The quantities a loading path may prescribe: the approach [m], the mean pressure [Pa].
CONTROLS = ("approach", "mean_pressure")


@dataclass(frozen=True)
class LoadingPath:
    """The approaches [m] or mean pressures [Pa] a sweep goes through, in order (they may
    rise and fall).

    Parameters
    ----------
    values : array_like, (k,)
        Non-negative, finite; at least one.
    control : {"approach", "mean_pressure"}
        Displacement or load control.
    """

    values: tuple[float, ...]
    control: str = "approach"

    def __post_init__(self):
        if self.control not in CONTROLS:
            raise ValueError(f"control must be one of {CONTROLS}, got {self.control!r}")
        values = np.asarray(self.values, dtype=float).reshape(-1)
        if values.size == 0 or not np.all(np.isfinite(values)) or np.any(values < 0.0):
            raise ValueError(f"values must be finite non-negative {self.control} values, at "
                             f"least one; got {self.values!r}")
        object.__setattr__(self, "values", tuple(float(v) for v in values))

    @classmethod
    def cycles(cls, peak: float, steps: int, *, unload_to: float = 0.0, cycles: int = 1,
               control: str = "approach") -> LoadingPath:
        """From 0 (the first value), ``cycles`` times: up to ``peak`` in ``steps`` equal
        steps, then down to ``unload_to`` in ``steps`` (the next cycle from there)."""
        if not (isinstance(steps, int | np.integer) and steps >= 1):
            raise ValueError(f"steps must be a positive integer, got {steps!r}")
        if not (isinstance(cycles, int | np.integer) and cycles >= 1):
            raise ValueError(f"cycles must be a positive integer, got {cycles!r}")
        if not (math.isfinite(peak) and peak > 0.0 and 0.0 <= unload_to < peak):
            raise ValueError(f"need 0 <= unload_to < peak, got unload_to {unload_to!r}, "
                             f"peak {peak!r}")
        values = list(np.linspace(0.0, peak, steps + 1))
        for cycle in range(cycles):
            values += list(np.linspace(peak, unload_to, steps + 1)[1:])
            if cycle + 1 < cycles:
                values += list(np.linspace(unload_to, peak, steps + 1)[1:])
        return cls(tuple(values), control)

    @property
    def rising(self) -> np.ndarray:
        """Per step, whether it loads (its value above the last one's; the first step
        loads)."""
        values = np.asarray(self.values)
        return np.concatenate([[True], np.diff(values) > 0.0])


@dataclass(frozen=True)
class CycleResult:
    """A :func:`cycle_sweep`: ``(m, k)`` arrays of ``m`` surfaces over the path's ``k``
    steps (NaN where a surface's step, or an earlier one, did not converge), and the
    final plastic displacement.

    Attributes
    ----------
    path : LoadingPath
    approach : ndarray
        ``d`` [m] from the original first touch.
    load, nominal_pressure : ndarray
        ``F = sum p dA`` [N], ``P = F / A_n`` [Pa].
    real_area_fraction, plastic_area_fraction : ndarray
        Shares of elements with ``p > 0`` and with ``p = H`` [-].
    plastic_volume : ndarray
        ``V_p = sum w dA`` [m^3] after the step's yield.
    permanent_set : ndarray
        ``min(f + w) - min(f)`` [m]: the approach at which the flattened surface first
        touches, the residual approach of an unloaded surface.
    contact_stiffness : ndarray
        ``dF/dd`` [N/m] on the free set (elastic on unloading: the flattened surface's).
    converged, stiffness_converged : ndarray of bool
    residual : ndarray
        The dimensionless KKT residual of each solve.
    plastic : ndarray, (m, n)
        ``w`` [m] after the last step.
    pressure : ndarray or None
        ``(m, k, n)`` [Pa] with ``options.return_fields``.
    hardness : float
        ``H`` [Pa].
    element_area : float
    probe_columns : ProbeColumns
        The columns of the interface grid's probes at every step
        (:mod:`roughcontact.contact.probes`: e.g. the flow through the gap on unloading),
        measured on the flattened surface's gap; empty without an interface grid.
    """

    path: LoadingPath
    approach: np.ndarray
    load: np.ndarray
    nominal_pressure: np.ndarray
    real_area_fraction: np.ndarray
    plastic_area_fraction: np.ndarray
    plastic_volume: np.ndarray
    permanent_set: np.ndarray
    contact_stiffness: np.ndarray
    converged: np.ndarray
    stiffness_converged: np.ndarray
    residual: np.ndarray
    plastic: np.ndarray
    pressure: np.ndarray | None
    hardness: float
    element_area: float
    probe_columns: probe_columns.ProbeColumns = dataclasses.field(
        default_factory=probe_columns.ProbeColumns)


_COLUMNS = ("approach", "load", "nominal_pressure", "real_area_fraction",
            "plastic_area_fraction", "plastic_volume", "permanent_set", "contact_stiffness",
            "residual")


def _check(operator, gaps, hardness, element_area):
    """The operator viewed once, the separations ``(m, n)`` and the cap, checked."""
    op = as_operator(operator, element_area)
    gaps = np.asarray(gaps, dtype=float)
    shape = gaps.shape
    gaps = gaps.reshape(shape[0], -1) if gaps.ndim > 1 else gaps.reshape(1, -1)
    if gaps.shape[1] != op.shape[0] or not np.all(np.isfinite(gaps)):
        raise ValueError(f"gaps must be finite separations of {op.shape[0]} elements per "
                         f"surface, got shape {shape}")
    hardness = float(hardness)
    if not (math.isfinite(hardness) and hardness > 0.0):
        raise ValueError(f"hardness must be a finite positive cap H [Pa] (the permanent "
                         f"set needs one), got {hardness!r}")
    return op, gaps, hardness


def _tangent(products, pressure, hardness, options):
    """``(dF/dd, converged)`` of each surface on its free set."""
    solution = free_set_cg(products, free_set(pressure, hardness), np.zeros_like(pressure),
                           options.stiffness_tol, default_max_iter(pressure.shape[1]))
    return products.operator.element_area * solution.total, solution.converged


def _yield(plastic, pressure, gap, hardness, ok) -> np.ndarray:
    """``plastic`` grown by the interpenetration of the saturated elements of the
    converged surfaces ``ok`` (in place); the growth."""
    saturated = (pressure >= hardness) & ok[:, None]
    growth = np.where(saturated, np.maximum(-gap, 0.0), 0.0)
    plastic += growth
    return growth


def _grid_shape(op, n: int) -> tuple[int, int]:
    """``(ny, nx)`` of the operator's contact grid (a square one of ``n`` elements where
    the operator names none)."""
    if op.grid is not None:
        nx, ny = op.grid
        return int(ny), int(nx)
    side = int(round(math.sqrt(n)))
    if side * side != n:
        raise ValueError(f"the operator names no grid and {n} elements are no square: give "
                         "an operator with its grid (e.g. a DenseInfluence) to record probes")
    return side, side


def _measured(interface: InterfaceGrid, shape, pressure, gap, separation) -> dict:
    """The probe columns of one step's fields ``(m, n)`` on ``interface``, the grid
    ``shape`` ``(ny, nx)``."""
    m = pressure.shape[0]
    fields = probe_columns.SolvedFields(pressure.reshape(m, *shape), gap.reshape(m, *shape),
                                        separation, interface.spacing, interface.periodic)
    return probe_columns.measure(interface.probes, fields)


def cycle_sweep(operator, gaps, path: LoadingPath, hardness: float, *,
                element_area: float | None = None,
                options: SolverOptions = DEFAULT_OPTIONS,
                interface: InterfaceGrid | None = None) -> CycleResult:
    """Solve every surface of ``gaps`` along ``path`` with the permanent set of the cap
    ``hardness`` [Pa] (module docstring).

    ``operator`` and ``options`` as in :func:`~roughcontact.contact.solve_many` (its
    ``stiffness`` computes the tangent at every step; ``return_fields`` keeps the
    pressures); ``gaps`` ``(m, n)`` or ``(m, ny, nx)`` [m] the original separations
    ``f``, each with its first touch at ``min(f)``. Every step starts from the last
    converged one's pressure. ``interface``: its probes
    (:class:`~roughcontact.contact.interface.InterfaceGrid`) are measured at every step
    on the gap of the flattened surface.
    """
    op, gaps, hardness = _check(operator, gaps, hardness, element_area)
    m, n = gaps.shape
    k = len(path.values)
    columns = {name: np.full((m, k), np.nan) for name in _COLUMNS}
    converged = np.zeros((m, k), dtype=bool)
    stiffness_ok = np.zeros((m, k), dtype=bool)
    fields = np.full((m, k, n), np.nan) if options.return_fields else None
    plastic, alive = np.zeros((m, n)), np.ones(m, dtype=bool)
    pressure, products, lowest = np.zeros((m, n)), Products(op), gaps.min(axis=1)
    probes = () if interface is None else tuple(interface.probes)
    recorded = probe_columns.ProbeColumns.allocated(probes, (m, k))
    for step, value in enumerate(path.values):
        results = solve_many(op, gaps + plastic, p0=pressure, hardness=hardness,
                             options=dataclasses.replace(options, return_fields=False),
                             **{path.control: value})
        ok = alive & np.array([r.converged for r in results])
        solved = np.stack([r.pressure for r in results])
        gap = np.stack([r.gap for r in results])
        gap += _yield(plastic, solved, gap, hardness, ok)  # the saturated gaps closed
        pressure = np.where(ok[:, None], solved, pressure)
        rows = np.flatnonzero(ok)
        columns["approach"][rows, step] = [results[j].approach for j in rows]
        columns["load"][rows, step] = solved[rows].sum(axis=1) * op.element_area
        columns["nominal_pressure"][rows, step] = solved[rows].mean(axis=1)
        columns["real_area_fraction"][rows, step] = (solved[rows] > 0.0).mean(axis=1)
        columns["plastic_area_fraction"][rows, step] = (solved[rows] >= hardness).mean(axis=1)
        columns["plastic_volume"][rows, step] = plastic[rows].sum(axis=1) * op.element_area
        columns["permanent_set"][rows, step] = (gaps + plastic)[rows].min(axis=1) - lowest[rows]
        columns["residual"][rows, step] = [results[j].residual for j in rows]
        converged[rows, step] = True
        if options.stiffness and rows.size:
            tangent, tangent_ok = _tangent(products, solved[rows], hardness, options)
            columns["contact_stiffness"][rows, step] = tangent
            stiffness_ok[rows, step] = tangent_ok
        if fields is not None:
            fields[rows, step] = solved[rows]
        if probes and rows.size:
            separation = (gaps + plastic)[rows].mean(axis=1) - columns["approach"][rows, step]
            for name, values in _measured(interface, _grid_shape(op, n), solved[rows],
                                          gap[rows], separation).items():
                recorded[name][rows, step] = values
        failed = alive & ~ok
        if failed.any():
            logger.warning("cycle sweep: step %d (%s %.6g) did not converge for surfaces %s; "
                           "their later steps are flagged too (they would rest on a surface "
                           "never solved)", step, path.control, value,
                           np.flatnonzero(failed)[:10].tolist())
        alive &= ok
    return CycleResult(path=path, **columns, converged=converged,
                       stiffness_converged=stiffness_ok, plastic=plastic, pressure=fields,
                       hardness=hardness, element_area=op.element_area,
                       probe_columns=recorded)


def cycle_to_physical(result: CycleResult, sigma: float, E: float, thickness: float,
                      area: float) -> CycleResult:
    """A dimensionless cycle (:func:`cycle_sweep` on the operator ``K = E C / L`` of
    :func:`~roughcontact.contact.nondim.dimensionless_operator`, element area ``1/n``,
    separations in units of sigma, the cap ``H L / (E sigma)``, a path of ``d / sigma``
    or ``P L / (E sigma)``) in SI units for one ``sigma`` [m], ``E`` [Pa], block
    ``thickness`` L [m] and nominal ``area`` A_n [m^2] (Eq 28-32 of Kumar et al. 2006,
    :mod:`roughcontact.contact.nondim`): lengths times sigma, pressures times
    ``E sigma / L``, the load ``P A_n``, the stiffness ``dF/dd = E (dPhat/ddhat) A_n / L``,
    the plastic volume ``mean(w) A_n``. Its probe columns are left as they are (in
    units of sigma to their ``length_power``)."""
    pressure_scale = E * sigma / thickness
    path = LoadingPath(tuple(np.asarray(result.path.values)
                             * (sigma if result.path.control == "approach" else pressure_scale)),
                       result.path.control)
    n = result.plastic.shape[1]
    return dataclasses.replace(
        result, path=path, approach=result.approach * sigma,
        load=result.load * pressure_scale * area,
        nominal_pressure=result.nominal_pressure * pressure_scale,
        plastic_volume=result.plastic_volume * n * (area / n) * sigma,
        permanent_set=result.permanent_set * sigma,
        contact_stiffness=result.contact_stiffness * E * area / thickness,
        plastic=result.plastic * sigma,
        pressure=None if result.pressure is None else result.pressure * pressure_scale,
        hardness=result.hardness * pressure_scale, element_area=area / n)


def loop_work(result: CycleResult, start: int = 0, stop: int | None = None) -> np.ndarray:
    """The work of the load along steps ``start..stop`` of each surface [J],
    ``sum 1/2 (F_i + F_{i+1}) (d_{i+1} - d_i)`` (trapezoids; the load is piecewise
    linear in the approach between changes of the contact set). From zero load back to
    zero load, the energy the cycle dissipated. NaN for a surface with an unconverged
    step in the range."""
    load = result.load[:, start:stop]
    approach = result.approach[:, start:stop]
    return 0.5 * ((load[:, 1:] + load[:, :-1]) * np.diff(approach, axis=1)).sum(axis=1)


def _cycles(path: LoadingPath) -> list[tuple[int, int, int]]:
    """``(start, peak, end)`` step indices of each cycle of ``path``: a rise from
    ``start`` to its highest step ``peak``, then the fall to ``end`` (the last step
    before the next rise, or the path's end)."""
    values = np.asarray(path.values)
    turns = np.flatnonzero(np.diff(np.sign(np.diff(values))) != 0) + 1
    ends = [0, *turns.tolist(), len(values) - 1]
    cycles = []
    for i in range(0, len(ends) - 2, 2):
        start, peak, end = ends[i], ends[i + 1], ends[i + 2]
        if values[peak] > values[start]:
            cycles.append((start, peak, end))
    return cycles


def legs(path: LoadingPath) -> tuple[np.ndarray, np.ndarray]:
    """Per step of ``path``, the cycle it belongs to (1, 2, ...; a cycle begins where
    the path turns to rise again) and its leg: ``"loading"`` (the first cycle's rise,
    the first step included), ``"unloading"``, ``"reloading"`` (a later cycle's
    rise)."""
    rising = path.rising
    starts = np.concatenate([[True], rising[1:] & ~rising[:-1]])
    cycle = np.cumsum(starts)
    leg = np.where(~rising, "unloading", np.where(cycle == 1, "loading", "reloading"))
    return cycle, leg


def _at_half_load(load, stiffness, peak: int, rows) -> np.ndarray:
    """The tangent stiffness at half the peak load of each surface, interpolated in the
    load along ``rows`` (the steps of one leg, any order)."""
    out = np.full(load.shape[0], np.nan)
    for j in range(load.shape[0]):
        loads, tangent = load[j, rows], stiffness[j, rows]
        order = np.argsort(loads)
        if np.all(np.isfinite(loads)) and np.all(np.isfinite(tangent)):
            out[j] = np.interp(load[j, peak] / 2, loads[order], tangent[order])
    return out


def cycle_summary(result: CycleResult) -> dict[str, np.ndarray]:
    """What each cycle of a :func:`cycle_sweep` did, ``(m, cycles)`` arrays by name:

    ``peak_load`` [N]; ``dissipated`` [J], the loop's work (:func:`loop_work`) from
    the cycle's start to its end; ``plastic_work`` [J], ``H`` times the plastic volume
    the cycle added; ``permanent_set`` [m] at its end (the residual approach where it
    unloads to zero load); ``unloading_stiffness_ratio``, the unloading leg's tangent
    over the loading leg's at half the peak load (interpolated in the load; above 1:
    the spots stay larger); ``shaken_down``, the cycle added no plastic volume beyond
    :data:`SHAKEDOWN_RTOL` of the total (elastic from then on)."""
    cycles = _cycles(result.path)
    m = result.load.shape[0]
    out = {name: np.full((m, len(cycles)), np.nan) for name in (
        "peak_load", "dissipated", "plastic_work", "permanent_set",
        "unloading_stiffness_ratio")}
    out["shaken_down"] = np.zeros((m, len(cycles)), dtype=bool)
    total = result.plastic_volume[:, -1]
    for c, (start, peak, end) in enumerate(cycles):
        before = result.plastic_volume[:, start] if start > 0 else np.zeros(m)
        added = result.plastic_volume[:, end] - before
        out["peak_load"][:, c] = result.load[:, peak]
        out["dissipated"][:, c] = loop_work(result, start, end + 1)
        out["plastic_work"][:, c] = result.hardness * added
        out["permanent_set"][:, c] = result.permanent_set[:, end]
        loading = _at_half_load(result.load, result.contact_stiffness, peak,
                                np.arange(start, peak + 1))
        unloading = _at_half_load(result.load, result.contact_stiffness, peak,
                                  np.arange(peak, end + 1))
        out["unloading_stiffness_ratio"][:, c] = unloading / loading
        out["shaken_down"][:, c] = added <= SHAKEDOWN_RTOL * total
    return out

