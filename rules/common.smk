# Shared workflow logic: environment, the study grid from the config, input
# functions (get_*) and wildcard constraints.
import json
import math
import os
import re

from snakemake.exceptions import WorkflowError

from roughcontact.study import cells as study
from roughcontact.elasticity.operators import coarsened_side
from roughcontact.study.provenance import config_hash

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = str(config["blas_threads"])

NOTEBOOKS = os.path.join(workflow.basedir, "notebooks")
FIGURES = [
    name
    for name in (*study.SURFACE_ONLY_FIGURES, *study.CONTACT_FIGURES)
    if name in config["figures"]
]
# contact studies: the paper's figures and the user's own sweeps
STUDIES = [n for n in FIGURES if n in study.CONTACT_FIGURES] + list(config["sweeps"])
_bad_studies = study.check_studies(config, STUDIES)
if _bad_studies:
    raise WorkflowError(
        "Invalid contact studies in the config (no job was started):\n  "
        + "\n  ".join(_bad_studies)
    )
CONTACT_JOBS = study.contact_jobs(config, STUDIES)
SURFACE_CELLS = study.surface_cells(config) | {
    job["surface_key"]: job["surface"] for job in CONTACT_JOBS.values()
}
GEOMETRIES = study.influence_geometries(config) | {
    job["geometry_key"]: job["geometry"] for job in CONTACT_JOBS.values()
}
# aggregates are computed once per source ("fig12: {from: fig07}" reuses fig07's)
AGGREGATES = sorted({study.source_name(config, name) for name in STUDIES})

_infeasible = study.check_feasible(SURFACE_CELLS)
if _infeasible:
    raise WorkflowError(
        "Infeasible surface cells in the config (no job was started):\n  "
        + "\n  ".join(_infeasible)
    )


wildcard_constraints:
    cell="|".join(re.escape(k) for k in SURFACE_CELLS) or "__none__",
    fig="|".join(FIGURES) or "__none__",
    geometry="|".join(re.escape(k) for k in GEOMETRIES) or "__none__",
    job="|".join(re.escape(k) for k in CONTACT_JOBS) or "__none__",
    study="|".join(AGGREGATES) or "__none__",


def canonical(obj):
    """``obj`` with every dict's keys sorted: rule params that do not depend on
    the order of keys in the config file (Snakemake reruns a job when the text
    of its params changes)."""
    return json.loads(study.canonical_json(obj))


def get_final_outputs():
    figures = expand(
        "results/figures/{fig}.{ext}", fig=FIGURES, ext=("png", "pdf", "ipynb")
    )
    influence = expand("results/influence/{geometry}.h5", geometry=GEOMETRIES)
    aggregates = expand(
        "results/aggregates/{study}.{ext}",
        study=AGGREGATES,
        ext=("csv", "moduli.csv", "json"),
    )
    audit = ["results/audit/audit.csv", "results/audit/audit.md"] if STUDIES else []
    if STUDIES and config["audit"]["verify"]:
        audit.append("results/audit/verify.csv")
    reports = []
    if "influence_convergence" in config["reports"]:
        reports += [
            "results/reports/influence_convergence.csv",
            "results/reports/influence_convergence.png",
        ]
    return figures + influence + aggregates + audit + reports + ["results/config.yaml"]


def get_body_geometry(wildcards):
    return study.geometry_params(config["body"], config["surfaces"])


def get_convergence_stored(wildcards):
    """Preset -> influence file of the body's geometry with that mesh."""
    params = study.geometry_params(config["body"], config["surfaces"])
    return {
        mesh: f"results/influence/{study.geometry_key({**params, 'mesh': mesh})}.h5"
        for mesh in study.convergence_presets(config)
    }


def get_convergence_inputs(wildcards):
    return sorted(get_convergence_stored(wildcards).values())


def get_audit_studies(wildcards):
    return {name: study.contact_cells(config, name) for name in STUDIES}


def get_audit_inputs(wildcards):
    files = set()
    for job in CONTACT_JOBS.values():
        files.add(f"results/contact/{study.contact_key(job)}.h5")
        files.add(f"results/surfaces/{job['surface_key']}.h5")
        files.add(f"results/influence/{job['geometry_key']}.h5")
    return sorted(files)


def get_contact_params(wildcards):
    return CONTACT_JOBS[wildcards.job]


def get_contact_inputs(wildcards):
    job = CONTACT_JOBS[wildcards.job]
    return {
        "surfaces": f"results/surfaces/{job['surface_key']}.h5",
        "influence": f"results/influence/{job['geometry_key']}.h5",
    }


