"""Typed records of a study's counter bodies: where their heights and compliance come from.

A counter body (Eq 17-18) has two sources, each a value: its heights
(:class:`CounterHeights`, the surface cell whose file holds them, or the smooth face
:data:`NO_HEIGHTS`) and its compliance (:class:`CounterCompliance`, the geometry whose
influence file, or pair file, holds it, or the rigid body :data:`NO_COMPLIANCE`). A
study cell holds the two with their scales in SI units (:class:`CounterBody`: the
counter surface's sigma [m] and the body's E [Pa]; its parameters, legend, table
columns and height scale); its contact job with their ratios to the first body's
(:class:`JobCounter`, :meth:`CounterBody.in_job`: the files it reads, and the values
of :mod:`roughcontact.contact.counterface` it makes of them, a
:class:`~roughcontact.contact.counterface.Body`). The paper's rigid smooth flat is the
null of both (:data:`NO_COUNTER_BODY`): nothing added to parameters, keys, files,
columns or costs. So the code that asks a counter body for something never needs to
know which it holds. A :class:`PairGeometry` is two bodies' influence models summed
once, and a :class:`JobFile` a file a contact job reads with what it must have been
made for.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from roughcontact.contact import counterface
from roughcontact.elasticity.operators import COARSE_MAX
from roughcontact.study import codec, layout
from roughcontact.study.codec import Record, in_unit
from roughcontact.study.provenance import short_hash
from roughcontact.study.records import (
    Geometry,
    InfluenceModel,
    SurfaceCell,
    surface_cell_from_params,
)
from roughcontact.units import MM, MPA, UM

#: Bytes of a double.
DOUBLE_BYTES = 8


@dataclass(frozen=True)
class JobFile:
    """A file a job reads: its ``path`` and the parameters it must have been made for
    (:func:`roughcontact.study.jobs.storage.check_parameters`), and the pair it holds."""

    path: str
    made_for: dict
    pair: object = None


# ---------------------------------------------------------------------------
# Where the heights come from: a surface cell, or none (a smooth counter face)


class _NoHeights:
    """A smooth counter face (the null): no surface cell, no file."""

    cell = None

    def height_scale(self, sigma: float, counter_sigma: float) -> float:
        return sigma

    def label(self, sigma: float) -> str:
        return "smooth"

    def name(self, sigma: float) -> str:
        return "smooth"

    def columns(self) -> dict:
        return {"counter_skew": float("nan"), "counter_kurt": float("nan")}

    def cells(self) -> dict:
        return {}

    def files(self, study_seed=None) -> dict:
        return {}

    def read(self, paths: dict, reader, sigma_ratio: float, study_seed=None):
        return counterface.SMOOTH

    def bytes(self, count: int, n: int) -> float:
        return 0.0


#: A smooth counter face: no heights.
NO_HEIGHTS = _NoHeights()


@dataclass(frozen=True)
class CounterHeights(Record):
    """A rough counter surface: the surface ``cell`` whose file holds its heights (on the
    first cell's grid and plan size; generated with the seed stream ``counter``, or
    measured), in units of its own sigma; written as ``surface`` and ``surface_key``
    (None of :data:`NO_HEIGHTS`)."""

    cell: SurfaceCell = codec.record(surface_cell_from_params, key="surface")
    surface_key: str = codec.key_of("cell")

    def height_scale(self, sigma: float, counter_sigma: float) -> float:
        """``sqrt(sigma^2 + sigma2^2)``: the rms height of the sum of two independent
        surfaces (the equivalent surface of Eq 17-18) [m]."""
        return float(np.hypot(sigma, counter_sigma))

    def label(self, sigma: float) -> str:
        """Its legend text at rms height ``sigma`` [m]."""
        return (f"{self.cell.source_label}sigma {in_unit(sigma, UM):g} um, "
                f"Sk {self.cell.skew:g}, Ku {self.cell.kurt:g}")

    def name(self, sigma: float) -> str:
        """Its short name at ``sigma`` [m]: sigma, and Sk and Ku unless Gaussian."""
        name = f"sigma {in_unit(sigma, UM):g} um"
        if not (self.cell.skew == 0 and self.cell.kurt == 3):
            name += f", Sk {self.cell.skew:g}, Ku {self.cell.kurt:g}"
        return name

    def columns(self) -> dict:
        return {"counter_skew": self.cell.skew, "counter_kurt": self.cell.kurt}

    def cells(self) -> dict:
        """The counter surface cell to generate or import, by key."""
        return {self.cell.key: self.cell}

    def files(self, study_seed=None) -> dict:
        """The counter surfaces' file, with what it must have been made for."""
        return {"counter_surfaces": JobFile(layout.surfaces(self.cell.key),
                                            {"cell": self.cell.params(),
                                             "study_seed": study_seed})}

    def read(self, paths: dict, reader, sigma_ratio: float,
             study_seed=None) -> counterface.RoughSurface:
        """The counter surface facing the first (:meth:`SurfaceCell.facing`) at
        ``sigma_ratio`` sigma2 / sigma1, read from its file by ``reader``
        (``surfaces(path, cell, study_seed)``: the stored surfaces, checked to have been
        made for the cell)."""
        stored = reader.surfaces(paths["counter_surfaces"], self.cell, study_seed)
        return self.cell.facing(stored["heights"], sigma_ratio, stored["content_sha256"])

    def bytes(self, count: int, n: int) -> float:
        """A contact job's memory for the counter surfaces [bytes]."""
        return DOUBLE_BYTES * count * n


