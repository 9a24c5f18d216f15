"""The contact studies of a configuration as typed records: the configuration's edge.

A contact figure or sweep describes its cells as a product of axes (scalars
or lists): ``moments`` (pairs of Sk, Ku), ``b_mm``, ``size_mm`` (square
nominal areas; the grid keeps the surfaces' spacing), ``nu``, ``meshes``,
``sigma_um``, ``E_MPa``; ``count``, ``pressure_MPa`` ([P_min, P_max]) and the
hardness settings apply to every cell. :meth:`~roughcontact.study.settings.Study.section`
applies the rules of inheritance once (the study's own values over the accuracy
preset's over the ``body``, ``surfaces`` and ``contact`` sections; the schema fills
every other default), and :func:`contact_cells` turns a study into
:class:`~roughcontact.study.contact_records.StudyCell` records in SI units: every
unit of a study's values is converted here, and every choice it writes as a
string is resolved here (its counter bodies by
:mod:`roughcontact.study.plan.counter_entries`).
"""

from __future__ import annotations

import dataclasses
import itertools

from roughcontact.study.codec import as_pair, from_unit
from roughcontact.study.contact_records import StudyCell
from roughcontact.study.plan.counter_entries import CounterfaceEntry, counterface_entries
from roughcontact.study.records import Geometry, MeasuredCell
from roughcontact.study.settings import Study, StudySection
from roughcontact.study.sources import MeasurementImport, spectrum_from_entry
from roughcontact.units import MM, MPA, UM

#: A study's (or ``contact.cap``'s) ``cap``: whether it has (elastic, capped) cells.
CAP_MODES = {False: (True, False), True: (False, True), "both": (True, True)}


def as_list(value) -> list:
    """A scalar axis as a list of one value; a list as itself."""
    return list(value) if isinstance(value, list | tuple) else [value]


def study_surfaces(study: Study, section: StudySection) -> list:
    """The surface cells of a study on a measured surface.

    The measurement (read from its file), then, with ``compare_synthetic``, its
    synthetic twin: a generated cell with the measured Sk, Ku and correlation
    lengths on its grid and plan size, with the study's surface count and
    spectrum and the ``surfaces`` section's ACF, periodicity and method.
    """
    measured = MeasuredCell.from_source(MeasurementImport.from_params(section.surface))
    if not section.compare_synthetic:
        return [measured]
    twin = study.surfaces.cell(spectrum_from_entry(section.spectrum), skew=measured.skew,
                               kurt=measured.kurt, corr_length=measured.corr_length,
                               count=section.count, size=measured.size, grid=measured.grid)
    return [measured, twin]


# ---------------------------------------------------------------------------
# The counter body (Eq 17-18): the ``counterface`` section and a study's ``counterface``


def counterface_groups(study: Study, name: str, cells: list[StudyCell],
                       ) -> list[tuple[CounterfaceEntry, list[StudyCell]]]:
    """Each counter body of the study ``name``
    (:func:`~roughcontact.study.plan.counter_entries.counterface_entries`) with the cells it
    makes of ``cells``: each cell against it, carrying the entry it comes from (for the
    messages that name its keys); a smooth rigid counter body leaves a cell as it is
    (no ``counterface``: today's jobs and numbers)."""
    return [(entry, [dataclasses.replace(cell, counterface=entry.counterface(study.surfaces,
                                                                             cell),
                                         counter_entry=entry)
                     for cell in cells])
            for entry in counterface_entries(study, name)]


def with_counterfaces(study: Study, name: str, cells: list[StudyCell]) -> list[StudyCell]:
    """Each cell once per counter body of the study ``name`` (:func:`counterface_groups`)."""
    return [cell for _, group in counterface_groups(study, name, cells) for cell in group]


def _generated_cells(study: Study, section: StudySection, body: Geometry,
                     common: dict) -> list[StudyCell]:
    """The product of a study's axes, in the order meshes, nu, size, b, moments, sigma, E,
    on the body's block (its thickness the study's ``thickness_mm`` where it names one)."""
    surfaces = study.surfaces
    spectrum = spectrum_from_entry(section.spectrum)
    size_mm = surfaces.size_mm
    spacing = [s / g for s, g in zip(size_mm, surfaces.grid, strict=True)]
    sizes = ([size_mm] if section.size_mm is None  # the surfaces'
             else [(s, s) for s in as_list(section.size_mm)])
    cells = []
    for mesh, nu, size, b, (skew, kurt), sigma, E in itertools.product(
            as_list(section.meshes), as_list(section.nu), sizes, as_list(section.b_mm),
            section.moments, as_list(section.sigma_um), as_list(section.E_MPa)):
        planform = {"size": from_unit(size),
                    "grid": tuple(max(4, round(s / h)) for s, h in zip(size, spacing,
                                                                       strict=True))}
        surface = surfaces.cell(spectrum, skew=skew, kurt=kurt,
                                corr_length=from_unit(as_pair(b)), count=section.count,
                                **planform)
        geometry = dataclasses.replace(
            body, nu=float(nu), mesh=str(mesh), **planform,
            thickness=patch_thickness(section.thickness_mm, planform["size"], body.thickness))
        cells.append(StudyCell(surface, geometry, sigma=float(sigma) * UM, E=float(E) * MPA,
                               **common))
    return cells


