"""The plan of a study: every surface cell, geometry, study cell and contact job a
configuration asks for, computed once.

:func:`study_plan` turns a validated configuration into a :class:`StudyPlan`
of typed records (:mod:`roughcontact.study.records`), after the checks the
schema cannot make (:mod:`roughcontact.study.plan.checks`). The workflow makes it
once per run (``rules/common.smk``) and every rule reads its jobs, inputs,
parameters and resources from it. The record keys name every parameter, so
a changed parameter is a new file and the workflow reruns exactly what
depends on it.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

from roughcontact.study import layout
from roughcontact.study.conductance_settings import check_conductance
from roughcontact.study.config import BuildSettings, ContactSettings
from roughcontact.study.contact_records import ContactJob, StudyCell
from roughcontact.study.counter_records import NO_COMPLIANCE, PairGeometry
from roughcontact.study.cycle_records import CycleJob, LoadingSettings
from roughcontact.study.flow_settings import check_flow
from roughcontact.study.plan.block_checks import check_blocks
from roughcontact.study.plan.body_checks import check_plausible
from roughcontact.study.plan.checks import (
    ConfigProblems,
    check_feasible,
    check_memory,
    check_spectra,
    check_studies,
    check_windows,
)
from roughcontact.study.plan.counter_checks import check_counterfaces
from roughcontact.study.plan.figures import FIGURES, Kind
from roughcontact.study.plan.flow_checks import check_open_faces
from roughcontact.study.plan.loading_checks import check_loading, cycle_studies
from roughcontact.study.plan.studies import contact_cells
from roughcontact.study.records import (
    SEEDED_PER_SURFACE,
    Geometry,
    InfluenceModel,
    SurfaceCell,
)
from roughcontact.study.settings import Study
from roughcontact.study.thermal_records import ThermalBlock, with_thermal


@dataclasses.dataclass(frozen=True)
class StudyPlan:
    """Everything a validated configuration asks the workflow to make.

    ``figures`` in drawing order; ``studies`` the contact figures and the
    user's sweeps; ``aggregates`` the studies whose cells are aggregated (a
    study ``from:`` another reuses its aggregates); ``cells`` the study cells
    of every study (a study ``from:`` another has its cells); ``jobs``,
    ``surfaces`` and ``geometries`` by file key; ``figure_surfaces`` the
    surface cells each figure draws, in its order; ``study`` the settings it was
    made of; ``body`` the geometry of the ``body`` section (the reports');
    ``contact`` and ``build`` the settings of the contact jobs and the influence
    builds.

    A geometry of ``operator: auto`` is resolved when the workflow runs (its
    ``choices`` entry, by key: the half-space criterion measured on its
    planned model): ``geometries`` and ``jobs`` hold its candidates
    (:meth:`~roughcontact.study.records.Geometry.candidates`), each under the
    key and file of a geometry configured with that model, so a geometry that
    resolves to the model it had before keeps its files; ``alternatives``
    are the keys built only where a choice picks them (the half-space).

    ``surfaces_from``: surface cell key -> the key of the cell whose file its
    surfaces are taken from (the largest cell of the same statistics,
    :func:`surfaces_from`); a cell not listed generates or imports its own.

    ``pairs``: the pairs of influence models summed once for the jobs with a
    compliant counter body on a dense first body, by key; ``thermal``: the blocks whose
    thermal influence the jobs' conductance reads, by key.

    ``cycles``: the cycle jobs of the capped cells with the ``loading`` section on
    (:mod:`roughcontact.study.cycle_records`; each candidate of an ``operator: auto``
    geometry, as ``jobs``), by key; ``cycle_studies`` the aggregated studies with a cell
    swept along the loading path (their cycle tables).
    """

    figures: tuple[str, ...]
    studies: tuple[str, ...]
    aggregates: tuple[str, ...]
    cells: Mapping[str, tuple[StudyCell, ...]]
    jobs: Mapping[str, ContactJob]
    surfaces: Mapping[str, SurfaceCell]
    geometries: Mapping[str, Geometry]
    figure_surfaces: Mapping[str, tuple[SurfaceCell, ...]]
    study: Study
    body: Geometry
    contact: ContactSettings
    build: BuildSettings
    choices: Mapping[str, Geometry] = dataclasses.field(default_factory=dict)
    alternatives: frozenset[str] = frozenset()
    surfaces_from: Mapping[str, str] = dataclasses.field(default_factory=dict)
    pairs: Mapping[str, PairGeometry] = dataclasses.field(default_factory=dict)
    thermal: Mapping[str, ThermalBlock] = dataclasses.field(default_factory=dict)
    cycles: Mapping[str, CycleJob] = dataclasses.field(default_factory=dict)
    cycle_studies: tuple[str, ...] = ()

    def cycle_of(self, cell: StudyCell) -> CycleJob:
        """The cycle job of a study cell swept along the loading path (on its resolved
        geometry: the plan's record of its contact job, with the files it reads)."""
        return self.study.loading.job(cell, self.jobs[cell.job.key])

    def audit_files(self, jobs: Mapping[str, ContactJob]) -> list[str]:
        """The files the audit reads for contact ``jobs`` (by key): their contact files,
        every file each reads, and the choices of ``operator: auto``."""
        files = {layout.choice(key) for key in self.choices}
        for key, job in jobs.items():
            files.add(layout.contact(key))
            files.update(job.paths().values())
        return sorted(files)


#: What a figure of each study probe draws (a refusal's words).
NEEDS = {"flow": "its leak rate, flow factors and percolation thresholds",
         "conductance": "its thermal contact conductance and bulk share",
         "loading": "its loops of loading and unloading"}


def _raise(title: str, problems: list[str]) -> None:
    if problems:
        raise ConfigProblems(title, problems)


def _figures_and_studies(study: Study) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """The figures a study draws (in the registry's order) and its contact studies (its
    contact figures and sweeps); a figure that lists a study it does not have is
    refused."""
    figures = tuple(name for name in FIGURES if name in study.figures)
    studies = tuple(n for n in figures if FIGURES[n].kind is Kind.CONTACT) + tuple(study.sweeps)
    listing = [name for name in figures if FIGURES[name].kind is Kind.STUDIES]
    _raise("Figures that list no study of the config", [
        f"figures.{name}.studies: {listed!r} is no sweep or contact figure of the config "
        f"(sweeps: {', '.join(study.sweeps) or 'none'})"
        for name in listing for listed in study.entry(name)["studies"] if listed not in studies])
    on = {record.kind for record in study.probes} | ({"loading"} if study.loading.enabled
                                                      else set())
    _raise("Figures of a probe that is off", [
        f"figures.{name}.studies: {listed!r} is solved without the {kind} ({NEEDS[kind]}), "
        f"so its aggregates have nothing to draw; set {kind}.enabled: true (config section "
        f"{kind}) or remove the figure {name}"
        for name in listing for kind in FIGURES[name].needs if kind not in on
        for listed in study.entry(name)["studies"]])
    return figures, studies


def study_plan(study: Study) -> StudyPlan:
    """The :class:`StudyPlan` of a :class:`~roughcontact.study.settings.Study`.

    Raises :class:`~roughcontact.study.plan.checks.ConfigProblems` naming every
    invalid contact study or infeasible surface cell, before any job is
    planned to run.
    """
    figures, studies = _figures_and_studies(study)
    _raise("Spectra that cannot be used", check_spectra(study, studies))
    _raise("Invalid contact studies in the config", check_studies(study, studies))
    sources = {name: study.source_name(name) for name in studies}
    by_source = {source: contact_cells(study, source) for source in sources.values()}
    cells = {name: by_source[source] for name, source in sources.items()}
    if study.plausibility_check:
        _raise("Values that are almost surely a mistake (a unit slip, or noise in place of a "
               "height map; set plausibility_check: false if they are meant)",
               check_plausible(study, cells))
    build = study.body.build
    _raise("Blocks that do not fit their surfaces",
           check_blocks({study.path(name): c for name, c in by_source.items()}, build,
                        frozenset(study.path(name) for name in by_source
                                  if study.section(name).thickness_mm is not None)))
    jobs = contact_jobs(cell for name in studies for cell in cells[name])
    grids = {f"the contact grid of {job.geometry.key}": job.geometry for job in jobs.values()}
    _raise("Flow settings that cannot be used", check_flow(
        study.flow, study.plausibility_check, {k: g.grid for k, g in grids.items()},
        {k: tuple(s / n for s, n in zip(g.size, g.grid, strict=True))
         for k, g in grids.items()}))
    _raise("Studies whose every level the fluid would open", check_open_faces(study, studies))
    _raise("Conductance settings that cannot be used", check_conductance(
        study.conductance, study.plausibility_check, grids,
        {cell.counterface.name for name in studies for cell in cells[name]
         if cell.counterface.compliance != NO_COMPLIANCE}))
    figure_cells = {name: tuple(FIGURES[name].surfaces(study, name, cells)) for name in figures}
    generated = [name for name in figures if FIGURES[name].generated]
    surfaces = {cell.key: cell for name in generated for cell in figure_cells[name]}
    surfaces |= {job.surface.key: job.surface for job in jobs.values()}
    surfaces |= {key: cell for job in jobs.values() for key, cell in job.counter.cells().items()}
    _raise("Counter bodies that do not fit their surfaces", check_counterfaces(study, cells))
    # by the figure or sweep whose b_mm they have (Fig 5 draws Fig 4's)
    windows = {name: [c.surface for c in study_cells] for name, study_cells in by_source.items()}
    windows |= {name: figure_cells[name] for name in generated
                if "b_mm" in study.entry(name)}
    _raise("Surfaces shorter than two correlation lengths", check_windows(study, windows))
    _raise("Infeasible surface cells in the config", check_feasible(surfaces))
    asked = influence_geometries(study) | {job.geometry.key: job.geometry
                                           for job in jobs.values()}
    asked |= {key: geometry for job in jobs.values()
              for key, geometry in job.counter.geometries().items()}
    geometries = {c.key: c for g in asked.values() for c in g.candidates(build.max_bytes)}
    planned = {g.candidates(build.max_bytes)[0].key for g in asked.values()}
    _raise("Influence models that do not fit body.max_memory_gb",
           check_memory(asked, build))
    candidates = {key: with_thermal(job, study.conductance)
                  for key, job in candidate_jobs(jobs, build).items()}
    _raise("A loading path that cannot be used", check_loading(study, cells, {
        name: study.entry(name)["studies"] for name in figures
        if "loading" in FIGURES[name].needs}))
    aggregates = tuple(sorted(set(sources.values())))
    return StudyPlan(figures=figures, studies=studies,
                     aggregates=aggregates, cells=cells,
                     jobs=candidates, surfaces=surfaces,
                     geometries=geometries, figure_surfaces=figure_cells, study=study,
                     body=study.body.geometry, contact=study.contact, build=build,
                     choices={k: g for k, g in asked.items()
                              if g.operator is InfluenceModel.AUTO},
                     alternatives=frozenset(geometries) - planned,
                     surfaces_from=surfaces_from(surfaces),
                     pairs={key: pair for job in candidates.values()
                            for key, pair in job.pairs().items()},
                     thermal={job.thermal.key: job.thermal for job in candidates.values()
                              if isinstance(job.thermal, ThermalBlock)},
                     cycles=cycle_jobs(study.loading, (cell for name in studies
                                                       for cell in cells[name]),
                                       candidates, build),
                     cycle_studies=cycle_studies(study, {name: cells[name]
                                                         for name in aggregates}))


def surfaces_from(surfaces: Mapping[str, SurfaceCell]) -> dict[str, str]:
    """Surface cell key -> the key of the cell its surfaces are taken from.

    A generated cell whose generator makes each surface from its seed alone
    (:data:`~roughcontact.study.records.SEEDED_PER_SURFACE`) holds the first
    surfaces of any larger cell of the same statistics key (the seeds derive
    from that key and the surface's index), bit for bit: its job copies them
    from the largest such cell's file instead of calibrating and generating
    again. Measured cells, and cells with no larger twin, are not listed.
    """
    largest = {}
    for cell in surfaces.values():
        if cell.method in SEEDED_PER_SURFACE:
            best = largest.get(cell.statistics_key)
            if best is None or cell.count > best.count:
                largest[cell.statistics_key] = cell
    return {cell.key: largest[cell.statistics_key].key for cell in surfaces.values()
            if cell.method in SEEDED_PER_SURFACE
            and cell.count < largest[cell.statistics_key].count}


def contact_jobs(cells) -> dict[str, ContactJob]:
    """The contact jobs of study cells by file key, in the order of their first cell: a
    job is shared by every cell on the same surfaces and geometry that needs the same
    sweep end and cap."""
    jobs = {}
    for cell in cells:
        job = cell.job
        jobs.setdefault(job.key, job)
    return jobs


def candidate_jobs(jobs: Mapping[str, ContactJob], build: BuildSettings) -> dict[str, ContactJob]:
    """The contact jobs by file key with each ``operator: auto`` job replaced by one job per
    candidate of its geometry (the one its choice picks runs)."""
    out = {}
    for job in jobs.values():
        for geometry in job.geometry.candidates(build.max_bytes):
            candidate = dataclasses.replace(job, geometry=geometry)
            out.setdefault(candidate.key, candidate)
    return out


def cycle_jobs(loading: LoadingSettings, cells, jobs: Mapping[str, ContactJob],
               build: BuildSettings) -> dict[str, CycleJob]:
    """The cycle jobs of the study cells ``cells`` that ``loading`` sweeps, by file key:
    one per candidate of each cell's geometry (as :func:`candidate_jobs`), on the
    plan's record of its contact job ``jobs`` (with the files it reads)."""
    out = {}
    for cell in cells:
        if loading.applies(cell):
            for geometry in cell.geometry.candidates(build.max_bytes):
                placed = dataclasses.replace(cell, geometry=geometry)
                cycle = loading.job(placed, jobs[placed.job.key])
                out.setdefault(cycle.key, cycle)
    return out


def influence_geometries(study: Study) -> dict[str, Geometry]:
    """The influence geometries the study asks for besides its contact jobs'.

    The mesh-convergence report (when configured) compares its presets on the
    body of the config and reuses their builds; the contact jobs add the
    geometries they solve on (:func:`study_plan`). Nothing else is built: a
    body that no study and no report uses costs nothing.
    """
    body = study.body.geometry
    variants = (dataclasses.replace(body, mesh=mesh)
                for mesh in study.reports.convergence_presets)
    return {geometry.key: geometry for geometry in variants}


# ---------------------------------------------------------------------------
# What each figure draws (the figure registry: roughcontact.study.plan.figures)


def figure_aggregates(plan: StudyPlan, name: str) -> tuple[str, ...]:
    """The studies whose aggregate tables a figure draws, in its order: a contact figure's
    own (its ``from:`` followed), the listed ones of a figure drawn from the studies it
    lists (each followed likewise), none for the others."""
    study, kind = plan.study, FIGURES[name].kind
    if kind is Kind.STUDIES:
        return tuple(study.source_name(listed) for listed in study.entry(name)["studies"])
    return (study.source_name(name),) if kind is Kind.CONTACT else ()


def figure_files(plan: StudyPlan, name: str) -> list[str]:
    """The files a figure reads, its notebook's ``aggregate_files``: those of each study
    of :func:`figure_aggregates` its registry entry names (``Figure.files``: the
    aggregates, or the cycles' tables), in the studies' order."""
    return [path for study in figure_aggregates(plan, name) for path in FIGURES[name].files(study)]


def drawn_with(plan: StudyPlan, name: str) -> dict:
    """The settings of the other figures a figure draws with, by figure name
    (``{"fig04": ...}`` for Fig 5; none for the others): notebook parameters."""
    return {other: plan.study.entry(other) for other in FIGURES[name].drawn_with}


def figure_parameters(plan: StudyPlan, name: str) -> dict:
    """Everything a figure's notebook needs from the plan, but its files: its settings as
    configured (following ``from:``), the params of the surface cells it draws and the
    settings of the figures it draws with."""
    return {"settings": plan.study.source(name),
            "cells": [c.params() for c in plan.figure_surfaces[name]], **drawn_with(plan, name)}


def figure_caption(plan: StudyPlan, name: str) -> str:
    """The report's caption of figure ``name``, written from the study's own settings
    (one paragraph of plain text)."""
    return FIGURES[name].caption(plan, name)

