"""Plan-time checks of the counter bodies of a study's cells (Eq 17-18).

A counter body (a study cell's ``counterface``, with the configured entry the plan made
it of, ``counter_entry``) meets the first body's checks, by their code: its block the
geometry limits of :mod:`~roughcontact.study.plan.block_checks` (with the keys of the
counter entry in the message), its generated surface the correlation window of
:func:`~roughcontact.study.plan.checks.window_message`. Besides, its surface must be
sampled like the first (:mod:`roughcontact.contact.counterface` adds the two height
maps element by element): a measured counter map on another grid or plan size is
refused with the import options that bring it onto the first surface's, each tried
here by importing the map so (an option is offered only if the map it makes fits).
"""

from __future__ import annotations

import dataclasses
import math

from roughcontact.elasticity.operators import HYBRID_MESHES
from roughcontact.study.codec import in_unit, in_units
from roughcontact.study.config import BuildSettings
from roughcontact.study.contact_records import StudyCell
from roughcontact.study.plan.block_checks import block_message, block_problems, thickest_block
from roughcontact.study.plan.body_checks import cell_bodies
from roughcontact.study.plan.checks import MAX_CORRELATION_FRACTION, window_message
from roughcontact.study.records import GeneratedCell, InfluenceModel, MeasuredCell, SurfaceCell
from roughcontact.study.settings import Study
from roughcontact.study.sources import MeasurementImport, load_measurement
from roughcontact.units import MM


def _block_problems(where: str, key: str, geometry, build: BuildSettings) -> list[str]:
    """Why a counter block ``geometry`` cannot be built (none: it can), naming its entry's
    ``key`` (of the study ``where``)."""
    if geometry.operator is InfluenceModel.HYBRID and geometry.mesh not in HYBRID_MESHES:
        return [f"{key}: operator hybrid needs an accurate coarse model: {key}.mesh one of "
                f"{list(HYBRID_MESHES)}, not {geometry.mesh!r} (or {key}.operator: dense)"]
    found = block_problems(geometry, build)
    return [block_message(where, geometry, build, found, False, body=key)] if found else []


def _window_problems(study: Study, name: str, cell: StudyCell) -> list[str]:
    """A generated counter surface of its own ``b_mm`` longer than half the surface (the
    first surface's check: :func:`~roughcontact.study.plan.checks.window_message`); one whose
    b is the first surface's is judged with it."""
    messages = (window_message(study, study.source_name(name), counter, key, written)
                for key, written, counter in cell.counter_entry.surface.own_b(cell.counterface))
    return [message for message in messages if message]


def _same_plan(cell: SurfaceCell, grid, size) -> bool:
    return cell.grid == tuple(grid) and all(
        math.isclose(a, b, rel_tol=1e-9) for a, b in zip(cell.size, size, strict=True))


def _import_fix(entry: dict, grid, size) -> str | None:
    """The import options, as config text, that bring the measured map of ``entry`` onto
    ``grid`` and plan ``size`` [m]: a window of that size from its first point (a whole
    number of its spacings) resampled to the grid; None where no window has it.
    Tested: the map imported so has that grid and size."""
    whole = load_measurement(MeasurementImport.from_params(
        {**entry, "crop_mm": None, "decimate": None, "resample_grid": None}))
    points = [length / spacing for length, spacing in zip(size, whole.spacing, strict=True)]
    if any(abs(p - round(p)) > 1e-6 * p or round(p) > n
           for p, n in zip(points, whole.grid, strict=True)):
        return None
    window = tuple(round(p) for p in points)
    options = {"crop_mm": None if window == whole.grid else [0, 0, *in_units(size)],
               "resample_grid": None if window == tuple(grid) else list(grid),
               "decimate": None}
    trial = MeasuredCell.from_source(MeasurementImport.from_params({**entry, **options}))
    if not _same_plan(trial, grid, size):
        return None
    words = [f"{key}: {value}".replace("'", "") for key, value in options.items()
             if value is not None]
    words += [f"remove {key}" for key, value in options.items()
              if value is None and entry.get(key) is not None]  # optional keys
    return " and ".join(words) if words else None


def _smaller_area(study: Study, entry: dict, first: SurfaceCell):
    """The study's ``size_mm`` (a square on the surfaces' spacing) and the counter map's
    import options that make both fit, where the map cannot cover the first surface:
    the largest side the map's window gives in whole spacings; None for a measured
    first surface (its size is its file's) or where none fits."""
    if not isinstance(first, GeneratedCell):
        return None
    surfaces = study.surfaces
    spacing = [s / n * MM for s, n in zip(surfaces.size_mm, surfaces.grid, strict=True)]
    whole = load_measurement(MeasurementImport.from_params(
        {**entry, "crop_mm": None, "decimate": None, "resample_grid": None}))
    step = max(whole.spacing)  # no larger than the map, nor than the study's area
    side = min(*(n * d for n, d in zip(whole.grid, whole.spacing, strict=True)), *first.size)
    side = math.floor(side / step * (1 + 1e-9)) * step
    side = in_unit(side, MM) * MM
    grid = tuple(max(4, round(side / h)) for h in spacing)
    fix = _import_fix(entry, grid, (side, side))
    return None if fix is None else (in_unit(side, MM), grid, fix)