# ---------------------------------------------------------------------------
# Where the compliance comes from: a geometry, or none (a rigid counter body)


class _NoCompliance:
    """A rigid counter body (the null): no geometry, no file."""

    geometry = None

    def modulus_ratio(self, E: float, counter_E) -> float:
        return 0.0

    def label(self, E) -> str:
        return "rigid"

    def columns(self, E) -> dict:
        return {"counter_E_MPa": float("nan")}

    def geometries(self) -> dict:
        return {}

    def pairs(self, first: Geometry, modulus_ratio: float, rigid_share: float) -> dict:
        return {}

    def files(self, first: Geometry, modulus_ratio: float, rigid_share: float) -> dict:
        return {}

    def read(self, paths: dict, first: Geometry, modulus_ratio: float, rigid_share: float,
             reader) -> tuple:
        return counterface.RIGID, {}

    def time_factor(self, model: dict) -> float:
        return 1.0

    def bytes(self, dense: bool, n: int) -> float:
        return 0.0


#: A rigid counter body: no compliance.
NO_COMPLIANCE = _NoCompliance()


@dataclass(frozen=True)
class CounterCompliance(Record):
    """An elastic counter body: the ``geometry`` whose influence file holds its
    unit-modulus operator (a block, or a half-space: ``operator`` halfspace); written as
    ``geometry`` and ``geometry_key`` (None of :data:`NO_COMPLIANCE`)."""

    geometry: Geometry = codec.record(Geometry)
    geometry_key: str = codec.key_of("geometry")

    def modulus_ratio(self, E: float, counter_E: float) -> float:
        """E1 / E2 of a first body of modulus ``E`` [Pa] on this one of ``counter_E``."""
        return E / counter_E

    def label(self, E: float) -> str:
        """Its legend text at Young's modulus ``E`` [Pa]."""
        g = self.geometry
        if g.operator is InfluenceModel.HALFSPACE:
            return f"half-space E {in_unit(E, MPA):g} MPa nu {g.nu:g}"
        return (f"block E {in_unit(E, MPA):g} MPa nu {g.nu:g} "
                f"{in_unit(g.thickness, MM):g} mm {g.mesh}")

    def columns(self, E: float) -> dict:
        return {"counter_E_MPa": in_unit(E, MPA)}

    def geometries(self) -> dict:
        """The counter body's influence model to build, by key."""
        return {self.geometry.key: self.geometry}

    def pairs(self, first: Geometry, modulus_ratio: float, rigid_share: float) -> dict:
        """The pair summed once for a job on ``first`` (:class:`PairGeometry`), by key: of
        a dense first body (one dense matrix); none on a matrix-free one (the job sums
        the two operators, without a matrix)."""
        if first.operator is not InfluenceModel.DENSE:
            return {}
        pair = PairGeometry(first=first, second=self.geometry, modulus_ratio=modulus_ratio,
                            rigid_share=rigid_share)
        return {pair.key: pair}

    def files(self, first: Geometry, modulus_ratio: float, rigid_share: float) -> dict:
        """The counter body's file for a job on ``first``: the pair's on a dense first
        body, else its influence file; with what it must have been made for."""
        for pair in self.pairs(first, modulus_ratio, rigid_share).values():
            return {"counter_influence": JobFile(layout.pair(pair.key),
                                                 {"geometry": pair.params()}, pair)}
        return {"counter_influence": JobFile(layout.influence(self.geometry.key),
                                             {"geometry": self.geometry.params()})}

    def read(self, paths: dict, first: Geometry, modulus_ratio: float, rigid_share: float,
             reader) -> tuple:
        """The counter body's compliance for a job on ``first``, read from its file by
        ``reader`` (``pair(path, pair)``: a pair file's
        :class:`~roughcontact.contact.counterface.PairModel` and hashes;
        ``influence(path, geometry)``: an influence file's certified operator and hashes;
        each checked to have been made for it), and the hashes to record."""
        path = paths["counter_influence"]
        for pair in self.pairs(first, modulus_ratio, rigid_share).values():
            model, hashes = reader.pair(path, pair)
            return counterface.SummedPair(model), hashes
        unit, hashes = reader.influence(path, self.geometry)
        return counterface.CompliantBody(unit, modulus_ratio), hashes

    def time_factor(self, model: dict) -> float:
        """A compliant counter body: more contact at the same pressure (the cost
        ``model``'s ``counter_body_factor``, config/cost_model.yaml)."""
        return float(model["contact"]["counter_body_factor"])

    def bytes(self, dense: bool, n: int) -> float:
        """A contact job's memory for the counter body [bytes]: on a dense first body the
        pair's matrix (2 n^2 doubles), on a matrix-free one its coarse correction."""
        if dense:
            return 2 * DOUBLE_BYTES * n**2
        return DOUBLE_BYTES * (COARSE_MAX**2) ** 2


