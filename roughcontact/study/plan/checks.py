"""Checks of a configuration the schema cannot make, run when the workflow is planned.

Each check returns one message per offending entry, naming the config keys
to change; :func:`roughcontact.study.plan.cells.study_plan` raises
:class:`ConfigProblems` with them before any job is planned to run.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import math

from roughcontact.elasticity.operators import HYBRID_MESHES
from roughcontact.study.codec import in_unit
from roughcontact.study.config import BuildSettings
from roughcontact.study.memory_advice import memory_message
from roughcontact.study.plan.counter_entries import counterface_entries, import_problems
from roughcontact.study.plan.studies import CAP_MODES, as_list, study_surfaces
from roughcontact.study.records import (
    GeneratedCell,
    Generator,
    Geometry,
    InfluenceModel,
)
from roughcontact.study.settings import Study, StudySection
from roughcontact.study.sources import (
    SPECTRA,
    load_measurement,
    spectrum_from_entry,
)
from roughcontact.surfaces import johnson, measured
from roughcontact.surfaces.calibration import calibrate_filter, input_moments, kurt_min
from roughcontact.surfaces.spec import SurfaceSpec
from roughcontact.surfaces.spectra import filter_kernel
from roughcontact.units import MM


class ConfigProblems(ValueError):
    """The configuration passed the schema but asks for something that cannot be
    run; ``problems`` lists one message per offending entry."""

    def __init__(self, title: str, problems: list[str]):
        super().__init__(f"{title} (no job was started):\n  " + "\n  ".join(problems))
        self.problems = problems


# ---------------------------------------------------------------------------
# Studies and spectra


def _spectrum_entries(study: Study, names) -> dict:
    """``where -> entry`` of the config's spectrum and of each named study's own."""
    entries = {"surfaces.spectrum": study.surfaces.spectrum}
    for name in names:
        try:
            own = study.source(name).get("spectrum")
        except (KeyError, ValueError):
            continue  # check_studies names it
        if own is not None:
            entries[f"{study.source_name(name)}.spectrum"] = own
    return entries


def check_spectra(study: Study, names) -> list[str]:
    """Messages for spectra that cannot be used: a spectrum with padded surfaces
    (``periodic: false``), a file that is missing or not a valid PSD table."""
    problems = []
    for where, entry in _spectrum_entries(study, names).items():
        if SPECTRA[entry["kind"]] is None:  # the ACF
            continue
        if not study.surfaces.periodic:
            problems.append(f"{where}: kind {entry['kind']} generates periodic surfaces only; "
                            "set surfaces.periodic: true or remove the spectrum")
            continue
        try:
            spectrum_from_entry(entry).spec_fields()
        except (OSError, ValueError) as err:
            problems.append(f"{where}: {err}")
    return problems


def check_studies(study: Study, names) -> list[str]:
    """Messages for contact figures or sweeps the schema cannot check: a ``from:`` that
    names no study or a cycle, a pressure range, a list axis that repeats a value, a
    measured surface (a study's or a counter body's), the hybrid operator's mesh, the
    hardness settings; where there are none, the warnings of
    :func:`warn_single_surfaces`."""
    problems = check_figure_duplicates(study)
    for name in names:
        try:
            section = study.section(name)
        except (KeyError, ValueError) as err:
            problems.append(f"{name}: {err}")
            continue
        low, high = section.pressure_MPa
        if not low < high:
            problems.append(f"{name}.pressure_MPa = [{low}, {high}]: expected [P_min, P_max] "
                            f"with P_min < P_max (MPa)")
        problems += check_duplicates(study, name)
        problems += _check_size(study, name, section)
        problems += check_measured(study, name, study.source(name))
        problems += check_counter_measured(study, name)
        problems += _check_operator(study, name, section)
        problems += _check_hardness(name, section)
        problems += _check_pressure_below_hardness(name, section)
    if not problems:  # a refusal comes alone
        warn_single_surfaces(study, names)
    return list(dict.fromkeys(problems))  # a study drawn from another: its messages once


#: Fewest contact elements along a side of a study's own ``size_mm`` (a smaller area
#: would need elements finer than the surfaces' spacing the schema promises).
MIN_STUDY_ELEMENTS = 4


def _smallest_size(study: Study, section: StudySection, spacing: list[float]) -> float:
    """The smallest square side [mm], in whole elements of ``spacing`` [mm] and at least
    :data:`MIN_STUDY_ELEMENTS` of them, that holds two of the study's longest correlation
    length and whose block passes the block check (its advice then plans in one round)."""
    from roughcontact.study.plan.block_checks import block_problems

    body, build = study.body.geometry, study.body.build
    b = max((max(as_list(v)) if isinstance(v, list) else float(v))
            for v in as_list(section.b_mm)) if section.b_mm is not None else 0.0
    step = max(spacing)
    for count in range(MIN_STUDY_ELEMENTS, 100 * MIN_STUDY_ELEMENTS):
        side = math.ceil(count * step * 1e6 - 1e-6) / 1e6
        grid = tuple(max(MIN_STUDY_ELEMENTS, round(side / h)) for h in spacing)
        block = dataclasses.replace(body, size=(side * MM, side * MM), grid=grid)
        if b <= MAX_CORRELATION_FRACTION * side and not any(
                block_problems(dataclasses.replace(block, mesh=str(mesh)), build)
                for mesh in as_list(section.meshes)):
            return side
    return math.ceil(MIN_STUDY_ELEMENTS * step * 1e6 - 1e-6) / 1e6


def _check_size(study: Study, name: str, section: StudySection) -> list[str]:
    """A study's own ``size_mm`` that holds fewer than :data:`MIN_STUDY_ELEMENTS`
    contact elements of the surfaces' spacing along a side (the schema promises that
    spacing: the study is refused, not solved on finer elements), with the smallest size
    that plans (:func:`_smallest_size`)."""
    if section.size_mm is None:
        return []
    surfaces = study.surfaces
    spacing = [s / n for s, n in zip(surfaces.size_mm, surfaces.grid, strict=True)]
    where = study.path(study.source_name(name))
    problems = []
    for index, size in enumerate(as_list(section.size_mm)):
        elements = min(round(size / h) for h in spacing)
        if elements >= MIN_STUDY_ELEMENTS:
            continue
        key = f"{where}.size_mm" + (f"[{index}]" if isinstance(section.size_mm, list) else "")
        problems.append(
            f"{key} = {size:g} holds {elements} contact element{'' if elements == 1 else 's'} "
            f"of the surfaces' spacing ({_pair_text(spacing)} mm: surfaces.size_mm / "
            f"surfaces.grid) along a side, fewer than {MIN_STUDY_ELEMENTS}; write {key}: "
            f"{_smallest_size(study, section, spacing):g}, or a finer surfaces.grid")
    return problems


#: The list axes of a contact study (one cell per value) and of the surface figures.
STUDY_AXES = ("meshes", "nu", "size_mm", "b_mm", "moments", "sigma_um", "E_MPa",
              "hardness_MPa", "cap_meshes")
FIGURE_AXES = {"fig02": ("b_mm",), "fig03": ("b_mm",), "fig04": ("moments",)}


def _repeats(where: str, values: list, written: list | None = None) -> list[str]:
    """Messages for the values of the list ``where`` that repeat an earlier one (each
    shown as ``written``, by default as compared)."""
    problems = []
    for j, value in enumerate(values):
        i = values.index(value)  # == compares numbers by value: 1 == 1.0
        if i < j:
            shown = json.dumps((values if written is None else written)[j])
            problems.append(f"{where}[{j}]: {shown} repeats {where}[{i}]: the "
                            f"same cells twice (a list axis names each value once); remove "
                            f"{where}[{j}]")
    return problems


def check_duplicates(study: Study, name: str) -> list[str]:
    """Messages for a list axis of the study ``name`` (of its source) that names a value
    twice, which would make the same cells twice: each list of :data:`STUDY_AXES`, and
    the counter bodies (compared with their defaults resolved, so ``{body: rigid}`` and
    ``{surface: smooth, body: rigid}`` are the same)."""
    entry = study.source(name)
    where = study.path(study.source_name(name))
    problems = []
    for key in STUDY_AXES:
        if isinstance(entry.get(key), list):  # optional: a scalar or the inherited value
            problems += _repeats(f"{where}.{key}", entry[key])
    if isinstance(entry.get("counterface"), list):  # optional: the section's
        resolved = [(e.surface, e.body) for e in counterface_entries(study, name)]
        problems += _repeats(f"{where}.counterface", resolved, entry["counterface"])
    return problems


def check_figure_duplicates(study: Study) -> list[str]:
    """:func:`check_duplicates` of the surface figures' lists (:data:`FIGURE_AXES`)."""
    return [problem for figure, keys in FIGURE_AXES.items() if figure in study.figures
            for key in keys if isinstance(study.entry(figure)[key], list)
            for problem in _repeats(f"figures.{figure}.{key}", study.entry(figure)[key])]


