"""When may a compliant counter body be treated as rigid? Its compliance share against the
change it makes to k_P, the real area fraction and the peak pressure.

The study's contact job treats a counter body as rigid when its share of the pair's
compliance (:func:`roughcontact.contact.counterface.compliance_share`),

    share = max(1^T C2 1 / 1^T (C1 + C2) 1,  sum diag C2 / sum diag (C1 + C2)),

is below ``counterface.rigid_share`` (``C2`` the counter body's unit-modulus operator
times E1 / E2). Measured here, on the equivalent problem of Eq 17-18
(:func:`~roughcontact.contact.counterface.equivalent_operator`):

- body 1: a block 4.8 mm x 4.8 mm x 10 mm (E1 511 MPa, nu 0, clamped base, mesh
  "paper", 32 x 32 contact grid);
- counter bodies: (a) the same block, (b) a half-space (nu 0.3, Love's matrix on the
  same grid), each at moduli E2 / E1 in ``RATIOS``;
- ``--surfaces`` Gaussian surfaces (exponential ACF, b 0.5 mm, the "paper"
  generator, seeds 0, 1, ...) at each sigma of ``SIGMAS``, 0.5 and 2 um: real area
  5-23 % and 2-10 % at 0.3-3 MPa on the block alone, pressed on a smooth counter face;
- load control (``contact.sweep(..., mean_pressures=...)``, method "pcg", tol 1e-10:
  the same numbers as block principal pivoting to 3e-9, 3-15x faster; a surface it
  leaves unconverged is solved again by pivoting) at the
  nominal pressures ``PRESSURES``: the normalized stiffness
  k_P = (L1 / A_n) dF/dd, the real area fraction and the peak pressure, each averaged
  over the surfaces, and their relative change against a rigid counter body (C2 = 0).

Per case and ratio the table gives the share, the signed change of largest magnitude
over the pressures of each quantity, the largest |change| of the three, and that change
over the share. The recommended ``rigid_share`` is ``TARGET`` (1 %) over the largest
change / share measured at shares up to ``LINEAR_SHARE`` (0.1: where a threshold can
sit; at larger shares the largest change is far above 1 %), rounded down to 1, 2 or
5 x 10^k; the table's pairs below it are checked to change no quantity by more than
``TARGET``. The real area is counted in elements, so a small change of it is quantized:
one element of the surfaces' contact sets at the lowest pressure is 0.2 % (sigma 0.5 um)
and 0.6 % (2 um) of the area with 8 surfaces. Optionally (default on, ``--no-timing`` to
skip) the cost of the counter operator in a matrix-free sweep: the same pcg sweep on the
block alone (a ``MatrixFreeInfluence``) and on its ``SumInfluence`` with a counter block
at E2 / E1 = 1e4 (almost the same contact problem, two operator products per product).

Writes results/benchmarks/counter_rigid.md and counter_rigid.csv.

Usage::

    .venv/bin/python benchmarks/bench_counter_rigid.py               # 1-3 min
    .venv/bin/python benchmarks/bench_counter_rigid.py --surfaces 3 --no-timing
"""

from __future__ import annotations

import argparse
import csv
import datetime
import math
import platform
import time
from pathlib import Path

import numpy as np

from roughcontact import contact
from roughcontact.contact import SolverOptions, counterface
from roughcontact.elasticity.halfspace import halfspace_influence
from roughcontact.elasticity.influence import BlockGeometry, unit_modulus_influence
from roughcontact.elasticity.protocol import DenseInfluence, MatrixFreeInfluence
from roughcontact.surfaces import synthetic
from roughcontact.surfaces.spec import SurfaceSpec

OUT = Path(__file__).resolve().parents[1] / "results" / "benchmarks"
GRID = 32
SIZE = 4.8e-3  # plan size [m]
THICKNESS = 10e-3  # block thickness L1 [m]
E1 = 5.11e8  # first body's Young's modulus [Pa]
NU_HALFSPACE = 0.3
CORRELATION = 0.5e-3  # b [m]
SIGMAS = (0.5e-6, 2e-6)  # rms roughness [m]
PRESSURES = (0.3e6, 1e6, 3e6)  # nominal pressures [Pa]
RATIOS = (1.0, 3.0, 10.0, 30.0, 100.0, 300.0, 1e3, 1e4)  # E2 / E1
TARGET = 0.01  # largest change allowed by treating the counter body as rigid
LINEAR_SHARE = 0.1  # largest share whose change / share enters the recommendation
METHOD = "pcg"
TOL = 1e-10
QUANTITIES = ("k_P", "area", "p_max")


