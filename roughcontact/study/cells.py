"""The study grid: which surface cells, geometries and contact cells a configuration asks for.

A *surface cell* is one set of surface statistics and sampling (skewness,
kurtosis, correlation lengths, grid, size, ACF or spectrum, periodicity,
generator) with a number of seeded realisations. Its key names every parameter, so a changed
parameter is a new file and the workflow reruns exactly what depends on it.
Sigma is not part of a cell: surfaces are stored in units of sigma and scaled
at use (Eq 28-32 of Kumar et al. 2006). The jobs that build them are in
:mod:`roughcontact.study.jobs`.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import logging
import math
import re
from pathlib import Path

import numpy as np

from roughcontact.contact.cell import nondim_pressure
from roughcontact.elasticity.influence import BlockGeometry, estimate_cost
from roughcontact.elasticity.operators import HYBRID_MESHES, choose_operator, default_coarse_grid
from roughcontact.errors import MeasurementError
from roughcontact.hashes import file_sha256
from roughcontact.study.presets import ACCURACY_PRESETS
from roughcontact.study.provenance import canonical_json
from roughcontact.surfaces import johnson, measured
from roughcontact.surfaces.calibration import calibrate_filter, input_moments, kurt_min
from roughcontact.surfaces.spec import SurfaceSpec
from roughcontact.surfaces.spectra import filter_kernel
from roughcontact.units import GB, MM, MPA, UM

log = logging.getLogger(__name__)

SURFACE_FIGURES = ("fig03", "fig04", "fig05")
#: Figures that need no contact solve (Fig 1 and 2 need no surfaces either).
SURFACE_ONLY_FIGURES = ("fig01", "fig02", "fig03", "fig04", "fig05")


def _pair(value) -> list:
    if isinstance(value, list | tuple):
        return [value[0], value[1]]
    return [value, value]


def cell_params(defaults: dict, **overrides) -> dict:
    """Complete, canonical parameters of one surface cell.

    ``defaults`` is the config's ``surfaces`` section; ``overrides`` may set
    ``skew``, ``kurt``, ``b_mm``, ``count``, ``spectrum`` and any default.
    A ``spectrum`` other than ``{kind: acf}`` (:func:`spectrum_params`) is
    stored under ``"spectrum"`` and replaces the ACF: ``acf`` is then
    ``"self-affine"`` or ``"psd"`` (the :class:`SurfaceSpec` kind) and
    ``b_mm`` only labels the cell. Without one the parameters are those of
    a cell before spectra existed (same keys, same surfaces).
    """
    merged = {**defaults, **overrides}
    params = {
        "skew": float(merged["skew"]),
        "kurt": float(merged["kurt"]),
        "b_mm": [float(v) for v in _pair(merged["b_mm"])],
        "grid": [int(v) for v in _pair(merged["grid"])],
        "size_mm": [float(v) for v in _pair(merged["size_mm"])],
        "acf": str(merged["acf"]),
        "periodic": bool(merged["periodic"]),
        "method": str(merged["method"]),
        "count": int(merged["count"]),
    }
    spectrum = spectrum_params(merged.get("spectrum"))
    if spectrum is not None:
        params["acf"] = "self-affine" if spectrum["kind"] == "self-affine" else "psd"
        params["spectrum"] = spectrum
    return params


def statistics_key(params: dict) -> str:
    """Key of a cell's statistics and sampling, without the surface count.

    Seeds derive from this key, so the first k surfaces of a cell are the same
    whatever the count. A measured cell's key is :func:`measured_key`. A cell
    with a spectrum ends in :func:`spectrum_tag`.
    """
    if params["method"] == "measured":
        return measured_key(params)
    bx, by = params["b_mm"]
    lx, ly = params["size_mm"]
    nx, ny = params["grid"]
    key = (
        f"sk{params['skew']:g}_ku{params['kurt']:g}_b{bx:g}x{by:g}mm_L{lx:g}x{ly:g}mm"
        f"_g{nx}x{ny}_{params['acf'][:3]}_{'per' if params['periodic'] else 'pad'}"
        f"_{params['method']}"
    )
    if "spectrum" in params:
        key += f"_{spectrum_tag(params['spectrum'])}"
    return key


def cell_key(params: dict) -> str:
    """File key of a surface cell: its statistics key and the surface count."""
    return f"{statistics_key(params)}_n{params['count']}"


def spec_from_params(params: dict, sigma: float = 1.0) -> SurfaceSpec:
    """The :class:`SurfaceSpec` of a cell (lengths converted from mm to m).

    A cell with a spectrum gets its fields from :func:`spectrum_fields` (a
    table is read from its file, which must be the planned one) and the
    spectrum's own correlation length (``b_mm`` is not used).
    """
    if "spectrum" in params:
        shape = {"corr_length": None, **spectrum_fields(params["spectrum"])}
    else:
        shape = {"corr_length": tuple(v * MM for v in params["b_mm"]), "acf": params["acf"]}
    return SurfaceSpec(
        grid=tuple(params["grid"]),
        size=tuple(v * MM for v in params["size_mm"]),
        sigma=sigma,
        skew=params["skew"],
        kurt=params["kurt"],
        periodic=params["periodic"],
        **shape,
    )


# ---------------------------------------------------------------------------
# Spectra: ``surfaces.spectrum`` (or a study's ``spectrum``) in place of the ACF

#: Short names of the spectrum kinds in cell keys (:func:`spectrum_tag`).
SPECTRUM_TAGS = {"self-affine": "sa", "table": "tab", "measured": "mpsd"}
#: Import options of a measured spectrum beyond the schema's (its own grid is kept).
_MEASURED_SPECTRUM_FIXED = {"decimate": None, "resample_grid": None}


def spectrum_params(entry: dict | None) -> dict | None:
    """Canonical parameters of a validated ``spectrum:`` entry; None for ``kind: acf``
    (or no entry): the ACF of the ``surfaces`` section.

    - ``self-affine``: ``hurst``, ``rolloff_mm``, ``cutoff_mm``.
    - ``table``: ``file`` (a CSV table, :func:`roughcontact.surfaces.measured.read_psd_table`)
      and its ``file_sha256``.
    - ``measured``: the import options of :func:`measured_options` (no
      decimation or resampling) and the file's ``file_sha256``.

    Files are read here (relative paths from the working directory), so a
    changed file is a new cell (:func:`spectrum_tag`).
    """
    if entry is None or entry["kind"] == "acf":
        return None
    kind = entry["kind"]
    if kind == "self-affine":
        return {"kind": kind, "hurst": float(entry["hurst"]),
                "rolloff_mm": float(entry["rolloff_mm"]), "cutoff_mm": float(entry["cutoff_mm"])}
    if kind == "table":
        path = str(entry["file"])
        return {"kind": kind, "file": path, "file_sha256": _psd_file(path, _stamp(path))[0]}
    options = measured_options({**{k: v for k, v in entry.items() if k != "kind"},
                                **_MEASURED_SPECTRUM_FIXED})
    return {"kind": kind, **options, "file_sha256": load_measured(options).sha256}


def spectrum_tag(spectrum: dict) -> str:
    """Short name and hash of a spectrum, appended to its cells' keys.

    ``sa-<8 hex>`` (self-affine: the hash of its parameters), ``tab-<12 hex>``
    (a table: the first 12 hex digits of the file's SHA-256, as ``sha256sum``
    prints it) or ``mpsd-<12 hex>-<8 hex>`` (a measured PSD: the file's
    SHA-256 and the hash of the import options). The file's name and folder do
    not enter; its content does, so a changed table regenerates the surfaces.
    """
    kind, tag = spectrum["kind"], SPECTRUM_TAGS[spectrum["kind"]]
    if kind == "self-affine":
        return f"{tag}-{hashlib.sha256(canonical_json(spectrum).encode()).hexdigest()[:8]}"
    if kind == "table":
        return f"{tag}-{spectrum['file_sha256'][:12]}"
    options = {k: v for k, v in spectrum.items() if k not in ("file", "file_sha256")}
    digest = hashlib.sha256(canonical_json(options).encode()).hexdigest()[:8]
    return f"{tag}-{spectrum['file_sha256'][:12]}-{digest}"


def spectrum_fields(spectrum: dict) -> dict:
    """:class:`SurfaceSpec` fields of a spectrum (:func:`spectrum_params`), in SI units.

    ``acf="self-affine"`` with its wavelengths in metres, or ``acf="psd"``
    with the table (q [1/m], C) of the file. Raises
    :class:`~roughcontact.errors.MeasurementError` if the file's content is
    no longer the one planned (``file_sha256``).
    """
    if spectrum["kind"] == "self-affine":
        return {"acf": "self-affine", "hurst": spectrum["hurst"],
                "rolloff_wavelength": spectrum["rolloff_mm"] * MM,
                "cutoff_wavelength": spectrum["cutoff_mm"] * MM}
    path = spectrum["file"]
    if spectrum["kind"] == "table":
        sha, table = _psd_file(path, _stamp(path))
    else:
        options = {k: v for k, v in spectrum.items() if k not in ("kind", "file_sha256")}
        sha, table = _measured_psd(canonical_json(options), _stamp(path))
    if sha != spectrum["file_sha256"]:
        raise MeasurementError(
            f"{path}: the spectrum's file changed after the workflow was planned (sha256 "
            f"{sha[:12]}, planned {spectrum['file_sha256'][:12]}); run again", path)
    return {"acf": "psd", "psd": table}


@functools.lru_cache(maxsize=16)
def _psd_file(path: str, stamp) -> tuple[str, tuple]:
    """SHA-256 and table of a PSD table file, kept per content stamp."""
    table = measured.read_psd_table(path)
    return file_sha256(path), table


@functools.lru_cache(maxsize=16)
def _measured_psd(options_json: str, stamp) -> tuple[str, tuple]:
    """SHA-256 and isotropic PSD table of a measured file, kept per options and stamp."""
    measurement = _load_measured(options_json, stamp)
    return measurement.sha256, measured.psd_table_from_measurement(measurement)


def spectrum_file(spectrum: dict | None) -> str | None:
    """The file a spectrum is read from (an input of the jobs that use it), or None."""
    return None if spectrum is None else spectrum.get("file")


def _spectrum_entries(config: dict, names) -> list[tuple[str, dict]]:
    """``(where, entry)`` of the config's spectrum and of each named study's own."""
    entries = [("surfaces.spectrum", config["surfaces"].get("spectrum"))]
    for name in names:
        try:
            entry = resolve_source(config, name)
        except (KeyError, ValueError):
            continue  # check_studies names it
        if "spectrum" in entry:
            entries.append((f"{source_name(config, name)}.spectrum", entry["spectrum"]))
    return entries


def check_spectra(config: dict, names) -> list[str]:
    """Messages for spectra that cannot be used: a spectrum with padded surfaces
    (``periodic: false``), a file that is missing or not a valid PSD table."""
    problems = []
    for where, entry in dict(_spectrum_entries(config, names)).items():
        if entry is None or entry["kind"] == "acf":
            continue
        if not config["surfaces"]["periodic"]:
            problems.append(f"{where}: kind {entry['kind']} generates periodic surfaces only; "
                            "set surfaces.periodic: true or remove the spectrum")
            continue
        try:
            spectrum_fields(spectrum_params(entry))
        except (OSError, ValueError) as err:
            problems.append(f"{where}: {err}")
    return problems


def figure_cells(config: dict, figure: str) -> list[dict]:
    """Surface cells a figure needs, in the order it draws them."""
    defaults = config["surfaces"]
    fig = config["figures"][figure]
    if figure == "fig03":
        return [
            cell_params(defaults, b_mm=b, skew=0.0, kurt=3.0, count=fig["count"])
            for b in fig["b_mm"]
        ]
    if figure == "fig10":  # the cumulative height distributions of the Fig 9 surfaces
        return [c["surface"] for c in contact_cells(config, "fig10")]
    if figure == "measured":  # the measured surface and its twin, once each
        unique = {c["surface_key"]: c["surface"] for c in contact_cells(config, figure)}
        return list(unique.values())
    if figure in ("fig04", "fig05"):
        src = config["figures"]["fig04"]
        return [
            cell_params(defaults, b_mm=src["b_mm"], skew=sk, kurt=ku)
            for sk, ku in src["moments"]
        ]
    return []


def surface_cells(config: dict, figures=SURFACE_FIGURES) -> dict[str, dict]:
    """All surface cells the requested figures need, keyed by :func:`cell_key`."""
    cells = {}
    for fig in figures:
        if fig in config.get("figures", {}):
            for params in figure_cells(config, fig):
                cells[cell_key(params)] = params
    return cells


#: A calibrated cell whose target kurtosis lies within this fraction of
#: (Ku - 1) above the filter's bound (Eq 15) is calibrated at plan time: the
#: window's sample bias (a few per cent) may carry it across the bound.
NEAR_BOUND = 0.1


def _check_calibrated(spec: SurfaceSpec) -> None:
    """Raise if the calibrated filter cannot reach ``spec``'s expected sample moments.

    Far inside the reachable region the process check (Eq 15) suffices; near
    its edge the calibration itself runs (about a second for 60 x 60).
    """
    try:
        bound = float(kurt_min(spec))
    except ValueError:
        bound = math.inf
    if spec.kurt >= bound + NEAR_BOUND * (spec.kurt - 1.0):
        johnson.fit(*input_moments(spec))
        return
    calibrate_filter(spec)


def check_feasible(cells: dict[str, dict]) -> list[str]:
    """Messages for cells whose (skew, kurt) the generator cannot reach, and for any
    Johnson law the generator would fit that cannot be fitted (each law is fitted
    here, before any job: the white noise's of the filter, the target's of exact)."""
    problems = []
    for key, params in cells.items():
        if params["method"] == "measured":
            continue
        try:
            if "spectrum" in params:  # the table and the grid agree (power on the grid)
                filter_kernel(spec_from_params(params))
            if params["method"] == "paper":
                johnson.fit(*input_moments(spec_from_params(params)))
            elif params["method"] == "filter":
                _check_calibrated(spec_from_params(params))
            else:
                johnson.fit(params["skew"], params["kurt"])
        except (ValueError, RuntimeError, FloatingPointError) as err:
            problems.append(f"{key}: {err}")
    return problems


# ---------------------------------------------------------------------------
# Measured surfaces: a study's ``surface: {file: ...}`` in place of moments


def _round12(value: float) -> float:
    """``value`` to 12 significant digits (keys and labels free of rounding noise)."""
    return float(f"{value:.12g}")


def measured_options(entry: dict) -> dict:
    """Canonical import and preparation options of a study's validated ``surface:``
    entry (lengths in mm; the schema's keys, None where not given)."""
    spacing, crop = entry.get("spacing_mm"), entry.get("crop_mm")
    grid = entry.get("resample_grid")
    return {
        "file": str(entry["file"]),
        "format": str(entry["format"]),
        "height_unit": entry.get("height_unit"),
        "lateral_unit": str(entry["lateral_unit"]),
        "spacing_mm": None if spacing is None else [float(v) for v in _pair(spacing)],
        "fill_holes": float(entry["fill_holes"]),
        "channel": entry.get("channel"),
        "decimal": str(entry["decimal"]),
        "crop_mm": None if crop is None else [float(v) for v in crop],
        "form_degree": int(entry["form_degree"]),
        "outliers_sigma": (None if entry.get("outliers_sigma") is None
                           else float(entry["outliers_sigma"])),
        "decimate": None if entry.get("decimate") is None else int(entry["decimate"]),
        "resample_grid": None if grid is None else [int(v) for v in _pair(grid)],
    }


def load_measured(options: dict) -> measured.Measurement:
    """Import and prepare the measurement that :func:`measured_options` describe (mm to m).

    Kept per file content and options for the life of the process: the workflow
    plans from it several times.
    """
    return _load_measured(canonical_json(options), _stamp(options["file"]))


def _stamp(path) -> tuple | None:
    """Modification time and size of a file: a changed file is loaded again."""
    try:
        stat = Path(path).stat()
    except OSError:
        return None  # load_measurement says the file is missing
    return (stat.st_mtime_ns, stat.st_size)


@functools.lru_cache(maxsize=16)
def _measured_statistics(options_json: str, stamp) -> dict:
    """:func:`roughcontact.surfaces.measured.statistics` of a loaded measurement, kept
    like the measurement (the plan reads every measured cell several times)."""
    return measured.statistics(_load_measured(options_json, stamp))


@functools.lru_cache(maxsize=16)
def _load_measured(options_json: str, stamp) -> measured.Measurement:
    options = json.loads(options_json)
    spacing, crop = options["spacing_mm"], options["crop_mm"]
    return measured.load_measurement(
        options["file"], options["format"], height_unit=options["height_unit"],
        lateral_unit=options["lateral_unit"],
        spacing=None if spacing is None else tuple(v * MM for v in spacing),
        fill_holes=options["fill_holes"], channel=options["channel"],
        decimal=options["decimal"],
        crop=None if crop is None else tuple(v * MM for v in crop),
        form_degree=options["form_degree"], outliers_sigma=options["outliers_sigma"],
        decimate_by=options["decimate"], resample_grid=options["resample_grid"],
    )


def measured_cell_params(entry: dict) -> dict:
    """Surface-cell parameters of a measured surface, read from its file.

    The file is imported here (milliseconds for the grids a dense influence
    matrix allows), so the cell knows its content hash (for its key), its
    grid and plan size (for its geometry) and its statistics: ``skew``,
    ``kurt`` and ``b_mm`` are the measured values (the labels of its results
    and the targets of a synthetic twin), ``count`` is 1 and ``method`` is
    ``"measured"``. ``measured`` holds the import options, the file's SHA-256
    and the measured sigma [um]. Relative paths are relative to the working
    directory (Snakemake's ``--directory``).
    """
    options = measured_options(entry)
    measurement = load_measured(options)
    stats = _measured_statistics(canonical_json(options), _stamp(options["file"]))
    return {
        "skew": _round12(stats["skew"]),
        "kurt": _round12(stats["kurt"]),
        "b_mm": [_round12(stats["corr_length_x"] / MM), _round12(stats["corr_length_y"] / MM)],
        "grid": [int(v) for v in stats["grid"]],
        "size_mm": [_round12(v / MM) for v in stats["size"]],
        "acf": "measured",
        "periodic": False,
        "method": "measured",
        "count": 1,
        "measured": {**options, "file_sha256": measurement.sha256,
                     "sigma_um": _round12(stats["sigma"] / UM)},
    }


def measured_key(params: dict) -> str:
    """Key of a measured cell: the file's name, a short hash of its content and of
    the import options (``measured-<stem>_<sha256[:12]>_<options[:8]>``).

    A changed file or option is a new key, so everything that depends on the
    surface is recomputed; the same content under another name or folder keeps
    the hashes.
    """
    info = params["measured"]
    stem = re.sub(r"[^A-Za-z0-9-]+", "-", Path(info["file"]).stem).strip("-")[:40]
    options = {k: v for k, v in info.items() if k not in ("file", "file_sha256", "sigma_um")}
    digest = hashlib.sha256(canonical_json(options).encode()).hexdigest()[:8]
    return f"measured-{stem or 'surface'}_{info['file_sha256'][:12]}_{digest}"


def synthetic_twin(defaults: dict, measured_cell: dict, count: int, **overrides) -> dict:
    """A generated cell with a measurement's Sk, Ku and correlation lengths.

    Same grid and plan size as the measurement; ACF shape (or spectrum),
    periodicity and generator are the config's ``surfaces`` defaults, or
    ``overrides`` (a study's ``spectrum``). Sigma is not part of a cell: both
    are scaled by the same sigma in the study.
    """
    return cell_params(defaults, skew=measured_cell["skew"], kurt=measured_cell["kurt"],
                       b_mm=measured_cell["b_mm"], grid=measured_cell["grid"],
                       size_mm=measured_cell["size_mm"], count=count, **overrides)


def _study_overrides(entry: dict) -> dict:
    """Surface settings a study may set for its generated cells: its ``spectrum``."""
    return {"spectrum": entry["spectrum"]} if "spectrum" in entry else {}


def study_surfaces(config: dict, entry: dict) -> list[dict]:
    """Surface cells of a study that names a measured surface.

    The measurement, then, with ``compare_synthetic: true``, its
    :func:`synthetic_twin` with the study's (or the config's) surface count
    and spectrum.
    """
    measured_cell = measured_cell_params(entry["surface"])
    cells = [measured_cell]
    if entry.get("compare_synthetic", False):
        count = entry.get("count", config["surfaces"]["count"])
        cells.append(synthetic_twin(config["surfaces"], measured_cell, count,
                                    **_study_overrides(entry)))
    return cells


def check_measured(config: dict, name: str, entry: dict) -> list[str]:
    """Messages for a study whose measured surface cannot be used as configured."""
    if "surface" not in entry:
        if entry.get("compare_synthetic"):
            return [f"{name}: compare_synthetic needs a measured surface ('surface:')"]
        return []
    if "spectrum" in entry and not entry.get("compare_synthetic"):
        return [f"{name}: 'spectrum' applies to the generated twin of a measured surface; "
                "add compare_synthetic: true or remove spectrum"]
    clashing = [k for k in ("moments", "b_mm", "size_mm") if k in entry]
    if clashing:
        return [f"{name}: 'surface' (a measured surface) fixes the statistics, grid and "
                f"size; remove {', '.join(clashing)}"]
    try:
        cells = study_surfaces(config, entry)
    except (OSError, ValueError) as err:
        return [f"{name}.surface: {err}"]
    b_mm = cells[0]["b_mm"]
    if len(cells) > 1 and not all(math.isfinite(b) for b in b_mm):
        return [f"{name}: the measured autocorrelation does not decay to 10 % within half "
                f"the measured length (b = {b_mm[0]:g} x {b_mm[1]:g} mm), so no synthetic "
                "twin can be made; remove the form (surface.form_degree: 2 or more), measure "
                "or crop a larger area, or drop compare_synthetic"]
    return []


# ---------------------------------------------------------------------------
# Influence geometries: the elastic body a contact cell is solved on


def geometry_params(body: dict, surfaces: dict, **overrides) -> dict:
    """Complete, canonical parameters of one influence geometry.

    ``body`` is the config's ``body`` section, ``surfaces`` its ``surfaces``
    section (the contact grid and plan size are the surfaces'); ``overrides``
    may set ``nu``, ``mesh``, ``size_mm``, ``grid`` and any body key. Young's
    modulus is not part of a geometry: matrices are stored as E * C.
    """
    merged = {**body, "grid": surfaces["grid"], "size_mm": surfaces["size_mm"], **overrides}
    params = {
        "nu": float(merged["nu"]),
        "size_mm": [float(v) for v in _pair(merged["size_mm"])],
        "thickness_mm": float(merged["thickness_mm"]),
        "grid": [int(v) for v in _pair(merged["grid"])],
        "base": str(merged["base"]),
        "mesh": str(merged["mesh"]),
    }
    # the influence model; the dense matrix (the paper's) adds no key, so its files keep
    # their names
    operator = str(merged["operator"])
    if operator != "dense":
        params["operator"] = operator
    if operator == "auto":
        params["halfspace_tolerance"] = {k: (None if v is None else float(v))
                                         for k, v in sorted(merged["halfspace_tolerance"].items())}
    return params


def geometry_key(params: dict) -> str:
    """File key of an influence geometry (every parameter that changes E * C)."""
    lx, ly = params["size_mm"]
    nx, ny = params["grid"]
    key = (
        f"nu{params['nu']:g}_L{lx:g}x{ly:g}mm_t{params['thickness_mm']:g}mm"
        f"_g{nx}x{ny}_{params['base']}_{params['mesh']}"
    )
    operator = params.get("operator", "dense")
    if operator == "auto":
        tolerance = "-".join("x" if v is None else f"{v:g}"
                             for _, v in sorted(params["halfspace_tolerance"].items()))
        return f"{key}_auto{tolerance}"
    return key if operator == "dense" else f"{key}_{operator}"


def block_geometry(params: dict, E: float = 1.0):
    """The :class:`~roughcontact.influence.BlockGeometry` of a geometry (mm to m)."""
    return BlockGeometry(
        size=tuple(v * MM for v in params["size_mm"]),
        thickness=params["thickness_mm"] * MM,
        grid=tuple(params["grid"]),
        E=E,
        nu=params["nu"],
        base=params["base"],
        mesh=params["mesh"],
    )


def influence_geometries(config: dict) -> dict[str, dict]:
    """The influence geometries the configuration asks for besides its contact jobs'.

    The mesh-convergence report (when configured) compares its presets on the
    body of the config and reuses their builds; the contact jobs add the
    geometries they solve on (:func:`study_plan`). Nothing else is built: a
    body that no study and no report uses costs nothing.
    """
    geoms = {}
    params = geometry_params(config["body"], config["surfaces"])
    for mesh in convergence_presets(config):
        variant = {**params, "mesh": mesh}
        geoms[geometry_key(variant)] = variant
    return geoms


def convergence_presets(config: dict) -> list[str]:
    """Mesh presets of the influence-convergence report ([] when it is not configured)."""
    report = config["reports"].get("influence_convergence")
    return [] if report is None else list(report["presets"])


def coarse_geometry(geom):
    """The coarse finite-element model of a hybrid operator (``refined`` for inaccurate meshes)."""
    mesh = geom.mesh if geom.mesh in HYBRID_MESHES else "refined"
    return dataclasses.replace(geom, grid=default_coarse_grid(geom.grid), mesh=mesh)


def planned_operator(params: dict, max_memory_gb: float) -> str:
    """The influence model a geometry's build starts with: "dense", "hybrid" or "halfspace".

    ``operator: auto`` picks dense or hybrid here (by size and memory,
    :func:`roughcontact.elasticity.operators.choose_operator`); the build may then
    replace either by the half-space when the measured criterion allows.
    """
    operator = params.get("operator", "dense")  # a dense geometry's key has no operator
    if operator != "auto":
        return operator
    return choose_operator(block_geometry(params), max_dense_bytes=max_memory_gb * GB)


def influence_cost(params: dict, solver: str, max_memory_gb: float):
    """:class:`~roughcontact.influence.CostEstimate` of the finite-element model a build
    solves with ``solver``, planned within ``max_memory_gb`` (the config's ``body``)."""
    geom = block_geometry(params)
    if planned_operator(params, max_memory_gb) in ("hybrid", "halfspace"):
        geom = coarse_geometry(geom)
    return estimate_cost(geom, solver)


# ---------------------------------------------------------------------------
# Contact study cells: surfaces x geometry x (sigma, E) x pressure range

#: Figures drawn from contact results, and the source of their cells ("measured": a
#: measured surface against its synthetic twin, usually ``from:`` a sweep).
CONTACT_FIGURES = ("fig07", "fig09", "fig10", "fig11", "fig12", "fig13", "fig14", "table_Eu",
                   "hardness", "measured")


def _as_list(value) -> list:
    return list(value) if isinstance(value, list | tuple) else [value]


def source_name(config: dict, name: str) -> str:
    """The figure or sweep whose cells ``name`` uses (itself unless ``from:``)."""
    section = {**config["figures"], **config["sweeps"]}
    seen = [name]
    while "from" in section[name]:
        source = section[name]["from"]
        if source in seen or source not in section:
            raise ValueError(f"{seen[0]}: 'from: {source}' must name another figure or sweep "
                             f"without a cycle (followed {' -> '.join(seen)})")
        seen.append(source)
        name = source
    return name


def resolve_source(config: dict, name: str) -> dict:
    """A figure's (or sweep's) cell description, following ``from: other``."""
    section = {**config["figures"], **config["sweeps"]}
    return section[source_name(config, name)]


def accuracy_preset(config: dict) -> dict | None:
    """The accuracy preset the config names (``accuracy: paper|fast|converged``), or None."""
    name = config.get("accuracy")
    if name is None:
        return None
    return dict(ACCURACY_PRESETS[name])


def accuracy_attrs(config: dict) -> dict:
    """``accuracy`` and the preset's measured ``expected_error`` for a cell's records."""
    preset = accuracy_preset(config)
    if preset is None:
        return {"accuracy": "as configured"}
    errors = {k: v for k, v in preset.items() if k.endswith("_error") or
              k.startswith(("grid_change_", "sampling_"))}
    return {"accuracy": config["accuracy"], "expected_error": errors}


def contact_settings(config: dict) -> dict:
    """The solver settings of the contact jobs: the config's, or the accuracy preset's.

    ``cap`` is left out: it decides which cells are capped, and a capped job
    carries its own cap (:func:`contact_jobs`).
    """
    settings = {k: v for k, v in config["contact"].items() if k != "cap"}
    preset = accuracy_preset(config)
    if preset is not None:
        settings.update(method=preset["method"], tol=preset["tol"],
                        precision=preset["precision"])
    return settings


def contact_cells(config: dict, name: str) -> list[dict]:
    """The study cells of a contact figure or sweep: the product of its axes.

    Axes (scalars or lists): ``moments`` (pairs of Sk, Ku), ``b_mm``,
    ``size_mm`` (square nominal areas; the grid keeps the surfaces' spacing),
    ``nu``, ``meshes``, ``sigma_um``, ``E_MPa``; ``count`` and
    ``pressure_MPa`` ([P_min, P_max]) apply to every cell. Each cell carries
    its surface cell, its geometry and the scaling parameters. A study that
    names a measured surface (``surface:``) has the cells of
    :func:`measured_study_cells` instead.
    """
    fig = resolve_source(config, name)
    surfaces, body = config["surfaces"], config["body"]
    preset = accuracy_preset(config)
    if preset is not None:  # the preset's mesh and count unless the figure names its own
        body = {**body, "mesh": preset["mesh"]}
        fig = {"count": preset["surfaces"], **fig}
    if "surface" in fig:
        return with_hardness(config, fig, measured_study_cells(config, fig, body))
    spacing = [s / g for s, g in zip(_pair(surfaces["size_mm"]), _pair(surfaces["grid"]),
                                     strict=True)]
    cells = []
    for mesh in _as_list(fig.get("meshes", body["mesh"])):
        for nu in _as_list(fig.get("nu", body["nu"])):
            sizes = ([[s, s] for s in _as_list(fig["size_mm"])] if "size_mm" in fig
                     else [_pair(surfaces["size_mm"])])
            for size in sizes:
                grid = [max(4, round(s / h)) for s, h in zip(size, spacing, strict=True)]
                for b in _as_list(fig.get("b_mm", 1.0)):
                    for skew, kurt in fig.get("moments", [[0.0, 3.0]]):
                        for sigma in _as_list(fig["sigma_um"]):
                            for E in _as_list(fig.get("E_MPa", body["E_MPa"])):
                                surf = cell_params(
                                    surfaces, skew=skew, kurt=kurt, b_mm=b,
                                    size_mm=size, grid=grid,
                                    count=fig.get("count", surfaces["count"]),
                                    **_study_overrides(fig),
                                )
                                geom = geometry_params(body, surfaces, nu=nu, mesh=mesh,
                                                       size_mm=size, grid=grid)
                                cells.append(_study_cell(config, fig, surf, geom, sigma, E))
    return with_hardness(config, fig, cells)


def hardness_settings(config: dict, fig: dict) -> tuple[list[float], object, float]:
    """A study's hardness values [MPa], cap setting (False, True, "both") and threshold.

    The study's own ``hardness_MPa`` and ``cap`` replace ``body.hardness_MPa``
    and ``contact.cap``.
    """
    value = fig.get("hardness_MPa", config["body"]["hardness_MPa"])
    values = [] if value is None else [float(v) for v in _as_list(value)]
    cap = fig.get("cap", config["contact"]["cap"])
    return values, cap, float(config["body"]["hardness_threshold"])


def with_hardness(config: dict, fig: dict, cells: list[dict]) -> list[dict]:
    """The cells of a study with its hardness (:func:`hardness_settings`).

    Without a hardness the cells are unchanged. With one, every elastic cell
    carries ``hardness_MPa`` (the values its elastic results are checked
    against: no extra solve) and ``hardness_threshold``; ``cap: true``
    replaces each cell by one capped cell per hardness (``cap_MPa``: solved
    with 0 <= p <= H), ``cap: both`` adds those beside the elastic cells.
    """
    values, cap, threshold = hardness_settings(config, fig)
    if not values:
        return cells
    elastic = [{**cell, "hardness_MPa": values, "hardness_threshold": threshold}
               for cell in cells]
    capped = [{**cell, "cap_MPa": H} for cell in cells for H in values] if cap else []
    return capped if cap is True else elastic + capped


def cap_value(cell: dict) -> float | None:
    """The dimensionless cap ``H L / (E sigma)`` of a capped cell (None: elastic)."""
    if cell.get("cap_MPa") is None:
        return None
    return nondim_pressure(cell["cap_MPa"] * MPA, thickness=cell["geometry"]["thickness_mm"] * MM,
                           E=cell["E_MPa"] * MPA, sigma=cell["sigma_um"] * UM)


def _study_cell(config: dict, fig: dict, surf: dict, geom: dict, sigma, E) -> dict:
    return {
        "surface": surf,
        "geometry": geom,
        "sigma_um": float(sigma),
        "E_MPa": float(E),
        "pressure_MPa": [float(p) for p in fig["pressure_MPa"]],
        "surface_key": cell_key(surf),
        "geometry_key": geometry_key(geom),
        **accuracy_attrs(config),
    }


def measured_study_cells(config: dict, fig: dict, body: dict) -> list[dict]:
    """The cells of a study on a measured surface (and its synthetic twin).

    Axes: ``meshes``, ``nu``, ``sigma_um`` (default: the measured sigma, so
    the results are those of the measured heights; another value rescales
    both surfaces) and ``E_MPa``. The geometry's grid and plan size are the
    measurement's, as the surfaces' are for generated cells; the measured
    cell comes first, its twin (``compare_synthetic``) second.
    """
    surface_cells_ = study_surfaces(config, fig)
    first = surface_cells_[0]
    cells = []
    for mesh in _as_list(fig.get("meshes", body["mesh"])):
        for nu in _as_list(fig.get("nu", body["nu"])):
            geom = geometry_params(body, config["surfaces"], nu=nu, mesh=mesh,
                                   size_mm=first["size_mm"], grid=first["grid"])
            for surf in surface_cells_:
                for sigma in _as_list(fig.get("sigma_um", first["measured"]["sigma_um"])):
                    for E in _as_list(fig.get("E_MPa", body["E_MPa"])):
                        cells.append(_study_cell(config, fig, surf, geom, sigma, E))
    return cells


def check_studies(config: dict, names) -> list[str]:
    """Messages for contact figures or sweeps the schema cannot check."""
    problems = []
    for name in names:
        try:
            entry = resolve_source(config, name)
        except (KeyError, ValueError) as err:
            problems.append(f"{name}: {err}")
            continue
        low, high = entry["pressure_MPa"]
        if not low < high:
            problems.append(f"{name}.pressure_MPa = [{low}, {high}]: expected [P_min, P_max] "
                            f"with P_min < P_max (MPa)")
        problems += check_measured(config, name, entry)
        problems += _check_operator(config, name, entry)
        values, cap, _ = hardness_settings(config, entry)
        if name == "hardness" and (not values or cap != "both"):
            problems.append(f"{name}: the hardness figure compares elastic and capped cells; "
                            f"give it hardness_MPa (a hardness [MPa]) and cap: both")
        elif cap and not values:
            problems.append(f"{name}: contact.cap = {cap!r} but no hardness is given; set "
                            f"body.hardness_MPa (or the study's hardness_MPa) to the hardness "
                            f"[MPa] to cap the pressure at, or cap: false")
    return problems


def _check_operator(config: dict, name: str, entry: dict) -> list[str]:
    """The hybrid operator needs a coarse model with an accurate near field."""
    if config["body"]["operator"] != "hybrid":
        return []
    preset = accuracy_preset(config)
    default = preset["mesh"] if preset else config["body"]["mesh"]
    bad = [m for m in _as_list(entry.get("meshes", default)) if m not in HYBRID_MESHES]
    if not bad:
        return []
    return [f"{name}: body.operator = hybrid with mesh {bad[0]!r}: the hybrid operator takes "
            f"its finite-body correction from a coarse model whose near field must be "
            f"accurate, so the mesh must be one of {list(HYBRID_MESHES)}; use operator: "
            f"dense (the paper's model) or auto (dense up to 64 x 64, hybrid with a "
            f"'refined' coarse model above)"]


def contact_key(cell: dict) -> str:
    """File key of a contact job: one surface cell solved on one geometry to one sweep end.

    The end (:func:`sweep_end`, a power of 2 of P L / (E sigma)) is part of the
    key: a file's content depends on its key alone, so a study that needs a
    longer sweep gets its own file, and no result is ever re-solved or
    rewritten because another study was added, changed or removed. A capped
    cell's key ends with its cap ``H L / (E sigma)`` (:func:`cap_value`): with a
    cap, sigma and E no longer only rescale the solution, so cells that differ
    in it are solved apart.
    """
    end = cell["pressure_end"] if "pressure_end" in cell else sweep_end(cell)
    key = f"{cell['surface_key']}__{cell['geometry_key']}__end{end:g}"
    cap = cell["hardness"] if "hardness" in cell else cap_value(cell)
    # 7 digits: cells whose caps agree to 1e-6 share a job (to_physical allows 1e-5)
    return key if cap is None else f"{key}__cap{cap:.7g}"


def sweep_end(cell: dict) -> float:
    """Non-dimensional nominal pressure P L / (E sigma) a cell needs, rounded up to 2^k.

    Rounding keeps a small change of sigma, E or the pressure range from
    re-solving a contact job that already reaches far enough.
    """
    value = nondim_pressure(cell["pressure_MPa"][1] * MPA,
                            thickness=cell["geometry"]["thickness_mm"] * MM,
                            E=cell["E_MPa"] * MPA, sigma=cell["sigma_um"] * UM)
    return float(2.0 ** np.ceil(np.log2(value)))


def contact_jobs(config: dict, names) -> dict[str, dict]:
    """Every contact job the named figures and sweeps need, with its sweep end.

    A job is shared by every cell on the same surfaces and geometry that needs
    the same sweep end (:func:`contact_key`).
    """
    jobs = {}
    for name in names:
        for cell in contact_cells(config, name):
            job = {
                "surface": cell["surface"], "geometry": cell["geometry"],
                "surface_key": cell["surface_key"], "geometry_key": cell["geometry_key"],
                "pressure_end": sweep_end(cell),
                "accuracy": cell.get("accuracy", "as configured"),
                "expected_error": cell.get("expected_error", {}),
            }
            if cell.get("cap_MPa") is not None:
                job["hardness"] = cap_value(cell)
            jobs.setdefault(contact_key(cell), job)
    return jobs


class ConfigProblems(ValueError):
    """The configuration passed the schema but asks for something that cannot be
    run; ``problems`` lists one message per offending entry."""

    def __init__(self, title: str, problems: list[str]):
        super().__init__(f"{title} (no job was started):\n  " + "\n  ".join(problems))
        self.problems = problems


@dataclasses.dataclass(frozen=True)
class StudyPlan:
    """Everything a validated configuration asks the workflow to make.

    ``figures`` in drawing order; ``studies`` the contact figures and the
    user's sweeps; ``jobs``, ``cells`` and ``geometries`` by file key
    (:func:`contact_jobs`, :func:`surface_cells`, :func:`influence_geometries`
    plus those of the jobs); ``aggregates`` the studies whose cells are
    aggregated (a study ``from:`` another reuses its aggregates).
    """

    figures: list[str]
    studies: list[str]
    jobs: dict[str, dict]
    cells: dict[str, dict]
    geometries: dict[str, dict]
    aggregates: list[str]


def study_plan(config: dict) -> StudyPlan:
    """The :class:`StudyPlan` of a validated ``config``.

    Raises :class:`ConfigProblems` naming every invalid contact study or
    infeasible surface cell, before any job is planned to run.
    """
    figures = [n for n in (*SURFACE_ONLY_FIGURES, *CONTACT_FIGURES) if n in config["figures"]]
    studies = [n for n in figures if n in CONTACT_FIGURES] + list(config["sweeps"])
    spectra = check_spectra(config, studies)
    if spectra:
        raise ConfigProblems("Spectra that cannot be used", spectra)
    bad = check_studies(config, studies)
    if bad:
        raise ConfigProblems("Invalid contact studies in the config", bad)
    if config["plausibility_check"]:
        implausible = check_plausible(config, studies)
        if implausible:
            raise ConfigProblems("Values that are almost surely a unit slip (set "
                                 "plausibility_check: false if they are meant)", implausible)
    jobs = contact_jobs(config, studies)
    cells = surface_cells(config) | {job["surface_key"]: job["surface"] for job in jobs.values()}
    infeasible = check_feasible(cells)
    if infeasible:
        raise ConfigProblems("Infeasible surface cells in the config", infeasible)
    geometries = influence_geometries(config) | {job["geometry_key"]: job["geometry"]
                                                 for job in jobs.values()}
    too_large = check_memory(geometries, config["body"])
    if too_large:
        raise ConfigProblems("Influence models that do not fit body.max_memory_gb", too_large)
    aggregates = sorted({source_name(config, name) for name in studies})
    return StudyPlan(figures, studies, jobs, cells, geometries, aggregates)


#: Accepted ranges of the plausibility check: sigma [um], E [MPa], and the largest
#: nominal pressure over E of a sweep (beyond it linear elasticity has no meaning).
PLAUSIBLE = {"sigma_um": (1e-3, 1e3), "E_MPa": (1e-3, 1e7), "pressure_over_E": 0.1}
#: Units a value is likely typed in by mistake: name, factor to the key's unit.
_SLIPS = {"sigma_um": (("m", 1e6), ("mm", 1e3), ("nm", 1e-3)),
          "E_MPa": (("Pa", 1e-6), ("kPa", 1e-3), ("GPa", 1e3))}


def _slip(key: str, value: float) -> str:
    """A sentence naming the unit ``value`` was likely typed in, if one puts it in range."""
    low, high = PLAUSIBLE[key]
    for unit, factor in _SLIPS[key]:
        if low <= value * factor <= high:
            return (f"; typed in {unit}? then write {value * factor:.6g} "
                    f"({key.split('_')[-1]})")
    return ""


def check_plausible(config: dict, names) -> list[str]:
    """Messages for study values that are almost surely a unit slip (:data:`PLAUSIBLE`)."""
    problems = set()
    for name in names:
        for cell in contact_cells(config, name):
            for key in ("sigma_um", "E_MPa"):
                value = float(cell[key])
                low, high = PLAUSIBLE[key]
                if not low <= value <= high:
                    problems.add(f"{name}: {key} = {value:g} lies outside {low:g}-{high:g}"
                                 f"{_slip(key, value)}")
            ratio = cell["pressure_MPa"][1] / cell["E_MPa"]
            if ratio > PLAUSIBLE["pressure_over_E"]:
                problems.add(
                    f"{name}: pressure_MPa up to {cell['pressure_MPa'][1]:g} on E_MPa = "
                    f"{cell['E_MPa']:g} is P / E = {ratio:.3g}, beyond "
                    f"{PLAUSIBLE['pressure_over_E']:g}, where the linear elastic model has no "
                    "meaning; check the units of pressure_MPa and E_MPa")
    return sorted(problems)


def memory_message(key: str, params: dict, body: dict, peak_bytes: float) -> str:
    """Why a geometry's influence build does not fit, and the config keys that change it."""
    nx, ny = params["grid"]
    operator = planned_operator(params, body["max_memory_gb"])
    options = []
    if operator == "dense":
        auto = influence_cost({**params, "operator": "auto"}, body["solver"],
                              body["max_memory_gb"]).peak_bytes
        options.append(f"body.operator: auto (matrix-free above 64 x 64 elements: about "
                       f"{auto / GB:.3g} GB here)")
    options += [f"raise body.max_memory_gb (now {body['max_memory_gb']:g})",
                "a coarser body.mesh or a smaller grid (surfaces.grid; for a measured surface "
                "surface.crop_mm, surface.decimate or surface.resample_grid)"]
    return (f"influence geometry {key}: {nx} x {ny} elements, operator {operator}, mesh "
            f"{params['mesh']}: estimated peak memory {peak_bytes / GB:.3g} GB, more than "
            f"body.max_memory_gb = {body['max_memory_gb']:g} GB. Options: "
            + "; ".join(options))


def check_memory(geometries: dict[str, dict], body: dict) -> list[str]:
    """Messages for the influence builds whose estimated peak memory exceeds the
    validated ``body``'s ``max_memory_gb`` (checked when the plan is made)."""
    problems = []
    for key, params in geometries.items():
        peak = influence_cost(params, body["solver"], body["max_memory_gb"]).peak_bytes
        if peak > body["max_memory_gb"] * GB:
            problems.append(memory_message(key, params, body, peak))
    return problems