log = logging.getLogger(__name__)


def warn_single_surfaces(study: Study, names) -> None:
    """Log a warning, once per source study, for a study whose generated cells have one
    surface each (``count: 1``): a cell's 95 % band of the mean needs two, so its
    aggregates have none (NaN)."""
    for source in dict.fromkeys(study.source_name(name) for name in names):
        section = study.section(source)
        generated = not section.measured or section.compare_synthetic
        if generated and section.count == 1:
            where = section.where
            key = f"{where}.count" if "count" in section.own else "surfaces.count"
            log.warning("%s: one surface per cell (%s = 1): a single-surface cell has no "
                        "confidence band (its 95 %% band of the mean is NaN in the "
                        "aggregates); set %s to 2 or more for one", where, key, key)


def _check_hardness(name: str, study: StudySection) -> list[str]:
    values, cap = study.hardness_MPa, study.cap
    elastic, capped = CAP_MODES[cap]
    if name == "hardness" and not (values and elastic and capped):
        return [f"{name}: the hardness figure compares elastic and capped cells; "
                f"give it hardness_MPa (a hardness [MPa]) and cap: both"]
    if capped and not values:
        return [f"{name}: contact.cap = {cap!r} but no hardness is given; set "
                f"body.hardness_MPa (or the study's hardness_MPa) to the hardness "
                f"[MPa] to cap the pressure at, or cap: false"]
    meshes, listed = as_list(study.meshes), study.cap_meshes
    unknown = [m for m in (listed or []) if m not in meshes]
    if unknown:
        return [f"{name}: cap_meshes lists {unknown}, which the study does not solve "
                f"(its meshes: {meshes}); list some of {meshes}, or null for all"]
    return []


