"""Typed records of a study's counter bodies: what the surfaces are pressed against.

A counter body (Eq 17-18) is its surface and its body, each a value: a rough
counter surface (:class:`RoughCounter`) or the smooth one (:data:`SMOOTH`), an
elastic counter body (:class:`ElasticCounter`) or the rigid one (:data:`RIGID`);
:class:`Counterface` joins them, in SI units for a study cell and as ratios to the
first body for its contact job (``job_form``). The paper's rigid smooth flat is the
null counter body (:data:`NO_COUNTERFACE`), whose methods give the one-body
answers. A :class:`PairGeometry` is two bodies' influence models summed once, and a
:class:`JobFile` a file a contact job reads with what it must have been made for.
Used by the study cells and contact jobs of :mod:`roughcontact.study.contact_records`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from roughcontact.contact import counterface
from roughcontact.elasticity.operators import COARSE_MAX
from roughcontact.study import layout
from roughcontact.study.config import in_unit
from roughcontact.study.provenance import short_hash
from roughcontact.study.records import (
    Geometry,
    InfluenceModel,
    SurfaceCell,
    surface_cell_from_params,
)
from roughcontact.units import MM, MPA, UM

# ---------------------------------------------------------------------------
# The counter body: what the surfaces are pressed against (Eq 17-18)
#
#: Bytes of a double.
DOUBLE_BYTES = 8

# A counter body is its surface and its body, each a value: a rough counter surface
# or the smooth one, an elastic counter body or the rigid one; the paper's rigid smooth
# flat is the null counter body (:data:`NO_COUNTERFACE`, on a study cell and its job),
# whose methods give the one-body answers. Each record
# answers what the study asks of it (its files, its parameters, its label, its share of
# a job's memory and time), so the code that asks never needs to know which it holds.


class _Smooth:
    """A smooth counter surface (the null): no heights, no file."""

    sigma = 0.0
    cell = None

    def job_form(self, sigma: float) -> _Smooth:
        return self

    def height_scale(self, sigma: float) -> float:
        return sigma

    def params(self) -> dict:
        return {"surface": None, "surface_key": None}

    def job_params(self) -> dict:
        return {"surface": None, "surface_key": None, "sigma_ratio": 0.0}

    def label(self) -> str:
        return "smooth"

    def columns(self) -> dict:
        return {"counter_skew": float("nan"), "counter_kurt": float("nan")}

    def cells(self) -> dict:
        return {}

    def files(self, study_seed=None) -> dict:
        return {}

    def read(self, paths: dict, reader, study_seed=None):
        return counterface.SMOOTH

    def bytes(self, count: int, n: int) -> float:
        return 0.0


#: The smooth counter surface.
SMOOTH = _Smooth()


@dataclass(frozen=True)
class RoughCounter:
    """A rough counter surface: its ``cell`` (generated with the seed stream
    ``counter``, or measured) and ``sigma`` [m] (on a study cell) or ``sigma_ratio``
    sigma2 / sigma1 (on a job)."""

    cell: SurfaceCell
    sigma: float = 0.0
    sigma_ratio: float = 0.0

    def job_form(self, sigma: float) -> RoughCounter:
        return RoughCounter(self.cell, sigma_ratio=self.sigma / sigma)

    def height_scale(self, sigma: float) -> float:
        """``sqrt(sigma^2 + sigma2^2)``: the rms height of the sum of two independent
        surfaces (the equivalent surface of Eq 17-18) [m]."""
        return float(np.hypot(sigma, self.sigma))

    def params(self) -> dict:
        return {"surface": self.cell.params(), "surface_key": self.cell.key}

    def job_params(self) -> dict:
        return {**self.params(), "sigma_ratio": self.sigma_ratio}

    def label(self) -> str:
        return (f"{self.cell.source_label}sigma {in_unit(self.sigma, UM):g} um, "
                f"Sk {self.cell.skew:g}, Ku {self.cell.kurt:g}")

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

    def read(self, paths: dict, reader, study_seed=None) -> counterface.RoughSurface:
        """The counter surface facing the first (:meth:`SurfaceCell.facing`), read from
        its file by ``reader`` (``surfaces(path, cell, study_seed)``: the stored surfaces,
        checked to have been made for the cell)."""
        stored = reader.surfaces(paths["counter_surfaces"], self.cell, study_seed)
        return self.cell.facing(stored["heights"], self.sigma_ratio, stored["content_sha256"])

    def bytes(self, count: int, n: int) -> float:
        """A contact job's memory for the counter surfaces [bytes]."""
        return DOUBLE_BYTES * count * n


