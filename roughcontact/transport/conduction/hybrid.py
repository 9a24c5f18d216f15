"""Matrix-free thermal influence of the finite block, for contact grids beyond 64 x 64.

The dense ``k R`` of :func:`~roughcontact.transport.conduction.block.unit_conductivity_influence`
needs ``8 n^2`` bytes and a finite-element solve on the contact grid; the
elastic model meets the same wall with its hybrid operator
(:mod:`roughcontact.elasticity.operators`: Love's half-space by FFT plus the
finite body's correction from a coarse finite-element model). The thermal
block takes the same form:

    k R = k R_half + A_f W K W^T,   K = (k R_fe - k R_half)(coarse) / A_c,

- ``k R_half``: the thermal half-space at the fine grid, the kernel ``1 / (2 pi
  r)``; it is Love's unit-modulus kernel at ``nu = 0`` (``1 / (pi r)``) times
  1/2 (:mod:`~roughcontact.transport.conduction.halfspace`), applied by a
  zero-padded FFT;
- ``K``: the finite block's correction per unit loaded area [1/m] (the
  isothermal base at depth ``L``, the insulated sides), from the dense thermal
  influence of the same block on a coarse contact grid; ``W`` the separable
  linear interpolation from coarse to fine element centres, ``A_f``, ``A_c``
  the element areas.

So ``k R = 0.5 * (E C)`` of the elastic hybrid operator at ``nu = 0`` built
from the coarse ``2 k R_fe``: :func:`hybrid_thermal_from_coarse` is
``scaled(hybrid_operator(geom at nu = 0, 2 k R_fe, coarse at nu = 0), 0.5)``
(:func:`~roughcontact.elasticity.operators.hybrid_operator`'s recipe,
:func:`~roughcontact.contact.counterface.scaled`), and no finite-element
solve. What a file must hold to rebuild it is the coarse block's dense ``k R``
(:func:`thermal_correction`, an ``nc x nc`` matrix: 134 MB at the largest
coarse grid, 64 x 64; 6.5 MB at 30 x 30); :func:`hybrid_thermal_influence`
builds both in one call.

The coarse model is the block on :func:`~roughcontact.elasticity.operators.default_coarse_grid`
(at most ``COARSE_MAX`` per side) with the fine model's mesh when it is one of
``HYBRID_MESHES``, else "refined": the paper's five layers and the graded
preset are too conductive near the face (the flux channel: -7.4 % at 8 x 4,
docs/performance/conductance.md), an error the interpolation would carry to
the fine grid.

Accuracy against the dense fine ``k R`` is measured in
``benchmarks/bench_thermal_hybrid.py`` and tested in
``tests/transport/test_thermal_hybrid.py``. Two differences are by
construction: the half-space part is the centre-point (collocation) kernel
while the finite-element matrix is patch-averaged (Galerkin), so the two
near fields differ by the patch average of ``1 / r`` over one element; and
the rows of the hybrid sum to ``L`` only to the interpolation's accuracy
(the finite-element matrix's do exactly), so full contact gives ``k A / L``
only to that accuracy.

The operator is a :class:`~roughcontact.contact.counterface.ScaledInfluence`
of a :class:`~roughcontact.elasticity.operators.BlockOperator`: an influence
operator (``matvec``, ``diagonal``, ``restrict``), not a grid operator, so the
conductance's CG (:func:`~roughcontact.contact.stiffness.free_set_cg`) runs on
it unpreconditioned, as on the free thermal half-space
(:func:`~roughcontact.transport.conduction.halfspace.free_thermal_halfspace`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from roughcontact.contact.counterface import scaled
from roughcontact.elasticity.hybrid import finite_body_correction
from roughcontact.elasticity.influence import BlockGeometry
from roughcontact.elasticity.operators import HYBRID_MESHES, BlockOperator, coarse_geometry
from roughcontact.transport.conduction.block import unit_conductivity_influence

__all__ = ["hybrid_coarse_geometry", "hybrid_thermal_from_coarse", "hybrid_thermal_influence",
           "thermal_correction"]


def hybrid_coarse_geometry(geom: BlockGeometry, coarse_grid=None) -> BlockGeometry:
    """The coarse model of ``geom``'s hybrid thermal influence: the elastic hybrid's
    (:func:`~roughcontact.elasticity.operators.coarse_geometry`), the same block on
    ``coarse_grid`` (default :func:`~roughcontact.elasticity.operators.default_coarse_grid`)
    with ``geom``'s mesh when it is one of ``HYBRID_MESHES``, else "refined"."""
    if not isinstance(geom, BlockGeometry):
        raise ValueError(f"geom must be a BlockGeometry, got {type(geom).__name__}")
    return coarse_geometry(geom, coarse_grid)


