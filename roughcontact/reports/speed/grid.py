"""The contact-grid experiment of the speed-against-error report.

:func:`grid_study` sweeps the same statistics on coarser and finer contact
grids over the same nominal area and reports the change of k_P (Eq 33), real
area and peak pressure at equal nominal pressure against the finest grid;
:data:`GRID_INFLUENCES` and :data:`PAIRINGS` hold its influence models and
its ways of pairing the surfaces across the grids, :class:`GridOptions` the
choice among them.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np
import pandas as pd

from roughcontact.contact.cell import SWEEP_OPTIONS, aggregate_sweep
from roughcontact.elasticity import operators
from roughcontact.elasticity.halfspace import halfspace_influence
from roughcontact.elasticity.influence import BlockGeometry, unit_modulus_influence
from roughcontact.reports.speed import sweeps
from roughcontact.reports.speed.machine import describe_machine

__all__ = ["GRID_COLUMNS", "GRID_INFLUENCES", "PAIRINGS", "PAPER_BLOCK", "GridOptions",
           "grid_study"]


def _hybrid_operator(geometry: BlockGeometry, coarsening: int):
    """Matrix-free hybrid: the dense hybrid matrix's operator, without its 8 n^2 bytes."""
    coarse = operators.coarsened_side(geometry.grid[0], coarsening)
    return operators.block_operator(geometry, coarse_grid=(coarse, coarse))


def _halfspace_matrix(geometry: BlockGeometry, coarsening: int):
    """Love's half-space, dense (``coarsening`` unused)."""
    return halfspace_influence(geometry.grid, geometry.size, 1.0, geometry.nu)


def _halfspace_fft(geometry: BlockGeometry, coarsening: int):
    """Love's half-space, matrix-free FFT convolution (``coarsening`` unused)."""
    return operators.halfspace_operator(geometry.grid, geometry.size, geometry.nu)


def _fe_matrix(geometry: BlockGeometry, coarsening: int):
    """The finite-element ``E C`` of ``geometry.mesh`` (``coarsening`` unused)."""
    return unit_modulus_influence(geometry)


#: Influence models of :func:`grid_study`: name -> (builder of ``E C`` [m] from a
#: geometry and a coarsening, the model's name in the table). ``"hybrid"``: the
#: matrix-free :class:`roughcontact.elasticity.operators.BlockOperator` (equal to
#: :func:`roughcontact.elasticity.hybrid.hybrid_unit_modulus_influence`), Love's
#: near field plus the finite-body correction of ``mesh`` on a grid ``coarsening``
#: times coarser (at most ``operators.COARSE_MAX`` per side): within 1.2 % of the
#: converged preset in k_P, area and peak pressure at 60 x 60 for about 3 s, and no
#: dense matrix (256 x 256 fits), where the refined finite-element model itself at
#: 120 x 120 would be four times that of 60 x 60 (about 0.5 M dofs). ``"halfspace"``:
#: Love's half-space (no finite-body bulk: k_P 11-17 % high at 60 x 60, fine for the
#: *change* between grids only); ``"halfspace_fft"``: the same, matrix-free (FFT
#: convolution, no n^2 matrix) for 240 x 240 and more; ``"fe"``: the finite-element
#: model of ``mesh`` (:func:`~roughcontact.elasticity.influence.unit_modulus_influence`).
GRID_INFLUENCES = MappingProxyType({
    "hybrid": (_hybrid_operator, "hybrid ({mesh}, coarsening {coarsening})"),
    "halfspace": (_halfspace_matrix, "halfspace"),
    "halfspace_fft": (_halfspace_fft, "halfspace_fft"),
    "fe": (_fe_matrix, "fe ({mesh})"),
})


def _nested_heights(cells, grids: list[int], generate: Callable) -> Callable:
    """Surfaces of the finest grid, point-sampled on every coarser one (and rescaled to
    unit std): ``heights(g, skew, kurt)``."""
    finest = grids[-1]
    if any(finest % g for g in grids):
        raise ValueError(f"nested pairing needs every grid to divide the finest, got {grids}")
    fine = {(skew, kurt): generate(finest, skew, kurt, "grid_study") for skew, kurt in cells}

    def heights(g: int, skew: float, kurt: float) -> np.ndarray:
        k = finest // g
        sampled = fine[(skew, kurt)][:, ::k, ::k]
        return sampled / sampled.std(axis=(1, 2), keepdims=True)

    return heights


