"""The counter bodies a study configures, resolved once (Eq 17-18): the config edge.

A study's counter body is written as a ``surface`` (``smooth``, a generated one
with its sigma and moments, or a ``measured`` map) and a ``body`` (``rigid``, an
elastic ``block`` or a ``halfspace``), each under its own key or the
``counterface`` section's. :func:`counterface_entries` reads them once into typed
entries, every default resolved (the ``body`` section's nu, thickness, base and
mesh for a block; the first surface's b and the measured sigma stay None, each
cell's), with the configuration keys of their values for the messages that name
them. An entry answers what the plan and its checks ask of it: the counter body
of a study cell (:meth:`CounterfaceEntry.counterface`), the keys of its typed
values, a measured map's import problems, a block's; the smooth surface and the
rigid body are its null values, so the code that asks never tests which it holds.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

from roughcontact.study.config import as_pair, from_unit, in_unit, in_units
from roughcontact.study.contact_records import StudyCell
from roughcontact.study.counter_records import (
    RIGID,
    SMOOTH,
    Counterface,
    ElasticCounter,
    RoughCounter,
)
from roughcontact.study.records import Geometry, InfluenceModel, MeasuredCell, SurfaceCell
from roughcontact.study.sources import MeasurementImport
from roughcontact.units import MM, MPA, UM

__all__ = ["BODY_INHERITED", "CounterfaceEntry", "counterface_entries", "import_problems"]

#: The keys of a counter block that default to the ``body`` section's.
BODY_INHERITED = ("nu", "thickness_mm", "base", "mesh")


def import_problems(where: str, entry) -> list[str]:
    """The refusal of a measured map that cannot be imported as its ``entry`` (a
    ``surface:`` or a counter surface's ``measured:``) says, named ``where``."""
    try:
        MeasuredCell.from_source(MeasurementImport.from_entry(entry))
    except (OSError, ValueError) as err:
        return [f"{where}: {err}"]
    return []


# ---------------------------------------------------------------------------
# Counter surfaces


@dataclass(frozen=True)
class SmoothEntry:
    """A smooth counter surface (the null): no heights, no keys."""

    key: str = field(default="counterface.surface", compare=False)

    def counter(self, surfaces, first: SurfaceCell):
        return SMOOTH

    def keys(self, cell) -> dict:
        return {}

    def own_b(self) -> tuple:
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

    def counter(self, surfaces, first: SurfaceCell) -> RoughCounter:
        """The counter surface of a first cell ``first``: the ``surfaces`` section's ACF,
        periodicity and method on its grid and plan size, one counter surface per first
        surface, b by default the first cell's."""
        b = first.corr_length if self.b_mm is None else from_unit(as_pair(self.b_mm))
        cell = surfaces.cell(None, skew=self.skew, kurt=self.kurt, corr_length=b,
                             count=first.count, size=first.size, grid=first.grid)
        return RoughCounter(dataclasses.replace(cell, stream="counter"),
                            sigma=float(self.sigma_um) * UM)

    def keys(self, cell) -> dict:
        return {"sigma_um": f"{self.key}.sigma_um"}

    def own_b(self) -> tuple:
        """The key and value of its own ``b_mm`` (none where b is each first surface's,
        judged with it)."""
        return () if self.b_mm is None else ((f"{self.key}.b_mm", self.b_mm),)

    def import_problems(self) -> list[str]:
        return []


@dataclass(frozen=True)
class MeasuredEntry:
    """A measured counter map: its ``measured`` import entry as configured and
    ``sigma_um`` (None: the measured sigma)."""

    measured: dict
    sigma_um: float | None = None
    key: str = field(default="counterface.surface", compare=False)

    def counter(self, surfaces, first: SurfaceCell) -> RoughCounter:
        cell = MeasuredCell.from_source(MeasurementImport.from_entry(self.measured))
        sigma = cell.sigma if self.sigma_um is None else float(self.sigma_um) * UM
        return RoughCounter(cell, sigma=sigma)

    def keys(self, cell) -> dict:
        keys = {"measured": f"{self.key}.measured"}
        if self.sigma_um is not None:
            keys["sigma_um"] = f"{self.key}.sigma_um"
        return keys

    def own_b(self) -> tuple:
        return ()

    def import_problems(self) -> list[str]:
        return import_problems(f"{self.key}.measured.file", self.measured)


# ---------------------------------------------------------------------------
# Counter bodies


@dataclass(frozen=True)
class RigidEntry:
    """A rigid counter body (the null): no compliance, no keys."""

    key: str = field(default="counterface.body", compare=False)

    def counter(self, first: Geometry):
        return RIGID

    def keys(self, geometry) -> dict:
        return {}


@dataclass(frozen=True)
class HalfspaceEntry:
    """An elastic half-space counter body (Love's) of ``E_MPa`` and ``nu``."""

    E_MPa: float
    nu: float
    key: str = field(default="counterface.body", compare=False)

    def counter(self, first: Geometry) -> ElasticCounter:
        """Its geometry on the first body's grid and plan size (the thickness only the
        reference length of the scaling)."""
        params = {"nu": self.nu, "size_mm": in_units(first.size), "grid": list(first.grid),
                  "operator": InfluenceModel.HALFSPACE.value, "base": "clamped",
                  "mesh": "paper", "thickness_mm": in_unit(first.thickness, MM)}
        return ElasticCounter(Geometry.from_params(params), E=float(self.E_MPa) * MPA)

    def keys(self, geometry) -> dict:
        return {"E_MPa": f"{self.key}.E_MPa"}


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

    def counter(self, first: Geometry) -> ElasticCounter:
        params = {"nu": self.nu, "size_mm": in_units(first.size), "grid": list(first.grid),
                  "thickness_mm": self.thickness_mm, "base": self.base, "mesh": self.mesh,
                  "operator": self.operator.value}
        return ElasticCounter(Geometry.from_params(params), E=float(self.E_MPa) * MPA)

    def keys(self, geometry) -> dict:
        """Its E's key and, of a finite block, its thickness's (the body section's where
        inherited)."""
        keys = {"E_MPa": f"{self.key}.E_MPa"}
        if self.operator is not InfluenceModel.HALFSPACE:
            keys["thickness_mm"] = ("body.thickness_mm" if "thickness_mm" in self.inherited
                                    else f"{self.key}.thickness_mm")
        return keys


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

    def counterface(self, surfaces, cell: StudyCell):
        """The counter body of a study ``cell`` (on its grid and plan size; ``surfaces``
        the study's surface settings); the smooth rigid one is no counter body at all
        (:data:`~roughcontact.study.counter_records.NO_COUNTERFACE`: the paper's)."""
        return Counterface.of(self.surface.counter(surfaces, cell.surface),
                              self.body.counter(cell.geometry), self.rigid_share)

    def keys(self, cell: StudyCell) -> dict:
        """The configuration key of each typed value of its counter body on ``cell``
        (:class:`~roughcontact.study.plan.body_checks.Body`'s ``keys``)."""
        return {**self.surface.keys(cell), **self.body.keys(cell.geometry)}


#: The counter body of a study that names none, in a section that names none.
NO_ENTRY = CounterfaceEntry(SmoothEntry(), RigidEntry())


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
        out.append(CounterfaceEntry(_surface_entry(surface, surface_key),
                                    _body_entry(counter, body_key, body), section.rigid_share))
    return out

