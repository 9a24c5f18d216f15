# Shared workflow logic: the typed study and its plan, the input functions (get_*) and
# wildcard constraints. The configuration stops here: the rules read the study (STUDY)
# and its plan (PLAN), the records of every job; the paths are roughcontact.study.layout's.
import dataclasses
import hashlib
import json
import os
import re

from snakemake.exceptions import IncompleteCheckpointException, WorkflowError

from roughcontact.study import layout
from roughcontact.study.plan import machine, resources
from roughcontact.study.plan.cells import (
    figure_caption,
    figure_files,
    figure_parameters,
    study_plan,
)
from roughcontact.study.plan.checks import ConfigProblems
from roughcontact.study.probes import study_probe_params
from roughcontact.study.provenance import canonical_json
from roughcontact.study.records import InfluenceModel
from roughcontact.study.settings import Study, thawed
from roughcontact.study.sources import spectrum_from_entry
from roughcontact.study.jobs.storage import read_choice

STUDY = Study.from_config(config)  # the validated configuration, typed (Snakefile)
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = str(STUDY.blas_threads)

NOTEBOOKS = os.path.join(workflow.basedir, "notebooks")
# every job, cell and file key of the study, as typed records: made once per run
# and every job's memory, reports included, within what a job may use (job_memory_gb)
try:
    PLAN = study_plan(STUDY)
    machine.check_machine(PLAN)
except ConfigProblems as err:
    raise WorkflowError(str(err)) from None
machine.warn_long_jobs(PLAN)  # a job estimated beyond a day, named once


wildcard_constraints:
    auto="|".join(re.escape(k) for k in PLAN.choices) or "__none__",
    cell="|".join(re.escape(k) for k in PLAN.surfaces) or "__none__",
    fig="|".join(PLAN.figures) or "__none__",
    geometry="|".join(re.escape(k) for k in PLAN.geometries) or "__none__",
    pair="|".join(re.escape(k) for k in PLAN.pairs) or "__none__",
    thermal="|".join(re.escape(k) for k in PLAN.thermal) or "__none__",
    job="|".join(re.escape(k) for k in PLAN.jobs) or "__none__",
    cycle="|".join(re.escape(k) for k in PLAN.cycles) or "__none__",
    study="|".join(PLAN.aggregates) or "__none__",


def canonical(obj):
    """``obj`` with every dict's keys sorted: rule params that do not depend on
    the order of keys in the config file (Snakemake reruns a job when the text
    of its params changes)."""
    return json.loads(canonical_json(obj))


def get_final_outputs():
    figures = [
        layout.figure(fig, ext)
        for fig in PLAN.figures
        for ext in ("png", "pdf", "ipynb")
    ] + [layout.figure(fig, "csv") for fig in PLAN.figures if fig.startswith("table_")]
    # a half-space that only a choice of operator: auto may pick is built if picked
    influence = [
        layout.influence(key) for key in PLAN.geometries if key not in PLAN.alternatives
    ] + [layout.choice(key) for key in PLAN.choices]
    aggregates = [path for name in PLAN.aggregates for path in layout.aggregates(name)]
    aggregates += [
        path for name in PLAN.cycle_studies for path in layout.cycle_aggregates(name)
    ]
    audit = (
        ["results/audit/audit.csv", "results/audit/audit.md"] if PLAN.studies else []
    )
    if PLAN.studies and STUDY.audit.strict:
        audit.append("results/audit/strict.ok")
    if PLAN.studies and STUDY.audit.verify:
        audit.append("results/audit/verify.csv")
    reports = []
    if "influence_convergence" in STUDY.reports.configured:
        reports += [
            "results/reports/influence_convergence.csv",
            "results/reports/influence_convergence.png",
        ]
    return figures + influence + aggregates + audit + reports + ["results/config.yaml"]


# ---- The plan's record of each job: its params, and what it asks a scheduler for ----
# Memory [MB] and wall time [min] of every job, for schedulers that enforce them
# (profiles/slurm): roughcontact.study.plan.resources.JOB_COSTS by the kind of job, from the
# plan's record its wildcards name; a retry (`attempt`) asks for more time.

RECORDS = {
    "contact": lambda wildcards: PLAN.jobs[wildcards.job],
    "cycle": lambda wildcards: PLAN.cycles[wildcards.cycle],
    "influence": lambda wildcards: PLAN.geometries[wildcards.geometry],
    "choice": lambda wildcards: PLAN.choices[wildcards.auto],
    "pair": lambda wildcards: PLAN.pairs[wildcards.pair],
    "thermal": lambda wildcards: PLAN.thermal[wildcards.thermal],
    "surfaces": lambda wildcards: PLAN.surfaces[wildcards.cell],
}


def get_params(kind):
    """The params of a job of ``kind``: its record's plain form (``params()``)."""
    return lambda wildcards: RECORDS[kind](wildcards).params()


def get_mem_mb(kind):
    return lambda wildcards: resources.job_memory_mb(PLAN, kind, wildcards)


