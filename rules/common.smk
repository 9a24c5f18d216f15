# Shared workflow logic: environment, the study grid from the config, input
# functions (get_*) and wildcard constraints.
import dataclasses
import hashlib
import json
import os
import re

from snakemake.exceptions import IncompleteCheckpointException, WorkflowError

from roughcontact.reports.captions import figure_caption
from roughcontact.study import grid_convergence, resources
from roughcontact.study.cells import (
    convergence_presets,
    drawn_with,
    figure_aggregates,
    study_plan,
)
from roughcontact.study.checks import ConfigProblems
from roughcontact.study.config import (
    ConvergenceSettings,
    SpeedReportSettings,
    report_section,
)
from roughcontact.study.flow_settings import flow_settings
from roughcontact.study.grid_convergence import GridConvergenceSettings
from roughcontact.study.provenance import canonical_json, config_hash
from roughcontact.study.records import InfluenceModel
from roughcontact.study.storage import read_choice
from roughcontact.study.sources import spectrum_from_entry
from roughcontact.study.studies import audit_verify_seed, resolve_source

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = str(config["blas_threads"])

NOTEBOOKS = os.path.join(workflow.basedir, "notebooks")
# every job, cell and file key of the study, as typed records: made once per run
# and every job's memory, reports included, within what a job may use (job_memory_gb)
try:
    PLAN = study_plan(config)
    resources.check_machine(config, plan=PLAN)
except ConfigProblems as err:
    raise WorkflowError(str(err)) from None
FIGURES = PLAN.figures
# contact studies: the paper's figures and the user's own sweeps
STUDIES = PLAN.studies
CONTACT_JOBS = PLAN.jobs
SURFACE_CELLS = PLAN.surfaces
GEOMETRIES = PLAN.geometries
# aggregates are computed once per source ("fig12: {from: fig07}" reuses fig07's)
AGGREGATES = PLAN.aggregates


wildcard_constraints:
    auto="|".join(re.escape(k) for k in PLAN.choices) or "__none__",
    cell="|".join(re.escape(k) for k in SURFACE_CELLS) or "__none__",
    fig="|".join(FIGURES) or "__none__",
    geometry="|".join(re.escape(k) for k in GEOMETRIES) or "__none__",
    pair="|".join(re.escape(k) for k in PLAN.pairs) or "__none__",
    job="|".join(re.escape(k) for k in CONTACT_JOBS) or "__none__",
    study="|".join(AGGREGATES) or "__none__",


def canonical(obj):
    """``obj`` with every dict's keys sorted: rule params that do not depend on
    the order of keys in the config file (Snakemake reruns a job when the text
    of its params changes)."""
    return json.loads(canonical_json(obj))


def get_final_outputs():
    figures = expand(
        "results/figures/{fig}.{ext}", fig=FIGURES, ext=("png", "pdf", "ipynb")
    ) + [f"results/figures/{fig}.csv" for fig in FIGURES if fig.startswith("table_")]
    # a half-space that only a choice of operator: auto may pick is built if picked
    influence = [
        f"results/influence/{key}.h5"
        for key in GEOMETRIES
        if key not in PLAN.alternatives
    ] + [f"results/influence/choices/{key}.json" for key in PLAN.choices]
    aggregates = expand(
        "results/aggregates/{study}.{ext}",
        study=AGGREGATES,
        ext=("csv", "moduli.csv", "json", "validity.csv"),
    )
    audit = ["results/audit/audit.csv", "results/audit/audit.md"] if STUDIES else []
    if STUDIES and config["audit"]["strict"]:
        audit.append("results/audit/strict.ok")
    if STUDIES and config["audit"]["verify"]:
        audit.append("results/audit/verify.csv")
    reports = []
    if "influence_convergence" in config["reports"]:
        reports += [
            "results/reports/influence_convergence.csv",
            "results/reports/influence_convergence.png",
        ]
    return figures + influence + aggregates + audit + reports + ["results/config.yaml"]


# ---- operator: auto, resolved when the workflow runs ---------------------------
# A geometry of operator: auto becomes its planned model (dense or hybrid) or the
# half-space, as its choice (a checkpoint) says; the resolved geometry has the key
# and files of a geometry configured with that model.


