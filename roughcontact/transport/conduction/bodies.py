"""The bodies heat and current cross: a half-space, the study's block, two in series.

Each is a frozen value with the same interface, read by the conductance probe
(:class:`~roughcontact.transport.conduction.probe.ConductanceProbe`):
``unit_influence(grid, spacing, built=None)``, its influence ``k R`` [m] for unit
conductivity on the sweep's grid (``built``: one given, e.g. read from a file);
``unit_bulk_resistance(operator, tol)``, its bulk resistance times ``k`` [1/m] (of its
influence ``operator``); ``parts()``, the bodies in series with their ratios;
``unbounded_at_full_contact``; ``params()`` (and :func:`body_from_params` back).

:class:`HalfSpaceBody`
    a half-space, periodic (FFT; the face's mean temperature the reference, so the
    conductance is the constriction's alone) or free (the zero-padded FFT, or the
    dense element integral); no bulk;
:class:`BlockBody`
    the finite block of the elastic model
    (:class:`~roughcontact.elasticity.influence.BlockGeometry`), isothermal base,
    insulated sides (:func:`~roughcontact.transport.conduction.block.unit_conductivity_influence`);
    dense up to 64 x 64 contact elements, matrix-free beyond (Love's half-space and the
    correction of a coarse block,
    :func:`~roughcontact.transport.conduction.hybrid.hybrid_thermal_influence`); its
    bulk full contact's resistance, ``L / A_n`` of the dense influence (whose rows sum
    to ``L``), the matrix-free one's own;
:class:`SeriesBody`
    a body and the counter body the heat crosses after it, ``R = R1 / k1 + R2 / k2``
    on the same elements (:func:`~roughcontact.transport.conduction.spot.in_series`):
    in the first body's units, ``k1 R = k1 R1 + (k1 / k2) k2 R2``, ``ratio = k1 / k2``
    (for the current ``rho2 / rho1``); its bulk the first's plus ``ratio`` times the
    counter's (:meth:`SeriesBody.parts`).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from roughcontact.contact.checks import given_matrix
from roughcontact.contact.counterface import scaled
from roughcontact.elasticity.influence import BlockGeometry, MeshSpec
from roughcontact.transport.conduction.block import unit_conductivity_influence
from roughcontact.transport.conduction.halfspace import (
    free_thermal_halfspace,
    halfspace_thermal_influence,
    periodic_thermal_halfspace,
)
from roughcontact.transport.conduction.hybrid import hybrid_thermal_influence
from roughcontact.transport.conduction.spot import full_contact_resistance, in_series

__all__ = ["DENSE_LIMIT", "BlockBody", "HalfSpaceBody", "SeriesBody", "body_from_params"]

#: Contact elements of the largest block whose thermal influence is dense (64 x 64, the
#: elastic model's dense limit); beyond it the matrix-free hybrid.
DENSE_LIMIT = 64 * 64

#: Relative agreement of a block's grid spacing with the sweep's.
SPACING_RTOL = 1e-9


def _given(built, grid):
    """A dense ``k R`` given for ``grid`` ``(nx, ny)``, checked to fit it."""
    n = int(grid[0]) * int(grid[1])
    if np.shape(built) != (n, n):
        raise ValueError(f"the given influence has shape {np.shape(built)}, the sweep's "
                         f"grid {tuple(grid)} needs ({n}, {n})")
    return built


@dataclass(frozen=True)
class HalfSpaceBody:
    """A half-space's face (module docstring).

    Parameters
    ----------
    periodic : bool
        Periodic (FFT, mean temperature the reference) or free.
    dense : bool
        Free only: the dense element integral
        (:func:`~roughcontact.transport.conduction.halfspace.halfspace_thermal_influence`,
        ``n^2`` numbers) instead of the zero-padded FFT (the default).
    """

    name: ClassVar[str] = "halfspace"

    periodic: bool = False
    dense: bool = False

    def __post_init__(self):
        for key in ("periodic", "dense"):
            if not isinstance(getattr(self, key), bool | np.bool_):
                raise ValueError(f"body.{key} must be true or false, got "
                                 f"{getattr(self, key)!r}")
        if self.periodic and self.dense:
            raise ValueError("body.dense is for a free half-space: set periodic or dense "
                             "false")

    def unit_influence(self, grid, spacing, built=None):
        """``k R`` [m] on ``grid`` ``(nx, ny)`` of element sides ``spacing`` [m] (``built``:
        a dense one given, of that grid)."""
        if built is not None:
            return _given(built, grid)
        size = (grid[0] * spacing[0], grid[1] * spacing[1])
        if self.periodic:
            return periodic_thermal_halfspace(grid, size, 1.0)
        if self.dense:
            return halfspace_thermal_influence(grid, size, 1.0)
        return free_thermal_halfspace(grid, size, 1.0)

    def unit_bulk_resistance(self, operator=None, tol: float = 1e-10) -> float:
        """The bulk resistance times ``k`` [1/m]: 0, a half-space has none."""
        return 0.0

    def parts(self) -> tuple:
        """The bodies in series and their ratios: itself alone."""
        return ((self, 1.0),)

    @property
    def unbounded_at_full_contact(self) -> bool:
        """A periodic half-space's full contact has no resistance at all."""
        return self.periodic

    def params(self) -> dict:
        return {"body": self.name, "periodic": bool(self.periodic), "dense": bool(self.dense)}


