"""Cost and accuracy of the finite-element influence coefficients per mesh preset.

Two studies, each case run in its own process so that its peak memory (resident
set) is measured alone:

A. The paper's block (Table 1 of Kumar et al. 2006: 9 mm x 9 mm, L = 10 mm,
   60 x 60 contact elements, clamped base) for every mesh preset: build time,
   peak memory, problem size, and the self compliance (diagonal), the nearest
   and the diagonal neighbour of the centre element, against Love's half-space
   values and against the "converged" preset.
B. Local mesh convergence on a small block with the same contact element size
   (8 x 8 elements of 0.15 mm, L = 1.2 mm) for nu = 0, 0.3, 0.49, against a
   much finer reference mesh (27-node elements, 4 x 4 per contact element,
   growth 1.2). The discretization error of near-field entries is local, so
   these ratios carry over to the 60 x 60 block; they also give the
   "extrapolated" 60 x 60 values (converged preset times the local
   reference / converged ratio).

Writes results/benchmarks/influence.csv and influence.md.

Usage::

    python benchmarks/bench_influence.py            # everything (about 10 min, 8 GB)
    python benchmarks/bench_influence.py --quick    # skip the converged preset at 60 x 60
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

from roughcontact.influence import (
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
H = 9e-3 / 60  # contact element size [m]


def paper_block(mesh, nu: float = 0.0) -> BlockGeometry:
    """The block of Table 1 (E = 5.11e8 Pa) with the given mesh."""
    return BlockGeometry(nu=nu, mesh=mesh)


def local_block(mesh, nu: float) -> BlockGeometry:
    """8 x 8 contact elements of the paper's size on a 1.2 mm thick block."""
    return BlockGeometry(size=(8 * H, 8 * H), thickness=1.2e-3, grid=(8, 8), nu=nu, mesh=mesh)


