"""Will the plan's jobs fit this machine and finish in reasonable time? Checked when the
workflow is planned, from the cost model's estimates (:mod:`roughcontact.study.plan.resources`):

- memory: a job that asks for more than the machine (or ``body.max_memory_gb``) has is
  refused before any job runs, naming the config keys that shrink it
  (:func:`check_machine`, :func:`machine_problems`, :func:`memory_advice`);
- time: a job estimated beyond a day is named once in a warning, with the keys that
  shorten it (:func:`warn_long_jobs`).
"""

from __future__ import annotations

import logging
import math
import os
from types import MappingProxyType

from roughcontact.study.plan.checks import ConfigProblems
from roughcontact.study.plan.cost_drift import predictions
from roughcontact.study.plan.resources import (
    MB,
    audit_mem_mb,
    audit_verify_mem_mb,
    choice_mem_mb,
    convergence_mem_mb,
    grid_mem_mb,
    speed_vs_error_mem_mb,
)
from roughcontact.study.records import InfluenceModel
from roughcontact.study.settings import Study
from roughcontact.units import GB

log = logging.getLogger(__name__)


def machine_memory_mb() -> float:
    """Physical memory of this machine [MB] (nan where the system does not say)."""
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / MB
    except (ValueError, OSError, AttributeError):
        return math.nan


#: What changes the memory of each kind of job: the config keys a refusal names.
MEMORY_KEYS = MappingProxyType({
    "contact": "Set body.operator: auto (matrix-free above 64 x 64 elements), or use a "
               "smaller grid (surfaces.grid) or fewer surfaces per cell (surfaces.count or "
               "the study's count)",
    "influence": "Set body.operator: auto (matrix-free above 64 x 64 elements), or use a "
                 "coarser body.mesh or a smaller grid (surfaces.grid)",
    "surfaces": "Use fewer surfaces per cell (surfaces.count or the study's count) or a "
                "smaller grid (surfaces.grid)",
    "cycles": "Set body.operator: auto (matrix-free above 64 x 64 elements), or use a "
              "smaller grid (surfaces.grid) or fewer surfaces per cell (surfaces.count or "
              "the study's count)",
    "thermal_influence": "Use a coarser body.mesh or a smaller grid (surfaces.grid), or let "
                         "the heat cross a half-space (conductance.body: halfspace)",
    "influence_convergence": "Remove reports.influence_convergence (it compares dense "
                             "matrices of the body's grid, whatever body.operator), or give "
                             "it fewer presets, or use a smaller grid (surfaces.grid)",
    "speed_vs_error": "Use fewer or smaller reports.speed_vs_error.grids, or a smaller grid "
                      "(surfaces.grid: its solver study uses dense matrices of it)",
    "grid_convergence": "Use smaller reports.grid_convergence.grids or fewer "
                        "reports.grid_convergence.surfaces",
    "influence_choice": "Set body.operator: dense or hybrid in place of auto, or use a "
                        "smaller grid (surfaces.grid)",
    "audit": "Set body.operator: auto (the audit reads each influence model), or use a "
             "smaller grid (surfaces.grid)",
    "audit_verify": "Set audit.verify: false or body.operator: auto, or use a smaller grid "
                    "(surfaces.grid)",
})
#: The advice of :data:`MEMORY_KEYS` where ``body.operator`` is already auto or hybrid
#: (never advise what the configuration already has).
_MATRIX_FREE_KEYS = MappingProxyType({
    "contact": "Use a smaller grid (surfaces.grid) or fewer surfaces per cell "
               "(surfaces.count or the study's count)",
    "cycles": "Use a smaller grid (surfaces.grid) or fewer surfaces per cell "
              "(surfaces.count or the study's count)",
    "influence": "Use a coarser body.mesh or a smaller grid (surfaces.grid)",
    "audit": "Use a smaller grid (surfaces.grid)",
    "audit_verify": "Set audit.verify: false, or use a smaller grid (surfaces.grid)",
})


