"""Memory [MB] and wall time [min] every job asks a scheduler for.

Estimated from the grid, the surface count, the mesh and the solver settings,
scaled from runs on the reference machine (2 cores, see docs/). The measured
numbers live in ``config/cost_model.yaml`` (each with what was measured); this
module holds the formulas. A job that outlives its wall time is killed, so a
time estimate is multiplied by the margin and by the attempt (``retries`` in
the profile). ``rules/common.smk`` passes the plan's typed records here
(:mod:`roughcontact.study.records`) with the settings of the contact jobs
(:class:`~roughcontact.study.config.ContactSettings`) and of the influence
builds (:class:`~roughcontact.study.config.BuildSettings`).

Check the model against a run's benchmarks with
:mod:`roughcontact.study.plan.cost_drift` (``python -m roughcontact.study.plan.cost_drift
--compare <results>/benchmarks/rules --configfile <config>``).
"""

from __future__ import annotations

import dataclasses
import math
from types import MappingProxyType

from roughcontact.contact.halfspace_criterion import CALIBRATION
from roughcontact.elasticity.operators import (
    COARSE_MAX,
    coarsened_side,
)
from roughcontact.study.config import (
    PILOT_FRACTIONS,
    BuildSettings,
    ContactSettings,
    ConvergenceSettings,
    GridConvergenceSettings,
    SpeedReportSettings,
)
from roughcontact.study.contact_records import ContactJob
from roughcontact.study.plan.cost_model import (  # noqa: F401 (the model's file and loader)
    COST_MODEL_FILE,
    DOUBLE_BYTES,
    MB,
    SCHEMA_FILE,
    load_cost_model,
)
from roughcontact.study.records import GeneratedCell, Generator, Geometry, InfluenceModel
from roughcontact.study.thermal_records import ThermalBlock
from roughcontact.surfaces.spectra import autocorrelation
from roughcontact.transport.conduction.probe import BlockBody
from roughcontact.units import GB

_MODEL = load_cost_model()


# ---------------------------------------------------------------------------
# Wall time


def runtime_minutes(seconds: float, attempt: int = 1) -> int:
    """Requested wall time [min] of a job estimated to take ``seconds`` [s]:
    ``attempt (start_min + ceil(margin seconds / 60))``."""
    runtime = _MODEL["runtime"]
    return attempt * (runtime["start_min"] + math.ceil(runtime["margin"] * seconds / 60))


def dense_scale(grid) -> float:
    """Cost of the dense contact solves on ``grid`` [nx, ny] relative to 60 x 60.

    A product with the dense influence matrix costs n^2 for n = nx ny
    elements, and CG iterations grow about as sqrt(n) with its condition
    number: (n / 3600)^2.5 (measured at 30 x 30 and 60 x 60 only, an upper
    bound there).
    """
    contact = _MODEL["contact"]
    return (grid[0] * grid[1] / contact["reference_elements"]) ** contact["dense_exponent"]


def tolerance_factor(settings: ContactSettings) -> float:
    """Iterations of a solve to tolerance ``settings.tol`` relative to 1e-8 (the
    reference), in proportion to its digits and never below 1."""
    digits = _MODEL["contact"]["reference_tol_digits"]
    return max(1.0, math.log10(1.0 / settings.tol) / digits)


def method_factor(settings: ContactSettings) -> float:
    """Matrix products per solve of ``settings.method`` relative to CG."""
    return _MODEL["contact"]["method_cost"][settings.method]


def dense_solve_seconds(grid, settings: ContactSettings) -> float:
    """Wall time [s] of one dense contact solve (one surface, one step) on ``grid``:
    0.11 s at 60 x 60 (the slowest measured cell: 186 s for 60 surfaces x
    30 steps, paper mesh, CG 1e-8) times :func:`dense_scale`."""
    seconds = _MODEL["contact"]["dense_solve_seconds"]
    return seconds * dense_scale(grid) * tolerance_factor(settings) * method_factor(settings)


def matrix_free_solve_seconds(grid) -> float:
    """Wall time [s] of one matrix-free solve at tolerance 1e-8 by CG: 0.62 s at
    256 x 256 (0.64 s at 240, 0.19 s at 120; 2 loaded cores), about in
    proportion to n, at least 0.05 s."""
    contact = _MODEL["contact"]
    per_solve = contact["matrix_free_solve_seconds"] * grid[0] * grid[1]
    return max(contact["matrix_free_floor_seconds"],
               per_solve / contact["matrix_free_reference_elements"])


