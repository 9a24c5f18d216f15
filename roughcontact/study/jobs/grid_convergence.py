"""Jobs of the grid-convergence study: one band-limited surface set, swept on each grid.

The study (config section ``reports.grid_convergence``, on demand) resolves
the same self-affine surfaces with a short-wavelength cut-off
(:mod:`roughcontact.surfaces.multiresolution`) on grids of 128^2 to 1024^2
elements and presses a rigid flat onto each on the periodic elastic
half-space (:class:`~roughcontact.elasticity.halfspace.PeriodicHalfSpace`),
so that what changes from grid to grid is the discretization of the contact
problem alone. Two jobs per grid:

- :func:`build_grid_surfaces`: the surfaces of every seed on one grid,
  heights in metres, with their height moments and spectral moments
  (h'_rms, m0, m2, m4, Nayak's alpha) and the seeds;
- :func:`solve_grid`: an approach sweep of every surface
  (:func:`roughcontact.contact.sweep`, method ``"auto"``), its approaches
  aimed, per surface, at the reduced pressures ``p0 / (E* h'_rms)`` of the
  study by a pilot sweep on the coarsest grid (:func:`aimed_approaches`).

:class:`~roughcontact.study.config.GridConvergenceSettings` is the validated section in SI
units. The
report (:mod:`roughcontact.reports.grid_convergence`) reads the contact
files (:func:`read_grid_contact`). File layouts::

    surfaces_<grid>.h5: /heights (m, ny, nx) [m], /seeds (m,),
        /stats/<name> (m,): mean, sigma [m], skew, kurt [-], m0 [m^2], m2 [-],
        m4 [1/m^2], rms_gradient [-], rms_curvature [1/m], nayak_alpha [-]
        attributes: params (JSON), spec (JSON), grid, band_grid, study_seed,
        content_sha256, provenance
    contact_<grid>.h5: /<field> (m, k): approach [m], load [N], nominal_pressure,
        max_pressure [Pa], mean_plane_deflection [m], real_area_fraction [-],
        iterations, matvecs, residual, converged; the interface quantities
        (:mod:`roughcontact.contact.interface`, periodic grid) spot_count,
        mean_spot_area [m^2], perimeter [m], corrected_real_area_fraction [-],
        mean_gap [m]; /rms_gradient (m,) [-]
        attributes: params, grid, seeds, method, tol, contact_modulus [Pa],
        wall_seconds, cpu_seconds, surfaces_content_sha256, content_sha256,
        provenance
"""

from __future__ import annotations

import json
import logging
import math
import time

import numpy as np

from roughcontact import contact
from roughcontact.contact.curves import PhysicalSweep
from roughcontact.contact.interface import InterfaceGrid
from roughcontact.contact.result import INTERFACE_SCALARS, INTERFACE_UNITS
from roughcontact.elasticity.halfspace import PeriodicHalfSpace
from roughcontact.errors import StoredFileError
from roughcontact.hashes import arrays_sha256
from roughcontact.study.config import PILOT_FRACTIONS, GridConvergenceSettings
from roughcontact.study.jobs import storage
from roughcontact.study.provenance import NO_RUN, RunInfo, canonical_json, provenance
from roughcontact.surfaces.multiresolution import band_grid, generate_resolved
from roughcontact.surfaces.statistics import height_stats, spectral_moments
from roughcontact.surfaces.synthetic import derive_seeds

__all__ = ["CONTACT_FIELDS", "aimed_approaches", "build_grid_surfaces", "read_grid_contact",
           "solve_grid"]

log = logging.getLogger("roughcontact.grid_convergence")

#: Per-step arrays (m, k) of a contact file (SI; see the module docstring).
CONTACT_FIELDS = ("approach", "load", "nominal_pressure", "mean_plane_deflection",
                  "real_area_fraction", "max_pressure", "iterations", "matvecs", "residual",
                  "converged")
#: Seed key of the study's surfaces (:func:`~roughcontact.surfaces.synthetic.derive_seeds`).
SEED_KEY = "grid_convergence"
#: The approaches of a sweep reach this factor below the smallest and above the largest
#: reduced pressure of the study, so that every level lies inside each surface's curve.
MARGIN = 1.5