def surfaces(count: int, sigma: float) -> np.ndarray:
    """``count`` Gaussian surfaces [m] of rms ``sigma`` [m], (count, GRID, GRID), zero mean."""
    spec = SurfaceSpec(grid=GRID, size=SIZE, corr_length=CORRELATION, sigma=sigma,
                       acf="exponential")
    return synthetic.generate_many(spec, range(count), method="paper")


def unit_operators() -> dict:
    """The unit-modulus operators ``E C`` [m] (DenseInfluence) of the block and the
    half-space on the contact grid."""
    area = (SIZE / GRID) ** 2
    block = unit_modulus_influence(BlockGeometry(size=(SIZE, SIZE), grid=(GRID, GRID),
                                                 thickness=THICKNESS, mesh="paper", nu=0.0))
    half = halfspace_influence((GRID, GRID), (SIZE, SIZE), 1.0, NU_HALFSPACE)
    return {name: DenseInfluence(matrix, area, (GRID, GRID))
            for name, matrix in (("block", block), ("half-space", half))}


def share_by_hand(c1: np.ndarray, c2: np.ndarray) -> float:
    """The share of the brief, from the matrices: max of the mean-plane and diagonal shares."""
    ones = np.ones(c1.shape[0])
    mean = (c2 @ ones).sum() / ((c1 + c2) @ ones).sum()
    diag = np.diag(c2).mean() / np.diag(c1 + c2).mean()
    return float(max(mean, diag))


def measure(unit_matrix: np.ndarray, gaps: np.ndarray) -> dict:
    """Surface means of k_P [Pa], real area fraction [-] and peak pressure [Pa] at
    ``PRESSURES``, each an array (len(PRESSURES),), for the unit-modulus operator
    ``unit_matrix`` of the pair (in E1's unit). A surface that ``METHOD`` leaves
    unconverged is solved again by block principal pivoting (exact on its contact set)."""
    def swept(method, rows):
        result = contact.sweep(unit_matrix / E1, gaps[rows], mean_pressures=np.array(PRESSURES),
                               element_area=(SIZE / GRID) ** 2,
                               options=SolverOptions(tol=TOL, method=method))
        ok = result.converged.all(axis=1) & result.stiffness_converged.all(axis=1)
        return {"k_P": THICKNESS / SIZE**2 * result.contact_stiffness,
                "area": result.real_area_fraction, "p_max": result.max_pressure}, ok

    values, ok = swept(METHOD, slice(None))
    if not ok.all():
        redo = np.flatnonzero(~ok)
        print(f"  {redo.size} surface(s) not converged by {METHOD}: solved again by pivoting",
              flush=True)
        again, ok_again = swept("auto", redo)
        if not ok_again.all():
            raise RuntimeError("a contact or stiffness solve did not converge")
        for name in values:
            values[name][redo] = again[name]
    return {name: value.mean(axis=0) for name, value in values.items()}


def nice_floor(value: float) -> float:
    """The largest of 1, 2, 5 x 10^k not above ``value``."""
    exponent = math.floor(math.log10(value))
    return next(m * 10.0**exponent for m in (5.0, 2.0, 1.0)
                if m * 10.0**exponent <= value * (1 + 1e-12))