def flow_solve_seconds(grid) -> float:
    """Wall time [s] of one flow solve through a gap on ``grid`` (one surface, one step,
    one direction; :mod:`roughcontact.transport`): 55 ms (n / 3600)^1.1, above every
    measured size (44 ms on 64 x 64, 1.33 s on 256 x 256, 15.7 s on 1024 x 1024;
    ``benchmarks/bench_flow_memory.py``)."""
    contact = _MODEL["contact"]
    scale = grid[0] * grid[1] / contact["reference_elements"]
    return contact["flow_solve_seconds"] * scale ** contact["flow_exponent"]


def flow_memory_bytes(grid, count: int, directions=()) -> float:
    """Peak memory [bytes] the flow through the gap adds to a contact job on ``grid``
    [nx, ny] recording ``directions`` (none: 0) for batches of ``count`` surfaces
    (:mod:`roughcontact.transport`): one field's linear solve (SuperLU's factors or the
    band Cholesky's band, the solves one after another), measured 6.6 MB on 64 x 64,
    178 MB on 256 x 256, 381 MB on 512 x 512 and 1.55 GB on 1024 x 1024, counted as
    180 MB (n / 256^2) (fields smaller than 64 x 64 are solved several at once:
    counted as 64 x 64), plus 4 (count, n) double arrays of the batch's gaps
    (``benchmarks/bench_flow_memory.py``)."""
    if not directions:
        return 0.0
    fit = _MODEL["contact"]
    n = grid[0] * grid[1]
    solved = max(n, fit["flow_memory_floor_elements"])
    solve = fit["flow_memory_mb"] * MB * (
        solved / fit["flow_memory_reference_elements"]) ** fit["flow_memory_exponent"]
    return solve + fit["flow_field_arrays"] * DOUBLE_BYTES * count * n


def _dense(geometry: Geometry, build: BuildSettings) -> bool:
    """Whether a geometry's build is planned as the dense matrix (within ``build``'s limit)."""
    return geometry.planned_model(build.max_bytes) is InfluenceModel.DENSE


def contact_seconds(job: ContactJob, settings: ContactSettings, build: BuildSettings) -> float:
    """Wall time [s] of a contact job: surfaces x approach steps x one solve.

    ``settings`` are the contact jobs' (:func:`roughcontact.study.plan.studies.contact_settings`),
    ``build`` the influence builds' (its memory limit plans the model). Measured
    35-186 s per cell of 60 surfaces x 30 steps on 60 x 60 (paper mesh; the
    converged mesh needs fewer iterations) and 4 s on 30 x 30. A sweep beyond
    P L / (E sigma) = 4 (the study's) reaches larger contact fractions, where
    CG needs more iterations: counted in proportion (not for a factoring method,
    :func:`factoring`: the seal's jobs, swept to 128 by pivoting, took 37-43 s for 20
    surfaces x 24 steps with the flow along x and y, against 1742 s counted so). With
    the flow on, each step's flow solves (:func:`flow_solve_seconds`, one per
    direction) are added.
    """
    solves = job.surface.count * settings.steps
    flow = solves * len(settings.flow.directions) * flow_solve_seconds(job.geometry.grid)
    dense = _dense(job.geometry, build)
    # beyond the study's reach CG needs more iterations; pivoting's steps stay about
    # as cheap (the seal, swept to 128: 37-43 s a job of 480 steps, flow included)
    reach = 1.0 if factoring(settings, dense) else max(
        1.0, job.pressure_end / _MODEL["contact"]["reference_reach"])
    # a compliant counter body: more contact at the same pressure (cost_model.yaml)
    pair = job.counter.time_factor(_MODEL)
    grid = job.geometry.grid
    if not dense:
        solving = (solves * matrix_free_solve_seconds(grid) * tolerance_factor(settings)
                   * method_factor(settings) * reach * pair)
    else:
        solving = solves * dense_solve_seconds(grid, settings) * reach * pair
    return solving + flow + conductance_seconds(settings, solving)


def cycle_seconds(cycle, settings: ContactSettings, build: BuildSettings) -> float:
    """Wall time [s] of a cycle job (:class:`~roughcontact.study.cycle_records.CycleJob`):
    its path's steps at a share of a step of its contact job (``config/cost_model.yaml``,
    ``cycles``)."""
    per_step = contact_seconds(cycle.contact, settings, build) / settings.steps
    return _MODEL["cycles"]["step_share"] * per_step * len(cycle.path().values)


