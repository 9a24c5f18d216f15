"""The study's flow through the contact gap: its settings, checks, leak rate and threshold.

The configuration's ``flow`` section (off by default) gives every contact job a
:class:`~roughcontact.transport.probe.FlowProbe` (directions, sides, face rule):
the job's sweep records the conductance, the flow factors and whether the free
space percolates at every step (:mod:`roughcontact.transport`), and stores them
in its contact file. The aggregation averages them per cell like every other
probe column (95 % bands), and adds from this module (:class:`FlowSettings`, the
flow's study-side record, :class:`~roughcontact.study.probes.StudyProbe`)

- the leak rate of the configured seal, ``Q = K W dp / (12 eta L)`` [m^3/s]
  (:meth:`~roughcontact.transport.flow.Seal.leak_rate`; linear in ``K``, so its mean
  and band are those of ``K`` scaled);
- at every level, whether the faces would open (:data:`FACES_OPEN`): the pressure drop
  exceeds the nominal contact pressure, so the fluid would lift the faces apart; the model
  does not load the faces with the fluid's pressure, so its leak rate there is that of
  faces held shut, not the seal's;
- each cell's percolation threshold (:mod:`roughcontact.transport.percolation`): the
  real area and the nominal pressure at which half the surfaces have sealed, with a
  distribution-free 95 % band.

Off, the section changes nothing: the jobs' parameters, files and tables are those
of a configuration without it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from roughcontact.study.codec import in_unit
from roughcontact.study.config import unit_slips
from roughcontact.transport.flow import FACE_RULES, Seal
from roughcontact.transport.probe import (
    BALANCE,
    CONDUCTANCE,
    CONNECTED,
    LEAK_RATE,
    NO_FLOW,
    FlowProbe,
    column_name,
    probe_from_params,
)
from roughcontact.units import MM, MPA

__all__ = ["FACES_OPEN", "FLOW_OFF", "FlowSettings", "check_flow", "flow_settings"]

#: The aggregate tables' column (with the flow on) that flags a level where the pressure
#: drop exceeds the nominal contact pressure: the fluid would lift the faces apart.
FACES_OPEN = "faces_open"

#: Plausible ranges of the seal's values (outside: almost surely a unit slip), the
#: narrower range of the values a seal has (a unit slip is guessed only where the value
#: it gives lies in it: 1e6 as a pressure drop is 1 MPa in Pa, not 1000 MPa in kPa), and
#: the units each is likely typed in by mistake with their factors to the key's unit.
PLAUSIBLE = {
    "viscosity_Pa_s": ((1e-6, 1e4), (1e-5, 1e3), (("mPa s", 1e-3),)),
    "pressure_drop_MPa": ((0.0, 1e3), (1e-3, 50.0),
                          (("Pa", 1e-6), ("kPa", 1e-3), ("bar", 0.1))),
    "seal_width_mm": ((1.0, 1e5), (1.0, 1e4), (("m", 1e3), ("um", 1e-3))),
    "seal_length_mm": ((1e-3, 1e4), (1e-2, 1e3), (("m", 1e3), ("um", 1e-3))),
}


@dataclass(frozen=True)
class FlowSettings:
    """The ``flow`` section as the study uses it: the jobs' ``probe`` and the ``seal``
    whose leak rate the aggregation reports (None with the flow off). Where the flow is
    on, the flow's study-side probe record
    (:class:`~roughcontact.study.probes.StudyProbe`, of ``kind`` "flow"): the leak rate
    in each cell's table, the percolation thresholds in the sidecar."""

    kind: ClassVar[str] = FlowProbe.kind

    probe: FlowProbe
    seal: Seal | None

    @property
    def directions(self) -> tuple[str, ...]:
        return self.probe.directions

    @property
    def enabled(self) -> bool:
        """The flow is on (a probe with directions)."""
        return bool(self.probe.directions)

    def job_probe(self, geometry) -> FlowProbe:
        """The probe a contact job records (the same on every ``geometry``)."""
        return self.probe

    def written(self) -> dict:
        """The seal's values in the configuration's units, by key (none with the flow
        off)."""
        if not self.enabled:
            return {}
        seal = self.seal
        return {"viscosity_Pa_s": seal.viscosity,
                "pressure_drop_MPa": in_unit(seal.pressure_drop, MPA),
                "seal_width_mm": in_unit(seal.width, MM),
                "seal_length_mm": in_unit(seal.length, MM)}

    def seal_text(self) -> str:
        """The fluid and the seal in words (a caption's)."""
        w = self.written()
        return (f"viscosity {w['viscosity_Pa_s']:g} Pa s through a seal "
                f"{w['seal_width_mm']:g} mm wide and {w['seal_length_mm']:g} mm long with "
                f"{w['pressure_drop_MPa']:g} MPa across it")

    def faces_open(self, nominal_pressure):
        """Whether the pressure drop exceeds each nominal contact pressure [Pa] (an array
        of bools): there the fluid, at up to the pressure drop at the inlet, would lift
        the faces apart. The model does not load the faces with the fluid's pressure, so
        its leak rate at such a level is that of faces held shut. All False with the flow
        off."""
        pressures = np.asarray(nominal_pressure, dtype=float)
        if not self.enabled:
            return np.zeros(pressures.shape, dtype=bool)
        return self.seal.pressure_drop > pressures

    def table_columns(self, rows) -> tuple[dict, dict]:
        """The leak-rate columns of a cell's aggregated ``rows`` (a table with the flow
        conductance's ``_mean``, ``_half_width`` and ``_count`` columns along each
        direction, :func:`~roughcontact.transport.probe.column_name`, and the
        ``nominal_pressure`` [Pa]): the leak rate's (``LEAK_RATE`` along each direction)
        ``_mean`` and ``_half_width`` [m^3/s] and ``_count``, then :data:`FACES_OPEN`
        (:meth:`faces_open` at each level), and their units; empty with the flow off."""
        if not self.enabled:
            return {}, {}
        columns, units = {}, {}
        for d in self.directions:
            conductance, leak = column_name(CONDUCTANCE, d), column_name(LEAK_RATE, d)
            for part in ("mean", "half_width"):
                columns[f"{leak}_{part}"] = self.seal.leak_rate(rows[f"{conductance}_{part}"])
                units[f"{leak}_{part}"] = "m^3/s"
            columns[f"{leak}_count"] = rows[f"{conductance}_count"]
            units[f"{leak}_count"] = "1"
        columns[FACES_OPEN] = self.faces_open(rows["nominal_pressure"])
        units[FACES_OPEN] = "-"
        return columns, units

    def cell_rows(self, sweep, labels: dict) -> list[dict]:
        """A cell's percolation thresholds
        (:func:`roughcontact.transport.percolation.threshold`) per flow direction of its
        SI ``sweep``: the real area fraction [-] and the nominal pressure [MPa] at which
        half its surfaces have sealed, with 95 % bands, and the steps whose flow stayed
        off balance (``unbalanced_steps``: conductance flagged, NaN;
        :mod:`roughcontact.transport.probe`), each row with the cell's ``labels``."""
        from roughcontact.transport.percolation import sealing_points, threshold

        rows = []
        for d in self.directions:
            points = sealing_points(sweep.probe_columns[column_name(CONNECTED, d)],
                                    sweep.real_area_fraction, sweep.nominal_pressure,
                                    sweep.converged)
            found = threshold(points).as_dict()
            for key in ("pressure", "pressure_low", "pressure_high"):
                found[f"{key}_MPa"] = found.pop(key) / MPA
            found["reopened_steps"] = int(np.sum(points.reopened))
            balance = sweep.probe_columns[column_name(BALANCE, d)]
            found["unbalanced_steps"] = int(np.sum(~(balance <= self.probe.balance_tol)))
            rows.append({**labels, "direction": d, **found})
        return rows

    @classmethod
    def from_params(cls, params: dict) -> FlowSettings:
        """The settings of their :meth:`params` (the aggregate rule's; empty: the flow
        off, :data:`FLOW_OFF`)."""
        if not params:
            return FLOW_OFF
        seal = Seal(pressure_drop=params["pressure_drop_Pa"], viscosity=params["viscosity_Pa_s"],
                    width=params["seal_width_m"], length=params["seal_length_m"])
        return cls(probe_from_params(params["probe"]), seal)

    def params(self) -> dict:
        """The seal's settings in SI units (the aggregation's sidecar, the aggregate rule's
        params)."""
        if not self.enabled:
            return {}
        return {"probe": self.probe.params(), "pressure_drop_Pa": self.seal.pressure_drop,
                "viscosity_Pa_s": self.seal.viscosity, "seal_width_m": self.seal.width,
                "seal_length_m": self.seal.length,
                "leak_rate": "Q = K W dp / (12 eta L) [m^3/s], K the conductance"}

    def sidecar(self, rows: list[dict]) -> dict:
        """The sidecar's entry of the flow: the seal's settings and every cell's
        percolation thresholds ``rows`` (:meth:`cell_rows`)."""
        return {**self.params(), "percolation": rows}