def study(count: int, sigma: float, units: dict) -> tuple[list[dict], list[dict], dict]:
    """The per-pressure rows, the per-ratio summary rows and the rigid reference of the
    surfaces of rms ``sigma`` [m]."""
    heights = surfaces(count, sigma)
    gaps = heights.max(axis=(1, 2), keepdims=True) - heights
    first = units["block"]
    start = time.perf_counter()
    rigid = measure(first.matrix, gaps)
    print(f"sigma {sigma * 1e6:g} um, rigid counter body: area {np.round(rigid['area'], 4)}, "
          f"k_P / E1 {np.round(rigid['k_P'] / E1, 4)}, p_max [MPa] "
          f"{np.round(rigid['p_max'] / 1e6, 1)} ({time.perf_counter() - start:.1f} s)",
          flush=True)
    detail, summary = [], []
    for case, counter in (("block", units["block"]), ("half-space", units["half-space"])):
        for ratio in RATIOS:
            second = counterface.scaled(counter, 1.0 / ratio)  # E2 C2 times E1 / E2
            share = counterface.compliance_share(first, second)
            check = share_by_hand(first.matrix, second.matrix)
            if abs(share - check) > 1e-12 * check:
                raise RuntimeError(f"compliance_share {share} != {check} by hand")
            pair = counterface.equivalent_operator(first, second)
            start = time.perf_counter()
            values = measure(pair.matrix, gaps)
            changes = {q: values[q] / rigid[q] - 1.0 for q in QUANTITIES}
            for i, pressure in enumerate(PRESSURES):
                detail.append({"case": case, "sigma_um": sigma * 1e6, "E2_over_E1": ratio,
                               "share": share,
                               "P_MPa": pressure / 1e6,
                               **{f"{q}_rigid": rigid[q][i] for q in QUANTITIES},
                               **{f"{q}_pair": values[q][i] for q in QUANTITIES},
                               **{f"d{q}": changes[q][i] for q in QUANTITIES}})
            worst = {q: float(changes[q][np.argmax(np.abs(changes[q]))]) for q in QUANTITIES}
            largest = max(abs(v) for v in worst.values())
            summary.append({"case": case, "sigma_um": sigma * 1e6, "E2_over_E1": ratio,
                            "share": share,
                            **{f"d{q}": worst[q] for q in QUANTITIES},
                            "max_change": largest, "change_over_share": largest / share})
            row = summary[-1]
            print(f"{case:10s} E2/E1 {ratio:8g}: share {share:.3e}, dk_P {row['dk_P']:+.2e}, "
                  f"darea {row['darea']:+.2e}, dp_max {row['dp_max']:+.2e}, "
                  f"change / share {row['change_over_share']:.3f} "
                  f"({time.perf_counter() - start:.1f} s)", flush=True)
    return detail, summary, rigid


def matrix_free_timing(block: DenseInfluence, repeats: int) -> dict:
    """pcg sweeps (2 surfaces, the three loads) on the matrix-free block alone and on its
    sum with a counter block at E2 / E1 = 1e4: minimum wall time [s] and products."""
    op = DenseInfluence(block.matrix / E1, block.element_area, block.grid)
    free = MatrixFreeInfluence(op, op.element_area, op.diagonal(), op.grid)
    second = counterface.ScaledInfluence(free, 1e-4)
    heights = surfaces(2, SIGMAS[0])
    gaps = heights.max(axis=(1, 2), keepdims=True) - heights
    runs = {"alone": free, "with counter": counterface.equivalent_operator(free, second)}
    best, matvecs = dict.fromkeys(runs, np.inf), {}
    for _ in range(repeats):
        for name, operator in runs.items():
            start = time.perf_counter()
            result = contact.sweep(operator, gaps, mean_pressures=np.array(PRESSURES),
                                   options=SolverOptions(tol=1e-8, method=METHOD))
            best[name] = min(best[name], time.perf_counter() - start)
            matvecs[name] = float(result.matvecs.sum())
    return {"seconds": best, "matvecs": matvecs}