# ---------------------------------------------------------------------------
# The counter body of a study cell (SI) and of its contact job (ratios)


class _Sources:
    """What a counter body asks its sources, on a cell and on its job."""

    def cells(self) -> dict:
        return self.heights.cells()

    def geometries(self) -> dict:
        return self.compliance.geometries()


def _heights():
    """The counter heights, written flat (``surface``, ``surface_key``)."""
    return codec.record(CounterHeights, null=NO_HEIGHTS, flatten=True, default=NO_HEIGHTS)


def _compliance():
    """The counter compliance, written flat (``geometry``, ``geometry_key``)."""
    return codec.record(CounterCompliance, null=NO_COMPLIANCE, flatten=True,
                        default=NO_COMPLIANCE)


@dataclass(frozen=True)
class CounterBody(_Sources, Record):
    """The body a study cell's surfaces are pressed against (Eq 17-18 of Kumar et al.
    2006; :mod:`roughcontact.contact.counterface`) in SI units: its ``heights`` at rms
    height ``sigma`` [m] (0: a smooth face) and its ``compliance`` at Young's modulus
    ``E`` [Pa] (None: rigid). ``rigid_share``: below this share of the pair's
    compliance the contact job treats the counter body as rigid (and logs it). The
    smooth rigid one is no counter body at all (:data:`NO_COUNTER_BODY`). A cell's params
    hold it under ``counterface`` (sigma in um, E in MPa)."""

    heights: CounterHeights | _NoHeights = _heights()
    sigma: float = codec.si(UM, "sigma_um", default=0.0)
    compliance: CounterCompliance | _NoCompliance = _compliance()
    E: float | None = codec.si(MPA, "E_MPa", default=None)
    rigid_share: float = 0.001

    @property
    def label(self) -> str:
        """What it adds to a study cell's legend."""
        return f"; counter {self.heights.label(self.sigma)}, {self.compliance.label(self.E)}"

    @property
    def name(self) -> str:
        """The counter body in a table's ``counter`` column: its body, and its surface in
        brackets (e.g. ``half-space E 110000 MPa nu 0.26 (sigma 1.5 um)``)."""
        return f"{self.compliance.label(self.E)} ({self.heights.name(self.sigma)})"

    def columns(self, height_scale: float) -> dict:
        """The counter body as table columns: its ``counter`` name, its parameters (um,
        MPa; NaN where none) and the composite sigma [um]."""
        return {"counter": self.name, "counter_sigma_um": in_unit(self.sigma, UM),
                **self.heights.columns(), "counter_body": self.compliance.label(self.E),
                **self.compliance.columns(self.E),
                "equivalent_sigma_um": in_unit(height_scale, UM)}

    def height_scale(self, sigma: float) -> float:
        """The unit of a job's heights [m] on a first body of rms height ``sigma`` [m]."""
        return self.heights.height_scale(sigma, self.sigma)

    def in_job(self, sigma: float, E: float) -> JobCounter:
        """The counter body of the contact job on a first body of rms height ``sigma``
        [m] and Young's modulus ``E`` [Pa]: the ratios sigma2 / sigma1 and E1 / E2."""
        return JobCounter(self.heights, self.sigma / sigma, self.compliance,
                          self.compliance.modulus_ratio(E, self.E), self.rigid_share)

    def summary(self, attrs: dict, height_scale: float) -> dict:
        """What the contact file records about the two bodies (:data:`COUNTER_ATTRIBUTES`),
        and the equivalent surface's sample sigma [um]."""
        out = {name: attrs[name].item() if hasattr(attrs[name], "item") else attrs[name]
               for name in COUNTER_ATTRIBUTES if name in attrs}
        if "equivalent_sigma_over_scale" in attrs:
            out["equivalent_sample_sigma_um"] = (float(attrs["equivalent_sigma_over_scale"])
                                                 * in_unit(height_scale, UM))
        return out


#: What a contact file of two bodies records about them (:meth:`CounterBody.summary`).
COUNTER_ATTRIBUTES = ("counter_compliance_share", "counter_treated_as_rigid",
                      "equivalent_skew", "equivalent_kurt")


