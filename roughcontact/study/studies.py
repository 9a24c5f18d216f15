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
from roughcontact.study.contact_records import Accuracy, StudyCell
from roughcontact.study.counter_records import (
    RIGID,
    SMOOTH,
    Counterface,
    ElasticCounter,
    RoughCounter,
)
from roughcontact.study.flow_settings import flow_settings
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
    capped job carries its own cap. The flow probe is the ``flow`` section's
    (:func:`roughcontact.study.flow_settings.flow_settings`).
    """
    settings = dataclasses.replace(ContactSettings.from_section(config["contact"]),
                                   flow=flow_settings(config).probe)
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


def study_path(config: dict, name: str) -> str:
    """The configuration path of a figure or sweep: ``figures.<name>`` or ``sweeps.<name>``."""
    return f"{'sweeps' if name in config['sweeps'] else 'figures'}.{name}"


@dataclasses.dataclass(frozen=True)
class CounterfaceEntry:
    """One counter body of a study as configured, every default resolved
    (:func:`counter_defaults`): its ``surface`` and ``body`` entries and the
    configuration keys they are written under (``counterface.surface``, or a study's
    ``sweeps.pad.counterface[1].body``), for the messages that name them; ``inherited``
    the keys of the body that are the ``body`` section's (:data:`BODY_INHERITED`)."""

    surface: str | dict
    body: str | dict
    surface_key: str
    body_key: str
    inherited: tuple[str, ...] = ()

    @property
    def is_null(self) -> bool:
        """A smooth rigid counter body: the paper's flat, no counter body at all."""
        return self.surface == "smooth" and self.body == "rigid"


#: The keys of a counter body that default to the ``body`` section's, by its kind.
BODY_INHERITED = {"block": ("nu", "thickness_mm", "base", "mesh"), "halfspace": ("nu",)}


def audit_verify_seed(config: dict) -> int:
    """The seed of the sample the audit re-solves: ``audit.verify_seed``, by default the
    ``study_seed`` (another key's value, which the schema cannot write as a default)."""
    seed = config["audit"].get("verify_seed")  # optional: the study_seed
    return int(config["study_seed"] if seed is None else seed)


def counter_defaults(config: dict, surface, body) -> tuple:
    """A counter ``surface`` and ``body`` entry with the defaults that are another
    section's value, which the schema cannot write (it fills the static ones: skew,
    kurt, a block's operator): the one place that resolves them.

    A block's nu, thickness_mm, base and mesh (a half-space's nu) are the ``body``
    section's; a generated counter surface's ``b_mm`` None stands for the first
    surface's (each cell's), a measured one's ``sigma_um`` None for its measured sigma.
    """
    if body != "rigid":
        body = {**{key: config["body"][key] for key in BODY_INHERITED[body["kind"]]}, **body}
    if surface != "smooth":
        surface = {("sigma_um" if "measured" in surface else "b_mm"): None, **surface}
    return surface, body


def counterface_entries(config: dict, name: str) -> list[CounterfaceEntry]:
    """The counter bodies of the figure or sweep ``name`` (of its source, with ``from:``):
    its ``counterface`` (one entry, or a list: an axis), each entry's ``surface`` and
    ``body`` over the ``counterface`` section's; the section's own (by default a smooth
    rigid flat) when the study names none."""
    section = config["counterface"]
    own = resolve_source(config, name).get("counterface")  # optional: the section's
    where = f"{study_path(config, source_name(config, name))}.counterface"
    if own is None:
        entries, keys = [{}], [None]
    elif isinstance(own, list):
        entries, keys = own, [f"{where}[{i}]" for i in range(len(own))]
    else:
        entries, keys = [own], [where]
    out = []
    for entry, key in zip(entries, keys, strict=True):
        (surface, surface_key), (body, body_key) = (
            (entry[part], f"{key}.{part}") if part in entry else
            (section[part], f"counterface.{part}") for part in ("surface", "body"))
        inherited = () if body == "rigid" else tuple(
            key for key in BODY_INHERITED[body["kind"]] if key not in body)
        out.append(CounterfaceEntry(*counter_defaults(config, surface, body),
                                    surface_key=surface_key, body_key=body_key,
                                    inherited=inherited))
    return out


