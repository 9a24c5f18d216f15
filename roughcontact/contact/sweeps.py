"""Force-deflection sweeps: every surface through its approaches, with warm starts.

:func:`sweep` solves Eq 27 for m surfaces at k approaches each and records
the load, areas, deflection and tangent stiffness of every solution (Eq 27,
33, 35). A method with its own approach loop runs it
(:func:`roughcontact.contact.pivot.sweep`: every surface in flight at
once); the others share :func:`approach_loop`: all surfaces at one step at
a time, each step started from the first-order prediction
``max(p + (d' - d) dp/dd, 0)`` of :func:`predict`, exact on an unchanged
contact set, with the tangent ``dp/dd = (C_FF)^-1 1`` from
:func:`~roughcontact.contact.stiffness.free_set_cg` (or, without the stiffness,
the secant of the last two steps): the contact solve then only corrects the
elements that enter or leave contact. Under load control (:func:`load_loop`)
each step starts from the previous step's pressure and is solved at its load
inside the iteration for ``"pcg"``, else by an outer solve on the approach
(:mod:`roughcontact.contact.loads`).
"""

from __future__ import annotations

import logging

import numpy as np

from roughcontact.contact import cg, checks
from roughcontact.contact.controls import Approaches, Loads
from roughcontact.contact.kkt import free_set
from roughcontact.contact.methods import Solver
from roughcontact.contact.problem import DEFAULT_OPTIONS, Problem, SolverOptions
from roughcontact.contact.result import SweepResult, SweepTable
from roughcontact.contact.stiffness import free_set_cg

__all__ = ["approach_loop", "load_loop", "predict", "sweep", "sweep_problem"]

logger = logging.getLogger("roughcontact.contact")


def predict(pressure, approach, last_approach, rate, hardness=None) -> np.ndarray:
    """First-order predictor ``max(p + (d - d_last) dp/dd, 0)`` [Pa] for the next step.

    On a fixed contact set the solution of Eq 27 is linear in ``d``
    (``C_AA p_A = d 1 - f_A``), so with the exact ``dp/dd`` the prediction is
    the solution whenever no element enters or leaves contact; rows of
    ``rate`` that are not finite (no rate yet) keep ``p``. With a cap the
    prediction is clipped to ``[0, H]``.
    """
    delta = (approach - last_approach)[:, None]
    predicted = pressure + delta * np.nan_to_num(rate, nan=0.0, posinf=0.0, neginf=0.0)
    if hardness is not None:
        return np.clip(predicted, 0.0, hardness, out=predicted)
    return np.maximum(predicted, 0.0, out=predicted)


def _tangent(solver: Solver, pressure, step: int, table: SweepTable):
    """The tangent ``(C_FF)^-1 1`` [Pa/m] of every surface at ``step``, recorded as
    ``dF/dd``. Solved from zero: a warm start from the last step's tangent costs its
    residual's product and loses the CG's Galerkin property, and took more products."""
    products, stiffness_tol = solver.products, solver.options.stiffness_tol
    solution = free_set_cg(products, free_set(pressure, solver.problem.hardness),
                           np.zeros_like(pressure), stiffness_tol,
                           cg.default_max_iter(products.operator.shape[0]))
    ok = solution.converged
    table.record_stiffness(slice(None), step, products.operator.element_area * solution.total,
                           ok)
    if not ok.all():
        logger.warning(
            "tangent stiffness: free-set CG did not reach tol %.3g for %d surfaces "
            "at step %d", stiffness_tol, int((~ok).sum()), step,
        )
    return solution.x


def approach_loop(solver: Solver, steps, table: SweepTable) -> None:
    """The shared approach loop: all surfaces through step 1, 2, ... k together.

    Each step starts from the previous solution or, with ``extrapolate``,
    from :func:`predict` with ``dp/dd`` the tangent of the stiffness solve
    (``stiffness``) or else the secant of the last two steps; a surface whose
    step did not converge (after the retries of
    :mod:`roughcontact.contact.retries`) starts its next step from zero
    pressure instead. Fills ``table``.
    """
    gaps, options = solver.problem.gaps, solver.options
    m, n = gaps.shape
    pressure = np.zeros((m, n))
    rate = np.full((m, n), np.nan)
    for step in range(steps.shape[1]):
        start = pressure
        if options.extrapolate and step > 0:
            start = predict(pressure, steps[:, step], steps[:, step - 1], rate,
                            solver.problem.hardness)
        batch, _ = solver.settle(Approaches(steps[:, step].copy()), start)
        if options.extrapolate and not options.stiffness:
            # Secant dp/dd of this step, for the next prediction.
            delta = steps[:, step] - (steps[:, step - 1] if step > 0 else np.nan)
            with np.errstate(invalid="ignore", divide="ignore"):
                rate = (batch.pressure - pressure) / delta[:, None]
        pressure = batch.pressure
        tangent = _record(solver, batch, step, table, steps[:, step])
        if options.stiffness:
            rate = tangent
        pressure, rate = _restart_failed(batch.converged, pressure, rate)


def _restart_failed(converged, pressure, rate):
    """The next step's start without the unconverged surfaces' solutions: zero pressure
    and no rate where ``converged`` is False."""
    if converged.all():
        return pressure, rate
    pressure = np.where(converged[:, None], pressure, 0.0)
    if rate is not None:
        rate = np.where(converged[:, None], rate, np.nan)
    return pressure, rate


