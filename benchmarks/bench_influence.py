"""Cost and accuracy of the finite-element influence coefficients per mesh preset.

Every case is built in its own Python process, so that its peak memory
(``ru_maxrss``, the peak resident set of that process: interpreter, libraries,
assembly and the sparse factorization, including MKL's own allocations) is
measured alone; ``increase`` subtracts the resident set just before the build.

Studies (all with a clamped base, E = 5.11e8 Pa):

A. The paper's block (Table 1 of Kumar et al. 2006: 9 mm x 9 mm, L = 10 mm,
   60 x 60 contact elements, nu = 0) for every mesh preset and both sparse
   solvers (MKL PARDISO and scipy's SuperLU; SuperLU only where its predicted
   peak fits the memory limit): build time, peak memory, dofs, and the centre
   element's self compliance and neighbours E C / h against Love's half-space
   and the "converged" preset.
B. Local mesh convergence on a small block with the same contact element size
   (8 x 8 elements of 0.15 mm, L = 1.2 mm) for nu = 0, 0.3, 0.49 against a much
   finer reference mesh (27-node elements, 4 x 4 per contact element, growth
   1.2). The discretization error of near-field entries is local, so these
   ratios carry over to the 60 x 60 block.
C. The "converged" preset on the paper's block at nu = 0.3 and 0.49: cost, and
   the diagonal against Love's value at the same nu and against the
   extrapolated value (converged times the local reference / converged ratio
   of study B). Target: within 5 %, under 3 minutes, within 16 GB.
D. 120 x 120 contact elements over 9 mm (h = 0.075 mm) with the paper and
   graded presets: predicted cost, built when the prediction fits the limit.
   Target: graded under 5 minutes within 16 GB.

Writes results/benchmarks/influence.csv and influence.md. With
``--convergence`` it also runs ``roughcontact.convergence.influence_convergence``
on the paper's block (all presets and Love's half-space, three Gaussian
surfaces) and writes influence_convergence.csv and .png there. With
``--hybrid`` it compares ``hybrid_unit_modulus_influence`` (coarse "converged"
and "refined" models, coarsening 2) with the "converged" preset on the paper's
block: entries, diagonal errors in the interior and at the free edges, and the
contact quantities of the convergence study; writes influence_hybrid.csv.

Usage::

    python benchmarks/bench_influence.py                # A-D (20-35 min, peak 13 GB)
    python benchmarks/bench_influence.py --quick        # only cases predicted below 4 GB
    python benchmarks/bench_influence.py --convergence  # also the contact convergence study
    python benchmarks/bench_influence.py --hybrid       # only the hybrid operator (about 3 min)

Timings depend on the load of the machine; the Markdown file records the CPU
count and the load average at the start.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from roughcontact.elasticity.influence import (
    MESH_PRESETS,
    BlockGeometry,
    MeshSpec,
    estimate_cost,
    halfspace_influence,
    unit_modulus_influence,
)

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "results" / "benchmarks"
REFERENCE = MeshSpec(element="hex27", refinement=4, layers=None, top_layer=1.0, growth=1.2)
H = 9e-3 / 60  # contact element size of the paper's model [m]
LIMIT = 16e9  # memory allowed per build [bytes]
QUICK_LIMIT = 4e9  # --quick: skip cases predicted above this [bytes]
KEYS = ("diag", "next", "diagonal_next")


def paper_block(mesh, nu: float = 0.0, grid: int = 60) -> BlockGeometry:
    """The block of Table 1 (E = 5.11e8 Pa) with the given mesh and contact grid."""
    return BlockGeometry(grid=(grid, grid), nu=nu, mesh=mesh)


def local_block(mesh, nu: float) -> BlockGeometry:
    """8 x 8 contact elements of the paper's size on a 1.2 mm thick block."""
    return BlockGeometry(size=(8 * H, 8 * H), thickness=1.2e-3, grid=(8, 8), nu=nu, mesh=mesh)


def geometry(spec: dict) -> BlockGeometry:
    mesh = spec["mesh"] if isinstance(spec["mesh"], str) else MeshSpec(**spec["mesh"])
    if spec["block"] == "paper":
        return paper_block(mesh, spec["nu"], spec.get("grid", 60))
    return local_block(mesh, spec["nu"])