#: The flow off: no probe, no seal.
FLOW_OFF = FlowSettings(NO_FLOW, None)


def flow_settings(section) -> FlowSettings:
    """The :class:`FlowSettings` of a validated configuration's ``flow`` section."""
    if not section["enabled"]:
        return FLOW_OFF
    probe = FlowProbe(directions=tuple(section["directions"]), sides=section["sides"],
                      face_rule=FACE_RULES[section["face_rule"]])
    seal = Seal(pressure_drop=section["pressure_drop_MPa"] * MPA,
                viscosity=section["viscosity_Pa_s"], width=section["seal_width_mm"] * MM,
                length=section["seal_length_mm"] * MM)
    return FlowSettings(probe, seal)


def _slip(key: str, value: float, shortest: tuple[float, str] = (0.0, "")) -> str | None:
    """The message for a value of ``flow.<key>`` outside its plausible range, or None;
    ``shortest`` a lower bound [the key's unit] beyond the range's and its reason (the
    seal's length: one contact element along the flow)."""
    (low, high), (usual_low, usual_high), slips = PLAUSIBLE[key]
    floor, reason = shortest
    if max(low, floor) <= value <= high:
        return None
    guesses = unit_slips(f"flow.{key}", value, slips,
                         lambda v: max(usual_low, floor) <= v <= usual_high)
    unit = key.rsplit("_", 1)[-1] if key != "viscosity_Pa_s" else "Pa s"
    why = (f"is shorter than {reason}" if value < floor and value >= low
           else f"is outside the plausible {low:g}-{high:g} {unit}")
    return (f"flow.{key}: {value:g} {why}"
            + (f" ({'; '.join(guesses)})" if guesses else "")
            + " (plausibility_check: false accepts it)")


