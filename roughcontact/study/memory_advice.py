"""The advice of an influence build beyond the memory limit: the keys that bring it within.

Shared by the plan's check (:func:`roughcontact.study.plan.checks.check_memory`:
refused before any job runs) and the influence job (a build that finds itself too
large names the same keys): each option is estimated here, and offered only where
its build fits.
"""

from __future__ import annotations

import dataclasses
import math

from roughcontact.elasticity.influence import MESH_PRESETS
from roughcontact.study.codec import in_unit
from roughcontact.study.config import BuildSettings
from roughcontact.study.records import Geometry, InfluenceModel
from roughcontact.units import GB

__all__ = ["memory_message", "memory_options"]


def _fits(geometry: Geometry, build: BuildSettings) -> float | None:
    """The estimated peak memory [GB] of a geometry's build if it fits ``build``'s
    limit, else None."""
    peak = geometry.influence_cost(build).peak_bytes
    return peak / GB if peak <= build.max_bytes else None


def memory_options(geometry: Geometry, build: BuildSettings, peak_bytes: float,
                   configured: Geometry) -> list[str]:
    """The changes, as config text, that bring a build within the memory limit, each
    estimated here (an option is offered only if its build fits), and none the
    configuration already has: ``body.operator: auto`` only to a geometry configured
    dense (``configured``: as the configuration gives it, before ``auto`` resolves)."""
    options = []
    if configured.operator is InfluenceModel.DENSE:
        auto = dataclasses.replace(configured, operator=InfluenceModel.AUTO)
        fits = _fits(auto.candidates(build.max_bytes)[0], build)
        if fits is not None:
            options.append(f"body.operator: auto (matrix-free above 64 x 64 elements: about "
                           f"{fits:.3g} GB here)")
    if build.solver == "superlu":  # auto: PARDISO where it loads (on this machine)
        fits = _fits(geometry, dataclasses.replace(build, solver="auto"))
        if fits is not None:
            options.append(f"body.solver: auto (MKL PARDISO: about {fits:.3g} GB here)")
    presets = list(MESH_PRESETS)
    coarser = [(mesh, _fits(dataclasses.replace(geometry, mesh=mesh), build))
               for mesh in presets[:presets.index(geometry.mesh)]
               if isinstance(geometry.mesh, str) and geometry.mesh in presets]
    options += [f"mesh {mesh} (body.mesh, or the study's meshes: about {fits:.3g} GB)"
                for mesh, fits in coarser if fits is not None]
    needed = math.ceil(peak_bytes / GB * 100) / 100
    options += [f"body.max_memory_gb: {needed:g} or more (now {in_unit(build.max_bytes, GB):g}, "
                "on a machine with that memory)",
                "a smaller grid (surfaces.grid, or for a measured surface surface.crop_mm, "
                "surface.decimate or surface.resample_grid)"]
    return options


def memory_message(geometry: Geometry, build: BuildSettings, peak_bytes: float,
                   configured: Geometry | None = None) -> str:
    """Why a geometry's influence build does not fit, and the config keys that change it
    (:func:`memory_options`; ``configured`` the geometry as configured, by default
    ``geometry``)."""
    nx, ny = geometry.grid
    limit_gb = in_unit(build.max_bytes, GB)
    model = geometry.planned_model(build.max_bytes)
    options = memory_options(geometry, build, peak_bytes,
                             geometry if configured is None else configured)
    return (f"influence geometry {geometry.key}: {nx} x {ny} elements, operator "
            f"{model.value}, mesh {geometry.mesh}: estimated peak memory "
            f"{peak_bytes / GB:.3g} GB, more than body.max_memory_gb = {limit_gb:g} GB. "
            "Options: " + "; ".join(options))
