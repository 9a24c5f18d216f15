"""Bodies of the workflow's jobs: surfaces, influence, contact, aggregation.

A *surface job* generates the seeded realisations of one surface cell (or
imports a measured height map) and stores them in units of sigma. An
*influence job* builds E * C of one block geometry (a dense finite-element
matrix or a matrix-free operator). A *contact job* solves every surface of
one surface cell on one influence geometry through an approach sweep, in the
non-dimensional form of :mod:`roughcontact.contact.nondim`, and stores the result;
sigma and E never enter.
An *aggregation* turns the contact results of a figure's (or sweep's) cells
into SI curves for each cell's sigma and E (Eq 28-32) and averages them on a
common nominal-pressure axis (:mod:`roughcontact.contact.aggregate`).


The layouts of the files are described in :mod:`roughcontact.study.storage`.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import time
from pathlib import Path

import numpy as np
import pandas as pd

from roughcontact.contact import aggregate, halfspace_criterion
from roughcontact.contact import cell as cell_module
from roughcontact.elasticity import influence, operators
from roughcontact.errors import MeasurementError
from roughcontact.hashes import file_sha256
from roughcontact.study.cells import (
    block_geometry,
    cell_key,
    coarse_geometry,
    contact_key,
    geometry_key,
    load_measured,
    memory_message,
    planned_operator,
    spec_from_params,
    statistics_key,
)
from roughcontact.study.config import ContactSettings
from roughcontact.study.provenance import (
    atomic_path,
    canonical_json,
    config_hash,
    peak_rss_bytes,
    provenance,
)
from roughcontact.study.storage import (
    read_contact,
    read_influence,
    read_surfaces,
    write_contact,
    write_influence,
    write_surfaces,
)
from roughcontact.surfaces import johnson, measured
from roughcontact.surfaces.calibration import calibrate_filter, input_moments, moment_transfer
from roughcontact.surfaces.exact import generate_exact
from roughcontact.surfaces.spectra import filter_kernel
from roughcontact.surfaces.statistics import correlation_length, height_stats
from roughcontact.surfaces.synthetic import derive_seeds, generate_many
from roughcontact.units import GB, MM, MPA, UM

log = logging.getLogger(__name__)

#: Seconds between progress lines of a contact job within one batch.
PROGRESS_SECONDS = 30.0

#: Surfaces solved together in one call (the batch also fixes the rounding of the
#: matrix products, so a re-solve of the same batch is bit-identical).
BATCH_SIZE = 20


# ---------------------------------------------------------------------------
# Surface jobs: generated cells and measured surfaces


def build_surface_cell(params: dict, study_seed: int, path, config=None) -> dict:
    """Generate a cell's surfaces and write them, with statistics, to ``path``.

    Heights are stored in units of sigma (dimensionless, zero mean per
    surface); realised moments (Eq 2-5) and 10 % ACF lags [m] per surface;
    the filter's transfer factors and the fitted Johnson curve of the white
    noise as attributes, with provenance. A cell with a spectrum also has
    ``spectrum`` (its parameters, JSON), ``spectrum_kind`` and, for a table or
    measured PSD, ``spectrum_file`` and ``spectrum_file_sha256`` (the SHA-256
    of the file the surfaces were generated from). Returns the root attributes.
    A measured cell (``method: measured``) is imported by
    :func:`build_measured_cell` instead.
    """
    if params["method"] == "measured":
        return build_measured_cell(params, study_seed, path, config)
    start = time.perf_counter()
    spec = spec_from_params(params)
    seeds = derive_seeds(study_seed, statistics_key(params), params["count"])
    attrs = {"cell": cell_key(params), "study_seed": int(study_seed), "method": params["method"]}
    if "spectrum" in params:
        spectrum = params["spectrum"]
        attrs |= {"spectrum": canonical_json(spectrum), "spectrum_kind": spectrum["kind"]}
        if "file_sha256" in spectrum:
            attrs |= {"spectrum_file": spectrum["file"],
                      "spectrum_file_sha256": spectrum["file_sha256"]}
    extra = {}
    if params["method"] in ("filter", "paper"):
        kern = filter_kernel(spec)
        s3, s4 = moment_transfer(spec)
        process = spec
        if params["method"] == "filter":  # targets = expected sample moments of a window
            cal = calibrate_filter(spec)
            attrs |= cal.as_attrs()
            process = dataclasses.replace(spec, skew=cal.skew, kurt=cal.kurt)
            log.info(
                "cell %s: calibrated process moments (%.4f, %.4f) for expected sample "
                "moments (%g, %g) (the paper's method would give %.4f, %.4f); %d surfaces, "
                "%.2f s", attrs["cell"], cal.skew, cal.kurt, params["skew"], params["kurt"],
                cal.paper_skew, cal.paper_kurt, cal.samples, cal.seconds)
        skew_x, kurt_x = input_moments(process)
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
        heights = generate_many(spec, seeds, method=params["method"])
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
    write_surfaces(path, datasets, attrs)
    return attrs


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
    stats = measured.statistics(measurement, spectral=True)
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
        "stats/psd_q": (np.array(stats["psd_q"]),
                        {"units": "1/m", "description": "wavevectors of the isotropic PSD "
                                                        "(SurfaceTopography, from the area)"}),
        "stats/psd_C": (np.array(stats["psd_C"]),
                        {"units": "m^4", "description": "isotropic power spectral density"}),
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
        **{f"import_{k}": v for k, v in options.items() if k != "file" and v is not None},
        "preparation": canonical_json(measurement.preparation),
        "measured_sigma_m": sigma,
        "measured_skew": stats["skew"],
        "measured_kurt": stats["kurt"],
        "measured_corr_length_x_m": stats["corr_length_x"],
        "measured_corr_length_y_m": stats["corr_length_y"],
        "measured_spacing_m": stats["spacing"],
        "measured_rms_slope": stats["rms_slope"],
        "measured_rms_curvature_per_m": stats["rms_curvature"],
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
        "rms slope %.4g, rms curvature %.4g 1/mm, %d points filled (%.3g %%), Johnson %s; "
        "%.2f s", attrs["cell"], info["file"], *stats["grid"], sigma / UM, stats["skew"],
        stats["kurt"], stats["corr_length_x"] / MM, stats["corr_length_y"] / MM,
        stats["rms_slope"], stats["rms_curvature"] * MM, stats["filled_points"],
        100 * stats["filled_fraction"], stats["johnson_family"], time.perf_counter() - start,
    )
    write_surfaces(path, datasets, attrs)
    return attrs


# ---------------------------------------------------------------------------
# Influence jobs: the elastic body of a geometry


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


def build_influence(params: dict, path, *, solver: str, max_memory_gb: float,
                    config=None) -> dict:
    """Build E * C of one geometry and write it, with checks and provenance, to ``path``.

    The influence model is the geometry's ``operator``: "dense" (the
    finite-element matrix, the paper's), "hybrid" (matrix-free: Love's
    half-space plus a coarse finite-element correction,
    :mod:`roughcontact.elasticity.operators`), "halfspace" (Love only) or "auto" (dense
    up to 64 x 64 elements, hybrid above; then the half-space instead when
    :func:`roughcontact.contact.halfspace_criterion.halfspace_errors`, measured on the coarse
    model, is within the geometry's ``halfspace_tolerance`` for every
    quantity it names).

    The peak memory is estimated first; a geometry that would not fit raises
    :class:`~roughcontact.influence.ModelTooLarge` with the estimate and the
    options before anything is built. Returns the root attributes.
    """
    geom = block_geometry(params)
    key = geometry_key(params)
    requested = params.get("operator", "dense")  # a dense geometry's key has no operator
    operator = planned_operator(params, max_memory_gb)
    model = geom if operator == "dense" else coarse_geometry(geom)
    try:
        cost = influence.check_memory(model, max_memory_gb * GB, solver)
    except influence.ModelTooLarge as err:  # name the config keys, not the Python argument
        body = {"solver": solver, "max_memory_gb": max_memory_gb}
        peak = influence.estimate_cost(model, solver).peak_bytes
        raise influence.ModelTooLarge(memory_message(key, params, body, peak)) from err
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
        errors = halfspace_criterion.halfspace_errors(fe, model.grid, model.size, geom.nu,
                                                      geom.thickness)
        meets = halfspace_criterion.halfspace_meets(errors, tolerance)
        log.info("geometry %s: half-space errors measured on the %s grid %s: %s; tolerance %s: "
                 "%s", key, model.mesh, model.grid, errors, tolerance,
                 "use the half-space" if meets else "keep the finite body")
        extra = {"halfspace_errors": errors, "halfspace_tolerance": tolerance}
        if meets:
            operator = "halfspace"
    model_attrs = {}
    if operator == "dense":
        unit = fe
        checks = _dense_checks(unit, geom, key)
    else:
        if operator == "hybrid":
            unit = operators.hybrid_operator(geom, fe, model)
        else:
            unit = operators.halfspace_operator(geom.grid, geom.size, geom.nu)
        del fe
        checks = _operator_checks(unit, geom)
        model_attrs["coarse_mesh"] = model.mesh
    seconds = time.perf_counter() - start
    log.info("geometry %s: %s built in %.1f s; checks %s", key, operator, seconds, checks)
    attrs = {
        "geometry": key,
        "params": canonical_json(params),
        **{f"geometry_{k}": v for k, v in params.items()},
        "operator": operator,
        "operator_requested": requested,
        **model_attrs,
        **extra,
        "mesh_spec": canonical_json(dataclasses.asdict(model.mesh_spec)),
        "dofs": int(cost.dofs),
        "estimated_peak_gb": cost.peak_bytes / 1e9,
        "build_seconds": seconds,
        "peak_rss_gb": peak_rss_bytes() / GB,
        "solver": solver,
        **{f"check_{k}": v for k, v in checks.items()},
        **provenance(config),
    }
    return write_influence(path, unit, attrs)


# ---------------------------------------------------------------------------
# Contact jobs


def solve_contact_job(job: dict, surfaces_path, influence_path, out_path, settings: dict,
                      config=None) -> dict:
    """Solve one contact job and write its non-dimensional sweep to ``out_path``.

    ``job`` comes from :func:`roughcontact.study.cells.contact_jobs` (surface and
    geometry parameters and the non-dimensional pressure the sweep must
    reach); ``settings`` is the config's validated ``contact`` section
    (:class:`~roughcontact.study.config.ContactSettings`). Returns the
    root attributes written.
    """
    start = time.perf_counter()
    surfaces = read_surfaces(surfaces_path)
    unit, geometry_attrs = read_influence(influence_path)
    heights = surfaces["heights"]
    m = heights.shape[0]
    geometry = job["geometry"]
    nx, ny = geometry["grid"]
    if heights.shape[1:] != (ny, nx):
        raise ValueError(
            f"surfaces {surfaces_path} have shape {heights.shape[1:]} but geometry "
            f"{job['geometry_key']} has a {ny} x {nx} (ny x nx) contact grid"
        )
    body = block_geometry(geometry)
    solver = ContactSettings.from_section(settings)
    hardness = job.get("hardness")
    log.info("contact %s__%s: %d surfaces x %d steps, sweep to P L / (E sigma) = %g; "
             "method %s, tol %.1e, precision %s, influence %s, %s", job["surface_key"],
             job["geometry_key"], m, solver.steps, job["pressure_end"], solver.method,
             solver.tol, solver.precision, geometry_attrs.get("operator", "dense"),
             "elastic" if hardness is None else f"pressure capped at H L / (E sigma) = "
             f"{hardness:.6g}")

    last = [time.perf_counter()]

    def progress(report):
        now = time.perf_counter()
        if report.step == report.steps_total:
            log.info("  surfaces %d/%d done, %d steps, %.1f s elapsed, %d unconverged",
                     report.surfaces_done, report.surfaces_total, report.steps_total,
                     report.elapsed, report.unconverged)
        elif now - last[0] > PROGRESS_SECONDS:  # long batches (large grids): a heartbeat
            log.info("  step %d/%d of the batch ending at surface %d/%d, %.1f s elapsed",
                     report.step, report.steps_total, report.surfaces_done,
                     report.surfaces_total, report.elapsed)
        else:
            return
        last[0] = now

    result = cell_module.sweep_cell(unit, heights, body, job["pressure_end"], solver.steps,
                                    method=solver.method, tol=solver.tol,
                                    precision=solver.precision, batch_size=min(m, BATCH_SIZE),
                                    progress=progress, hardness=hardness)
    log.info("approach d/sigma %.3g .. %.3g", result.approach[0, 0], result.approach[0, -1])
    reached = result.nominal_pressure[:, -1].min()
    if reached < job["pressure_end"]:
        log.warning("the sweep reached P L / (E sigma) = %.3g on its least loaded surface, "
                    "below the %.3g asked for: higher pressure levels rest on fewer surfaces",
                    reached, job["pressure_end"])
    seconds = time.perf_counter() - start
    unconverged = int((~result.converged).sum())
    stats = {
        "unconverged_steps": unconverged,
        "unconverged_stiffness_steps": int((~result.stiffness_converged).sum()),
        "worst_residual": float(result.residual.max()),
        "total_iterations": int(result.iterations.sum()),
        "max_iterations": int(result.iterations.max()),
        "total_matvecs": int(result.matvecs.sum()),
        "max_plastic_area_fraction": float(result.plastic_area_fraction.max()),
        "wall_seconds": seconds,
    }
    (log.warning if unconverged else log.info)(
        "contact %s__%s: %s", job["surface_key"], job["geometry_key"], stats)
    attrs = {
        "batch_size": min(m, BATCH_SIZE),
        "job": canonical_json(job),
        **stats,
        "surfaces_content_sha256": surfaces["content_sha256"],
        "influence_content_sha256": geometry_attrs["content_sha256"],
        "seeds": surfaces["seeds"].tolist(),
        **provenance(config),
    }
    return write_contact(out_path, result, attrs)


def cell_label(cell: dict) -> str:
    """Short legend text of a study cell."""
    s, g = cell["surface"], cell["geometry"]
    source = (f"measured {Path(s['measured']['file']).name}: " if s.get("method") == "measured"
              else "")
    cap = f", capped at {cell['cap_MPa']:g} MPa" if cell.get("cap_MPa") is not None else ""
    return (f"{source}Sk {s['skew']:g}, Ku {s['kurt']:g}, b {s['b_mm'][0]:g} mm, "
            f"{g['size_mm'][0]:g} mm, nu {g['nu']:g}, {g['mesh']} mesh, "
            f"sigma {cell['sigma_um']:g} um{cap}")


def validity_rows(cell: dict, nd, levels) -> list[pd.DataFrame]:
    """The validity tables of an elastic cell (one per hardness it names), with ``flagged``.

    ``levels`` [Pa]; each table is :func:`roughcontact.contact.cell.validity_table`
    with ``hardness_MPa`` and ``flagged`` (the mean share of the real area or
    of the load above H exceeds the cell's ``hardness_threshold``).
    """
    if cell.get("cap_MPa") is not None or not cell.get("hardness_MPa"):
        return []
    sigma, E = cell["sigma_um"] * UM, cell["E_MPa"] * MPA
    threshold = float(cell["hardness_threshold"])
    out = []
    for H in cell["hardness_MPa"]:
        frame = cell_module.validity_table(nd, sigma, E, H * MPA, levels)
        flagged = ((frame["area_above_mean"] > threshold)
                   | (frame["load_above_mean"] > threshold))
        out.append(frame.drop(columns="hardness").assign(
            hardness_MPa=float(H), threshold=threshold, flagged=flagged))
    return out


def validity_summary(frame: pd.DataFrame) -> dict:
    """Per cell and hardness: the lowest flagged pressure level [MPa] and the largest shares."""
    flagged = frame[frame["flagged"]]
    return {
        "first_flagged_MPa": (float(flagged["nominal_pressure"].min() / MPA)
                              if len(flagged) else None),
        "max_area_above": float(frame["area_above_mean"].max()),
        "max_load_above": float(frame["load_above_mean"].max()),
        "max_excess_load": float(frame["excess_load_mean"].max()),
    }


#: Columns of a study's validity table, in order (also its header when no cell names a
#: hardness).
VALIDITY_COLUMNS = ("cell", "label", "contact_key", "hardness_MPa", "threshold",
                    "nominal_pressure", *(f"{q}_{s}" for q in cell_module.VALIDITY_QUANTITIES
                                          for s in ("mean", "half_width", "count")), "flagged")


def aggregate_study(cells: list[dict], contact_paths: dict, levels: int, table_path,
                    moduli_path, meta_path, config=None, validity_path=None) -> pd.DataFrame:
    """Aggregate a figure's or sweep's cells into CSV tables with a JSON sidecar.

    ``contact_paths`` maps a contact key to its file. The table has one row per
    cell and pressure level (:func:`roughcontact.contact.aggregate.aggregate_cell`
    columns plus the cell's parameters); the moduli table one row per cell and
    surface (E_u, Eq 36) with the cell summary in the sidecar. Unconverged
    solves are excluded by the aggregation and counted in both. With
    ``validity_path``, the validity table (:func:`validity_rows`: the share of
    each elastic cell's real area and load above each hardness it names, no
    extra solve; header only without a hardness) is written there, its
    flagged cells summarised in the sidecar.
    """
    rows, moduli, summaries, checks, validity = [], [], [], [], []
    for index, cell in enumerate(cells):
        key = contact_key(cell)
        nd, attrs = read_contact(contact_paths[key])
        sigma, E = cell["sigma_um"] * UM, cell["E_MPa"] * MPA
        p_min, p_max = (p * MPA for p in cell["pressure_MPa"])
        axis = aggregate.pressure_axis(p_min, p_max, levels)
        cap = cell.get("cap_MPa")
        physical, frame = cell_module.aggregate_sweep(
            nd, sigma, E, axis, hardness=None if cap is None else cap * MPA)
        s, g = cell["surface"], cell["geometry"]
        labels = {
            "cell": index, "label": cell_label(cell), "contact_key": key,
            "skew": s["skew"], "kurt": s["kurt"], "b_mm": s["b_mm"][0],
            "size_mm": g["size_mm"][0], "nu": g["nu"], "mesh": g["mesh"],
            "thickness_mm": g["thickness_mm"], "sigma_um": cell["sigma_um"],
            "E_MPa": cell["E_MPa"],
        }
        if cap is not None or cell.get("hardness_MPa"):
            labels["cap_MPa"] = float("nan") if cap is None else float(cap)
        for part in validity_rows(cell, nd, axis):
            validity.append(part.assign(cell=index, label=labels["label"], contact_key=key))
            summary = validity_summary(part)
            checks.append({"cell": index, "label": labels["label"],
                           "hardness_MPa": float(part["hardness_MPa"].iloc[0]),
                           "threshold": float(part["threshold"].iloc[0]), **summary})
            if summary["first_flagged_MPa"] is not None:
                log.warning("cell %s: above the hardness %g MPa from P = %.3g MPa (share of "
                            "real area up to %.3g, of load up to %.3g; threshold %g): the "
                            "elastic model overstates pressures there", labels["label"],
                            checks[-1]["hardness_MPa"], summary["first_flagged_MPa"],
                            summary["max_area_above"], summary["max_load_above"],
                            checks[-1]["threshold"])
        rows.append(frame.assign(**labels))
        per_surface = aggregate.mean_plane_modulus(physical)
        moduli.append(per_surface.assign(seed=attrs["seeds"], **labels))
        summary = aggregate.modulus_summary(per_surface, E)
        summaries.append({**labels, **{k: float(v) for k, v in summary.items()},
                          "unconverged_steps": int(attrs["unconverged_steps"]),
                          "worst_residual": float(attrs["worst_residual"])})
        if int(attrs["unconverged_steps"]):
            log.warning("cell %s: %d unconverged steps excluded", key,
                        int(attrs["unconverged_steps"]))
        for reason in aggregate.COVERAGE[2:]:
            short = frame["nominal_pressure"][frame["coverage"] == reason] / MPA
            if len(short):
                log.warning("cell %s: %d pressure levels (%.4g-%.4g MPa) have no values: %s; "
                            "their rows are NaN with count 0", cell_label(cell), len(short),
                            short.min(), short.max(), reason)
    table = pd.concat(rows, ignore_index=True)
    units = rows[0].attrs["units"] if rows else {}
    with atomic_path(table_path) as tmp:
        table.to_csv(tmp, index=False)
    with atomic_path(moduli_path) as tmp:
        pd.concat(moduli, ignore_index=True).to_csv(tmp, index=False)
    if validity_path is not None:
        frame = (pd.concat(validity, ignore_index=True) if validity
                 else pd.DataFrame(columns=list(VALIDITY_COLUMNS)))
        with atomic_path(validity_path) as tmp:
            frame[list(VALIDITY_COLUMNS)].to_csv(tmp, index=False)
    meta = {
        "description": "aggregates of the contact study; one row per cell and nominal "
                       "pressure level; mean, 95 % Student-t half width and surface count "
                       "per quantity",
        "units": units,
        "interpolation": aggregate.INTERPOLATION,
        "cells": cells,
        "mean_plane_modulus": summaries,
        "config_hash": config_hash(config) if config is not None else "",
        **{k: v for k, v in provenance(config).items() if k != "config_hash"},
        # what the figures check before they read the tables
        "table_sha256": file_sha256(table_path),
        "moduli_sha256": file_sha256(moduli_path),
    }
    if validity_path is not None:
        meta["validity"] = {
            "description": "share of each elastic cell's real contact area and load above "
                           "the hardness (from the stored solutions, no extra solve); flagged "
                           "where a mean share exceeds the threshold",
            "checks": checks,
            "flagged_cells": sorted({c["cell"] for c in checks
                                     if c["first_flagged_MPa"] is not None}),
        }
        meta["validity_sha256"] = file_sha256(validity_path)
    with atomic_path(meta_path) as tmp:
        Path(tmp).write_text(json.dumps(meta, indent=1, default=float))
    return table


__all__ = [
    "BATCH_SIZE",
    "VALIDITY_COLUMNS",
    "aggregate_study",
    "build_influence",
    "build_measured_cell",
    "build_surface_cell",
    "cell_label",
    "solve_contact_job",
    "validity_rows",
    "validity_summary",
]