def _longest_element(flow: FlowSettings, spacings: dict) -> tuple[float, str]:
    """The longest contact element along a flow direction [mm] of the grids
    ``spacings`` (a grid's name -> its element (dx, dy) [m]), in words: a seal band is
    at least one element long (the patch's conductance averages the flow over many)."""
    found = [(in_unit(spacing["xy".index(d)], MM), where)
             for where, spacing in spacings.items() for d in flow.directions]
    if not found:
        return 0.0, ""
    length, where = max(found)
    return length, f"one contact element ({length:.3g} mm along the flow on {where})"


def check_flow(flow: FlowSettings, plausibility_check: bool, grids: dict,
               spacings: dict | None = None) -> list[str]:
    """The problems of the ``flow`` settings: values that are almost surely a unit slip
    (with ``plausibility_check``: outside their plausible range, and a seal shorter along
    the flow than one contact element of the grids ``spacings``, a grid's name -> its
    element (dx, dy) [m]), and contact grids (``grids``: a geometry's configuration key
    -> its (nx, ny)) too small to carry a flow (at least two elements along and across
    each direction)."""
    written = flow.written()
    problems = []
    if plausibility_check:
        shortest = _longest_element(flow, spacings or {}) if written else (0.0, "")
        problems += [message for key, value in written.items()
                     if (message := _slip(key, float(value), shortest if key ==
                                          "seal_length_mm" else (0.0, ""))) is not None]
    if written and written["pressure_drop_MPa"] == 0.0:
        problems.append("flow.pressure_drop_MPa: 0 gives no leak rate; give the inlet minus "
                        "outlet pressure [MPa] (e.g. 0.1 for 1 bar)")
    for where, (nx, ny) in grids.items() if written else ():
        if min(nx, ny) < 2:
            problems.append(f"{where}: a {nx} x {ny} contact grid cannot carry a flow (it "
                            "needs at least 2 elements along and across the flow); give it "
                            "at least 2 x 2 elements or set flow.enabled: false")
    return problems
