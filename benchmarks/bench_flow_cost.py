"""What recording the flow through the gap costs a sweep (issue budget: off, nothing; on,
at most 25 % of a contact job at 60 x 60 and of a 1024 x 1024 pcg sweep).

A sweep records the flow (:mod:`roughcontact.transport.probe`) when its interface grid
carries a :class:`~roughcontact.transport.FlowProbe`; the default
:data:`~roughcontact.transport.NO_FLOW` records nothing. Measured with one thread (the
BLAS and FFT thread counts set to 1 before numpy is imported), A and B alternated in one
run, the minimum of ``--repeats`` runs of each:

(a) *off*: the study's contact job at 60 x 60 (60 Gaussian surfaces, exponential ACF,
    b = 1 mm, on the paper's 9 mm x 9 mm block 10 mm thick, clamped, paper mesh: the
    dense influence matrix built by
    :func:`roughcontact.elasticity.influence.unit_modulus_influence`, 3 s; 30 approaches
    of :func:`roughcontact.contact.cell.approach_grid` to P L / (E sigma) = 4, the study's
    :data:`~roughcontact.contact.cell.SWEEP_OPTIONS`, method "auto", tol 1e-8, precision
    "mixed", batches of 20) without flow, against the same sweep by the code before the
    flow (``--baseline DIR``: a checkout of that commit), each in a fresh subprocess
    whose ``PYTHONPATH`` is its tree, alternated; every array of the two sweeps is
    compared bit for bit;
(b) *on at 60 x 60*: the same sweep with ``FlowProbe()`` (x and y, sides of the grid:
    sealed) against ``NO_FLOW``, alternated in one process, and, in the runs with flow,
    the time inside :meth:`FlowProbe.measure` (timed around each call) over the sweep's;
(c) *on at 1024 x 1024*: one periodic cell (b = 1/32 of the period) of 2 Gaussian
    surfaces on :class:`~roughcontact.elasticity.halfspace.PeriodicHalfSpace`, method
    "pcg", tol 1e-8, no stiffness, 4 mean pressures from about 1 % to 30 % real area,
    with ``FlowProbe()`` against ``NO_FLOW``; then the flow's parts on its 8 gaps (gap
    clipping and assembly, clusters, SuperLU's ordering and factorisation) and cheaper
    linear solvers of the same systems, each checked against the default's conductance.

Writes results/benchmarks/flow_cost.md and flow_cost.csv.

Usage::

    .venv/bin/python benchmarks/bench_flow_cost.py --baseline ../preflow   # all (~25 min)
    .venv/bin/python benchmarks/bench_flow_cost.py --skip 1024              # (a) and (b)
    .venv/bin/python benchmarks/bench_flow_cost.py --skip off --skip 60    # (c) only

Measured (2026-12-02, 2 shared cores, one thread; see flow_cost.md):

- off: the 60 x 60 job without flow 12.15 s against 11.30 s by the code before the
  flow (x 1.075; a first run gave x 0.69: within the machine's noise), all 27 arrays of
  the two sweeps bit-identical. Off costs nothing.
- on, 60 x 60: 29.9 s against 5.6 s off, +432 % (budget 25 %); 24.4 s inside
  FlowProbe.measure, 82 % of the sweep with flow. About 3/4 of the flow is SuperLU
  (one 60 x 60 field a factorisation, ordering included), the rest the per-field
  assembly and clusters. ``BandedCholesky`` (band Cholesky, sealed sides): +265 %;
  with it and ``directions=("x",)``: +170 %; conductances the same to 7e-13.
  PARDISO (a setup per call) and JacobiCG (3.6e-8 off at rtol 1e-10) are slower.
- on, 1024 x 1024 (one run each: over 4 min with flow): 294 s against 61 s off,
  +382 %; 259 s inside the probe, 88 % of the sweep with flow; of one field's flow
  98 % is SuperLU (18 s at 1 % real area, 5.4 s at 25 %), the clusters 0.1 s.
  Along x only halves it (two independent solves): about +190 %. PARDISO (METIS,
  Cholesky): 6.0 s and 3.4 s, conductance within 4e-11; SuperLU on a geometric
  nested-dissection order: 11.2 s and 3.8 s, but 2.5e-10 off at 25 %. In one
  exploratory run JacobiCG took 231 s (8832 iterations) and CG with an spilu
  (drop 1e-4) preconditioner 54 s (1.5e-9 off) at 1 %. No exact remedy measured
  comes near the budget: it needs a solver of cost about linear in the unknowns
  (algebraic multigrid), or fewer flow solves (steps, surfaces).
"""

