"""Will the faces open? A study whose every level lies below the flow's pressure drop is
refused before any job, naming the keys, with advice that plans when followed; one of
which only some levels lie below it plans, with a warning naming them."""

import copy
import logging
import re

import pytest

from roughcontact.study.config import validated
from roughcontact.study.plan.cells import study_plan
from roughcontact.study.plan.checks import ConfigProblems
from roughcontact.study.settings import Study

STUDY = {"sigma_um": 10.0, "b_mm": 0.5, "pressure_MPa": [0.1, 2.0]}
BASE = {"study_seed": 0,
        "surfaces": {"grid": [8, 8], "size_mm": [1.2, 1.2], "count": 2},
        "body": {"thickness_mm": 2.0, "E_MPa": 500.0},
        "contact": {"pressure_levels": 6},
        "figures": {"fig07": STUDY}}


def config(drop_MPa: float, enabled: bool = True, **sections) -> dict:
    raw = copy.deepcopy(BASE)
    raw["flow"] = {"enabled": enabled, "pressure_drop_MPa": drop_MPa}
    for section, values in sections.items():
        raw.setdefault(section, {}).update(values)
    return raw


def plan(raw: dict):
    return study_plan(Study.from_config(validated(copy.deepcopy(raw))))


def follow(raw: dict, advice: str) -> dict:
    """The configuration with one piece of advice (``<key path>: <YAML value>``) applied."""
    key, value = advice.split(": ", 1)
    *path, last = key.split(".")
    followed = copy.deepcopy(raw)
    entry = followed
    for part in path:
        entry = entry[part]
    entry[last] = ([float(v) for v in value.strip("[]").split(", ")] if value.startswith("[")
                   else float(value))
    return followed


def refusal(raw: dict) -> str:
    with pytest.raises(ConfigProblems) as caught:
        plan(raw)
    return str(caught.value)


def test_a_sweep_wholly_below_the_pressure_drop_is_refused_and_each_advice_plans():
    raw = config(5.0)  # 5 MPa across the seal, contact pressures 0.1-2 MPa
    message = refusal(raw)
    assert "no job was started" in message
    assert ("figures.fig07.pressure_MPa: every level of [0.1, 2] MPa lies below "
            "flow.pressure_drop_MPa = 5 MPa") in message
    advice = re.findall(r"((?:figures\.fig07\.pressure_MPa|flow\.pressure_drop_MPa): "
                        r"(?:\[[^\]]+\]|[\d.e+-]+))", message.split("Fix:")[1])
    assert advice == ["figures.fig07.pressure_MPa: [0.1, 50]", "flow.pressure_drop_MPa: 0.2"]
    for piece in advice:  # each followed on its own: the plan passes (levels below: warned)
        assert plan(follow(raw, piece)).cells["fig07"]


def test_the_advised_range_stays_below_the_hardness():
    raw = config(5.0, body={"hardness_MPa": 20.0})
    message = refusal(raw)
    assert "figures.fig07.pressure_MPa: [0.1, 20]" in message  # not 50: above H
    assert plan(follow(raw, "figures.fig07.pressure_MPa: [0.1, 20]")).cells["fig07"]


def test_a_sweep_partly_below_the_drop_plans_with_a_warning_naming_its_levels(caplog):
    # levels 0.1 * 20^(k/5) MPa: 0.1, 0.182, 0.331, 0.603, 1.1, 2; below 0.5 MPa: three
    with caplog.at_level(logging.WARNING):
        plan(config(0.5))
    (warning,) = [r.getMessage() for r in caplog.records if "faces" in r.getMessage()]
    assert warning.startswith("figures.fig07.pressure_MPa: 3 of its 6 levels (0.1-0.331 MPa) "
                              "lie below flow.pressure_drop_MPa = 0.5 MPa")
    assert "faces_open" in warning


def test_no_check_with_the_flow_off_or_every_level_above_the_drop(caplog):
    with caplog.at_level(logging.WARNING):
        plan(config(5.0, enabled=False))
        plan(config(0.05))
    assert not [r for r in caplog.records if "faces" in r.getMessage()]