def conductance_seconds(settings: ContactSettings, solving: float) -> float:
    """Wall time [s] the conductance adds to a contact job whose solves take ``solving``
    [s] (none with the ``conductance`` section off): its solve at every step, a share of
    the contact solves (``config/cost_model.yaml``, ``conductance``; the block's thermal
    influence is its own job's, :func:`thermal_seconds`)."""
    if not settings.conductance.enabled:
        return 0.0
    return _MODEL["conductance"]["solve_share"] * solving


def thermal_seconds(thermal, build: BuildSettings) -> float:
    """Wall time [s] of a block's thermal influence build
    (:class:`~roughcontact.study.thermal_records.ThermalBlock`): a share of the elastic
    build of its block (:func:`influence_seconds` of the dense model)."""
    return _MODEL["conductance"]["build_share"] * influence_seconds(_elastic(thermal), build)


def thermal_mem_mb(thermal, build: BuildSettings) -> int:
    """Peak memory [MB] of a thermal influence build: the larger of its dense matrix
    (the block's, or beyond the dense limit its coarse model's) with the condensation's
    copies (``dense_arrays`` n^2 doubles) and a share of the elastic build's peak, plus
    the interpreter's."""
    fit = _MODEL["conductance"]
    built = _elastic(thermal)
    n = built.grid[0] * built.grid[1]
    peak = max(fit["dense_arrays"] * DOUBLE_BYTES * n**2,
               fit["build_memory_share"] * built.influence_cost(build).peak_bytes)
    return int(_MODEL["contact"]["memory_base_mb"] + peak / MB)


def _elastic(thermal) -> Geometry:
    """The elastic geometry of what a thermal block's build solves (its cost's
    reference): the block, or beyond the dense limit its coarse model (the matrix-free
    thermal block's correction, :mod:`roughcontact.transport.conduction.hybrid`)."""
    built = thermal.coarse_model() or thermal.block()
    return Geometry(nu=0.0, size=thermal.size, thickness=thermal.thickness,
                    grid=tuple(built.grid), base="clamped", mesh=built.mesh)


def conductance_bytes(job: ContactJob, settings: ContactSettings) -> float:
    """Peak memory [bytes] the conductance adds to a contact job (none off): on a block
    its dense thermal influence with the solve's copies (``dense_arrays`` n^2 doubles),
    beyond the dense limit the matrix-free one's coarse correction (twice) and FFT
    arrays; on a half-space the FFT arrays of the batch."""
    if not settings.conductance.enabled:
        return 0.0
    fit = _MODEL["conductance"]
    nx, ny = job.geometry.grid
    n = nx * ny
    fft = fit["fft_batch_arrays"] * DOUBLE_BYTES * job.surface.count * n
    if not isinstance(job.geometry.thermal_body(settings.conductance.body), BlockBody):
        return fft
    coarse = ThermalBlock.of(job.geometry).coarse_model()
    if coarse is not None:  # matrix-free: the coarse correction, twice, and the FFTs
        return 2 * DOUBLE_BYTES * coarse.n_elements**2 + fft
    return fit["dense_arrays"] * DOUBLE_BYTES * n**2


def contact_runtime(job: ContactJob, settings: ContactSettings, build: BuildSettings,
                    attempt: int = 1) -> int:
    """Requested wall time [min] of a contact job (:func:`contact_seconds`)."""
    return runtime_minutes(contact_seconds(job, settings, build), attempt)


def influence_seconds(geometry: Geometry, build: BuildSettings) -> float:
    """Wall time [s] of an influence build, from its estimated peak memory.

    The work of the sparse factorization and of the dense Schur complement
    grows with the memory they need. Build times on 2 cores (MKL PARDISO)
    against :meth:`~roughcontact.study.records.Geometry.influence_cost`'s peak: 60 x 60
    paper 4.2 s (0.92 GB), graded 12.5 s (2.0 GB), refined 12.3 s (2.1 GB),
    converged 116-132 s (9.6 GB); 120 x 120 paper 63 s (6.9 GB), graded
    248 s (12.6 GB). 4.2 s (GB / 0.92)^1.56 passes through the first and the
    last and lies above the others (SuperLU: 36 s at 60 x 60 paper, 45 s
    predicted).
    """
    fit = _MODEL["influence"]
    peak_gb = geometry.influence_cost(build).peak_bytes / GB
    return fit["anchor_seconds"] * (peak_gb / fit["anchor_peak_gb"]) ** fit["exponent"]


