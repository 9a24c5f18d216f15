"""Typed records of a study's contact: study cells and contact jobs.

Frozen dataclasses in SI units like those of :mod:`roughcontact.study.records` (the
surface cells and geometries they are made of), each with its file key, its
``params()`` (the configuration's units) and ``from_params``, both declared on its
fields (:mod:`roughcontact.study.codec`). A *study cell* is a
surface cell on a geometry at one sigma and E over a nominal-pressure range, with
the body it is pressed against (a counter body of
:mod:`roughcontact.study.counter_records`, in SI units; the null: the paper's rigid
smooth flat); the *contact job* that solves it (its counter body as ratios to the
first body's) is shared by every study cell with the same surfaces, geometry, sweep
end, cap and counter body. :func:`study_columns` gives the cells' columns as a study's
tables have them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from roughcontact.contact.cell import nondim_pressure
from roughcontact.study import codec, layout
from roughcontact.study.codec import DEFAULT, Record, in_unit
from roughcontact.study.counter_records import (
    NO_COUNTER_BODY,
    CounterBody,
    JobCounter,
    JobFile,
    PairGeometry,
)
from roughcontact.study.records import (
    Geometry,
    SurfaceCell,
    surface_cell_from_params,
)
from roughcontact.study.thermal_records import NO_THERMAL, ThermalBlock, thermal_from_params
from roughcontact.units import MM, MPA, UM


@dataclass(frozen=True)
class Accuracy(Record):
    """The accuracy preset a cell is solved with (``accuracy:``; ``"as configured"``
    without one) and the preset's measured ``expected_error`` ((name, relative error)
    pairs, in the presets file's order; None without a preset: left out of a cell's
    params)."""

    name: str = codec.field(key="accuracy", default="as configured")
    expected_error: tuple[tuple[str, float], ...] | None = codec.pairs(omit=DEFAULT,
                                                                      default=None)

    def errors(self) -> dict:
        """``expected_error`` as a dict ({} without a preset)."""
        return dict(self.expected_error or ())


def _job_accuracy(accuracy: Accuracy) -> dict:
    """A job's accuracy params: ``expected_error`` always ({} without a preset)."""
    return {"accuracy": accuracy.name, "expected_error": accuracy.errors()}


def _job_accuracy_from(params: dict) -> Accuracy:
    return Accuracy(params["accuracy"], tuple(params["expected_error"].items()) or None)


@dataclass(frozen=True)
class ContactJob(Record):
    """One contact job: every surface of a surface cell on one geometry, swept in
    non-dimensional form to ``pressure_end`` = P L / (E sigma) (a power of 2).

    ``nondim_hardness``: the cap H L / (E sigma) of a capped job (None: elastic,
    ``hardness`` of its params), with which sigma and E no longer only rescale the
    solution. Its params are passed to it and stored with its result.
    """

    surface: SurfaceCell = codec.record(surface_cell_from_params)
    geometry: Geometry = codec.record(Geometry)
    surface_key: str = codec.key_of("surface")
    geometry_key: str = codec.key_of("geometry")
    pressure_end: float
    accuracy: Accuracy = codec.field(write=_job_accuracy, read=_job_accuracy_from,
                                     flatten=True, default=Accuracy())
    nondim_hardness: float | None = codec.field(key="hardness", omit=DEFAULT, default=None)
    counter: JobCounter = codec.record(JobCounter, omit=DEFAULT, default=NO_COUNTER_BODY)
    # the block's thermal influence where the conductance crosses it (none: no key)
    thermal: ThermalBlock = codec.record(thermal_from_params, omit=DEFAULT,
                                         default=NO_THERMAL)

    def pairs(self) -> dict[str, PairGeometry]:
        """The pair of influence models summed once for this job, by key: of a compliant
        counter body on a dense first body (the pair is one dense matrix); none
        otherwise (a matrix-free first body sums the two operators in the job)."""
        return self.counter.pairs(self.geometry)

    def files(self, study_seed=None) -> dict[str, JobFile]:
        """The files the job reads, by input name, each with what it must have been made
        for: its surfaces and influence model, its counter body's (the pair's file on
        a dense first body) and its block's thermal influence (``thermal``, where its
        conductance crosses the block). The one place that decides them: the rules, the plan, the
        audit, the resources and the job take them from here."""
        return {"surfaces": JobFile(layout.surfaces(self.surface.key),
                                    {"cell": self.surface.params(), "study_seed": study_seed}),
                "influence": JobFile(layout.influence(self.geometry.key),
                                     {"geometry": self.geometry.params()}),
                **self.counter.files(self.geometry, study_seed), **self.thermal.files()}

    def paths(self) -> dict[str, str]:
        """The paths of :meth:`files`, by input name (a rule's inputs)."""
        return {name: file.path for name, file in self.files().items()}

    @property
    def key(self) -> str:
        """File key: surface cell, geometry and sweep end, and a capped job's cap.

        The end is part of the key: a file's content depends on its key alone,
        so a study that needs a longer sweep gets its own file, and no result
        is re-solved or rewritten because another study was added, changed or
        removed. The cap has 7 digits: cells whose caps agree to 1e-6 share a
        job (:func:`~roughcontact.contact.nondim.to_physical` allows 1e-5).
        """
        key = f"{self.surface.key}__{self.geometry.key}__end{self.pressure_end:g}"
        if self.nondim_hardness is not None:
            key = f"{key}__cap{self.nondim_hardness:.7g}"
        return key + self.counter.key()


