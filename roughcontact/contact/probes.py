"""What a sweep measures beyond pressure and load: probes, and the columns they fill.

A *probe* is a value a sweep is given (through its interface grid,
:class:`~roughcontact.contact.interface.InterfaceGrid`, ``probes``): at every step
it reads the solved fields (a :class:`SolvedFields`: the pressure and gap of every
surface, their nominal separations and the grid) and returns one (m,) value per
surface for each of its columns. The sweep allocates, fills and stores its columns
without knowing what they mean: each is described by a :class:`Column` (name, unit,
meaning, how it scales to SI units, float or yes/no), which is all the solver, the
dimensionless form (:func:`~roughcontact.contact.nondim.to_physical`), the aggregation
(:mod:`roughcontact.contact.aggregate`) and the storage need. A sweep without probes
(the empty tuple, the default) has no probe columns and costs nothing more.

A probe satisfies :class:`Probe`: ``kind`` (the name its settings are stored under),
``columns`` (its :class:`Column` specs, in order), ``params()`` (its settings as plain
values) and ``measure(fields)`` (name -> values). The flow through the gap
(:class:`roughcontact.transport.probe.FlowProbe`) is one; the columns a sweep holds are
a :class:`ProbeColumns`.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Protocol, runtime_checkable

import numpy as np

__all__ = ["Column", "Probe", "ProbeColumns", "SolvedFields", "column_names", "measure"]

#: The types of values a column may hold: a number, or a yes/no state.
DTYPES = (float, bool)


@dataclass(frozen=True)
class Column:
    """One (m, k) column a probe records: a value per surface and step.

    Parameters
    ----------
    name : str
        The column's name in a sweep, a contact file (its dataset) and an aggregate
        table (``<name>_mean``, ``_half_width``, ``_count``).
    unit : str
        The unit of its aggregated values in SI units (``"m^3"``, ``"1"``, ...; a
        yes/no column's mean is a share, ``"1"``).
    meaning : str
        What it is, for the tables' readers (the aggregate sidecar's units and
        :data:`~roughcontact.contact.aggregate.QUANTITIES`-like descriptions).
    length_power : int
        The power of the length scale that takes its values to SI units: the gaps a
        dimensionless sweep reads are in units of sigma, so a column of the gap cubed
        [m^3] is multiplied by ``sigma**3`` (3); a ratio or a state is the same in
        both forms (0).
    dtype : {float, bool}
        A number (averaged by interpolation in log P) or a yes/no state (averaged as
        the share of surfaces in it, each read at its step nearest in log P).
    rounding : float
        Values that differ by at most this much are the same to rounding (a measure
        of rounding error itself, e.g. the flow's balance): the scale below which a
        re-solve's relative difference is not counted (the audit); 0: none.
    """

    name: str
    unit: str
    meaning: str
    length_power: int = 0
    dtype: type = float
    rounding: float = 0.0

    def __post_init__(self):
        if not (isinstance(self.name, str) and self.name.isidentifier()):
            raise ValueError(f"a column's name must be an identifier, got {self.name!r}")
        if self.dtype not in DTYPES:
            raise ValueError(f"column {self.name}: dtype must be float or bool, got "
                             f"{self.dtype!r}")
        if isinstance(self.length_power, bool) or int(self.length_power) != self.length_power:
            raise ValueError(f"column {self.name}: length_power must be an integer, got "
                             f"{self.length_power!r}")
        if self.dtype is bool and self.length_power:
            raise ValueError(f"column {self.name}: a yes/no column does not scale "
                             f"(length_power 0), got {self.length_power!r}")

    @property
    def state(self) -> bool:
        """A yes/no state (``dtype`` bool): aggregated as the share of surfaces in it."""
        return self.dtype is bool


@dataclass(frozen=True)
class SolvedFields:
    """The solved steps a probe reads: a stack of fields (leading axes: surfaces, and
    perhaps steps) on the interface grid.

    Attributes
    ----------
    pressure : ndarray, (..., ny, nx)
        Element pressures [Pa] (in a dimensionless sweep ``p L / (E sigma)``; ``p > 0``
        marks contact).
    gap : ndarray, (..., ny, nx)
        Gaps ``u + f - d`` [m] (in a dimensionless sweep, in units of sigma).
    separation : ndarray, (...)
        Nominal separations ``mean(f) - d`` of the flat and the undeformed mean plane of
        the rough surface [m] (likewise in units of sigma).
    spacing : (float, float)
        Element sides ``(dx, dy)`` [m] (``dx`` along the last axis).
    periodic : bool
        The grid repeats.
    """

    pressure: np.ndarray
    gap: np.ndarray
    separation: np.ndarray
    spacing: tuple[float, float]
    periodic: bool


@runtime_checkable
class Probe(Protocol):
    """What a sweep records at every step beyond pressure and load (module docstring)."""

    #: The name its settings are stored under (a contact file's attribute).
    kind: str

    @property
    def columns(self) -> tuple[Column, ...]:
        """Its columns, in order."""

    def params(self) -> dict:
        """Its settings as plain values (JSON), from which it is made again."""

    def measure(self, fields: SolvedFields) -> Mapping[str, np.ndarray]:
        """Its columns' values of the solved ``fields``: name -> array of their leading
        shape."""


def measure(probes, fields: SolvedFields) -> dict:
    """Every column of ``probes`` measured on ``fields``, by name in their order (a probe
    must return each of its columns)."""
    out = {}
    for probe in probes:
        values = probe.measure(fields)
        for column in probe.columns:
            out[column.name] = values[column.name]
    return out


def column_names(probes) -> tuple[str, ...]:
    """The columns' names of ``probes`` in order, refused where two share a name."""
    names = tuple(column.name for probe in probes for column in probe.columns)
    if len(set(names)) != len(names):
        raise ValueError(f"the probes' columns must have distinct names, got {names}")
    return names


@dataclass(frozen=True, eq=False)
class ProbeColumns(Mapping):
    """The probe columns a sweep or record holds: a read-only mapping name -> array
    (m, k), in the order of its ``probes``' columns; empty without probes.

    Parameters
    ----------
    probes : tuple of Probe
        The probes that recorded them.
    values : mapping
        Name -> array, one for every column of ``probes``.
    """

    probes: tuple = ()
    values: Mapping[str, np.ndarray] = field(default_factory=dict)

    def __post_init__(self):
        probes = tuple(self.probes)
        names = column_names(probes)
        if set(self.values) != set(names):
            raise ValueError(f"probe columns {sorted(self.values)} differ from the columns "
                             f"{list(names)} of the probes")
        object.__setattr__(self, "probes", probes)
        object.__setattr__(self, "values", MappingProxyType(
            {name: self.values[name] for name in names}))

    def __getitem__(self, name: str) -> np.ndarray:
        return self.values[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self.values)

    def __len__(self) -> int:
        return len(self.values)

    @property
    def specs(self) -> tuple[Column, ...]:
        """The :class:`Column` of every column, in order."""
        return tuple(column for probe in self.probes for column in probe.columns)

    @classmethod
    def allocated(cls, probes, shape) -> ProbeColumns:
        """Columns of ``probes`` of ``shape`` to fill (zeros of each column's dtype)."""
        return cls(probes, {column.name: np.zeros(shape, dtype=column.dtype)
                            for probe in probes for column in probe.columns})

    @classmethod
    def concatenated(cls, parts) -> ProbeColumns:
        """The columns of ``parts`` (of the same probes; e.g. batches of surfaces) joined
        along their first axis."""
        parts = list(parts)
        probes = parts[0].probes
        return cls(probes, {name: np.concatenate([part[name] for part in parts])
                            for name in parts[0]})

    def in_length(self, length: float) -> ProbeColumns:
        """The columns with lengths in units of ``length`` [m] (sigma of a dimensionless
        sweep) taken to SI units: each multiplied by ``length**length_power``; those of
        power 0 unchanged (the same arrays)."""
        return ProbeColumns(self.probes, {
            column.name: (self[column.name] if column.length_power == 0
                          else length**column.length_power * self[column.name])
            for column in self.specs})
