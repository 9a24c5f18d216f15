"""Bodies of the workflow's contact jobs.

A *contact job* solves every surface of one surface cell on one influence
geometry through an approach sweep, in the non-dimensional form of
:mod:`roughcontact.contact.nondim`, and stores the result; sigma and E never
enter. With a counter body (Eq 17-18) it solves the equivalent problem of the
pair (:func:`contact_problem`): the two surfaces summed, the two bodies'
compliances summed (the pair's file of :func:`roughcontact.study.jobs.build_pair`
on a dense first body). The influence and pair jobs are in
:mod:`roughcontact.study.jobs`.

A job takes its rule's params: the plain ``params()`` of the records of
:mod:`roughcontact.study.records`, which its first lines turn into those
records (the job's edge); everything after works on the records. The
layouts of the files are described in :mod:`roughcontact.study.storage`.
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
from roughcontact.study.jobs import (
    PairModel,
    certified_influence,
    pair_model,
    read_pair_model,
)
from roughcontact.study.provenance import canonical_json, provenance
from roughcontact.study.records import MeasuredCell
from roughcontact.study.storage import read_influence, read_surfaces, write_contact
from roughcontact.surfaces.statistics import height_stats

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


def read_counter(job: ContactJob, first, surfaces_path, model_path,
                 study_seed=None) -> tuple:
    """A job's counter surfaces (:func:`~roughcontact.study.storage.read_surfaces`) and
    :class:`PairModel` (with the first body's unit-modulus operator ``first``), each None
    where the job has none, and the content hashes to record. ``model_path``: the pair
    file of a dense first body (:attr:`~roughcontact.study.contact_records.ContactJob.pair`), else
    the counter body's influence file; each file checked to have been made for the
    job's counter body."""
    counter = job.counter
    surfaces = model = None
    hashes = {}
    if counter is not None and counter.surface is not None:
        surfaces = read_surfaces(surfaces_path, cell=counter.surface.params(),
                                 study_seed=study_seed)
    if job.pair is not None:
        model, hashes = read_pair_model(model_path, job.pair)
    elif counter is not None and counter.geometry is not None:
        unit, attrs = read_influence(model_path, geometry=counter.geometry.params())
        unit = certified_influence(unit, model_path, counter.geometry)
        hashes["counter_influence_content_sha256"] = attrs["content_sha256"]
        model = pair_model(first, unit, counter.modulus_ratio, counter.rigid_share)
    return surfaces, model, hashes


def _equivalent_moments(heights: np.ndarray) -> dict:
    """The equivalent surface's sample sigma (in units of the height scale), Sk and Ku,
    means over the surfaces (:func:`~roughcontact.surfaces.statistics.height_stats`)."""
    stats = height_stats(heights)
    return {"equivalent_sigma_over_scale": float(stats["sigma"].mean()),
            "equivalent_skew": float(stats["skew"].mean()),
            "equivalent_kurt": float(stats["kurt"].mean())}


def contact_problem(job: ContactJob, heights, unit, counter_surfaces=None,
                    pair: PairModel | None = None) -> ContactProblem:
    """The problem a contact job sweeps: its own (one body against a rigid smooth flat),
    or with a counter body the equivalent problem of Eq 17-18
    (:mod:`roughcontact.contact.counterface`): heights ``(z1 + r z2) / sqrt(1 + r^2)``
    (r = sigma2 / sigma1; a measured counter map, measured face up like the first
    surface, mirrored in x as the two face each other, and added to every surface),
    the ``pair``'s operator (:class:`PairModel`; the first
    body's ``unit`` where the counter body is treated as rigid), the interface grid
    with the counter body's deflection weights and the bulk factor raised by its
    compliance."""
    counter = job.counter
    if counter is None:
        return ContactProblem(heights, unit)
    attrs, grid, bulk = {}, cell_module.block_interface(job.geometry), cell_module.BULK_FACTOR
    if counter.surface is not None:
        z2 = counter_surfaces["heights"]
        if isinstance(counter.surface, MeasuredCell):
            # measured face up, like the first; facing it, the map is mirrored in x (one
            # map, added to every surface)
            z2 = z2[0, :, ::-1]
        heights = (counterface.equivalent_heights(heights, counter.sigma_ratio * z2)
                   * counter.height_factor)
        attrs["counter_surfaces_content_sha256"] = counter_surfaces["content_sha256"]
        attrs.update(_equivalent_moments(heights))
        log.info("equivalent surface: (z1 + %.4g z2) / %.4g; sample sigma / scale %.4f, "
                 "Sk %.4f, Ku %.4f (means over surfaces)", counter.sigma_ratio,
                 1.0 / counter.height_factor, attrs["equivalent_sigma_over_scale"],
                 attrs["equivalent_skew"], attrs["equivalent_kurt"])
    if pair is not None:
        attrs.update(pair.attrs)
        log.info("counter body %s: %.3g of the pair's compliance (rigid_share %g): %s",
                 counter.geometry.key, pair.attrs["counter_compliance_share"],
                 counter.rigid_share, "treated as rigid" if pair.unit is None
                 else "solved as an elastic pair")
        if pair.unit is not None:
            unit, bulk = pair.unit, bulk * pair.bulk_ratio
            grid = dataclasses.replace(grid, counter_weights=pair.weights
                                       / job.geometry.thickness)
    return ContactProblem(heights, unit, grid, bulk, attrs)


def solve_contact_job(params: dict, surfaces_path, influence_path, out_path, settings: dict,
                      config=None, counter_surfaces_path=None,
                      counter_influence_path=None) -> dict:
    """Solve one contact job and write its non-dimensional sweep to ``out_path``.

    ``params``: the job's :meth:`~roughcontact.study.contact_records.ContactJob.params`,
    whose record ``job`` holds the surface cell, the geometry, the
    non-dimensional pressure P L / (E sigma) the sweep must reach and a capped
    job's cap H L / (E sigma); ``settings`` the solver's
    (:meth:`~roughcontact.study.config.ContactSettings.params`). The surface
    and influence files must have been made for the job's cell (and the
    configuration's ``study_seed``) and geometry, else
    :class:`~roughcontact.errors.StoredFileError` names the file and the
    field that differs. A job with a counter body (``counter``) also reads the counter
    surfaces and influence files, checked alike, and solves the equivalent problem
    (:func:`_pair_problem`). Returns the root attributes written.
    """
    job, settings = ContactJob.from_params(params), ContactSettings.from_section(settings)
    start = time.perf_counter()
    # each input must have been made for this job (not only carry its name)
    surfaces = read_surfaces(surfaces_path, cell=job.surface.params(),
                             study_seed=None if config is None else config["study_seed"])
    unit, geometry_attrs = read_influence(influence_path, geometry=job.geometry.params())
    unit = certified_influence(unit, influence_path, job.geometry)
    heights = surfaces["heights"]
    m = heights.shape[0]
    name = f"{job.surface.key}__{job.geometry.key}"
    nx, ny = job.geometry.grid
    if heights.shape[1:] != (ny, nx):
        raise ValueError(
            f"surfaces {surfaces_path} have shape {heights.shape[1:]} but geometry "
            f"{job.geometry.key} has a {ny} x {nx} (ny x nx) contact grid"
        )
    counter_surfaces, pair, counter_hashes = read_counter(
        job, unit, counter_surfaces_path, counter_influence_path,
        None if config is None else config["study_seed"])
    problem = contact_problem(job, heights, unit, counter_surfaces, pair)
    hardness = job.nondim_hardness
    log.info("contact %s: %d surfaces x %d steps, sweep to P L / (E sigma) = %g; "
             "method %s, tol %.1e, precision %s, influence %s, %s", name, m, settings.steps,
             job.pressure_end, settings.method, settings.tol, settings.precision,
             geometry_attrs["operator"],
             "elastic" if hardness is None else f"pressure capped at H L / (E sigma) = "
             f"{hardness:.6g}")
    result = cell_module.sweep_cell(problem.unit, problem.heights, job.geometry.block(),
                                    job.pressure_end,
                                    settings.steps, method=settings.method, tol=settings.tol,
                                    precision=settings.precision, batch_size=min(m, BATCH_SIZE),
                                    progress=_progress_log(), nondim_hardness=hardness,
                                    interface=problem.interface,
                                    bulk_factor=problem.bulk_factor)
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
        "surfaces_content_sha256": surfaces["content_sha256"],
        "influence_content_sha256": geometry_attrs["content_sha256"],
        "seeds": surfaces["seeds"].tolist(),
        **counter_hashes,
        **problem.attrs,
        **provenance(config),
    }
    return write_contact(out_path, result, attrs)


__all__ = [
    "BATCH_SIZE",
    "ContactProblem",
    "contact_problem",
    "read_counter",
    "solve_contact_job",
]
