# Shared workflow logic: environment, the study grid from the config, input
# functions (get_*) and wildcard constraints.
import os
import re

from snakemake.exceptions import WorkflowError

from roughcontact import study

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = str(config.get("blas_threads", 1))

NOTEBOOKS = os.path.join(workflow.basedir, "notebooks")
FIGURES = [f"fig{i:02d}" for i in range(1, 6) if f"fig{i:02d}" in config["figures"]]
SURFACE_CELLS = study.surface_cells(config)
GEOMETRIES = study.influence_geometries(config)

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


def get_final_outputs():
    figures = expand(
        "results/figures/{fig}.{ext}", fig=FIGURES, ext=("png", "pdf", "ipynb")
    )
    influence = expand("results/influence/{geometry}.h5", geometry=GEOMETRIES)
    return figures + influence


def get_geometry_params(wildcards):
    return GEOMETRIES[wildcards.geometry]


def get_influence_mem_mb(wildcards):
    """Estimated peak memory of an influence build [MB], for the scheduler."""
    from roughcontact.influence import estimate_cost

    geom = study.block_geometry(GEOMETRIES[wildcards.geometry])
    solver = config.get("body", {}).get("solver", "auto")
    return int(estimate_cost(geom, solver).peak_bytes / 1e6) + 200


def get_surface_params(wildcards):
    return SURFACE_CELLS[wildcards.cell]


def get_surface_path(params):
    return f"results/surfaces/{study.cell_key(params)}.h5"


def get_figure_surfaces(wildcards):
    return [get_surface_path(p) for p in study.figure_cells(config, wildcards.fig)]


def get_figure_parameters(wildcards):
    """Everything a figure notebook needs, passed to it by papermill."""
    cells = study.figure_cells(config, wildcards.fig)
    return {
        "figure": wildcards.fig,
        "settings": config["figures"][wildcards.fig],
        "surface_files": [get_surface_path(p) for p in cells],
        "cells": cells,
        "fig04": config["figures"].get("fig04", {}),
    }