#: A measured study's ``thickness_mm`` that sizes the block to the patch.
PATCH_THICKNESS = "patch"


def patch_thickness(value, size: tuple[float, float], body_thickness: float) -> float:
    """The block thickness [m] under a measured patch of plan ``size`` [m]: a study's
    ``thickness_mm`` (a number [mm], or ``patch``: the patch's longer side, the paper's
    proportions), else the body's [m]."""
    if value is None:
        return body_thickness
    if value == PATCH_THICKNESS:
        return max(size)
    return float(value) * MM


def _measured_cells(study: Study, section: StudySection, body: Geometry,
                    common: dict) -> list[StudyCell]:
    """The cells of a study on a measured surface: meshes x nu x (measurement, twin) x
    sigma x E, on the measurement's grid and plan size and under a block of the study's
    ``thickness_mm`` (:func:`patch_thickness`); sigma by default the measured one (the
    results of the measured heights; another value rescales both surfaces)."""
    surfaces = study_surfaces(study, section)
    first = surfaces[0]
    sigmas = ([first.sigma] if section.sigma_um is None  # the measurement's
              else [float(s) * UM for s in as_list(section.sigma_um)])
    thickness = patch_thickness(section.thickness_mm, first.size, body.thickness)
    cells = []
    for mesh, nu, surface, sigma, E in itertools.product(
            as_list(section.meshes), as_list(section.nu), surfaces, sigmas,
            as_list(section.E_MPa)):
        geometry = dataclasses.replace(body, nu=float(nu), mesh=str(mesh), size=first.size,
                                       grid=first.grid, thickness=thickness)
        cells.append(StudyCell(surface, geometry, sigma=sigma, E=float(E) * MPA, **common))
    return cells


def with_hardness(cells: list[StudyCell], section: StudySection,
                  threshold: float) -> list[StudyCell]:
    """The cells of a study with its hardness values ``hardness_MPa`` and ``cap``.

    Without a hardness the cells are unchanged. With one, each elastic cell
    is checked against every value (``checked_hardness``, no extra solve;
    flagged beyond ``threshold``); ``cap: true`` replaces each cell by one
    capped cell per hardness (solved with 0 <= p <= H), ``cap: both`` adds
    those beside the elastic cells; either only for the meshes of
    ``cap_meshes`` (None: every mesh), the cells of the others staying elastic.
    """
    if section.hardness_MPa is None:
        return cells
    values = from_unit(as_list(section.hardness_MPa), MPA)
    elastic, capped = CAP_MODES[section.cap]
    meshes = section.cap_meshes
    to_cap = [cell for cell in cells if capped and (meshes is None
                                                    or cell.geometry.mesh in meshes)]
    stay = [cell for cell in cells if elastic or cell not in to_cap]
    checked = [dataclasses.replace(cell, checked_hardness=values, hardness_threshold=threshold)
               for cell in stay]
    return checked + [dataclasses.replace(cell, hardness=H) for cell in to_cap for H in values]


def contact_cells(study: Study, name: str) -> tuple[StudyCell, ...]:
    """The study cells of a contact figure or sweep (of its source, with ``from:``).

    Each cell carries its surface cell, its geometry, the scaling sigma and E,
    the pressure range, the accuracy preset and the hardness settings; a study
    that names a measured surface (``surface:``) has the cells of the
    measurement and its twin.
    """
    cells = with_counterfaces(study, name, study_base_cells(study, name))
    return tuple(with_hardness(cells, study.section(name), study.body.hardness_threshold))


def study_base_cells(study: Study, name: str) -> list[StudyCell]:
    """The cells of a contact figure or sweep on the body section's block, before its
    counter bodies and hardness settings (:func:`contact_cells`)."""
    section = study.section(name)
    common = {"pressure_range": from_unit(section.pressure_MPa, MPA),
              "accuracy": study.accuracy}
    build = _measured_cells if section.measured else _generated_cells
    return build(study, section, study.body.geometry, common)
