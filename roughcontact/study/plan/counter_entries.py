"""The counter bodies a study configures, resolved once (Eq 17-18): the config edge.

A study's counter body is written as a ``surface`` (``smooth``, a generated one
with its sigma and moments, or a ``measured`` map) and a ``body`` (``rigid``, an
elastic ``block`` or a ``halfspace``), each under its own key or the
``counterface`` section's. :func:`counterface_entries` reads them once into typed
entries, every default resolved (the ``body`` section's nu, thickness, base and
mesh for a block; the first surface's b and the measured sigma stay None, each
cell's), with the configuration keys of their values for the messages that name
them. An entry answers what the plan and its checks ask of it: the counter body
of a study cell (:meth:`CounterfaceEntry.counterface`, a
:class:`~roughcontact.study.counter_records.CounterBody`), its typed values with
their keys (:meth:`CounterfaceEntry.typed_values`, what the plausibility checks
judge), a measured map's import problems, a block's; the smooth surface and the
rigid body are its null values, and a smooth rigid counter body is no counter body
at all (:class:`FlatEntry`), so the code that asks never tests which it holds.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

from roughcontact.study.codec import as_pair, from_unit, in_unit, in_units
from roughcontact.study.contact_records import StudyCell
from roughcontact.study.counter_records import (
    NO_COMPLIANCE,
    NO_COUNTER_BODY,
    NO_HEIGHTS,
    CounterBody,
    CounterCompliance,
    CounterHeights,
)
from roughcontact.study.records import Geometry, InfluenceModel, MeasuredCell, SurfaceCell
from roughcontact.study.sources import MeasurementImport
from roughcontact.units import MM, MPA, UM

__all__ = ["BODY_INHERITED", "CounterfaceEntry", "FlatEntry", "counterface_entries",
           "import_problems"]

#: The keys of a counter block that default to the ``body`` section's.
BODY_INHERITED = ("nu", "thickness_mm", "base", "mesh")


def import_problems(where: str, entry) -> list[str]:
    """The refusal of a measured map that cannot be imported as its ``entry`` (a
    ``surface:`` or a counter surface's ``measured:``) says, named ``where``."""
    try:
        MeasuredCell.from_source(MeasurementImport.from_params(entry))
    except (OSError, ValueError) as err:
        return [f"{where}: {err}"]
    return []


# ---------------------------------------------------------------------------
# Counter surfaces


@dataclass(frozen=True)
class SmoothEntry:
    """A smooth counter surface (the null): no heights, no typed values."""

    key: str = field(default="counterface.surface", compare=False)

    def counter(self, surfaces, first: SurfaceCell) -> tuple:
        return NO_HEIGHTS, 0.0

    def typed_values(self, counter: CounterBody) -> dict:
        return {}

    def own_b(self, counter: CounterBody) -> tuple:
        return ()

    def import_problems(self) -> list[str]:
        return []


@dataclass(frozen=True)
class GeneratedEntry:
    """A generated counter surface: ``sigma_um``, ``skew``, ``kurt`` and ``b_mm`` as
    written (None: each first surface's b), seed stream ``counter``."""

    sigma_um: float
    skew: float
    kurt: float
    b_mm: object = None
    key: str = field(default="counterface.surface", compare=False)

    def counter(self, surfaces, first: SurfaceCell) -> tuple:
        """The counter heights and sigma [m] of a first cell ``first``: the ``surfaces``
        section's ACF, periodicity and method on its grid and plan size, one counter
        surface per first surface, b by default the first cell's."""
        b = first.corr_length if self.b_mm is None else from_unit(as_pair(self.b_mm))
        cell = surfaces.cell(None, skew=self.skew, kurt=self.kurt, corr_length=b,
                             count=first.count, size=first.size, grid=first.grid)
        return (CounterHeights(dataclasses.replace(cell, stream="counter")),
                float(self.sigma_um) * UM)

    def typed_values(self, counter: CounterBody) -> dict:
        """Its sigma [m] with its key."""
        return {"sigma_um": (f"{self.key}.sigma_um", counter.sigma)}

    def own_b(self, counter: CounterBody) -> tuple:
        """The key and value of its own ``b_mm`` with the counter cell it made (none
        where b is each first surface's, judged with it)."""
        if self.b_mm is None:
            return ()
        return ((f"{self.key}.b_mm", self.b_mm, counter.heights.cell),)

    def import_problems(self) -> list[str]:
        return []


@dataclass(frozen=True)
class MeasuredEntry:
    """A measured counter map: its ``measured`` import entry as configured and
    ``sigma_um`` (None: the measured sigma)."""

    measured: dict
    sigma_um: float | None = None
    key: str = field(default="counterface.surface", compare=False)

    def counter(self, surfaces, first: SurfaceCell) -> tuple:
        cell = MeasuredCell.from_source(MeasurementImport.from_params(self.measured))
        sigma = cell.sigma if self.sigma_um is None else float(self.sigma_um) * UM
        return CounterHeights(cell), sigma

    def typed_values(self, counter: CounterBody) -> dict:
        """Its measured map and, where written, its sigma [m], with their keys."""
        values = {"measured": (f"{self.key}.measured", counter.heights.cell)}
        if self.sigma_um is not None:
            values["sigma_um"] = (f"{self.key}.sigma_um", counter.sigma)
        return values

    def own_b(self, counter: CounterBody) -> tuple:
        return ()

    def import_problems(self) -> list[str]:
        return import_problems(f"{self.key}.measured.file", self.measured)


# ---------------------------------------------------------------------------
# Counter bodies


@dataclass(frozen=True)
class RigidEntry:
    """A rigid counter body (the null): no compliance, no typed values."""

    key: str = field(default="counterface.body", compare=False)

    def counter(self, first: Geometry) -> tuple:
        return NO_COMPLIANCE, None

    def typed_values(self, counter: CounterBody) -> dict:
        return {}


@dataclass(frozen=True)
class HalfspaceEntry:
    """An elastic half-space counter body (Love's) of ``E_MPa`` and ``nu``."""

    E_MPa: float
    nu: float
    key: str = field(default="counterface.body", compare=False)

    def counter(self, first: Geometry) -> tuple:
        """Its compliance, on the first body's grid and plan size (the thickness only the
        reference length of the scaling), and E [Pa]."""
        params = {"nu": self.nu, "size_mm": in_units(first.size), "grid": list(first.grid),
                  "operator": InfluenceModel.HALFSPACE.value, "base": "clamped",
                  "mesh": "paper", "thickness_mm": in_unit(first.thickness, MM)}
        return CounterCompliance(Geometry.from_params(params)), float(self.E_MPa) * MPA

    def typed_values(self, counter: CounterBody) -> dict:
        """Its E [Pa] with its key."""
        return {"E_MPa": (f"{self.key}.E_MPa", counter.E)}


@dataclass(frozen=True)
class BlockEntry:
    """An elastic block counter body: ``E_MPa``, ``nu``, ``thickness_mm``, ``base``,
    ``mesh`` and ``operator``; ``inherited`` the keys of :data:`BODY_INHERITED` that are
    the ``body`` section's."""

    E_MPa: float
    nu: float
    thickness_mm: float
    base: str
    mesh: object
    operator: InfluenceModel
    inherited: tuple[str, ...] = field(default=(), compare=False)
    key: str = field(default="counterface.body", compare=False)

    def counter(self, first: Geometry) -> tuple:
        params = {"nu": self.nu, "size_mm": in_units(first.size), "grid": list(first.grid),
                  "thickness_mm": self.thickness_mm, "base": self.base, "mesh": self.mesh,
                  "operator": self.operator.value}
        return CounterCompliance(Geometry.from_params(params)), float(self.E_MPa) * MPA

    def typed_values(self, counter: CounterBody) -> dict:
        """Its E [Pa] and, of a finite block, its geometry (judged by its thickness), with
        their keys (the body section's where inherited)."""
        values = {"E_MPa": (f"{self.key}.E_MPa", counter.E)}
        if self.operator is not InfluenceModel.HALFSPACE:
            values["thickness_mm"] = ("body.thickness_mm" if "thickness_mm" in self.inherited
                                      else f"{self.key}.thickness_mm",
                                      counter.compliance.geometry)
        return values


def _surface_entry(entry, key: str):
    """The counter surface of its configured ``entry`` (``smooth`` or a section)."""
    if entry == "smooth":
        return SmoothEntry(key)
    if "measured" in entry:
        return MeasuredEntry(dict(entry["measured"]), entry.get("sigma_um"), key)
    return GeneratedEntry(entry["sigma_um"], entry["skew"], entry["kurt"], entry.get("b_mm"),
                          key)


def _body_entry(entry, key: str, body: Geometry):
    """The counter body of its configured ``entry`` (``rigid`` or a section), a block's
    missing keys the ``body`` section's (``body``, its geometry)."""
    if entry == "rigid":
        return RigidEntry(key)
    if entry["kind"] == "halfspace":
        return HalfspaceEntry(entry["E_MPa"], entry.get("nu", body.nu), key)
    section = {"nu": body.nu, "thickness_mm": in_unit(body.thickness, MM), "base": body.base,
               "mesh": body.mesh}
    inherited = tuple(k for k in BODY_INHERITED if k not in entry)
    values = {**section, **{k: entry[k] for k in BODY_INHERITED if k in entry}}
    return BlockEntry(entry["E_MPa"], inherited=inherited, key=key,
                      operator=InfluenceModel(entry["operator"]), **values)


@dataclass(frozen=True)
class CounterfaceEntry:
    """One counter body of a study as configured: its ``surface`` and ``body`` entries
    (every default resolved, each with its configuration key) and the ``rigid_share``."""

    surface: SmoothEntry | GeneratedEntry | MeasuredEntry
    body: RigidEntry | HalfspaceEntry | BlockEntry
    rigid_share: float = field(default=0.001, compare=False)

    @property
    def surface_key(self) -> str:
        return self.surface.key

    @property
    def body_key(self) -> str:
        return self.body.key

    def counterface(self, surfaces, cell: StudyCell) -> CounterBody:
        """The counter body of a study ``cell`` (on its grid and plan size; ``surfaces``
        the study's surface settings)."""
        heights, sigma = self.surface.counter(surfaces, cell.surface)
        compliance, E = self.body.counter(cell.geometry)
        return CounterBody(heights=heights, sigma=sigma, compliance=compliance, E=E,
                           rigid_share=self.rigid_share)

    def typed_values(self, cell: StudyCell) -> dict:
        """The typed values of the counter body of ``cell``, each with its configuration
        key: ``sigma_um`` (sigma [m]), ``E_MPa`` (E [Pa]), ``thickness_mm`` (the block's
        geometry), ``measured`` (the measured cell); absent where not typed (the checks
        of :mod:`~roughcontact.study.plan.body_checks` judge each)."""
        counter = cell.counterface
        return {**self.surface.typed_values(counter), **self.body.typed_values(counter)}


@dataclass(frozen=True)
class FlatEntry(CounterfaceEntry):
    """The paper's rigid smooth flat as configured (a smooth surface on a rigid body):
    no counter body at all."""

    def counterface(self, surfaces, cell: StudyCell):
        return NO_COUNTER_BODY

    def typed_values(self, cell: StudyCell) -> dict:
        return {}


def _entry(surface, surface_key: str, counter, body_key: str, body: Geometry,
           rigid_share: float):
    """The counter body of its configured ``surface`` and ``body`` entries (a smooth
    surface on a rigid body: a :class:`FlatEntry`, with their keys)."""
    entry = (_surface_entry(surface, surface_key), _body_entry(counter, body_key, body))
    if entry == (SmoothEntry(), RigidEntry()):
        return FlatEntry(*entry, rigid_share)
    return CounterfaceEntry(*entry, rigid_share)


def counterface_entries(study, name: str) -> list[CounterfaceEntry]:
    """The counter bodies of the figure or sweep ``name`` of ``study`` (of its source,
    with ``from:``): its ``counterface`` (one entry, or a list: an axis), each entry's
    ``surface`` and ``body`` over the ``counterface`` section's; the section's own (by
    default a smooth rigid flat) when the study names none."""
    section = study.counterface
    own = study.source(name).get("counterface")  # optional: the section's
    where = f"{study.path(study.source_name(name))}.counterface"
    if own is None:
        entries, keys = [{}], [None]
    elif isinstance(own, list):
        entries, keys = own, [f"{where}[{i}]" for i in range(len(own))]
    else:
        entries, keys = [own], [where]
    body = study.body.geometry
    out = []
    for entry, key in zip(entries, keys, strict=True):
        (surface, surface_key), (counter, body_key) = (
            (entry[part], f"{key}.{part}") if part in entry else
            (getattr(section, part), f"counterface.{part}") for part in ("surface", "body"))
        out.append(_entry(surface, surface_key, counter, body_key, body, section.rigid_share))
    return out