@dataclass(frozen=True)
class StudyCell(Record):
    """One cell of a contact study: a surface cell on a geometry, scaled by ``sigma``
    [m] and ``E`` [Pa] (Eq 28-32) over the nominal ``pressure_range`` (P_min, P_max) [Pa].
    Its params are the cell as the configuration writes it (sigma in um, E and pressures
    in MPa) with its surface and geometry keys, passed to the aggregation and the audit.

    ``hardness`` H [Pa]: the cap 0 <= p <= H a capped cell is solved with (None:
    elastic). ``checked_hardness`` [Pa]: the values an elastic cell's results
    are checked against (the share of real area and load above each, no extra
    solve), flagged beyond ``hardness_threshold``. ``counterface``: the body its surfaces
    are pressed against (:class:`~roughcontact.study.counter_records.CounterBody`; the
    null :data:`~roughcontact.study.counter_records.NO_COUNTER_BODY`: the paper's rigid
    smooth flat). ``counter_entry``: the configured counter body the plan made it of
    (:class:`~roughcontact.study.plan.counter_entries.CounterfaceEntry`, with the keys the
    plan's messages name; not a parameter of the cell).
    """

    surface: SurfaceCell = codec.record(surface_cell_from_params)
    geometry: Geometry = codec.record(Geometry)
    sigma: float = codec.si(UM, "sigma_um")
    E: float = codec.si(MPA, "E_MPa")
    pressure_range: tuple[float, float] = codec.si_tuple(MPA, "pressure_MPa")
    surface_key: str = codec.key_of("surface")
    geometry_key: str = codec.key_of("geometry")
    accuracy: Accuracy = codec.record(Accuracy, flatten=True, default=Accuracy())
    checked_hardness: tuple[float, ...] = codec.si_tuple(MPA, "hardness_MPa", omit=DEFAULT,
                                                         default=())
    hardness_threshold: float | None = codec.field(when=lambda c: c.checked_hardness,
                                                   default=None)
    hardness: float | None = codec.si(MPA, "cap_MPa", omit=DEFAULT, default=None)
    counterface: CounterBody = codec.record(CounterBody, omit=DEFAULT, default=NO_COUNTER_BODY)
    counter_entry: object = codec.unwritten(default=None, compare=False, repr=False)

    @property
    def height_scale(self) -> float:
        """The unit of the job's heights [m]: ``sigma``, or with a rough counter surface
        ``sqrt(sigma^2 + sigma2^2)``, the standard deviation of the sum of two
        independent surfaces (the equivalent surface of Eq 17-18)."""
        return self.counterface.height_scale(self.sigma)

    def nondim(self, pressure: float) -> float:
        """``pressure`` [Pa] as this cell's job sweeps it: ``P L / (E sigma)``, sigma its
        height scale."""
        return nondim_pressure(pressure, thickness=self.geometry.thickness, E=self.E,
                               sigma=self.height_scale)

    @property
    def sweep_end(self) -> float:
        """P_max L / (E sigma) rounded up to 2^k: a small change of sigma, E or the
        pressure range does not re-solve a job that already reaches far enough."""
        return float(2.0 ** np.ceil(np.log2(self.nondim(self.pressure_range[1]))))

    @property
    def nondim_hardness(self) -> float | None:
        """The cap H L / (E sigma) of a capped cell (None: elastic)."""
        return None if self.hardness is None else self.nondim(self.hardness)

    @property
    def job(self) -> ContactJob:
        """The contact job that solves this cell."""
        return ContactJob(surface=self.surface, geometry=self.geometry,
                          pressure_end=self.sweep_end, accuracy=self.accuracy,
                          nondim_hardness=self.nondim_hardness, counter=self.counter_job)

    @property
    def counter_job(self) -> JobCounter:
        """The counter body of its job (ratios to this cell's sigma and E)."""
        return self.counterface.in_job(self.sigma, self.E)

    @property
    def contact_key(self) -> str:
        return self.job.key

    @property
    def label(self) -> str:
        """Short legend text of the cell."""
        cap = "" if self.hardness is None else f", capped at {in_unit(self.hardness, MPA):g} MPa"
        counter = self.counterface.label
        columns = self.columns()
        return (f"{self.surface.source_label}Sk {columns['skew']:g}, Ku {columns['kurt']:g}, "
                f"b {columns['b_mm']:g} mm, {columns['size_mm']:g} mm, nu {columns['nu']:g}, "
                f"{columns['mesh']} mesh, sigma {columns['sigma_um']:g} um{cap}{counter}")

    def columns(self) -> dict:
        """The cell's parameters as table columns for people (mm, um, MPa)."""
        s, g = self.surface, self.geometry
        return {"skew": s.skew, "kurt": s.kurt, "b_mm": in_unit(s.corr_length[0], MM),
                "size_mm": in_unit(g.size[0], MM), "nu": g.nu, "mesh": g.mesh,
                "thickness_mm": in_unit(g.thickness, MM), "sigma_um": in_unit(self.sigma, UM),
                "E_MPa": in_unit(self.E, MPA), **self.counterface.columns(self.height_scale)}


def study_columns(cells) -> list[dict]:
    """The columns of a study's ``cells`` (:meth:`StudyCell.columns`) as its tables have
    them: where a cell has a counter body, every cell names its own in ``counter`` (the
    rigid smooth flat's too); a study without counter bodies keeps its columns."""
    rows = [cell.columns() for cell in cells]
    if any("counter" in row for row in rows):
        for row, cell in zip(rows, cells, strict=True):
            row.setdefault("counter", cell.counterface.name)
    return rows
