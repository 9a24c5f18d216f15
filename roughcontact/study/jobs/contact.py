"""Bodies of the workflow's contact jobs.

A *contact job* solves every surface of one surface cell on one influence
geometry through an approach sweep, in the non-dimensional form of
:mod:`roughcontact.contact.nondim`, and stores the result; sigma and E never
enter. With a counter body (Eq 17-18) it solves the equivalent problem of the
pair (:func:`contact_problem`): the two surfaces summed, the two bodies'
compliances summed (the pair's file of :func:`roughcontact.study.jobs.influence.build_pair`
on a dense first body). The influence and pair jobs are in
:mod:`roughcontact.study.jobs.influence`.

Its params become its records in its first lines (the job's edge, as every job of
:mod:`roughcontact.study.jobs`).
"""

from __future__ import annotations

import dataclasses
import logging
import time

import numpy as np

from roughcontact.contact import cell as cell_module
from roughcontact.contact import counterface
from roughcontact.study.config import ContactSettings
from roughcontact.study.contact_records import ContactJob
from roughcontact.study.jobs.influence import (
    certified_influence,
    read_pair_model,
)
from roughcontact.study.jobs.storage import read_influence, read_surfaces, write_contact
from roughcontact.study.jobs.thermal import read_thermal
from roughcontact.study.provenance import RunInfo, canonical_json, provenance

log = logging.getLogger(__name__)

#: Seconds between progress lines of a contact job within one batch.
PROGRESS_SECONDS = 30.0

#: Surfaces solved together in one call (the batch also fixes the rounding of the
#: matrix products, so a re-solve of the same batch is bit-identical).
BATCH_SIZE = 20


# ---------------------------------------------------------------------------
# Contact jobs


def _progress_log():
    """A progress callback of a sweep: a line per batch, and a heartbeat every
    :data:`PROGRESS_SECONDS` within a long batch (large grids)."""
    last = [time.perf_counter()]

    def progress(report):
        now = time.perf_counter()
        if report.step == report.steps_total:
            log.info("  surfaces %d/%d done, %d steps, %.1f s elapsed, %d unconverged",
                     report.surfaces_done, report.surfaces_total, report.steps_total,
                     report.elapsed, report.unconverged)
        elif now - last[0] > PROGRESS_SECONDS:
            log.info("  step %d/%d of the batch ending at surface %d/%d, %.1f s elapsed",
                     report.step, report.steps_total, report.surfaces_done,
                     report.surfaces_total, report.elapsed)
        else:
            return
        last[0] = now

    return progress


def _solver_stats(result, seconds: float) -> dict:
    """The solver statistics a contact file records."""
    return {
        "unconverged_steps": int((~result.converged).sum()),
        "unconverged_stiffness_steps": int((~result.stiffness_converged).sum()),
        "worst_residual": float(result.residual.max()),
        "total_iterations": int(result.iterations.sum()),
        "max_iterations": int(result.iterations.max()),
        "total_matvecs": int(result.matvecs.sum()),
        "max_plastic_area_fraction": float(result.plastic_area_fraction.max()),
        "wall_seconds": seconds,
    }


@dataclasses.dataclass(frozen=True)
class ContactProblem:
    """What a contact job sweeps: ``heights`` in units of the cell's height scale, the
    unit-modulus operator ``unit`` [m] in the first body's unit, the ``interface``
    grid (True: the block's), the sweep's ``bulk_factor``
    (:func:`~roughcontact.contact.cell.approach_grid`) and the attributes that say
    what was modelled (none for one body)."""

    heights: np.ndarray
    unit: object
    interface: object = True
    bulk_factor: float = cell_module.BULK_FACTOR
    attrs: dict = dataclasses.field(default_factory=dict)


class _ModelReader:
    """How a counter body's files are read (for
    :meth:`~roughcontact.study.counter_records.JobCounter.read`): each checked to have
    been made for its surface cell, geometry or pair, an operator certified."""

    @staticmethod
    def surfaces(path, cell, study_seed):
        return read_surfaces(path, cell=cell.params(), study_seed=study_seed)

    @staticmethod
    def pair(path, pair):
        return read_pair_model(path, pair)

    @staticmethod
    def influence(path, geometry):
        unit, attrs = read_influence(path, geometry=geometry.params())
        return (certified_influence(unit, path, geometry),
                {"counter_influence_content_sha256": attrs["content_sha256"]})