def memory_advice(plan, kind: str) -> str:
    """The keys that change the memory of a ``kind`` of job (:data:`MEMORY_KEYS`), less
    ``body.operator: auto`` where the study's body already has it (or hybrid)."""
    if plan.study.body.geometry.operator is InfluenceModel.DENSE:
        return MEMORY_KEYS[kind]
    return _MATRIX_FREE_KEYS.get(kind, MEMORY_KEYS[kind])


def _report_memory(plan) -> dict[str, dict[str, int]]:
    """Planned memory [MB] of the jobs of the default target besides the study's: the
    choices of ``operator: auto``, the mesh-convergence report when configured, and the
    audits; by kind of job and job."""
    out, study = {}, plan.study
    if plan.choices:
        out["influence_choice"] = {
            key: choice_mem_mb(geometry.candidates(plan.build.max_bytes)[0], plan.build)
            for key, geometry in plan.choices.items()}
    if "influence_convergence" in study.reports.configured:  # optional: a report to run
        presets = study.reports.convergence_presets
        out["influence_convergence"] = {"influence_convergence":
                                        convergence_mem_mb(plan.body, presets)}
    if plan.studies:
        out["audit"] = {"audit": audit_mem_mb(plan.geometries.values(), plan.build)}
        if study.audit.verify:
            out["audit_verify"] = {"audit_verify": audit_verify_mem_mb(
                plan.jobs.values(), plan.geometries.values(), plan.contact, plan.build)}
    return out


def on_demand_memory(plan) -> dict[str, dict[str, int]]:
    """Planned memory [MB] of the reports made only when asked for (their targets): the
    speed-against-error report, and the grid-convergence jobs when configured."""
    reports = plan.study.reports
    out = {"speed_vs_error": {"speed_vs_error": speed_vs_error_mem_mb(
        plan.body, reports.speed_vs_error, plan.build)}}
    if "grid_convergence" in reports.configured:  # optional: a report to run
        settings = reports.grid_convergence
        out["grid_convergence"] = {f"grid {g}": grid_mem_mb(settings, g)
                                   for g in settings.grids}
    return out


def planned_memory(plan) -> dict[str, dict[str, int]]:
    """Planned peak memory [MB] of every job a study's ``plan`` runs by default, by kind
    of job (:data:`MEMORY_KEYS`) and job: the contact, influence and surfaces jobs, the
    choices of ``operator: auto``, the mesh-convergence report when configured and the
    audits (the reports made on demand: :func:`on_demand_memory`)."""
    jobs = {rule: {key: mem_mb for key, (_, mem_mb) in by_key.items()}
            for rule, by_key in predictions(plan).items()}
    return jobs | _report_memory(plan)


def _amount(mem_mb: float) -> str:
    """A memory [MB] in the unit that suits it (MB, GB, TB, PB)."""
    for unit, scale in (("PB", 1e9), ("TB", 1e6), ("GB", 1e3)):
        if mem_mb >= scale:
            return f"{mem_mb / scale:.3g} {unit}"
    return f"{mem_mb:.0f} MB"


def memory_limit_mb(study: Study) -> tuple[float, str]:
    """The memory [MB] one job may use and where it comes from: ``job_memory_gb``, or
    this machine's physical memory."""
    configured = study.job_memory_gb  # null: this machine's
    if configured is not None:
        return float(configured) * GB / MB, f"job_memory_gb = {configured:g}"
    total = machine_memory_mb()
    return total, f"this machine's {_amount(total)}"


