"""The verification matrix of the contact solver, tabulated (issue 42).

Every cell of ``tests/contact/test_verification_matrix.py`` (operator x method x control
x cap) on the core cases (seed 0) and, with ``--seeded``, the seeded set of
``tests/contact/test_verification_seeded.py`` (seeds 1-3, the issue's 32 x 32 block, eight
random blocks, aspect-64 cells): each solved twice through ``contact.solve``, as users
get it (with the retries of ``roughcontact.contact.retries``) and as the method alone
(``retries=False``), and refereed (``tests/contact/verification.py``: scipy's nnls /
lsq_linear, an independent KKT residual and load error).

Per cell the table gives its referee, the worst KKT residual, load error and
disagreement with scipy (energy, gaps) over its cases, the most iterations, and how many
cases the method converged on alone; the totals count results returned as converged
that are not (by the referees) and converged ones flagged unconverged.

Writes results/benchmarks/verification_matrix.csv and .md (a line per cell) and
verification_matrix_compact.md (a line per operator, control and cap; the table of
docs/performance/verification.md).

Usage::

    .venv/bin/python benchmarks/verification_matrix.py            # core cells, ~1 min
    .venv/bin/python benchmarks/verification_matrix.py --seeded   # and the seeded set
"""

from __future__ import annotations

import argparse
import csv
import datetime
import logging
import platform
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "contact"))

import verification as V  # noqa: E402

OUT = ROOT / "results" / "benchmarks"


def referee(body: V.Body, capped: bool) -> str:
    """The referee of a cell in words."""
    scipy_name = "lsq_linear (bvls)" if capped else "nnls"
    shift = " on C + k 1 1^T/n" if body.zero_mean else ""
    return f"scipy {scipy_name}{shift}, KKT"


def run(bodies: dict, seeds, say) -> list[dict]:
    """Every cell of ``bodies`` on the cases of ``seeds``: one row per cell and case."""
    rows = []
    for name, build in bodies.items():
        start = time.perf_counter()
        body = build()
        for seed in seeds:
            for case in V.cases(body, seed):
                for method in V.METHODS:
                    for control in V.CONTROLS:
                        user = V.verify(body, method, control, case)
                        own = V.verify(body, method, control, case, retries=False)
                        rows.append({
                            "body": name, "seed": seed, "case": case.name,
                            "capped": case.hardness is not None, "method": method,
                            "control": control, "refused": user.refused or "",
                            "referee": referee(body, case.hardness is not None),
                            "converged": user.converged, "honest": user.honest,
                            "agrees": user.agrees, "kkt": user.kkt,
                            "load_error": user.load_error,
                            "energy_error": user.energy_error, "gap_error": user.gap_error,
                            "iterations": user.iterations, "seconds": user.seconds,
                            "own_converged": own.converged, "own_honest": own.honest,
                            "own_iterations": own.iterations, "own_kkt": own.kkt})
        say(f"{name}: {time.perf_counter() - start:.1f} s")
    return rows


def _fmt(value: float) -> str:
    return "-" if value != value else f"{value:.0e}"


def cells(rows: list[dict]) -> list[dict]:
    """The rows grouped by cell (body, method, control, cap), worst over the cases."""
    grouped: dict[tuple, list[dict]] = {}
    for row in rows:
        grouped.setdefault((row["body"], row["method"], row["control"], row["capped"]),
                           []).append(row)
    out = []
    for (body, method, control, capped), members in grouped.items():
        solved = [r for r in members if not r["refused"]]
        out.append({
            "body": body, "method": method, "control": control, "capped": capped,
            "cases": len(members), "referee": members[0]["referee"],
            "refused": members[0]["refused"] if not solved else "",
            "converged": sum(r["converged"] for r in solved),
            "own_converged": sum(r["own_converged"] for r in solved),
            "kkt": max((r["kkt"] for r in solved), default=float("nan")),
            "load_error": max((r["load_error"] for r in solved), default=float("nan")),
            "energy_error": max((abs(r["energy_error"]) for r in solved),
                                default=float("nan")),
            "gap_error": max((r["gap_error"] for r in solved), default=float("nan")),
            "iterations": max((r["iterations"] for r in solved), default=0),
            "own_iterations": max((r["own_iterations"] for r in solved), default=0),
            "dishonest": sum(not (r["honest"] and r["own_honest"]) for r in solved),
            "disagree": sum(not r["agrees"] for r in solved)})
    return out