class _Rigid:
    """A rigid counter body (the null): no compliance, no file."""

    E = None
    geometry = None

    def job_form(self, E: float) -> _Rigid:
        return self

    def params(self) -> dict:
        return {"geometry": None, "geometry_key": None, "E_MPa": None}

    def job_params(self) -> dict:
        return {"geometry": None, "geometry_key": None, "modulus_ratio": 0.0}

    def label(self) -> str:
        return "rigid"

    def columns(self) -> dict:
        return {"counter_E_MPa": float("nan")}

    def geometries(self) -> dict:
        return {}

    def pairs(self, first: Geometry, rigid_share: float) -> dict:
        return {}

    def files(self, first: Geometry, rigid_share: float) -> dict:
        return {}

    def read(self, paths: dict, first: Geometry, rigid_share: float, reader) -> tuple:
        return counterface.RIGID, {}

    def time_factor(self, model: dict) -> float:
        return 1.0

    def bytes(self, dense: bool, n: int) -> float:
        return 0.0


#: The rigid counter body.
RIGID = _Rigid()


@dataclass(frozen=True)
class ElasticCounter:
    """An elastic counter body: its ``geometry`` (a block, or a half-space:
    ``operator`` halfspace) and ``E`` [Pa] (on a study cell) or ``modulus_ratio``
    E1 / E2 (on a job)."""

    geometry: Geometry
    E: float | None = None
    modulus_ratio: float = 0.0

    def job_form(self, E: float) -> ElasticCounter:
        return ElasticCounter(self.geometry, modulus_ratio=E / self.E)

    def params(self) -> dict:
        return {"geometry": self.geometry.params(), "geometry_key": self.geometry.key,
                "E_MPa": in_unit(self.E, MPA)}

    def job_params(self) -> dict:
        return {"geometry": self.geometry.params(), "geometry_key": self.geometry.key,
                "modulus_ratio": self.modulus_ratio}

    def label(self) -> str:
        g = self.geometry
        if g.operator is InfluenceModel.HALFSPACE:
            return f"half-space E {in_unit(self.E, MPA):g} MPa nu {g.nu:g}"
        return (f"block E {in_unit(self.E, MPA):g} MPa nu {g.nu:g} "
                f"{in_unit(g.thickness, MM):g} mm {g.mesh}")

    def columns(self) -> dict:
        return {"counter_E_MPa": in_unit(self.E, MPA)}

    def geometries(self) -> dict:
        """The counter body's influence model to build, by key."""
        return {self.geometry.key: self.geometry}

    def pairs(self, first: Geometry, rigid_share: float) -> dict:
        """The pair summed once for a job on ``first`` (:class:`PairGeometry`), by key: of
        a dense first body (one dense matrix); none on a matrix-free one (the job sums
        the two operators, without a matrix)."""
        if first.operator is not InfluenceModel.DENSE:
            return {}
        pair = PairGeometry(first=first, second=self.geometry,
                            modulus_ratio=self.modulus_ratio, rigid_share=rigid_share)
        return {pair.key: pair}

    def files(self, first: Geometry, rigid_share: float) -> dict:
        """The counter body's file for a job on ``first``: the pair's on a dense first
        body, else its influence file; with what it must have been made for."""
        for pair in self.pairs(first, rigid_share).values():
            return {"counter_influence": JobFile(layout.pair(pair.key),
                                                 {"geometry": pair.params()}, pair)}
        return {"counter_influence": JobFile(layout.influence(self.geometry.key),
                                             {"geometry": self.geometry.params()})}

    def read(self, paths: dict, first: Geometry, rigid_share: float, reader) -> tuple:
        """The counter body's compliance for a job on ``first``, read from its file by
        ``reader`` (``pair(path, pair)``: a pair file's :class:`PairModel` and hashes;
        ``influence(path, geometry)``: an influence file's certified operator and
        hashes; each checked to have been made for it), and the hashes to record."""
        path = paths["counter_influence"]
        for pair in self.pairs(first, rigid_share).values():
            model, hashes = reader.pair(path, pair)
            return counterface.SummedPair(model), hashes
        unit, hashes = reader.influence(path, self.geometry)
        return counterface.CompliantBody(unit, self.modulus_ratio), hashes

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


@dataclass(frozen=True)
class JobFile:
    """A file a job reads: its ``path`` and the parameters it must have been made for
    (:func:`roughcontact.study.jobs.storage.check_parameters`), and the pair it holds."""

    path: str
    made_for: dict
    pair: object = None


def _counter_surface(params: dict, scale: str) -> _Smooth | RoughCounter:
    """The counter surface of stored parameters: a cell's (``scale`` "sigma_um") or a
    job's ("sigma_ratio")."""
    if params["surface"] is None:
        return SMOOTH
    cell = surface_cell_from_params(params["surface"])
    if scale == "sigma_um":
        return RoughCounter(cell, sigma=float(params["sigma_um"]) * UM)
    return RoughCounter(cell, sigma_ratio=float(params["sigma_ratio"]))