def machine_problems(plan, total_mb: float | None = None,
                     jobs: dict | None = None) -> list[str]:
    """The ``jobs`` (default: :func:`planned_memory`'s, every job of the default
    target, reports included) of a study's ``plan`` whose planned memory exceeds
    ``total_mb`` (default: ``job_memory_gb``, else this machine's): one message per kind
    of job, with the largest, the count and the keys to change."""
    if total_mb is None:
        total_mb, source = memory_limit_mb(plan.study)
    else:
        source = f"the limit of {_amount(total_mb)}"
    if not math.isfinite(total_mb):
        return []
    problems = []
    for kind, by_key in (planned_memory(plan) if jobs is None else jobs).items():
        over = {key: mem for key, mem in by_key.items() if mem > total_mb}
        if not over:
            continue
        key, mem = max(over.items(), key=lambda item: item[1])
        more = f" (and {len(over) - 1} more of its kind)" if len(over) > 1 else ""
        problems.append(
            f"{kind} job {key}: planned {_amount(mem)} of memory{more}, more than {source}. "
            f"{memory_advice(plan, kind)}; or, if the jobs run on cluster nodes with more, set "
            "job_memory_gb to their memory [GB]")
    return problems


def check_machine(plan, kinds: tuple[str, ...] | None = None) -> None:
    """Raise :class:`~roughcontact.study.plan.checks.ConfigProblems` naming every kind of job
    of a study's ``plan`` that would not fit (:func:`machine_problems`), before any job
    runs: the jobs of the default target, or the on-demand reports of ``kinds`` (when
    their target is asked for)."""
    jobs = None if kinds is None else \
        {k: v for k, v in on_demand_memory(plan).items() if k in kinds}
    problems = machine_problems(plan, jobs=jobs)
    if problems:
        raise ConfigProblems("Jobs planned beyond the memory a job may use", problems)


#: [s] A job planned to take longer than this (a day) is named when the plan is made.
LONG_JOB_SECONDS = 86400.0

#: What shortens each kind of job the long-job warning names: the config keys to change.
TIME_KEYS = MappingProxyType({
    "contact": "Use fewer surfaces per cell (surfaces.count or the study's count), fewer "
               "contact.steps or a smaller grid (surfaces.grid), set body.operator: auto "
               "(matrix-free above 64 x 64 elements) where it is dense, or, with the flow "
               "on, record it along one direction (flow.directions: [x])",
    "influence": "Set body.operator: auto (matrix-free above 64 x 64 elements), or use a "
                 "coarser body.mesh or a smaller grid (surfaces.grid)",
    "surfaces": "Use fewer surfaces per cell (surfaces.count or the study's count), a "
                "smaller grid (surfaces.grid) or surfaces.method: filter",
    "thermal_influence": "Use a coarser body.mesh or a smaller grid (surfaces.grid), or let "
                         "the heat cross a half-space (conductance.body: halfspace)",
})


def _duration(seconds: float) -> str:
    """A wall time [s] in days or hours."""
    days = seconds / 86400.0
    return f"{days:.3g} days" if days >= 1.0 else f"{seconds / 3600.0:.3g} hours"


def long_jobs(plan, limit_seconds: float = LONG_JOB_SECONDS) -> list[str]:
    """One message for each contact, influence, surfaces and thermal influence job of a
    study's ``plan`` whose estimated wall time
    (:func:`~roughcontact.study.plan.cost_drift.predictions`, before the margin; measured
    on the reference machine's 2 cores, one BLAS thread a job: ``blas_threads``) exceeds
    ``limit_seconds``: the job, its estimate and the keys that shorten it
    (:data:`TIME_KEYS`), the longest first."""
    threads = plan.study.blas_threads
    over = sorted(((seconds, kind, key) for kind, jobs in predictions(plan).items()
                   for key, (seconds, _) in jobs.items() if seconds > limit_seconds),
                  reverse=True)
    return [f"{kind} job {key}: estimated {_duration(seconds)} of wall time with "
            f"blas_threads = {threads}. {TIME_KEYS[kind]}" for seconds, kind, key in over]


def warn_long_jobs(plan) -> None:
    """Log one warning naming every job of a study's ``plan`` estimated to take more than a
    day (:func:`long_jobs`), before any job runs; nothing when there is none."""
    messages = long_jobs(plan)
    if messages:
        log.warning("Jobs planned to run longer than a day (the cost model's estimate):\n  "
                    + "\n  ".join(messages))
