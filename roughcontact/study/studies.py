"""The contact studies of a configuration as typed records: the configuration's edge.

A contact figure or sweep describes its cells as a product of axes (scalars
or lists): ``moments`` (pairs of Sk, Ku), ``b_mm``, ``size_mm`` (square
nominal areas; the grid keeps the surfaces' spacing), ``nu``, ``meshes``,
``sigma_um``, ``E_MPa``; ``count``, ``pressure_MPa`` ([P_min, P_max]) and the
hardness settings apply to every cell. :func:`study_section` applies the
rules of inheritance once (the study's own values over the accuracy preset's
over the ``body``, ``surfaces`` and ``contact`` sections; the schema fills
every other default), and :func:`contact_cells` turns a study into
:class:`~roughcontact.study.contact_records.StudyCell` records in SI units: every
unit of the configuration is converted here, and every choice it writes as a
string is resolved here.
"""

from __future__ import annotations

import dataclasses
import itertools

from roughcontact.study.config import (
    ContactSettings,
    as_pair,
    from_unit,
    grid_pair,
    in_unit,
    in_units,
)
from roughcontact.study.contact_records import (
    RIGID,
    SMOOTH,
    Accuracy,
    Counterface,
    ElasticCounter,
    RoughCounter,
    StudyCell,
)
from roughcontact.study.presets import ACCURACY_PRESETS
from roughcontact.study.records import (
    GeneratedCell,
    Generator,
    Geometry,
    InfluenceModel,
    MeasuredCell,
    SurfaceCell,
)
from roughcontact.study.sources import MeasurementImport, spectrum_from_entry
from roughcontact.units import MM, MPA, UM

#: A study's (or ``contact.cap``'s) ``cap``: whether it has (elastic, capped) cells.
CAP_MODES = {False: (True, False), True: (False, True), "both": (True, True)}


def as_list(value) -> list:
    """A scalar axis as a list of one value; a list as itself."""
    return list(value) if isinstance(value, list | tuple) else [value]


def source_name(config: dict, name: str) -> str:
    """The figure or sweep whose cells ``name`` uses (itself unless ``from:``)."""
    section = {**config["figures"], **config["sweeps"]}
    seen = [name]
    source = section[name].get("from")
    while source is not None:
        if source in seen or source not in section:
            raise ValueError(f"{seen[0]}: 'from: {source}' must name another figure or sweep "
                             f"without a cycle (followed {' -> '.join(seen)})")
        seen.append(source)
        source = section[source].get("from")
    return seen[-1]


def resolve_source(config: dict, name: str) -> dict:
    """A figure's (or sweep's) cell description as configured, following ``from: other``."""
    return {**config["figures"], **config["sweeps"]}[source_name(config, name)]


def accuracy_preset(config: dict):
    """The accuracy preset the config names (``accuracy: paper|fast|converged``), or None."""
    name = config.get("accuracy")  # optional: no preset unless named
    return None if name is None else ACCURACY_PRESETS[name]


def study_accuracy(config: dict) -> Accuracy:
    """The preset's name and measured expected errors, recorded with every cell."""
    preset = accuracy_preset(config)
    if preset is None:
        return Accuracy()
    errors = tuple((k, v) for k, v in preset.items()
                   if k.endswith("_error") or k.startswith(("grid_change_", "sampling_")))
    return Accuracy(config["accuracy"], errors)


def contact_settings(config: dict) -> ContactSettings:
    """The solver settings of the contact jobs: the config's, or the accuracy preset's.

    ``contact.cap`` is not among them: it decides which cells are capped, and a
    capped job carries its own cap.
    """
    settings = ContactSettings.from_section(config["contact"])
    preset = accuracy_preset(config)
    if preset is None:
        return settings
    return dataclasses.replace(settings, method=str(preset["method"]), tol=float(preset["tol"]),
                               precision=str(preset["precision"]))


def body_geometry(config: dict) -> Geometry:
    """The geometry of the ``body`` section on the ``surfaces``' grid and plan size."""
    surfaces = config["surfaces"]
    return Geometry.from_params({**config["body"], "grid": surfaces["grid"],
                                 "size_mm": surfaces["size_mm"]})


def study_section(config: dict, name: str) -> dict:
    """The cell description of a contact figure or sweep (following ``from:``) with
    every axis present: its own values over the accuracy preset's (mesh, surface
    count) over the ``body``'s (meshes, nu, E_MPa, hardness_MPa), the ``surfaces``'
    (count, spectrum) and the ``contact`` section's (cap)."""
    body, surfaces = config["body"], config["surfaces"]
    preset = accuracy_preset(config)
    inherited = {
        "meshes": body["mesh"] if preset is None else preset["mesh"],
        "count": surfaces["count"] if preset is None else preset["surfaces"],
        "nu": body["nu"], "E_MPa": body["E_MPa"], "spectrum": surfaces["spectrum"],
        "hardness_MPa": body["hardness_MPa"], "cap": config["contact"]["cap"],
        "cap_meshes": config["contact"]["cap_meshes"],
    }
    return {**inherited, **resolve_source(config, name)}