def _thickness_fixes(study: Study, name: str, cell: StudyCell, side: float,
                     grid) -> list[str] | None:
    """The thicknesses, as config text, that let the blocks of ``cell`` (the first body's
    and a counter block's, :func:`~roughcontact.study.plan.body_checks.cell_bodies`) pass
    the block check on a square area of ``side`` [mm] and ``grid``: none where they pass
    as they are, None where no thickness does. Each tried here on every block it sets."""
    build = study.body.build
    blocks = [values["thickness_mm"] for values in cell_bodies(study, name, cell)
              if "thickness_mm" in values]
    planform = {"size": (side * MM, side * MM), "grid": tuple(grid)}
    moved = [(key, dataclasses.replace(geometry, **planform)) for key, geometry in blocks]
    chosen = {}
    for key, geometry in moved:
        if block_problems(geometry, build):
            thickest = thickest_block(geometry, build)
            if thickest is None:
                return None
            chosen[key] = min(chosen.get(key, thickest), thickest)
    for key, geometry in moved:
        thickness = chosen.get(key, geometry.thickness)
        if block_problems(dataclasses.replace(geometry, thickness=thickness), build):
            return None
    return [f"{key}: {in_unit(thickness, MM):g}" for key, thickness in chosen.items()]


def _grid_problems(study: Study, name: str, cell: StudyCell) -> list[str]:
    """A measured counter map on another grid or plan size than the surface it meets."""
    first, other = cell.surface, cell.counterface.heights.cell
    if not isinstance(other, MeasuredCell) or _same_plan(other, first.grid, first.size):
        return []
    key = f"{cell.counter_entry.surface_key}.measured"
    entry = cell.counter_entry.surface.measured
    (nx, ny), (lx, ly) = first.grid, in_units(first.size)
    (ox, oy), (olx, oly) = other.grid, in_units(other.size)
    text = (f"{key}: {other.source.file}: {ox} x {oy} points over {olx:g} mm x {oly:g} mm, "
            f"but the surface it meets ({first.key}) has {nx} x {ny} over {lx:g} mm x "
            f"{ly:g} mm: the two height maps add element by element, so they need the same "
            f"grid and plan size")
    fix = _import_fix(entry, first.grid, first.size)
    if fix is not None:
        return [f"{text}; set in {key}: {fix}"]
    smaller = _smaller_area(study, entry, first)
    if smaller is None:
        return [f"{text}; no window of the counter map has the first surface's plan size: "
                f"crop both maps to one window of the same size, on the same grid"]
    side, (gx, gy), fix = smaller
    where = study.path(study.source_name(name))
    thicker = _thickness_fixes(study, name, cell, side, (gx, gy))
    blocks = ("" if not thicker else
              f", with {' and '.join(thicker)} (the thickest block{'s' * (len(thicker) > 1)} "
              f"that area carries)")
    b = max(in_units(first.corr_length))
    if b > MAX_CORRELATION_FRACTION * side:  # the window check's bound, on the new area
        shortest = math.floor(MAX_CORRELATION_FRACTION * side * 1e3 + 1e-9) / 1e3
        written = study.entry(study.source_name(name)).get("b_mm")
        scans = isinstance(written, list) and len(written) > 1
        blocks += (f", with {where}.b_mm: {shortest:g}{f' in place of {b:g}' if scans else ''}"
                   f" (at most half that area)")
    return [f"{text}; no window of the counter map has the first surface's plan size (the "
            f"map is {olx:g} x {oly:g} mm): make the study's area one it has, "
            f"{where}.size_mm: {side:g} ({gx} x {gy} elements at the surfaces' spacing)"
            f"{blocks}, and set in {key}: {fix}"]


def check_counterfaces(study: Study, cells: dict[str, tuple[StudyCell, ...]]) -> list[str]:
    """Messages for the study cells whose counter body cannot be used: a counter block
    that cannot be solved reliably or a hybrid one on an inaccurate mesh, a generated
    counter surface longer in b than half the surface, and a measured counter map on
    another grid or plan size than the first, with the keys that fix it. Each once;
    ``cells`` by study name."""
    problems = {}
    for name, study_cells in cells.items():
        where = study.path(study.source_name(name))
        for cell in study_cells:
            found = _window_problems(study, name, cell) + _grid_problems(study, name, cell)
            for geometry in cell.counterface.geometries().values():
                found += _block_problems(where, cell.counter_entry.body_key, geometry,
                                         study.body.build)
            problems.update(dict.fromkeys(found))
    return list(problems)


__all__ = ["check_counterfaces"]