def _numbers(numbers: list[float], like) -> str:
    """``numbers`` as the configuration writes them: a list if ``like`` is one, else the
    number (6 significant digits)."""
    text = [f"{v:.6g}" for v in numbers]
    return f"[{', '.join(text)}]" if isinstance(like, list) else text[0]


#: A hardness typed in GPa into an MPa key: the factor to MPa.
_HARDNESS_SLIP = ("GPa", 1e3)


def _check_pressure_below_hardness(name: str, study: StudySection) -> list[str]:
    """Refuse a study whose largest nominal pressure exceeds its smallest hardness.

    The cap holds ``0 <= p <= H`` at every point, so the nominal (mean)
    pressure P of any contact is at most H: a capped cell cannot reach a
    P_max above H, and an elastic cell checked against H would be beyond it
    at every such P (the validity share 100 %), so neither result means
    anything. A hardness below the pressures is a unit slip (H typed in GPa
    into ``hardness_MPa``, or the pressures in kPa): refused whatever
    ``cap`` and ``plausibility_check`` say, naming the key the hardness
    comes from (the study's own ``hardness_MPa``, else ``body.hardness_MPa``).
    """
    values = study.hardness_MPa
    if values is None:
        return []
    hardness = as_list(values)
    p_min, p_max = study.pressure_MPa
    if p_max <= min(hardness):
        return []
    where = study.where
    key = f"{where}.hardness_MPa" if "hardness_MPa" in study.own else "body.hardness_MPa"
    elastic, capped = CAP_MODES[study.cap]
    meaningless = ((["cells capped at it cannot reach P_max"] if capped else [])
                   + (["elastic cells checked against it are beyond it at P_max (their mean "
                       "contact pressure exceeds it)"] if elastic else []))
    unit, factor = _HARDNESS_SLIP
    scaled = [h * factor if h < p_max else h for h in hardness]
    fixes = [f"give a hardness of at least {p_max:g} MPa"]
    if min(scaled) >= p_max:
        fixes.insert(0, f"typed in {unit}? then write {key}: {_numbers(scaled, values)}")
    if p_min < min(hardness):
        fixes.append(f"nominal pressures up to it, {where}.pressure_MPa: "
                     f"[{p_min:g}, {min(hardness):g}]")
    return [f"{where}: pressure_MPa up to {p_max:g} lies above {key} = "
            f"{_numbers(hardness, values)}: no contact carries a nominal pressure above the "
            f"hardness (0 <= p <= H at every point, so P <= H), so "
            f"{' and '.join(meaningless)}. Fix: " + "; or ".join(fixes)]


