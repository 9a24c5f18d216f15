"""Typed records of a study: surface cells and geometries (what a contact job solves on).

The study cells, contact jobs and counter bodies built from them are in
:mod:`roughcontact.study.contact_records`.

Frozen dataclasses in SI units, built once from the validated configuration
(:mod:`roughcontact.study.plan.studies`, :func:`roughcontact.study.plan.cells.study_plan`).
Each has its file key and its ``params()``: the plain, JSON-able form the
workflow passes to a job (Snakemake compares it to decide reruns) and stores
with the result, with the configuration's units (lengths in mm, sigma in um,
pressures and moduli in MPa); ``from_params`` builds the record again in the
job. Both come from the fields' declarations (:mod:`roughcontact.study.codec`: each
field's unit and key written once, beside it). The choices the configuration
writes as strings are resolved here once: :class:`Generator` (``surfaces.method``),
:class:`InfluenceModel` (``body.operator``), a type per spectrum kind
(:data:`roughcontact.study.sources.SPECTRA`) and per surface source
(:class:`GeneratedCell`, :class:`MeasuredCell`).

A *surface cell* is one set of surface statistics and sampling (skewness,
kurtosis, correlation lengths, grid, size, ACF or spectrum, periodicity,
generator) with a number of seeded realisations, or one measured surface.
Sigma is not part of a cell: surfaces are stored in units of sigma and
scaled at use (Eq 28-32 of Kumar et al. 2006), and Young's modulus is not
part of a geometry (influence files hold E * C). A *study cell* is a surface
cell on a geometry at one sigma and E over a nominal-pressure range; the
*contact job* that solves it is shared by every study cell with the same
surfaces, geometry, sweep end and cap.
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass
from enum import Enum
from pathlib import Path
from typing import ClassVar

from roughcontact.contact import counterface
from roughcontact.elasticity.influence import BlockGeometry, CostEstimate, estimate_cost
from roughcontact.elasticity.operators import choose_operator, coarse_geometry
from roughcontact.study import codec, sources
from roughcontact.study.codec import DEFAULT, Record, from_unit, grid_pair, in_unit, in_units
from roughcontact.study.config import BuildSettings
from roughcontact.study.provenance import short_hash
from roughcontact.study.sources import MeasurementImport, Spectrum, spectrum_from_params
from roughcontact.surfaces.spec import SurfaceSpec
from roughcontact.transport.conduction.probe import BlockBody, HalfSpaceBody
from roughcontact.units import MM, UM


class Generator(Enum):
    """How a surface cell's surfaces come to be (``surfaces.method``, or a measurement).

    ``FILTER``: the paper's filter with the white noise calibrated to the
    window's expected sample moments; ``PAPER``: the paper's Eq 12-13
    uncorrected; ``EXACT``: iterative amplitude adjustment; ``MEASURED``: an
    imported height map.
    """

    FILTER = "filter"
    PAPER = "paper"
    EXACT = "exact"
    MEASURED = "measured"


#: Generators whose surface i depends only on its seed i (:func:`~roughcontact.surfaces.
#: synthetic.derive_seeds`: of the statistics key and i) and the cell's spec: the filter,
#: calibrated or not (the calibration is of the spec alone, over its own fixed seeds; each
#: seed's white noise is translated and filtered alone, and each surface's mean is taken
#: alone), and the exact generator (each seed's IAAFT alone). The first k surfaces of any
#: such cell are those of a larger cell of the same statistics key, bit for bit, and the
#: workflow takes them from its file (:func:`roughcontact.study.plan.cells.surfaces_from`).
SEEDED_PER_SURFACE = frozenset({Generator.FILTER, Generator.PAPER, Generator.EXACT})


class InfluenceModel(Enum):
    """The influence model of a geometry (``body.operator``): the finite-element matrix
    (``DENSE``, the paper's), the matrix-free ``HYBRID`` or ``HALFSPACE`` operators, or
    ``AUTO`` (decided per geometry, :meth:`Geometry.planned_model`)."""

    DENSE = "dense"
    HYBRID = "hybrid"
    HALFSPACE = "halfspace"
    AUTO = "auto"


# ---------------------------------------------------------------------------
# Surface cells


@dataclass(frozen=True)
class _SurfaceStatistics(Record):
    """What every surface cell has: skewness ``skew`` and kurtosis ``kurt`` (Pearson),
    correlation lengths ``corr_length`` (bx, by) [m], contact ``grid`` (nx, ny) over the
    plan ``size`` (Lx, Ly) [m]."""

    skew: float
    kurt: float
    corr_length: tuple[float, float] = codec.si_pair(MM, "b_mm")
    grid: tuple[int, int] = codec.grid()
    size: tuple[float, float] = codec.si_pair(MM, "size_mm")


@dataclass(frozen=True)
class GeneratedCell(_SurfaceStatistics):
    """A surface cell of ``count`` seeded realisations of one set of statistics.

    ``skew``, ``kurt`` (Pearson); correlation lengths ``corr_length`` (bx, by)
    [m] of the ACF ``acf`` (Eq 1), or, with a ``spectrum``, the spectrum's
    :class:`SurfaceSpec` kind (``corr_length`` then only labels the cell);
    contact ``grid`` (nx, ny) over the plan ``size`` (Lx, Ly) [m]; periodic
    or padded filter; the ``method`` that generates them. ``stream``: the seed
    stream ("" for a study's surfaces; ``counter`` for a counter body's heights,
    :class:`~roughcontact.study.counter_records.CounterHeights`): it enters the
    statistics key, so a counter surface of the same statistics as the first is
    another realisation, not the same one.
    """

    acf: str
    periodic: bool
    method: Generator = codec.enum(Generator)
    count: int
    # only with a spectrum, so a cell without one keeps the keys of before spectra
    spectrum: Spectrum | None = codec.record(spectrum_from_params, omit=DEFAULT, default=None)
    # a counter body's: a study's surfaces keep their keys
    stream: str = codec.field(omit=DEFAULT, default="")

    @property
    def statistics_key(self) -> str:
        """Key of the statistics and sampling, without the surface count.

        Seeds derive from it, so the first k surfaces of a cell are the same
        whatever the count. With a spectrum it ends in the spectrum's tag.
        """
        (bx, by), (lx, ly) = in_units(self.corr_length), in_units(self.size)
        nx, ny = self.grid
        key = (f"sk{self.skew:g}_ku{self.kurt:g}_b{bx:g}x{by:g}mm_L{lx:g}x{ly:g}mm"
               f"_g{nx}x{ny}_{self.acf[:3]}_{'per' if self.periodic else 'pad'}"
               f"_{self.method.value}")
        if self.spectrum is not None:
            key = f"{key}_{self.spectrum.tag()}"
        return key if not self.stream else f"{key}_{self.stream}"

    @property
    def key(self) -> str:
        """File key: the statistics key and the surface count."""
        return f"{self.statistics_key}_n{self.count}"

    @property
    def input_files(self) -> tuple[str, ...]:
        """The file the spectrum is read from (an input of the surfaces job), if any."""
        file = None if self.spectrum is None else self.spectrum.file
        return () if file is None else (file,)

    @property
    def source_label(self) -> str:
        """The start of a study cell's legend text: none for generated surfaces."""
        return ""

    def facing(self, heights, sigma_ratio: float, content_sha256: str = ""):
        """These surfaces as a counter surface facing the first body
        (:class:`~roughcontact.contact.counterface.RoughSurface`): generated ones as
        they are (each added to its first surface)."""
        return counterface.RoughSurface(heights, sigma_ratio, content_sha256)

    def spec(self, sigma: float = 1.0) -> SurfaceSpec:
        """The :class:`SurfaceSpec` of the cell's surfaces (heights in units of ``sigma``).

        A spectrum gives its own fields (a table is read from its file, which
        must be the planned one) in place of the ACF and correlation lengths.
        """
        if self.spectrum is None:
            shape = {"corr_length": self.corr_length, "acf": self.acf}
        else:
            shape = {"corr_length": None, **self.spectrum.spec_fields()}
        return SurfaceSpec(grid=self.grid, size=self.size, sigma=sigma, skew=self.skew,
                           kurt=self.kurt, periodic=self.periodic, **shape)


@dataclass(frozen=True)
class MeasuredCell(_SurfaceStatistics):
    """A surface cell of one measured surface, imported as ``source`` describes.

    ``skew``, ``kurt``, ``corr_length`` [m] are the measured values (the labels
    of its results and the targets of a synthetic twin), rounded to 12
    significant digits in the configuration's units; ``grid`` and ``size``
    [m] the prepared measurement's; ``sigma`` [m] its height standard
    deviation; ``file_sha256`` the file's content the workflow was planned with.
    """

    acf: str = codec.constant("measured")
    periodic: bool = codec.constant(False)
    method: Generator = codec.constant(Generator.MEASURED)
    count: int = codec.constant(1)
    # ``measured`` holds the import options, the file's SHA-256 and the measured sigma
    source: MeasurementImport = codec.record(MeasurementImport, flatten=True,
                                             group="measured")
    file_sha256: str = codec.field(group="measured")
    sigma: float = codec.si(UM, "sigma_um", group="measured")
    spectrum: ClassVar[None] = None

    @classmethod
    def from_source(cls, source: MeasurementImport) -> MeasuredCell:
        """The cell of a measurement, read from its file (milliseconds for the grids a
        dense influence matrix allows)."""
        stats = sources.measurement_statistics(source)
        return cls(skew=in_unit(stats["skew"], 1.0), kurt=in_unit(stats["kurt"], 1.0),
                   corr_length=from_unit(in_units((stats["corr_length_x"],
                                                   stats["corr_length_y"]))),
                   grid=grid_pair(stats["grid"]), size=from_unit(in_units(stats["size"])),
                   source=source,
                   file_sha256=sources.load_measurement(source).sha256,
                   sigma=in_unit(stats["sigma"], UM) * UM)

    @property
    def statistics_key(self) -> str:
        """``measured-<stem>_<sha256[:12]>_<options[:8]>``: the file's name, a short hash of
        its content and of the import options. A changed file or option is a new key;
        the same content under another name or folder keeps the hashes."""
        stem = re.sub(r"[^A-Za-z0-9-]+", "-", Path(self.source.file).stem).strip("-")[:40]
        return (f"measured-{stem or 'surface'}_{self.file_sha256[:12]}_"
                f"{short_hash(self.source.options(), 8)}")

    @property
    def key(self) -> str:
        return f"{self.statistics_key}_n{self.count}"

    @property
    def input_files(self) -> tuple[str, ...]:
        return (self.source.file,)

    @property
    def source_label(self) -> str:
        return f"measured {Path(self.source.file).name}: "

    def facing(self, heights, sigma_ratio: float, content_sha256: str = ""):
        """The measured map as a counter surface facing the first body: measured face up
        like the first, so mirrored in x (one map, added to every first surface)."""
        return counterface.RoughSurface.face_up(heights[0], sigma_ratio, content_sha256)


SurfaceCell = GeneratedCell | MeasuredCell

#: The record type of a surface cell's ``params()`` by its ``method`` (generated otherwise).
_SURFACE_CELLS = {Generator.MEASURED.value: MeasuredCell}


def surface_cell_from_params(params: dict) -> SurfaceCell:
    """The surface cell of its ``params()``."""
    return _SURFACE_CELLS.get(params["method"], GeneratedCell).from_params(params)


# ---------------------------------------------------------------------------
# Geometries: the elastic body a cell is solved on


@dataclass(frozen=True)
class Geometry(Record):
    """An influence geometry: the block (``nu``, plan ``size`` (Lx, Ly) [m], ``thickness``
    L [m], contact ``grid`` (nx, ny), ``base``, ``mesh`` preset) and its influence model.
    Its params (lengths in mm) hold every parameter that changes E * C; it is read from
    them, or from a validated ``body`` section completed by ``grid`` and ``size_mm``.

    ``halfspace_tolerance`` ((quantity, relative error or None), ...) sorted by
    quantity: the half-space criterion of ``operator: auto`` (empty otherwise).
    """

    nu: float
    size: tuple[float, float] = codec.si_pair(MM, "size_mm")
    thickness: float = codec.si(MM, "thickness_mm")
    grid: tuple[int, int] = codec.grid()
    base: str
    mesh: str
    # the paper's model adds no key (a dense geometry's files keep their names)
    operator: InfluenceModel = codec.enum(InfluenceModel, omit=DEFAULT,
                                          default=InfluenceModel.DENSE)
    halfspace_tolerance: tuple[tuple[str, float | None], ...] = codec.pairs(
        float, sort=True, when=lambda g: g.operator is InfluenceModel.AUTO, default=())

    @property
    def key(self) -> str:
        """File key of the geometry (every parameter that changes E * C)."""
        (lx, ly), (nx, ny) = in_units(self.size), self.grid
        key = (f"nu{self.nu:g}_L{lx:g}x{ly:g}mm_t{in_unit(self.thickness, MM):g}mm"
               f"_g{nx}x{ny}_{self.base}_{self.mesh}")
        if self.operator is InfluenceModel.DENSE:
            return key
        if self.operator is InfluenceModel.AUTO:
            return key + "_auto" + "-".join("x" if v is None else f"{v:g}"
                                            for _, v in self.halfspace_tolerance)
        return f"{key}_{self.operator.value}"

    def block(self, E: float = 1.0) -> BlockGeometry:
        """The :class:`~roughcontact.elasticity.influence.BlockGeometry` of Young's modulus
        ``E`` [Pa] (1: the unit-modulus model of an influence file)."""
        return BlockGeometry(size=self.size, thickness=self.thickness, grid=self.grid, E=E,
                             nu=self.nu, base=self.base, mesh=self.mesh)

    def thermal_body(self, kind: str = "block"):
        """The body heat and current cross (the conductance probe's,
        :mod:`roughcontact.transport.conduction.probe`), of ``kind`` (the
        ``conductance.body`` key, one of
        :data:`~roughcontact.transport.conduction.probe.BODY_KINDS`): the block itself,
        isothermal base and insulated sides, on its mesh, whatever model its elastic
        influence has (its bulk resistance ``L / (k A)`` is the block's); or a free
        half-space (the spots' constriction alone)."""
        if kind == "halfspace":
            return HalfSpaceBody(periodic=False)
        return BlockBody(BlockGeometry(size=self.size, thickness=self.thickness,
                                       grid=self.grid, mesh=self.mesh))

    def resolved(self, model: InfluenceModel) -> Geometry:
        """The geometry with the influence ``model`` in place of ``auto``: the key, params
        and file of a geometry configured with that model."""
        return dataclasses.replace(self, operator=model, halfspace_tolerance=())

    def candidates(self, max_bytes: float) -> tuple[Geometry, ...]:
        """The geometries an ``operator: auto`` geometry resolves to: its planned model
        (dense or hybrid, :meth:`planned_model`; the half-space criterion is measured
        on it), then the half-space; any other geometry is its own one candidate."""
        if self.operator is not InfluenceModel.AUTO:
            return (self,)
        return (self.resolved(self.planned_model(max_bytes)),
                self.resolved(InfluenceModel.HALFSPACE))

    def planned_model(self, max_bytes: float) -> InfluenceModel:
        """The influence model a build starts with: dense, hybrid or half-space.

        ``operator: auto`` picks dense or hybrid here (by size and the memory
        limit ``max_bytes``, :func:`roughcontact.elasticity.operators.choose_operator`);
        the build may then replace either by the half-space when the measured
        criterion allows.
        """
        if self.operator is not InfluenceModel.AUTO:
            return self.operator
        return InfluenceModel(choose_operator(self.block(), max_dense_bytes=max_bytes))

    def finite_element_model(self, max_bytes: float) -> BlockGeometry:
        """The finite-element model a build solves: the block, or the coarse model of a
        matrix-free operator (:func:`coarse_geometry`)."""
        block = self.block()
        if self.planned_model(max_bytes) is InfluenceModel.DENSE:
            return block
        return coarse_geometry(block)

    def influence_cost(self, build: BuildSettings):
        """:class:`~roughcontact.elasticity.influence.CostEstimate` of the finite-element
        model a build solves with ``build``'s solver within its memory limit (none for
        the half-space: zero)."""
        if self.operator is InfluenceModel.HALFSPACE:
            return CostEstimate(dofs=0, stiffness_nonzeros=0, condensed_size=0,
                                peak_bytes=0.0)
        return estimate_cost(self.finite_element_model(build.max_bytes), build.solver)


