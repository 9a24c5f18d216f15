"""Plan-time checks that every body of a study's cells gets: the first and the counter body.

A study cell presses its surfaces (the first body: the study's surface cell, sigma,
block and E) against a counter body (Eq 17-18: its own surface, sigma, block or
half-space and E; none for the paper's rigid smooth flat). :func:`cell_bodies` gives
both as :class:`Body` records with the configuration keys each value comes from
(``sweeps.pad.E_MPa[1]``, ``body.thickness_mm``, ``counterface.body.E_MPa``,
``sweeps.pad.counterface[1].surface.sigma_um``), and the checks below run on every
body alike: one code, whichever body a value belongs to.

:func:`check_plausible` refuses values that are almost surely a unit slip
(:data:`PLAUSIBLE`): sigma, E, the largest nominal pressure over E, and a block
thinner than one contact element (``thickness_mm: 0.01``, metres meant), each with
the value in the unit it was likely typed in where that value passes; measured maps
(first or counter) that are noise or whose measured sigma is out of range
(:mod:`~roughcontact.study.plan.measured_checks`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from roughcontact.study.config import BuildSettings, in_unit, unit_slips
from roughcontact.study.contact_records import StudyCell
from roughcontact.study.plan.block_checks import block_problems
from roughcontact.study.plan.counter_entries import CounterfaceEntry
from roughcontact.study.plan.measured_checks import measured_problems
from roughcontact.study.records import Geometry, InfluenceModel, MeasuredCell, SurfaceCell
from roughcontact.study.settings import Study
from roughcontact.units import MM, MPA, UM

#: Accepted ranges of the plausibility check: sigma [um], E [MPa], and the largest
#: nominal pressure over E of a sweep (beyond it linear elasticity has no meaning).
#: A block must be at least one contact element thick (its spacing).
PLAUSIBLE = {"sigma_um": (1e-3, 1e3), "E_MPa": (1e-3, 1e7), "pressure_over_E": 0.1}
#: Units a value is likely typed in by mistake: name, factor to the key's unit.
_SLIPS = {"sigma_um": (("m", 1e6), ("mm", 1e3), ("nm", 1e-3)),
          "E_MPa": (("Pa", 1e-6), ("kPa", 1e-3), ("GPa", 1e3)),
          "thickness_mm": (("m", 1e3), ("um", 1e-3))}
_UNITS = {"sigma_um": "um", "E_MPa": "MPa", "thickness_mm": "mm"}


@dataclass(frozen=True)
class Body:
    """One body of a study cell as the checks see it: ``surface`` (None: smooth) of
    height standard deviation ``sigma`` [m], ``geometry`` (None: rigid) of Young's
    modulus ``E`` [Pa], pressed up to ``p_max`` [Pa]; ``keys`` the configuration key
    of each value (``sigma_um``, ``E_MPa``, ``thickness_mm``; absent where the value
    is not typed: a measured sigma, a patch's thickness, a half-space's) and of a
    measured surface's import (``measured``: ``sweeps.pad.surface``,
    ``counterface.surface.measured``); ``where`` the study's configuration path
    (``sweeps.pad``); ``entry`` the configured counter body it is (None: the first
    body)."""

    where: str
    surface: SurfaceCell | None
    sigma: float
    geometry: Geometry | None
    E: float | None
    p_max: float
    keys: dict
    entry: CounterfaceEntry | None = None


def _axis_key(where: str, entry: dict, key: str, value: float) -> str:
    """The key of ``value`` of a study axis: ``where.key``, with the index of the value
    nearest it when the study lists several."""
    values = entry[key]
    if not isinstance(values, list):
        return f"{where}.{key}"
    index = min(range(len(values)), key=lambda i: abs(float(values[i]) - value))
    return f"{where}.{key}[{index}]"


def first_body(study: Study, name: str, cell: StudyCell) -> Body:
    """The first body of a study cell (of the figure or sweep ``name``)."""
    where, entry = study.path(study.source_name(name)), study.source(name)
    keys = {"E_MPa": (_axis_key(where, entry, "E_MPa", in_unit(cell.E, MPA))
                      if "E_MPa" in entry else "body.E_MPa")}
    if "sigma_um" in entry:  # else a measured surface's own sigma
        keys["sigma_um"] = _axis_key(where, entry, "sigma_um", in_unit(cell.sigma, UM))
    if isinstance(cell.surface, MeasuredCell):
        keys["measured"] = f"{where}.surface"
    thickness = entry.get("thickness_mm")  # optional: a measured patch's own block
    if cell.geometry.operator is not InfluenceModel.HALFSPACE and thickness != "patch":
        keys["thickness_mm"] = "body.thickness_mm" if thickness is None else f"{where}.thickness_mm"
    return Body(where, cell.surface, cell.sigma, cell.geometry, cell.E,
                cell.pressure_range[1], keys)


def counter_body(study: Study, name: str, cell: StudyCell) -> Body:
    """The counter body of a study cell (of the figure or sweep ``name``) as a
    :class:`Body`, keyed to the configured entry the plan made it of (``counter_entry``;
    the rigid smooth flat has no typed value, so no key)."""
    counter, entry = cell.counterface, cell.counter_entry
    return Body(study.path(study.source_name(name)), counter.surface.cell,
                counter.surface.sigma, counter.body.geometry, counter.body.E,
                cell.pressure_range[1], entry.keys(cell), entry)


def cell_bodies(study: Study, name: str, cell: StudyCell) -> list[Body]:
    """The bodies of a study cell: the first and its counter body."""
    return [first_body(study, name, cell), counter_body(study, name, cell)]


def _slip(kind: str, key: str, value: float, fits) -> str:
    """The advice naming each unit ``value`` may have been typed in, where the value in
    the key's unit then ``fits`` (passes every check here), else ''."""
    return "".join(f"; {advice}" for advice in unit_slips(key, value, _SLIPS[kind], fits))


