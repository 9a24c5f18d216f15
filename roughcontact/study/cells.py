"""The plan of a study: every surface cell, geometry, study cell and contact job a
configuration asks for, computed once.

:func:`study_plan` turns a validated configuration into a :class:`StudyPlan`
of typed records (:mod:`roughcontact.study.records`), after the checks the
schema cannot make (:mod:`roughcontact.study.checks`). The workflow makes it
once per run (``rules/common.smk``) and every rule reads its jobs, inputs,
parameters and resources from it. The record keys name every parameter, so
a changed parameter is a new file and the workflow reruns exactly what
depends on it.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

from roughcontact.study.block_checks import check_blocks
from roughcontact.study.body_checks import check_plausible
from roughcontact.study.checks import (
    ConfigProblems,
    check_feasible,
    check_memory,
    check_spectra,
    check_studies,
    check_windows,
)
from roughcontact.study.config import BuildSettings, ContactSettings, as_pair, from_unit
from roughcontact.study.contact_records import ContactJob, StudyCell
from roughcontact.study.counter_checks import check_counterfaces
from roughcontact.study.counter_records import PairGeometry
from roughcontact.study.flow_settings import check_flow
from roughcontact.study.records import (
    SEEDED_PER_SURFACE,
    Geometry,
    InfluenceModel,
    SurfaceCell,
)
from roughcontact.study.sources import spectrum_from_entry
from roughcontact.study.studies import (
    body_geometry,
    contact_cells,
    contact_settings,
    generated_cell,
    source_name,
)

#: Figures of generated surfaces only (their cells are :func:`figure_surfaces`').
SURFACE_FIGURES = ("fig03", "fig04", "fig05")
#: Figures that need no contact solve (Fig 1 and 2 need no surfaces either).
SURFACE_ONLY_FIGURES = ("fig01", "fig02", "fig03", "fig04", "fig05")
#: Figures drawn from contact results, and the source of their cells ("measured": a
#: measured surface against its synthetic twin, usually ``from:`` a sweep;
#: "fig11_resolved": Fig 11 on a grid that resolves the ACF, config/fig11_resolved.yaml;
#: "gaps": the mean gap and the spots of a study's cells, usually ``from:`` fig07).
CONTACT_FIGURES = ("fig07", "fig09", "fig10", "fig11", "fig12", "fig13", "fig14", "table_Eu",
                   "hardness", "measured", "fig11_resolved", "gaps")
#: Figures drawn from the aggregates of the studies they list (``studies:``), with no cells
#: of their own ("two_bodies": each counter body of those studies beside the rigid flat;
#: "leakage": the flow through the contact gap of those studies, needs the flow on).
STUDIES_FIGURES = ("two_bodies", "leakage")
#: The :data:`STUDIES_FIGURES` drawn from the flow columns of their studies' aggregates.
FLOW_FIGURES = ("leakage",)


@dataclasses.dataclass(frozen=True)
class StudyPlan:
    """Everything a validated configuration asks the workflow to make.

    ``figures`` in drawing order; ``studies`` the contact figures and the
    user's sweeps; ``aggregates`` the studies whose cells are aggregated (a
    study ``from:`` another reuses its aggregates); ``cells`` the study cells
    of every study (a study ``from:`` another has its cells); ``jobs``,
    ``surfaces`` and ``geometries`` by file key; ``figure_surfaces`` the
    surface cells each figure draws, in its order; ``body`` the geometry of
    the ``body`` section (the reports'); ``contact`` and ``build`` the settings
    of the contact jobs and the influence builds.

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
    compliant counter body on a dense first body, by key.
    """

    figures: tuple[str, ...]
    studies: tuple[str, ...]
    aggregates: tuple[str, ...]
    cells: Mapping[str, tuple[StudyCell, ...]]
    jobs: Mapping[str, ContactJob]
    surfaces: Mapping[str, SurfaceCell]
    geometries: Mapping[str, Geometry]
    figure_surfaces: Mapping[str, tuple[SurfaceCell, ...]]
    body: Geometry
    contact: ContactSettings
    build: BuildSettings
    choices: Mapping[str, Geometry] = dataclasses.field(default_factory=dict)
    alternatives: frozenset[str] = frozenset()
    surfaces_from: Mapping[str, str] = dataclasses.field(default_factory=dict)
    pairs: Mapping[str, PairGeometry] = dataclasses.field(default_factory=dict)


def _raise(title: str, problems: list[str]) -> None:
    if problems:
        raise ConfigProblems(title, problems)


def _figures_and_studies(config: dict) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """The figures a config draws and its contact studies (its contact figures and
    sweeps); a figure that lists a study the config does not have is refused."""
    figures = tuple(n for n in (*SURFACE_ONLY_FIGURES, *CONTACT_FIGURES, *STUDIES_FIGURES)
                    if n in config["figures"])
    studies = tuple(n for n in figures if n in CONTACT_FIGURES) + tuple(config["sweeps"])
    _raise("Figures that list no study of the config", [
        f"figures.{name}.studies: {study!r} is no sweep or contact figure of the config "
        f"(sweeps: {', '.join(config['sweeps']) or 'none'})"
        for name in figures if name in STUDIES_FIGURES
        for study in config["figures"][name]["studies"] if study not in studies])
    _raise("Figures of the flow through the gap with the flow off", [
        f"figures.{name}.studies: {study!r} is solved without the flow, so its aggregates "
        f"have no leak rate, flow factor or percolation threshold to draw; set "
        f"flow.enabled: true (config section flow) or remove the figure {name}"
        for name in figures if name in FLOW_FIGURES and not config["flow"]["enabled"]
        for study in config["figures"][name]["studies"]])
    return figures, studies


def study_plan(config: dict) -> StudyPlan:
    """The :class:`StudyPlan` of a validated ``config``.

    Raises :class:`~roughcontact.study.checks.ConfigProblems` naming every
    invalid contact study or infeasible surface cell, before any job is
    planned to run.
    """
    figures, studies = _figures_and_studies(config)
    _raise("Spectra that cannot be used", check_spectra(config, studies))
    _raise("Invalid contact studies in the config", check_studies(config, studies))
    sources = {name: source_name(config, name) for name in studies}
    by_source = {source: contact_cells(config, source) for source in sources.values()}
    cells = {name: by_source[source] for name, source in sources.items()}
    if config["plausibility_check"]:
        _raise("Values that are almost surely a mistake (a unit slip, or noise in place of a "
               "height map; set plausibility_check: false if they are meant)",
               check_plausible(config, cells))
    build = BuildSettings.from_section(config["body"])
    section = {name: "sweeps" if name in config["sweeps"] else "figures" for name in by_source}
    _raise("Blocks that do not fit their surfaces",
           check_blocks({f"{section[name]}.{name}": c for name, c in by_source.items()}, build))
    jobs = contact_jobs(cell for name in studies for cell in cells[name])
    _raise("Flow settings that cannot be used", check_flow(config, {
        f"the contact grid of {job.geometry.key}": job.geometry.grid for job in jobs.values()}))
    figure_cells = {name: figure_surfaces(config, name, cells) for name in figures}
    surfaces = {cell.key: cell for name in SURFACE_FIGURES if name in figure_cells
                for cell in figure_cells[name]}
    surfaces |= {job.surface.key: job.surface for job in jobs.values()}
    surfaces |= {key: cell for job in jobs.values() for key, cell in job.counter.cells().items()}
    _raise("Counter bodies that do not fit their surfaces",
           check_counterfaces(config, cells, build))
    # by the figure or sweep whose b_mm they have (Fig 5 draws Fig 4's)
    windows = {name: [c.surface for c in study_cells] for name, study_cells in by_source.items()}
    windows |= {name: figure_cells[name] for name in SURFACE_FIGURES
                if name in figure_cells and "b_mm" in config["figures"][name]}
    _raise("Surfaces shorter than two correlation lengths", check_windows(config, windows))
    _raise("Infeasible surface cells in the config", check_feasible(surfaces))
    asked = influence_geometries(config) | {job.geometry.key: job.geometry
                                            for job in jobs.values()}
    asked |= {key: geometry for job in jobs.values()
              for key, geometry in job.counter.geometries().items()}
    geometries = {c.key: c for g in asked.values() for c in g.candidates(build.max_bytes)}
    planned = {g.candidates(build.max_bytes)[0].key for g in asked.values()}
    _raise("Influence models that do not fit body.max_memory_gb",
           check_memory(asked, build))
    candidates = candidate_jobs(jobs, build)
    return StudyPlan(figures=figures, studies=studies,
                     aggregates=tuple(sorted(set(sources.values()))), cells=cells,
                     jobs=candidates, surfaces=surfaces,
                     geometries=geometries, figure_surfaces=figure_cells,
                     body=body_geometry(config), contact=contact_settings(config), build=build,
                     choices={k: g for k, g in asked.items()
                              if g.operator is InfluenceModel.AUTO},
                     alternatives=frozenset(geometries) - planned,
                     surfaces_from=surfaces_from(surfaces),
                     pairs={key: pair for job in candidates.values()
                            for key, pair in job.pairs().items()})


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


def influence_geometries(config: dict) -> dict[str, Geometry]:
    """The influence geometries the configuration asks for besides its contact jobs'.

    The mesh-convergence report (when configured) compares its presets on the
    body of the config and reuses their builds; the contact jobs add the
    geometries they solve on (:func:`study_plan`). Nothing else is built: a
    body that no study and no report uses costs nothing.
    """
    body = body_geometry(config)
    variants = (dataclasses.replace(body, mesh=mesh) for mesh in convergence_presets(config))
    return {geometry.key: geometry for geometry in variants}


def convergence_presets(config: dict) -> list[str]:
    """Mesh presets of the influence-convergence report ([] when it is not configured)."""
    report = config["reports"].get("influence_convergence")  # optional: a report to run
    return [] if report is None else list(report["presets"])


# ---------------------------------------------------------------------------
# The surface cells each figure draws


def _fig03_surfaces(config: dict, name: str, cells) -> list:
    """Fig 3: one Gaussian cell per correlation length."""
    figure, surfaces = config["figures"][name], config["surfaces"]
    spectrum = spectrum_from_entry(surfaces["spectrum"])
    return [generated_cell(surfaces, spectrum, skew=0.0, kurt=3.0,
                           corr_length=from_unit(as_pair(b)), count=figure["count"])
            for b in figure["b_mm"]]


def _fig04_surfaces(config: dict, name: str, cells) -> list:
    """Figs 4 and 5: one cell per (Sk, Ku) pair of Fig 4."""
    figure, surfaces = config["figures"]["fig04"], config["surfaces"]
    spectrum = spectrum_from_entry(surfaces["spectrum"])
    return [generated_cell(surfaces, spectrum, skew=skew, kurt=kurt,
                           corr_length=from_unit(as_pair(figure["b_mm"])),
                           count=surfaces["count"])
            for skew, kurt in figure["moments"]]


def _study_surfaces(config: dict, name: str, cells) -> list:
    """Fig 10: the surfaces of each of its study cells (the cumulative height
    distributions of the Fig 9 surfaces)."""
    return [cell.surface for cell in cells[name]]


def _unique_study_surfaces(config: dict, name: str, cells) -> list:
    """The measured figure: the measured surface and its twin, once each."""
    return list({cell.surface.key: cell.surface for cell in cells[name]}.values())


#: The surface cells of the figures that draw surfaces.
_FIGURE_SURFACES = {"fig03": _fig03_surfaces, "fig04": _fig04_surfaces,
                    "fig05": _fig04_surfaces, "fig10": _study_surfaces,
                    "measured": _unique_study_surfaces}


#: Figures drawn with other figures' settings besides their own: Fig 5 draws the heights
#: of Fig 4's surfaces in Fig 4's sigma (the schema requires fig04 beside fig05).
_DRAWN_WITH = {"fig05": ("fig04",)}


def drawn_with(config: dict, name: str) -> dict:
    """The validated settings of the other figures a figure draws with, by figure name
    (``{"fig04": ...}`` for Fig 5; none for the others): notebook parameters."""
    return {other: config["figures"][other] for other in _DRAWN_WITH.get(name, ())}


def figure_aggregates(config: dict, name: str) -> tuple[str, ...]:
    """The studies whose aggregate tables a figure draws, in its order: a contact figure's
    own (its ``from:`` followed), the listed ones of a :data:`STUDIES_FIGURES` figure
    (each followed likewise), none for the others."""
    if name in STUDIES_FIGURES:
        return tuple(source_name(config, study) for study in config["figures"][name]["studies"])
    return (source_name(config, name),) if name in CONTACT_FIGURES else ()


def figure_surfaces(config: dict, name: str, cells) -> tuple[SurfaceCell, ...]:
    """The surface cells a figure draws, in its order (none for the others); ``cells``
    the study cells by study name."""
    surfaces = _FIGURE_SURFACES.get(name)
    return () if surfaces is None else tuple(surfaces(config, name, cells))