from __future__ import annotations

import os

for _name in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ[_name] = "1"

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import datetime  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from roughcontact.contact import SolverOptions  # noqa: E402

OUT = Path(__file__).resolve().parents[1] / "results" / "benchmarks"
STEPS, PRESSURE_END, BATCH = 30, 4.0, 20


# --------------------------------------------------------------------------- the 60 x 60 job


def study_job():
    """The study's contact job at 60 x 60 (module docstring): ``run(flow)`` sweeps it
    (``flow`` None: the code's default interface grid, as before the flow existed)."""
    from roughcontact.contact import cell
    from roughcontact.elasticity.influence import BlockGeometry, unit_modulus_influence
    from roughcontact.surfaces import synthetic
    from roughcontact.surfaces.spec import SurfaceSpec

    geometry = BlockGeometry()  # the paper's: 9 mm x 9 mm, 10 mm thick, 60 x 60, paper mesh
    unit = unit_modulus_influence(geometry)
    spec = SurfaceSpec(grid=60, size=geometry.size[0], corr_length=1e-3)
    heights = synthetic.generate_many(spec, range(60))
    heights = heights / heights.std(axis=(1, 2), keepdims=True)  # units of sigma
    options = cell.SWEEP_OPTIONS.with_(method="auto", tol=1e-8, precision="mixed",
                                       batch_size=BATCH)

    def run(flow=None):
        grid = True if flow is None else dataclasses.replace(
            cell.block_interface(geometry), probes=(flow,) if flow.columns else ())
        return cell.sweep_cell(unit, heights, geometry, PRESSURE_END, STEPS,
                               options=dataclasses.replace(options, interface=grid))

    return run


def _arrays(sweep) -> dict:
    """Every array and number of a sweep, by field name."""
    out = {}
    for f in dataclasses.fields(sweep):
        value = getattr(sweep, f.name)
        if isinstance(value, (np.ndarray, int, float, bool, np.generic)):
            out[f.name] = np.asarray(value)
    return out


def worker(save: str) -> None:
    """One timed sweep of the 60 x 60 job without flow, by whichever tree is imported;
    its arrays saved to ``save``, its wall time printed as JSON."""
    run = study_job()
    start = time.perf_counter()
    sweep = run()
    seconds = time.perf_counter() - start
    np.savez(save, **_arrays(sweep))
    print(json.dumps({"seconds": seconds}))


def off_vs_baseline(baseline: Path, repeats: int) -> dict:
    """(a): the sweep without flow by this tree and by ``baseline``, alternated."""
    here = Path(__file__).resolve().parents[1]
    trees = {"before": baseline.resolve(), "now": here}
    best = dict.fromkeys(trees, np.inf)
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(repeats):
            for name, tree in trees.items():
                env = {**os.environ, "PYTHONPATH": str(tree)}
                done = subprocess.run([sys.executable, str(Path(__file__).resolve()),
                                       "--worker", f"{tmp}/{name}.npz"], cwd=tree, env=env,
                                      capture_output=True, text=True, check=True)
                best[name] = min(best[name], json.loads(done.stdout.splitlines()[-1])["seconds"])
                print(f"  off, code {name}: {best[name]:.2f} s", flush=True)
        before, now = np.load(f"{tmp}/before.npz"), np.load(f"{tmp}/now.npz")
        common = sorted(set(before.files) & set(now.files))
        differ = [k for k in common if not np.array_equal(before[k], now[k], equal_nan=True)]
        only = sorted(set(before.files) ^ set(now.files))
    return {"before": best["before"], "now": best["now"], "compared": len(common),
            "differ": differ, "only_one": only}


class _Timed:
    """A function with the wall time of its calls added up in ``seconds``; the
    ``(pressure, gap)`` arguments of :meth:`FlowProbe.measure` kept in ``calls`` when
    ``keep``."""

    def __init__(self, function, keep=False):
        self.function, self.seconds, self.keep, self.calls = function, 0.0, keep, []

    def __call__(self, *args, **kwargs):
        if self.keep:
            self.calls.append((np.array(args[1].pressure), np.array(args[1].gap)))
        start = time.perf_counter()
        try:
            return self.function(*args, **kwargs)
        finally:
            self.seconds += time.perf_counter() - start


