"""Plan-time checks that every body of a study's cells gets: the first and the counter body.

A study cell presses its surfaces (the first body: the study's surface cell, sigma,
block and E) against a counter body (Eq 17-18: its own surface, sigma, block or
half-space and E; none for the paper's rigid smooth flat). Each body's typed values
come with the configuration keys they were written under (``sweeps.pad.E_MPa[1]``,
``body.thickness_mm``, ``counterface.body.E_MPa``,
``sweeps.pad.counterface[1].surface.sigma_um``): the first body's from the cell and its
study's entry (:func:`first_body`), the counter body's from its configured entry
(:meth:`~roughcontact.study.plan.counter_entries.CounterfaceEntry.typed_values`); the
checks below run on every body alike (:func:`body_problems`): one code, whichever
body a value belongs to.

:func:`check_plausible` refuses values that are almost surely a unit slip
(:data:`PLAUSIBLE`): sigma, E, the largest nominal pressure over E, and a block
thinner than one contact element (``thickness_mm: 0.01``, metres meant), each with
the value in the unit it was likely typed in where that value passes; measured maps
(first or counter) that are noise or whose measured sigma is out of range
(:mod:`~roughcontact.study.plan.measured_checks`).
"""

from __future__ import annotations

import dataclasses

from roughcontact.study.codec import in_unit
from roughcontact.study.config import BuildSettings, unit_slips
from roughcontact.study.contact_records import StudyCell
from roughcontact.study.plan.block_checks import block_problems, thickest_block
from roughcontact.study.plan.measured_checks import measured_problems
from roughcontact.study.records import Geometry, InfluenceModel, MeasuredCell
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


def _axis_key(where: str, entry: dict, key: str, value: float) -> str:
    """The key of ``value`` of a study axis: ``where.key``, with the index of the value
    nearest it when the study lists several."""
    values = entry[key]
    if not isinstance(values, list):
        return f"{where}.{key}"
    index = min(range(len(values)), key=lambda i: abs(float(values[i]) - value))
    return f"{where}.{key}[{index}]"


def first_body(study: Study, name: str, cell: StudyCell) -> dict:
    """The typed values of the first body of a study cell (of the figure or sweep
    ``name``), each with its configuration key: ``E_MPa`` (E [Pa]), ``sigma_um`` (sigma
    [m]; absent for a measured surface's own), ``measured`` (its measured cell) and
    ``thickness_mm`` (its block's geometry; absent for a patch's or a half-space)."""
    where, entry = study.path(study.source_name(name)), study.source(name)
    values = {"E_MPa": (_axis_key(where, entry, "E_MPa", in_unit(cell.E, MPA))
                        if "E_MPa" in entry else "body.E_MPa", cell.E)}
    if "sigma_um" in entry:  # else a measured surface's own sigma
        values["sigma_um"] = (_axis_key(where, entry, "sigma_um", in_unit(cell.sigma, UM)),
                              cell.sigma)
    if isinstance(cell.surface, MeasuredCell):
        values["measured"] = (f"{where}.surface", cell.surface)
    thickness = entry.get("thickness_mm")  # optional: a measured patch's own block
    if cell.geometry.operator is not InfluenceModel.HALFSPACE and thickness != "patch":
        values["thickness_mm"] = ("body.thickness_mm" if thickness is None
                                  else f"{where}.thickness_mm", cell.geometry)
    return values


def cell_bodies(study: Study, name: str, cell: StudyCell) -> list[dict]:
    """The typed values of the bodies of a study cell: the first's and its counter
    body's (of the configured entry the plan made it of: ``counter_entry``; the rigid
    smooth flat has none)."""
    return [first_body(study, name, cell), cell.counter_entry.typed_values(cell)]


def _slip(kind: str, key: str, value: float, fits) -> str:
    """The advice naming each unit ``value`` may have been typed in, where the value in
    the key's unit then ``fits`` (passes every check here), else ''."""
    return "".join(f"; {advice}" for advice in unit_slips(key, value, _SLIPS[kind], fits))


def _in_range(kind: str, value: float) -> bool:
    low, high = PLAUSIBLE[kind]
    return low <= value <= high


