"""The thermal influence of a contact job's block: built once per block, read by its jobs.

With the ``conductance`` section on and the heat crossing the block
(``conductance.body: block``), every contact job records the conductance through its
block's thermal influence ``k R`` [m] (:mod:`roughcontact.transport.conduction`), which
depends on the block's plan size, thickness, contact grid and mesh only (not on E, nu,
the base's support or the elastic model). Like the elastic influence, it is built once
per block by its own job (``rules/influence.smk``, ``thermal_influence``;
:func:`roughcontact.study.jobs.thermal.build_thermal`) and read by every contact job on
that block, checked to have been made for it: a :class:`ThermalBlock` on the contact
job (:attr:`~roughcontact.study.contact_records.ContactJob.thermal`) names the file
(:meth:`ThermalBlock.files`) and gives the job's conductance probe the stored influence
the job reads (:meth:`ThermalBlock.seeded`). A job without it holds :data:`NO_THERMAL`,
which names no file and leaves the probes as they are.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from roughcontact.elasticity.influence import BlockGeometry
from roughcontact.elasticity.operators import coarse_geometry
from roughcontact.study import codec, layout
from roughcontact.study.codec import Record, in_unit, in_units
from roughcontact.study.counter_records import JobFile
from roughcontact.transport.conduction.bodies import DENSE_LIMIT
from roughcontact.transport.conduction.probe import BlockBody, ConductanceProbe
from roughcontact.units import MM

__all__ = ["NO_THERMAL", "ThermalBlock", "thermal_from_params", "with_thermal"]


@dataclass(frozen=True)
class ThermalBlock(Record):
    """A block's thermal influence file (module docstring): plan ``size`` (Lx, Ly) [m],
    ``thickness`` L [m], contact ``grid`` (nx, ny) and ``mesh`` preset. Its params
    (lengths in mm) are the file's ``params`` attribute and the build job's params."""

    size: tuple[float, float] = codec.si_pair(MM, "size_mm")
    thickness: float = codec.si(MM, "thickness_mm")
    grid: tuple[int, int] = codec.grid()
    mesh: str

    @classmethod
    def of(cls, geometry) -> ThermalBlock:
        """The thermal block of a contact job's
        :class:`~roughcontact.study.records.Geometry`."""
        return cls(size=tuple(geometry.size), thickness=geometry.thickness,
                   grid=tuple(geometry.grid), mesh=geometry.mesh)

    @property
    def key(self) -> str:
        """File key (every parameter that changes ``k R``)."""
        (lx, ly), (nx, ny) = in_units(self.size), self.grid
        return (f"L{lx:g}x{ly:g}mm_t{in_unit(self.thickness, MM):g}mm_g{nx}x{ny}"
                f"_{self.mesh}")

    def block(self) -> BlockGeometry:
        """The block (E, nu and the base do not enter the thermal problem)."""
        return BlockGeometry(size=self.size, thickness=self.thickness, grid=self.grid,
                             mesh=self.mesh)

    def coarse_model(self) -> BlockGeometry | None:
        """The coarse block whose dense ``k R`` its job builds and stores beyond
        :data:`~roughcontact.transport.conduction.bodies.DENSE_LIMIT` elements (the
        matrix-free thermal block's correction); None: its own dense ``k R``."""
        if self.grid[0] * self.grid[1] <= DENSE_LIMIT:
            return None
        return coarse_geometry(self.block())

    def files(self) -> dict[str, JobFile]:
        """The file a contact job reads, under its input name ``thermal``."""
        return {"thermal": JobFile(layout.thermal(self.key), {"geometry": self.params()})}

    def seeded(self, probes: tuple, paths: dict, read) -> tuple:
        """``probes`` with the conductance probe given the stored influence of
        ``paths["thermal"]``, read by the job's ``read(path, block)``
        (:func:`roughcontact.study.jobs.thermal.read_thermal`: checked to have been made
        for this block, its content hash verified)."""
        unit = read(paths["thermal"], self)
        return tuple(probe.with_unit_influence(unit) if isinstance(probe, ConductanceProbe)
                     else probe for probe in probes)


@dataclass(frozen=True)
class _NoThermal:
    """No thermal influence file: the job's probes build what they need."""

    key: str = ""

    def files(self) -> dict:
        return {}

    def seeded(self, probes: tuple, paths: dict, read) -> tuple:
        return probes

    def params(self) -> None:
        return None


#: A contact job that reads no thermal influence.
NO_THERMAL = _NoThermal()


def thermal_from_params(params: dict) -> ThermalBlock:
    """The :class:`ThermalBlock` of its params."""
    return ThermalBlock.from_params(params)


def with_thermal(job, conductance):
    """``job`` (a :class:`~roughcontact.study.contact_records.ContactJob`) reading its
    block's thermal influence where the study's ``conductance``
    (:class:`~roughcontact.study.conductance_settings.ConductanceSettings`) is on and
    crosses the block; unchanged otherwise."""
    if not conductance.enabled or not isinstance(
            job.geometry.thermal_body(conductance.materials.body), BlockBody):
        return job
    return dataclasses.replace(job, thermal=ThermalBlock.of(job.geometry))
