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

:class:`GridConvergenceSettings` is the validated section in SI units. The
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
from dataclasses import dataclass

import numpy as np

from roughcontact import contact
from roughcontact.contact.curves import PhysicalSweep
from roughcontact.contact.interface import InterfaceGrid
from roughcontact.contact.result import INTERFACE_SCALARS, INTERFACE_UNITS
from roughcontact.elasticity.halfspace import PeriodicHalfSpace
from roughcontact.errors import StoredFileError
from roughcontact.hashes import arrays_sha256
from roughcontact.study.provenance import NO_RUN, RunInfo, canonical_json, provenance
from roughcontact.study.storage import (
    REBUILD,
    check_attributes,
    open_h5,
    read_surfaces,
    verify,
    write_h5,
)
from roughcontact.surfaces.multiresolution import band_grid, generate_resolved
from roughcontact.surfaces.spec import SurfaceSpec
from roughcontact.surfaces.statistics import height_stats, spectral_moments
from roughcontact.surfaces.synthetic import derive_seeds
from roughcontact.units import MM, MPA

__all__ = ["CONTACT_FIELDS", "GridConvergenceSettings", "aimed_approaches",
           "build_grid_surfaces", "grid_mem_mb", "read_grid_contact", "solve_grid",
           "sweep_runtime"]

log = logging.getLogger("roughcontact.grid_convergence")

#: Per-step arrays (m, k) of a contact file (SI; see the module docstring).
CONTACT_FIELDS = ("approach", "load", "nominal_pressure", "mean_plane_deflection",
                  "real_area_fraction", "max_pressure", "iterations", "matvecs", "residual",
                  "converged")
#: Seed key of the study's surfaces (:func:`~roughcontact.surfaces.synthetic.derive_seeds`).
SEED_KEY = "grid_convergence"
#: Pilot sweep on the coarsest grid: approaches as fractions of the mean initial gap.
PILOT_FRACTIONS = np.geomspace(0.1, 0.95, 24)
#: The approaches of a sweep reach this factor below the smallest and above the largest
#: reduced pressure of the study, so that every level lies inside each surface's curve.
MARGIN = 1.5


@dataclass(frozen=True)
class GridConvergenceSettings:
    """The grid-convergence study (``reports.grid_convergence``), SI units.

    ``grids`` (elements per side, ascending), ``surfaces`` seeds, square
    ``size`` [m]; the self-affine spectrum (``hurst``, ``rolloff_wavelength``,
    ``cutoff_wavelength`` [m]) and ``generator`` (``"paper"``: a Gaussian
    process); each surface scaled to ``rms_gradient`` h'_rms [-]; the body's
    ``E`` [Pa] and ``nu``; the ``reduced_pressures`` ``p0 / (E* h'_rms)`` [-]
    read per grid; ``kappa_area`` the (lowest, highest) real area fraction of
    the fit of kappa; ``steps`` approaches per sweep, contact ``tol``; and
    ``converged_within``, the relative distance to the extrapolated value at
    which an aggregate counts as converged.
    """

    grids: tuple[int, ...]
    surfaces: int
    size: float
    hurst: float
    rolloff_wavelength: float
    cutoff_wavelength: float
    generator: str
    rms_gradient: float
    E: float
    nu: float
    reduced_pressures: tuple[float, ...]
    kappa_area: tuple[float, float]
    steps: int
    tol: float
    converged_within: float

    @classmethod
    def from_section(cls, section: dict) -> GridConvergenceSettings:
        return cls(grids=tuple(sorted(int(g) for g in section["grids"])),
                   surfaces=int(section["surfaces"]), size=float(section["size_mm"]) * MM,
                   hurst=float(section["hurst"]),
                   rolloff_wavelength=float(section["rolloff_mm"]) * MM,
                   cutoff_wavelength=float(section["cutoff_mm"]) * MM,
                   generator=str(section["generator"]),
                   rms_gradient=float(section["rms_gradient"]),
                   E=float(section["E_MPa"]) * MPA, nu=float(section["nu"]),
                   reduced_pressures=tuple(sorted(float(p)
                                                  for p in section["reduced_pressures"])),
                   kappa_area=(float(section["kappa_area"][0]),
                               float(section["kappa_area"][1])),
                   steps=int(section["steps"]), tol=float(section["tol"]),
                   converged_within=float(section["converged_within"]))

    @property
    def contact_modulus(self) -> float:
        """``E* = E / (1 - nu^2)`` [Pa] (rigid flat on an elastic body)."""
        return self.E / (1.0 - self.nu**2)

    @property
    def pressure_scale(self) -> float:
        """``E* h'_rms`` [Pa]: nominal pressure = reduced pressure x this."""
        return self.contact_modulus * self.rms_gradient

    def spec(self, grid: int | None = None) -> SurfaceSpec:
        """The surfaces' :class:`SurfaceSpec` (``sigma`` 1: the scale is ``rms_gradient``)."""
        return SurfaceSpec(grid=grid or self.grids[0], size=self.size, acf="self-affine",
                           hurst=self.hurst, rolloff_wavelength=self.rolloff_wavelength,
                           cutoff_wavelength=self.cutoff_wavelength)


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
    write_h5(path, datasets, attrs)
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
    surfaces = read_surfaces(surfaces_path)
    check_attributes(surfaces_path, surfaces["attrs"], {"params": params, "grid": int(grid)})
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
    write_h5(out_path, datasets, attrs)
    return attrs


