"""Expected sample moments of the filter generator: the paper's method against the calibrated one.

For each window -- the five of issue 16's table (exponential ACF, b = 1 mm,
periodic) and every synthetic cell of the default config -- generates
``--count`` surfaces per method with seeds independent of the calibration's
(``derive_seeds(1602, "verify|<window>", count)``), computes their sample
skewness and kurtosis here with ``scipy.stats`` (1/N normalisation, not the
library's ``height_stats``), and reports the mean, its standard error, the
median and the error of the mean against the target. A window passes when the
mean is within 0.5 % of the target (kurtosis relative; skewness relative to
max(1, |Sk|)).

- ``paper``: Eq 12-13 as the paper uses them (targets = the process's moments);
- ``filter``: the white noise calibrated so that the expected sample moments
  are the targets (:func:`roughcontact.surfaces.calibration.calibrate_filter`);
  ``cal_s`` is the calibration's wall time (one thread) and ``process`` the
  moments it feeds to Eq 12-13.

Usage::

    .venv/bin/python benchmarks/bench_unbiased.py                 # 20000 each, ~4 min
    .venv/bin/python benchmarks/bench_unbiased.py --count 2000 --tag quick

Writes ``results/benchmarks/unbiased[_<tag>].csv`` and ``.md``.
"""

from __future__ import annotations

import os

for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_name] = "1"

import argparse  # noqa: E402
import platform  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import yaml  # noqa: E402
from scipy import stats  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from roughcontact.study.config import apply_schema  # noqa: E402
from roughcontact.study.plan.cells import study_plan  # noqa: E402
from roughcontact.study.settings import Study  # noqa: E402
from roughcontact.surfaces import calibration, synthetic  # noqa: E402
from roughcontact.surfaces.spec import SurfaceSpec  # noqa: E402

MM = 1e-3
TOLERANCE = 5e-3
ISSUE_WINDOWS = [  # (grid, size [mm], Sk, Ku)
    (60, 9.0, 0.0, 4.5), (60, 9.0, -0.8, 4.0), (60, 9.0, 2.0, 10.0),
    (30, 4.5, 0.0, 3.0), (30, 4.5, 0.0, 4.5),
]


def windows() -> dict[str, tuple[str, SurfaceSpec]]:
    out = {}
    for grid, size, skew, kurt in ISSUE_WINDOWS:
        spec = SurfaceSpec(grid=grid, size=size * MM, corr_length=MM,
                                     skew=skew, kurt=kurt)
        out[f"{grid}x{grid} over {size:g} mm, b 1 mm, ({skew:g}, {kurt:g})"] = ("issue", spec)
    config = apply_schema(yaml.safe_load((ROOT / "config" / "config.yaml").read_text()))
    for cell in study_plan(Study.from_config(config)).surfaces.values():
        params = cell.params()
        if params["method"] != "filter":
            continue
        spec = cell.spec()
        name = (f"{spec.grid[0]}x{spec.grid[1]} over {params['size_mm'][0]:g} mm, "
                f"b {params['b_mm'][0]:g} mm, ({spec.skew:g}, {spec.kurt:g})")
        out.setdefault(name, ("config", spec))
        if out[name][0] == "issue":
            out[name] = ("issue + config", spec)
    return out


def measure(name: str, source: str, spec: SurfaceSpec, count: int) -> list[dict]:
    seeds = synthetic.derive_seeds(1602, f"verify|{name}", count)
    rows = []
    for method in ("paper", "filter"):
        extra = {}
        if method == "filter":
            start = time.perf_counter()
            cal = calibration.calibrate_filter(spec)
            extra = {"cal_s": time.perf_counter() - start, "cal_samples": cal.samples,
                     "process": f"({cal.skew:.4f}, {cal.kurt:.4f})"}
        skews, kurts = [], []
        for chunk in np.array_split(seeds, max(1, count // 2000)):
            z = synthetic.generate_many(spec, chunk, method=method).reshape(len(chunk), -1)
            skews.append(stats.skew(z, axis=1))
            kurts.append(stats.kurtosis(z, axis=1, fisher=False))
        sk, ku = np.concatenate(skews), np.concatenate(kurts)
        sk_err = (sk.mean() - spec.skew) / max(1.0, abs(spec.skew))
        ku_err = (ku.mean() - spec.kurt) / spec.kurt
        rows.append({
            "window": name, "source": source, "method": method, "count": count,
            "skew_mean": sk.mean(), "skew_se": sk.std(ddof=1) / np.sqrt(count),
            "kurt_mean": ku.mean(), "kurt_se": ku.std(ddof=1) / np.sqrt(count),
            "kurt_median": float(np.median(ku)),
            "skew_err": sk_err, "kurt_err": ku_err,
            "within_0.5%": bool(abs(sk_err) <= TOLERANCE and abs(ku_err) <= TOLERANCE),
            **extra,
        })
        print(f"{name:45s} {method:6s} Sk {sk.mean():+.4f} ({rows[-1]['skew_se']:.4f}) "
              f"Ku {ku.mean():.4f} ({rows[-1]['kurt_se']:.4f}) err {100 * ku_err:+.2f} %",
              flush=True)
    return rows


def markdown(table: pd.DataFrame, count: int) -> str:
    lines = [
        f"# Expected sample moments: paper's filter against the calibrated filter ({count} "
        "surfaces each)", "",
        f"{platform.machine()}, numpy {np.__version__}, one thread. Seeds independent of the "
        "calibration's. Error: of the mean against the target (Ku relative, Sk relative to "
        "max(1, |Sk|)); pass: both within 0.5 %.", "",
        "| window | method | mean Sk (SE) | mean Ku (SE) | median Ku | Ku error | pass "
        "| process (Sk, Ku) | calibration |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for _, r in table.iterrows():
        cal = (f"{r['cal_s']:.2f} s, {int(r['cal_samples'])} surfaces"
               if r["method"] == "filter" else "")
        lines.append(
            f"| {r['window']} | {r['method']} | {r['skew_mean']:+.4f} ({r['skew_se']:.4f}) | "
            f"{r['kurt_mean']:.4f} ({r['kurt_se']:.4f}) | {r['kurt_median']:.3f} | "
            f"{100 * r['kurt_err']:+.2f} % | {'yes' if r['within_0.5%'] else 'NO'} | "
            f"{r.get('process') if r['method'] == 'filter' else '= target'} | {cal} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=20000, help="surfaces per window and method")
    parser.add_argument("--tag", default="", help="suffix of the output files")
    args = parser.parse_args(argv)
    rows = []
    for name, (source, spec) in windows().items():
        rows += measure(name, source, spec, args.count)
    table = pd.DataFrame(rows)
    out = ROOT / "results" / "benchmarks"
    out.mkdir(parents=True, exist_ok=True)
    stem = "unbiased" + (f"_{args.tag}" if args.tag else "")
    table.to_csv(out / f"{stem}.csv", index=False)
    (out / f"{stem}.md").write_text(markdown(table, args.count))
    print(f"wrote {out / stem}.csv and .md")
    failed = table[(table["method"] == "filter") & ~table["within_0.5%"]]
    return 1 if len(failed) else 0


if __name__ == "__main__":
    sys.exit(main())