def resolved_geometry(geometry):
    """The geometry ``geometry`` resolves to (itself unless it is ``operator: auto``)."""
    if geometry.key not in PLAN.choices:
        return geometry
    path = checkpoints.influence_choice.get(auto=geometry.key).output[0]
    choice = read_choice(path, geometry=geometry.params())
    return geometry.resolved(InfluenceModel(choice["operator"]))


def resolved_cells(study):
    """The study cells of ``study`` on their resolved geometries."""
    return [
        dataclasses.replace(cell, geometry=resolved_geometry(cell.geometry))
        for cell in PLAN.cells[study]
    ]


def resolved_jobs():
    """The contact jobs the study cells run, on their resolved geometries, by key."""
    jobs = {}
    for name in STUDIES:  # the plan's order
        for cell in resolved_cells(name):
            jobs.setdefault(cell.job.key, cell.job)
    return jobs


def settled(function, *args):
    """``function(*args)``, or with every choice taken as planned while a choice is
    still to be made (params are read before a checkpoint has run; the job is
    planned again after it)."""
    try:
        return function(*args)
    except IncompleteCheckpointException:
        return None


def get_choice_geometry(wildcards):
    return PLAN.choices[wildcards.auto].params()


def get_choice_planned(wildcards):
    """The planned model of an operator: auto geometry (its first candidate)."""
    return PLAN.choices[wildcards.auto].candidates(PLAN.build.max_bytes)[0].params()


def get_choice_input(wildcards):
    planned = PLAN.choices[wildcards.auto].candidates(PLAN.build.max_bytes)[0]
    return f"results/influence/{planned.key}.h5"


# ---- Params of the jobs: the plan's records in their plain form (params()) --


def get_body_geometry(wildcards):
    return PLAN.body.params()


def get_convergence_stored(wildcards):
    """Preset -> influence file of the body's geometry with that mesh (of operator: auto,
    its planned model: the report compares finite-element models)."""
    max_bytes = PLAN.build.max_bytes
    return {
        mesh: "results/influence/"
        f"{dataclasses.replace(PLAN.body, mesh=mesh).candidates(max_bytes)[0].key}.h5"
        for mesh in convergence_presets(config)
    }


def get_convergence_inputs(wildcards):
    return sorted(get_convergence_stored(wildcards).values())


def _audit_studies():
    return {name: [c.params() for c in resolved_cells(name)] for name in AGGREGATES}


def get_audit_studies(wildcards):
    # each cell once: a study "from:" another (fig12 from fig07, the measured figure
    # from its sweep) has the same cells
    return settled(_audit_studies)


def get_audit_stamp(wildcards):
    """A hash of the size, mtime and ctime of every file the audit reads."""
    digest = hashlib.sha256()
    for path in settled(get_audit_inputs, wildcards) or []:
        try:
            st = os.stat(path)
            digest.update(
                f"{path}|{st.st_size}|{st.st_mtime_ns}|{st.st_ctime_ns}\n".encode()
            )
        except FileNotFoundError:
            digest.update(f"{path}|missing\n".encode())
    return digest.hexdigest()


def audit_files(jobs):
    """The files the audit reads for contact ``jobs`` (by key) and the choices."""
    files = {f"results/influence/choices/{key}.json" for key in PLAN.choices}
    for key, job in jobs.items():
        files.add(f"results/contact/{key}.h5")
        files.update(job.paths().values())
    return sorted(files)


def get_audit_inputs(wildcards):
    return audit_files(resolved_jobs())


def get_audit_jobs(wildcards):
    return settled(lambda: {key: job.params() for key, job in resolved_jobs().items()})


def get_contact_params(wildcards):
    return CONTACT_JOBS[wildcards.job].params()


def get_contact_inputs(wildcards):
    # the files a contact job reads: one place decides them (ContactJob.files)
    return CONTACT_JOBS[wildcards.job].paths()


def get_aggregate_cells(wildcards):
    return settled(lambda: [cell.params() for cell in resolved_cells(wildcards.study)])