def alternated(runs: dict, repeats: int, kept: list | None = None) -> dict:
    """Minimum wall time [s] of each callable of ``runs``, called in turn ``repeats``
    times, and ``probe``: the time inside :meth:`FlowProbe.measure` of the fastest
    ``"on"`` run, with ``share`` its ratio to that run's wall time; the arguments of
    the first ``"on"`` run's calls appended to ``kept``."""
    from roughcontact.transport.probe import FlowProbe

    best = dict.fromkeys(runs, np.inf)
    probe = share = np.inf
    original = FlowProbe.measure
    for repeat in range(repeats):
        for name, run in runs.items():
            timed = _Timed(original, keep=kept is not None and repeat == 0 and name == "on")
            FlowProbe.measure = lambda self, *a, _t=timed, **k: _t(self, *a, **k)
            try:
                start = time.perf_counter()
                run()
                elapsed = time.perf_counter() - start
            finally:
                FlowProbe.measure = original
            if timed.keep:
                kept.extend(timed.calls)
            print(f"  {name}: {elapsed:.2f} s (probe {timed.seconds:.2f} s)", flush=True)
            if name == "on" and elapsed < best[name]:
                probe, share = timed.seconds, timed.seconds / elapsed
            if name.startswith("on") and elapsed < best[name]:
                best[f"{name} probe"] = timed.seconds
            best[name] = min(best[name], elapsed)
    return {**best, "probe": probe, "probe_share": share}


def on_60(repeats: int) -> dict:
    """(b): the 60 x 60 job with flow along x and y against without; and with flow by
    :class:`~roughcontact.transport.flow.BandedCholesky`, along x and y and along x."""
    from roughcontact.transport import NO_FLOW, BandedCholesky, FlowProbe

    run, last = study_job(), {}

    def probe(flow):
        def sweep():
            last[flow] = run(flow)
        return sweep

    banded = BandedCholesky()
    flows = {"off": NO_FLOW, "on": FlowProbe(),
             "on, banded": FlowProbe(solver=banded),
             "on, banded, x only": FlowProbe(directions=("x",), solver=banded)}
    times = alternated({name: probe(flow) for name, flow in flows.items()}, repeats)
    swept = last[flows["on"]]
    for name in ("on, banded", "on, banded, x only"):
        other = last[flows[name]]
        times[f"{name} relative difference"] = float(np.nanmax(np.abs(
            other.probe_columns["flow_conductance_x"]
            / np.where(swept.probe_columns["flow_conductance_x"] > 0,
                       swept.probe_columns["flow_conductance_x"], np.nan) - 1.0)))
    return {"sweep": "60 x 60 study job, 60 surfaces x 30 steps, pivot, block (sealed sides)",
            **times, "area_first": float(swept.real_area_fraction[:, 0].mean()),
            "area_last": float(swept.real_area_fraction[:, -1].mean())}


# --------------------------------------------------------------------------- 1024 x 1024

GRID_1024, PERIOD = 1024, 1e-3


def cell_1024():
    """(c)'s problem: the operator, the initial gaps (2, 1024, 1024) [m] and the mean
    pressures [Pa] of real areas ~1 % to ~30 % (``A / A0 = kappa P / (E* h'_rms)``,
    kappa = 2)."""
    from roughcontact.elasticity.halfspace import PeriodicHalfSpace
    from roughcontact.surfaces import synthetic
    from roughcontact.surfaces.spec import SurfaceSpec

    spec = SurfaceSpec(grid=GRID_1024, size=PERIOD, corr_length=PERIOD / 32)
    heights = synthetic.generate_many(spec, range(2))
    heights = heights / heights.std(axis=(1, 2), keepdims=True) * 1e-6
    dx = PERIOD / GRID_1024
    slope = np.sqrt(np.mean(np.gradient(heights[0], dx, axis=0) ** 2
                            + np.gradient(heights[0], dx, axis=1) ** 2))
    modulus = 1.0e9
    op = PeriodicHalfSpace((GRID_1024, GRID_1024), (PERIOD, PERIOD), modulus, 0.0)
    gaps = heights.max(axis=(1, 2), keepdims=True) - heights
    pressures = np.geomspace(0.01, 0.30, 4) * modulus * slope / 2.0
    return op, gaps, pressures


