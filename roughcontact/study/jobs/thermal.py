"""The thermal influence job: a block's ``k R`` built once and stored for its contact jobs.

:func:`build_thermal` builds the unit-conductivity influence of a
:class:`~roughcontact.study.thermal_records.ThermalBlock`
(:func:`roughcontact.transport.conduction.block.unit_conductivity_influence`: the
scalar Laplace problem on the elastic model's mesh, isothermal base, insulated sides)
and stores it with the block's params, the run's provenance and a content hash;
:func:`read_thermal` reads it back for a contact job, checked to have been made for the
job's block (the params compared field by field, the hash verified, the shape the
block's grid). Its params become its record in its first lines (the job's edge).
"""

from __future__ import annotations

import logging
import os
import time

import numpy as np

from roughcontact.study.jobs.storage import (
    _decoded,
    check_attributes,
    datasets_sha256,
    open_h5,
    parameters_error,
    upgraded,
    verify,
    write_h5,
)
from roughcontact.study.provenance import RunInfo, provenance
from roughcontact.study.thermal_records import ThermalBlock
from roughcontact.transport.conduction.block import unit_conductivity_influence

__all__ = ["build_thermal", "read_thermal"]

log = logging.getLogger(__name__)

#: The dataset of a thermal influence file.
DATASET = "unit_conductivity_influence"


def build_thermal(params: dict, out_path, solver: str = "auto", config=None) -> dict:
    """Build the thermal influence ``k R`` [m] of the block of ``params``
    (:meth:`~roughcontact.study.thermal_records.ThermalBlock.params`) with the sparse
    ``solver`` and write it to ``out_path``; returns the attributes written."""
    run = RunInfo.of(config)  # the job's edge: the run it belongs to
    block = ThermalBlock.from_params(params)
    start = time.perf_counter()
    log.info("thermal influence of block %s: %d x %d elements, %s mesh", block.key,
             *block.grid, block.mesh)
    unit = unit_conductivity_influence(block.block(), solver=solver)
    seconds = time.perf_counter() - start
    rows = unit.sum(axis=1)
    log.info("built in %.1f s; row sums %.10g-%.10g m (the thickness %.10g m: full contact "
             "gives k A / L)", seconds, rows.min(), rows.max(), block.thickness)
    datasets = {DATASET: unit}
    attrs = {"params": block.params(), "wall_seconds": seconds,
             "content_sha256": datasets_sha256(datasets), **provenance(run)}
    write_h5(out_path, datasets, attrs)
    return attrs


def read_thermal(path: str | os.PathLike, block: ThermalBlock) -> np.ndarray:
    """``k R`` [m] of a thermal influence file made for ``block`` (its params compared
    field by field, its content hash verified, its shape the block's grid), else
    :class:`~roughcontact.errors.StoredFileError` naming the file and what differs."""
    with open_h5(path) as f:
        attrs = upgraded(path, _decoded(f.attrs), "thermal")
        check_attributes(path, attrs, {"params": block.params()})
        unit = f[DATASET][...]
    verify(path, attrs, datasets_sha256({DATASET: unit}))
    n = block.grid[0] * block.grid[1]
    if unit.shape != (n, n):
        raise parameters_error(path, [(f"shape of {DATASET} (n x n for the {block.grid} grid)",
                                       [n, n], list(unit.shape))])
    return unit
