"""Plan-time check of the elastic block under each study's surfaces.

The block takes its plan size and contact grid from the surfaces (a measured
patch: the prepared measurement's), its thickness and mesh from the
configuration. A block far thicker than its plan (a 10 mm block under a
0.1 mm patch) or a mesh of elongated elements cannot be solved reliably
(:func:`roughcontact.elasticity.influence.shape_problems`): such a study is
refused before any job, with the keys to change and values that work, each
checked here by the same test (a value is offered only if the block it makes
passes).
"""

from __future__ import annotations

import dataclasses
import math

from roughcontact.elasticity.influence import MAX_SLENDERNESS, shape_problems
from roughcontact.study.codec import in_unit
from roughcontact.study.config import BuildSettings
from roughcontact.study.contact_records import StudyCell
from roughcontact.study.plan.studies import PATCH_THICKNESS
from roughcontact.study.records import Geometry, InfluenceModel, MeasuredCell
from roughcontact.units import MM

#: Thickness candidates tried, as multiples of the patch's narrower side (from 1 %
#: to :data:`MAX_SLENDERNESS` times; the largest that passes is offered).
_THICKNESS_STEPS = 48


def block_problems(geometry: Geometry, build: BuildSettings) -> list[str]:
    """:func:`shape_problems` of the finite-element model a geometry's build solves (the
    block, or a matrix-free operator's coarse model; none for the half-space)."""
    if geometry.planned_model(build.max_bytes) is InfluenceModel.HALFSPACE:
        return []
    return shape_problems(geometry.finite_element_model(build.max_bytes))


def thickest_block(geometry: Geometry, build: BuildSettings) -> float | None:
    """The largest thickness [m], rounded down to 2 digits in mm, whose block passes
    :func:`block_problems` (None: none up to the slenderness limit does)."""
    side = min(geometry.size)
    for k in range(_THICKNESS_STEPS, -1, -1):
        raw = side * MAX_SLENDERNESS * 1000.0 ** (k / _THICKNESS_STEPS - 1.0)
        digits = 1 - math.floor(math.log10(raw / MM))
        thickness = math.floor(raw / MM * 10**digits) / 10**digits * MM
        if thickness > 0 and not block_problems(
                dataclasses.replace(geometry, thickness=thickness), build):
            return thickness
    return None


def _remedies(where: str, geometry: Geometry, build: BuildSettings,
              measured: bool, body: str, own_thickness: bool = False) -> list[str]:
    """The changes, as config text, that give ``geometry`` a usable block (each tested);
    ``where`` the study's config path (``sweeps.<name>``), ``body`` the path of the
    block's keys (``body``, or a counter body's ``counterface.body``); ``own_thickness``:
    the study names its block's thickness (``thickness_mm``)."""
    passes = [] if not measured else [(f"{where}.thickness_mm: {PATCH_THICKNESS}",
                                       max(geometry.size), geometry.mesh)]
    thickest = thickest_block(geometry, build)
    thickness_key = (f"{where}.thickness_mm" if measured or own_thickness
                     else f"{body}.thickness_mm")
    if thickest is not None:
        passes.append((f"{thickness_key}: {in_unit(thickest, MM):g}", thickest, geometry.mesh))
    if geometry.mesh != "refined":
        passes.append((f"{body}.mesh: refined", geometry.thickness, "refined"))
    out = []
    for text, thickness, mesh in passes:
        changed = dataclasses.replace(geometry, thickness=thickness, mesh=mesh)
        if not block_problems(changed, build):
            out.append(f"{text} (a {in_unit(thickness, MM):.3g} mm {mesh} block)")
    return out


def block_message(where: str, geometry: Geometry, build: BuildSettings, problems: list[str],
                  measured: bool, body: str = "body", own_thickness: bool = False) -> str:
    """Why the block of the study at config path ``where`` is refused, and the changes
    that work; ``body`` the path of the block's keys (the ``body`` section's, or a
    counter body's: ``sweeps.pad.counterface[1].body``, then named in its place)."""
    (lx, ly), (nx, ny) = (in_unit(v, MM) for v in geometry.size), geometry.grid
    what = "the measured patch" if measured else "the surfaces"
    remedies = _remedies(where, geometry, build, measured, body, own_thickness)
    if measured:
        remedies.append(f"or measure (or crop, {where}.surface.crop_mm) a larger patch")
    where = where if body == "body" else f"{body} (a counter block)"
    return (f"{where}: the block under {what} ({lx:.3g} x {ly:.3g} mm, {nx} x {ny} elements, "
            f"{in_unit(geometry.thickness, MM):g} mm thick, {geometry.mesh} mesh) cannot be "
            f"solved reliably: {'; '.join(problems)}. Change "
            + ("; ".join(remedies) if remedies else "the block's thickness or the grid"))


def check_blocks(cells: dict[str, tuple[StudyCell, ...]], build: BuildSettings,
                 own_thickness=frozenset()) -> list[str]:
    """Messages for the studies whose block fails :func:`block_problems` (once per study
    and geometry); ``cells`` by the study's config path (``sweeps.<name>``),
    ``own_thickness`` the paths of those that name their block's ``thickness_mm``."""
    problems = []
    for where, study_cells in cells.items():
        measured = any(isinstance(c.surface, MeasuredCell) for c in study_cells)
        geometries = {c.geometry.key: c.geometry for c in study_cells}
        for geometry in geometries.values():
            found = block_problems(geometry, build)
            if found:
                problems.append(block_message(where, geometry, build, found, measured,
                                              own_thickness=where in own_thickness))
    return problems


__all__ = ["block_message", "block_problems", "check_blocks", "thickest_block"]