def influence_runtime(geometry: Geometry, build: BuildSettings, attempt: int = 1) -> int:
    """Requested wall time [min] of an influence build (:func:`influence_seconds`)."""
    return runtime_minutes(influence_seconds(geometry, build), attempt)


def surfaces_seconds(cell) -> float:
    """Wall time [s] of a surface cell: 60 surfaces of 60 x 60 take 0.01 s by the
    filter and 0.15-0.30 s by IAAFT (``exact``); 120 x 120: 0.04 s, 0.47-0.92 s.
    Counted as 0.001 s (filter, paper) or 0.01 s (IAAFT) per surface times
    (n / 3600)^1.5, plus the calibration of ``filter`` (at most about 15 s a cell)."""
    fit = _MODEL["surfaces"]
    per_surface = fit["exact_seconds"] if cell.method is Generator.EXACT else fit["filter_seconds"]
    size = cell.grid[0] * cell.grid[1] / fit["reference_elements"]
    calibration = fit["calibration_seconds"] if cell.method is Generator.FILTER else 0.0
    return calibration + cell.count * per_surface * size ** fit["exponent"]


def surfaces_runtime(cell, attempt: int = 1) -> int:
    """Requested wall time [min] of a surface cell (:func:`surfaces_seconds`)."""
    return runtime_minutes(surfaces_seconds(cell), attempt)


def choice_seconds(planned: Geometry, build: BuildSettings) -> float:
    """Wall time [s] of the choice of an ``operator: auto`` geometry: the half-space
    criterion's solves (its surfaces and steps, on both models) on the planned model's
    finite-element grid, as dense solves by CG."""
    grid = planned.finite_element_model(build.max_bytes).grid
    solves = 2 * CALIBRATION["surfaces"] * CALIBRATION["steps"]
    settings = ContactSettings(method="cg", tol=1e-8, precision="double", steps=1,
                               pressure_levels=2)
    return solves * dense_solve_seconds(grid, settings)


def choice_runtime(planned: Geometry, build: BuildSettings, attempt: int = 1) -> int:
    """Requested wall time [min] of a choice of ``operator: auto`` (:func:`choice_seconds`)."""
    return runtime_minutes(choice_seconds(planned, build), attempt)


def summary_runtime(attempt: int = 1) -> int:
    """Wall time [min] of an aggregate, a figure or the config snapshot: 3-6 s
    measured (a figure starts a notebook kernel), asked as 30 s."""
    return runtime_minutes(_MODEL["summaries"]["seconds"], attempt)


def audit_runtime(files: int, attempt: int = 1) -> int:
    """Wall time [min] of the audit: it reads and hashes ``files`` stored files."""
    audit = _MODEL["audit"]
    return runtime_minutes(audit["base_seconds"] + audit["seconds_per_file"] * files, attempt)


def audit_verify_runtime(jobs, settings: ContactSettings, build: BuildSettings, sample: int,
                         attempt: int = 1) -> int:
    """Wall time [min] of audit_verify: at most ``sample`` of the contact ``jobs``
    re-solved, each as long as the slowest."""
    slowest = max((contact_seconds(job, settings, build) for job in jobs), default=0)
    return runtime_minutes(sample * slowest, attempt)


def convergence_runtime(geometry: Geometry, presets, report: ConvergenceSettings,
                        attempt: int = 1) -> int:
    """Wall time [min] of the mesh-convergence report: it reads the stored
    matrices and solves its surfaces on each of ``presets`` and on the
    half-space (measured about 10 s per preset for 3 surfaces on 60 x 60;
    counted as 4 s per solve, scaled as :func:`dense_scale`)."""
    fit = _MODEL["convergence"]
    solves = (len(presets) + 1) * report.surfaces
    seconds = fit["base_seconds"] + solves * fit["solve_seconds"] * dense_scale(geometry.grid)
    return runtime_minutes(seconds, attempt)