def on_1024(repeats: int) -> tuple[dict, object]:
    """(c): the pcg sweep with flow along x and y against without; and the open gaps
    the flow saw (surfaces, steps, ny, nx) [m], for :func:`remedies`."""
    from roughcontact import contact
    from roughcontact.contact import interface
    from roughcontact.transport import NO_FLOW, FlowProbe

    op, gaps, pressures = cell_1024()

    def run(flow):
        grid = dataclasses.replace(interface.InterfaceGrid.of(op, (PERIOD, PERIOD)),
                                   probes=(flow,) if flow.columns else ())
        return contact.sweep(op, gaps, mean_pressures=pressures, interface=grid,
                             options=SolverOptions(method="pcg", tol=1e-8, stiffness=False))

    kept = []
    times = alternated({"off": lambda: run(NO_FLOW), "on": lambda: run(FlowProbe())},
                       repeats, kept)
    pressure = np.stack([p for p, _ in kept], axis=1)  # (surfaces, steps, ny, nx)
    gap = np.stack([g for _, g in kept], axis=1)
    open_gap = np.where(pressure > 0.0, 0.0, np.maximum(gap, 0.0))
    area = (pressure > 0.0).mean(axis=(-2, -1))
    row = {"sweep": "1024 x 1024, 2 surfaces x 4 steps, pcg, periodic half-space", **times,
           "area_first": float(area[:, 0].mean()), "area_last": float(area[:, -1].mean())}
    return row, open_gap


# --------------------------------------------------------------------------- remedies


class _TimedSolver:
    """A flow solver with the wall time of its solves added up in ``seconds``."""

    def __init__(self, solver):
        self.solver, self.seconds = solver, 0.0
        self.batch_unknowns = solver.batch_unknowns

    def solve(self, matrix, rhs):
        start = time.perf_counter()
        try:
            return self.solver.solve(matrix, rhs)
        finally:
            self.seconds += time.perf_counter() - start


class _Pardiso:
    """MKL PARDISO (``pypardiso``; METIS ordering, Cholesky of the SPD matrix)."""

    def __init__(self, batch_unknowns=1 << 12):
        self.batch_unknowns = batch_unknowns

    def solve(self, matrix, rhs):
        import pypardiso
        import scipy.sparse as sp

        solver = pypardiso.PyPardisoSolver(mtype=2)  # real symmetric positive definite
        solution = solver.solve(sp.triu(matrix, format="csr"), rhs)
        solver.free_memory(everything=True)
        return solution, 0


def _nested_dissection(ny: int, nx: int, periodic: bool, leaf: int = 16) -> np.ndarray:
    """Flat indices of a (ny, nx) grid in geometric nested-dissection order: each box
    split by its middle row or column (the separator, ordered last), down to boxes of
    at most ``leaf`` elements; a grid periodic across its rows first cut by two rows."""
    index = np.arange(ny * nx).reshape(ny, nx)
    order = []

    def split(r0, r1, c0, c1, wrap):
        h, w = r1 - r0, c1 - c0
        if h <= 0 or w <= 0:
            return
        if wrap and h > 2:
            middle = r0 + h // 2
            split(r0 + 1, middle, c0, c1, False)
            split(middle + 1, r1, c0, c1, False)
            order.extend([index[r0, c0:c1], index[middle, c0:c1]])
        elif h * w <= leaf:
            order.append(index[r0:r1, c0:c1].ravel())
        elif w >= h:
            middle = c0 + w // 2
            split(r0, r1, c0, middle, False)
            split(r0, r1, middle + 1, c1, False)
            order.append(index[r0:r1, middle])
        else:
            middle = r0 + h // 2
            split(r0, middle, c0, c1, False)
            split(middle + 1, r1, c0, c1, False)
            order.append(index[middle, c0:c1])

    split(0, ny, 0, nx, periodic)
    return np.concatenate(order)