@dataclass(frozen=True)
class BlockBody:
    """The finite block of the elastic model (module docstring).

    Parameters
    ----------
    geometry : BlockGeometry
        Plan size, thickness, contact grid and mesh (``E``, ``nu``, ``base`` unused).
    solver : {"auto", "pardiso", "superlu"}
        Sparse solver of the condensation.
    """

    name: ClassVar[str] = "block"
    unbounded_at_full_contact: ClassVar[bool] = False

    geometry: BlockGeometry
    solver: str = "auto"

    def __post_init__(self):
        if not isinstance(self.geometry, BlockGeometry):
            raise ValueError(f"body.geometry must be a BlockGeometry, got "
                             f"{type(self.geometry).__name__}")

    def unit_influence(self, grid, spacing, built=None):
        """``k R`` [m] of the block (``built``: given, e.g. read from its file): dense up
        to :data:`DENSE_LIMIT` contact elements, matrix-free beyond
        (:func:`~roughcontact.transport.conduction.hybrid.hybrid_thermal_influence`);
        ``grid`` and ``spacing`` must be its own."""
        geom = self.geometry
        own = (geom.size[0] / geom.grid[0], geom.size[1] / geom.grid[1])
        if tuple(grid) != tuple(geom.grid) or not np.allclose(spacing, own,
                                                              rtol=SPACING_RTOL, atol=0.0):
            raise ValueError(
                f"body.geometry has grid {geom.grid} of elements {own} m, the sweep's "
                f"fields grid {tuple(grid)} of elements {tuple(spacing)} m: give the "
                f"block the sweep's grid and size")
        if built is not None:
            return _given(built, grid)
        if geom.grid[0] * geom.grid[1] > DENSE_LIMIT:
            return hybrid_thermal_influence(geom, solver=self.solver)
        return unit_conductivity_influence(geom, solver=self.solver)

    def unit_bulk_resistance(self, operator=None, tol: float = 1e-10) -> float:
        """The bulk resistance times ``k`` [1/m], full contact's: of the dense influence
        (``operator`` None or a matrix) ``L / A_n`` (1-D conduction through the
        thickness; the condensed influence's rows sum to ``L``, so its full-contact solve
        gives the same to rounding); of the matrix-free one (beyond
        :data:`DENSE_LIMIT`) its own full-contact solve (its rows sum to ``L`` only to
        its interpolation's accuracy, and the bulk must be its own for the constriction
        ``1/C - R_bulk`` to be)."""
        if operator is None or given_matrix(operator) is not None:
            geom = self.geometry
            return geom.thickness / (geom.size[0] * geom.size[1])
        return full_contact_resistance(operator, tol=tol)

    def parts(self) -> tuple:
        """The bodies in series and their ratios: itself alone."""
        return ((self, 1.0),)

    def params(self) -> dict:
        geom = self.geometry
        mesh = geom.mesh if isinstance(geom.mesh, str) else dataclasses.asdict(geom.mesh)
        return {"body": self.name, "size": list(geom.size), "thickness": geom.thickness,
                "grid": list(geom.grid), "mesh": mesh, "solver": self.solver}