def markdown(rows: list[dict], table: list[dict], meta: dict) -> str:
    """The report: totals, then one line per cell."""
    solved = [r for r in rows if not r["refused"]]
    lines = [
        "# Verification matrix", "",
        f"{meta['date']}, commit {meta['commit']}, {meta['machine']}; "
        f"{len(rows)} solves ({len(table)} cells x their cases), "
        f"{meta['seconds']:.0f} s.", "",
        f"- converged (as users get it): {sum(r['converged'] for r in solved)} of "
        f"{len(solved)}; refused with a message: {len(rows) - len(solved)} "
        "(pcg with a cap)",
        f"- converged by the method alone (retries=False): "
        f"{sum(r['own_converged'] for r in solved)} of {len(solved)}",
        f"- returned as converged but not (by the referees): "
        f"{sum(r['converged'] and not r['honest'] for r in solved)} (with retries), "
        f"{sum(r['own_converged'] and not r['own_honest'] for r in solved)} (alone)",
        f"- flagged unconverged but converged: "
        f"{sum(not r['converged'] and not r['honest'] for r in solved)} (with retries), "
        f"{sum(not r['own_converged'] and not r['own_honest'] for r in solved)} (alone)",
        f"- disagreeing with scipy (load 1e-6, energy 1e-8, gaps 1e-6): "
        f"{sum(not r['agrees'] for r in solved)}", "",
        "| operator | method | control | cap | cases | converged (alone) | worst KKT | "
        "worst load error | worst energy / gap vs scipy | most iterations (alone) |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for c in table:
        cap = "H" if c["capped"] else "-"
        if c["refused"]:
            lines.append(f"| {c['body']} | {c['method']} | {c['control']} | {cap} | "
                         f"{c['cases']} | refused: *{c['refused'].split(';')[0]}* "
                         "| | | | |")
            continue
        lines.append(
            f"| {c['body']} | {c['method']} | {c['control']} | {cap} | {c['cases']} | "
            f"{c['converged']} ({c['own_converged']}) | {_fmt(c['kkt'])} | "
            f"{_fmt(c['load_error'])} | {_fmt(c['energy_error'])} / {_fmt(c['gap_error'])} | "
            f"{c['iterations']} ({c['own_iterations']}) |")
    lines += ["", "Referee of every solved cell: " + "; ".join(sorted(
        {c["referee"] for c in table if not c["refused"]})) + "."]
    return "\n".join(lines) + "\n"


def compact(table: list[dict]) -> str:
    """The cells as one row per operator, control and cap, a column per method: cases
    converged, the worst KKT residual and the most iterations, and (where it differs)
    how many the method converged on alone."""
    grouped: dict[tuple, dict] = {}
    for c in table:
        grouped.setdefault((c["body"], c["control"], c["capped"]), {})[c["method"]] = c
    lines = ["| operator | control | cap | " + " | ".join(V.METHODS)
             + " | worst energy / gap vs scipy |",
             "|---|---|---|" + "---|" * len(V.METHODS) + "---|"]
    for (body, control, capped), by_method in grouped.items():
        entries, energy, gap = [], 0.0, 0.0
        for method in V.METHODS:
            c = by_method[method]
            if c["refused"]:
                entries.append("refused")
                continue
            alone = "" if c["own_converged"] == c["converged"] else \
                f", alone {c['own_converged']}"
            entries.append(f"{c['converged']}/{c['cases']}{alone}; {_fmt(c['kkt'])}; "
                           f"{c['iterations']} it")
            energy, gap = max(energy, c["energy_error"]), max(gap, c["gap_error"])
        lines.append(f"| {body} | {control} | {'H' if capped else '-'} | "
                     + " | ".join(entries) + f" | {_fmt(energy)} / {_fmt(gap)} |")
    return "\n".join(lines) + "\n"


def _read(path: Path) -> list[dict]:
    """The rows of a CSV written by :func:`main`, typed."""
    numbers = {"kkt", "load_error", "energy_error", "gap_error", "seconds", "own_kkt"}
    flags = {"capped", "converged", "honest", "agrees", "own_converged", "own_honest"}
    counts = {"seed", "iterations", "own_iterations"}
    out = []
    with open(path, newline="") as handle:
        for row in csv.DictReader(handle):
            out.append({key: (float(value) if key in numbers else value == "True"
                              if key in flags else int(value) if key in counts else value)
                        for key, value in row.items()})
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeded", action="store_true", help="also the seeded set")
    parser.add_argument("--from-csv", action="store_true",
                        help="only render the tables again from the last CSV")
    args = parser.parse_args()
    logging.disable(logging.WARNING)  # the unconverged attempts are counted, not logged
    start = time.perf_counter()
    if args.from_csv:
        rows = _read(OUT / "verification_matrix.csv")
    else:
        rows = run(V.core_bodies(), (0,), print)
        if args.seeded:
            rows += run(V.seeded_bodies(), (1, 2, 3), print)
    table = cells(rows)
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                            capture_output=True, text=True).stdout.strip()
    meta = {"date": datetime.date.today().isoformat(), "commit": commit,
            "machine": f"{platform.machine()}, {platform.python_version()}",
            "seconds": (sum(r["seconds"] for r in rows) if args.from_csv
                        else time.perf_counter() - start)}
    OUT.mkdir(parents=True, exist_ok=True)
    if not args.from_csv:
        with open(OUT / "verification_matrix.csv", "w", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
            writer.writeheader()
            writer.writerows(rows)
    (OUT / "verification_matrix.md").write_text(markdown(rows, table, meta))
    (OUT / "verification_matrix_compact.md").write_text(compact(table))
    print(f"wrote {OUT / 'verification_matrix.md'} ({meta['seconds']:.0f} s)")


if __name__ == "__main__":
    main()
