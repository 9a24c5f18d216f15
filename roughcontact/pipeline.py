"""Bodies of the workflow's contact and aggregation jobs.

A *contact job* solves every surface of one surface cell on one influence
geometry through an approach sweep, in the non-dimensional form of
:mod:`roughcontact.nondim`, and stores the result; sigma and E never enter.
An *aggregation* turns the contact results of a figure's (or sweep's) cells
into SI curves for each cell's sigma and E (Eq 28-32) and averages them on a
common nominal-pressure axis (:mod:`roughcontact.aggregate`).

Layout of a contact file (``results/contact/<surface cell>__<geometry>.h5``)::

    /<field>   (m, k)  every array of NondimSweep (dimensionless; see there)
    attributes: job (JSON), the NondimSweep settings, solver statistics
                (unconverged steps, worst residual, iterations), wall time,
                the content hashes of the surface and influence inputs, provenance
"""

from __future__ import annotations

import hashlib
import json
import logging
import time
from pathlib import Path

import h5py
import numpy as np
import pandas as pd

from . import aggregate, nondim
from .operators import read_operator
from .provenance import atomic_path, canonical_json, config_hash, provenance
from .storage import read_surfaces, write_h5

log = logging.getLogger(__name__)

#: Seconds between progress lines of a contact job within one batch.
PROGRESS_SECONDS = 30.0

MM = 1e-3
_ARRAYS = ("approach", "nominal_pressure", "mean_plane_deflection", "real_area_fraction",
           "max_pressure", "stiffness", "iterations", "matvecs", "residual", "converged",
           "stiffness_converged")
_SETTINGS = ("thickness", "element_area", "n_elements", "method", "tol", "stiffness_tol",
             "precision")

#: Steps of the sweep's geometric approach grid below its end (first step = end / this).
APPROACH_RANGE = 64.0
#: Surfaces solved together in one call (the batch also fixes the rounding of the
#: matrix products, so a re-solve of the same batch is bit-identical).
BATCH_SIZE = 20


def arrays_sha256(datasets: dict) -> str:
    """SHA-256 of named arrays (names sorted; dtype, shape and bytes of each)."""
    digest = hashlib.sha256()
    for name in sorted(datasets):
        array = np.ascontiguousarray(datasets[name])
        digest.update(f"{name}|{array.dtype.str}|{array.shape}|".encode())
        digest.update(array.tobytes())
    return digest.hexdigest()


def _file_sha256(path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def sweep_approaches(heights: np.ndarray, pressure_end: float, steps: int,
                     bulk_factor: float = 1.1) -> np.ndarray:
    """Approaches ``d / sigma`` of a contact job: geometric, up to a guaranteed end.

    The end reaches the non-dimensional pressure ``pressure_end`` on every
    surface without a trial solve: averaging the gap over the nominal area
    gives ``d - d_b <= mean(f) = max(h)`` (heights of zero mean), and
    ``d_b = P L / E_u`` with ``E_u >= E / bulk_factor`` (``E_u = E`` for nu = 0,
    rows of ``E C`` summing to L; a few percent above E for nu > 0), so
    ``d = bulk_factor * P_end + max(h)`` is enough. The grid is geometric from
    ``end / APPROACH_RANGE``, fine where the load grows fastest.
    """
    end = bulk_factor * pressure_end + float(np.max(heights))
    return np.geomspace(end / APPROACH_RANGE, end, steps)


def solve_contact_job(job: dict, surfaces_path, influence_path, out_path, settings: dict,
                      config=None) -> dict:
    """Solve one contact job and write its non-dimensional sweep to ``out_path``.

    ``job`` comes from :func:`roughcontact.study.contact_jobs` (surface and
    geometry parameters and the non-dimensional pressure the sweep must
    reach); ``settings`` is the config's ``contact`` section. Returns the
    root attributes written.
    """
    start = time.perf_counter()
    cell = read_surfaces(surfaces_path)
    unit, geometry_attrs = read_operator(influence_path)
    heights = cell["heights"]
    m = heights.shape[0]
    geometry = job["geometry"]
    nx, ny = geometry["grid"]
    if heights.shape[1:] != (ny, nx):
        raise ValueError(
            f"surfaces {surfaces_path} have shape {heights.shape[1:]} but geometry "
            f"{job['geometry_key']} has a {ny} x {nx} (ny x nx) contact grid"
        )
    thickness = geometry["thickness_mm"] * MM
    element_area = (geometry["size_mm"][0] / nx) * (geometry["size_mm"][1] / ny) * MM**2
    steps = int(settings.get("steps", 30))
    approaches = sweep_approaches(heights, job["pressure_end"], steps)
    method = settings.get("method", "cg")
    tol = float(settings.get("tol", 1e-8))
    precision = settings.get("precision", "mixed")
    log.info("contact %s__%s: %d surfaces x %d steps, approach d/sigma %.3g .. %.3g, "
             "sweep to P L / (E sigma) = %g; method %s, tol %.1e, precision %s, influence %s",
             job["surface_key"], job["geometry_key"], m, steps, approaches[0], approaches[-1],
             job["pressure_end"], method, tol, precision,
             geometry_attrs.get("operator", "dense"))

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

    result = nondim.solve_cell(
        unit, heights, thickness=thickness, element_area=element_area, approaches=approaches,
        method=method, tol=tol, precision=precision, batch_size=min(m, BATCH_SIZE),
        progress=progress,
    )
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
        "wall_seconds": seconds,
    }
    (log.warning if unconverged else log.info)(
        "contact %s__%s: %s", job["surface_key"], job["geometry_key"], stats)
    datasets = {name: np.asarray(getattr(result, name)) for name in _ARRAYS}
    attrs = {
        "content_sha256": arrays_sha256(datasets),
        "batch_size": min(m, BATCH_SIZE),
        "job": canonical_json(job),
        **{f"sweep_{k}": getattr(result, k) for k in _SETTINGS},
        "sweep_max_iter": -1 if result.max_iter is None else result.max_iter,
        **stats,
        "surfaces_sha256": _file_sha256(surfaces_path),
        "influence_content_sha256": geometry_attrs.get("content_sha256", ""),
        "seeds": cell["seeds"].tolist(),
        **provenance(config),
    }
    write_h5(out_path, datasets, attrs)
    return attrs