def check_counter_measured(study: Study, name: str) -> list[str]:
    """Messages for the measured counter surfaces of a study that cannot be imported
    (:func:`~roughcontact.study.plan.counter_entries.import_problems`, as a study's
    ``surface:``)."""
    return [problem for entry in counterface_entries(study, name)
            for problem in entry.surface.import_problems()]


def check_measured(study: Study, name: str, entry) -> list[str]:
    """Messages for a study whose measured surface cannot be used as configured
    (``entry``: the study as configured)."""
    if entry.get("surface") is None:
        return ([f"{name}: compare_synthetic needs a measured surface ('surface:')"]
                if entry.get("compare_synthetic") else [])
    if entry.get("spectrum") is not None and not entry["compare_synthetic"]:
        return [f"{name}: 'spectrum' applies to the generated twin of a measured surface; "
                "add compare_synthetic: true or remove spectrum"]
    clashing = [k for k in ("moments", "b_mm", "size_mm") if k in entry]
    if clashing:
        return [f"{name}: 'surface' (a measured surface) fixes the statistics, grid and "
                f"size; remove {', '.join(clashing)}"]
    problems = import_problems(f"{name}.surface", entry["surface"])
    if problems:
        return problems
    try:
        surfaces = study_surfaces(study, study.section(name))
    except (OSError, ValueError) as err:
        return [f"{name}.surface: {err}"]
    bx, by = (in_unit(b, MM) for b in surfaces[0].corr_length)
    if len(surfaces) > 1 and not (math.isfinite(bx) and math.isfinite(by)):
        advice = measured.form_advice(load_measurement(surfaces[0].source))
        return [f"{name}: the measured autocorrelation does not decay to 10 % within half "
                f"the measured length (b = {bx:g} x {by:g} mm), so no synthetic twin can be "
                f"made. {advice}; or set compare_synthetic: false (the measurement alone)"]
    return []


def _check_operator(study: Study, name: str, section: StudySection) -> list[str]:
    """The hybrid operator needs a coarse model with an accurate near field."""
    if study.body.geometry.operator is not InfluenceModel.HYBRID:
        return []
    bad = [m for m in as_list(section.meshes) if m not in HYBRID_MESHES]
    if not bad:
        return []
    return [f"{name}: body.operator = hybrid with mesh {bad[0]!r}: the hybrid operator takes "
            f"its finite-body correction from a coarse model whose near field must be "
            f"accurate, so the mesh must be one of {list(HYBRID_MESHES)}; use operator: "
            f"dense (the paper's model) or auto (dense up to 64 x 64, hybrid with a "
            f"'refined' coarse model above)"]


# ---------------------------------------------------------------------------
# Generated surfaces too small for their correlation length

#: The longest correlation length a generated surface may have, as a fraction of its
#: side along the same axis: b <= L / 2, two correlation lengths per window.
#:
#: The 10 % lag of Eq 1 is a lag a window can show only up to half its side: the
#: autocorrelation of a periodic window is symmetric about L / 2, and
#: :func:`~roughcontact.surfaces.statistics.correlation_length` reads lags up to
#: L / 2 (NaN beyond). A measured map whose autocorrelation does not fall to 10 %
#: there is refused a synthetic twin for that reason (:func:`check_measured`), and
#: the generator warns at this bound when it runs
#: (:func:`~roughcontact.surfaces.spectra.check_domain`). Measured on 40 Gaussian
#: surfaces (60 x 60 over 9 mm, method paper, periodic): at b = L / 2 a window's
#: sigma is 0.88 of the target and 30 % of the windows show no 10 % decay within
#: L / 2; at b = 20 mm (2.2 L) 0.57 and 45 %. The paper's studies reach b = 0.22 L
#: (b = 1 mm on 4.5 mm, 2 mm on 9 mm: sigma 0.97 of the target).
MAX_CORRELATION_FRACTION = 0.5