def speed_vs_error_runtime(geometry: Geometry, report: SpeedReportSettings,
                           attempt: int = 1) -> int:
    """Wall time [min] of the speed-against-error report, from its parts as
    measured with the defaults (2026-11-24, 2 cores, 401 s in all): the solver
    study on the body's grid with dense matrices (240 s at 60 x 60, 4 surfaces,
    scaled as the contact jobs), the grid study with the matrix-free hybrid
    operator (30 s per grid plus 50 s at 240 x 240, in proportion to n) and
    the surface-count study (70 s for 120 surfaces at 60 x 60)."""
    fit = _MODEL["speed_vs_error"]
    grid = geometry.grid
    surfaces = report.surfaces
    solver = fit["solver_seconds"] * dense_scale(grid) * surfaces / fit["reference_surfaces"]
    grids = sum(
        (fit["grid_seconds"] + fit["grid_reference_seconds"]
         * (g / fit["grid_reference_side"]) ** 2) * surfaces / fit["reference_surfaces"]
        for g in report.grids
    )
    counts = (fit["count_seconds"] * report.count_surfaces / fit["count_surfaces"]
              * grid[0] * grid[1] / fit["reference_elements"])
    return runtime_minutes(solver + grids + counts, attempt)


# ---------------------------------------------------------------------------
# Memory


#: Methods that factor ``C`` on each surface's contact set (block principal pivoting).
PIVOTING = frozenset({"pivot", "exact"})


def slope_per_height(cell) -> float:
    """Root-mean-square slope of a surface cell's heights on its grid per unit of their
    rms height [1/m]: the finite differences along x and y from the ACF of Eq 1,
    ``sqrt(sum 2 (1 - R(spacing) / sigma^2) / spacing^2)``; nan where the plan does not
    know the ACF (a measured cell, a cell of a spectrum)."""
    if not isinstance(cell, GeneratedCell) or cell.spectrum is not None:
        return math.nan
    spec = cell.spec()
    dx, dy = spec.spacing
    try:
        drops = 1.0 - autocorrelation(spec, dx, 0.0), 1.0 - autocorrelation(spec, 0.0, dy)
    except ValueError:  # an ACF given by its spectrum
        return math.nan
    return math.sqrt(2.0 * drops[0] / dx**2 + 2.0 * drops[1] / dy**2)


def contact_fraction_bound(job: ContactJob) -> float:
    """Real contact area fraction a contact job's sweep may reach, at most 1.

    The contact area grows about in proportion to the load, ``A / A0 = kappa P / (E*
    h')`` (Bush, Gibson and Thomas 1975; Persson 2001: kappa 1.6-2.5 at small
    fractions), ``h'`` the rms slope of the heights (:func:`slope_per_height` times
    sigma); in the sweep's variable P L / (E sigma) (``job.pressure_end``, L the
    block's thickness) the fraction is ``kappa (1 + E1 / E2) pressure_end / (L h' /
    sigma)``, a compliant counter body lowering E* by ``1 + E1 / E2``. kappa is the
    cost model's ``contact_fraction_slope``: 4, above kappa = A L h' / (P sigma) at the
    last step of every measured job, P the sweep's end (3.2 at most; 0.6 on the paper
    mesh; the last step overshoots the end by 1.1-2.1); a step's own kappa reaches 4.7
    at 1-5 % contact, where the factors are a few MB. A cell whose slope the plan does
    not know (measured, or of a spectrum) counts as full contact."""
    slope = slope_per_height(job.surface)
    if not math.isfinite(slope):
        return 1.0
    kappa = _MODEL["contact"]["contact_fraction_slope"] * (1.0 + job.counter.modulus_ratio)
    return min(1.0, kappa * job.pressure_end / (job.geometry.thickness * slope))


def factoring(settings: ContactSettings, dense: bool) -> bool:
    """Whether the contact jobs' method factors ``C`` on the contact set (block principal
    pivoting: ``pivot`` or ``exact``, and ``auto`` on a dense matrix) rather than
    iterating with its products."""
    return settings.method in PIVOTING or (settings.method == "auto" and dense)


def pivot_factor_bytes(job: ContactJob, settings: ContactSettings, dense: bool) -> float:
    """Bytes of the Cholesky factors block principal pivoting holds
    (:mod:`roughcontact.contact.pivot`; method ``pivot`` or ``exact``, and ``auto`` on
    a dense matrix): one of ``C`` on the contact set of each surface of a batch in
    flight (``pivot_batch_surfaces``, the contact job's batch: 20), each (a n)^2
    doubles at the contact fraction a (:func:`contact_fraction_bound`), and 3 more
    (``pivot_transient_factors``: the block and its factor, or the old factor and the
    new, while one surface is factored or extended, and their work arrays). Measured
    on the seal study (60 x 60, 20 surfaces swept to P L / (E sigma) = 128, 98-100 %
    contact at the end): 1.95 GB of factors held at
    once, a peak of 2.19-2.53 GB in all against 0.73 GB counted without them."""
    if not factoring(settings, dense):
        return 0.0
    fit = _MODEL["contact"]
    contact_set = contact_fraction_bound(job) * job.geometry.grid[0] * job.geometry.grid[1]
    held = min(job.surface.count, fit["pivot_batch_surfaces"]) + fit["pivot_transient_factors"]
    return held * DOUBLE_BYTES * contact_set**2


