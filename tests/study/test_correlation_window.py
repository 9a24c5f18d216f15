"""A generated surface shorter than two correlation lengths is refused when the plan is made.

b <= L / 2 along each axis (:data:`~roughcontact.study.plan.checks.MAX_CORRELATION_FRACTION`):
the message names the study's b_mm and the size key the surface takes its side from
(surfaces.size_mm, or the study's own size_mm), and each fix it offers plans.
"""

import copy
import re

import pytest
import yaml

from roughcontact.study.config import validated
from roughcontact.study.plan.cells import study_plan
from roughcontact.study.plan.checks import ConfigProblems
from roughcontact.study.settings import Study

#: 12 x 12 elements over the paper's 9 mm (0.75 mm spacing) and the paper's generator (no
#: calibration when the plan is made): each plan takes a fraction of a second.
BASE = {"study_seed": 0, "surfaces": {"grid": 12, "size_mm": 9.0, "count": 2, "method": "paper"},
        "figures": {}, "sweeps": {"long": {"sigma_um": 24.5, "b_mm": 20.0,
                                           "pressure_MPa": [0.1, 5.0]}}}


def refusal(raw: dict) -> str:
    with pytest.raises(ConfigProblems) as raised:
        study_plan(Study.from_config(validated(raw)))
    (problem,) = raised.value.problems
    return problem


def follow(raw: dict, fixes: str) -> list[dict]:
    """``raw`` with each fix of a message ('key: value' joined by '; or ' after 'Fix: ',
    one or two keys each, 'with' between them) applied literally."""
    configs = []
    for fix in fixes.split("; or "):
        changed = copy.deepcopy(raw)
        for change in fix.removeprefix("a larger surface, ").split(" with "):
            path, text = change.split(": ", 1)
            value = re.match(r"\[[^]]*\]|\S+", text).group()
            *parents, key = path.split(".")
            section = changed
            for name in parents:
                section = section[name]
            section[key] = yaml.safe_load(value)  # a number or a list, as written
        configs.append(changed)
    return configs


def test_a_correlation_length_longer_than_half_the_surface_is_refused_and_each_fix_plans():
    problem = refusal(BASE)
    assert problem.startswith("sweeps.long: b_mm = 20 is longer than half the surface, "
                              "surfaces.size_mm = 9 (L / 2 = 4.5 mm): fewer than two "
                              "correlation lengths fit in it")
    fixes = problem.split("Fix: ")[1]
    assert fixes == ("sweeps.long.b_mm: 4.5 or shorter; or a larger surface, "
                     "surfaces.size_mm: 40 with surfaces.grid: 53 (the same spacing)")
    for fixed in follow(BASE, fixes.replace(" or shorter", "")):
        assert study_plan(Study.from_config(validated(fixed))).jobs
    at_bound = copy.deepcopy(BASE)
    at_bound["sweeps"]["long"]["b_mm"] = 4.5  # b = L / 2 exactly
    assert study_plan(Study.from_config(validated(at_bound))).jobs


def test_a_studys_own_size_is_named_and_only_the_short_side_refused():
    raw = copy.deepcopy(BASE)
    raw["sweeps"]["long"].update(b_mm=[1.0, 3.0], size_mm=[9.0, 4.5])
    problem = refusal(raw)  # one cell of four: b 3 mm on 4.5 mm
    assert problem.startswith("sweeps.long: b_mm = 3 is longer than half the surface, "
                              "sweeps.long.size_mm = 4.5 (L / 2 = 2.25 mm)")
    assert problem.split("Fix: ")[1] == (
        "sweeps.long.b_mm: 2.25 or shorter in place of 3; or a larger surface, "
        "sweeps.long.size_mm: 6 in place of 4.5 (8 x 8 elements at the surfaces' spacing)")
    for value in ({"b_mm": [1.0, 2.25]}, {"size_mm": [9.0, 6.0]}):
        raw["sweeps"]["long"].update({"b_mm": [1.0, 3.0], "size_mm": [9.0, 4.5], **value})
        assert study_plan(Study.from_config(validated(raw))).jobs


def test_fig04_and_its_anisotropic_lengths_on_a_rectangle():
    raw = {"study_seed": 0, "surfaces": {"grid": [12, 6], "size_mm": [9.0, 4.5], "count": 2},
           "figures": {"fig04": {"sigma_um": 40.0, "b_mm": [1.0, 6.0], "moments": [[0, 3]]},
                       "fig05": {}}}
    problem = refusal(raw)  # once: Fig 5 draws Fig 4's cells
    assert problem.startswith("figures.fig04: b_mm = [1, 6] is longer than half the surface, "
                              "surfaces.size_mm = [9, 4.5] (L / 2 = [4.5, 2.25] mm)")
    fixes = problem.split("Fix: ")[1]
    assert fixes == ("figures.fig04.b_mm: [1, 2.25] or shorter; or a larger surface, "
                     "surfaces.size_mm: [9, 12] with surfaces.grid: [12, 16] (the same "
                     "spacing)")
    for fixed in follow(raw, fixes.replace(" or shorter", "")):
        assert study_plan(Study.from_config(validated(fixed))).figure_surfaces["fig05"]


def test_a_length_that_only_labels_a_spectrum_is_not_judged():
    raw = copy.deepcopy(BASE)
    raw["sweeps"]["long"]["spectrum"] = {"kind": "self-affine", "hurst": 0.8,
                                         "rolloff_mm": 3.0, "cutoff_mm": 1.5}
    assert study_plan(Study.from_config(validated(raw))).jobs