def get_runtime(kind):
    return lambda wildcards, attempt: resources.job_runtime(
        PLAN, kind, wildcards, attempt
    )


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
    geometry = PLAN.geometries[wildcards.geometry]
    return EARLY_PRIORITY + 1 + resources.influence_seconds(geometry, PLAN.build)


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
    for name in PLAN.studies:  # the plan's order
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


def planned_choice(wildcards):
    """The planned model of an operator: auto geometry (its first candidate)."""
    return PLAN.choices[wildcards.auto].candidates(PLAN.build.max_bytes)[0]


# ---- Inputs and params of the jobs ----------------------------------------------


def get_contact_inputs(wildcards):
    # the files a contact job reads: one place decides them (ContactJob.files)
    return PLAN.jobs[wildcards.job].paths()


def get_cycle_inputs(wildcards):
    # a cycle job reads its contact job's files (CycleJob.files)
    return PLAN.cycles[wildcards.cycle].paths()


def get_surface_inputs(wildcards):
    """``files``: the measured file of a measured surface cell, the spectrum's file (a
    PSD table or a measurement) of a generated cell with one; ``source``: the file of
    the larger cell whose first surfaces the cell takes (PLAN.surfaces_from), if any."""
    inputs = {"files": list(PLAN.surfaces[wildcards.cell].input_files)}
    source = PLAN.surfaces_from.get(wildcards.cell)
    if source is not None:
        inputs["source"] = layout.surfaces(source)
    return inputs


def get_surface_source(wildcards):
    """The params of the cell whose file the cell's surfaces are taken from (None: it
    makes its own)."""
    source = PLAN.surfaces_from.get(wildcards.cell)
    return None if source is None else PLAN.surfaces[source].params()


def get_aggregate_cells(wildcards):
    return settled(lambda: [cell.params() for cell in resolved_cells(wildcards.study)])


def get_aggregate_inputs(wildcards):
    cells = resolved_cells(wildcards.study)
    return sorted({layout.contact(cell.contact_key) for cell in cells})


def cycle_cells(study):
    """The cells of ``study`` swept along the loading path, on their resolved geometries."""
    return [cell for cell in resolved_cells(study) if STUDY.loading.applies(cell)]


def get_cycle_cells(wildcards):
    return settled(lambda: [cell.params() for cell in cycle_cells(wildcards.study)])


def get_cycle_aggregate_inputs(wildcards):
    return sorted({PLAN.cycle_of(cell).output for cell in cycle_cells(wildcards.study)})


def get_audit_studies(wildcards):
    # each cell once: a study "from:" another (fig12 from fig07, the measured figure
    # from its sweep) has the same cells
    return settled(
        lambda: {
            name: [c.params() for c in resolved_cells(name)] for name in PLAN.aggregates
        }
    )


def get_audit_inputs(wildcards):
    return PLAN.audit_files(resolved_jobs())


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


def get_audit_jobs(wildcards):
    return settled(lambda: {key: job.params() for key, job in resolved_jobs().items()})


def get_figure_surfaces(wildcards):
    return [layout.surfaces(c.key) for c in PLAN.figure_surfaces[wildcards.fig]]


def get_figure_aggregates(wildcards):
    """The files of the studies a figure draws, in their order: each study's aggregates
    (four), or its cycles' tables (three) for a figure of the loops (its registry entry's
    ``files``)."""
    return figure_files(PLAN, wildcards.fig)


def get_figure_caption(wildcards):
    """The report's caption of a figure, written from the study's own settings."""
    return figure_caption(PLAN, wildcards.fig)


def get_figure_parameters(wildcards):
    """Everything a figure notebook needs, passed to it by papermill."""
    parameters = figure_parameters(PLAN, wildcards.fig)
    return canonical(
        {
            "figure": wildcards.fig,
            "settings": parameters.pop("settings"),
            "surface_files": get_figure_surfaces(wildcards),
            "aggregate_files": get_figure_aggregates(wildcards),
            **parameters,
        }
    )


def get_convergence_stored(wildcards):
    """Preset -> influence file of the body's geometry with that mesh (of operator: auto,
    its planned model: the report compares finite-element models)."""
    max_bytes = PLAN.build.max_bytes
    return {
        mesh: layout.influence(
            dataclasses.replace(PLAN.body, mesh=mesh).candidates(max_bytes)[0].key
        )
        for mesh in STUDY.reports.convergence_presets
    }


def _on_demand_fits(kind):
    """Refuse an on-demand report (asked for: its job is being planned) that would not
    fit the memory a job may use."""
    try:
        machine.check_machine(PLAN, kinds=(kind,))
    except ConfigProblems as err:
        raise WorkflowError(str(err)) from None


def get_speed_vs_error_spectrum_files(wildcards):
    """The file of the grid study's spectrum (a PSD table or a measurement), if any."""
    _on_demand_fits("speed_vs_error")
    section = thawed(STUDY.reports.sections["speed_vs_error"])
    spectrum = spectrum_from_entry(section.get("spectrum"))
    return [] if spectrum is None or spectrum.file is None else [spectrum.file]


def get_grid_convergence_contacts(wildcards):
    """The contact file of every grid of the grid-convergence study."""
    _on_demand_fits("grid_convergence")
    return [layout.grid_contact(grid) for grid in STUDY.reports.grid_convergence.grids]