def run_one(spec: dict) -> dict:
    """Build one influence matrix and report cost and centre-row entries (E * C / h)."""
    mesh = spec["mesh"] if isinstance(spec["mesh"], str) else MeshSpec(**spec["mesh"])
    factory = paper_block if spec["block"] == "paper" else local_block
    geom = factory(mesh, spec["nu"])
    start = time.perf_counter()
    C = unit_modulus_influence(geom, max_bytes=float(spec.get("max_bytes", 16e9)))
    seconds = time.perf_counter() - start
    nx = geom.grid[0]
    c = (geom.grid[1] // 2) * nx + nx // 2
    h = geom.spacing[0]
    cost = estimate_cost(geom)
    return {
        "seconds": seconds,
        "peak_gb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6,
        "estimate_gb": cost.peak_bytes / 1e9,
        "dofs": cost.dofs,
        "diag": C[c, c] / h,
        "next": C[c, c + 1] / h,
        "diagonal_next": C[c, c + nx + 1] / h,
        "row_sum_over_L": C[c].sum() / geom.thickness,
    }


def run_isolated(spec: dict) -> dict:
    """``run_one`` in a fresh interpreter (clean peak-memory measurement)."""
    out = subprocess.run(
        [sys.executable, __file__, "--one", json.dumps(spec)],
        check=True, capture_output=True, text=True, env={**os.environ},
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def love_entries(geom: BlockGeometry) -> dict:
    """Love's half-space values of the same entries, E * C / h."""
    nx, ny = geom.grid
    h = geom.spacing[0]
    hs = halfspace_influence(geom.grid, geom.size, 1.0, geom.nu)
    c = (ny // 2) * nx + nx // 2
    return {"diag": hs[c, c] / h, "next": hs[c, c + 1] / h,
            "diagonal_next": hs[c, c + nx + 1] / h}


def mesh_label(mesh) -> str:
    if isinstance(mesh, str):
        return mesh
    return f"{mesh['element']} r={mesh['refinement']} growth={mesh['growth']}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--one", help=argparse.SUPPRESS)
    parser.add_argument("--quick", action="store_true",
                        help="skip the converged preset at 60 x 60 (about 8 GB, 2-3 min)")
    args = parser.parse_args()
    if args.one:
        print(json.dumps(run_one(json.loads(args.one))))
        return

    keys = ("diag", "next", "diagonal_next")
    rows = []
    # B: local convergence against the fine reference
    reference_spec = {k: getattr(REFERENCE, k) for k in
                      ("element", "refinement", "layers", "top_layer", "growth", "coarsen_at")}
    local = {}
    for nu in (0.0, 0.3, 0.49):
        ref = run_isolated({"block": "local", "mesh": reference_spec, "nu": nu})
        for name in MESH_PRESETS:
            res = run_isolated({"block": "local", "mesh": name, "nu": nu})
            local[(name, nu)] = res
            rows.append({"study": "local 8x8", "mesh": name, "nu": nu, **res,
                         **{f"{k}_vs_ref": res[k] / ref[k] - 1 for k in keys}})
        rows.append({"study": "local 8x8", "mesh": "reference " + mesh_label(reference_spec),
                     "nu": nu, **ref, **{f"{k}_vs_ref": 0.0 for k in keys}})
        local[("reference", nu)] = ref
        print(f"local nu={nu} done", file=sys.stderr)

    # A: the paper's 60 x 60 block
    love = love_entries(paper_block("paper"))
    paper_rows = {}
    for name in MESH_PRESETS:
        if args.quick and name == "converged":
            continue
        res = run_isolated({"block": "paper", "mesh": name, "nu": 0.0})
        paper_rows[name] = res
        print(f"60x60 {name}: {res['seconds']:.1f} s, {res['peak_gb']:.2f} GB", file=sys.stderr)
    best = paper_rows.get("converged")
    for name, res in paper_rows.items():
        row = {"study": "paper 60x60", "mesh": name, "nu": 0.0, **res}
        for k in keys:
            row[f"{k}_vs_love"] = res[k] / love[k] - 1
            if best is not None:
                ratio = local[("reference", 0.0)][k] / local[("converged", 0.0)][k]
                row[f"{k}_vs_converged"] = res[k] / best[k] - 1
                row[f"{k}_vs_extrapolated"] = res[k] / (best[k] * ratio) - 1
        rows.append(row)
    rows.append({"study": "paper 60x60", "mesh": "Love half-space", "nu": 0.0, **love})
    write(rows)


def write(rows: list[dict]) -> None:
    """CSV of every number and a Markdown summary, written atomically."""
    OUT.mkdir(parents=True, exist_ok=True)
    columns = sorted({k for row in rows for k in row},
                     key=lambda k: (k not in ("study", "mesh", "nu"), k))
    lines = [",".join(columns)]
    for row in rows:
        lines.append(",".join(_fmt(row.get(k, "")) for k in columns))
    _atomic_write(OUT / "influence.csv", "\n".join(lines) + "\n")

    md = ["# Finite-element influence coefficients: cost and accuracy", "",
          "Entries are E * C / h (h = 0.15 mm) for the centre contact element: self",
          "compliance (diag), x neighbour (next), diagonal neighbour. Love: elastic",
          "half-space (1.122 for the diagonal at nu = 0).", "",
          "## Paper's block (9 x 9 mm, L = 10 mm, 60 x 60, nu = 0, clamped base)", "",
          "| mesh | dofs | time [s] | peak [GB] | estimate [GB] | diag | next | diag. next "
          "| diag vs Love | diag vs converged | diag vs extrapolated | next vs extrapolated |",
          "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for row in rows:
        if row["study"] != "paper 60x60":
            continue
        md.append("| " + " | ".join([
            row["mesh"], _fmt(row.get("dofs", "")), _fmt(row.get("seconds", ""), 1),
            _fmt(row.get("peak_gb", ""), 2), _fmt(row.get("estimate_gb", ""), 2),
            _fmt(row["diag"], 4), _fmt(row["next"], 4), _fmt(row["diagonal_next"], 4),
            _pct(row.get("diag_vs_love")), _pct(row.get("diag_vs_converged")),
            _pct(row.get("diag_vs_extrapolated")), _pct(row.get("next_vs_extrapolated")),
        ]) + " |")
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
        if row["study"] != "local 8x8":
            continue
        md.append("| " + " | ".join([
            _fmt(row["nu"]), row["mesh"], _fmt(row["dofs"]), _fmt(row["seconds"], 1),
            _fmt(row["diag"], 4), _pct(row["diag_vs_ref"]), _pct(row["next_vs_ref"]),
            _pct(row["diagonal_next_vs_ref"]),
        ]) + " |")
    _atomic_write(OUT / "influence.md", "\n".join(md) + "\n")


def _fmt(value, digits: int | None = None) -> str:
    if isinstance(value, float | np.floating):
        return f"{value:.{digits}f}" if digits is not None else f"{value:.6g}"
    return str(value)


def _pct(value) -> str:
    return "" if value is None else f"{100 * value:+.1f} %"


def _atomic_write(path: Path, text: str) -> None:
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(text)
    tmp.replace(path)


if __name__ == "__main__":
    main()