class _NestedDissectionSuperLU:
    """SuperLU with no ordering of its own (``NATURAL``) on the system permuted to the
    geometric nested-dissection order of the grid. The solver only sees the matrix, so
    the through elements are taken from :func:`roughcontact.transport.flow._clusters`
    (wrapped while the solve runs)."""

    batch_unknowns = 1 << 12

    def __init__(self, order, batch_unknowns=1 << 12):
        self.order, self.through, self.batch_unknowns = order, None, batch_unknowns

    def solve(self, matrix, rhs):
        import scipy.sparse.linalg as spla

        number = np.cumsum(self.through) - 1
        fields = self.through.size // self.order.size
        order = (self.order + self.order.size * np.arange(fields)[:, None]).ravel()
        unknowns = number[order[self.through[order]]]
        factor = spla.splu(matrix[unknowns][:, unknowns].tocsc(), permc_spec="NATURAL",
                           options={"SymmetricMode": True})
        solution = np.empty_like(rhs)
        solution[unknowns] = factor.solve(rhs[unknowns])
        return solution, 0


def _solve_timed(field, solver, spacing, sides=None):
    """The flow along x of a field or stack with ``solver``: the conductances [m^3], the
    wall time [s], the time in the solver's solves and in the clusters [s]."""
    from roughcontact.transport import flow

    timed = _TimedSolver(solver)
    clusters = _Timed(flow._clusters)

    def clusters_kept(k, a, b):
        kinds = clusters(k, a, b)
        if isinstance(solver, _NestedDissectionSuperLU):
            solver.through = kinds[0]
        return kinds

    flow._clusters = clusters_kept
    try:
        start = time.perf_counter()
        result = flow.solve_flow(field, flow.FlowSetup(spacing, "x", sides or flow.PERIODIC,
                                                       flow.HARMONIC, timed))
        elapsed = time.perf_counter() - start
    finally:
        flow._clusters = clusters.function
    return result.conductance, elapsed, timed.seconds, clusters.seconds


def remedies_60(repeats: int) -> list[dict]:
    """The flow along x of the 60 x 60 job's gaps, as the sweep calls it (sealed sides,
    a batch of 20 gaps a call; every 10th of its 90 calls: 180 gaps at 9 steps) by each
    solver, alternated: minimum wall time [s] and the largest relative difference of a
    conductance to the default's (connected gaps)."""
    from roughcontact.transport import flow
    from roughcontact.transport.probe import FlowProbe

    timed = _Timed(FlowProbe.measure, keep=True)
    FlowProbe.measure = lambda self, *a, **k: timed(self, *a, **k)
    try:
        study_job()(FlowProbe(directions=("x",)))
    finally:
        FlowProbe.measure = timed.function
    gaps = [np.where(p > 0.0, 0.0, np.maximum(g, 0.0)) for p, g in timed.calls[::10]]
    spacing = (9e-3 / 60,) * 2
    order = _nested_dissection(60, 60, False)
    stack = 20 * 3600
    solvers = {"SuperLU, MMD_AT_PLUS_A, a field a system (default)": lambda: flow.DIRECT,
               "BandedCholesky (LAPACK pbsv), a field a system": lambda: (
                   flow.BandedCholesky()),
               "SuperLU, NATURAL on a nested-dissection order, 20 fields a system": lambda: (
                   _NestedDissectionSuperLU(order, stack)),
               "PARDISO (MKL, METIS), SPD, 20 fields a system": lambda: _Pardiso(stack),
               "JacobiCG, rtol 1e-10, 20 fields a system": lambda: flow.JacobiCG()}
    best = dict.fromkeys(solvers, (None, np.inf, 0.0, 0.0))
    for _ in range(repeats):
        for name, make in solvers.items():
            runs = [_solve_timed(field, make(), spacing, flow.SEALED) for field in gaps]
            total = tuple(sum(r[i] for r in runs) for i in (1, 2, 3))
            print(f"  60 x 60, {name}: {total[0]:.2f} s", flush=True)
            if total[0] < best[name][1]:
                best[name] = (np.concatenate([r[0] for r in runs]), *total)
    reference = best[next(iter(solvers))][0]
    live = reference > 0.0
    return [{"solver": name, "field": "180 of the job's gaps", "open_fraction": float(
                np.mean([np.mean(g > 0) for g in gaps])),
             "seconds": seconds, "solver_seconds": solving, "cluster_seconds": clustering,
             "relative_difference": float(np.max(np.abs(k[live] / reference[live] - 1.0)))}
            for name, (k, seconds, solving, clustering) in best.items()]


