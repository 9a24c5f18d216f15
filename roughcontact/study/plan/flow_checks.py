"""Plan-time checks of the flow against the studies it is solved with: will the faces open?

The model presses the faces together with the nominal contact pressure P alone: the
fluid's pressure, up to the pressure drop dp at the inlet, does not load them. Where
dp exceeds P, the fluid would lift the faces apart, and the leak rate the study reports
there is that of faces held shut, not the seal's
(:meth:`~roughcontact.study.flow_settings.FlowSettings.faces_open`, the tables'
``faces_open`` column). A study whose every level lies below the drop has no answer
for the seal: refused, naming the keys. A study of which only some levels lie below
it is planned, with a warning: its levels above the drop are the seal's answers (and
the levels below show how the leak rate falls towards them), and the tables, the
leakage figure and its caption mark the levels below.
"""

from __future__ import annotations

import logging

from roughcontact.contact.aggregate import pressure_axis
from roughcontact.study.settings import Study
from roughcontact.units import MPA

__all__ = ["check_open_faces", "open_levels_MPa"]

log = logging.getLogger(__name__)


def open_levels_MPa(study: Study, p_min: float, p_max: float) -> list[float]:
    """The nominal-pressure levels [MPa] of a range ``p_min``-``p_max`` [MPa] (the
    study's ``contact.pressure_levels``, as the aggregation spaces them) at which the
    pressure drop exceeds the contact pressure (the faces would open); none with the
    flow off."""
    levels = pressure_axis(p_min * MPA, p_max * MPA, study.contact.pressure_levels)
    return [float(f"{p / MPA:.12g}") for p in levels[study.flow.faces_open(levels)]]


def _sources(study: Study, names) -> list[str]:
    """The studies whose cells ``names`` solve, once each, in their order."""
    return list(dict.fromkeys(study.source_name(name) for name in names))


def _refusal(where: str, p_min: float, p_max: float, drop: float, hardness) -> str:
    """The message for a study whose every level lies below the pressure drop ``drop``
    [MPa]; ``hardness`` [MPa] bounds the advised range (None: no bound)."""
    fixes = []
    top = 10.0 * drop if hardness is None else min(10.0 * drop, hardness)
    if top > drop:
        fixes.append(f"sweep to contact pressures above the drop, {where}.pressure_MPa: "
                     f"[{p_min:g}, {top:g}]")
    fixes.append(f"or give the smaller drop the seal holds, flow.pressure_drop_MPa: "
                 f"{p_max / 10.0:g}")
    return (f"{where}.pressure_MPa: every level of [{p_min:g}, {p_max:g}] MPa lies below "
            f"flow.pressure_drop_MPa = {drop:g} MPa, so at every level the fluid would lift "
            f"the faces apart (the model does not load the faces with the fluid's pressure: "
            f"its leak rates there would be those of faces held shut). Fix: "
            + "; ".join(fixes))


def check_open_faces(study: Study, names) -> list[str]:
    """Messages for the contact studies ``names`` (their sources, once each) whose every
    nominal-pressure level lies below the flow's pressure drop; a warning (logged) for
    each whose lower levels do. None with the flow off."""
    if not study.flow.enabled:
        return []
    drop = study.flow.written()["pressure_drop_MPa"]
    problems = []
    for name in _sources(study, names):
        section = study.section(name)
        p_min, p_max = (float(p) for p in section.pressure_MPa)
        if not 0.0 < p_min < p_max:
            continue  # check_studies refuses the range
        opened = open_levels_MPa(study, p_min, p_max)
        if len(opened) == study.contact.pressure_levels:
            hardness = section.hardness_MPa
            lowest = None if hardness is None else min(
                hardness if isinstance(hardness, list) else [hardness])
            problems.append(_refusal(section.where, p_min, p_max, drop, lowest))
        elif opened:
            log.warning("%s.pressure_MPa: %d of its %d levels (%.3g-%.3g MPa) lie below "
                        "flow.pressure_drop_MPa = %g MPa: there the fluid would lift the "
                        "faces apart (the model does not load them with it); their rows "
                        "are marked faces_open in the tables and on the leakage figure",
                        section.where, len(opened), study.contact.pressure_levels,
                        opened[0], opened[-1], drop)
    return problems