def _counter_body(params: dict, scale: str) -> _Rigid | ElasticCounter:
    """The counter body of stored parameters: a cell's (``scale`` "E_MPa") or a job's
    ("modulus_ratio")."""
    if params["geometry"] is None:
        return RIGID
    geometry = Geometry.from_params(params["geometry"])
    if scale == "E_MPa":
        return ElasticCounter(geometry, E=float(params["E_MPa"]) * MPA)
    return ElasticCounter(geometry, modulus_ratio=float(params["modulus_ratio"]))


@dataclass(frozen=True)
class Counterface:
    """The body a study cell's surfaces are pressed against (Eq 17-18 of Kumar et al.
    2006; :mod:`roughcontact.contact.counterface`), one record for the cell and its
    job: its ``surface`` (a :class:`RoughCounter` on the first cell's grid and plan
    size, generated with the seed stream ``counter`` or measured, or :data:`SMOOTH`)
    and its ``body`` (an :class:`ElasticCounter`, block or half-space, or
    :data:`RIGID`), in SI units on a study cell (sigma [m], E [Pa]) and as ratios to
    the first body's on a job (:meth:`job_form`). ``rigid_share``: below this share of
    the pair's compliance the contact job treats the counter body as rigid (and logs
    it). A smooth rigid counter body is no counterface at all (:data:`NO_COUNTERFACE`:
    today's case)."""

    surface: _Smooth | RoughCounter = SMOOTH
    body: _Rigid | ElasticCounter = RIGID
    rigid_share: float = 0.001

    @classmethod
    def of(cls, surface, body, rigid_share: float = 0.001) -> AnyCounterface:
        """The counter body of a ``surface`` and a ``body``: the smooth rigid one is no
        counter body at all (:data:`NO_COUNTERFACE`, the paper's flat)."""
        if surface is SMOOTH and body is RIGID:
            return NO_COUNTERFACE
        return cls(surface, body, rigid_share)

    @classmethod
    def from_params(cls, params: dict) -> Counterface:
        """From a cell's ``counterface`` parameters (sigma_um, E_MPa)."""
        return cls(_counter_surface(params, "sigma_um"), _counter_body(params, "E_MPa"),
                   float(params["rigid_share"]))

    @classmethod
    def from_job_params(cls, params: dict) -> Counterface:
        """From a job's ``counter`` parameters (sigma_ratio, modulus_ratio)."""
        return cls(_counter_surface(params, "sigma_ratio"),
                   _counter_body(params, "modulus_ratio"), float(params["rigid_share"]))

    def params(self) -> dict:
        """What the counter body adds to a cell's parameters (um, MPa)."""
        return {"counterface": {**self.surface.params(),
                                "sigma_um": in_unit(self.surface.sigma, UM),
                                **self.body.params(), "rigid_share": self.rigid_share}}

    def counter_params(self) -> dict:
        """The job form's parameters (the ratios), stored with the job and hashed."""
        return {**self.surface.job_params(), **self.body.job_params(),
                "rigid_share": self.rigid_share}

    def job_params(self) -> dict:
        """What the counter body adds to a job's parameters."""
        return {"counter": self.counter_params()}

    def key(self) -> str:
        """What the counter body adds to a job's key: both bodies' parameters, hashed
        (names stay short)."""
        return f"__cf{short_hash(self.counter_params(), 10)}"

    @property
    def label(self) -> str:
        return f"; counter {self.surface.label()}, {self.body.label()}"

    def columns(self, height_scale: float) -> dict:
        """The counter body's parameters as table columns (um, MPa; NaN where none), and
        the composite sigma [um]."""
        return {"counter_sigma_um": in_unit(self.surface.sigma, UM), **self.surface.columns(),
                "counter_body": self.body.label(), **self.body.columns(),
                "equivalent_sigma_um": in_unit(height_scale, UM)}

    def height_scale(self, sigma: float) -> float:
        return self.surface.height_scale(sigma)

    def job_form(self, sigma: float, E: float) -> Counterface:
        """The counter body in a job's form: ratios to the first body's ``sigma`` [m]
        and ``E`` [Pa]."""
        return Counterface(self.surface.job_form(sigma), self.body.job_form(E),
                           self.rigid_share)

    def summary(self, attrs: dict, height_scale: float) -> dict:
        """What the contact file records about the two bodies (:data:`COUNTER_ATTRIBUTES`),
        and the equivalent surface's sample sigma [um]."""
        out = {name: attrs[name].item() if hasattr(attrs[name], "item") else attrs[name]
               for name in COUNTER_ATTRIBUTES if name in attrs}
        if "equivalent_sigma_over_scale" in attrs:
            out["equivalent_sample_sigma_um"] = (float(attrs["equivalent_sigma_over_scale"])
                                                 * in_unit(height_scale, UM))
        return out

    def cells(self) -> dict:
        return self.surface.cells()

    def geometries(self) -> dict:
        return self.body.geometries()

    def pairs(self, first: Geometry) -> dict:
        return self.body.pairs(first, self.rigid_share)

    def files(self, first: Geometry, study_seed=None) -> dict:
        return {**self.surface.files(study_seed), **self.body.files(first, self.rigid_share)}

    def read(self, paths: dict, first: Geometry, reader, study_seed=None) -> tuple:
        """The counter body (:class:`~roughcontact.contact.counterface.Body`) read from
        the job's files ``paths`` (each checked; ``reader`` as
        :meth:`ElasticCounter.read`), and the content hashes to record."""
        compliance, hashes = self.body.read(paths, first, self.rigid_share, reader)
        return counterface.Body(self.surface.read(paths, reader, study_seed), compliance,
                                self.rigid_share), hashes

    def time_factor(self, model: dict) -> float:
        return self.body.time_factor(model)

    def bytes(self, count: int, n: int, dense: bool) -> float:
        return self.surface.bytes(count, n) + self.body.bytes(dense, n)