def _independent_heights(cells, grids: list[int], generate: Callable) -> Callable:
    """Surfaces of their own on every grid (seeds per grid): ``heights(g, skew, kurt)``."""
    return lambda g, skew, kurt: generate(g, skew, kurt, f"grid_study|{g}")


#: Pairings of the surfaces across the grids of :func:`grid_study`: name -> maker of
#: ``heights(g, skew, kurt)`` from the cells, the sorted grids and a generator.
#: ``"nested"``: the finest grid's surfaces point-sampled (the same random field, a
#: coarser grid), so the change between grids is the discretization alone;
#: ``"independent"``: each grid's own surfaces, so the change also holds sampling
#: noise (see the ``*_half_width`` columns).
PAIRINGS = MappingProxyType({"nested": _nested_heights, "independent": _independent_heights})

#: Columns of the grid table -> the columns of the aggregated cell table
#: (:func:`roughcontact.contact.cell.aggregate_sweep`) they hold.
GRID_COLUMNS = MappingProxyType({
    "k_P_Pa": "normalized_stiffness_mean",
    "k_P_half_width_Pa": "normalized_stiffness_half_width",
    "real_area_fraction": "real_area_fraction_mean",
    "real_area_half_width": "real_area_fraction_half_width",
    "max_pressure_Pa": "max_pressure_mean",
    "max_pressure_half_width_Pa": "max_pressure_half_width",
})


#: The paper's block (Table 1: 9 mm x 9 mm x 10 mm, E = 511 MPa, nu = 0, clamped):
#: :func:`grid_study`'s default.
PAPER_BLOCK = BlockGeometry()


@dataclass(frozen=True)
class GridOptions:
    """How :func:`grid_study` models its grids and pairs their surfaces.

    Attributes
    ----------
    influence : str
        Influence model of every grid, a key of :data:`GRID_INFLUENCES`
        (default ``"hybrid"``: the matrix-free hybrid operator).
    mesh : str
        Mesh preset of the finite-element part (``"hybrid"``, ``"fe"``; default
        ``"refined"``).
    coarsening : int
        How many times coarser the hybrid's finite-element grid is (default 2).
    pairing : str
        How the surfaces are paired across the grids, a key of :data:`PAIRINGS`
        (default ``"nested"``).
    """

    influence: str = "hybrid"
    mesh: str = "refined"
    coarsening: int = 2
    pairing: str = "nested"

    def __post_init__(self) -> None:
        if self.pairing not in PAIRINGS:
            raise ValueError(f"pairing must be 'nested' or 'independent', got {self.pairing!r}")
        if self.influence not in GRID_INFLUENCES:
            raise ValueError("influence must be 'hybrid', 'halfspace', 'halfspace_fft' or "
                             f"'fe', got {self.influence!r}")

    def model_name(self) -> str:
        """The influence model's name in the table, e.g. ``hybrid (refined, coarsening 2)``."""
        return GRID_INFLUENCES[self.influence][1].format(mesh=self.mesh,
                                                         coarsening=self.coarsening)


def _grid_rows(frame: pd.DataFrame, fields: Mapping) -> list[dict]:
    """The grid table's rows of one aggregated sweep ``frame``, after the shared ``fields``."""
    return [dict(fields) | {"pressure_Pa": float(agg["nominal_pressure"])}
            | {name: agg[column] for name, column in GRID_COLUMNS.items()}
            for _, agg in frame.iterrows()]


def _changes_against_finest(table: pd.DataFrame) -> pd.DataFrame:
    """``table`` sorted, with the relative change ``q / q_finest - 1`` of k_P, real area and
    peak pressure at equal cell and pressure against the finest grid."""
    table = table.sort_values(["skew", "kurt", "grid", "pressure_Pa"], ignore_index=True)
    keys = ["skew", "kurt", "pressure_Pa"]
    finest_rows = table[table["grid"] == table["grid"].max()].set_index(keys)
    for name, column in (("k_P", "k_P_Pa"), ("real_area", "real_area_fraction"),
                         ("max_pressure", "max_pressure_Pa")):
        reference = finest_rows[column].reindex(pd.MultiIndex.from_frame(table[keys]))
        table[f"{name}_change"] = table[column].to_numpy() / reference.to_numpy() - 1.0
    return table


