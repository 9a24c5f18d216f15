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
import logging
import time

import numpy as np

from . import johnson
from .provenance import canonical_json, provenance
from .storage import array_sha256, write_h5
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
    whatever the count.
    """
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
    """
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
# Influence geometries: the elastic body a contact cell is solved on


def geometry_params(body: dict, surfaces: dict, **overrides) -> dict:
    """Complete, canonical parameters of one influence geometry.

    ``body`` is the config's ``body`` section, ``surfaces`` its ``surfaces``
    section (the contact grid and plan size are the surfaces'); ``overrides``
    may set ``nu``, ``mesh``, ``size_mm``, ``grid`` and any body key. Young's
    modulus is not part of a geometry: matrices are stored as E * C.
    """
    merged = {**body, "grid": surfaces["grid"], "size_mm": surfaces["size_mm"], **overrides}
    return {
        "nu": float(merged["nu"]),
        "size_mm": [float(v) for v in _pair(merged["size_mm"])],
        "thickness_mm": float(merged["thickness_mm"]),
        "grid": [int(v) for v in _pair(merged["grid"])],
        "base": str(merged.get("base", "clamped")),
        "mesh": str(merged.get("mesh", "paper")),
    }


def geometry_key(params: dict) -> str:
    """File key of an influence geometry (every parameter that changes E * C)."""
    lx, ly = params["size_mm"]
    nx, ny = params["grid"]
    return (
        f"nu{params['nu']:g}_L{lx:g}x{ly:g}mm_t{params['thickness_mm']:g}mm"
        f"_g{nx}x{ny}_{params['base']}_{params['mesh']}"
    )


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


def build_influence(params: dict, path, *, solver: str = "auto", max_memory_gb: float = 16.0,
                    config=None) -> dict:
    """Build E * C of one geometry and write it, with checks and provenance, to ``path``.

    The peak memory is estimated first; a geometry that would not fit raises
    :class:`~roughcontact.influence.ModelTooLarge` with the estimate and the
    options before anything is built. Returns the root attributes.
    """
    from . import influence

    geom = block_geometry(params)
    cost = influence.check_memory(geom, max_memory_gb * 1e9, solver)
    key = geometry_key(params)
    log.info(
        "geometry %s: %d dofs, estimated peak %.2f GB (limit %.1f GB)",
        key, cost.dofs, cost.peak_bytes / 1e9, max_memory_gb,
    )
    start = time.perf_counter()
    unit = influence.unit_modulus_influence(geom, solver=solver, max_bytes=max_memory_gb * 1e9)
    seconds = time.perf_counter() - start
    import resource

    peak_rss_gb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024 / 1e9  # Linux: KiB
    if not np.isfinite(unit).all():
        raise FloatingPointError(f"geometry {key}: the influence matrix has non-finite entries")
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
    log.info("geometry %s: built in %.1f s; checks %s", key, seconds, checks)
    attrs = {
        "geometry": key,
        "params": canonical_json(params),
        **{f"geometry_{k}": v for k, v in params.items()},
        "mesh_spec": canonical_json(dataclasses.asdict(geom.mesh_spec)),
        "dofs": int(cost.dofs),
        "estimated_peak_gb": cost.peak_bytes / 1e9,
        "build_seconds": seconds,
        "peak_rss_gb": peak_rss_gb,
        "solver": solver,
        "content_sha256": array_sha256(unit),
        **{f"check_{k}": v for k, v in checks.items()},
        **provenance(config),
    }
    datasets = {
        "unit_influence": (
            unit,
            {
                "units": "m (E * C: displacement per unit pressure times Young's modulus)",
                "layout": "C[i, j]: displacement at the centre of element i per unit pressure "
                          "on element j; elements row-major over y then x",
            },
        ),
    }
    write_h5(path, datasets, attrs)
    return attrs


# ---------------------------------------------------------------------------
# Contact study cells: surfaces x geometry x (sigma, E) x pressure range

#: Figures drawn from contact results, and the source of their cells.
CONTACT_FIGURES = ("fig07", "fig09", "fig10", "fig11", "fig12", "fig13", "fig14", "table_Eu")


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
    its surface cell, its geometry and the scaling parameters.
    """
    fig = resolve_source(config, name)
    surfaces, body = config["surfaces"], config["body"]
    preset = accuracy_preset(config)
    if preset is not None:  # the preset's mesh and count unless the figure names its own
        body = {**body, "mesh": preset["mesh"]}
        fig = {"count": preset["surfaces"], **fig}
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
                                cells.append({
                                    "surface": surf,
                                    "geometry": geom,
                                    "sigma_um": float(sigma),
                                    "E_MPa": float(E),
                                    "pressure_MPa": [float(p) for p in fig["pressure_MPa"]],
                                    "surface_key": cell_key(surf),
                                    "geometry_key": geometry_key(geom),
                                    **accuracy_attrs(config),
                                })
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
    return problems


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