def get_aggregate_cells(wildcards):
    return study.contact_cells(config, wildcards.study)


def get_aggregate_inputs(wildcards):
    cells = study.contact_cells(config, wildcards.study)
    return sorted({f"results/contact/{study.contact_key(c)}.h5" for c in cells})


def get_geometry_params(wildcards):
    return GEOMETRIES[wildcards.geometry]


def get_influence_mem_mb(wildcards):
    """Estimated peak memory of an influence build [MB], for the scheduler."""
    cost = study.influence_cost(
        GEOMETRIES[wildcards.geometry], **_influence_build_settings()
    )
    return int(cost.peak_bytes / 1e6) + 200


def _influence_build_settings():
    body = config.get("body", {})
    return {
        "solver": body.get("solver", "auto"),
        "max_memory_gb": body.get("max_memory_gb", 16),
    }


def get_surface_params(wildcards):
    return SURFACE_CELLS[wildcards.cell]


def get_surface_inputs(wildcards):
    """The measured file of a measured surface cell (none for generated cells)."""
    cell = SURFACE_CELLS[wildcards.cell]
    return [cell["measured"]["file"]] if cell["method"] == "measured" else []


def get_surface_path(params):
    return f"results/surfaces/{study.cell_key(params)}.h5"


def get_figure_surfaces(wildcards):
    return [get_surface_path(p) for p in study.figure_cells(config, wildcards.fig)]


def get_figure_aggregates(wildcards):
    if wildcards.fig not in study.CONTACT_FIGURES:
        return []
    name = study.source_name(config, wildcards.fig)
    return [
        f"results/aggregates/{name}.csv",
        f"results/aggregates/{name}.moduli.csv",
        f"results/aggregates/{name}.json",
    ]


def get_figure_parameters(wildcards):
    """Everything a figure notebook needs, passed to it by papermill."""
    cells = study.figure_cells(config, wildcards.fig)
    return canonical(
        {
            "figure": wildcards.fig,
            "settings": study.resolve_source(config, wildcards.fig),
            "surface_files": [get_surface_path(p) for p in cells],
            "aggregate_files": get_figure_aggregates(wildcards),
            "cells": cells,
            "fig04": config["figures"].get("fig04", {}),
        }
    )


# ---- Cluster resources ------------------------------------------------------
# Memory [MB] and wall time [min] of every job, for schedulers that enforce
# them (profiles/slurm). Estimated from the grid, the surface count, the mesh
# and the solver settings, scaled from runs on the reference machine (2 cores,
# see README); a job that outlives its wall time is killed, so the estimate is
# multiplied by RUNTIME_MARGIN and by the attempt (`retries` in the profile).
RUNTIME_MARGIN = 3
RUNTIME_START_MIN = 5  # interpreter start, imports, reading and writing files
# one contact solve (one surface, one approach step) on 60 x 60 elements: the
# slowest measured cell, 186 s for 60 surfaces x 30 steps (paper mesh, CG 1e-8)
CONTACT_SOLVE_SECONDS = 0.11
# matrix products per solve relative to CG (steepest descent: 2-3 times)
CONTACT_METHOD_COST = {"cg": 1.0, "steepest": 3.0, "exact": 3.0}


def _runtime_minutes(seconds, attempt=1):
    """Requested wall time [min] of a job estimated to take ``seconds`` [s]."""
    import math

    return attempt * (RUNTIME_START_MIN + math.ceil(RUNTIME_MARGIN * seconds / 60))


def _dense_scale(grid):
    """Cost of the contact solves on ``grid`` [nx, ny] relative to 60 x 60.

    A product with the dense influence matrix costs n^2 for n = nx ny
    elements, and CG iterations grow about as sqrt(n) with its condition
    number: n^2.5 (measured at 30 x 30 and 60 x 60 only, an upper bound there).
    """
    return (grid[0] * grid[1] / 3600) ** 2.5


def _contact_solve_seconds(grid, settings):
    """Wall time [s] of one contact solve on ``grid`` with solver ``settings``.

    A tighter tolerance costs iterations in proportion to its digits (1e-8 is
    the reference).
    """
    import math

    digits = max(1.0, math.log10(1.0 / float(settings.get("tol", 1e-8))) / 8)
    method = CONTACT_METHOD_COST[settings.get("method", "cg")]
    return CONTACT_SOLVE_SECONDS * _dense_scale(grid) * digits * method