def contact_mem_mb(job: ContactJob, settings: ContactSettings, build: BuildSettings) -> int:
    """Peak memory [MB] of a contact job solved with ``settings`` (the contact jobs').

    Dense model: E * C in double and single precision and the contact-set
    matrix of the stiffness (3 n^2 doubles at most), the batch of surfaces
    (10 (count, n) arrays) and 400 MB of interpreter and libraries (measured:
    415 MB on 60 x 60, 167 MB on 30 x 30), and with block principal pivoting (the
    default on a dense matrix) its factors on the contact sets
    (:func:`pivot_factor_bytes`). Matrix-free model: the coarse
    correction (64^2 x 64^2 doubles at most) and FFT work arrays of the batch
    (30 (count, n) arrays: 4 padded copies per surface). A compliant counter body
    adds its model and, on a dense first body, the pair's matrix (2 n^2 doubles),
    and its surfaces (count, n). With the flow on (``settings.flow.directions``), its
    peak (:func:`flow_memory_bytes`) is added.
    """
    fit = _MODEL["contact"]
    nx, ny = job.geometry.grid
    n = nx * ny
    count = job.surface.count
    dense = _dense(job.geometry, build)
    extra = (job.counter.bytes(count, n, dense) + pivot_factor_bytes(job, settings, dense)
             + flow_memory_bytes((nx, ny), count, settings.flow.directions)
             + conductance_bytes(job, settings))
    if not dense:
        return int(fit["memory_base_mb"] + (DOUBLE_BYTES * (COARSE_MAX**2) ** 2 + extra
                   + fit["matrix_free_batch_arrays"] * DOUBLE_BYTES * count * n) / MB)
    return int(fit["memory_base_mb"] + (fit["dense_matrices"] * DOUBLE_BYTES * n**2 + extra
               + fit["dense_batch_arrays"] * DOUBLE_BYTES * count * n) / MB)


def pair_mem_mb(pair) -> int:
    """Peak memory [MB] of a pair's sum (:func:`roughcontact.study.jobs.influence.build_pair`): both
    bodies' matrices, a densified counter body's, the sum and its Cholesky factor (5 n^2
    doubles) and the interpreter's."""
    nx, ny = pair.first.grid
    return int(_MODEL["contact"]["memory_base_mb"] + 5 * DOUBLE_BYTES * (nx * ny) ** 2 / MB)


def pair_runtime(pair, attempt: int = 1) -> int:
    """Requested wall time [min] of a pair's sum: a few seconds on 60 x 60 (2.4 s with a
    half-space made dense, measured), within the shortest request."""
    return runtime_minutes(10.0, attempt)


def influence_mem_mb(geometry: Geometry, build: BuildSettings) -> int:
    """Peak memory [MB] of an influence build: the estimated peak of its
    finite-element solve plus 200 MB."""
    cost = geometry.influence_cost(build)
    return int(cost.peak_bytes / MB) + _MODEL["influence"]["memory_margin_mb"]


def surfaces_mem_mb(cell) -> int:
    """Peak memory [MB] of a surface cell: 300 MB of interpreter and libraries
    (measured 92 MB in all) and 20 work arrays per surface."""
    fit = _MODEL["surfaces"]
    n = cell.grid[0] * cell.grid[1]
    return int(fit["memory_base_mb"] + fit["work_arrays"] * DOUBLE_BYTES * cell.count * n / MB)


def stored_bytes(geometry: Geometry, build: BuildSettings) -> int:
    """Bytes of a stored influence model: the dense matrix, or a matrix-free
    operator's coarse correction (at most 64^2 x 64^2 doubles)."""
    nx, ny = geometry.grid
    if not _dense(geometry, build):
        return DOUBLE_BYTES * (COARSE_MAX**2) ** 2
    return DOUBLE_BYTES * (nx * ny) ** 2