def _in_range(kind: str, value: float) -> bool:
    low, high = PLAUSIBLE[kind]
    return low <= value <= high


def _modulus_problems(body: Body) -> list[str]:
    """Messages for a body's E [MPa] out of range, or below its largest pressure over
    :data:`PLAUSIBLE`'s ``pressure_over_E``."""
    key, E, p_max = body.keys["E_MPa"], in_unit(body.E, MPA), in_unit(body.p_max, MPA)
    limit = PLAUSIBLE["pressure_over_E"]

    def fits(value):
        return _in_range("E_MPa", value) and p_max / value <= limit

    if not _in_range("E_MPa", E):
        low, high = PLAUSIBLE["E_MPa"]
        return [f"{key} = {E:g} lies outside {low:g}-{high:g} MPa{_slip('E_MPa', key, E, fits)}"]
    if p_max / E <= limit:
        return []
    return [f"{body.where}.pressure_MPa up to {p_max:g} on {key} = {E:g} is P / E = "
            f"{p_max / E:.3g}, beyond {limit:g}, where the linear elastic model has no "
            f"meaning{_slip('E_MPa', key, E, fits)}; else check the units of "
            f"{body.where}.pressure_MPa and {key}"]


def _thickness_problems(body: Body, build: BuildSettings) -> list[str]:
    """Messages for a block thinner than one contact element (a thickness in metres
    typed in mm), with the thickness it was likely meant as where that block passes
    :func:`~roughcontact.study.plan.block_checks.block_problems`."""
    geometry, key = body.geometry, body.keys["thickness_mm"]
    spacing = min(s / n for s, n in zip(geometry.size, geometry.grid, strict=True))
    if geometry.thickness >= spacing * (1 - 1e-9):
        return []

    def fits(value):
        block = dataclasses.replace(geometry, thickness=value * MM)
        return block.thickness >= spacing and not block_problems(block, build)

    thickness = in_unit(geometry.thickness, MM)
    return [f"{key} = {thickness:g} is thinner than one contact element "
            f"({in_unit(spacing, MM):g} mm){_slip('thickness_mm', key, thickness, fits)}; "
            f"else a block at least {in_unit(spacing, MM):g} mm thick"]


def body_problems(body: Body, build: BuildSettings) -> list[str]:
    """Messages for a body's typed values that are almost surely a unit slip."""
    problems = []
    if "sigma_um" in body.keys:
        key, sigma = body.keys["sigma_um"], in_unit(body.sigma, UM)
        if not _in_range("sigma_um", sigma):
            low, high = PLAUSIBLE["sigma_um"]
            slip = _slip("sigma_um", key, sigma, lambda v: _in_range("sigma_um", v))
            problems.append(f"{key} = {sigma:g} lies outside {low:g}-{high:g} um{slip}")
    if "E_MPa" in body.keys:
        problems += _modulus_problems(body)
    if "thickness_mm" in body.keys:
        problems += _thickness_problems(body, build)
    if "measured" in body.keys:
        problems += measured_problems(body.keys["measured"], body.surface,
                                      PLAUSIBLE["sigma_um"])
    return problems


def check_plausible(study: Study, cells: dict[str, tuple[StudyCell, ...]]) -> list[str]:
    """Messages for the values of every body of the studies' cells (:func:`cell_bodies`)
    that are almost surely a unit slip (:func:`body_problems`), in the units they were
    written in, each once; ``cells`` by study name."""
    build = study.body.build
    problems = {}
    for name, study_cells in cells.items():
        for cell in study_cells:
            for body in cell_bodies(study, name, cell):
                problems.update(dict.fromkeys(body_problems(body, build)))
    return list(problems)


__all__ = ["PLAUSIBLE", "Body", "body_problems", "cell_bodies", "check_plausible",
           "counter_body", "first_body"]