def _contact_seconds(job):
    """Wall time [s] of a contact job: surfaces x approach steps x one solve.

    Measured 35-186 s per cell of 60 surfaces x 30 steps on 60 x 60 (paper
    mesh; the converged mesh needs fewer iterations) and 4 s on 30 x 30. A
    sweep beyond P L / (E sigma) = 4 (the study's) reaches larger contact
    fractions, where CG needs more iterations: counted in proportion.
    """
    settings = study.contact_settings(config)
    solves = job["surface"]["count"] * int(settings.get("steps", 30))
    reach = max(1.0, job["pressure_end"] / 4)
    if study.planned_operator(job["geometry"]) != "dense":
        # matrix-free operator: 0.62 s per solve at 256 x 256 (0.64 s at 240,
        # 0.19 s at 120; 2 loaded cores), about in proportion to n
        nx, ny = job["geometry"]["grid"]
        per_solve = max(0.05, 0.62 * nx * ny / 65536)
        digits = max(1.0, math.log10(1.0 / float(settings.get("tol", 1e-8))) / 8)
        method = CONTACT_METHOD_COST[settings.get("method", "cg")]
        return solves * per_solve * digits * method * reach
    return solves * _contact_solve_seconds(job["geometry"]["grid"], settings) * reach


def get_contact_runtime(wildcards, attempt):
    return _runtime_minutes(_contact_seconds(CONTACT_JOBS[wildcards.job]), attempt)


def _contact_mem_mb(job):
    """Peak memory [MB] of a contact job: E * C in double and single precision
    and the contact-set matrix of the stiffness (3 n^2 doubles at most), the
    batch of surfaces (10 (count, n) arrays) and 400 MB of interpreter and
    libraries (measured: 415 MB on 60 x 60, 167 MB on 30 x 30)."""
    nx, ny = job["geometry"]["grid"]
    n = nx * ny
    if study.planned_operator(job["geometry"]) != "dense":
        # matrix-free: the coarse correction (64^2 x 64^2 doubles at most) and
        # FFT work arrays of the batch (4 padded copies per surface)
        return int(400 + (8 * 4096**2 + 30 * 8 * job["surface"]["count"] * n) / 1e6)
    return int(400 + (3 * 8 * n**2 + 10 * 8 * job["surface"]["count"] * n) / 1e6)


def get_contact_mem_mb(wildcards):
    return _contact_mem_mb(CONTACT_JOBS[wildcards.job])


def get_influence_runtime(wildcards, attempt):
    """Wall time [min] of an influence build, from its estimated peak memory.

    The work of the sparse factorization and of the dense Schur complement
    grows with the memory they need. Build times on 2 cores (MKL PARDISO)
    against ``roughcontact.influence.estimate_cost``'s peak: 60 x 60 paper
    4.2 s (0.92 GB), graded 12.5 s (2.0 GB), refined 12.3 s (2.1 GB),
    converged 116-132 s (9.6 GB); 120 x 120 paper 63 s (6.9 GB), graded
    248 s (12.6 GB). 4.2 s (GB / 0.92)^1.56 passes through the first and
    the last and lies above the others (SuperLU: 36 s at 60 x 60 paper,
    45 s predicted).
    """
    cost = study.influence_cost(
        GEOMETRIES[wildcards.geometry], **_influence_build_settings()
    )
    peak_gb = cost.peak_bytes / 1e9
    return _runtime_minutes(4.2 * (peak_gb / 0.92) ** 1.56, attempt)


def get_surfaces_runtime(wildcards, attempt):
    """Wall time [min] of a surface cell: 60 surfaces of 60 x 60 take 0.01 s
    by the filter and 1.3 s by IAAFT (``exact``); 120 x 120: 0.04 s, 7.7 s."""
    cell = SURFACE_CELLS[wildcards.cell]
    per_surface = 0.03 if cell["method"] == "exact" else 0.001
    size = cell["grid"][0] * cell["grid"][1] / 3600
    return _runtime_minutes(cell["count"] * per_surface * size**1.5, attempt)


def get_surfaces_mem_mb(wildcards):
    """Peak memory [MB] of a surface cell: 300 MB of interpreter and libraries
    (measured 92 MB in all) and 20 work arrays per surface."""
    cell = SURFACE_CELLS[wildcards.cell]
    return int(300 + 20 * 8 * cell["count"] * cell["grid"][0] * cell["grid"][1] / 1e6)


def get_summary_runtime(wildcards, attempt):
    """Wall time [min] of an aggregate, a figure or the config snapshot:
    3-6 s measured (a figure starts a notebook kernel)."""
    return _runtime_minutes(30, attempt)


def get_audit_runtime(wildcards, attempt):
    """Wall time [min] of the audit: it reads and hashes every stored file."""
    return _runtime_minutes(30 + 2 * len(get_audit_inputs(wildcards)), attempt)