def _modulus_problems(where: str, key: str, E: float, p_max: float) -> list[str]:
    """Messages for a body's E [Pa] (of the configuration ``key``) out of range, or below
    the largest pressure ``p_max`` [Pa] of the study ``where`` over :data:`PLAUSIBLE`'s
    ``pressure_over_E``."""
    E, p_max = in_unit(E, MPA), in_unit(p_max, MPA)
    limit = PLAUSIBLE["pressure_over_E"]

    def fits(value):
        return _in_range("E_MPa", value) and p_max / value <= limit

    if not _in_range("E_MPa", E):
        low, high = PLAUSIBLE["E_MPa"]
        return [f"{key} = {E:g} lies outside {low:g}-{high:g} MPa{_slip('E_MPa', key, E, fits)}"]
    if p_max / E <= limit:
        return []
    return [f"{where}.pressure_MPa up to {p_max:g} on {key} = {E:g} is P / E = "
            f"{p_max / E:.3g}, beyond {limit:g}, where the linear elastic model has no "
            f"meaning{_slip('E_MPa', key, E, fits)}; else check the units of "
            f"{where}.pressure_MPa and {key}"]


def _thickness_problems(key: str, geometry: Geometry, build: BuildSettings) -> list[str]:
    """Messages for a block ``geometry`` thinner than one contact element (a thickness in
    metres typed in mm, under the configuration ``key``), with the thickness it was
    likely meant as where that block passes
    :func:`~roughcontact.study.plan.block_checks.block_problems`, else (that thickness too
    thick for the patch) the thickest block that passes."""
    spacing = min(s / n for s, n in zip(geometry.size, geometry.grid, strict=True))
    if geometry.thickness >= spacing * (1 - 1e-9):
        return []

    def fits(value):
        block = dataclasses.replace(geometry, thickness=value * MM)
        return block.thickness >= spacing and not block_problems(block, build)

    thickness, element = in_unit(geometry.thickness, MM), in_unit(spacing, MM)
    text = f"{key} = {thickness:g} is thinner than one contact element ({element:g} mm)"
    slips = _slip("thickness_mm", key, thickness, fits)
    if slips:
        return [f"{text}{slips}; otherwise give a block at least {element:g} mm thick"]
    meant = thickness * dict(_SLIPS["thickness_mm"])["m"]
    largest = thickest_block(geometry, build)
    if largest is not None and meant * MM > largest and fits(in_unit(largest, MM)):
        (lx, ly) = (in_unit(v, MM) for v in geometry.size)
        return [f"{text}; typed in m, it would be {meant:g} mm, too thick for the "
                f"{lx:.3g} x {ly:.3g} mm patch (the thickest block it carries is "
                f"{in_unit(largest, MM):g} mm): write {key}: {in_unit(largest, MM):g}"]
    return [f"{text}: give a block at least {element:g} mm thick"]


def body_problems(where: str, values: dict, p_max: float, build: BuildSettings) -> list[str]:
    """Messages for a body's typed ``values`` (:func:`cell_bodies`: each with its
    configuration key) that are almost surely a unit slip, in the study ``where`` swept
    up to ``p_max`` [Pa]."""
    problems = []
    if "sigma_um" in values:
        key, sigma = values["sigma_um"]
        sigma = in_unit(sigma, UM)
        if not _in_range("sigma_um", sigma):
            low, high = PLAUSIBLE["sigma_um"]
            slip = _slip("sigma_um", key, sigma, lambda v: _in_range("sigma_um", v))
            problems.append(f"{key} = {sigma:g} lies outside {low:g}-{high:g} um{slip}")
    if "E_MPa" in values:
        problems += _modulus_problems(where, *values["E_MPa"], p_max)
    if "thickness_mm" in values:
        problems += _thickness_problems(*values["thickness_mm"], build)
    if "measured" in values:
        problems += measured_problems(*values["measured"], PLAUSIBLE["sigma_um"])
    return problems


def check_plausible(study: Study, cells: dict[str, tuple[StudyCell, ...]]) -> list[str]:
    """Messages for the values of every body of the studies' cells (:func:`cell_bodies`)
    that are almost surely a unit slip (:func:`body_problems`), in the units they were
    written in, each once; ``cells`` by study name."""
    build = study.body.build
    problems = {}
    for name, study_cells in cells.items():
        where = study.path(study.source_name(name))
        for cell in study_cells:
            for values in cell_bodies(study, name, cell):
                found = body_problems(where, values, cell.pressure_range[1], build)
                problems.update(dict.fromkeys(found))
    return list(problems)


__all__ = ["PLAUSIBLE", "body_problems", "cell_bodies", "check_plausible", "first_body"]