def centre_entries(ec: np.ndarray, geom: BlockGeometry) -> dict:
    """Self compliance, x neighbour and diagonal neighbour of the centre element, E C / h."""
    nx, ny = geom.grid
    c = (ny // 2) * nx + nx // 2
    h = geom.spacing[0]
    return {"diag": ec[c, c] / h, "next": ec[c, c + 1] / h,
            "diagonal_next": ec[c, c + nx + 1] / h}


def run_one(spec: dict) -> dict:
    """Build one influence matrix; report cost and centre-row entries (E * C / h)."""
    geom = geometry(spec)
    solver = spec.get("solver", "auto")
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    start = time.perf_counter()
    ec = unit_modulus_influence(geom, solver=solver, max_bytes=LIMIT)
    seconds = time.perf_counter() - start
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    nx = geom.grid[0]
    c = (geom.grid[1] // 2) * nx + nx // 2
    return {
        "seconds": seconds,
        "peak_gb": peak / 1e9,
        "increase_gb": (peak - before) / 1e9,
        "dofs": estimate_cost(geom, solver).dofs,
        **centre_entries(ec, geom),
        "row_sum_over_L": ec[c].sum() / geom.thickness,
    }


def run_isolated(spec: dict, quick: bool) -> dict:
    """``run_one`` in a fresh interpreter, or a 'skipped' row when it would not fit."""
    geom = geometry(spec)
    solver = spec.get("solver", "auto")
    cost = estimate_cost(geom, solver)
    row = {"estimate_gb": cost.peak_bytes / 1e9, "dofs": cost.dofs}
    limit = QUICK_LIMIT if quick else LIMIT
    if cost.peak_bytes > limit:
        reason = "--quick" if quick and cost.peak_bytes <= LIMIT else "over the limit"
        return row | {"status": f"skipped: estimate {cost.peak_bytes / 1e9:.1f} GB ({reason})"}
    out = subprocess.run(
        [sys.executable, __file__, "--one", json.dumps(spec)],
        capture_output=True, text=True, env={**os.environ},
    )
    if out.returncode != 0:
        return row | {"status": f"failed (exit {out.returncode}): "
                                f"{out.stderr.strip().splitlines()[-1][:120]}"}
    return row | {"status": "ok", **json.loads(out.stdout.strip().splitlines()[-1])}


def love_entries(geom: BlockGeometry) -> dict:
    """Love's half-space values of the same entries, E * C / h."""
    return centre_entries(halfspace_influence(geom.grid, geom.size, 1.0, geom.nu), geom)


def mesh_label(mesh) -> str:
    if isinstance(mesh, str):
        return mesh
    return f"{mesh['element']} r={mesh['refinement']} growth={mesh['growth']}"


def report(label: str, row: dict) -> None:
    if row["status"] == "ok":
        print(f"{label}: {row['seconds']:.1f} s, {row['peak_gb']:.2f} GB, "
              f"diag {row['diag']:.4f}", file=sys.stderr, flush=True)
    else:
        print(f"{label}: {row['status']}", file=sys.stderr, flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--one", help=argparse.SUPPRESS)
    parser.add_argument("--quick", action="store_true",
                        help="run only cases predicted below 4 GB (about 3 min)")
    parser.add_argument("--convergence", action="store_true",
                        help="also run the contact convergence study at 60 x 60 (about 10 min)")
    parser.add_argument("--hybrid", action="store_true",
                        help="only compare the hybrid operator with the converged preset")
    parser.add_argument("--one-hybrid", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        print(json.dumps(run_one(json.loads(args.one))))
        return
    if args.one_hybrid:
        print(json.dumps(run_hybrid(args.one_hybrid)))
        return
    if args.hybrid:
        hybrid_study()
        return
    header = {"cpus": os.cpu_count(), "load": os.getloadavg(), "quick": args.quick,
              "started": time.strftime("%Y-%m-%d %H:%M:%S")}
    rows = []

    # B: local convergence against the fine reference
    reference_spec = {k: getattr(REFERENCE, k) for k in
                      ("element", "refinement", "layers", "top_layer", "growth", "coarsen_at")}
    local = {}
    for nu in (0.0, 0.3, 0.49):
        ref = run_isolated({"block": "local", "mesh": reference_spec, "nu": nu}, args.quick)
        local[("reference", nu)] = ref
        for name in MESH_PRESETS:
            res = run_isolated({"block": "local", "mesh": name, "nu": nu}, args.quick)
            local[(name, nu)] = res
            errors = {f"{k}_vs_ref": res[k] / ref[k] - 1 for k in KEYS
                      if res["status"] == ref["status"] == "ok"}
            rows.append({"study": "local 8x8", "mesh": name, "nu": nu, "solver": "pardiso",
                         **res, **errors})
        rows.append({"study": "local 8x8", "mesh": "reference " + mesh_label(reference_spec),
                     "nu": nu, "solver": "pardiso", **ref, **dict.fromkeys(
                         (f"{k}_vs_ref" for k in KEYS), 0.0)})
        report(f"local nu={nu} reference", ref)

    # A: the paper's 60 x 60 block, every preset and solver; C: converged at nu > 0
    cases = [(name, 0.0, solver) for name in MESH_PRESETS for solver in ("pardiso", "superlu")]
    cases += [("converged", nu, "pardiso") for nu in (0.3, 0.49)]
    results = {}
    for name, nu, solver in cases:
        res = run_isolated({"block": "paper", "mesh": name, "nu": nu, "solver": solver},
                           args.quick)
        results[(name, nu, solver)] = res
        report(f"60x60 {name} nu={nu} {solver}", res)
    for (name, nu, solver), res in results.items():
        row = {"study": "paper 60x60", "mesh": name, "nu": nu, "solver": solver, **res}
        if res["status"] == "ok":
            love = love_entries(paper_block(name, nu))
            best = results.get(("converged", nu, "pardiso"), {})
            ratio = {k: local[("reference", nu)].get(k, np.nan)
                     / local[("converged", nu)].get(k, np.nan) for k in KEYS}
            for k in KEYS:
                row[f"{k}_love"] = love[k]
                row[f"{k}_vs_love"] = res[k] / love[k] - 1
                if best.get("status") == "ok":
                    row[f"{k}_vs_converged"] = res[k] / best[k] - 1
                    row[f"{k}_vs_extrapolated"] = res[k] / (best[k] * ratio[k]) - 1
        rows.append(row)

    # D: 120 x 120 contact elements
    for name in ("paper", "graded"):
        res = run_isolated({"block": "paper", "mesh": name, "nu": 0.0, "grid": 120,
                            "solver": "pardiso"}, args.quick)
        report(f"120x120 {name}", res)
        row = {"study": "paper 120x120", "mesh": name, "nu": 0.0, "solver": "pardiso", **res}
        if res["status"] == "ok":
            love = love_entries(paper_block(name, 0.0, 120))
            row |= {f"{k}_vs_love": res[k] / love[k] - 1 for k in KEYS}
        rows.append(row)
    write(rows, header)

    if args.convergence:
        convergence_study()


def convergence_study() -> None:
    """``influence_convergence`` on the paper's block (nu = 0), CSV and PNG."""
    import logging

    from roughcontact.reports.convergence import influence_convergence, plot_influence_convergence
    from roughcontact.study.config import ConvergenceSettings

    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s: %(message)s")
    table = influence_convergence(paper_block("paper"),
                                  ConvergenceSettings(presets=tuple(MESH_PRESETS)))
    OUT.mkdir(parents=True, exist_ok=True)
    tmp = OUT / "influence_convergence.csv.tmp"
    table.to_csv(tmp, index=False)
    tmp.replace(OUT / "influence_convergence.csv")
    plot_influence_convergence(table, OUT / "influence_convergence.png")
    print(f"Richardson: {table.attrs['richardson']}", file=sys.stderr)


def run_hybrid(which: str) -> dict:
    """Build "converged" or "hybrid:<coarse mesh>" at 60 x 60; entries and contact response."""
    import dataclasses

    from roughcontact.contact.cell import SWEEP_OPTIONS, sweep_and_aggregate
    from roughcontact.elasticity.hybrid import hybrid_unit_modulus_influence
    from roughcontact.reports.convergence import CONTACT_COLUMNS
    from roughcontact.surfaces.spec import SurfaceSpec
    from roughcontact.surfaces.synthetic import derive_seeds, generate_many

    geom = paper_block("converged")
    start = time.perf_counter()
    if which == "converged":
        ec = unit_modulus_influence(geom)
    else:
        coarse_mesh = which.split(":")[1]
        ec = hybrid_unit_modulus_influence(dataclasses.replace(geom, mesh=coarse_mesh),
                                           coarsening=2)
    seconds = time.perf_counter() - start
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024 / 1e9
    np.save(OUT / f"ec_{which.replace(':', '_')}.npy", ec)
    sigma = 24.5e-6
    spec = SurfaceSpec(grid=geom.grid, size=geom.size, corr_length=(1e-3, 1e-3), sigma=sigma)
    heights = generate_many(spec, derive_seeds(2006, "influence_convergence", 3)) / sigma
    # swept and read as the convergence report does (40 steps to 1.1 P_max, exact-ish CG)
    _, _, frame = sweep_and_aggregate(ec, heights, geom, sigma=sigma, pressures=(0.3e6, 1e6, 2e6),
                                      steps=40, reach=1.1,
                                      options=SWEEP_OPTIONS.with_(method="cg", tol=1e-10,
                                                                  precision="double"))
    return {"seconds": seconds, "peak_gb": peak,
            **{k: frame[f"{c}_mean"].tolist() for k, c in CONTACT_COLUMNS.items()}}


def hybrid_study() -> None:
    """Hybrid operators against the converged preset (60 x 60, nu = 0): influence_hybrid.csv."""
    OUT.mkdir(parents=True, exist_ok=True)
    results = {}
    for which in ("converged", "hybrid:converged", "hybrid:refined"):
        out = subprocess.run([sys.executable, __file__, "--one-hybrid", which],
                             capture_output=True, text=True, check=True, env={**os.environ})
        results[which] = json.loads(out.stdout.strip().splitlines()[-1])
        print(f"{which}: {results[which]['seconds']:.1f} s", file=sys.stderr, flush=True)
    reference = np.load(OUT / "ec_converged.npy")
    n = 60
    c = 30 * n + 30
    lines = ["operator,seconds,peak_gb,quantity,value"]
    for which, res in results.items():
        ec = np.load(OUT / f"ec_{which.replace(':', '_')}.npy")
        diag = (np.diag(ec) / np.diag(reference) - 1).reshape(n, n)
        edges = np.concatenate([diag[0], diag[-1], diag[:, 0], diag[:, -1]])
        values = {
            "centre_diag_error": diag[30, 30],
            **{f"neighbour_{dx}_{dy}_error": ec[c, c + dy * n + dx] / reference[c, c + dy * n + dx]
               - 1 for dx, dy in ((1, 0), (1, 1), (2, 0), (10, 0))},
            "interior_diag_max_abs_error": np.abs(diag[3:-3, 3:-3]).max(),
            "edge_diag_max_abs_error": np.abs(edges).max(),
            "row_sum_max_error": np.abs(ec.sum(axis=1) / 10e-3 - 1).max(),
        }
        for q in ("k_P_Pa", "real_area_fraction", "max_pressure_Pa", "asperity_deflection_m"):
            for p, a, b in zip((0.3, 1.0, 2.0), res[q], results["converged"][q], strict=True):
                values[f"{q}_error_at_{p:g}MPa"] = a / b - 1
        for key, value in values.items():
            lines.append(f"{which},{res['seconds']:.2f},{res['peak_gb']:.3f},{key},{value:.6g}")
        (OUT / f"ec_{which.replace(':', '_')}.npy").unlink()
    _atomic_write(OUT / "influence_hybrid.csv", "\n".join(lines) + "\n")


def write(rows: list[dict], header: dict) -> None:
    """CSV of every number and a Markdown summary, written atomically."""
    OUT.mkdir(parents=True, exist_ok=True)
    first = ("study", "mesh", "nu", "solver", "status", "dofs", "seconds", "peak_gb",
             "increase_gb", "estimate_gb")
    columns = sorted({k for row in rows for k in row},
                     key=lambda k: (k not in first, first.index(k) if k in first else 0, k))
    lines = [",".join(columns)]
    for row in rows:
        lines.append(",".join(_fmt(row.get(k, "")).replace(",", ";") for k in columns))
    _atomic_write(OUT / "influence.csv", "\n".join(lines) + "\n")

    md = ["# Finite-element influence coefficients: cost and accuracy", "",
          f"Run {header['started']} on {header['cpus']} CPUs, load average at start "
          f"{header['load'][0]:.2f}{' (--quick)' if header['quick'] else ''}. Each build ran "
          "in its own process; peak = its peak resident set (ru_maxrss), increase = peak "
          "minus the set before the build, estimate = influence.estimate_cost.", "",
          "Entries are E * C / h for the centre contact element: self compliance (diag),",
          "x neighbour (next), diagonal neighbour. Love: elastic half-space (1.122 for the",
          "diagonal at nu = 0).", "",
          "## Cost per preset and solver (9 x 9 mm, L = 10 mm, clamped base)", "",
          "| grid | mesh | nu | solver | dofs | time [s] | peak [GB] | increase [GB] "
          "| estimate [GB] | diag | diag vs Love | diag vs converged | diag vs extrapolated "
          "| next vs extrapolated |",
          "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for row in rows:
        if not row["study"].startswith("paper"):
            continue
        grid = row["study"].split()[1]
        if row["status"] != "ok":
            md.append(f"| {grid} | {row['mesh']} | {_fmt(row['nu'])} | {row['solver']} | "
                      f"{row['dofs']} | {row['status']} | | | {row['estimate_gb']:.2f} "
                      "| | | | | |")
            continue
        md.append("| " + " | ".join([
            grid, row["mesh"], _fmt(row["nu"]), row["solver"], _fmt(row["dofs"]),
            _fmt(row["seconds"], 1), _fmt(row["peak_gb"], 2), _fmt(row["increase_gb"], 2),
            _fmt(row["estimate_gb"], 2), _fmt(row["diag"], 4), _pct(row.get("diag_vs_love")),
            _pct(row.get("diag_vs_converged")), _pct(row.get("diag_vs_extrapolated")),
            _pct(row.get("next_vs_extrapolated")),
        ]) + " |")
    md += ["", "## Targets", ""]
    md += _targets(rows)
    md += ["", "## Local convergence (8 x 8 contact elements of 0.15 mm, L = 1.2 mm)", "",
           "Relative error against the reference mesh " + mesh_label(
               {"element": REFERENCE.element, "refinement": REFERENCE.refinement,
                "growth": REFERENCE.growth}) + ". The errors of \"refined\" and",
           "\"converged\" are local and carry over to the 60 x 60 block; those of",
           "\"paper\" and \"graded\" depend on their layer thickness relative to the",
           "contact element (0.24 mm here, 2 mm in the paper's block), see the first table.",
           "", "Extrapolated (first table): converged preset times the local reference /",
           "converged ratio at the same nu.", "",
           "| nu | mesh | dofs | time [s] | diag | diag error | next error | diag. next error |",
           "|---|---|---|---|---|---|---|---|"]
    for row in rows:
        if row["study"] != "local 8x8" or row["status"] != "ok":
            continue
        md.append("| " + " | ".join([
            _fmt(row["nu"]), row["mesh"], _fmt(row["dofs"]), _fmt(row["seconds"], 1),
            _fmt(row["diag"], 4), _pct(row.get("diag_vs_ref")), _pct(row.get("next_vs_ref")),
            _pct(row.get("diagonal_next_vs_ref")),
        ]) + " |")
    _atomic_write(OUT / "influence.md", "\n".join(md) + "\n")


def _targets(rows: list[dict]) -> list[str]:
    """Pass/fail lines for the stated targets."""
    lines = []
    for row in rows:
        ok = row["status"] == "ok"
        if row["study"] == "paper 60x60" and row["mesh"] == "converged" \
                and row["solver"] == "pardiso":
            if not ok:
                lines.append(f"- converged, 60 x 60, nu = {row['nu']:g}: {row['status']}")
                continue
            error = row.get("diag_vs_extrapolated", np.nan)
            passed = abs(error) <= 0.05 and row["seconds"] <= 180 and row["peak_gb"] <= 16
            lines.append(
                f"- converged, 60 x 60, nu = {row['nu']:g}: diagonal {_pct(error)} vs "
                f"extrapolated, {_pct(row.get('diag_vs_love'))} vs Love; "
                f"{row['seconds']:.0f} s, {row['peak_gb']:.1f} GB "
                f"(target 5 %, 180 s, 16 GB): {'met' if passed else 'MISSED'}")
        if row["study"] == "paper 120x120" and row["mesh"] == "graded":
            if not ok:
                lines.append(f"- graded, 120 x 120: {row['status']} (target 300 s, 16 GB)")
                continue
            passed = row["seconds"] <= 300 and row["peak_gb"] <= 16
            lines.append(f"- graded, 120 x 120: {row['seconds']:.0f} s, {row['peak_gb']:.1f} GB "
                         f"(estimate {row['estimate_gb']:.1f} GB; target 300 s, 16 GB): "
                         f"{'met' if passed else 'MISSED'}")
    return lines


def _fmt(value, digits: int | None = None) -> str:
    if isinstance(value, float | np.floating):
        return f"{value:.{digits}f}" if digits is not None else f"{value:.6g}"
    return str(value)


def _pct(value) -> str:
    return "" if value is None or not np.isfinite(value) else f"{100 * value:+.1f} %"


def _atomic_write(path: Path, text: str) -> None:
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(text)
    tmp.replace(path)


if __name__ == "__main__":
    main()
