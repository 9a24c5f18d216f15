"""Every input error of a counter body is refused before any job, naming its key.

The counter body (Eq 17-18) gets the checks of the first body, by the same code: the
schema's defaults, the plausibility (unit slips) of E, sigma and thickness, the
block's geometry limits, the surface's window, the measured import; a list axis
refuses duplicates. Each refusal names the configuration key (the section's
``counterface.body.E_MPa`` or a study's ``sweeps.pad.counterface[1].surface.sigma_um``)
and, where it gives advice, the advice is followed here and the plan then passes.
"""

import copy

import pytest

from roughcontact.study.cells import study_plan
from roughcontact.study.config import ConfigError, validated
from roughcontact.study.studies import counterface_entries

SWEEP = {"sigma_um": 24.5, "b_mm": 0.5, "pressure_MPa": [0.1, 3.0], "count": 3}
BASE = {"study_seed": 3, "surfaces": {"grid": [16, 16], "size_mm": [2.4, 2.4]},
        "figures": {}, "reports": {}}


def raw(**sweep) -> dict:
    return {**copy.deepcopy(BASE), "sweeps": {"pad": {**SWEEP, **sweep}}}


def config(**sweep) -> dict:
    return validated(raw(**sweep))


def test_the_schema_fills_the_static_defaults_and_one_function_the_body_sections():
    entry = config(counterface={"surface": {"sigma_um": 1.0},
                                "body": {"kind": "block", "E_MPa": 511.0}})
    written = entry["sweeps"]["pad"]["counterface"]
    assert written["surface"] == {"sigma_um": 1.0, "skew": 0.0, "kurt": 3.0}
    assert written["body"] == {"kind": "block", "E_MPa": 511.0, "operator": "dense"}
    (resolved,) = counterface_entries(entry, "pad")
    body = entry["body"]
    assert resolved.body == {**written["body"], "nu": body["nu"], "base": body["base"],
                             "thickness_mm": body["thickness_mm"], "mesh": body["mesh"]}
    assert resolved.surface == {**written["surface"], "b_mm": None}  # the first surface's
    assert (resolved.surface_key, resolved.body_key) == ("sweeps.pad.counterface.surface",
                                                        "sweeps.pad.counterface.body")
    # a half-space takes no block default; a smooth rigid section none at all
    half = config(counterface={"body": {"kind": "halfspace", "E_MPa": 2e5, "nu": 0.3}})
    assert half["sweeps"]["pad"]["counterface"]["body"] == {"kind": "halfspace",
                                                             "E_MPa": 2e5, "nu": 0.3}
    assert half["counterface"]["surface"] == "smooth" and half["counterface"]["body"] == "rigid"
    (entry,) = counterface_entries(half, "pad")
    assert (entry.surface_key, entry.body_key) == ("counterface.surface",
                                                   "sweeps.pad.counterface.body")
    # the plan is the one of the values written out
    explicit = config(counterface={"surface": {"sigma_um": 1.0, "skew": 0.0, "kurt": 3.0},
                                   "body": {"kind": "block", "E_MPa": 511.0, "nu": 0.0,
                                            "thickness_mm": 10.0, "base": "clamped",
                                            "mesh": "paper", "operator": "dense"}})
    defaults = config(counterface={"surface": {"sigma_um": 1.0},
                                   "body": {"kind": "block", "E_MPa": 511.0}})
    assert list(study_plan(explicit).jobs) == list(study_plan(defaults).jobs)


@pytest.mark.parametrize(("counterface", "key"), [
    ({"surface": {"sigma_um": "1.5"}}, "sweeps.pad.counterface.surface.sigma_um"),
    ([{"body": "rigid"}, {"surface": {"sigma_um": "1.5"}}],
     "sweeps.pad.counterface[1].surface.sigma_um"),
])
def test_a_counter_value_of_the_wrong_type_names_its_key_and_that_a_number_is_expected(
        counterface, key):
    with pytest.raises(ConfigError) as raised:
        config(counterface=counterface)
    (line,) = [t.strip() for t in str(raised.value).splitlines() if t.startswith("  ")]
    assert line == f'{key}: "1.5" is not a number (text: write 1.5 without quotes)'
    # the section's own, and the advice followed
    with pytest.raises(ConfigError, match=r'\n  counterface.surface.sigma_um: "1.5" is not a '
                                          r"number \(text: write 1.5 without quotes\)\n"):
        validated({**raw(), "counterface": {"surface": {"sigma_um": "1.5"}}})
    fixed = copy.deepcopy(counterface)
    (fixed if isinstance(fixed, dict) else fixed[1])["surface"]["sigma_um"] = 1.5
    study_plan(config(counterface=fixed))