def write(detail: list[dict], summary: list[dict], timing: dict | None, count: int,
          elapsed: float) -> tuple[float, dict]:
    """The csv and md files; returns the recommended threshold and the ratios by case."""
    OUT.mkdir(parents=True, exist_ok=True)
    with open(OUT / "counter_rigid.csv", "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(detail[0]))
        writer.writeheader()
        writer.writerows(detail)
    ratios = {case: max(r["change_over_share"] for r in summary
                        if r["case"] == case and r["share"] <= LINEAR_SHARE)
              for case in ("block", "half-space")}
    overall = {case: max(r["change_over_share"] for r in summary if r["case"] == case)
               for case in ratios}
    worst = max(ratios.values())
    recommended = nice_floor(TARGET / worst)
    below = [r for r in summary if r["share"] < recommended]
    held = all(r["max_change"] <= TARGET for r in below)
    lines = [
        "# Treating a compliant counter body as rigid",
        "",
        f"{datetime.date.today()}, {platform.processor() or platform.machine()}, "
        f"{elapsed:.0f} s (`benchmarks/bench_counter_rigid.py`). Body 1: block "
        f"{SIZE * 1e3:g} x {SIZE * 1e3:g} x {THICKNESS * 1e3:g} mm, E1 {E1 / 1e6:g} MPa, "
        f"nu 0, clamped, mesh paper, {GRID} x {GRID}; {count} Gaussian surfaces (exp. ACF, "
        f"b {CORRELATION * 1e3:g} mm) per sigma on a smooth counter face; "
        f"load control at P = {', '.join(f'{p / 1e6:g}' for p in PRESSURES)} MPa "
        f"(method {METHOD}, tol {TOL:g}). Changes of the surface means against a rigid "
        f"counter body (C2 = 0), the signed one of largest magnitude over the pressures; "
        f"share = max(mean-plane, diagonal) share of C1 + C2 "
        f"(`counterface.compliance_share`). Per-pressure values: `counter_rigid.csv`.",
        "",
        "| case | sigma [um] | E2/E1 | share | dk_P | darea | dp_max | max change "
        "| change / share |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in summary:
        lines.append(f"| {r['case']} | {r['sigma_um']:g} | {r['E2_over_E1']:g} | "
                     f"{r['share']:.3g} | "
                     f"{100 * r['dk_P']:+.3g} % | {100 * r['darea']:+.3g} % | "
                     f"{100 * r['dp_max']:+.3g} % | {100 * r['max_change']:.3g} % | "
                     f"{r['change_over_share']:.2f} |")
    lines += [
        "",
        f"Largest change / share at shares <= {LINEAR_SHARE:g}: block "
        f"{ratios['block']:.2f}, half-space {ratios['half-space']:.2f} (over all shares: "
        f"{overall['block']:.2f} and {overall['half-space']:.2f}). The real area is "
        f"counted in elements: a change below one element of the surfaces' contact sets "
        f"reads 0.",
        "",
        f"**Recommendation: `rigid_share` = {recommended:g}** ({100 * TARGET:g} % / "
        f"{worst:.2f}, rounded down): treating a counter body below it as rigid changes "
        f"k_P, the real area and the peak pressure by less than {100 * TARGET:g} %"
        + (f" (every measured pair below it: largest change "
           f"{100 * max((r['max_change'] for r in below), default=0.0):.2g} %)."
           if held else " (NOT met by every measured pair below it: check the table)."),
    ]
    if timing is not None:
        s, mv = timing["seconds"], timing["matvecs"]
        lines += [
            "",
            f"Matrix-free pcg sweep (2 surfaces, the three loads, tol 1e-8, minimum of the "
            f"runs): block alone {s['alone']:.2f} s ({mv['alone']:.0f} products), with the "
            f"counter operator (`SumInfluence`, E2/E1 1e4) {s['with counter']:.2f} s "
            f"({mv['with counter']:.0f} products of the sum, each two operator products): "
            f"x{s['with counter'] / s['alone']:.2f} in time, x"
            f"{s['with counter'] / mv['with counter'] / (s['alone'] / mv['alone']):.2f} per "
            f"product (a shared 2-core machine: times vary by tens of %).",
        ]
    (OUT / "counter_rigid.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines), flush=True)
    return recommended, ratios


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--surfaces", type=int, default=8, help="surfaces per sigma")
    parser.add_argument("--no-timing", action="store_true",
                        help="skip the matrix-free timing")
    parser.add_argument("--repeats", type=int, default=3, help="timing repeats")
    args = parser.parse_args()
    start = time.perf_counter()
    units = unit_operators()
    detail, summary = [], []
    for sigma in SIGMAS:
        rows, table, _ = study(args.surfaces, sigma, units)
        detail += rows
        summary += table
    timing = None if args.no_timing else matrix_free_timing(units["block"], args.repeats)
    write(detail, summary, timing, args.surfaces, time.perf_counter() - start)


if __name__ == "__main__":
    main()