def _pair_text(values) -> str:
    """A pair as the configuration may write it: one number if both are equal."""
    return _numbers(list(values), None if values[0] == values[-1] else list(values))


def window_message(study: Study, name: str, cell: GeneratedCell, b_key: str | None = None,
                   b_written=None) -> str | None:
    """Why a generated cell of the figure or sweep ``name`` has a correlation length
    longer than :data:`MAX_CORRELATION_FRACTION` of its side, with the fixes, or None.

    ``b_key`` names the key of the correlation length (``b_written`` its value as
    written) where it is not the study's ``b_mm``: a counter surface's
    (``sweeps.pad.counterface[1].surface.b_mm``), on the study's plan size."""
    b, size = (tuple(in_unit(v, MM) for v in pair) for pair in (cell.corr_length, cell.size))
    limit = tuple(MAX_CORRELATION_FRACTION * side for side in size)
    if all(bi <= li for bi, li in zip(b, limit, strict=True)):
        return None
    entry = study.entry(name)
    where = study.path(name)
    b_key = f"{where}.b_mm" if b_key is None else b_key
    b_written = entry["b_mm"] if b_written is None else b_written
    own_size = entry.get("size_mm") is not None  # a study's own size, else the surfaces'
    size_key = f"{where}.size_mm" if own_size else "surfaces.size_mm"
    spacing = [s / n for s, n in zip(size, cell.grid, strict=True)]
    needed = [math.ceil(bi / MAX_CORRELATION_FRACTION * 1e3 - 1e-9) / 1e3 for bi in b]
    if own_size:  # a square area on the surfaces' spacing
        side = max(needed)
        grid = [max(4, round(side / h)) for h in spacing]
        larger = (f"{size_key}: {side:g}{_in_place(entry['size_mm'], size)} ({grid[0]} x "
                  f"{grid[1]} elements at the surfaces' spacing)")
    else:
        sides = [max(n, s) for n, s in zip(needed, size, strict=True)]
        grid = [max(4, round(side / h)) for side, h in zip(sides, spacing, strict=True)]
        larger = (f"{size_key}: {_pair_text(sides)} with surfaces.grid: {_pair_text(grid)} "
                  "(the same spacing)")
    shortest = [min(bi, li) for bi, li in zip(b, limit, strict=True)]
    what = where if b_key == f"{where}.b_mm" else b_key.rsplit(".", 1)[0]
    return (f"{what}: b_mm = {_pair_text(b)} is longer than half the surface, {size_key} = "
            f"{_pair_text(size)} (L / 2 = {_pair_text(limit)} mm): fewer than two "
            "correlation lengths fit in it: the lag at which the autocorrelation falls to "
            "10 % (Eq 1) lies beyond the L / 2 a window shows, and a window's sigma falls "
            "short of the target (0.88 of it at b = L / 2, 0.57 at b = 2.2 L). Fix: "
            f"{b_key}: {_pair_text(shortest)} or shorter"
            f"{_in_place(b_written, b)}; or a larger surface, {larger}")


def _in_place(configured, pair) -> str:
    """`` in place of x`` where a configured list scans values and ``pair`` [mm] (equal
    along both axes) is one of them, else ''."""
    if isinstance(configured, list) and pair[0] == pair[-1] and len(configured) > 1:
        return f" in place of {pair[0]:g}"
    return ""


def check_windows(study: Study, cells) -> list[str]:
    """Messages for the generated cells whose correlation length exceeds
    :data:`MAX_CORRELATION_FRACTION` of their side (:func:`window_message`), once per
    cell; ``cells`` the surface cells by the figure or sweep whose ``b_mm`` they have.
    Cells with a spectrum (where b only labels them) and measured surfaces and their
    twins (whose b is measured: :func:`check_measured`) are not judged here."""
    problems = []
    for name, surfaces in cells.items():
        if study.entry(name).get("surface") is not None:
            continue
        for cell in {c.key: c for c in surfaces}.values():
            if isinstance(cell, GeneratedCell) and cell.spectrum is None:
                message = window_message(study, name, cell)
                problems += [message] if message else []
    return problems