def read_counter(job: ContactJob, paths: dict, study_seed=None) -> tuple:
    """A job's counter body (:class:`~roughcontact.contact.counterface.Body`; the rigid
    smooth flat for a job without one) from its files ``paths`` (input name -> path, as
    :meth:`~roughcontact.study.contact_records.ContactJob.files` names them), each
    checked to have been made for the job's counter body, and the content hashes to
    record."""
    return job.counter.read(paths, job.geometry, _ModelReader, study_seed)


def contact_problem(job: ContactJob, heights, unit,
                    counter: counterface.Body = counterface.RIGID_FLAT,
                    probes: tuple = ()) -> ContactProblem:
    """The problem a contact job sweeps: the pair of its first body (``heights`` in units
    of the cell's sigma, unit-modulus operator ``unit`` [m]) and its ``counter`` body
    (Eq 17-18; :func:`roughcontact.contact.counterface.pair`): the equivalent heights,
    the pair's operator, the interface grid with the counter body's deflection weights
    and the ``probes`` to record at every step (:mod:`roughcontact.contact.probes`;
    :meth:`~roughcontact.study.config.ContactSettings.probes`), and the bulk factor
    raised by its compliance; against the rigid smooth flat the job's own problem."""
    paired = counterface.pair(heights, unit, counter)
    grid = paired.model.interface(
        dataclasses.replace(cell_module.block_interface(job.geometry), probes=probes),
        job.geometry.thickness)
    return ContactProblem(paired.heights, paired.model.operator(unit), grid,
                          cell_module.BULK_FACTOR * paired.model.bulk_ratio, paired.attrs)


def _read_first_body(job: ContactJob, inputs: dict, study_seed) -> tuple:
    """A job's surfaces, its first body's certified unit-modulus operator and the
    influence file's attributes, each file checked to have been made for the job (not
    only to carry its name) and the surfaces to lie on the geometry's grid."""
    surfaces = read_surfaces(inputs["surfaces"], cell=job.surface.params(),
                             study_seed=study_seed)
    unit, attrs = read_influence(inputs["influence"], geometry=job.geometry.params())
    unit = certified_influence(unit, inputs["influence"], job.geometry)
    nx, ny = job.geometry.grid
    if surfaces["heights"].shape[1:] != (ny, nx):
        raise ValueError(
            f"surfaces {inputs['surfaces']} have shape {surfaces['heights'].shape[1:]} but "
            f"geometry {job.geometry.key} has a {ny} x {nx} (ny x nx) contact grid")
    return surfaces, unit, attrs


def read_problem(job: ContactJob, inputs: dict, settings: ContactSettings,
                 study_seed) -> tuple[ContactProblem, dict, str]:
    """A job's problem (:func:`contact_problem`) from its files ``inputs`` (input name ->
    path, :meth:`~roughcontact.study.contact_records.ContactJob.files`), each checked to
    have been made for it, with the probes of ``settings`` (the conductance's reading the
    block's thermal influence); the attributes a file made of it records (the content
    hashes of what it read, the seeds, the pair's attributes) and the influence's
    operator. The contact job's and the cycle job's
    (:mod:`roughcontact.study.jobs.cycles`) first step."""
    surfaces, unit, geometry_attrs = _read_first_body(job, inputs, study_seed)
    counter, counter_hashes = read_counter(job, inputs, study_seed)
    # the block's thermal influence from its file where the conductance crosses it
    probes = job.thermal.seeded(settings.probes(job.geometry), inputs, read_thermal)
    problem = contact_problem(job, surfaces["heights"], unit, counter, probes)
    read = {"surfaces_content_sha256": surfaces["content_sha256"],
            "influence_content_sha256": geometry_attrs["content_sha256"],
            "seeds": surfaces["seeds"].tolist(), **counter_hashes, **problem.attrs}
    return problem, read, geometry_attrs["operator"]