def get_aggregate_inputs(wildcards):
    cells = resolved_cells(wildcards.study)
    return sorted({f"results/contact/{cell.contact_key}.h5" for cell in cells})


def get_geometry_params(wildcards):
    return GEOMETRIES[wildcards.geometry].params()


def get_surface_params(wildcards):
    return SURFACE_CELLS[wildcards.cell].params()


def get_surface_inputs(wildcards):
    """``files``: the measured file of a measured surface cell, the spectrum's file (a
    PSD table or a measurement) of a generated cell with one; ``source``: the file of
    the larger cell whose first surfaces the cell takes (PLAN.surfaces_from), if any."""
    inputs = {"files": list(SURFACE_CELLS[wildcards.cell].input_files)}
    source = PLAN.surfaces_from.get(wildcards.cell)
    if source is not None:
        inputs["source"] = f"results/surfaces/{source}.h5"
    return inputs


def get_surface_source(wildcards):
    """The params of the cell whose file the cell's surfaces are taken from (None: it
    makes its own)."""
    source = PLAN.surfaces_from.get(wildcards.cell)
    return None if source is None else SURFACE_CELLS[source].params()


def get_figure_surfaces(wildcards):
    return [f"results/surfaces/{c.key}.h5" for c in PLAN.figure_surfaces[wildcards.fig]]


def get_figure_aggregates(wildcards):
    """The aggregate files of the studies a figure draws, four per study in its order."""
    return [
        f"results/aggregates/{name}.{ext}"
        for name in figure_aggregates(config, wildcards.fig)
        for ext in ("csv", "moduli.csv", "json", "validity.csv")
    ]


def get_figure_caption(wildcards):
    """The report's caption of a figure, written from the study's own settings."""
    return figure_caption(wildcards.fig, config, PLAN)


def get_figure_parameters(wildcards):
    """Everything a figure notebook needs, passed to it by papermill."""
    cells = PLAN.figure_surfaces[wildcards.fig]
    return canonical(
        {
            "figure": wildcards.fig,
            "settings": resolve_source(config, wildcards.fig),
            "surface_files": get_figure_surfaces(wildcards),
            "aggregate_files": get_figure_aggregates(wildcards),
            "cells": [c.params() for c in cells],
            **drawn_with(config, wildcards.fig),
        }
    )


# ---- Cluster resources ------------------------------------------------------
# Memory [MB] and wall time [min] of every job, for schedulers that enforce
# them (profiles/slurm): the formulas are in roughcontact.study.resources, the
# measured numbers in config/cost_model.yaml; a retry (`attempt`) asks for
# more time.


def get_contact_runtime(wildcards, attempt):
    job = CONTACT_JOBS[wildcards.job]
    return resources.contact_runtime(job, PLAN.contact, PLAN.build, attempt)


def get_contact_mem_mb(wildcards):
    return resources.contact_mem_mb(CONTACT_JOBS[wildcards.job], PLAN.build)


def get_influence_runtime(wildcards, attempt):
    geometry = GEOMETRIES[wildcards.geometry]
    return resources.influence_runtime(geometry, PLAN.build, attempt)


#: Scheduling priority of the jobs that need no contact result (builds, surfaces):
#: above every other job's, so that all of them run first.
EARLY_PRIORITY = 100
#: Scheduling priority of the contact jobs and aggregates: after the builds and
#: surfaces, before the figures and reports (0), which would otherwise delay the chain
#: contact -> aggregate -> figure that ends the run.
CONTACT_PRIORITY = 50


def get_influence_priority(wildcards):
    """Builds before every other job, the longest (estimated) first: it starts at once
    and the jobs that wait on it find it done (Snakemake runs higher priorities first).
    """
    geometry = GEOMETRIES[wildcards.geometry]
    return EARLY_PRIORITY + 1 + resources.influence_seconds(geometry, PLAN.build)


def get_pair_mem_mb(wildcards):
    return resources.pair_mem_mb(PLAN.pairs[wildcards.pair])


def get_pair_runtime(wildcards, attempt):
    return resources.pair_runtime(PLAN.pairs[wildcards.pair], attempt)


def get_influence_mem_mb(wildcards):
    """Estimated peak memory of an influence build [MB], for the scheduler."""
    return resources.influence_mem_mb(GEOMETRIES[wildcards.geometry], PLAN.build)


