"""A study cell on the finite block with the hybrid operator: the library before and after.

The cell of ``config/large.yaml``: the paper's block (9 mm x 9 mm x 10 mm,
E 511 MPa, nu 0, clamped base), the hybrid operator (Love's half-space by
FFT plus the finite-body correction of a 64 x 64 "refined" finite-element
model) on a ``--grid`` x ``--grid`` contact grid, ``--surfaces`` Gaussian
surfaces (exponential ACF, b 1 mm, from ``bench_contact.gaussian_surfaces``,
seed 20061, heights in units of sigma = 24.5 um) swept over ``--steps``
approaches up to P L / (E sigma) of 5 MPa by
:func:`roughcontact.contact.cell.sweep_cell` (tol 1e-8, precision "mixed",
tangent stiffness at every step), as the study's contact job runs it.

Variants ``TREE:METHOD``: ``before`` is the library at ``--before`` (a git
revision, default ``e109424``: pcg one surface at a time), ``after`` the
working tree or, with ``--after REV``, the library at that revision (so
that edits made while the benchmark runs do not enter it); the method is
``pcg`` or ``cg``. Every run is a fresh Python
process (``PYTHONPATH`` set to its tree, one BLAS thread) that times the
sweep alone (CPU ``time.process_time``; the finite-element model is built
once, before, and passed to every run). Rounds alternate the variants (each
round starts one variant further on); the minimum over ``--repeats`` rounds
is reported, with every run's time. Results are compared with the first
variant's: contact fraction, mean pressure, peak pressure and k_P at every
approach of every surface (largest relative difference, and the number of
(surface, step) pairs whose contact fraction differs).

Writes ``results/benchmarks/hybrid_cell_<grid>.csv`` and ``.md``; the
``cell_60x30_min`` column scales the CPU time to a cell of 60 surfaces x 30
steps (linear in the surfaces).

Usage (on a shared machine, at lower priority)::

    nice -n 5 .venv/bin/python benchmarks/bench_hybrid_cell.py --grid 256 --surfaces 20
    nice -n 5 .venv/bin/python benchmarks/bench_hybrid_cell.py --grid 1024 --surfaces 4 \\
        --repeats 1 --variants after:pcg
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "results" / "benchmarks"
E = 5.11e8  # Young's modulus [Pa]
SIZE = 9e-3  # block side [m]
THICKNESS = 10e-3  # [m]
SIGMA = 24.5e-6  # rms roughness [m]
END_PRESSURE = 5e6  # nominal pressure at the last approach [Pa]
SEED = 20061
#: Per-step arrays compared between variants.
COMPARED = ("real_area_fraction", "nominal_pressure", "max_pressure", "normalized_stiffness")
THREADS = {name: "1" for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS",
                                   "MKL_NUM_THREADS")}


def geometry(grid: int):
    """The block with a ``grid`` x ``grid`` contact grid ("refined" coarse model)."""
    from roughcontact.elasticity.influence import BlockGeometry

    return BlockGeometry(size=(SIZE, SIZE), thickness=THICKNESS, grid=(grid, grid), E=E,
                         nu=0.0, mesh="refined")


def build_correction(grid: int, path: Path) -> float:
    """The finite-body correction of the block (its 64 x 64 finite-element model) saved
    to ``path``; the CPU seconds of the build."""
    from roughcontact.elasticity.operators import block_operator

    start = time.process_time()
    operator = block_operator(geometry(grid))
    np.savez(path, correction=operator.correction, coarse_grid=operator.coarse_grid)
    return time.process_time() - start


def worker(spec: dict) -> None:
    """One timed sweep in this process (its ``roughcontact`` is the variant's tree)."""
    from roughcontact.contact import cell
    from roughcontact.elasticity.operators import BlockOperator

    sys.path.insert(0, str(Path(spec["tree"]) / "benchmarks"))  # the tree's own helpers
    from bench_contact import gaussian_surfaces

    grid = spec["grid"]
    stored = np.load(spec["correction"])
    operator = BlockOperator(grid=(grid, grid), size=(SIZE, SIZE), nu=0.0,
                             correction=stored["correction"],
                             coarse_grid=tuple(int(g) for g in stored["coarse_grid"]))
    heights = gaussian_surfaces(spec["surfaces"], grid, SIZE, seed=SEED)
    heights /= heights.std(axis=(1, 2), keepdims=True)
    end = cell.nondim_pressure(END_PRESSURE, thickness=THICKNESS, E=E, sigma=SIGMA)
    cpu, wall = time.process_time(), time.perf_counter()
    result = cell.sweep_cell(operator, heights, geometry(grid), end, spec["steps"],
                             options=cell.SWEEP_OPTIONS.with_(method=spec["method"], tol=1e-8,
                                                             precision="mixed", profile=False))
    cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
    np.savez(spec["arrays"], **{name: getattr(result, name) for name in
                                (*COMPARED, "iterations", "matvecs", "converged")})
    print(json.dumps(dict(
        cpu_s=cpu, wall_s=wall, iterations=int(result.iterations.sum()),
        matvecs=int(result.matvecs.sum()), converged=bool(result.converged.all()),
        stiffness_converged=bool(result.stiffness_converged.all()),
        last_contact=float(result.real_area_fraction[:, -1].mean()),
        peak_rss_MB=peak_resident() / 1e6)))


def peak_resident() -> float:
    """Peak resident memory of this process [bytes] (``VmHWM``; unlike ``ru_maxrss`` it
    does not inherit the parent's peak across the exec)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return float(line.split()[1]) * 1024.0
    return float("nan")


def checkout(revision: str, target: Path) -> Path:
    """The library and the benchmark helpers at ``revision``, extracted under ``target``."""
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", revision, "roughcontact",
                              "benchmarks/bench_contact.py"], check=True, capture_output=True)
    target.mkdir(parents=True, exist_ok=True)
    subprocess.run(["tar", "-x", "-C", str(target)], input=archive.stdout, check=True)
    return target


def run_variant(tree: Path, spec: dict) -> dict:
    """One sweep in a fresh process with ``tree`` first on its path."""
    env = dict(os.environ, PYTHONPATH=str(tree), **THREADS)
    done = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--worker",
                           json.dumps(spec)], env=env, check=True, capture_output=True,
                          text=True, cwd=str(tree))
    return json.loads(done.stdout.strip().splitlines()[-1])


def differences(arrays: dict, reference: dict) -> dict:
    """Largest relative differences of the :data:`COMPARED` arrays (NaN where either is
    NaN is skipped) and the pairs whose contact fraction differs."""
    out = {}
    for name in COMPARED:
        a, b = arrays[name], reference[name]
        ok = np.isfinite(a) & np.isfinite(b)
        scale = np.abs(b[ok]).clip(1e-300)
        out[f"max_rel_diff_{name}"] = float((np.abs(a[ok] - b[ok]) / scale).max(initial=0.0))
    out["contact_fraction_differs"] = int((arrays["real_area_fraction"]
                                           != reference["real_area_fraction"]).sum())
    return out


def measure(args) -> list[dict]:
    """Every variant ``args.repeats`` times, alternated; one row per variant."""
    with tempfile.TemporaryDirectory() as scratch:
        scratch = Path(scratch)
        build_s = build_correction(args.grid, scratch / "correction.npz")
        trees = {"after": ROOT if args.after is None else checkout(args.after,
                                                                    scratch / "after")}
        if any(v.startswith("before:") for v in args.variants):
            trees["before"] = checkout(args.before, scratch / "before")
        runs = {variant: [] for variant in args.variants}
        for round_ in range(args.repeats):
            order = args.variants[round_ % len(args.variants):] + \
                args.variants[:round_ % len(args.variants)]
            for variant in order:
                tree, method = variant.split(":")
                spec = dict(grid=args.grid, surfaces=args.surfaces, steps=args.steps,
                            method=method, tree=str(trees[tree]),
                            correction=str(scratch / "correction.npz"),
                            arrays=str(scratch / f"{tree}_{method}.npz"))
                runs[variant].append(run_variant(trees[tree], spec))
                print(variant, runs[variant][-1], flush=True)
        arrays = {v: dict(np.load(scratch / f"{v.replace(':', '_')}.npz"))
                  for v in args.variants}
    rows = []
    reference = arrays[args.variants[0]]
    for variant in args.variants:
        best = min(runs[variant], key=lambda r: r["cpu_s"])
        rows.append(dict(
            variant=variant, grid=args.grid, surfaces=args.surfaces, steps=args.steps,
            cpu_s=round(best["cpu_s"], 2),
            cpu_all_s=" ".join(f"{r['cpu_s']:.1f}" for r in runs[variant]),
            wall_s=round(best["wall_s"], 2),
            cell_60x30_min=round(best["cpu_s"] * 60 / args.surfaces * 30 / args.steps / 60, 2),
            iterations=best["iterations"], matvecs=best["matvecs"],
            converged=best["converged"] and best["stiffness_converged"],
            last_contact=round(best["last_contact"], 4),
            peak_rss_MB=round(max(r["peak_rss_MB"] for r in runs[variant])),
            correction_build_s=round(build_s, 1),
            **differences(arrays[variant], reference)))
    base = rows[0]["cpu_s"]
    for row in rows:
        row[f"ratio_to_{args.variants[0]}"] = round(row["cpu_s"] / base, 3)
    return rows


def write(rows: list[dict], grid: int) -> None:
    """``hybrid_cell_<grid>.csv`` and ``.md`` under results/benchmarks."""
    import pandas as pd

    OUT.mkdir(parents=True, exist_ok=True)
    frame = pd.DataFrame(rows)
    frame.to_csv(OUT / f"hybrid_cell_{grid}.csv", index=False)
    lines = [f"# hybrid_cell_{grid} ({time.strftime('%Y-%m-%d %H:%M')}, load average "
             f"{os.getloadavg()[0]:.1f}, {os.cpu_count()} cores)", "",
             frame.to_markdown(index=False), ""]
    (OUT / f"hybrid_cell_{grid}.md").write_text("\n".join(lines))


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--worker", help=argparse.SUPPRESS)
    parser.add_argument("--grid", type=int, default=256)
    parser.add_argument("--surfaces", type=int, default=20)
    parser.add_argument("--steps", type=int, default=30)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--before", default="e109424")
    parser.add_argument("--after", default=None, help="a git revision (default: this tree)")
    parser.add_argument("--variants", nargs="+",
                        default=["before:pcg", "after:pcg", "after:cg"])
    args = parser.parse_args(argv)
    if args.worker:
        worker(json.loads(args.worker))
        return
    sys.path.insert(0, str(ROOT))
    write(measure(args), args.grid)


if __name__ == "__main__":
    main()