def grid_study(
    block: BlockGeometry = PAPER_BLOCK, cells: Sequence[tuple[float, float]] = ((0.0, 3.0),),
    *, grids: Sequence[int] = (30, 60, 120), surfaces: int = 4,
    generator: sweeps.CellSurfaces = sweeps.DEFAULT_SURFACES,
    sweep: sweeps.SweepSettings = sweeps.DEFAULT_SWEEP,
    options: GridOptions = GridOptions(), progress: Callable[[str], None] | None = None,
) -> pd.DataFrame:
    """k_P, real area and peak pressure of the same statistics on several contact grids.

    The square ``block`` (plan size [m], thickness L [m], E [Pa], nu, base;
    default: the paper's 9 mm x 9 mm x 10 mm), meshed with ``g`` x ``g``
    contact elements for each ``g`` in ``grids`` (its own grid and mesh are
    replaced), its influence coefficients from ``options``
    (:class:`GridOptions`; default: the matrix-free hybrid of the refined
    mesh, twice coarser). ``surfaces`` surfaces per cell of ``cells`` (skew,
    kurt), generated by ``generator``
    (:class:`~roughcontact.reports.speed.sweeps.CellSurfaces`: exponential ACF, Eq 1, or a
    spectrum, e.g. ``{"acf": "self-affine", "hurst": 0.8,
    "rolloff_wavelength": 3e-3, "cutoff_wavelength": 0.6e-3}``, with which real
    area and peak pressure converge with the grid, which they do not for Eq 1),
    are paired across the grids by ``options.pairing`` (:data:`PAIRINGS`;
    default: generated on the finest grid, point-sampled on the coarser ones).
    Each grid is swept as a contact job (``sweep``,
    :class:`~roughcontact.reports.speed.sweeps.SweepSettings`:
    :func:`~roughcontact.contact.cell.sweep_cell` with its method, tol, precision and
    steps) and averaged at its pressures
    (:func:`~roughcontact.contact.cell.aggregate_sweep`).

    Returns
    -------
    pandas.DataFrame
        One row per (cell, grid, pressure): ``skew``, ``kurt``, ``grid``,
        ``element_size_m`` (Lx / g), ``influence_model``, ``pairing``, ``build_s``
        (influence), ``solve_s`` (all surfaces), ``surfaces``,
        ``converged_fraction``, ``pressure_Pa``, the columns of
        :data:`GRID_COLUMNS` (means and 95 % half-widths), and ``k_P_change``,
        ``real_area_change``, ``max_pressure_change``: ``q / q_finest - 1``.
    """
    grids = sorted(int(g) for g in grids)
    build, _ = GRID_INFLUENCES[options.influence]
    model = options.model_name()
    heights = PAIRINGS[options.pairing](cells, grids, lambda g, skew, kurt, tag: (
        generator.heights((g, g), block.size, (skew, kurt), surfaces, tag)))
    levels = np.asarray(sweep.pressures, dtype=float)
    end = sweep.end(block, generator.sigma)
    say, rows = sweeps.reporter(progress), []
    for g in reversed(grids):
        geometry = dataclasses.replace(block, grid=(g, g), mesh=options.mesh)
        start = time.perf_counter()
        unit = build(geometry, options.coarsening)
        build_s = time.perf_counter() - start
        for skew, kurt in cells:
            options_g = SWEEP_OPTIONS.with_(method=sweep.method, tol=sweep.tol,
                                            precision=sweep.precision, stiffness_tol=1e-6,
                                            max_iter=None)
            nd, solve_s = sweeps.timed_sweep(unit, heights(g, skew, kurt), geometry, end,
                                             sweep.steps, options_g)
            _, frame = aggregate_sweep(nd, generator.sigma, block.E, levels)
            say(f"grid {g} x {g} {sweeps.cell_key(skew, kurt)}: influence {build_s:.1f} s, "
                f"sweep {solve_s:.1f} s")
            rows += _grid_rows(frame, {
                "skew": float(skew), "kurt": float(kurt), "grid": g,
                "element_size_m": block.size[0] / g, "influence_model": model,
                "pairing": options.pairing, "build_s": build_s, "solve_s": solve_s,
                "surfaces": surfaces, "converged_fraction": float(nd.converged.mean())})
        del unit
    table = _changes_against_finest(pd.DataFrame(rows))
    table.attrs.update(influence_model=model, pairing=options.pairing, method=sweep.method,
                       tol=sweep.tol, spectrum=dict(generator.spectrum or {}),
                       machine=describe_machine())
    return table