def generated_cell(surfaces: dict, spectrum, *, skew, kurt, corr_length, count, size=None,
                   grid=None) -> GeneratedCell:
    """A generated surface cell: the ``surfaces`` section's ACF (or ``spectrum``),
    periodicity, method, grid and plan size (unless given, SI) and these statistics."""
    return GeneratedCell(
        skew=float(skew), kurt=float(kurt), corr_length=corr_length,
        grid=grid_pair(surfaces["grid"]) if grid is None else grid,
        size=from_unit(as_pair(surfaces["size_mm"])) if size is None else size,
        acf=str(surfaces["acf"]) if spectrum is None else spectrum.acf,
        periodic=bool(surfaces["periodic"]), method=Generator(surfaces["method"]),
        count=int(count), spectrum=spectrum)


def study_surfaces(config: dict, study: dict) -> list:
    """The surface cells of a study on a measured surface (:func:`study_section`).

    The measurement (read from its file), then, with ``compare_synthetic``, its
    synthetic twin: a generated cell with the measured Sk, Ku and correlation
    lengths on its grid and plan size, with the study's surface count and
    spectrum and the ``surfaces`` section's ACF, periodicity and method.
    """
    measured = MeasuredCell.from_source(MeasurementImport.from_entry(study["surface"]))
    if not study["compare_synthetic"]:
        return [measured]
    twin = generated_cell(config["surfaces"], spectrum_from_entry(study["spectrum"]),
                          skew=measured.skew, kurt=measured.kurt,
                          corr_length=measured.corr_length, count=study["count"],
                          size=measured.size, grid=measured.grid)
    return [measured, twin]


# ---------------------------------------------------------------------------
# The counter body (Eq 17-18): the ``counterface`` section and a study's ``counterface``


def counterface_entries(config: dict, study: dict) -> list[dict]:
    """A study's counter bodies as configured: its ``counterface`` (one entry, or a list:
    an axis), each entry's ``surface`` and ``body`` over the ``counterface`` section's;
    the section's own (by default a smooth rigid flat) when the study names none."""
    section = config["counterface"]
    entries = as_list(study.get("counterface") or {})
    return [{"surface": entry.get("surface", section["surface"]),
             "body": entry.get("body", section["body"])} for entry in entries]


def counter_surface(config: dict, entry, first: SurfaceCell) -> tuple[SurfaceCell | None, float]:
    """The counter surface cell of a ``counterface.surface`` entry on the first cell's
    grid and plan size, and its sigma [m]: ``smooth`` (None, 0); generated (the
    ``surfaces`` section's ACF, periodicity and method, seed stream ``counter``, one
    counter surface per first surface; Sk, Ku by default (0, 3), b by default the
    first cell's); or ``measured`` (its file; sigma by default the measured one)."""
    if entry == "smooth":
        return None, 0.0
    if "measured" in entry:
        cell = MeasuredCell.from_source(MeasurementImport.from_entry(entry["measured"]))
        sigma = entry.get("sigma_um")
        return cell, cell.sigma if sigma is None else float(sigma) * UM
    b = entry.get("b_mm")
    cell = generated_cell(config["surfaces"], None, skew=entry.get("skew", 0.0),
                          kurt=entry.get("kurt", 3.0),
                          corr_length=first.corr_length if b is None else from_unit(as_pair(b)),
                          count=first.count, size=first.size, grid=first.grid)
    return dataclasses.replace(cell, stream="counter"), float(entry["sigma_um"]) * UM


def counter_body(config: dict, entry, first: Geometry) -> tuple[Geometry | None, float | None]:
    """The counter body of a ``counterface.body`` entry on the first body's grid and plan
    size, and its E [Pa]: ``rigid`` (None, None); a ``halfspace`` (Love's, of its nu);
    or a ``block`` (its thickness, base, mesh and operator, each by default the
    ``body`` section's)."""
    if entry == "rigid":
        return None, None
    body = config["body"]
    params = {"nu": entry.get("nu", body["nu"]), "size_mm": in_units(first.size),
              "grid": list(first.grid), "base": entry.get("base", body["base"]),
              "mesh": entry.get("mesh", body["mesh"]),
              "thickness_mm": entry.get("thickness_mm", body["thickness_mm"])}
    if entry["kind"] == "halfspace":
        # Love's half-space: the thickness is only the reference length of the scaling
        params.update(operator=InfluenceModel.HALFSPACE.value, base="clamped", mesh="paper",
                      thickness_mm=in_unit(first.thickness, MM))
    else:
        params["operator"] = entry.get("operator", InfluenceModel.DENSE.value)
    return Geometry.from_params(params), float(entry["E_MPa"]) * MPA