def get_audit_mem_mb(wildcards):
    """Peak memory [MB] of the audit: one influence matrix (held twice while
    hashed) at a time, plus 1 GB."""
    return int(
        1000 + 2 * max((_stored_bytes(g) for g in GEOMETRIES.values()), default=0) / 1e6
    )


def _stored_bytes(geometry):
    """Bytes of a stored influence model: the dense matrix, or a matrix-free
    operator's coarse correction (at most 64^2 x 64^2 doubles)."""
    nx, ny = geometry["grid"]
    if study.planned_operator(geometry) != "dense":
        return 8 * 4096**2
    return 8 * (nx * ny) ** 2


def _verify_sample():
    return int(config.get("audit", {}).get("verify_sample", 3))


def get_audit_verify_runtime(wildcards, attempt):
    """Wall time [min] of audit_verify: at most `verify_sample` contact jobs re-solved."""
    slowest = max((_contact_seconds(job) for job in CONTACT_JOBS.values()), default=0)
    return _runtime_minutes(_verify_sample() * slowest, attempt)


def get_audit_verify_mem_mb(wildcards):
    largest = max((_contact_mem_mb(job) for job in CONTACT_JOBS.values()), default=0)
    return max(get_audit_mem_mb(wildcards), largest)


def get_convergence_runtime(wildcards, attempt):
    """Wall time [min] of the mesh-convergence report: it reads the stored
    matrices and solves its surfaces on each preset and on the half-space
    (measured about 10 s per preset for 3 surfaces on 60 x 60)."""
    settings = config.get("reports", {}).get("influence_convergence", {})
    params = study.geometry_params(config["body"], config["surfaces"])
    solves = (len(study.convergence_presets(config)) + 1) * settings.get("surfaces", 3)
    return _runtime_minutes(30 + solves * 4 * _dense_scale(params["grid"]), attempt)


def get_convergence_mem_mb(wildcards):
    """Peak memory [MB] of the mesh-convergence report: every preset's matrix
    and the half-space's at once, plus 1 GB."""
    params = study.geometry_params(config["body"], config["surfaces"])
    n = params["grid"][0] * params["grid"][1]
    matrices = len(study.convergence_presets(config)) + 1
    return max(2000, int(1000 + matrices * 8 * n**2 / 1e6))


def _speed_settings():
    return config.get("reports", {}).get("speed_vs_error", {})


def get_speed_vs_error_runtime(wildcards, attempt):
    """Wall time [min] of the speed-against-error report, from its parts as
    measured with the defaults (2026-11-24, 2 cores, 401 s in all): the solver
    study on the body's grid with dense matrices (240 s at 60 x 60, 4 surfaces,
    scaled as the contact jobs), the grid study with the matrix-free hybrid
    operator (30 s per grid plus 50 s at 240 x 240, in proportion to n) and
    the surface-count study (70 s for 120 surfaces at 60 x 60)."""
    settings = _speed_settings()
    grid = study.geometry_params(config["body"], config["surfaces"])["grid"]
    surfaces = settings.get("surfaces", 4)
    solver = 240 * _dense_scale(grid) * surfaces / 4
    grids = sum(
        (30 + 50 * (g / 240) ** 2) * surfaces / 4
        for g in settings.get("grids", [30, 60, 120])
    )
    counts = 70 * settings.get("count_surfaces", 120) / 120 * grid[0] * grid[1] / 3600
    return _runtime_minutes(solver + grids + counts, attempt)


def get_speed_vs_error_mem_mb(wildcards):
    """Peak memory [MB] of the speed-against-error report: the largest
    finite-element build it makes (the body's grid with the "paper" mesh of
    the solver study; the hybrid operators' coarse "refined" models), three dense
    matrices of the body's grid, and 500 MB (measured 1.4 GB with the
    defaults, against 2.9 GB from this estimate)."""
    settings = _speed_settings()
    params = study.geometry_params(config["body"], config["surfaces"])
    n = params["grid"][0] * params["grid"][1]
    dense = dict(params, operator="dense")
    # the solver study's "paper" matrix; the hybrid operators' coarse models
    builds = [dict(dense, mesh="paper")] + [
        dict(dense, mesh="refined", grid=[coarsened_side(g)] * 2)
        for g in [*settings.get("grids", [30, 60, 120]), params["grid"][0]]
    ]
    peak = max(
        study.influence_cost(b, **_influence_build_settings()).peak_bytes
        for b in builds
    )
    return int(500 + (peak + 3 * 8 * n**2) / 1e6)
