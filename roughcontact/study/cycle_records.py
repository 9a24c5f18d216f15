"""Loading, unloading, reloading in a study: the ``loading`` section and its cycle jobs.

With the ``loading`` section on, every capped cell of a study (``contact.cap``) is also
swept along a loading path that rises and falls
(:class:`~roughcontact.contact.cycles.LoadingPath`): from no load up to the cell's
highest pressure level, down to ``unload_to`` of it, ``cycles`` times, ``steps`` equal
load steps per leg, with the cap's permanent set kept from step to step
(:func:`~roughcontact.contact.cycles.cycle_sweep`). Load control: every surface of a
cell sits at the same nominal pressure at every step, so the study averages them step
by step.

A :class:`CycleJob` solves one cell's path on the files of its contact job (the same
surfaces, influence, counter body and thermal influence, :meth:`CycleJob.files`), in
the non-dimensional form of :mod:`roughcontact.contact.nondim`: the path in
``P L / (E sigma)``, shared by every cell with the same contact job and peak. Its file
is ``results/cycles/<key>.h5`` (:data:`roughcontact.study.layout.cycle`). The
:class:`LoadingSettings` of a study off (:data:`NO_LOADING`) asks for no cycle job.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from roughcontact.contact.cycles import LoadingPath
from roughcontact.study import codec, layout
from roughcontact.study.codec import Record
from roughcontact.study.contact_records import ContactJob, StudyCell
from roughcontact.study.counter_records import JobFile

__all__ = ["NO_LOADING", "CycleJob", "LoadingSettings", "loading_settings"]


@dataclass(frozen=True)
class CycleJob(Record):
    """One cell's loading path on its contact job's files (module docstring).

    ``contact`` the capped :class:`~roughcontact.study.contact_records.ContactJob` whose
    surfaces, influence, cap and counter body it sweeps; ``peak`` the path's highest
    ``P L / (E sigma)`` (7 significant digits); ``cycles``, ``steps`` per leg and
    ``unload_to`` (a fraction of the peak) as in
    :meth:`~roughcontact.contact.cycles.LoadingPath.cycles`.
    """

    contact: ContactJob = codec.record(ContactJob)
    contact_key: str = codec.key_of("contact")
    peak: float
    cycles: int
    steps: int
    unload_to: float

    @property
    def key(self) -> str:
        """File key: its contact job's and the path's."""
        unload = f"_to{self.unload_to:g}" if self.unload_to else ""
        return (f"{self.contact.key}__cycles{self.cycles}x{self.steps}_peak{self.peak:.7g}"
                f"{unload}")

    def path(self) -> LoadingPath:
        """The path in ``P L / (E sigma)``, from no load."""
        return LoadingPath.cycles(self.peak, self.steps, unload_to=self.unload_to * self.peak,
                                  cycles=self.cycles, control="mean_pressure")

    def files(self, study_seed=None) -> dict[str, JobFile]:
        """The files it reads: its contact job's
        (:meth:`~roughcontact.study.contact_records.ContactJob.files`)."""
        return self.contact.files(study_seed)

    def paths(self) -> dict[str, str]:
        """The paths of :meth:`files`, by input name (a rule's inputs)."""
        return self.contact.paths()

    @property
    def output(self) -> str:
        """Its file."""
        return layout.cycle(self.key)


@dataclass(frozen=True)
class LoadingSettings(Record):
    """The ``loading`` section: ``enabled``; ``cycles`` of loading and unloading, each
    leg in ``steps`` equal load steps; ``unload_to`` the share of the peak each cycle
    unloads to (0: no load). The peak is each cell's highest pressure level."""

    enabled: bool = False
    cycles: int = 2
    steps: int = 16
    unload_to: float = 0.0

    def applies(self, cell: StudyCell) -> bool:
        """Whether ``cell`` is swept along the path: on, and the cell capped."""
        return self.enabled and cell.hardness is not None

    def job(self, cell: StudyCell, contact: ContactJob | None = None) -> CycleJob:
        """The cycle job of a capped ``cell`` (on ``contact``, the plan's record of its
        contact job, with the files it reads; by default the cell's own)."""
        return CycleJob(contact=cell.job if contact is None else contact,
                        peak=float(f"{cell.nondim(cell.pressure_range[1]):.7g}"),
                        cycles=self.cycles, steps=self.steps, unload_to=self.unload_to)


#: The section off: no cycle job.
NO_LOADING = LoadingSettings()


def loading_settings(section: Mapping) -> LoadingSettings:
    """The settings of a validated ``loading`` section (every default filled in)."""
    return LoadingSettings(enabled=bool(section["enabled"]), cycles=int(section["cycles"]),
                           steps=int(section["steps"]),
                           unload_to=float(section["unload_to"]))