def read_grid_contact(path) -> tuple[PhysicalSweep, dict]:
    """The sweep of a contact file as a :class:`~roughcontact.contact.curves.PhysicalSweep`
    (reference length and nominal area: the period ``L``, ``L^2``) and its attributes;
    the content hash is checked first (:class:`~roughcontact.errors.StoredFileError`)."""
    with open_h5(path) as f:
        names = (*CONTACT_FIELDS, *INTERFACE_SCALARS, "rms_gradient")
        missing = [name for name in names if name not in f]
        if missing:
            raise StoredFileError(f"{path}: no {', '.join(missing)}; {REBUILD}", path)
        arrays = {name: f[name][...] for name in names}
        attrs = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}
    verify(path, attrs, arrays_sha256(arrays))
    size = GridConvergenceSettings.from_section(json.loads(attrs["params"])).size
    nan = np.full(arrays["approach"].shape, math.nan)
    sweep = PhysicalSweep(**{name: arrays[name] for name in CONTACT_FIELDS + INTERFACE_SCALARS},
                          normalized_stiffness=nan, contact_stiffness=nan,
                          stiffness_converged=np.zeros(nan.shape, dtype=bool),
                          thickness=size, sigma=math.nan, E=float(attrs["contact_modulus"]),
                          nominal_area=size * size)
    attrs["rms_gradient"] = arrays["rms_gradient"]
    return sweep, attrs



#: CPU seconds of one contact solve on 1024^2 elements at tol 1e-8 and 3-15 % contact
#: (measured 4-11 s on the shared 2-core machine, cold starts) and the growth with the
#: element count n (n log n products, iterations growing with the grid).
SOLVE_SECONDS_1024 = 12.0
SOLVE_EXPONENT = 1.2


def sweep_runtime(settings: GridConvergenceSettings, grid: int, attempt: int = 1) -> int:
    """Requested wall time [min] of :func:`solve_grid` on ``grid`` (a retry asks for more)."""
    solves = settings.surfaces * (settings.steps + len(PILOT_FRACTIONS) / 10.0)
    seconds = solves * SOLVE_SECONDS_1024 * (grid * grid / 1024**2) ** SOLVE_EXPONENT
    return int(math.ceil(attempt * (2.0 + 2.0 * seconds / 60.0)))


def grid_mem_mb(settings: GridConvergenceSettings, grid: int) -> int:
    """Peak memory [MB] of a job on ``grid``: 300 MB of interpreter and libraries and 20
    work arrays of doubles per surface (the batched sweep's iterates and products)."""
    return int(300 + 20 * 8 * settings.surfaces * grid * grid / 1e6)