def remedies(open_gap: np.ndarray, repeats: int, jacobi: bool) -> list[dict]:
    """(c)'s flow on one surface's gaps at the first and the last step (the lowest and
    the highest real area), along x, by each solver, alternated: minimum wall time [s],
    the default's parts, and each conductance's relative difference to the default's."""
    from roughcontact.transport import flow

    spacing = (PERIOD / GRID_1024,) * 2
    order = _nested_dissection(GRID_1024, GRID_1024, True)
    solvers = {"SuperLU, MMD_AT_PLUS_A (default)": lambda: flow.DIRECT,
               "SuperLU, NATURAL on a nested-dissection order": lambda: (
                   _NestedDissectionSuperLU(order)),
               "PARDISO (MKL, METIS), SPD": _Pardiso}
    fields = {"first step": open_gap[0, 0], "last step": open_gap[0, -1]}
    best = {(s, f): (np.nan, np.inf, 0.0, 0.0) for s in solvers for f in fields}
    for _ in range(repeats):
        for s, make in solvers.items():
            for f, field in fields.items():
                run = _solve_timed(field, make(), spacing)
                print(f"  {s}, {f}: {run[1]:.2f} s", flush=True)
                if run[1] < best[s, f][1]:
                    best[s, f] = run
    if jacobi:  # one run: minutes
        for f, field in fields.items():
            best["JacobiCG, rtol 1e-10 (one run)", f] = _solve_timed(field, flow.JacobiCG(),
                                                                     spacing)
            print(f"  JacobiCG, {f}: {best['JacobiCG, rtol 1e-10 (one run)', f][1]:.2f} s",
                  flush=True)
    rows = []
    default = next(iter(solvers))
    for (s, f), (conductance, seconds, solving, clustering) in best.items():
        conductance, reference = float(conductance), float(best[default, f][0])
        rows.append({"solver": s, "field": f, "open_fraction": float(np.mean(fields[f] > 0)),
                     "seconds": seconds, "solver_seconds": solving,
                     "cluster_seconds": clustering,
                     "relative_difference": abs(conductance / reference - 1.0)})
    return rows


# --------------------------------------------------------------------------- report


def _share(row: dict) -> float:
    return row["on"] / row["off"] - 1.0