def counter_surface(config: dict, entry, first: SurfaceCell) -> tuple[SurfaceCell | None, float]:
    """The counter surface cell of a counter ``surface`` entry (:func:`counter_defaults`)
    on the first cell's grid and plan size, and its sigma [m]: ``smooth`` (None, 0);
    generated (the ``surfaces`` section's ACF, periodicity and method, seed stream
    ``counter``, one counter surface per first surface; b by default the first
    cell's); or ``measured`` (its file; sigma by default the measured one)."""
    if entry == "smooth":
        return None, 0.0
    sigma = entry["sigma_um"]
    if "measured" in entry:
        cell = MeasuredCell.from_source(MeasurementImport.from_entry(entry["measured"]))
        return cell, cell.sigma if sigma is None else float(sigma) * UM
    b = entry["b_mm"]
    cell = generated_cell(config["surfaces"], None, skew=entry["skew"], kurt=entry["kurt"],
                          corr_length=first.corr_length if b is None else from_unit(as_pair(b)),
                          count=first.count, size=first.size, grid=first.grid)
    return dataclasses.replace(cell, stream="counter"), float(sigma) * UM


def counter_body(entry, first: Geometry) -> tuple[Geometry | None, float | None]:
    """The counter body of a counter ``body`` entry (:func:`counter_defaults`) on the
    first body's grid and plan size, and its E [Pa]: ``rigid`` (None, None); a
    ``halfspace`` (Love's, of its nu); or a ``block`` (its nu, thickness, base, mesh
    and operator)."""
    if entry == "rigid":
        return None, None
    params = {"nu": entry["nu"], "size_mm": in_units(first.size), "grid": list(first.grid)}
    if entry["kind"] == "halfspace":
        # Love's half-space: the thickness is only the reference length of the scaling
        params.update(operator=InfluenceModel.HALFSPACE.value, base="clamped", mesh="paper",
                      thickness_mm=in_unit(first.thickness, MM))
    else:
        params.update({key: entry[key] for key in ("thickness_mm", "base", "mesh", "operator")})
    return Geometry.from_params(params), float(entry["E_MPa"]) * MPA


def counterface_of(config: dict, entry: CounterfaceEntry, cell: StudyCell) -> Counterface:
    """The counter body of ``entry`` for a study cell (on its grid and plan size)."""
    surface, sigma = counter_surface(config, entry.surface, cell.surface)
    geometry, E = counter_body(entry.body, cell.geometry)
    return Counterface(
        surface=SMOOTH if surface is None else RoughCounter(surface, sigma=sigma),
        body=RIGID if geometry is None else ElasticCounter(geometry, E=E),
        rigid_share=float(config["counterface"]["rigid_share"]))


def counterface_groups(config: dict, name: str,
                       cells: list[StudyCell]) -> list[tuple[CounterfaceEntry, list[StudyCell]]]:
    """Each counter body of the study ``name`` (:func:`counterface_entries`) with the
    cells it makes of ``cells``: each cell against it; a smooth rigid counter body
    leaves a cell as it is (no ``counterface``: today's jobs and numbers)."""
    return [(entry, list(cells) if entry.is_null else
             [dataclasses.replace(cell, counterface=counterface_of(config, entry, cell))
              for cell in cells])
            for entry in counterface_entries(config, name)]


def with_counterfaces(config: dict, name: str, cells: list[StudyCell]) -> list[StudyCell]:
    """Each cell once per counter body of the study ``name`` (:func:`counterface_groups`)."""
    return [cell for _, group in counterface_groups(config, name, cells) for cell in group]


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
    cells = with_counterfaces(config, name, study_base_cells(config, name))
    return tuple(with_hardness(cells, study, float(config["body"]["hardness_threshold"])))


def study_base_cells(config: dict, name: str) -> list[StudyCell]:
    """The cells of a contact figure or sweep on the body section's block, before its
    counter bodies and hardness settings (:func:`contact_cells`)."""
    study = study_section(config, name)
    common = {"pressure_range": from_unit(study["pressure_MPa"], MPA),
              "accuracy": study_accuracy(config)}
    build = _generated_cells if study.get("surface") is None else _measured_cells
    return build(config, study, body_geometry(config), common)
