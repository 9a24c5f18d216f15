"""Peak memory and wall time of the flow through the gap against the grid size: the
numbers behind the flow's terms of the contact jobs' cost model
(``config/cost_model.yaml``, ``contact.flow_*``; :mod:`roughcontact.study.plan.resources`).

Each measurement runs in a fresh subprocess (one thread): a smooth random gap field on
``side x side`` elements (a Gaussian-filtered white noise, 5 % of it closed, as at the
first steps of a sweep, the costliest to solve), handed to the default
:class:`~roughcontact.transport.FlowProbe` (x and y, as a contact job records it) once for
``count`` fields, with the sides sealed (a block: band Cholesky up to 256 elements along
the flow, SuperLU beyond) or periodic (a periodic half-space: SuperLU). The peak is the
process's resident high-water mark during the probe (``/proc/self/status`` VmHWM, reset
through ``/proc/self/clear_refs`` before it) less its resident memory before: what the
flow adds to a job's peak, C libraries (SuperLU's factors, LAPACK's band) included, which
``tracemalloc`` would miss.

Writes results/benchmarks/flow_memory.md and flow_memory.csv.

Usage::

    .venv/bin/python benchmarks/bench_flow_memory.py                  # 64^2 .. 512^2
    .venv/bin/python benchmarks/bench_flow_memory.py --sides 64 128   # a quick look
"""

from __future__ import annotations

import argparse
import csv
import datetime
import json
import os
import platform
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "results" / "benchmarks"

#: The child: one measurement, printed as JSON.
CHILD = r"""
import json, sys, time
import numpy as np
from roughcontact.contact.probes import SolvedFields
from roughcontact.transport import FlowProbe

side, count, periodic = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3] == "periodic"
rng = np.random.default_rng(side)
freq = np.fft.fftfreq(side)
kernel = np.exp(-(freq[:, None] ** 2 + freq[None, :] ** 2) * (side / 16.0) ** 2)
noise = rng.standard_normal((count, side, side))
heights = np.fft.ifft2(np.fft.fft2(noise) * kernel).real
level = np.quantile(heights, 0.05, axis=(-2, -1), keepdims=True)
gap = np.maximum(heights - level, 0.0)
pressure = np.where(gap > 0.0, 0.0, 1.0)
fields = SolvedFields(pressure, gap, gap.mean(axis=(-2, -1)), (1e-4, 1e-4), periodic)
probe = FlowProbe()

def status(key):
    for line in open("/proc/self/status"):
        if line.startswith(key):
            return int(line.split()[1]) * 1024

before = status("VmRSS")
with open("/proc/self/clear_refs", "w") as refs:
    refs.write("5")  # the high-water mark starts again from the resident memory
start = time.perf_counter()
columns = probe.measure(fields)
seconds = time.perf_counter() - start
peak = status("VmHWM")
print(json.dumps({"side": side, "count": count, "sides": sys.argv[3],
                  "seconds": seconds, "peak_bytes": peak - before,
                  "open_fraction": float(np.mean(gap > 0)),
                  "connected": bool(np.all(columns["flow_connected_x"]))}))
"""


def measure(side: int, count: int, sides: str) -> dict:
    env = dict(os.environ, PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1",
               OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    out = subprocess.run([sys.executable, "-c", CHILD, str(side), str(count), sides],
                         env=env, check=True, capture_output=True, text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sides", type=int, nargs="+", default=[64, 128, 256, 512])
    parser.add_argument("--counts", type=int, nargs="+", default=[1, 8],
                        help="fields per probe call (the surfaces of a step)")
    parser.add_argument("--repeats", type=int, default=2)
    args = parser.parse_args(argv)
    rows = []
    for side in args.sides:
        for sides in ("sealed", "periodic"):
            for count in args.counts:
                if count > 1 and side > 256:
                    continue  # the per-field arrays are measured on the smaller grids
                runs = [measure(side, count, sides) for _ in range(args.repeats)]
                row = min(runs, key=lambda r: r["seconds"])
                row["peak_bytes"] = max(r["peak_bytes"] for r in runs)
                rows.append(row)
                print(json.dumps(row), flush=True)
    OUT.mkdir(parents=True, exist_ok=True)
    with (OUT / "flow_memory.csv").open("w", newline="") as table:
        writer = csv.DictWriter(table, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    lines = [
        "# Peak memory and time of the flow through the gap against the grid",
        "",
        f"{datetime.date.today()}, {platform.machine()}, one thread, 2 cores shared with "
        "other jobs (`benchmarks/bench_flow_memory.py`): the default FlowProbe (x and y) "
        "on `count` smooth random gap fields, 5 % closed; peak: resident high-water mark "
        "during the probe less the resident memory before (largest of "
        f"{args.repeats}); time: the least of {args.repeats}.",
        "",
        "| side | sides | fields | open fraction | wall [s] | per field and direction [s] "
        "| peak [MB] | peak per field [MB] |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['side']} | {r['sides']} | {r['count']} | {r['open_fraction']:.3f} "
            f"| {r['seconds']:.3f} | {r['seconds'] / (2 * r['count']):.4f} "
            f"| {r['peak_bytes'] / 1e6:.1f} | {r['peak_bytes'] / 1e6 / r['count']:.1f} |")
    (OUT / "flow_memory.md").write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