def read_contact(path) -> tuple[nondim.NondimSweep, dict]:
    """The :class:`~roughcontact.nondim.NondimSweep` and attributes of a contact file."""
    with h5py.File(path, "r") as f:
        arrays = {name: f[name][...] for name in _ARRAYS}
        attrs = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}
    settings = {k: attrs[f"sweep_{k}"] for k in _SETTINGS}
    settings["n_elements"] = int(settings["n_elements"])
    for key in ("method", "precision"):
        settings[key] = str(settings[key])
    if isinstance(attrs.get("seeds"), str):  # stored as JSON text
        attrs["seeds"] = json.loads(attrs["seeds"])
    max_iter = int(attrs["sweep_max_iter"])
    return nondim.NondimSweep(**arrays, **settings,
                              max_iter=None if max_iter < 0 else max_iter), attrs


def cell_label(cell: dict) -> str:
    """Short legend text of a study cell."""
    s, g = cell["surface"], cell["geometry"]
    source = (f"measured {Path(s['measured']['file']).name}: " if s.get("method") == "measured"
              else "")
    return (f"{source}Sk {s['skew']:g}, Ku {s['kurt']:g}, b {s['b_mm'][0]:g} mm, "
            f"{g['size_mm'][0]:g} mm, nu {g['nu']:g}, {g['mesh']} mesh, "
            f"sigma {cell['sigma_um']:g} um")


def aggregate_study(cells: list[dict], contact_paths: dict, levels: int, table_path,
                    moduli_path, meta_path, config=None) -> pd.DataFrame:
    """Aggregate a figure's or sweep's cells into CSV tables with a JSON sidecar.

    ``contact_paths`` maps a contact key to its file. The table has one row per
    cell and pressure level (:func:`roughcontact.aggregate.aggregate_cell`
    columns plus the cell's parameters); the moduli table one row per cell and
    surface (E_u, Eq 36) with the cell summary in the sidecar. Unconverged
    solves are excluded by the aggregation and counted in both.
    """
    from .study import contact_key

    rows, moduli, summaries = [], [], []
    for index, cell in enumerate(cells):
        key = contact_key(cell)
        nd, attrs = read_contact(contact_paths[key])
        sigma, E = cell["sigma_um"] * 1e-6, cell["E_MPa"] * 1e6
        physical = nondim.to_physical(nd, sigma, E)
        p_min, p_max = (p * 1e6 for p in cell["pressure_MPa"])
        frame = aggregate.aggregate_cell(physical, aggregate.pressure_axis(p_min, p_max, levels))
        s, g = cell["surface"], cell["geometry"]
        labels = {
            "cell": index, "label": cell_label(cell), "contact_key": key,
            "skew": s["skew"], "kurt": s["kurt"], "b_mm": s["b_mm"][0],
            "size_mm": g["size_mm"][0], "nu": g["nu"], "mesh": g["mesh"],
            "thickness_mm": g["thickness_mm"], "sigma_um": cell["sigma_um"],
            "E_MPa": cell["E_MPa"],
        }
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
    table = pd.concat(rows, ignore_index=True)
    units = rows[0].attrs["units"] if rows else {}
    with atomic_path(table_path) as tmp:
        table.to_csv(tmp, index=False)
    with atomic_path(moduli_path) as tmp:
        pd.concat(moduli, ignore_index=True).to_csv(tmp, index=False)
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
    }
    with atomic_path(meta_path) as tmp:
        Path(tmp).write_text(json.dumps(meta, indent=1, default=float))
    return table


__all__ = [
    "BATCH_SIZE",
    "aggregate_study",
    "arrays_sha256",
    "cell_label",
    "read_contact",
    "solve_contact_job",
    "sweep_approaches",
]
