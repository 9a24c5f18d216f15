"""Typed records of a study's contact: study cells, contact jobs and counter bodies.

Frozen dataclasses in SI units like those of :mod:`roughcontact.study.records` (the
surface cells and geometries they are made of), each with its file key, its
``params()`` (the configuration's units) and ``from_params``. A *study cell* is a
surface cell on a geometry at one sigma and E over a nominal-pressure range, with
the body it is pressed against (:class:`Counterface`; none: the paper's rigid smooth
flat); the *contact job* that solves it is shared by every study cell with the same
surfaces, geometry, sweep end, cap and counter body. A :class:`PairGeometry` is two
bodies' influence models summed once.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from roughcontact.contact.cell import nondim_pressure
from roughcontact.study.config import from_unit, in_unit, in_units
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


def _counter_body_label(geometry: Geometry | None, E: float | None) -> str:
    if geometry is None:
        return "rigid"
    if geometry.operator is InfluenceModel.HALFSPACE:
        return f"half-space E {in_unit(E, MPA):g} MPa nu {geometry.nu:g}"
    return (f"block E {in_unit(E, MPA):g} MPa nu {geometry.nu:g} "
            f"{in_unit(geometry.thickness, MM):g} mm {geometry.mesh}")


@dataclass(frozen=True)
class Counterface:
    """The body a study cell's surfaces are pressed against (Eq 17-18 of Kumar et al.
    2006; :mod:`roughcontact.contact.counterface`): its surface and its body.

    ``surface``: the counter surface cell on the first cell's grid and plan
    size (a generated cell of seed stream ``counter``, or a measured one), None
    for a smooth one; ``sigma`` [m] its heights' standard deviation (0 when
    smooth). ``geometry``: the counter body (a block, or a half-space:
    ``operator`` halfspace), None for a rigid one; ``E`` [Pa] its Young's
    modulus. ``rigid_share``: below this share of the pair's compliance the
    contact job treats the counter body as rigid (and logs it). A smooth rigid
    counter body is no counterface at all (None on the cell: today's case).
    """

    surface: SurfaceCell | None = None
    sigma: float = 0.0
    geometry: Geometry | None = None
    E: float | None = None
    rigid_share: float = 0.001

    @classmethod
    def from_params(cls, params: dict) -> Counterface:
        surface, geometry = params["surface"], params["geometry"]
        return cls(surface=None if surface is None else surface_cell_from_params(surface),
                   sigma=float(params["sigma_um"]) * UM,
                   geometry=None if geometry is None else Geometry.from_params(geometry),
                   E=None if params["E_MPa"] is None else float(params["E_MPa"]) * MPA,
                   rigid_share=float(params["rigid_share"]))

    def params(self) -> dict:
        s, g = self.surface, self.geometry
        return {"surface": None if s is None else s.params(),
                "surface_key": None if s is None else s.key,
                "sigma_um": in_unit(self.sigma, UM),
                "geometry": None if g is None else g.params(),
                "geometry_key": None if g is None else g.key,
                "E_MPa": None if self.E is None else in_unit(self.E, MPA),
                "rigid_share": self.rigid_share}

    @property
    def label(self) -> str:
        if self.surface is None:
            surface = "smooth"
        else:
            surface = (f"{self.surface.source_label}sigma {in_unit(self.sigma, UM):g} um, "
                       f"Sk {self.surface.skew:g}, Ku {self.surface.kurt:g}")
        return f"counter {surface}, {_counter_body_label(self.geometry, self.E)}"

    def columns(self) -> dict:
        """The counter body's parameters as table columns (um, MPa; NaN where none)."""
        s, nan = self.surface, float("nan")
        return {"counter_sigma_um": in_unit(self.sigma, UM),
                "counter_skew": nan if s is None else s.skew,
                "counter_kurt": nan if s is None else s.kurt,
                "counter_body": _counter_body_label(self.geometry, self.E),
                "counter_E_MPa": nan if self.E is None else in_unit(self.E, MPA)}


@dataclass(frozen=True)
class CounterJob:
    """The counter body of a contact job, in the job's non-dimensional form: the
    counter ``surface`` cell (None: smooth) with ``sigma_ratio`` sigma2 / sigma1,
    the counter ``geometry`` (None: rigid) with ``modulus_ratio`` E1 / E2, and the
    ``rigid_share`` below which the job treats the body as rigid."""

    surface: SurfaceCell | None
    sigma_ratio: float
    geometry: Geometry | None
    modulus_ratio: float
    rigid_share: float

    @classmethod
    def from_params(cls, params: dict) -> CounterJob:
        surface, geometry = params["surface"], params["geometry"]
        return cls(surface=None if surface is None else surface_cell_from_params(surface),
                   sigma_ratio=float(params["sigma_ratio"]),
                   geometry=None if geometry is None else Geometry.from_params(geometry),
                   modulus_ratio=float(params["modulus_ratio"]),
                   rigid_share=float(params["rigid_share"]))

    def params(self) -> dict:
        s, g = self.surface, self.geometry
        return {"surface": None if s is None else s.params(),
                "surface_key": None if s is None else s.key,
                "sigma_ratio": self.sigma_ratio,
                "geometry": None if g is None else g.params(),
                "geometry_key": None if g is None else g.key,
                "modulus_ratio": self.modulus_ratio, "rigid_share": self.rigid_share}

    @property
    def height_factor(self) -> float:
        """sigma1 / sqrt(sigma1^2 + sigma2^2): the equivalent heights in units of the
        cell's height scale are ``(z1 + sigma_ratio z2) * height_factor``."""
        return 1.0 / float(np.hypot(1.0, self.sigma_ratio))


@dataclass(frozen=True)
class PairGeometry:
    """Two bodies' influence models summed once: the ``first`` body's (dense) and the
    ``second``'s scaled by ``modulus_ratio`` E1 / E2, with the ``rigid_share`` that
    decides whether the second is treated as rigid. Its file
    (``results/influence/pairs/<key>.h5``) is shared by every contact job on the
    same pair (:func:`roughcontact.study.jobs.build_pair`)."""

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
    counter: CounterJob | None = None

    @classmethod
    def from_params(cls, params: dict) -> ContactJob:
        counter = params.get("counter")
        return cls(surface=surface_cell_from_params(params["surface"]),
                   geometry=Geometry.from_params(params["geometry"]),
                   pressure_end=float(params["pressure_end"]),
                   accuracy=Accuracy(params["accuracy"],
                                     tuple(params["expected_error"].items()) or None),
                   nondim_hardness=params.get("hardness"),
                   counter=None if counter is None else CounterJob.from_params(counter))

    def params(self) -> dict:
        """The job as passed to it and stored with its result (``hardness``: the cap)."""
        params = {"surface": self.surface.params(), "geometry": self.geometry.params(),
                  "surface_key": self.surface.key, "geometry_key": self.geometry.key,
                  "pressure_end": self.pressure_end, "accuracy": self.accuracy.name,
                  "expected_error": self.accuracy.errors()}
        if self.nondim_hardness is not None:
            params["hardness"] = self.nondim_hardness
        if self.counter is not None:
            params["counter"] = self.counter.params()
        return params

    @property
    def pair(self) -> PairGeometry | None:
        """The pair of influence models summed once for this job: of a compliant counter
        body on a dense first body (the pair is one dense matrix); None otherwise (a
        matrix-free first body sums the two operators in the job, without a matrix)."""
        counter = self.counter
        if (counter is None or counter.geometry is None
                or self.geometry.operator is not InfluenceModel.DENSE):
            return None
        return PairGeometry(first=self.geometry, second=counter.geometry,
                            modulus_ratio=counter.modulus_ratio, rigid_share=counter.rigid_share)

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
        if self.counter is not None:  # both bodies' parameters, hashed (names stay short)
            key = f"{key}__cf{short_hash(self.counter.params(), 10)}"
        return key


@dataclass(frozen=True)
class StudyCell:
    """One cell of a contact study: a surface cell on a geometry, scaled by ``sigma``
    [m] and ``E`` [Pa] (Eq 28-32) over the nominal ``pressure_range`` (P_min, P_max) [Pa].

    ``hardness`` H [Pa]: the cap 0 <= p <= H a capped cell is solved with (None:
    elastic). ``checked_hardness`` [Pa]: the values an elastic cell's results
    are checked against (the share of real area and load above each, no extra
    solve), flagged beyond ``hardness_threshold``.
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
    counterface: Counterface | None = None

    @classmethod
    def from_params(cls, params: dict) -> StudyCell:
        cap, expected = params.get("cap_MPa"), params.get("expected_error")
        threshold, counter = params.get("hardness_threshold"), params.get("counterface")
        return cls(surface=surface_cell_from_params(params["surface"]),
                   geometry=Geometry.from_params(params["geometry"]),
                   sigma=float(params["sigma_um"]) * UM, E=float(params["E_MPa"]) * MPA,
                   pressure_range=from_unit(params["pressure_MPa"], MPA),
                   accuracy=Accuracy(params["accuracy"],
                                     None if expected is None else tuple(expected.items())),
                   hardness=None if cap is None else float(cap) * MPA,
                   checked_hardness=from_unit(params.get("hardness_MPa") or (), MPA),
                   hardness_threshold=None if threshold is None else float(threshold),
                   counterface=None if counter is None else Counterface.from_params(counter))

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
        if self.counterface is not None:
            params["counterface"] = self.counterface.params()
        return params

    @property
    def height_scale(self) -> float:
        """The unit of the job's heights [m]: ``sigma``, or with a rough counter surface
        ``sqrt(sigma^2 + sigma2^2)``, the standard deviation of the sum of two
        independent surfaces (the equivalent surface of Eq 17-18)."""
        counter = self.counterface
        if counter is None or counter.surface is None:
            return self.sigma
        return float(np.hypot(self.sigma, counter.sigma))

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
    def counter_job(self) -> CounterJob | None:
        """The counter body in the job's form (None: a smooth rigid one)."""
        c = self.counterface
        if c is None:
            return None
        return CounterJob(surface=c.surface,
                          sigma_ratio=0.0 if c.surface is None else c.sigma / self.sigma,
                          geometry=c.geometry,
                          modulus_ratio=0.0 if c.geometry is None else self.E / c.E,
                          rigid_share=c.rigid_share)

    @property
    def contact_key(self) -> str:
        return self.job.key

    @property
    def label(self) -> str:
        """Short legend text of the cell."""
        cap = "" if self.hardness is None else f", capped at {in_unit(self.hardness, MPA):g} MPa"
        counter = "" if self.counterface is None else f"; {self.counterface.label}"
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
                "E_MPa": in_unit(self.E, MPA),
                **({} if self.counterface is None else
                   {**self.counterface.columns(),
                    "equivalent_sigma_um": in_unit(self.height_scale, UM)})}
