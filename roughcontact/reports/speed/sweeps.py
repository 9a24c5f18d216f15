"""Shared pieces of the speed experiments: a cell's surfaces, a timed contact sweep.

Every experiment of :mod:`roughcontact.reports.speed` generates the surfaces of
a statistics cell (:func:`cell_heights`, seeded per experiment and cell) and
sweeps them as a contact job does (:func:`timed_sweep`, wall time in seconds).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Mapping

import numpy as np

from roughcontact.contact.cell import sweep_cell
from roughcontact.contact.curves import NondimSweep
from roughcontact.elasticity.influence import BlockGeometry
from roughcontact.surfaces.spec import SurfaceSpec
from roughcontact.surfaces.synthetic import derive_seeds, generate_many

__all__ = ["cell_heights", "cell_key", "reporter", "timed_sweep"]

log = logging.getLogger("roughcontact.speed")


def reporter(progress: Callable[[str], None] | None) -> Callable[[str], None]:
    """``progress``, or (when None) a writer of INFO lines to the ``roughcontact.speed`` log."""
    return progress or (lambda message: log.info("%s", message))


def cell_key(skew: float, kurt: float) -> str:
    """Name of a statistics cell (skewness, kurtosis) in seeds and messages, e.g. ``sk0_ku3``."""
    return f"sk{float(skew):g}_ku{float(kurt):g}"


def cell_heights(grid, size, b: float, skew: float, kurt: float, count: int, seed: int,
                 tag: str, spectrum: Mapping | None = None) -> np.ndarray:
    """``count`` surfaces of one cell in units of sigma, shape (count, ny, nx).

    Exponential ACF (Eq 1) with 10 % correlation length ``b`` [m], periodic
    filter of the pipeline; seeds from ``derive_seeds(seed, tag|cell, count)``.
    ``spectrum``: :class:`SurfaceSpec` fields replacing the ACF (e.g.
    ``acf="self-affine"``, ``hurst``, ``rolloff_wavelength``,
    ``cutoff_wavelength``); ``b`` is then unused.
    """
    if spectrum:
        spec = SurfaceSpec(grid=tuple(grid), size=tuple(size), sigma=1.0, skew=float(skew),
                           kurt=float(kurt), **spectrum)
    else:
        spec = SurfaceSpec(grid=tuple(grid), size=tuple(size), corr_length=(b, b), sigma=1.0,
                           skew=float(skew), kurt=float(kurt))
    seeds = derive_seeds(seed, f"{tag}|{cell_key(skew, kurt)}", count)
    return generate_many(spec, seeds)


def timed_sweep(unit_influence, heights, geometry: BlockGeometry, pressure_end: float,
                steps: int, **options) -> tuple[NondimSweep, float]:
    """One :func:`~roughcontact.contact.cell.sweep_cell` and its wall time [s].

    ``options`` go to ``sweep_cell``; callers pass ``precision`` explicitly
    (the sweep's default is "mixed", the exact reference needs "double").
    """
    start = time.perf_counter()
    sweep = sweep_cell(unit_influence, heights, geometry, pressure_end, steps, **options)
    return sweep, time.perf_counter() - start