# ---------------------------------------------------------------------------
# Surface cells the generator cannot make

#: A calibrated cell whose target kurtosis lies within this fraction of
#: (Ku - 1) of the filter's bound (Eq 15), above or below it, is left to its
#: surface job: the window's sample bias (a few per cent) may carry it across
#: the bound either way, and only the calibration itself (seconds to a minute a
#: cell) can tell.
NEAR_BOUND = 0.1


def _gaussian(spec: SurfaceSpec) -> bool:
    """Whether ``spec`` asks for Gaussian heights, (Sk, Ku) = (0, 3): every filter makes
    them from Gaussian white noise (Eq 12-13), and a window's expected sample kurtosis,
    below 3, is raised by the calibration; nothing to check, and the filter's moment
    transfer (an FFT of the grid: 15 s on 4096 x 4096) is not computed."""
    return spec.skew == 0.0 and spec.kurt == 3.0


def _check_paper(spec: SurfaceSpec) -> None:
    """Raise if the paper's filter cannot make ``spec`` (Eq 15; its white noise's law)."""
    if not _gaussian(spec):
        johnson.fit(*input_moments(spec))


def _check_calibrated(spec: SurfaceSpec) -> None:
    """Raise if the calibrated filter cannot reach ``spec``'s expected sample moments.

    The plan never calibrates a cell it accepts. Far above the reachable
    region's edge the process check (Eq 15) suffices and the white noise's
    Johnson law is fitted; near the edge (within :data:`NEAR_BOUND`) the cell
    is accepted and its surface job calibrates
    (:func:`~roughcontact.surfaces.calibration.calibrate_filter`), refusing a
    target it cannot reach with the message given here; far below the edge the
    calibration runs here only to refuse, naming the reachable kurtosis.
    """
    if _gaussian(spec):
        return
    try:
        bound = float(kurt_min(spec))
    except ValueError:
        bound = math.inf
    band = NEAR_BOUND * (spec.kurt - 1.0)
    if spec.kurt >= bound + band:
        johnson.fit(*input_moments(spec))
    elif spec.kurt < bound - band:
        calibrate_filter(spec)  # raises: no process reaches it (the job's message)


#: The Johnson law each generator fits (raises where it cannot): the white noise's of
#: the filter (calibrated or the paper's), the target's of exact.
_FITS = {
    Generator.FILTER: lambda cell: _check_calibrated(cell.spec()),
    Generator.PAPER: lambda cell: _check_paper(cell.spec()),
    Generator.EXACT: lambda cell: johnson.fit(cell.skew, cell.kurt),
}


def check_feasible(surfaces: dict) -> list[str]:
    """Messages for generated cells whose (skew, kurt) the generator cannot reach, and
    for any Johnson law the generator would fit that cannot be fitted (each is
    fitted here, before any job); a spectrum's table must agree with the grid."""
    problems = []
    for key, cell in surfaces.items():
        if not isinstance(cell, GeneratedCell):
            continue  # a measurement: nothing to generate
        try:
            if cell.spectrum is not None:  # the table and the grid agree (power on the grid)
                filter_kernel(cell.spec())
            _FITS[cell.method](cell)
        except (ValueError, RuntimeError, FloatingPointError) as err:
            problems.append(f"{key}: {err}")
    return problems


# ---------------------------------------------------------------------------
# Influence builds beyond the memory limit


def check_memory(geometries: dict[str, Geometry], build: BuildSettings) -> list[str]:
    """Messages for the influence builds whose estimated peak memory exceeds the
    body's ``max_memory_gb`` (checked when the plan is made); ``geometries`` as
    configured, each judged on its candidates (an ``operator: auto`` geometry on the
    model it plans)."""
    problems = {}
    for configured in geometries.values():
        for geometry in configured.candidates(build.max_bytes):
            peak = geometry.influence_cost(build).peak_bytes
            if peak > build.max_bytes:
                problems.setdefault(geometry.key,
                                    memory_message(geometry, build, peak, configured))
    return list(problems.values())
