"""Non-dimensional contact sweeps: one solve per surface cell and geometry.

The contact problem of Section 3 of Kumar, Sadeghi & Krousgrill (2006) is
linear and homogeneous, so sigma (the height scale) and E (Young's modulus)
only rescale its solution (Eq 28-32). This module solves it once, in
dimensionless form (:func:`solve_cell`, a
:class:`~roughcontact.contact.curves.NondimSweep`), and maps the result to SI
units for any (sigma, E) (:func:`to_physical`, a
:class:`~roughcontact.contact.curves.PhysicalSweep`), each array by its scale
in :data:`SI_SCALES`.

Scaling
-------
With surface heights ``h = z / sigma``, the unit-modulus compliance
``Chat = E C`` [m] (``influence.unit_modulus_influence``; it depends on the
geometry and nu only) and the block thickness ``L`` [m], define

- influence operator: ``K = Chat / L`` [-]; back: ``C = L K / E`` [m/Pa]
- initial separation: ``fhat = max(h) - h``; back: ``f = sigma fhat`` [m]
- rigid approach: ``dhat = d / sigma``; back: ``d = sigma dhat`` [m]
- element pressure: ``phat = p L / (E sigma)``; back: ``p = E sigma phat / L`` [Pa]
- nominal pressure: ``Phat = mean(phat)``; back: ``P = E sigma Phat / L`` [Pa],
  load ``F = P A_n`` [N]
- mean-plane deflection (Eq 35): ``dhat_b = mean(K phat)``; back:
  ``d_b = sigma dhat_b`` [m]
- real area fraction: unchanged [-]
- normalized stiffness: ``k_P / E = dPhat / ddhat``; back: ``k_P = E dPhat/ddhat``
  [Pa] (Eq 33), contact stiffness ``dF/dd = k_P A_n / L`` [N/m]
- hardness cap: ``nondim_hardness = H L / (E sigma)``; back: ``H`` [Pa]
- a probe column (:mod:`roughcontact.contact.probes`) of lengths to the power
  ``k`` (its ``length_power``; the gaps it reads are in units of sigma): back:
  times ``sigma**k`` (e.g. a flow conductance, a gap cubed [m^3])

Substituting, ``u / sigma = K phat`` and the contact conditions (Eq 19-22)
``u + f - d = 0`` where ``p > 0``, ``>= 0`` elsewhere, become
``K phat + fhat - dhat = 0`` where ``phat > 0``, ``>= 0`` elsewhere: neither
sigma nor E appears. The normalized stiffness of Eq 33 is
``k_P = (L / A_n) dF/dd = (L / A_n) A_n dP/dd = E dPhat/ddhat``.

Relation to the paper's form (Eq 23-26): the paper writes ``p~ = p / E``,
``u~ = u / sigma``, ``d~ = d / sigma`` and ``C~ = C E / sigma = Chat /
sigma``, so ``u~ = C~ p~``. That form is equivalent but keeps sigma inside
``C~`` (and the pressure ``p~`` grows with sigma). The two are related by
``phat = (L / sigma) p~`` and ``K = (sigma / L) C~``; the form used here
absorbs sigma into the pressure, so one solve serves every sigma and E. For a
half-space operator (no thickness) any reference length may play the role
of ``L``, provided the same one is used in :func:`solve_cell` and
:func:`to_physical`.

The KKT residual of :mod:`roughcontact.contact` is invariant under this
scaling (it compares ``C_ii p_i`` with the gap, both lengths, and divides by
the largest rigid interference), so the dimensionless and the SI solves stop
on the same criterion.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from roughcontact.contact import validity
from roughcontact.contact.checks import (
    approach_steps,
    as_operator,
    check_positive,
    given_matrix,
    preconditioned_operator,
)
from roughcontact.contact.curves import (
    DIAGNOSTICS,
    PROFILES,
    SOLVER_FIELDS,
    NondimSweep,
    PhysicalSweep,
    interface_arrays,
    solver_arrays,
)
from roughcontact.contact.methods import resolve_method
from roughcontact.contact.probes import ProbeColumns
from roughcontact.contact.problem import Problem, SolverOptions
from roughcontact.contact.result import INTERFACE
from roughcontact.contact.sweeps import sweep_problem
from roughcontact.elasticity import definiteness
from roughcontact.elasticity.protocol import DenseInfluence

__all__ = [
    "CELL_SOLVER",
    "INTERFACE_SCALES",
    "SI_SCALES",
    "CellOptions",
    "SweepProgress",
    "cell_operator",
    "dimensionless_operator",
    "initial_separation",
    "solve_cell",
    "to_physical",
]

logger = logging.getLogger("roughcontact.nondim")

#: Accepted range of the standard deviation of ``heights`` (in units of sigma);
#: outside it the heights were almost certainly passed in metres.
HEIGHT_STD_RANGE = (0.1, 10.0)
#: Relative tolerance when checking that to_physical gets the geometry of the solve.
GEOMETRY_RTOL = 1e-9
#: Relative tolerance of the dimensionless cap H L / (E sigma) in :func:`to_physical`.
HARDNESS_RTOL = 1e-5
#: The scale that takes each scaled array of a NondimSweep back to SI units
#: (module docstring, Eq 28-32); :func:`to_physical` gives the scales their values.
SI_SCALES = {
    "approach": "sigma",
    "mean_plane_deflection": "sigma",
    "nominal_pressure": "E sigma / L",
    "max_pressure": "E sigma / L",
    "normalized_stiffness": "E",
    "real_area_fraction": "1",
    "plastic_area_fraction": "1",
}
#: The scale of each interface quantity (:mod:`roughcontact.contact.interface`): gaps
#: are heights (sigma); spots, perimeter and areas are lateral, the same in both forms.
#: (A probe column's scale is ``sigma**length_power`` of its
#: :class:`~roughcontact.contact.probes.Column`.)
INTERFACE_SCALES = {name: "1" for name in INTERFACE} | {"mean_gap": "sigma",
                                                        "gap_quantiles": "sigma",
                                                        "counter_deflection": "sigma"}
#: SweepResult field of each array of a NondimSweep: the dimensionless problem has
#: nominal area 1, so the solver's load is ``Phat`` and its tangent stiffness
#: ``dPhat / ddhat = k_P / E``.
FROM_SOLVER = {**SOLVER_FIELDS, "nominal_pressure": "load",
               "normalized_stiffness": "contact_stiffness"}


@dataclass(frozen=True)
class SweepProgress:
    """Progress of :func:`solve_cell`, passed to its ``progress`` callback.

    Attributes
    ----------
    surfaces_done : int
        Surfaces whose sweep has finished, this batch included.
    surfaces_total : int
        Surfaces in the cell.
    step : int
        Approach step reported, 1-based.
    steps_total : int
        Approach steps per surface.
    iterations : int
        Contact-solver iterations of this batch at this step, summed over its
        surfaces.
    unconverged : int
        Surfaces of this batch whose contact solve did not converge at this step.
    elapsed : float
        Wall time since :func:`solve_cell` started [s], when the report is made.
    """

    surfaces_done: int
    surfaces_total: int
    step: int
    steps_total: int
    iterations: int
    unconverged: int
    elapsed: float


# ---------------------------------------------------------------------------
# Inputs


def initial_separation(heights) -> np.ndarray:
    """Dimensionless initial separation ``fhat = max(h) - h`` per surface (Eq 21).

    Parameters
    ----------
    heights : array_like, (m, ny, nx) or (m, n)
        Heights in units of sigma (``z / sigma``), as stored in
        ``results/surfaces/<cell>.h5`` (:func:`roughcontact.study.jobs.storage.read_surfaces`).

    Returns
    -------
    ndarray, (m, n)
        ``fhat >= 0``, zero at each surface's highest point (first touch at
        ``dhat = 0``).

    Raises
    ------
    ValueError
        If the heights are not a finite batch, a surface is flat (all heights
        equal), or their standard deviation is outside ``HEIGHT_STD_RANGE``
        (heights passed in metres, not in sigma).
    """
    h = np.asarray(heights, dtype=float)
    if h.ndim not in (2, 3) or h.shape[0] < 1 or h[0].size < 2:
        raise ValueError(f"heights must have shape (m, ny, nx) or (m, n), got {h.shape}")
    if not np.isfinite(h).all():
        raise ValueError("heights must be finite (NaN or inf found)")
    flat = h.reshape(h.shape[0], -1)
    level = np.ptp(flat, axis=1) == 0.0
    if level.any():
        # std of equal heights is rounding noise (1e-16), not a scale: name the real problem
        j = int(np.argmax(level))
        raise ValueError(
            f"heights of surface {j} are all equal (a flat surface, standard deviation 0): "
            f"it has no roughness scale sigma to make the problem dimensionless. A flat "
            f"punch (full contact, C p = d) is solved in SI units with contact.solve."
        )
    std = flat.std(axis=1)
    low, high = HEIGHT_STD_RANGE
    if ((std < low) | (std > high)).any():
        j = int(np.argmax((std < low) | (std > high)))
        raise ValueError(
            f"heights must be in units of sigma (z / sigma, standard deviation near 1); "
            f"surface {j} has standard deviation {std[j]:.3g}, outside {HEIGHT_STD_RANGE}. "
            f"Divide heights in metres by sigma."
        )
    return flat.max(axis=1, keepdims=True) - flat


class _ScaledOperator:
    """A matrix-free unit-modulus operator divided by ``L``: ``K p = Chat p / L``."""

    def __init__(self, operator, thickness: float):
        self._operator = operator
        self._scale = 1.0 / thickness
        self.shape = tuple(operator.shape)
        grid = getattr(operator, "grid", None)
        if grid is not None:
            self.grid = grid
        mean_compliance = getattr(operator, "mean_compliance", None)
        if mean_compliance is not None:
            self.mean_compliance = mean_compliance * self._scale

    def diagonal(self) -> np.ndarray:
        return np.asarray(self._operator.diagonal(), dtype=float) * self._scale

    def matvec(self, pressure) -> np.ndarray:
        return np.asarray(self._operator.matvec(pressure), dtype=float) * self._scale


class _ScaledGridOperator(_ScaledOperator):
    """A grid FFT operator divided by ``L``, still a
    :class:`~roughcontact.elasticity.protocol.PreconditionedOperator` (so the
    preconditioned CG solves the dimensionless problem too)."""

    def __init__(self, operator, thickness: float):
        super().__init__(operator, thickness)
        self.size = operator.size
        self.column_budget = operator.column_budget
        self._thickness = thickness

    def apply(self, pressure) -> np.ndarray:
        u = self._operator.apply(pressure)
        return u * u.dtype.type(self._scale)

    def preconditioner(self):
        return self._operator.preconditioner()  # its scale does not matter to CG

    def add_columns(self, target, rows, cols, values) -> None:
        self._operator.add_columns(target, rows, cols, np.asarray(values) * self._scale)

    def coarsened(self) -> _ScaledGridOperator:
        return _ScaledGridOperator(self._operator.coarsened(), self._thickness)


def dimensionless_operator(unit_influence, thickness: float):
    """``K = Chat / L``, the influence operator of the dimensionless problem.

    Parameters
    ----------
    unit_influence : ndarray (n, n) or operator object
        Unit-modulus compliance ``Chat = E C`` [m]: a dense symmetric matrix
        (``influence.unit_modulus_influence``, or ``halfspace_influence`` with
        ``E = 1``) or a matrix-free operator with ``shape``, ``diagonal()``
        and ``matvec`` built with ``E = 1`` (e.g. ``PeriodicHalfSpace``).
    thickness : float
        Block thickness ``L`` [m] (for a half-space, any reference length).

    Returns
    -------
    ndarray or operator object
        ``K`` [-], of the same kind as ``unit_influence`` (a
        :class:`~roughcontact.elasticity.protocol.DenseInfluence` for one),
        carrying its certificate of definiteness
        (:mod:`roughcontact.elasticity.definiteness`) divided by ``L``.
    """
    thickness = check_positive(thickness, "thickness")
    if isinstance(unit_influence, np.ndarray) or not hasattr(unit_influence, "matvec"):
        return np.asarray(unit_influence, dtype=float) / thickness
    if isinstance(unit_influence, DenseInfluence):
        mean_compliance = unit_influence.mean_compliance
        scaled = DenseInfluence(given_matrix(unit_influence) / thickness,
                                unit_influence.element_area, unit_influence.grid,
                                None if mean_compliance is None else mean_compliance / thickness)
    elif preconditioned_operator(unit_influence) is not None:
        scaled = _ScaledGridOperator(unit_influence, thickness)
    else:
        scaled = _ScaledOperator(unit_influence, thickness)
    definiteness.carry(unit_influence, scaled, 1.0 / thickness)
    return scaled


def _certified(unit_influence, element_area: float):
    """``E C`` checked and certified positive definite once, in its own unit [m].

    A dense matrix comes back as the checked
    :class:`~roughcontact.elasticity.protocol.DenseInfluence` that keeps the
    certificate, any other operator as given (the certificate kept on it):
    :func:`dimensionless_operator` carries it to ``K``, so that no batch of
    the sweep takes it again.
    """
    checked = as_operator(unit_influence, element_area)
    definiteness.certify(checked, name="the unit-modulus influence operator E C", unit="m")
    return checked if checked.matrix is not None else unit_influence


def cell_operator(unit_influence, thickness: float, element_area: float, n: int):
    """The operator of a cell's dimensionless problem, ``K = E C / L`` (certified once,
    :func:`dimensionless_operator`) viewed with element area ``1/n`` (the nominal area
    1), as :func:`solve_cell` and the cycles of
    :func:`roughcontact.contact.cell.cycle_cell` solve with it."""
    return as_operator(dimensionless_operator(_certified(unit_influence, element_area),
                                              thickness), 1.0 / n)


def _check_steps(approaches, m: int) -> np.ndarray:
    steps = approach_steps(approaches, m, "units of sigma")
    if (np.diff(steps, axis=1) <= 0.0).any():
        raise ValueError("approaches must increase strictly along the steps (units of sigma)")
    return np.ascontiguousarray(steps)


def _check_batch_size(batch_size, m: int) -> int:
    if batch_size is None:
        return m
    if isinstance(batch_size, bool) or int(batch_size) != batch_size or batch_size < 1:
        raise ValueError(f"batch_size must be a positive integer or None, got {batch_size!r}")
    return int(batch_size)


# ---------------------------------------------------------------------------
# Sweep


#: The solver of a cell's sweep unless told otherwise (:class:`CellOptions`): CG to a
#: dimensionless KKT residual of 1e-8, in double precision, with the tangent stiffness at
#: every step.
CELL_SOLVER = SolverOptions(method="cg", tol=1e-8)
_SOLVER_FIELDS = frozenset(field.name for field in dataclasses.fields(SolverOptions))


@dataclass(frozen=True)
class CellOptions:
    """How the surfaces of a cell are swept (:func:`solve_cell`,
    :func:`roughcontact.contact.cell.sweep_cell`): one record for every setting.

    Attributes
    ----------
    solver : SolverOptions
        The solver of every batch's sweep (:func:`roughcontact.contact.sweep`; default
        :data:`CELL_SOLVER`): ``method``, ``tol`` (it bounds the dimensionless KKT
        residual, the same as in SI units), ``max_iter``, ``precision``,
        ``stiffness_tol``, ``profile``, ... Its ``stiffness`` (on by default) gives the
        normalized stiffness ``dPhat/ddhat`` of every step.
    batch_size : int or None
        Surfaces per sweep (None: all in one, the fastest; smaller batches bound
        memory).
    progress : callable or None
        Called with a :class:`SweepProgress` for every step of every batch, in step
        order when the batch is finished.
    nondim_hardness : float or None
        The dimensionless cap ``H L / (E sigma)`` (the result then holds only for the
        (sigma, E, H) with that value, :func:`to_physical` checks it; None: elastic).
    interface : InterfaceGrid or None
        As in :func:`roughcontact.contact.sweep` (its gaps in units of sigma, like the
        heights); :func:`roughcontact.contact.cell.sweep_cell` also takes True, the
        grid of its block.

    Build a variant with :meth:`with_`, e.g. ``CellOptions().with_(method="pivot",
    batch_size=2)``.
    """

    solver: SolverOptions = CELL_SOLVER
    batch_size: int | None = None
    progress: Callable[[SweepProgress], None] | None = None
    nondim_hardness: float | None = None
    interface: object = None

    def with_(self, **changes) -> CellOptions:
        """These options with the fields ``changes`` replaced: the names of
        :class:`~roughcontact.contact.problem.SolverOptions` fields in :attr:`solver`
        (checked again), the others here (an unknown name raises TypeError)."""
        solver = {name: changes.pop(name) for name in list(changes) if name in _SOLVER_FIELDS}
        return dataclasses.replace(self, solver=self.solver.with_(**solver), **changes)


def solve_cell(unit_influence, heights, *, thickness: float, element_area: float, approaches,
               options: CellOptions = CellOptions()) -> NondimSweep:
    """Dimensionless force-deflection sweep of all surfaces of one cell (Eq 27, 33, 35).

    Solves Eq 27 in the variables of the module docstring for every surface at every
    approach with :func:`roughcontact.contact.sweep` (a batch at once, warm starts),
    with the stiffness ``dPhat/ddhat = (1/n) 1^T (K_AA)^-1 1`` (``k_P / E``) at every
    step; element area ``1/n``. The result holds for every sigma and E
    (:func:`to_physical`).

    Parameters
    ----------
    unit_influence : ndarray (n, n) or operator object
        ``Chat = E C`` [m], see :func:`dimensionless_operator`.
    heights : ndarray, (m, ny, nx) or (m, n)
        Surface heights in units of sigma (``z / sigma``).
    thickness : float
        Block thickness ``L`` [m] of the geometry ``Chat`` was built for.
    element_area : float
        Contact element area ``dA`` [m^2] of that geometry (for loads in N).
    approaches : ndarray, (k,) or (m, k)
        Rigid approaches ``dhat = d / sigma`` [-], shared or per surface, non-negative
        and increasing (:func:`roughcontact.contact.cell.approach_grid`).
    options : CellOptions
        The sweep's settings (the solver's among them, :attr:`CellOptions.solver`); a
        variant is built with :meth:`CellOptions.with_`.

    Returns
    -------
    NondimSweep
        (m, k) arrays; steps that did not converge (or gave non-finite values)
        have ``converged=False``, must not be used as results, and are counted
        in a warning.
    """
    thickness = check_positive(thickness, "thickness")
    element_area = check_positive(element_area, "element_area")
    gaps = initial_separation(heights)
    m, n = gaps.shape
    steps = _check_steps(approaches, m)
    operator = cell_operator(unit_influence, thickness, element_area, n)
    hardness = (None if options.nondim_hardness is None else
                check_positive(options.nondim_hardness, "nondim_hardness (H L / (E sigma))"))
    solver = options.solver.with_(method=resolve_method(options.solver.method, operator,
                                                        hardness))
    options = dataclasses.replace(options, batch_size=_check_batch_size(options.batch_size, m),
                                  nondim_hardness=hardness, solver=solver)
    if options.interface is not None:  # the interface quantities need the fields' (ny, nx)
        if np.ndim(heights) != 3:
            raise ValueError(f"interface quantities need heights of shape (m, ny, nx), got "
                             f"{np.shape(heights)}")
        gaps = gaps.reshape(np.shape(heights))
    arrays = _sweep_batches(operator, gaps, steps, options)
    _warn_unconverged(arrays, solver.tol, solver.stiffness_tol)
    return NondimSweep(**arrays, thickness=thickness, element_area=element_area, n_elements=n,
                       method=solver.method, tol=float(solver.tol),
                       stiffness_tol=float(solver.stiffness_tol), precision=solver.precision,
                       max_iter=None if solver.max_iter is None else int(solver.max_iter),
                       nondim_hardness=hardness,
                       profile_ranks=validity.rank_grid(n) if solver.profile else None)


def _sweep_batches(operator, gaps, steps, options: CellOptions) -> dict:
    """:func:`roughcontact.contact.sweep` of ``options.batch_size`` surfaces at a time
    (:func:`solve_cell`): the (m, k) arrays of a NondimSweep, with ``profile`` its
    (m, k, R) profiles, and its ``probe_columns``."""
    m, n = gaps.shape[0], gaps[0].size
    batches, probed = [], []
    start = time.perf_counter()
    for first in range(0, m, options.batch_size):
        rows = slice(first, min(m, first + options.batch_size))
        problem = Problem.of(operator, gaps[rows], hardness=options.nondim_hardness,
                             interface=options.interface, element_area=1.0 / n)
        result = sweep_problem(problem, steps[rows], options=options.solver)
        batch = solver_arrays(result, FROM_SOLVER, stiffness="normalized_stiffness")
        batch["solved_by"] = result.solved_by
        if options.solver.profile:
            batch.update({name: getattr(result, name) for name in PROFILES})
        batch.update(interface_arrays(result))
        _report_batch(batch, rows, m, time.perf_counter() - start, options.progress)
        batches.append(batch)
        probed.append(result.probe_columns)
    return {**{name: np.concatenate([batch[name] for batch in batches]) for name in batches[0]},
            "probe_columns": ProbeColumns.concatenated(probed)}


def _report_batch(batch: dict, rows: slice, m: int, elapsed: float,
                  progress: Callable[[SweepProgress], None] | None) -> None:
    """Log a finished batch of :func:`solve_cell` and report its steps, in order, to
    ``progress``."""
    unconverged = ~batch["converged"]
    k = unconverged.shape[1]
    logger.info("surfaces %d-%d of %d swept over %d steps (%.1f s, %d unconverged steps)",
                rows.start + 1, rows.stop, m, k, elapsed, int(unconverged.sum()))
    if progress is None:
        return
    for step in range(k):
        progress(SweepProgress(
            surfaces_done=rows.stop, surfaces_total=m, step=step + 1, steps_total=k,
            iterations=int(batch["iterations"][:, step].sum()),
            unconverged=int(unconverged[:, step].sum()), elapsed=elapsed))


def _warn_unconverged(arrays: dict, tol: float, stiffness_tol: float) -> None:
    """Warn of the contact and stiffness solves of :func:`solve_cell` that did not converge."""
    total = arrays["converged"].size
    bad = int((~arrays["converged"]).sum())
    if bad:
        logger.warning("%d of %d contact solves did not reach tol %.3g; flagged converged=False",
                       bad, total, tol)
    bad_stiffness = int((~arrays["stiffness_converged"]).sum())
    if bad_stiffness:
        logger.warning("%d of %d stiffness solves did not reach %.3g; flagged "
                       "stiffness_converged=False", bad_stiffness, total, stiffness_tol)


# ---------------------------------------------------------------------------
# Back to SI units


def to_physical(nd: NondimSweep, sigma: float, E: float, thickness: float | None = None,
                area: float | None = None, hardness: float | None = None) -> PhysicalSweep:
    """SI force-deflection curves of a dimensionless sweep for one (sigma, E).

    ``d = sigma dhat``, ``d_b = sigma dhat_b``, ``P = E sigma Phat / L``,
    ``p_max = E sigma phat_max / L``, ``F = P A_n``, real area unchanged,
    ``k_P = E dPhat/ddhat`` (Eq 33) and ``dF/dd = k_P A_n / L`` (module
    docstring; Eq 28-32 of Kumar et al. 2006); each probe column times
    ``sigma**length_power`` (:meth:`~roughcontact.contact.probes.ProbeColumns.in_length`).

    Parameters
    ----------
    nd : NondimSweep
        Result of :func:`solve_cell`.
    sigma : float
        Standard deviation of the heights [m] (the unit of ``heights``).
    E : float
        Young's modulus [Pa].
    thickness : float, optional
        Block thickness ``L`` [m]; must equal the one of the solve, since
        ``K = Chat / L`` fixed it (default: that one).
    area : float, optional
        Nominal area ``A_n`` [m^2]; must equal ``nd.nominal_area`` (default).
    hardness : float, optional
        Pressure cap ``H`` [Pa] of a capped sweep (required for one, refused
        for an elastic one). A capped sweep holds only where ``H L / (E
        sigma)`` equals the value it was solved for: another (sigma, E, H)
        that changes it is refused, and must be solved anew.

    Returns
    -------
    PhysicalSweep
        Converged flags carried over unchanged.
    """
    sigma = check_positive(sigma, "sigma")
    E = check_positive(E, "E")
    _check_geometry(nd, thickness, area)
    length = nd.thickness
    scales = {"sigma": sigma, "E sigma / L": E * sigma / length, "E": E, "1": 1.0}
    cap = _check_cap(nd, hardness, scales["E sigma / L"])
    scaled = {name: scales[scale] * np.asarray(getattr(nd, name), dtype=float)
              for name, scale in SI_SCALES.items()}
    interface = interface_arrays(nd)
    for name, values in interface.items():
        interface[name] = (values if INTERFACE_SCALES[name] == "1"
                           else scales[INTERFACE_SCALES[name]] * values)
    return PhysicalSweep(
        **scaled,
        **interface,
        probe_columns=nd.probe_columns.in_length(sigma),
        **{name: np.array(getattr(nd, name)) for name in DIAGNOSTICS},
        load=scaled["nominal_pressure"] * nd.nominal_area,
        contact_stiffness=scaled["normalized_stiffness"] * nd.nominal_area / length,
        sigma=sigma,
        E=E,
        thickness=length,
        nominal_area=nd.nominal_area,
        hardness=cap,
    )


def _check_geometry(nd: NondimSweep, thickness, area) -> None:
    """Refuse a ``thickness`` or ``area`` other than the solve's (:func:`to_physical`)."""
    for name, given, recorded in (("thickness", thickness, nd.thickness),
                                  ("area", area, nd.nominal_area)):
        if given is None:
            continue
        if abs(check_positive(given, name) - recorded) > GEOMETRY_RTOL * recorded:
            raise ValueError(
                f"{name} = {given!r} differs from the {recorded!r} of the dimensionless solve; "
                f"the influence matrix fixes the geometry, solve the other geometry separately"
            )


def _check_cap(nd: NondimSweep, hardness, pressure_scale: float) -> float | None:
    """``hardness`` [Pa] checked against the dimensionless cap of ``nd`` (:func:`to_physical`)."""
    cap = nd.nondim_hardness
    if cap is None:
        if hardness is not None:
            raise ValueError(
                f"hardness = {hardness!r} Pa given, but the sweep is elastic (solved without a "
                f"cap): solve it with nondim_hardness = H L / (E sigma), or check the elastic "
                f"result against H with roughcontact.contact.validity")
        return None
    if hardness is None:
        raise ValueError(
            f"the sweep was solved with the cap H L / (E sigma) = {cap:.6g}; give the "
            f"hardness H [Pa] so that the scaling can be checked")
    H = check_positive(hardness, "hardness")
    wanted = H / pressure_scale
    if abs(wanted - cap) > HARDNESS_RTOL * cap:
        raise ValueError(
            f"H L / (E sigma) = {wanted:.6g} for this (sigma, E, H), but the sweep was solved "
            f"for {cap:.6g}: with a cap, pressure no longer scales with sigma E alone, "
            f"so this rescaling would change the problem; solve it anew with that cap")
    return H