def _check_coarse(geom: BlockGeometry, coarse: BlockGeometry) -> None:
    """``coarse`` must be ``geom``'s block (size, thickness) on an accurate mesh."""
    if not isinstance(coarse, BlockGeometry):
        raise ValueError(f"coarse must be a BlockGeometry, got {type(coarse).__name__}")
    same = np.allclose(coarse.size, geom.size, rtol=1e-12, atol=0.0) and \
        np.isclose(coarse.thickness, geom.thickness, rtol=1e-12, atol=0.0)
    if not same:
        raise ValueError(f"coarse block {coarse.size} m x {coarse.thickness} m is not the fine "
                         f"one, {geom.size} m x {geom.thickness} m")
    if not (isinstance(coarse.mesh, str) and coarse.mesh in HYBRID_MESHES):
        raise ValueError(f"the coarse model's mesh must be one of {HYBRID_MESHES} (an accurate "
                         f"near field), got {coarse.mesh!r}")


def thermal_correction(coarse: BlockGeometry, *, solver: str = "auto") -> np.ndarray:
    """What a file holds to rebuild the hybrid thermal influence: the coarse block's
    dense ``k R`` [m], ``(nc, nc)`` (:func:`unit_conductivity_influence` of ``coarse``;
    :func:`hybrid_thermal_from_coarse` turns it into the correction). ``coarse`` must
    have a mesh of ``HYBRID_MESHES``."""
    if not (isinstance(coarse, BlockGeometry) and isinstance(coarse.mesh, str)
            and coarse.mesh in HYBRID_MESHES):
        raise ValueError(f"coarse must be a BlockGeometry with a mesh of {HYBRID_MESHES}, "
                         f"got {coarse!r}")
    return unit_conductivity_influence(coarse, solver=solver)


def hybrid_thermal_from_coarse(geom: BlockGeometry, coarse: BlockGeometry,
                               coarse_kR: np.ndarray, *, workers: int = 1):
    """The matrix-free ``k R`` [m] of ``geom``'s block from its coarse model's dense
    ``k R`` (:func:`thermal_correction`), with no finite-element solve (module docstring).

    Parameters
    ----------
    geom : BlockGeometry
        Block and fine contact grid (``E``, ``nu``, ``base`` unused).
    coarse : BlockGeometry
        The same block (size, thickness) on the coarse grid of ``coarse_kR``, a mesh
        of ``HYBRID_MESHES`` (:func:`hybrid_coarse_geometry`).
    coarse_kR : ndarray, shape (nc, nc)
        ``unit_conductivity_influence(coarse)`` [m]; not modified.
    workers : int
        Threads of the FFTs.

    Returns
    -------
    ScaledInfluence
        ``0.5 * BlockOperator``: ``matvec``, ``diagonal``, ``restrict``, ``element_area``,
        ``grid`` of ``geom``; symmetric positive definite (to rounding).
    """
    if not isinstance(geom, BlockGeometry):
        raise ValueError(f"geom must be a BlockGeometry, got {type(geom).__name__}")
    _check_coarse(geom, coarse)
    nc = coarse.n_elements
    unit = np.asarray(coarse_kR, dtype=float)
    if unit.shape != (nc, nc) or not np.all(np.isfinite(unit)):
        raise ValueError(f"coarse_kR must be a finite ({nc}, {nc}) matrix (coarse grid "
                         f"{coarse.grid}), got shape {unit.shape}")
    # hybrid_operator's recipe (Love at E = 1, nu = 0 is 2 k R_half), with the FFTs' workers
    correction = finite_body_correction(2.0 * unit, dataclasses.replace(coarse, nu=0.0))
    operator = BlockOperator(grid=geom.grid, size=geom.size, nu=0.0, correction=correction,
                             coarse_grid=coarse.grid, workers=int(workers))
    return scaled(operator, 0.5)


def hybrid_thermal_influence(geom: BlockGeometry, *, coarse: BlockGeometry | None = None,
                             solver: str = "auto", workers: int = 1):
    """Matrix-free thermal influence ``k R`` [m] of the block on ``geom``'s grid (module
    docstring): the thermal half-space plus the finite block's correction from
    ``coarse``'s dense ``k R`` (default :func:`hybrid_coarse_geometry`).

    ``solver`` is the coarse model's sparse solver; returns as
    :func:`hybrid_thermal_from_coarse`.
    """
    coarse = hybrid_coarse_geometry(geom) if coarse is None else coarse
    _check_coarse(geom, coarse)
    return hybrid_thermal_from_coarse(geom, coarse, thermal_correction(coarse, solver=solver),
                                      workers=workers)
