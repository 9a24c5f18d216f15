"""The study grid: which surface cells a configuration asks for, and building them.

A *surface cell* is one set of surface statistics and sampling (skewness,
kurtosis, correlation lengths, grid, size, ACF, periodicity, generator) with a
number of seeded realisations. Its key names every parameter, so a changed
parameter is a new file and the workflow reruns exactly what depends on it.
Sigma is not part of a cell: surfaces are stored in units of sigma and scaled
at use (Eq 28-32 of Kumar et al. 2006).
"""

from __future__ import annotations

import dataclasses
import hashlib
import logging
import math
import re
import time
from pathlib import Path

import numpy as np

from . import johnson, measured
from .errors import MeasurementError
from .provenance import canonical_json, provenance
from .storage import write_h5
from .surface import (
    SurfaceSpec,
    correlation_length,
    derive_seeds,
    filter_kernel,
    generate_exact,
    generate_many,
    height_stats,
    input_moments,
    moment_transfer,
)

log = logging.getLogger(__name__)

MM = 1e-3
UM = 1e-6

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
    ``skew``, ``kurt``, ``b_mm``, ``count`` and any default.
    """
    merged = {**defaults, **overrides}
    return {
        "skew": float(merged.get("skew", 0.0)),
        "kurt": float(merged.get("kurt", 3.0)),
        "b_mm": [float(v) for v in _pair(merged["b_mm"])],
        "grid": [int(v) for v in _pair(merged["grid"])],
        "size_mm": [float(v) for v in _pair(merged["size_mm"])],
        "acf": str(merged.get("acf", "exponential")),
        "periodic": bool(merged.get("periodic", True)),
        "method": str(merged.get("method", "filter")),
        "count": int(merged["count"]),
    }


def statistics_key(params: dict) -> str:
    """Key of a cell's statistics and sampling, without the surface count.

    Seeds derive from this key, so the first k surfaces of a cell are the same
    whatever the count. A measured cell's key is :func:`measured_key`.
    """
    if params["method"] == "measured":
        return measured_key(params)
    bx, by = params["b_mm"]
    lx, ly = params["size_mm"]
    nx, ny = params["grid"]
    return (
        f"sk{params['skew']:g}_ku{params['kurt']:g}_b{bx:g}x{by:g}mm_L{lx:g}x{ly:g}mm"
        f"_g{nx}x{ny}_{params['acf'][:3]}_{'per' if params['periodic'] else 'pad'}"
        f"_{params['method']}"
    )


def cell_key(params: dict) -> str:
    """File key of a surface cell: its statistics key and the surface count."""
    return f"{statistics_key(params)}_n{params['count']}"


def spec_from_params(params: dict, sigma: float = 1.0) -> SurfaceSpec:
    """The :class:`SurfaceSpec` of a cell (lengths converted from mm to m)."""
    return SurfaceSpec(
        grid=tuple(params["grid"]),
        size=tuple(v * MM for v in params["size_mm"]),
        corr_length=tuple(v * MM for v in params["b_mm"]),
        sigma=sigma,
        skew=params["skew"],
        kurt=params["kurt"],
        acf=params["acf"],
        periodic=params["periodic"],
    )


def figure_cells(config: dict, figure: str) -> list[dict]:
    """Surface cells a figure needs, in the order it draws them."""
    defaults = config["surfaces"]
    fig = config["figures"][figure]
    if figure == "fig03":
        return [
            cell_params(defaults, b_mm=b, skew=0.0, kurt=3.0, count=fig.get("count", 1))
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


def check_feasible(cells: dict[str, dict]) -> list[str]:
    """Messages for cells whose (skew, kurt) the filter cannot reach."""
    problems = []
    for key, params in cells.items():
        if params["method"] != "filter":
            continue
        try:
            input_moments(spec_from_params(params))
        except ValueError as err:
            problems.append(f"{key}: {err}")
    return problems


def build_surface_cell(params: dict, study_seed: int, path, config=None) -> dict:
    """Generate a cell's surfaces and write them, with statistics, to ``path``.

    Heights are stored in units of sigma (dimensionless, zero mean per
    surface); realised moments (Eq 2-5) and 10 % ACF lags [m] per surface;
    the filter's transfer factors and the fitted Johnson curve of the white
    noise as attributes, with provenance. Returns the root attributes.
    A measured cell (``method: measured``) is imported by
    :func:`build_measured_cell` instead.
    """
    if params["method"] == "measured":
        return build_measured_cell(params, study_seed, path, config)
    start = time.perf_counter()
    spec = spec_from_params(params)
    seeds = derive_seeds(study_seed, statistics_key(params), params["count"])
    attrs = {"cell": cell_key(params), "study_seed": int(study_seed), "method": params["method"]}
    extra = {}
    if params["method"] == "filter":
        kern = filter_kernel(spec)
        s3, s4 = moment_transfer(spec)
        skew_x, kurt_x = input_moments(spec)
        curve = johnson.fit(skew_x, kurt_x)
        attrs |= {
            "filter_S3": s3,
            "filter_S4": s4,
            "filter_clipped": kern.clipped,
            "input_skew": skew_x,
            "input_kurt": kurt_x,
            "johnson_family": curve.family,
            "johnson_params": [curve.gamma, curve.delta, curve.xi, curve.lam],
        }
        log.info(
            "cell %s: S3 = %.4f, S4 = %.4f, white noise Sk_x = %.4f, Ku_x = %.4f (%s)",
            attrs["cell"], s3, s4, skew_x, kurt_x, curve.family,
        )
        heights = generate_many(spec, seeds)
    else:
        results = [generate_exact(spec, s) for s in seeds]
        heights = np.stack([z for z, _ in results])
        extra["spectral_error"] = (
            np.array([r.spectral_error for _, r in results]),
            {"units": "1", "description": "relative L2 error of the Fourier amplitude"},
        )
        extra["converged"] = np.array([r.converged for _, r in results])
    stats = height_stats(heights)
    lags = np.array([correlation_length(z, spec.spacing, spec.periodic) for z in heights])
    log.info(
        "cell %s: %d surfaces in %.2f s; mean realised Sk %.3f (target %g), Ku %.3f (target %g)",
        attrs["cell"], len(seeds), time.perf_counter() - start,
        np.mean(stats["skew"]), params["skew"], np.mean(stats["kurt"]), params["kurt"],
    )
    unit = {"units": "1 (heights / sigma)"}
    datasets = {
        "heights": (heights, unit | {"layout": "(surface, y, x), row-major over y then x"}),
        "seeds": (seeds.astype(np.int64), {"generator": "numpy.random.default_rng(seed)"}),
        "stats/mean": (stats["mean"], unit),
        "stats/sigma": (stats["sigma"], unit),
        "stats/skew": (stats["skew"], {"units": "1"}),
        "stats/kurt": (stats["kurt"], {"units": "1 (Pearson, normal = 3)"}),
        "stats/corr_length_x": (lags[:, 0], {"units": "m"}),
        "stats/corr_length_y": (lags[:, 1], {"units": "m"}),
        **{f"stats/{k}": v for k, v in extra.items()},
    }
    attrs |= {
        "spec": canonical_json(spec.as_dict()),
        "params": canonical_json(params),
        **{f"spec_{k}": v for k, v in spec.as_dict().items()},
        **provenance(config),
    }
    write_h5(path, datasets, attrs)
    return attrs


# ---------------------------------------------------------------------------
# Measured surfaces: a study's ``surface: {file: ...}`` in place of moments


def _round12(value: float) -> float:
    """``value`` to 12 significant digits (keys and labels free of rounding noise)."""
    return float(f"{value:.12g}")


def measured_options(entry: dict) -> dict:
    """Canonical import options of a study's ``surface:`` entry (lengths in mm).

    Keys: ``file``, ``format`` (npy, text, xyz), ``height_unit`` (nm, um, mm,
    m), ``lateral_unit`` (um, mm, m; the x, y columns of xyz files),
    ``spacing_mm`` ([dx, dy] of npy and text grids, else None) and
    ``fill_holes`` (largest fraction of missing points filled).
    """
    spacing = entry.get("spacing_mm")
    return {
        "file": str(entry["file"]),
        "format": str(entry["format"]),
        "height_unit": str(entry["height_unit"]),
        "lateral_unit": str(entry.get("lateral_unit", "mm")),
        "spacing_mm": None if spacing is None else [float(v) for v in _pair(spacing)],
        "fill_holes": float(entry.get("fill_holes", 0.0)),
    }


def load_measured(options: dict) -> measured.Measurement:
    """Import the measurement that :func:`measured_options` describe (mm to m)."""
    spacing = options["spacing_mm"]
    return measured.load_measurement(
        options["file"], options["format"], height_unit=options["height_unit"],
        lateral_unit=options["lateral_unit"],
        spacing=None if spacing is None else tuple(v * MM for v in spacing),
        fill_holes=options["fill_holes"],
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
    stats = measured.statistics(measurement)
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


def synthetic_twin(defaults: dict, measured_cell: dict, count: int) -> dict:
    """A generated cell with a measurement's Sk, Ku and correlation lengths.

    Same grid and plan size as the measurement; ACF shape, periodicity and
    generator are the config's ``surfaces`` defaults. Sigma is not part of a
    cell: both are scaled by the same sigma in the study.
    """
    return cell_params(defaults, skew=measured_cell["skew"], kurt=measured_cell["kurt"],
                       b_mm=measured_cell["b_mm"], grid=measured_cell["grid"],
                       size_mm=measured_cell["size_mm"], count=count)


def study_surfaces(config: dict, entry: dict) -> list[dict]:
    """Surface cells of a study that names a measured surface.

    The measurement, then, with ``compare_synthetic: true``, its
    :func:`synthetic_twin` with the study's (or the config's) surface count.
    """
    measured_cell = measured_cell_params(entry["surface"])
    cells = [measured_cell]
    if entry.get("compare_synthetic", False):
        count = entry.get("count", config["surfaces"]["count"])
        cells.append(synthetic_twin(config["surfaces"], measured_cell, count))
    return cells


def build_measured_cell(params: dict, study_seed: int, path, config=None) -> dict:
    """Import a measured surface and write it as a surface cell of one surface.

    The layout is that of generated cells (heights in units of sigma with
    zero mean, ``stats/*``, ``seeds``; seed -1: none), so contact jobs read
    it unchanged. Attributes: the source file and its SHA-256 (which must be
    the one the workflow was planned with), the import options, the measured
    statistics in SI (``measured_*``), the filled points, the removed plane,
    the Johnson law of the measured moments (for heights / sigma), provenance.
    Returns the root attributes.
    """
    start = time.perf_counter()
    info = params["measured"]
    measurement = load_measured(info)
    if measurement.sha256 != info["file_sha256"]:
        raise MeasurementError(
            f"{info['file']}: the file changed after the workflow was planned (sha256 "
            f"{measurement.sha256[:12]}, planned {info['file_sha256'][:12]}); run again",
            info["file"],
        )
    stats = measured.statistics(measurement)
    sigma = stats["sigma"]
    heights = (measurement.heights / sigma)[None]
    realised = height_stats(heights)
    unit = {"units": "1 (heights / sigma)"}
    one = {"units": "1"}
    datasets = {
        "heights": (heights, unit | {"layout": "(surface, y, x), row-major over y then x",
                                     "source": info["file"]}),
        "seeds": (np.array([-1], dtype=np.int64), {"generator": "none: a measured surface"}),
        "stats/mean": (realised["mean"], unit),
        "stats/sigma": (realised["sigma"], unit),
        "stats/skew": (realised["skew"], one),
        "stats/kurt": (realised["kurt"], {"units": "1 (Pearson, normal = 3)"}),
        "stats/corr_length_x": (np.array([stats["corr_length_x"]]), {"units": "m"}),
        "stats/corr_length_y": (np.array([stats["corr_length_y"]]), {"units": "m"}),
        "stats/filled_points": (np.array([stats["filled_points"]]),
                                one | {"description": "missing points filled by Laplace "
                                                      "interpolation"}),
    }
    spec = {"grid": stats["grid"], "size": stats["size"],
            "corr_length": [stats["corr_length_x"], stats["corr_length_y"]],
            "sigma": sigma, "skew": stats["skew"], "kurt": stats["kurt"],
            "acf": "measured", "periodic": False}
    options = {k: v for k, v in info.items() if k not in ("file_sha256", "sigma_um")}
    attrs = {
        "cell": cell_key(params), "study_seed": int(study_seed), "method": "measured",
        "source_file": str(info["file"]),
        "source_sha256": measurement.sha256,
        "import_options": canonical_json(options),
        **{f"import_{k}": v for k, v in options.items() if k != "file"},
        "measured_sigma_m": sigma,
        "measured_skew": stats["skew"],
        "measured_kurt": stats["kurt"],
        "measured_corr_length_x_m": stats["corr_length_x"],
        "measured_corr_length_y_m": stats["corr_length_y"],
        "measured_spacing_m": stats["spacing"],
        "filled_points": stats["filled_points"],
        "filled_fraction": stats["filled_fraction"],
        "plane_offset_m": stats["plane_offset"],
        "plane_slope_x": stats["plane_slope_x"],
        "plane_slope_y": stats["plane_slope_y"],
        "johnson_family": stats["johnson_family"],
        "johnson_params": stats["johnson_params"],
        "johnson_of": "measured heights / sigma: [gamma, delta, xi, lambda]",
        "spec": canonical_json(spec),
        "params": canonical_json(params),
        **{f"spec_{k}": v for k, v in spec.items()},
        **provenance(config),
    }
    log.info(
        "measured cell %s from %s: %d x %d, sigma %.4g um, Sk %.4f, Ku %.4f, b %.4g x %.4g mm, "
        "%d points filled (%.3g %%), Johnson %s; %.2f s",
        attrs["cell"], info["file"], *stats["grid"], sigma / UM, stats["skew"], stats["kurt"],
        stats["corr_length_x"] / MM, stats["corr_length_y"] / MM, stats["filled_points"],
        100 * stats["filled_fraction"], stats["johnson_family"], time.perf_counter() - start,
    )
    write_h5(path, datasets, attrs)
    return attrs


def check_measured(config: dict, name: str, entry: dict) -> list[str]:
    """Messages for a study whose measured surface cannot be used as configured."""
    if "surface" not in entry:
        if entry.get("compare_synthetic"):
            return [f"{name}: compare_synthetic needs a measured surface ('surface:')"]
        return []
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
                "twin can be made; measure a larger area or drop compare_synthetic"]
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
        "base": str(merged.get("base", "clamped")),
        "mesh": str(merged.get("mesh", "paper")),
    }
    # the influence model; the dense matrix (the paper's) adds no key, so its files keep
    # their names
    operator = str(merged.get("operator", "dense"))
    if operator != "dense":
        params["operator"] = operator
    if operator == "auto":
        tolerance = {**HALFSPACE_TOLERANCE, **(merged.get("halfspace_tolerance") or {})}
        params["halfspace_tolerance"] = {k: (None if v is None else float(v))
                                         for k, v in sorted(tolerance.items())}
    return params


#: Default tolerances of the half-space criterion (``operator: auto``): largest
#: relative error of the half-space model in each quantity (None: not needed).
HALFSPACE_TOLERANCE = {"k_P": 0.02, "real_area": 0.05, "max_pressure": 0.05}


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
    from .influence import BlockGeometry

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
    """Every influence geometry the configuration asks for, keyed by :func:`geometry_key`.

    The body of the config is always included (``make run`` builds it once);
    study figures add the variants they need (another nu, mesh or area).
    """
    geoms = {}
    if "body" in config:
        params = geometry_params(config["body"], config["surfaces"])
        geoms[geometry_key(params)] = params
        for mesh in convergence_presets(config):  # the mesh report reuses these builds
            variant = {**params, "mesh": mesh}
            geoms[geometry_key(variant)] = variant
    return geoms


def convergence_presets(config: dict) -> list[str]:
    """Mesh presets of the influence-convergence report ([] when it is not configured)."""
    report = config.get("reports", {}).get("influence_convergence")
    if not report:
        return []
    return list(report.get("presets", ["paper", "graded", "refined", "converged"]))


def _coarse_geometry(geom):
    """The coarse finite-element model of a hybrid operator (``refined`` for inaccurate meshes)."""
    from .operators import HYBRID_MESHES, default_coarse_grid

    mesh = geom.mesh if geom.mesh in HYBRID_MESHES else "refined"
    return dataclasses.replace(geom, grid=default_coarse_grid(geom.grid), mesh=mesh)


def planned_operator(params: dict, max_memory_gb: float = 16.0) -> str:
    """The influence model a geometry's build starts with: "dense", "hybrid" or "halfspace".

    ``operator: auto`` picks dense or hybrid here (by size and memory,
    :func:`roughcontact.operators.choose_operator`); the build may then
    replace either by the half-space when the measured criterion allows.
    """
    from .operators import choose_operator

    operator = params.get("operator", "dense")
    if operator != "auto":
        return operator
    return choose_operator(block_geometry(params), max_dense_bytes=max_memory_gb * 1e9)


def influence_cost(params: dict, solver: str = "auto", max_memory_gb: float = 16.0):
    """:class:`~roughcontact.influence.CostEstimate` of the finite-element model a build solves."""
    from .influence import estimate_cost

    geom = block_geometry(params)
    if planned_operator(params, max_memory_gb) in ("hybrid", "halfspace"):
        geom = _coarse_geometry(geom)
    return estimate_cost(geom, solver)


def _peak_rss_gb() -> float:
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024 / 1e9  # Linux: KiB


def _dense_checks(unit: np.ndarray, geom, key: str) -> dict:
    n = unit.shape[0]
    nx, ny = geom.grid
    diag = np.diag(unit)
    eigmin = float(np.linalg.eigvalsh(unit)[0]) if n <= 4000 else float("nan")
    rows = unit.sum(axis=1)
    checks = {
        "asymmetry": float(np.abs(unit - unit.T).max() / np.abs(unit).max()),
        "min_eigenvalue_m": eigmin,
        "row_sum_min_m": float(rows.min()),
        "row_sum_max_m": float(rows.max()),
        "centre_diagonal_m": float(diag[(ny // 2) * nx + nx // 2]),
    }
    if not eigmin > 0 and np.isfinite(eigmin):
        raise FloatingPointError(f"geometry {key}: E * C is not positive definite "
                                 f"(smallest eigenvalue {eigmin:.3g} m)")
    return checks


def _operator_checks(op, geom) -> dict:
    nx, ny = geom.grid
    rows = op.matvec(np.ones(nx * ny))
    diag = op.diagonal()
    return {
        "row_sum_min_m": float(rows.min()),
        "row_sum_max_m": float(rows.max()),
        "centre_diagonal_m": float(diag[(ny // 2) * nx + nx // 2]),
        "min_diagonal_m": float(diag.min()),
    }


def build_influence(params: dict, path, *, solver: str = "auto", max_memory_gb: float = 16.0,
                    config=None) -> dict:
    """Build E * C of one geometry and write it, with checks and provenance, to ``path``.

    The influence model is the geometry's ``operator``: "dense" (the
    finite-element matrix, the paper's), "hybrid" (matrix-free: Love's
    half-space plus a coarse finite-element correction,
    :mod:`roughcontact.operators`), "halfspace" (Love only) or "auto" (dense
    up to 64 x 64 elements, hybrid above; then the half-space instead when
    :func:`roughcontact.operators.halfspace_errors`, measured on the coarse
    model, is within the geometry's ``halfspace_tolerance`` for every
    quantity it names).

    The peak memory is estimated first; a geometry that would not fit raises
    :class:`~roughcontact.influence.ModelTooLarge` with the estimate and the
    options before anything is built. Returns the root attributes.
    """
    from . import influence, operators

    geom = block_geometry(params)
    key = geometry_key(params)
    requested = params.get("operator", "dense")
    operator = planned_operator(params, max_memory_gb)
    model = geom if operator == "dense" else _coarse_geometry(geom)
    cost = influence.check_memory(model, max_memory_gb * 1e9, solver)
    log.info(
        "geometry %s: operator %s (requested %s); finite-element model %s grid %s, %d dofs, "
        "estimated peak %.2f GB (limit %.1f GB)", key, operator, requested, model.mesh,
        model.grid, cost.dofs, cost.peak_bytes / 1e9, max_memory_gb,
    )
    start = time.perf_counter()
    fe = influence.unit_modulus_influence(model, solver=solver, max_bytes=max_memory_gb * 1e9)
    if not np.isfinite(fe).all():
        raise FloatingPointError(f"geometry {key}: the influence matrix has non-finite entries")
    extra = {}
    if requested == "auto":
        tolerance = params["halfspace_tolerance"]
        errors = operators.halfspace_errors(fe, model.grid, model.size, geom.nu, geom.thickness)
        meets = operators.halfspace_meets(errors, tolerance)
        log.info("geometry %s: half-space errors measured on the %s grid %s: %s; tolerance %s: "
                 "%s", key, model.mesh, model.grid, errors, tolerance,
                 "use the half-space" if meets else "keep the finite body")
        extra = {"halfspace_errors": errors, "halfspace_tolerance": tolerance}
        if meets:
            operator = "halfspace"
    if operator == "dense":
        unit = fe
        checks = _dense_checks(unit, geom, key)
        datasets = {
            "unit_influence": (
                unit,
                {
                    "units": "m (E * C: displacement per unit pressure times Young's modulus)",
                    "layout": "C[i, j]: displacement at the centre of element i per unit "
                              "pressure on element j; elements row-major over y then x",
                },
            ),
        }
        op_attrs = {}
    else:
        if operator == "hybrid":
            from .halfspace import halfspace_influence

            fe -= halfspace_influence(model.grid, model.size, 1.0, geom.nu)
            fe /= model.spacing[0] * model.spacing[1]
            unit = operators.BlockOperator(grid=geom.grid, size=geom.size, nu=geom.nu,
                                           correction=fe, coarse_grid=model.grid)
        else:
            unit = operators.halfspace_operator(geom.grid, geom.size, geom.nu)
        del fe
        checks = _operator_checks(unit, geom)
        datasets, op_attrs = operators.operator_datasets(unit)
        op_attrs["coarse_mesh"] = model.mesh
    seconds = time.perf_counter() - start
    log.info("geometry %s: %s built in %.1f s; checks %s", key, operator, seconds, checks)
    attrs = {
        "geometry": key,
        "params": canonical_json(params),
        **{f"geometry_{k}": v for k, v in params.items()},
        "operator": operator,
        "operator_requested": requested,
        **op_attrs,
        **extra,
        "mesh_spec": canonical_json(dataclasses.asdict(model.mesh_spec)),
        "dofs": int(cost.dofs),
        "estimated_peak_gb": cost.peak_bytes / 1e9,
        "build_seconds": seconds,
        "peak_rss_gb": _peak_rss_gb(),
        "solver": solver,
        "content_sha256": operators.content_sha256(unit),
        **{f"check_{k}": v for k, v in checks.items()},
        **provenance(config),
    }
    write_h5(path, datasets, attrs)
    return attrs


# ---------------------------------------------------------------------------
# Contact study cells: surfaces x geometry x (sigma, E) x pressure range

#: Figures drawn from contact results, and the source of their cells ("measured": a
#: measured surface against its synthetic twin, usually ``from:`` a sweep).
CONTACT_FIGURES = ("fig07", "fig09", "fig10", "fig11", "fig12", "fig13", "fig14", "table_Eu",
                   "measured")


def _as_list(value) -> list:
    return list(value) if isinstance(value, list | tuple) else [value]


def source_name(config: dict, name: str) -> str:
    """The figure or sweep whose cells ``name`` uses (itself unless ``from:``)."""
    section = {**config.get("figures", {}), **config.get("sweeps", {})}
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
    section = {**config.get("figures", {}), **config.get("sweeps", {})}
    return section[source_name(config, name)]


def accuracy_preset(config: dict) -> dict | None:
    """The accuracy preset the config names (``accuracy: paper|fast|converged``), or None."""
    name = config.get("accuracy")
    if name is None:
        return None
    from .speed import ACCURACY_PRESETS

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
    """The solver settings of the contact jobs: the config's, or the accuracy preset's."""
    settings = dict(config.get("contact", {}))
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
        return measured_study_cells(config, fig, body)
    spacing = [s / g for s, g in zip(_pair(surfaces["size_mm"]), _pair(surfaces["grid"]),
                                     strict=True)]
    cells = []
    for mesh in _as_list(fig.get("meshes", body.get("mesh", "paper"))):
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
                                )
                                geom = geometry_params(body, surfaces, nu=nu, mesh=mesh,
                                                       size_mm=size, grid=grid)
                                cells.append(_study_cell(config, fig, surf, geom, sigma, E))
    return cells


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
    for mesh in _as_list(fig.get("meshes", body.get("mesh", "paper"))):
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
    return problems


def _check_operator(config: dict, name: str, entry: dict) -> list[str]:
    """The hybrid operator needs a coarse model with an accurate near field."""
    from .operators import HYBRID_MESHES

    if config.get("body", {}).get("operator", "dense") != "hybrid":
        return []
    preset = accuracy_preset(config)
    default = preset["mesh"] if preset else config["body"].get("mesh", "paper")
    bad = [m for m in _as_list(entry.get("meshes", default)) if m not in HYBRID_MESHES]
    if not bad:
        return []
    return [f"{name}: body.operator = hybrid with mesh {bad[0]!r}: the hybrid operator takes "
            f"its finite-body correction from a coarse model whose near field must be "
            f"accurate, so the mesh must be one of {list(HYBRID_MESHES)}; use operator: "
            f"dense (the paper's model) or auto (dense up to 64 x 64, hybrid with a "
            f"'refined' coarse model above)"]


def contact_key(cell: dict) -> str:
    """File key of a contact job: one surface cell solved on one geometry."""
    return f"{cell['surface_key']}__{cell['geometry_key']}"


def sweep_end(cell: dict) -> float:
    """Non-dimensional nominal pressure P L / (E sigma) a cell needs, rounded up to 2^k.

    Rounding keeps a small change of sigma, E or the pressure range from
    re-solving a contact job that already reaches far enough.
    """
    p_max = cell["pressure_MPa"][1] * 1e6
    value = p_max * cell["geometry"]["thickness_mm"] * MM / (
        cell["E_MPa"] * 1e6 * cell["sigma_um"] * UM
    )
    return float(2.0 ** np.ceil(np.log2(value)))


def contact_jobs(config: dict, names) -> dict[str, dict]:
    """Every contact job the named figures and sweeps need, with its sweep end.

    A job is shared by every cell on the same surfaces and geometry; it
    sweeps as far as the most demanding of them needs.
    """
    jobs = {}
    for name in names:
        for cell in contact_cells(config, name):
            key = contact_key(cell)
            job = jobs.setdefault(key, {
                "surface": cell["surface"], "geometry": cell["geometry"],
                "surface_key": cell["surface_key"], "geometry_key": cell["geometry_key"],
                "pressure_end": 0.0,
                "accuracy": cell.get("accuracy", "as configured"),
                "expected_error": cell.get("expected_error", {}),
            })
            job["pressure_end"] = max(job["pressure_end"], sweep_end(cell))
    return jobs