def _stats(heights: np.ndarray, size: float) -> dict:
    """Height moments and spectral moments of each surface, with units."""
    moments = height_stats(heights)
    spectral = [spectral_moments(z, size) for z in heights]
    units = {"mean": "m", "sigma": "m", "skew": "1", "kurt": "1", "m0": "m^2", "m2": "1",
             "m4": "1/m^2", "rms_gradient": "1", "rms_curvature": "1/m", "nayak_alpha": "1"}
    values = {**moments, **{name: np.array([getattr(s, name) for s in spectral])
                            for name in ("m0", "m2", "m4", "rms_gradient", "rms_curvature",
                                         "nayak_alpha")}}
    return {f"stats/{name}": (np.asarray(values[name]), {"units": unit})
            for name, unit in units.items()}


def build_grid_surfaces(params: dict, study_seed: int, grid: int, path,
                        run: RunInfo = NO_RUN) -> dict:
    """Generate the study's surfaces on ``grid`` x ``grid`` and write them to ``path``.

    ``params``: the validated ``reports.grid_convergence`` section. Seeds from
    ``derive_seeds(study_seed, "grid_convergence", surfaces)``: every grid
    holds the same surfaces (:func:`~roughcontact.surfaces.multiresolution.generate_resolved`).
    Returns the root attributes written.
    """
    settings = GridConvergenceSettings.from_section(params)
    start = time.perf_counter()
    spec = settings.spec(grid)
    seeds = derive_seeds(study_seed, SEED_KEY, settings.surfaces)
    heights = generate_resolved(spec, seeds, [grid], settings.generator,
                                rms_gradient=settings.rms_gradient)[grid]
    datasets = {"heights": (heights, {"units": "m", "layout": "(surface, y, x)"}),
                "seeds": (seeds.astype(np.int64), {"generator": "numpy.random.default_rng"}),
                **_stats(heights, settings.size)}
    attrs = {"params": canonical_json(params), "spec": canonical_json(spec.as_dict()),
             "grid": int(grid), "band_grid": list(band_grid(spec)),
             "study_seed": int(study_seed), "generator": settings.generator,
             **provenance(run)}
    storage.write_h5(path, datasets, attrs)
    log.info("grid %d: %d surfaces in %.2f s (band grid %s)", grid, len(seeds),
             time.perf_counter() - start, attrs["band_grid"])
    return attrs


def aimed_approaches(settings: GridConvergenceSettings, seeds) -> np.ndarray:
    """Approaches (m, steps) [m] that reach the study's reduced pressures on every surface.

    A pilot sweep of each surface on the study's coarsest grid (or its band
    grid, if finer: the coarsest that carries it; so cheap) at
    ``PILOT_FRACTIONS`` of its mean initial gap gives its curve ``P(d)``; the
    approaches are read from it (``log P`` linear in ``d``) at ``steps``
    reduced pressures spaced geometrically from ``min / MARGIN`` to
    ``max * MARGIN`` of ``reduced_pressures``. Every grid uses these
    approaches: the surfaces are the same, their curves differ by the
    discretization only (the coarsest grid's load at a given approach is the
    highest, by about 2 % at 128^2 in the default study), so the levels fall
    inside each sweep.
    """
    spec = settings.spec()
    band = band_grid(spec)
    pilot_grid = (max(settings.grids[0], band[0]), max(settings.grids[0], band[1]))
    heights = generate_resolved(spec, seeds, [pilot_grid], settings.generator,
                                rms_gradient=settings.rms_gradient)[pilot_grid]
    gaps = heights.max(axis=(1, 2), keepdims=True) - heights
    pilot = np.outer(gaps.mean(axis=(1, 2)), PILOT_FRACTIONS)
    operator = PeriodicHalfSpace(pilot_grid, (settings.size, settings.size), settings.E,
                                 settings.nu)
    result = contact.sweep(operator, gaps, pilot,
                           options=contact.SolverOptions(tol=settings.tol, stiffness=False))
    targets = np.geomspace(min(settings.reduced_pressures) / MARGIN,
                           max(settings.reduced_pressures) * MARGIN, settings.steps)
    reduced = result.nominal_pressure / settings.pressure_scale
    out = np.empty((len(heights), settings.steps))
    for j in range(len(heights)):
        keep = reduced[j] > 0
        if targets[-1] > reduced[j, keep][-1]:
            log.warning("pilot of surface %d reaches p0 / (E* h'_rms) = %.3g only, below %.3g",
                        j, reduced[j, keep][-1], targets[-1])
        out[j] = np.interp(np.log(targets), np.log(reduced[j, keep]), pilot[j, keep])
    return out


