"""The thermal influence job: a block's ``k R`` built once and stored for its contact jobs.

:func:`build_thermal` builds the unit-conductivity influence of a
:class:`~roughcontact.study.thermal_records.ThermalBlock`
(:func:`roughcontact.transport.conduction.block.unit_conductivity_influence`: the
scalar Laplace problem on the elastic model's mesh, isothermal base, insulated sides;
beyond 64 x 64 elements that of its coarse model, from which the job rebuilds the
matrix-free one, :mod:`roughcontact.transport.conduction.hybrid`) and stores it with
the block's params, the run's provenance and a content hash; :func:`read_thermal`
reads it back for a contact job, checked to have been made for the
job's block (the params compared field by field, the hash verified, the shape the
block's grid). Its params become its record in its first lines (the job's edge).
"""

from __future__ import annotations

import logging
import os
import time

from roughcontact.study.jobs.storage import (
    check_attributes,
    datasets_sha256,
    decoded,
    open_h5,
    parameters_error,
    upgraded,
    verify,
    write_h5,
)
from roughcontact.study.provenance import NO_RUN, RunInfo, provenance
from roughcontact.study.thermal_records import ThermalBlock
from roughcontact.transport.conduction.block import unit_conductivity_influence
from roughcontact.transport.conduction.bodies import DENSE_LIMIT
from roughcontact.transport.conduction.hybrid import hybrid_thermal_from_coarse, thermal_correction

__all__ = ["build_thermal", "read_thermal"]

log = logging.getLogger(__name__)

#: The dataset of a thermal influence file: the dense ``k R``, or (beyond
#: :data:`~roughcontact.transport.conduction.bodies.DENSE_LIMIT` elements) the coarse
#: block's, from which the matrix-free one is rebuilt.
DATASET, COARSE_DATASET = "unit_conductivity_influence", "coarse_unit_conductivity_influence"


def build_thermal(params: dict, out_path, solver: str = "auto", run: RunInfo = NO_RUN) -> dict:
    """Build the thermal influence ``k R`` [m] of the block of ``params``
    (:meth:`~roughcontact.study.thermal_records.ThermalBlock.params`) with the sparse
    ``solver`` and write it to ``out_path`` with the provenance of ``run`` (the
    script's :meth:`~roughcontact.study.provenance.RunInfo.of` its configuration);
    returns the attributes written."""
    block = ThermalBlock.from_params(params)
    start = time.perf_counter()
    log.info("thermal influence of block %s: %d x %d elements, %s mesh", block.key,
             *block.grid, block.mesh)
    coarse = block.coarse_model()
    if coarse is None:
        unit = unit_conductivity_influence(block.block(), solver=solver)
        datasets, extra = {DATASET: unit}, {}
    else:  # matrix-free: the coarse block's dense k R, from which the job rebuilds it
        log.info("beyond %d elements: matrix-free, its finite-block correction from the "
                 "block on %d x %d elements (%s mesh)", DENSE_LIMIT, *coarse.grid,
                 coarse.mesh)
        unit = thermal_correction(coarse, solver=solver)
        datasets = {COARSE_DATASET: unit}
        extra = {"coarse": {"grid": list(coarse.grid), "mesh": coarse.mesh}}
    seconds = time.perf_counter() - start
    rows = unit.sum(axis=1)
    log.info("built in %.1f s; row sums %.10g-%.10g m (the thickness %.10g m: full contact "
             "gives k A / L)", seconds, rows.min(), rows.max(), block.thickness)
    attrs = {"params": block.params(), **extra, "wall_seconds": seconds,
             "content_sha256": datasets_sha256(datasets), **provenance(run)}
    write_h5(out_path, datasets, attrs)
    return attrs


def read_thermal(path: str | os.PathLike, block: ThermalBlock):
    """``k R`` [m] of a thermal influence file made for ``block`` (its params compared
    field by field, its content hash verified, its shape the block's grid or its coarse
    model's), else :class:`~roughcontact.errors.StoredFileError` naming the file and what
    differs: the dense matrix, or beyond :data:`DENSE_LIMIT` elements the matrix-free
    operator rebuilt from the stored coarse block's (no finite-element solve)."""
    geometry, coarse = block.block(), block.coarse_model()
    name = DATASET if coarse is None else COARSE_DATASET
    with open_h5(path) as f:
        attrs = upgraded(path, decoded(f.attrs), "thermal")
        expected = {"params": block.params()}
        if coarse is not None:
            expected["coarse"] = {"grid": list(coarse.grid), "mesh": coarse.mesh}
        check_attributes(path, attrs, expected)
        if name not in f:
            raise parameters_error(path, [("dataset", name, sorted(f))])
        unit = f[name][...]
    verify(path, attrs, datasets_sha256({name: unit}))
    grid = geometry.grid if coarse is None else coarse.grid
    n = grid[0] * grid[1]
    if unit.shape != (n, n):
        raise parameters_error(path, [(f"shape of {name} (n x n for the {grid} grid)",
                                       [n, n], list(unit.shape))])
    return unit if coarse is None else hybrid_thermal_from_coarse(geometry, coarse, unit)
