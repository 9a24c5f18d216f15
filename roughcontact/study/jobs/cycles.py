"""The cycle job: one capped cell's surfaces along its loading path, with the permanent set.

A cycle job (:class:`~roughcontact.study.cycle_records.CycleJob`, the ``loading``
section's) reads the files of its contact job, checked alike
(:func:`~roughcontact.study.jobs.contact.read_problem`: the surfaces, the influence,
the counter body's and the thermal influence where the conductance crosses the block),
sweeps every surface along the path in ``P L / (E sigma)`` with the cap's permanent set
kept from step to step (:func:`roughcontact.contact.cell.cycle_cell`, under load
control; the probes measured on the flattened surface's gap at every step) and writes
the dimensionless result (:mod:`roughcontact.study.jobs.cycle_storage`). A step that
does not converge after the solver's retries is flagged with the surface's later steps,
counted in the file and the log, and left out of the aggregates.
"""

from __future__ import annotations

import logging
import time

import numpy as np

from roughcontact.contact import cell as cell_module
from roughcontact.study.config import ContactSettings
from roughcontact.study.cycle_records import CycleJob
from roughcontact.study.jobs.contact import ContactProblem, read_problem
from roughcontact.study.jobs.cycle_storage import write_cycle
from roughcontact.study.provenance import NO_RUN, RunInfo, canonical_json, provenance

__all__ = ["solve_cycle_job", "sweep_cycle"]

log = logging.getLogger(__name__)


def sweep_cycle(job: CycleJob, problem: ContactProblem, settings: ContactSettings):
    """Sweep a cycle job's ``problem`` (its contact job's,
    :func:`~roughcontact.study.jobs.contact.read_problem`) along its path with the
    contact jobs' solver ``settings`` (method, tolerance, precision): the dimensionless
    :class:`~roughcontact.contact.cycles.CycleResult`."""
    solver = cell_module.SWEEP_OPTIONS.solver.with_(method=settings.method, tol=settings.tol,
                                                    precision=settings.precision,
                                                    profile=False)
    return cell_module.cycle_cell(problem.unit, problem.heights, job.contact.geometry.block(),
                                  job.path(), nondim_hardness=job.contact.nondim_hardness,
                                  solver=solver, interface=problem.interface)


def _stats(result, seconds: float) -> dict:
    """The statistics a cycle file records."""
    return {"unconverged_steps": int((~result.converged).sum()),
            "unconverged_stiffness_steps": int((result.converged
                                                & ~result.stiffness_converged).sum()),
            "worst_residual": float(np.nanmax(result.residual, initial=0.0)),
            "max_plastic_area_fraction": float(np.nanmax(result.plastic_area_fraction,
                                                         initial=0.0)),
            "wall_seconds": seconds}


def solve_cycle_job(params: dict, inputs: dict, out_path, settings: dict,
                    run: RunInfo = NO_RUN) -> dict:
    """Solve one cycle job and write its dimensionless path to ``out_path``.

    ``params``: the job's :meth:`~roughcontact.study.cycle_records.CycleJob.params`;
    ``inputs`` its files by input name (:meth:`~roughcontact.study.cycle_records.
    CycleJob.files`, its contact job's, each checked to have been made for it);
    ``settings`` the contact jobs' solver settings
    (:meth:`~roughcontact.study.config.ContactSettings.params`); ``run`` the run it
    belongs to (its seed, config hash and provenance). Returns the root attributes
    written.
    """
    job, settings = CycleJob.from_params(params), ContactSettings.from_section(settings)
    start = time.perf_counter()
    problem, read, operator = read_problem(job.contact, inputs, settings, run.study_seed)
    path = job.path()
    m = problem.heights.shape[0]
    log.info("cycles %s: %d surfaces x %d steps (%d cycles to P L / (E sigma) = %g and down "
             "to %g of it, %d steps a leg), pressure capped at H L / (E sigma) = %.6g; "
             "method %s, tol %.1e, influence %s", job.key, m, len(path.values), job.cycles,
             job.peak, job.unload_to, job.steps, job.contact.nondim_hardness,
             settings.method, settings.tol, operator)
    for probe in problem.interface.probes:
        log.info("probe %s recorded at every step: %s", probe.kind, probe.params())
    result = sweep_cycle(job, problem, settings)
    stats = _stats(result, time.perf_counter() - start)
    (log.warning if stats["unconverged_steps"] else log.info)("cycles %s: %s", job.key, stats)
    log.info("permanent set at the end d/sigma: mean %.4g; plastic area fraction at most %.3g",
             float(np.nanmean(result.permanent_set[:, -1])), stats["max_plastic_area_fraction"])
    attrs = {"job": canonical_json(job.params()), **stats, **read, **provenance(run)}
    return write_cycle(out_path, result, attrs)