def solve_grid(params: dict, surfaces_path, grid: int, out_path, run: RunInfo = NO_RUN) -> dict:
    """Sweep every surface of ``surfaces_path`` on the periodic half-space; write ``out_path``.

    The surfaces file must be this study's (its ``params`` equal ``params``)
    on ``grid`` x ``grid`` and match its content hash, else
    :class:`~roughcontact.errors.StoredFileError`. Each surface is swept
    (:func:`roughcontact.contact.sweep`, ``method="auto"``, no tangent
    stiffness) through :func:`aimed_approaches`; unconverged steps are kept,
    flagged and logged. Returns the root attributes written.
    """
    settings = GridConvergenceSettings.from_section(params)
    surfaces = storage.read_surfaces(surfaces_path)
    storage.check_attributes(surfaces_path, surfaces["attrs"],
                             {"params": params, "grid": int(grid)})
    heights = surfaces["heights"]
    wall, cpu = time.perf_counter(), time.process_time()
    approaches = aimed_approaches(settings, surfaces["seeds"])
    operator = PeriodicHalfSpace((grid, grid), (settings.size, settings.size), settings.E,
                                 settings.nu)
    gaps = heights.max(axis=(1, 2), keepdims=True) - heights
    result = contact.sweep(operator, gaps, approaches,
                           interface=InterfaceGrid.of(operator, (settings.size, settings.size)),
                           options=contact.SolverOptions(method="auto", tol=settings.tol,
                                                         stiffness=False))
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    if not result.converged.all():
        log.warning("grid %d: %d of %d solves did not converge (tol %.1e); they are left out "
                    "of the report", grid, int((~result.converged).sum()),
                    result.converged.size, settings.tol)
    log.info("grid %d: %d surfaces x %d steps, method %s, %.1f s wall, %.1f s CPU, "
             "%d iterations", grid, len(heights), settings.steps, result.method, wall, cpu,
             int(result.iterations.sum()))
    units = {"approach": "m", "load": "N", "nominal_pressure": "Pa", "max_pressure": "Pa",
             "mean_plane_deflection": "m", **INTERFACE_UNITS}
    datasets = {name: (np.asarray(getattr(result, name)), {"units": units.get(name, "1")})
                for name in CONTACT_FIELDS + INTERFACE_SCALARS}
    datasets["rms_gradient"] = (surfaces["stats"]["rms_gradient"], {"units": "1"})
    attrs = {"params": canonical_json(params), "grid": int(grid),
             "seeds": surfaces["seeds"].tolist(), "method": result.method, "tol": settings.tol,
             "contact_modulus": settings.contact_modulus, "wall_seconds": wall,
             "cpu_seconds": cpu, "surfaces_content_sha256": surfaces["content_sha256"],
             **provenance(run)}
    storage.write_h5(out_path, datasets, attrs)
    return attrs


def read_grid_contact(path) -> tuple[PhysicalSweep, dict]:
    """The sweep of a contact file as a :class:`~roughcontact.contact.curves.PhysicalSweep`
    (reference length and nominal area: the period ``L``, ``L^2``) and its attributes;
    the content hash is checked first (:class:`~roughcontact.errors.StoredFileError`)."""
    with storage.open_h5(path) as f:
        names = (*CONTACT_FIELDS, *INTERFACE_SCALARS, "rms_gradient")
        missing = [name for name in names if name not in f]
        if missing:
            raise StoredFileError(f"{path}: no {', '.join(missing)}; {storage.REBUILD}", path)
        arrays = {name: f[name][...] for name in names}
        attrs = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}
    storage.verify(path, attrs, arrays_sha256(arrays))
    size = GridConvergenceSettings.from_section(json.loads(attrs["params"])).size
    nan = np.full(arrays["approach"].shape, math.nan)
    sweep = PhysicalSweep(**{name: arrays[name] for name in CONTACT_FIELDS + INTERFACE_SCALARS},
                          normalized_stiffness=nan, contact_stiffness=nan,
                          stiffness_converged=np.zeros(nan.shape, dtype=bool),
                          thickness=size, sigma=math.nan, E=float(attrs["contact_modulus"]),
                          nominal_area=size * size)
    attrs["rms_gradient"] = arrays["rms_gradient"]
    return sweep, attrs