def choice_mem_mb(planned: Geometry, build: BuildSettings) -> int:
    """Peak memory [MB] of a choice of ``operator: auto``: the planned model read (the
    dense matrix, or the coarse correction and Love's coarse matrix beside it) as the
    audit holds one, plus its base."""
    return audit_mem_mb([planned], build)


def audit_mem_mb(geometries, build: BuildSettings) -> int:
    """Peak memory [MB] of the audit: one influence model of ``geometries`` (held
    twice while hashed) at a time, plus 1 GB."""
    audit = _MODEL["audit"]
    largest = max((stored_bytes(g, build) for g in geometries), default=0)
    return int(audit["memory_base_mb"] + audit["model_copies"] * largest / MB)


def audit_verify_mem_mb(jobs, geometries, settings: ContactSettings,
                        build: BuildSettings) -> int:
    """Peak memory [MB] of audit_verify: the audit's or the largest contact job's (solved
    with the contact jobs' ``settings``, the flow as the jobs record it)."""
    largest = max((contact_mem_mb(job, settings, build) for job in jobs), default=0)
    return max(audit_mem_mb(geometries, build), largest)


def convergence_mem_mb(geometry: Geometry, presets) -> int:
    """Peak memory [MB] of the mesh-convergence report: the matrix of each of
    ``presets`` and the half-space's at once, plus 1 GB (2 GB at least)."""
    fit = _MODEL["convergence"]
    n = geometry.grid[0] * geometry.grid[1]
    matrices = len(presets) + 1
    return max(fit["memory_floor_mb"],
               int(fit["memory_base_mb"] + matrices * DOUBLE_BYTES * n**2 / MB))


def speed_vs_error_mem_mb(geometry: Geometry, report: SpeedReportSettings,
                          build: BuildSettings) -> int:
    """Peak memory [MB] of the speed-against-error report: the largest
    finite-element build it makes (the body's grid with the "paper" mesh of
    the solver study; the hybrid operators' coarse "refined" models), three
    dense matrices of the body's grid, and 500 MB (measured 1.4 GB with the
    defaults, against 2.9 GB from this estimate)."""
    fit = _MODEL["speed_vs_error"]
    n = geometry.grid[0] * geometry.grid[1]
    dense = dataclasses.replace(geometry, operator=InfluenceModel.DENSE, halfspace_tolerance=())
    builds = [dataclasses.replace(dense, mesh="paper")] + [
        dataclasses.replace(dense, mesh="refined", grid=(coarsened_side(g),) * 2)
        for g in [*report.grids, geometry.grid[0]]
    ]
    peak = max(b.influence_cost(build).peak_bytes for b in builds)
    return int(fit["memory_base_mb"] + (peak + fit["dense_matrices"] * DOUBLE_BYTES * n**2) / MB)


#: CPU seconds of one contact solve on 1024^2 elements at tol 1e-8 and 3-15 % contact
#: (measured 4-11 s on the shared 2-core machine, cold starts) and the growth with the
#: element count n (n log n products, iterations growing with the grid).
SOLVE_SECONDS_1024 = 12.0
SOLVE_EXPONENT = 1.2


def sweep_runtime(settings: GridConvergenceSettings, grid: int, attempt: int = 1) -> int:
    """Requested wall time [min] of the grid-convergence sweep on ``grid``
    (:func:`roughcontact.study.jobs.grid_convergence.solve_grid`; a retry asks for more)."""
    solves = settings.surfaces * (settings.steps + len(PILOT_FRACTIONS) / 10.0)
    seconds = solves * SOLVE_SECONDS_1024 * (grid * grid / 1024**2) ** SOLVE_EXPONENT
    return int(math.ceil(attempt * (2.0 + 2.0 * seconds / 60.0)))


def grid_mem_mb(settings: GridConvergenceSettings, grid: int) -> int:
    """Peak memory [MB] of a job on ``grid``: 300 MB of interpreter and libraries and 20
    work arrays of doubles per surface (the batched sweep's iterates and products)."""
    return int(300 + 20 * 8 * settings.surfaces * grid * grid / 1e6)


# ---------------------------------------------------------------------------
# Every job's request, by the kind of job (its rule) and its wildcards


def _planned_choice(plan, wildcards) -> Geometry:
    """The planned model of an ``operator: auto`` geometry (its first candidate)."""
    return plan.choices[wildcards["auto"]].candidates(plan.build.max_bytes)[0]


