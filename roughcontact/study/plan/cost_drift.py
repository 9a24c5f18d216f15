"""The cost model against a run's benchmarks: predicted and measured time and memory.

Check the model (:mod:`roughcontact.study.plan.resources`) against a run::

    python -m roughcontact.study.plan.cost_drift --compare <results>/benchmarks/rules \\
        --configfile config/quick.yaml
"""

from __future__ import annotations

import argparse
import csv
import math
import os
import sys
from pathlib import Path

from roughcontact.study.plan.cells import study_plan
from roughcontact.study.plan.resources import (
    contact_mem_mb,
    contact_seconds,
    cycle_seconds,
    influence_mem_mb,
    influence_seconds,
    surfaces_mem_mb,
    surfaces_seconds,
    thermal_mem_mb,
    thermal_seconds,
)
from roughcontact.study.settings import load_study

__all__ = ["compare", "main", "predictions"]


def predictions(plan) -> dict[str, dict[str, tuple[float, int]]]:
    """Rule -> wildcard -> (runtime [s] before the margin, memory [MB]) of the
    contact, influence, surfaces, thermal influence and cycle jobs of a study's
    :func:`~roughcontact.study.plan.cells.study_plan`."""
    settings, build = plan.contact, plan.build
    return {
        "contact": {key: (contact_seconds(job, settings, build),
                            contact_mem_mb(job, settings, build))
                    for key, job in plan.jobs.items()},
        "influence": {k: (influence_seconds(g, build), influence_mem_mb(g, build))
                      for k, g in plan.geometries.items()},
        "surfaces": {k: (surfaces_seconds(c), surfaces_mem_mb(c))
                     for k, c in plan.surfaces.items()},
        "thermal_influence": {k: (thermal_seconds(t, build), thermal_mem_mb(t, build))
                              for k, t in plan.thermal.items()},
        "cycles": {key: (cycle_seconds(cycle, settings, build),
                         contact_mem_mb(cycle.contact, settings, build))
                   for key, cycle in plan.cycles.items()},
    }


def _number(text: str) -> float:
    """A benchmark column's value ("NA" or "-" when Snakemake could not measure it: nan)."""
    try:
        return float(text)
    except ValueError:
        return math.nan


def _ratio(predicted: float, measured: float) -> float:
    """Predicted over measured (nan when nothing was measured)."""
    return predicted / measured if measured > 0 else math.nan


def compare(benchmarks: str | os.PathLike, plan) -> list[str]:
    """Lines of a table of predicted against measured time [s] and memory [MB]
    of every job benchmarked under ``benchmarks`` (``<rule>/<wildcard>.tsv``
    as Snakemake writes them) that a study's ``plan`` asks for."""
    lines = [f"{'rule':17} {'s pred':>9} {'s meas':>9} {'ratio':>6} "
             f"{'MB pred':>8} {'MB meas':>8} {'ratio':>6}  job"]
    for rule, predicted in predictions(plan).items():
        for path in sorted((Path(benchmarks) / rule).glob("*.tsv")):
            if path.stem not in predicted:
                continue
            with path.open() as table:
                measured = next(csv.DictReader(table, delimiter="\t"))
            seconds, mem_mb = predicted[path.stem]
            s, rss = _number(measured["s"]), _number(measured["max_rss"])
            lines.append(f"{rule:17} {seconds:9.2f} {s:9.2f} {_ratio(seconds, s):6.2f} "
                         f"{mem_mb:8d} {rss:8.1f} {_ratio(mem_mb, rss):6.2f}  {path.stem}")
    return lines


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--compare", required=True,
                        help="the benchmarks/rules folder of a run's results")
    parser.add_argument("--configfile", default="config/config.yaml")
    args = parser.parse_args(argv)
    study = load_study(args.configfile)  # fills the schema's defaults, as Snakemake does
    print("\n".join(compare(args.compare, study_plan(study))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