def _record(solver: Solver, batch, step: int, table: SweepTable, approach):
    """A step's solutions, work and (with ``stiffness``) tangent in ``table``; the tangent
    (None without ``stiffness``). The gaps ``f`` (m, n) [m] and ``approach`` (m,) [m]
    give the gap ``u + f - d`` of the interface quantities."""
    problem = solver.problem
    gap = (batch.displacement + problem.gaps - approach[:, None]) if table.interface else None
    table.record(slice(None), step, batch.pressure, batch.displacement, batch.residual,
                 problem.operator.element_area, problem.hardness, gap)
    table.record_work(slice(None), step, batch.iterations, batch.matvecs, batch.converged,
                      batch.solved_by)
    if solver.options.stiffness:
        return _tangent(solver, batch.pressure, step, table)
    return None


def load_loop(solver: Solver, loads, table: SweepTable) -> np.ndarray:
    """The loop of a load-controlled sweep: all surfaces through the mean pressures
    ``loads`` (m, k) [Pa], each step started from the previous step's pressure (from
    zero after a step that did not converge; :mod:`roughcontact.contact.retries`) and
    met to ``options.load_tol`` (:func:`roughcontact.contact.loads.solve_at_loads`).
    Fills ``table``; returns the approaches found (m, k) [m]."""
    m, n = solver.problem.gaps.shape
    pressure = np.zeros((m, n))
    approaches = np.zeros(loads.shape)
    for step in range(loads.shape[1]):
        batch, approaches[:, step] = solver.settle(
            Loads(loads[:, step].copy(), solver.options.load_tol), pressure)
        _record(solver, batch, step, table, approaches[:, step])
        pressure, _ = _restart_failed(batch.converged, batch.pressure, None)
    return approaches


def _steps(problem, approaches, mean_pressures) -> np.ndarray:
    """The checked steps (m, k): approaches [m] or mean pressures [Pa], exactly one."""
    checks.check_control(approaches, mean_pressures, ("approaches", "mean_pressures"))
    m = problem.gaps.shape[0]
    if mean_pressures is not None:
        return checks.approach_steps(mean_pressures, m, "Pa", "mean_pressures")
    steps = checks.approach_steps(approaches, m, "m")
    checks.check_bounded(problem.operator, problem.gaps, steps.max(axis=1), "approaches",
                         problem.hardness)
    return steps


def sweep_problem(problem: Problem, approaches=None, *, mean_pressures=None,
                  options: SolverOptions = DEFAULT_OPTIONS) -> SweepResult:
    """Force-deflection curves of the surfaces of ``problem`` over k approaches or loads.

    :func:`sweep` on a problem made beforehand
    (:meth:`~roughcontact.contact.problem.Problem.of`); the arguments as there.
    """
    solver = Solver.of(problem, options)
    steps = _steps(problem, approaches, mean_pressures)
    table = SweepTable(problem.gaps.shape[0], steps.shape[1], problem.shape,
                       options.return_fields, options.profile, problem.interface)
    if mean_pressures is not None:  # load control
        steps = load_loop(solver, steps, table)
    else:
        loop = solver.method.sweep or approach_loop
        loop(solver, steps, table)
    return table.result(steps, solver.method.name, options.tol, problem.hardness)


def sweep(operator, gaps0, approaches=None, *, mean_pressures=None, hardness=None,
          interface=None, element_area=None,
          options: SolverOptions = DEFAULT_OPTIONS) -> SweepResult:
    """Force-deflection curves of m surfaces over k approaches or loads (Eq 27, 33, 35).

    Every surface at every step, all at once (:func:`roughcontact.contact.solve_many`;
    the loops and warm starts: module docstring), with the tangent ``dF/dd =
    dA 1^T (C_AA)^-1 1`` (:func:`roughcontact.contact.tangent_stiffness`). The short
    form of ``sweep_problem(Problem.of(operator, gaps0, ...), ...)``
    (:class:`~roughcontact.contact.problem.Problem`, :func:`sweep_problem`).

    Parameters
    ----------
    operator : ndarray (n, n) or operator object
        Influence coefficients ``C`` [m/Pa], see :func:`roughcontact.contact.solve`.
    gaps0 : ndarray, (m, ny, nx) or (m, n)
        Initial separations ``f`` [m] (Eq 21).
    approaches : ndarray, (k,) or (m, k), optional
        Rigid-body approaches ``d >= 0`` [m] at each step, shared or per surface.
    mean_pressures : ndarray, (k,) or (m, k), optional
        Mean pressures ``P >= 0`` [Pa] instead (:func:`load_loop`).
    hardness, element_area
        As in :func:`roughcontact.contact.solve`.
    interface : InterfaceGrid, optional
        The surfaces' grid (:class:`~roughcontact.contact.interface.InterfaceGrid`):
        record every solution's spots, perimeter, corrected area and gaps, and the
        columns of the grid's probes (:mod:`roughcontact.contact.probes`).
    options : SolverOptions
        As in :func:`roughcontact.contact.solve` (``precision`` also for the
        stiffness CG), and the sweep's own: ``stiffness`` (compute
        ``contact_stiffness``, else NaN) and ``stiffness_tol``, ``extrapolate`` (start
        each step from the extrapolated pressure), ``profile`` (keep every solution's
        pressure and load profiles, :mod:`roughcontact.contact.validity`),
        ``return_fields`` (keep the pressure fields ``(m, k, *surface shape)`` [Pa])
        (:class:`~roughcontact.contact.problem.SolverOptions`). A step unconverged
        after its retries is flagged, logged, and the surface's next step starts from
        zero pressure, not from it.

    Returns
    -------
    SweepResult
    """
    problem = Problem.of(operator, gaps0, hardness=hardness, interface=interface,
                         element_area=element_area)
    return sweep_problem(problem, approaches, mean_pressures=mean_pressures, options=options)