@dataclass(frozen=True)
class JobCounter(_Sources, Record):
    """A contact job's counter body: its ``heights`` and ``compliance`` at the ratios
    ``sigma_ratio`` sigma2 / sigma1 and ``modulus_ratio`` E1 / E2 to the first body
    (:meth:`CounterBody.in_job`), with the ``rigid_share`` of :class:`CounterBody`. It
    decides the files the job reads for it, and reads them into the contact's
    :class:`~roughcontact.contact.counterface.Body`. A job's params hold it under
    ``counter`` (stored with it and hashed)."""

    heights: CounterHeights | _NoHeights = _heights()
    sigma_ratio: float = 0.0
    compliance: CounterCompliance | _NoCompliance = _compliance()
    modulus_ratio: float = 0.0
    rigid_share: float = 0.001

    def key(self) -> str:
        """What the counter body adds to a job's key: its parameters, hashed (names stay
        short)."""
        return f"__cf{short_hash(self.params(), 10)}"

    def pairs(self, first: Geometry) -> dict:
        return self.compliance.pairs(first, self.modulus_ratio, self.rigid_share)

    def files(self, first: Geometry, study_seed=None) -> dict:
        return {**self.heights.files(study_seed),
                **self.compliance.files(first, self.modulus_ratio, self.rigid_share)}

    def read(self, paths: dict, first: Geometry, reader, study_seed=None) -> tuple:
        """The counter body (:class:`~roughcontact.contact.counterface.Body`) read from
        the job's files ``paths`` (each checked; ``reader`` as
        :meth:`CounterCompliance.read` and :meth:`CounterHeights.read`), and the content
        hashes to record."""
        compliance, hashes = self.compliance.read(paths, first, self.modulus_ratio,
                                                  self.rigid_share, reader)
        surface = self.heights.read(paths, reader, self.sigma_ratio, study_seed)
        return counterface.Body(surface, compliance, self.rigid_share), hashes

    def time_factor(self, model: dict) -> float:
        return self.compliance.time_factor(model)

    def bytes(self, count: int, n: int, dense: bool) -> float:
        return self.heights.bytes(count, n) + self.compliance.bytes(dense, n)


class _NoCounterBody(_Sources):
    """The paper's counter body, a rigid smooth flat (the null), on a cell and on its job:
    nothing added to parameters, keys, files, columns or costs."""

    heights, compliance = NO_HEIGHTS, NO_COMPLIANCE
    label = ""
    #: E1 / E2 of a rigid body (as :attr:`JobCounter.modulus_ratio`).
    modulus_ratio = 0.0
    #: Its name in the ``counter`` column of a study of counter bodies.
    name = "rigid smooth flat"

    def key(self) -> str:
        return ""

    def columns(self, height_scale: float) -> dict:
        return {}

    def height_scale(self, sigma: float) -> float:
        return sigma

    def in_job(self, sigma: float, E: float) -> _NoCounterBody:
        return self

    def summary(self, attrs: dict, height_scale: float) -> dict:
        return {}

    def pairs(self, first: Geometry) -> dict:
        return {}

    def files(self, first: Geometry, study_seed=None) -> dict:
        return {}

    def read(self, paths: dict, first: Geometry, reader, study_seed=None) -> tuple:
        return counterface.RIGID_FLAT, {}

    def time_factor(self, model: dict) -> float:
        return 1.0

    def bytes(self, count: int, n: int, dense: bool) -> float:
        return 0.0


#: A study cell, or a contact job, against the rigid smooth flat.
NO_COUNTER_BODY = _NoCounterBody()


def counter_name(row) -> str:
    """The counter body a row of a study's table names (its ``counter`` column; a study
    without counter bodies: the rigid smooth flat)."""
    return row.get("counter", NO_COUNTER_BODY.name)


@dataclass(frozen=True)
class PairGeometry(Record):
    """Two bodies' influence models summed once: the ``first`` body's (dense) and the
    ``second``'s scaled by ``modulus_ratio`` E1 / E2, with the ``rigid_share`` that
    decides whether the second is treated as rigid. Its file
    (:func:`roughcontact.study.layout.pair`) is shared by every contact job on the
    same pair (:func:`roughcontact.study.jobs.influence.build_pair`)."""

    first: Geometry = codec.record(Geometry)
    second: Geometry = codec.record(Geometry)
    first_key: str = codec.key_of("first")
    second_key: str = codec.key_of("second")
    modulus_ratio: float
    rigid_share: float

    @property
    def key(self) -> str:
        """File key: both bodies' geometry keys, the modulus ratio and the rigid share."""
        return (f"{self.first.key}__{self.second.key}__r{self.modulus_ratio:.10g}"
                f"_rs{self.rigid_share:g}")
