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
configuration turns on.
"""

from __future__ import annotations

import json
from types import MappingProxyType
from typing import Protocol

from roughcontact.contact.probes import Probe
from roughcontact.study.flow_settings import FlowSettings
from roughcontact.transport.probe import FlowProbe, probe_from_params

__all__ = ["PROBE_KINDS", "StudyProbe", "probes_from_attrs", "study_probes"]

#: Probe kind (the attribute its settings are stored under) -> the probe of its stored
#: settings (``params()``).
PROBE_KINDS = MappingProxyType({FlowProbe.kind: probe_from_params})


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
    #: The probe the contact jobs record (:class:`~roughcontact.contact.probes.Probe`).
    probe: Probe

    def table_columns(self, rows) -> tuple[dict, dict]:
        """Columns added to a cell's aggregated table ``rows``, and their units."""

    def cell_rows(self, sweep, labels: dict) -> list[dict]:
        """A cell's rows of the sidecar, from its SI sweep (each with ``labels``)."""

    def sidecar(self, rows: list[dict]) -> dict:
        """The sidecar's entry under :attr:`kind`, of every cell's rows."""


def study_probes(flow: FlowSettings) -> tuple[StudyProbe, ...]:
    """The study-side records of the probes a study turns on: the ``flow``'s
    (:class:`~roughcontact.study.flow_settings.FlowSettings`) where it is on."""
    return (flow,) if flow.enabled else ()