def write(results: dict, repeats: dict) -> str:
    """flow_cost.md and flow_cost.csv of ``results`` and those of the parts run before
    (kept in flow_cost.json, so a part can be run alone); the tables' lines."""
    import pandas as pd

    kept = OUT / "flow_cost.json"
    if kept.exists():
        before = json.loads(kept.read_text())
        solvers = {"60-solvers": "remedies_60", "1024-solvers": "remedies"}
        fresh = {k: v for k, v in repeats.items() if solvers.get(k, k) in results}
        results, repeats = {**before["results"], **results}, {**before["repeats"], **fresh}
    OUT.mkdir(parents=True, exist_ok=True)
    kept.write_text(json.dumps({"results": results, "repeats": repeats}, indent=1,
                               default=float))

    lines = ["# Cost of the flow through the gap in a sweep", "",
             f"{datetime.date.today()}, {platform.processor() or platform.machine()}, "
             "one thread, 2 cores shared with other jobs; A and B alternated in one run, "
             "minimum of the repetitions given (`benchmarks/bench_flow_cost.py`). Budget: "
             "off, nothing; on, at most 25 % of the sweep.", ""]
    records = []
    if "off" in results:
        off = results["off"]
        lines += ["## Off: the study's 60 x 60 job without flow, the code before the flow "
                  f"against now (fresh subprocesses, {repeats['off']} each)", "",
                  "| code before [s] | now [s] | now / before | arrays compared | "
                  "differing |", "|---|---|---|---|---|",
                  f"| {off['before']:.2f} | {off['now']:.2f} | "
                  f"{off['now'] / off['before']:.3f} | {off['compared']} | "
                  f"{', '.join(off['differ']) or 'none (bit-identical)'} |", ""]
        if off["only_one"]:
            lines += [f"Fields in one sweep only: {', '.join(off['only_one'])}.", ""]
        records.append({"case": "off 60", "a_seconds": off["before"],
                        "b_seconds": off["now"], "ratio": off["now"] / off["before"]})
    on_rows = [results[key] for key in ("60", "1024") if key in results]
    if on_rows:
        lines += ["## On: FlowProbe() (x and y) against NO_FLOW", "",
                  "| sweep | runs each | off [s] | on [s] | (on - off) / off | "
                  "in FlowProbe.measure [s] | its share of the sweep with flow | "
                  "real area, first to last step |",
                  "|---|---|---|---|---|---|---|---|"]
        for key in ("60", "1024"):
            if key not in results:
                continue
            row = results[key]
            for variant in ("on", "on, banded", "on, banded, x only"):
                if variant not in row:
                    continue
                probe = row.get(f"{variant} probe", row["probe"])
                label = row["sweep"] + ("" if variant == "on" else
                                        f"; BandedCholesky{variant[10:]}")
                extra = row[variant] / row["off"] - 1.0
                lines.append(f"| {label} | {repeats[key]} | {row['off']:.2f} | "
                             f"{row[variant]:.2f} | {100 * extra:+.0f} % | "
                             f"{probe:.2f} | {100 * probe / row[variant]:.0f} % | "
                             f"{row['area_first']:.3f} - {row['area_last']:.3f} |")
                records.append({"case": f"{variant} {key}", "a_seconds": row["off"],
                                "b_seconds": row[variant], "ratio": row[variant] / row["off"],
                                "probe_seconds": probe,
                                "relative_difference": row.get(
                                    f"{variant} relative difference", 0.0)})
        lines.append("")
    for key, title in (("remedies_60", "60 x 60: the job's flow along x by solver "
                        f"(minimum of {repeats.get('60-solvers')} alternated)"),
                       ("remedies", "1024 x 1024: one field's flow along x by solver "
                        f"(minimum of {repeats.get('1024-solvers')} alternated)")):
        if key not in results:
            continue
        lines += [f"## {title}", "",
                  "| solver | field (open fraction) | wall [s] | in the linear solve [s] | "
                  "in the clusters [s] | conductance vs default |", "|---|---|---|---|---|---|"]
        for row in results[key]:
            lines.append(f"| {row['solver']} | {row['field']} ({row['open_fraction']:.3f}) | "
                         f"{row['seconds']:.2f} | {row['solver_seconds']:.2f} | "
                         f"{row['cluster_seconds']:.2f} | {row['relative_difference']:.1e} |")
            records.append({"case": f"{'60' if key == 'remedies_60' else '1024'} x, "
                                    f"{row['solver']}, {row['field']}",
                            "b_seconds": row["seconds"],
                            "probe_seconds": row["solver_seconds"],
                            "relative_difference": row["relative_difference"]})
        lines.append("")
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "flow_cost.md").write_text("\n".join(lines) + "\n")
    pd.DataFrame(records).to_csv(OUT / "flow_cost.csv", index=False)
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", type=Path,
                        help="a checkout of the code before the flow, for (a)")
    parser.add_argument("--skip", action="append", default=[],
                        choices=("off", "60", "60-solvers", "1024"))
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--repeats-1024", type=int, default=1,
                        help="runs of the 1024 x 1024 sweep each (one with flow: ~7 min)")
    parser.add_argument("--jacobi", action="store_true", help="JacobiCG too (minutes a field)")
    parser.add_argument("--worker", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        worker(args.worker)
        return
    results = {}
    repeats = {"off": args.repeats, "60": args.repeats, "1024": args.repeats_1024,
               "60-solvers": args.repeats, "1024-solvers": args.repeats}
    if "off" not in args.skip:
        if args.baseline is None:
            parser.error("(a) needs --baseline (or --skip off)")
        results["off"] = off_vs_baseline(args.baseline, args.repeats)
    if "60" not in args.skip:
        results["60"] = on_60(args.repeats)
    if "60-solvers" not in args.skip:
        results["remedies_60"] = remedies_60(args.repeats)
    if "1024" not in args.skip:
        results["1024"], open_gap = on_1024(args.repeats_1024)
        results["remedies"] = remedies(open_gap, args.repeats, args.jacobi)
    print(write(results, repeats))


if __name__ == "__main__":
    main()