def sweep_problem(job: ContactJob, problem: ContactProblem, steps: int, options,
                  rows: slice | None = None):
    """Sweep a job's ``problem`` over ``steps`` approaches to its end
    (:func:`roughcontact.contact.cell.sweep_cell`, ``options`` a
    :class:`~roughcontact.contact.nondim.CellOptions`; the job's cap, the problem's
    interface grid and bulk factor set here): the job's sweep, and the audit's re-solve
    of the stored batch ``rows``."""
    options = dataclasses.replace(options, nondim_hardness=job.nondim_hardness,
                                  interface=problem.interface)
    return cell_module.sweep_cell(problem.unit, problem.heights, job.geometry.block(),
                                  job.pressure_end, steps, options=options, rows=rows,
                                  bulk_factor=problem.bulk_factor)


def solve_contact_job(params: dict, inputs: dict, out_path, settings: dict,
                      config=None) -> dict:
    """Solve one contact job and write its non-dimensional sweep to ``out_path``.

    ``params``: the job's :meth:`~roughcontact.study.contact_records.ContactJob.params`,
    whose record ``job`` holds the surface cell, the geometry, the
    non-dimensional pressure P L / (E sigma) the sweep must reach and a capped
    job's cap H L / (E sigma); ``settings`` the solver's
    (:meth:`~roughcontact.study.config.ContactSettings.params`). The surface
    and influence files must have been made for the job's cell (and the
    configuration's ``study_seed``) and geometry, else
    :class:`~roughcontact.errors.StoredFileError` names the file and the
    field that differs. ``inputs``: the job's files by input name
    (:meth:`~roughcontact.study.contact_records.ContactJob.files`: ``surfaces``,
    ``influence`` and a counter body's, each checked alike); a job with a counter body
    solves the equivalent problem (:func:`contact_problem`). Returns the root
    attributes written.
    """
    run = RunInfo.of(config)  # the job's edge: the run it belongs to
    job, settings = ContactJob.from_params(params), ContactSettings.from_section(settings)
    start = time.perf_counter()
    problem, read, operator = read_problem(job, inputs, settings, run.study_seed)
    probes = problem.interface.probes
    m = problem.heights.shape[0]
    name = f"{job.surface.key}__{job.geometry.key}"
    hardness = job.nondim_hardness
    log.info("contact %s: %d surfaces x %d steps, sweep to P L / (E sigma) = %g; "
             "method %s, tol %.1e, precision %s, influence %s, %s", name, m, settings.steps,
             job.pressure_end, settings.method, settings.tol, settings.precision,
             operator,
             "elastic" if hardness is None else f"pressure capped at H L / (E sigma) = "
             f"{hardness:.6g}")
    for probe in probes:
        log.info("probe %s recorded at every step: %s", probe.kind, probe.params())
    options = cell_module.SWEEP_OPTIONS.with_(method=settings.method, tol=settings.tol,
                                              precision=settings.precision,
                                              batch_size=min(m, BATCH_SIZE),
                                              progress=_progress_log())
    result = sweep_problem(job, problem, settings.steps, options)
    log.info("approach d/sigma %.3g .. %.3g", result.approach[0, 0], result.approach[0, -1])
    reached = result.nominal_pressure[:, -1].min()
    if reached < job.pressure_end:
        log.warning("the sweep reached P L / (E sigma) = %.3g on its least loaded surface, "
                    "below the %.3g asked for: higher pressure levels rest on fewer surfaces",
                    reached, job.pressure_end)
    stats = _solver_stats(result, time.perf_counter() - start)
    (log.warning if stats["unconverged_steps"] else log.info)("contact %s: %s", name, stats)
    attrs = {
        "batch_size": min(m, BATCH_SIZE),
        "job": canonical_json(job.params()),
        **stats,
        **read,
        **provenance(run),
    }
    return write_contact(out_path, result, attrs)


__all__ = [
    "BATCH_SIZE",
    "ContactProblem",
    "contact_problem",
    "read_counter",
    "read_problem",
    "solve_contact_job",
    "sweep_problem",
]