def get_choice_runtime(wildcards, attempt):
    planned = PLAN.choices[wildcards.auto].candidates(PLAN.build.max_bytes)[0]
    return resources.choice_runtime(planned, PLAN.build, attempt)


def get_choice_mem_mb(wildcards):
    planned = PLAN.choices[wildcards.auto].candidates(PLAN.build.max_bytes)[0]
    return resources.choice_mem_mb(planned, PLAN.build)


def get_surfaces_runtime(wildcards, attempt):
    return resources.surfaces_runtime(SURFACE_CELLS[wildcards.cell], attempt)


def get_surfaces_mem_mb(wildcards):
    return resources.surfaces_mem_mb(SURFACE_CELLS[wildcards.cell])


def get_summary_runtime(wildcards, attempt):
    return resources.summary_runtime(attempt)


def get_audit_runtime(wildcards, attempt):
    # a choice still to be made (a dry run): every candidate's files, at most what it
    # reads (Snakemake takes a pending checkpoint's placeholder for no resource at all)
    files = settled(get_audit_inputs, wildcards)
    return resources.audit_runtime(len(files or audit_files(CONTACT_JOBS)), attempt)


def get_audit_mem_mb(wildcards):
    return resources.audit_mem_mb(GEOMETRIES.values(), PLAN.build)


def get_audit_verify_runtime(wildcards, attempt):
    sample = config["audit"]["verify_sample"]
    return resources.audit_verify_runtime(
        CONTACT_JOBS.values(), PLAN.contact, PLAN.build, sample, attempt
    )


def get_audit_verify_mem_mb(wildcards):
    return resources.audit_verify_mem_mb(
        CONTACT_JOBS.values(), GEOMETRIES.values(), PLAN.build
    )


def _report_settings(name):
    return report_section(config, name)  # the schema's defaults if not configured


def get_convergence_runtime(wildcards, attempt):
    section = ConvergenceSettings.from_section(
        _report_settings("influence_convergence")
    )
    presets = convergence_presets(config)
    return resources.convergence_runtime(PLAN.body, presets, section, attempt)


def get_convergence_mem_mb(wildcards):
    return resources.convergence_mem_mb(PLAN.body, convergence_presets(config))


def _on_demand_fits(kind):
    """Refuse an on-demand report (asked for: its job is being planned) that would not
    fit the memory a job may use."""
    try:
        resources.check_machine(config, plan=PLAN, kinds=(kind,))
    except ConfigProblems as err:
        raise WorkflowError(str(err)) from None


def get_speed_vs_error_spectrum_files(wildcards):
    """The file of the grid study's spectrum (a PSD table or a measurement), if any."""
    _on_demand_fits("speed_vs_error")
    spectrum = spectrum_from_entry(_report_settings("speed_vs_error").get("spectrum"))
    return [] if spectrum is None or spectrum.file is None else [spectrum.file]


def get_speed_vs_error_runtime(wildcards, attempt):
    section = SpeedReportSettings.from_section(_report_settings("speed_vs_error"))
    return resources.speed_vs_error_runtime(PLAN.body, section, attempt)


def get_speed_vs_error_mem_mb(wildcards):
    section = SpeedReportSettings.from_section(_report_settings("speed_vs_error"))
    return resources.speed_vs_error_mem_mb(PLAN.body, section, PLAN.build)


def _grid_convergence():
    return GridConvergenceSettings.from_section(_report_settings("grid_convergence"))


def get_grid_convergence_contacts(wildcards):
    """The contact file of every grid of the grid-convergence study."""
    _on_demand_fits("grid_convergence")
    return [
        f"results/grid_convergence/contact_{grid}.h5"
        for grid in _grid_convergence().grids
    ]


def get_grid_convergence_runtime(wildcards, attempt):
    return grid_convergence.sweep_runtime(
        _grid_convergence(), int(wildcards.gcgrid), attempt
    )


def get_grid_convergence_mem_mb(wildcards):
    return grid_convergence.grid_mem_mb(_grid_convergence(), int(wildcards.gcgrid))