def _convergence(plan) -> tuple:
    return plan.body, plan.study.reports.convergence_presets


@dataclasses.dataclass(frozen=True)
class JobCost:
    """What a kind of job asks a scheduler for: ``memory(plan, wildcards)`` [MB] and
    ``runtime(plan, wildcards, attempt)`` [min]."""

    memory: object
    runtime: object


#: The request of each kind of job (the workflow's rules), from the plan's record that
#: its wildcards name (``job``, ``cycle``, ``geometry``, ``pair``, ``auto``, ``cell``,
#: ``gcgrid``).
JOB_COSTS = MappingProxyType({
    "contact": JobCost(
        lambda plan, w: contact_mem_mb(plan.jobs[w["job"]], plan.contact, plan.build),
        lambda plan, w, a: contact_runtime(plan.jobs[w["job"]], plan.contact, plan.build, a)),
    "cycle": JobCost(
        lambda plan, w: contact_mem_mb(plan.cycles[w["cycle"]].contact, plan.contact,
                                       plan.build),
        lambda plan, w, a: runtime_minutes(cycle_seconds(plan.cycles[w["cycle"]], plan.contact,
                                                         plan.build), a)),
    "influence": JobCost(
        lambda plan, w: influence_mem_mb(plan.geometries[w["geometry"]], plan.build),
        lambda plan, w, a: influence_runtime(plan.geometries[w["geometry"]], plan.build, a)),
    "thermal": JobCost(
        lambda plan, w: thermal_mem_mb(plan.thermal[w["thermal"]], plan.build),
        lambda plan, w, a: runtime_minutes(thermal_seconds(plan.thermal[w["thermal"]],
                                                           plan.build), a)),
    "pair": JobCost(lambda plan, w: pair_mem_mb(plan.pairs[w["pair"]]),
                    lambda plan, w, a: pair_runtime(plan.pairs[w["pair"]], a)),
    "choice": JobCost(
        lambda plan, w: choice_mem_mb(_planned_choice(plan, w), plan.build),
        lambda plan, w, a: choice_runtime(_planned_choice(plan, w), plan.build, a)),
    "surfaces": JobCost(lambda plan, w: surfaces_mem_mb(plan.surfaces[w["cell"]]),
                        lambda plan, w, a: surfaces_runtime(plan.surfaces[w["cell"]], a)),
    "summary": JobCost(lambda plan, w: 1000, lambda plan, w, a: summary_runtime(a)),
    "audit": JobCost(
        lambda plan, w: audit_mem_mb(plan.geometries.values(), plan.build),
        # every candidate's files: at most what the audit reads once the choices are made
        lambda plan, w, a: audit_runtime(len(plan.audit_files(plan.jobs)), a)),
    "audit_verify": JobCost(
        lambda plan, w: audit_verify_mem_mb(plan.jobs.values(), plan.geometries.values(),
                                            plan.contact, plan.build),
        lambda plan, w, a: audit_verify_runtime(plan.jobs.values(), plan.contact, plan.build,
                                                plan.study.audit.verify_sample, a)),
    "influence_convergence": JobCost(
        lambda plan, w: convergence_mem_mb(*_convergence(plan)),
        lambda plan, w, a: convergence_runtime(
            *_convergence(plan), plan.study.reports.influence_convergence, a)),
    "speed_vs_error": JobCost(
        lambda plan, w: speed_vs_error_mem_mb(plan.body, plan.study.reports.speed_vs_error,
                                              plan.build),
        lambda plan, w, a: speed_vs_error_runtime(plan.body,
                                                  plan.study.reports.speed_vs_error, a)),
    "grid_convergence": JobCost(
        lambda plan, w: grid_mem_mb(plan.study.reports.grid_convergence,
                                    int(w["gcgrid"])),
        lambda plan, w, a: sweep_runtime(plan.study.reports.grid_convergence,
                                         int(w["gcgrid"]), a)),
})


def job_memory_mb(plan, kind: str, wildcards) -> int:
    """Memory [MB] a job of ``kind`` (:data:`JOB_COSTS`) asks for."""
    return JOB_COSTS[kind].memory(plan, wildcards)


def job_runtime(plan, kind: str, wildcards, attempt: int = 1) -> int:
    """Wall time [min] a job of ``kind`` (:data:`JOB_COSTS`) asks for at its ``attempt``."""
    return JOB_COSTS[kind].runtime(plan, wildcards, attempt)
