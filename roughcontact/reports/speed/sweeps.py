"""Shared pieces of the speed experiments: a cell's surfaces, a timed contact sweep.

Every experiment of :mod:`roughcontact.reports.speed` generates the surfaces of
a statistics cell (:meth:`CellSurfaces.heights`, seeded per experiment and cell)
and sweeps them as a contact job does (:class:`SweepSettings`, :func:`timed_sweep`,
wall time in seconds). The two records are built once by the caller and shared
by the experiments.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from roughcontact.contact.cell import SWEEP_OPTIONS, nondim_pressure, sweep_cell
from roughcontact.contact.curves import NondimSweep
from roughcontact.contact.nondim import CellOptions
from roughcontact.elasticity.influence import BlockGeometry
from roughcontact.surfaces.spec import SurfaceSpec
from roughcontact.surfaces.synthetic import derive_seeds, generate_many

__all__ = [
    "DEFAULT_SURFACES",
    "DEFAULT_SWEEP",
    "CellSurfaces",
    "SweepSettings",
    "cell_key",
    "reporter",
    "timed_sweep",
]

log = logging.getLogger("roughcontact.speed")


def reporter(progress: Callable[[str], None] | None) -> Callable[[str], None]:
    """``progress``, or (when None) a writer of INFO lines to the ``roughcontact.speed`` log."""
    return progress or (lambda message: log.info("%s", message))


def cell_key(skew: float, kurt: float) -> str:
    """Name of a statistics cell (skewness, kurtosis) in seeds and messages, e.g. ``sk0_ku3``."""
    return f"sk{float(skew):g}_ku{float(kurt):g}"


@dataclass(frozen=True)
class CellSurfaces:
    """How every experiment generates the random surfaces of a statistics cell.

    Attributes
    ----------
    sigma : float
        Height standard deviation [m]. The surfaces are generated in units of
        sigma; sigma scales their pressures and approaches (Eq 28-32).
    b : float
        10 % correlation length of the exponential ACF (Eq 1) [m], the same
        along x and y.
    seed : int
        Root seed: the surfaces of an experiment's cell are seeded by
        ``derive_seeds(seed, "<tag>|<cell>", count)``.
    spectrum : mapping or None
        :class:`~roughcontact.surfaces.spec.SurfaceSpec` fields replacing the ACF
        (e.g. ``acf="self-affine"``, ``hurst``, ``rolloff_wavelength``,
        ``cutoff_wavelength`` [m]); ``b`` is then unused. None: the ACF of Eq 1.

    The defaults are the paper's (Table 1): sigma 24.5 um, b 1 mm, seed 2006.
    """

    sigma: float = 24.5e-6
    b: float = 1e-3
    seed: int = 2006
    spectrum: Mapping | None = None

    def heights(self, grid, size, cell: tuple[float, float], count: int,
                tag: str) -> np.ndarray:
        """``count`` surfaces of ``cell`` (skew, kurt; Eq 4-5) in units of sigma, shape
        (count, ny, nx), on ``grid`` (nx, ny) over ``size`` (Lx, Ly) [m].

        Periodic filter of the pipeline, unit standard deviation; seeds from
        ``derive_seeds(seed, tag|cell, count)`` (:func:`cell_key`).
        """
        skew, kurt = cell
        if self.spectrum:
            spec = SurfaceSpec(grid=tuple(grid), size=tuple(size), sigma=1.0, skew=float(skew),
                               kurt=float(kurt), **self.spectrum)
        else:
            spec = SurfaceSpec(grid=tuple(grid), size=tuple(size), corr_length=(self.b, self.b),
                               sigma=1.0, skew=float(skew), kurt=float(kurt))
        seeds = derive_seeds(self.seed, f"{tag}|{cell_key(skew, kurt)}", count)
        return generate_many(spec, seeds)


@dataclass(frozen=True)
class SweepSettings:
    """How every experiment sweeps a cell, as a contact job does.

    :func:`~roughcontact.contact.cell.sweep_cell` over ``steps`` geometric
    approaches up to one carrying the largest of ``pressures`` on every
    surface, with ``method`` to the dimensionless KKT residual ``tol`` (Eq 27)
    in ``precision``, warm starts and tangent stiffness; the experiments read
    their tables at each of ``pressures`` [Pa]. The solver study compares its
    own methods and tolerances (:class:`~roughcontact.reports.speed.experiments.SolverComparison`)
    and uses only ``pressures``, ``steps`` and ``precision``.

    The defaults are the pipeline's steps, tolerance and precision
    (``config/schema.yaml``: 30, 1e-8, mixed) with cg, read at 0.3, 1 and 3 MPa.
    """

    pressures: tuple[float, ...] = (0.3e6, 1e6, 3e6)
    steps: int = 30
    precision: str = "mixed"
    method: str = "cg"
    tol: float = 1e-8

    def end(self, geometry: BlockGeometry, sigma: float) -> float:
        """The dimensionless nominal pressure the sweeps reach: the largest of ``pressures``
        on ``geometry`` (L [m], E [Pa]) for surfaces of height std ``sigma`` [m]."""
        return nondim_pressure(max(self.pressures), thickness=geometry.thickness, E=geometry.E,
                               sigma=sigma)


#: The paper's surfaces (sigma 24.5 um, b 1 mm, seed 2006): the experiments' default.
DEFAULT_SURFACES = CellSurfaces()
#: The pipeline's sweep at 0.3, 1 and 3 MPa: the experiments' default.
DEFAULT_SWEEP = SweepSettings()


def timed_sweep(unit_influence, heights, geometry: BlockGeometry, pressure_end: float,
                steps: int, options: CellOptions = SWEEP_OPTIONS) -> tuple[NondimSweep, float]:
    """One :func:`~roughcontact.contact.cell.sweep_cell` and its wall time [s].

    ``options`` go to ``sweep_cell``; callers set ``precision`` explicitly
    (``SWEEP_OPTIONS.with_(precision=...)``: the sweep's default is "mixed", the exact
    reference needs "double").
    """
    start = time.perf_counter()
    sweep = sweep_cell(unit_influence, heights, geometry, pressure_end, steps, options=options)
    return sweep, time.perf_counter() - start
