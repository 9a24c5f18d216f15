"""Typed records of a study's contact: study cells and contact jobs.

Frozen dataclasses in SI units like those of :mod:`roughcontact.study.records` (the
surface cells and geometries they are made of), each with its file key, its
``params()`` (the configuration's units) and ``from_params``. A *study cell* is a
surface cell on a geometry at one sigma and E over a nominal-pressure range, with
the body it is pressed against (a counter body of
:mod:`roughcontact.study.counter_records`, in SI units; the null: the paper's rigid
smooth flat); the *contact job* that solves it (its counter body as ratios to the
first body's) is shared by every study cell with the same surfaces, geometry, sweep
end, cap and counter body. :func:`study_columns` gives the cells' columns as a study's
tables have them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from roughcontact.contact.cell import nondim_pressure
from roughcontact.study import layout
from roughcontact.study.config import from_unit, in_unit, in_units
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
from roughcontact.units import MM, MPA, UM


@dataclass(frozen=True)
class Accuracy:
    """The accuracy preset a cell is solved with (``accuracy:``; ``"as configured"``
    without one) and the preset's measured ``expected_error`` ((name, relative error)
    pairs, in the presets file's order; None without a preset)."""

    name: str = "as configured"
    expected_error: tuple[tuple[str, float], ...] | None = None

    def errors(self) -> dict:
        """``expected_error`` as a dict ({} without a preset)."""
        return dict(self.expected_error or ())


@dataclass(frozen=True)
class ContactJob:
    """One contact job: every surface of a surface cell on one geometry, swept in
    non-dimensional form to ``pressure_end`` = P L / (E sigma) (a power of 2).

    ``nondim_hardness``: the cap H L / (E sigma) of a capped job (None: elastic),
    with which sigma and E no longer only rescale the solution.
    """

    surface: SurfaceCell
    geometry: Geometry
    pressure_end: float
    accuracy: Accuracy = Accuracy()
    nondim_hardness: float | None = None
    counter: JobCounter = NO_COUNTER_BODY

    @classmethod
    def from_params(cls, params: dict) -> ContactJob:
        return cls(surface=surface_cell_from_params(params["surface"]),
                   geometry=Geometry.from_params(params["geometry"]),
                   pressure_end=float(params["pressure_end"]),
                   accuracy=Accuracy(params["accuracy"],
                                     tuple(params["expected_error"].items()) or None),
                   nondim_hardness=params.get("hardness"),
                   counter=(JobCounter.from_params(params["counter"]) if "counter" in params
                            else NO_COUNTER_BODY))

    def params(self) -> dict:
        """The job as passed to it and stored with its result (``hardness``: the cap)."""
        params = {"surface": self.surface.params(), "geometry": self.geometry.params(),
                  "surface_key": self.surface.key, "geometry_key": self.geometry.key,
                  "pressure_end": self.pressure_end, "accuracy": self.accuracy.name,
                  "expected_error": self.accuracy.errors()}
        if self.nondim_hardness is not None:
            params["hardness"] = self.nondim_hardness
        params.update(self.counter.params())
        return params

    def pairs(self) -> dict[str, PairGeometry]:
        """The pair of influence models summed once for this job, by key: of a compliant
        counter body on a dense first body (the pair is one dense matrix); none
        otherwise (a matrix-free first body sums the two operators in the job)."""
        return self.counter.pairs(self.geometry)

    def files(self, study_seed=None) -> dict[str, JobFile]:
        """The files the job reads, by input name, each with what it must have been made
        for: its surfaces and influence model and its counter body's (the pair's file on
        a dense first body). The one place that decides them: the rules, the plan, the
        audit, the resources and the job take them from here."""
        return {"surfaces": JobFile(layout.surfaces(self.surface.key),
                                    {"cell": self.surface.params(), "study_seed": study_seed}),
                "influence": JobFile(layout.influence(self.geometry.key),
                                     {"geometry": self.geometry.params()}),
                **self.counter.files(self.geometry, study_seed)}

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
class StudyCell:
    """One cell of a contact study: a surface cell on a geometry, scaled by ``sigma``
    [m] and ``E`` [Pa] (Eq 28-32) over the nominal ``pressure_range`` (P_min, P_max) [Pa].

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

    surface: SurfaceCell
    geometry: Geometry
    sigma: float
    E: float
    pressure_range: tuple[float, float]
    accuracy: Accuracy = Accuracy()
    hardness: float | None = None
    checked_hardness: tuple[float, ...] = ()
    hardness_threshold: float | None = None
    counterface: CounterBody = NO_COUNTER_BODY
    counter_entry: object = field(default=None, compare=False, repr=False)

    @classmethod
    def from_params(cls, params: dict) -> StudyCell:
        cap, expected = params.get("cap_MPa"), params.get("expected_error")
        threshold = params.get("hardness_threshold")
        return cls(surface=surface_cell_from_params(params["surface"]),
                   geometry=Geometry.from_params(params["geometry"]),
                   sigma=float(params["sigma_um"]) * UM, E=float(params["E_MPa"]) * MPA,
                   pressure_range=from_unit(params["pressure_MPa"], MPA),
                   accuracy=Accuracy(params["accuracy"],
                                     None if expected is None else tuple(expected.items())),
                   hardness=None if cap is None else float(cap) * MPA,
                   checked_hardness=from_unit(params.get("hardness_MPa") or (), MPA),
                   hardness_threshold=None if threshold is None else float(threshold),
                   counterface=(CounterBody.from_params(params["counterface"])
                                if "counterface" in params else NO_COUNTER_BODY))

    def params(self) -> dict:
        """The cell as the configuration writes it (sigma in um, E and pressures in MPa),
        with its surface and geometry keys; passed to the aggregation and the audit."""
        params = {"surface": self.surface.params(), "geometry": self.geometry.params(),
                  "sigma_um": in_unit(self.sigma, UM), "E_MPa": in_unit(self.E, MPA),
                  "pressure_MPa": in_units(self.pressure_range, MPA),
                  "surface_key": self.surface.key, "geometry_key": self.geometry.key,
                  "accuracy": self.accuracy.name}
        if self.accuracy.expected_error is not None:
            params["expected_error"] = self.accuracy.errors()
        if self.checked_hardness:
            params["hardness_MPa"] = in_units(self.checked_hardness, MPA)
            params["hardness_threshold"] = self.hardness_threshold
        if self.hardness is not None:
            params["cap_MPa"] = in_unit(self.hardness, MPA)
        params.update(self.counterface.params())
        return params

    @property
    def height_scale(self) -> float:
        """The unit of the job's heights [m]: ``sigma``, or with a rough counter surface
        ``sqrt(sigma^2 + sigma2^2)``, the standard deviation of the sum of two
        independent surfaces (the equivalent surface of Eq 17-18)."""
        return self.counterface.height_scale(self.sigma)

    def _nondim(self, pressure: float) -> float:
        return nondim_pressure(pressure, thickness=self.geometry.thickness, E=self.E,
                               sigma=self.height_scale)

    @property
    def sweep_end(self) -> float:
        """P_max L / (E sigma) rounded up to 2^k: a small change of sigma, E or the
        pressure range does not re-solve a job that already reaches far enough."""
        return float(2.0 ** np.ceil(np.log2(self._nondim(self.pressure_range[1]))))

    @property
    def nondim_hardness(self) -> float | None:
        """The cap H L / (E sigma) of a capped cell (None: elastic)."""
        return None if self.hardness is None else self._nondim(self.hardness)

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
