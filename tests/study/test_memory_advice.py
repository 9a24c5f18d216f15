"""The refusal of an influence build beyond body.max_memory_gb offers only changes whose
build fits (each estimated when the message is made) and none the configuration
already has: ``operator: auto`` is not offered again once it is set."""

import re

import pytest

from roughcontact.study.config import validated
from roughcontact.study.plan.cells import study_plan
from roughcontact.study.plan.checks import ConfigProblems
from roughcontact.study.settings import Study


def config(grid, **body) -> dict:
    return validated({
        "surfaces": {"grid": [grid, grid], "size_mm": [4.8, 4.8], "count": 3},
        "figures": {}, "reports": {},
        "body": {"mesh": "refined", "solver": "superlu", **body},
        "sweeps": {"s": {"sigma_um": 24.5, "b_mm": 0.5, "pressure_MPa": [0.1, 3.0]}}})


def options(cfg) -> list[str]:
    with pytest.raises(ConfigProblems) as raised:
        study_plan(Study.from_config(cfg))
    (problem,) = raised.value.problems
    return problem.split("Options: ")[1].split("; ")


def followed(cfg, option):
    """``cfg`` with a ``body.key: value`` option set (the value its first word)."""
    key, value = re.match(r"body\.(\w+): (\S+)", option).groups()
    cfg["body"][key] = float(value) if key == "max_memory_gb" else value
    return validated(cfg)


def test_a_dense_build_beyond_the_limit_is_offered_auto_where_that_fits():
    cfg = config(100, operator="dense", max_memory_gb=2.0)
    offered = options(cfg)
    assert offered[0].startswith("body.operator: auto (matrix-free above 64 x 64 elements: "
                                 "about 1.59 GB here)")
    plan = study_plan(Study.from_config(followed(cfg, offered[0])))  # the advice, followed
    assert [g.operator.value for g in plan.geometries.values()] == ["hybrid", "halfspace"]


def test_auto_is_not_offered_again_and_every_option_offered_plans():
    # 64 x 64: auto plans the dense matrix, which SuperLU's estimate puts at 2.51 GB
    cfg = config(64, operator="auto", max_memory_gb=1.0)
    offered = options(cfg)
    assert not any("operator" in option for option in offered)
    assert "body.max_memory_gb: 2.52 or more (now 1, on a machine with that memory)" in offered
    for option in offered:
        if option.startswith("body."):
            study_plan(Study.from_config(
                    followed(config(64, operator="auto", max_memory_gb=1.0), option)))
    # where auto does not fit either, it is not offered to a dense build
    assert not any("operator" in o for o in options(config(100, operator="dense",
                                                           max_memory_gb=1.0)))