def with_counterfaces(config: dict, study: dict, cells: list[StudyCell]) -> list[StudyCell]:
    """Each cell once per counter body of the study (:func:`counterface_entries`); a
    smooth rigid counter body leaves a cell as it is (no ``counterface``: today's
    jobs and numbers)."""
    rigid_share = float(config["counterface"]["rigid_share"])
    out = []
    for entry in counterface_entries(config, study):
        if entry["surface"] == "smooth" and entry["body"] == "rigid":
            out.extend(cells)
            continue
        for cell in cells:
            surface, sigma = counter_surface(config, entry["surface"], cell.surface)
            geometry, E = counter_body(config, entry["body"], cell.geometry)
            counter = Counterface(
                surface=SMOOTH if surface is None else RoughCounter(surface, sigma=sigma),
                body=RIGID if geometry is None else ElasticCounter(geometry, E=E),
                rigid_share=rigid_share)
            out.append(dataclasses.replace(cell, counterface=counter))
    return out


def _generated_cells(config: dict, study: dict, body: Geometry, common: dict) -> list[StudyCell]:
    """The product of a study's axes, in the order meshes, nu, size, b, moments, sigma, E."""
    surfaces = config["surfaces"]
    spectrum = spectrum_from_entry(study["spectrum"])
    spacing = [s / g for s, g in zip(as_pair(surfaces["size_mm"]), as_pair(surfaces["grid"]),
                                     strict=True)]
    sizes = ([as_pair(surfaces["size_mm"])] if study.get("size_mm") is None  # the surfaces'
             else [(s, s) for s in as_list(study["size_mm"])])
    cells = []
    for mesh, nu, size, b, (skew, kurt), sigma, E in itertools.product(
            as_list(study["meshes"]), as_list(study["nu"]), sizes, as_list(study["b_mm"]),
            study["moments"], as_list(study["sigma_um"]), as_list(study["E_MPa"])):
        planform = {"size": from_unit(size),
                    "grid": tuple(max(4, round(s / h)) for s, h in zip(size, spacing,
                                                                       strict=True))}
        surface = generated_cell(surfaces, spectrum, skew=skew, kurt=kurt,
                                 corr_length=from_unit(as_pair(b)), count=study["count"],
                                 **planform)
        geometry = dataclasses.replace(body, nu=float(nu), mesh=str(mesh), **planform)
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


def _measured_cells(config: dict, study: dict, body: Geometry, common: dict) -> list[StudyCell]:
    """The cells of a study on a measured surface: meshes x nu x (measurement, twin) x
    sigma x E, on the measurement's grid and plan size and under a block of the study's
    ``thickness_mm`` (:func:`patch_thickness`); sigma by default the measured one (the
    results of the measured heights; another value rescales both surfaces)."""
    surfaces = study_surfaces(config, study)
    first = surfaces[0]
    sigmas = ([first.sigma] if study.get("sigma_um") is None  # the measurement's
              else [float(s) * UM for s in as_list(study["sigma_um"])])
    thickness = patch_thickness(study.get("thickness_mm"), first.size, body.thickness)
    cells = []
    for mesh, nu, surface, sigma, E in itertools.product(
            as_list(study["meshes"]), as_list(study["nu"]), surfaces, sigmas,
            as_list(study["E_MPa"])):
        geometry = dataclasses.replace(body, nu=float(nu), mesh=str(mesh), size=first.size,
                                       grid=first.grid, thickness=thickness)
        cells.append(StudyCell(surface, geometry, sigma=sigma, E=float(E) * MPA, **common))
    return cells


def with_hardness(cells: list[StudyCell], study: dict, threshold: float) -> list[StudyCell]:
    """The cells of a study with its hardness values ``hardness_MPa`` and ``cap``.

    Without a hardness the cells are unchanged. With one, each elastic cell
    is checked against every value (``checked_hardness``, no extra solve;
    flagged beyond ``threshold``); ``cap: true`` replaces each cell by one
    capped cell per hardness (solved with 0 <= p <= H), ``cap: both`` adds
    those beside the elastic cells; either only for the meshes of
    ``cap_meshes`` (None: every mesh), the cells of the others staying elastic.
    """
    if study["hardness_MPa"] is None:
        return cells
    values = from_unit(as_list(study["hardness_MPa"]), MPA)
    elastic, capped = CAP_MODES[study["cap"]]
    meshes = study["cap_meshes"]
    to_cap = [cell for cell in cells if capped and (meshes is None
                                                    or cell.geometry.mesh in meshes)]
    stay = [cell for cell in cells if elastic or cell not in to_cap]
    checked = [dataclasses.replace(cell, checked_hardness=values, hardness_threshold=threshold)
               for cell in stay]
    return checked + [dataclasses.replace(cell, hardness=H) for cell in to_cap for H in values]


def contact_cells(config: dict, name: str) -> tuple[StudyCell, ...]:
    """The study cells of a contact figure or sweep (of its source, with ``from:``).

    Each cell carries its surface cell, its geometry, the scaling sigma and E,
    the pressure range, the accuracy preset and the hardness settings; a study
    that names a measured surface (``surface:``) has the cells of the
    measurement and its twin.
    """
    study = study_section(config, name)
    common = {"pressure_range": from_unit(study["pressure_MPa"], MPA),
              "accuracy": study_accuracy(config)}
    build = _generated_cells if study.get("surface") is None else _measured_cells
    cells = with_counterfaces(config, study, build(config, study, body_geometry(config), common))
    return tuple(with_hardness(cells, study, float(config["body"]["hardness_threshold"])))
