"""The probes a study records: the one registry of probe kinds, and their study-side records.

A contact job's sweep records the columns of the probes its settings name
(:attr:`~roughcontact.study.config.ContactSettings.probes`;
:mod:`roughcontact.contact.probes`), and its contact file stores each probe's
settings (``params()``, JSON) under the probe's ``kind`` (``flow`` for the flow
through the gap, the attribute files have carried since the flow began).
:data:`PROBE_KINDS` is the one place that turns a kind and its stored settings back
into the probe (:func:`probes_from_attrs`: the reader of a contact file, the audit).

What a study adds to a probe's columns when it aggregates a cell (the leak rate of
a seal beside the flow's conductance, the percolation thresholds in the sidecar) is
the probe's :class:`StudyProbe` record; :func:`study_probes` gives those the
configuration turns on, :data:`STUDY_PROBE_KINDS` makes them again from their params
(the aggregate rule's, :func:`study_probe_params`).
"""

from __future__ import annotations

import json
from types import MappingProxyType
from typing import Protocol

from roughcontact.contact.probes import Probe
from roughcontact.study.conductance_settings import ConductanceSettings
from roughcontact.study.flow_settings import FlowSettings
from roughcontact.transport.conduction.probe import (
    ConductanceProbe,
    conductance_probe_from_params,
)
from roughcontact.transport.probe import FlowProbe, probe_from_params

__all__ = ["PROBE_KINDS", "STUDY_PROBE_KINDS", "StudyProbe", "probes_from_attrs",
           "study_probe_params", "study_probes", "study_probes_from_params"]

#: Probe kind (the attribute its settings are stored under) -> the probe of its stored
#: settings (``params()``).
PROBE_KINDS = MappingProxyType({FlowProbe.kind: probe_from_params,
                                ConductanceProbe.kind: conductance_probe_from_params})


def probes_from_attrs(attrs: dict) -> tuple[Probe, ...]:
    """The probes a contact file was solved with: one for each kind of
    :data:`PROBE_KINDS` whose settings its attributes ``attrs`` hold (JSON text, or
    already parsed); none for a file solved without probes."""
    probes = []
    for kind, from_params in PROBE_KINDS.items():
        stored = attrs.get(kind)
        if stored:
            probes.append(from_params(json.loads(stored) if isinstance(stored, str)
                                      else stored))
    return tuple(probes)


class StudyProbe(Protocol):
    """What the aggregation adds to a probe's columns (e.g.
    :class:`~roughcontact.study.flow_settings.FlowSettings` for the flow)."""

    #: The probe's kind: its entry in the sidecar.
    kind: str

    @property
    def enabled(self) -> bool:
        """The configuration turns the probe on."""

    def job_probe(self, geometry) -> Probe:
        """The probe a contact job on ``geometry`` records
        (:class:`~roughcontact.contact.probes.Probe`;
        :class:`~roughcontact.study.records.Geometry`)."""

    def params(self) -> dict:
        """Its settings as plain values (the aggregate rule's params)."""

    def table_columns(self, rows) -> tuple[dict, dict]:
        """Columns added to a cell's aggregated table ``rows``, and their units."""

    def cell_rows(self, sweep, labels: dict) -> list[dict]:
        """A cell's rows of the sidecar, from its SI sweep (each with ``labels``)."""

    def sidecar(self, rows: list[dict]) -> dict:
        """The sidecar's entry under :attr:`kind`, of every cell's rows."""


#: Study-side probe kind -> its record of its :meth:`StudyProbe.params`.
STUDY_PROBE_KINDS = MappingProxyType({FlowSettings.kind: FlowSettings.from_params,
                                      ConductanceSettings.kind: ConductanceSettings.from_params})


def study_probes(*records: StudyProbe) -> tuple[StudyProbe, ...]:
    """The study-side records among ``records`` (the flow's
    :class:`~roughcontact.study.flow_settings.FlowSettings`, the conductance's
    :class:`~roughcontact.study.conductance_settings.ConductanceSettings`) that are on,
    in their order (the order the contact jobs record their probes in)."""
    return tuple(record for record in records if record.enabled)


def study_probe_params(records: tuple[StudyProbe, ...]) -> dict:
    """The params of study-side ``records`` by kind (the aggregate rule's)."""
    return {record.kind: record.params() for record in records}


def study_probes_from_params(params: dict) -> tuple[StudyProbe, ...]:
    """The study-side records of their :func:`study_probe_params`, in their order."""
    return tuple(STUDY_PROBE_KINDS[kind](value) for kind, value in params.items())