@dataclass(frozen=True)
class SeriesBody:
    """A body and the counter body the heat crosses after it (module docstring).

    Parameters
    ----------
    first : HalfSpaceBody or BlockBody
        The body whose conductivity the probe's columns are in.
    counter : HalfSpaceBody or BlockBody
        The counter body, on the same grid.
    ratio : float
        ``k1 / k2`` (thermal) or ``rho2 / rho1`` (electrical): the counter's influence
        in the first body's units.
    """

    name: ClassVar[str] = "series"

    first: HalfSpaceBody | BlockBody
    counter: HalfSpaceBody | BlockBody
    ratio: float

    def __post_init__(self):
        for key in ("first", "counter"):
            if not isinstance(getattr(self, key), HalfSpaceBody | BlockBody):
                raise ValueError(f"body.{key} must be a HalfSpaceBody or a BlockBody, got "
                                 f"{type(getattr(self, key)).__name__}")
        ratio = float(self.ratio)
        if not (math.isfinite(ratio) and ratio > 0.0):
            raise ValueError(f"body.ratio must be a finite positive number, got "
                             f"{self.ratio!r}")
        object.__setattr__(self, "ratio", ratio)

    @property
    def unbounded_at_full_contact(self) -> bool:
        """Full contact has no resistance only where neither body has any."""
        return self.first.unbounded_at_full_contact and self.counter.unbounded_at_full_contact

    def unit_influence(self, grid, spacing, built=None):
        """``k1 R1 + ratio k2 R2`` [m] (``built``: the first body's, given): one dense
        matrix where both are dense, else their sum applied product by product."""
        area = spacing[0] * spacing[1]
        first = self.first.unit_influence(grid, spacing, built)
        counter = scaled(self.counter.unit_influence(grid, spacing), self.ratio,
                         element_area=area)
        return in_series(first, counter, element_area=area)

    def parts(self) -> tuple:
        """The bodies in series and their ratios: the first (1) and the counter
        (``ratio``); the series' bulk is theirs so weighted, each of its own influence."""
        return ((self.first, 1.0), (self.counter, self.ratio))

    def params(self) -> dict:
        return {"body": self.name, "first": self.first.params(),
                "counter": self.counter.params(), "ratio": self.ratio}


def body_from_params(params: dict) -> HalfSpaceBody | BlockBody | SeriesBody:
    """The body of stored settings (``params()`` of :class:`HalfSpaceBody`,
    :class:`BlockBody` or :class:`SeriesBody`)."""
    name = params.get("body")
    if name == HalfSpaceBody.name:
        return HalfSpaceBody(periodic=bool(params["periodic"]), dense=bool(params["dense"]))
    if name == BlockBody.name:
        mesh = params["mesh"]
        geometry = BlockGeometry(size=tuple(params["size"]), thickness=params["thickness"],
                                 grid=tuple(params["grid"]),
                                 mesh=mesh if isinstance(mesh, str) else MeshSpec(**mesh))
        return BlockBody(geometry, solver=str(params["solver"]))
    if name == SeriesBody.name:
        return SeriesBody(body_from_params(params["first"]),
                          body_from_params(params["counter"]), float(params["ratio"]))
    raise ValueError(f"body.body must be one of ('{HalfSpaceBody.name}', "
                     f"'{BlockBody.name}', '{SeriesBody.name}'), got {name!r}")