#: What a contact file of two bodies records about them (:meth:`Counterface.summary`).
COUNTER_ATTRIBUTES = ("counter_compliance_share", "counter_treated_as_rigid",
                      "equivalent_skew", "equivalent_kurt")


class _NoCounterface:
    """The paper's counter body, a rigid smooth flat: no counterface (the null), on a
    cell and on its job; nothing added to parameters, keys, files or costs."""

    label = ""
    surface, body = SMOOTH, RIGID

    def params(self) -> dict:
        return {}

    def job_params(self) -> dict:
        return {}

    def key(self) -> str:
        return ""

    def columns(self, height_scale: float) -> dict:
        return {}

    def height_scale(self, sigma: float) -> float:
        return sigma

    def job_form(self, sigma: float, E: float) -> _NoCounterface:
        return self

    def summary(self, attrs: dict, height_scale: float) -> dict:
        return {}

    def cells(self) -> dict:
        return {}

    def geometries(self) -> dict:
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


#: A study cell, or a job, against the rigid smooth flat.
NO_COUNTERFACE = _NoCounterface()
#: What a study cell or a contact job holds as its counter body: one, or the null.
AnyCounterface = Counterface | _NoCounterface


def counter_from_params(params: dict) -> Counterface | _NoCounterface:
    """A job's counter body from its stored parameters (none: :data:`NO_COUNTERFACE`)."""
    counter = params.get("counter")
    return NO_COUNTERFACE if counter is None else Counterface.from_job_params(counter)


def counterface_from_params(params: dict) -> Counterface | _NoCounterface:
    """A study cell's counter body from its parameters (none: :data:`NO_COUNTERFACE`)."""
    counter = params.get("counterface")
    return NO_COUNTERFACE if counter is None else Counterface.from_params(counter)


@dataclass(frozen=True)
class PairGeometry:
    """Two bodies' influence models summed once: the ``first`` body's (dense) and the
    ``second``'s scaled by ``modulus_ratio`` E1 / E2, with the ``rigid_share`` that
    decides whether the second is treated as rigid. Its file
    (:func:`roughcontact.study.layout.pair`) is shared by every contact job on the
    same pair (:func:`roughcontact.study.jobs.influence.build_pair`)."""

    first: Geometry
    second: Geometry
    modulus_ratio: float
    rigid_share: float

    @classmethod
    def from_params(cls, params: dict) -> PairGeometry:
        return cls(first=Geometry.from_params(params["first"]),
                   second=Geometry.from_params(params["second"]),
                   modulus_ratio=float(params["modulus_ratio"]),
                   rigid_share=float(params["rigid_share"]))

    def params(self) -> dict:
        return {"first": self.first.params(), "second": self.second.params(),
                "first_key": self.first.key, "second_key": self.second.key,
                "modulus_ratio": self.modulus_ratio, "rigid_share": self.rigid_share}

    @property
    def key(self) -> str:
        """File key: both bodies' geometry keys, the modulus ratio and the rigid share."""
        return (f"{self.first.key}__{self.second.key}__r{self.modulus_ratio:.10g}"
                f"_rs{self.rigid_share:g}")


# ---------------------------------------------------------------------------
# Study cells and contact jobs
