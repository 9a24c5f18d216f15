"""roughcontact against its peers, Tamaas and ContactMechanics (run on demand).

ASPHER is compared in ``benchmarks/peers_aspher.py`` (``--parts aspher``
runs it here on one thread).

Part 1, periodic half-space: cold solves of the same periodic Gaussian
surface (exponential ACF, about 20 % contact, tol 1e-10) on 256 x 256 and
512 x 512 grids, with the spectral kernel ``2 / (E* |q|)`` shared by the three
libraries (``bench_contact.SpectralHalfSpace``), so they solve the identical
discrete problem: ours by displacement control, Tamaas (PolonskyKeerRey) and
ContactMechanics (constrained_conjugate_gradients) by load control at our
solution's mean pressure (from one untimed solve of ours). One more row solves
our own discretisation (``PeriodicHalfSpace``: element-constant pressure, Love
kernel) at its own ~20 % contact, for timing only (a different discrete
problem).

What is timed: the solve call alone; every run starts cold (models, solvers
and substrates are built afresh before the timer). The libraries' runs
alternate in ``--repeats`` rounds (default 3; at least 3 for numbers to
quote), the order rotated each round; the report gives each library's
minimum, the ratio of minima to ours (``time_ratio``) and the spread
(slowest / fastest run), not single runs: one cold run gave ratios anywhere
from 2.6 to 6.7 on a loaded machine. The pressures of the last round are
compared with ours (contact set, peak and mean pressure, our KKT residual).

Part 1b, periodic half-space with a hardness cap (elastic-perfectly-plastic
elements, 0 <= p <= H): the surface, kernel and approach of part 1, with H the
0.95 quantile of our elastic contact pressures at that approach, so that
about 5 % of the capped contact (1 % of the area) saturates. Ours: cg with
``hardness=H`` by displacement control; the peers by load control at our
capped solution's mean pressure (from one untimed solve of ours):

- ContactMechanics: ``constrained_conjugate_gradients(hardness=...)``
  (Polonsky & Keer 1999 with the plastic extension of Almqvist et al. 2007 /
  Weber et al. 2018); it works in forces per grid point, so the cap is
  ``H dA``, the conversion ``PlasticNonSmoothContactSystem`` makes for a
  ``PlasticTopography`` (which then also accumulates the plastic
  displacement, not needed here). Load or displacement controlled; used
  with ``external_force``.
- Tamaas: ``KatoSaturated(model, heights, tol, pmax)`` (Kato's projected
  gradient with the pressure cap, Almqvist et al. 2007), load controlled
  (``solve(mean pressure)``), on the ``basic_2d`` model, whose kernel is the
  shared one. Its iteration works in absolute units: in SI (E* ~ 5e8 Pa,
  heights ~ 1e-5 m) its error stays at its first value (about 3) and it
  returns a pressure spread over the whole grid, or does not return within
  minutes (seen on 32^2 to 128^2 grids). It is therefore run on
  the same discrete problem in dimensionless units: E* = 1, period 1,
  heights / L, pressures / E* (the kernel ``2 / (E* |q|)`` is invariant
  under that scaling), and its pressures are scaled back.
- On grids up to 32 x 32 a dense referee: scipy's bounded least squares
  (``lsq_linear``, BVLS) on the Cholesky factor of the matrix of the same
  kernel, as in tests/contact/test_hardness.py. The zero-mean kernel has a
  zero eigenvalue; ``C + c 1 1^T / n`` at the approach ``d + c mean(p)`` has
  the same solution and is positive definite.

Compared with ours: the load (mean pressure), the contact and saturated area
fractions and the points where they differ, ``max |p - p_ours| / H``, and our
capped KKT residual of each pressure. Measured (tol 1e-10, 32^2 to 512^2):
both peers and BVLS agree with ours to within 6e-10 H pointwise, with the
same contact and saturated points, and loads equal to 1e-13 (BVLS, by
displacement control: 4e-12). Tamaas' Kato iteration is slow (about 30 s on
256^2 and 4.5 min on 512^2, against 0.15 s and 1.2 s for ours and 0.55 s and
6 s for ContactMechanics), so the default grids are 32 and 256
(``--capped-grids`` for others).

Peers are optional (the ``bench`` extra, ``pip install -e '.[bench]'``): a
library that does not import is skipped and named in the report, and the
script then times ours alone; a peer without its capped solver (older
versions) is skipped in part 1b, with the reason in the report. SlipPY is
not compared: its latest release (0.5.2) installs on Python < 3.11 only.

Part 2, finite thickness: the influence matrix of roughcontact's finite-element
block (``unit_modulus_influence``; free lateral sides, bottom bonded to a rigid
base) against ContactMechanics' ``PeriodicFFTElasticHalfSpace(thickness=L)``
(periodic elastic layer bonded to a rigid flat, Carbone & Mangialardi 2008
Eq A.30) on a wide block, 9 mm x 9 mm, L = 1 mm, 60 x 60, nu = 0 and 0.3.
ContactMechanics treats pressures as point forces at grid points; the
``CM sub r`` columns put the same Green's function on an r-times finer grid,
load the r x r sub-points of an element uniformly and read the displacement
at its centre, i.e. the element-constant-pressure, centre-displacement
convention of the FE matrix. A FE block with a frictionless ("sliding") base
isolates the effect of the base condition (made without ContactMechanics too).

Usage::

    .venv/bin/python benchmarks/peers.py                      # ~12 min
    .venv/bin/python benchmarks/peers.py --quick              # 128^2 (capped: 32^2, 128^2),
                                                              #   "refined" only
    .venv/bin/python benchmarks/peers.py --parts periodic --repeats 5
    .venv/bin/python benchmarks/peers.py --parts capped --capped-grids 512  # ~16 min

Writes ``results/benchmarks/peers.csv`` and ``peers.md``. FE matrices are
cached in /tmp (``roughcontact_peers_*.npy``). BLAS and OpenMP run one thread.
"""

from __future__ import annotations

import os

for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_name] = "1"

import argparse  # noqa: E402
import importlib  # noqa: E402
import inspect  # noqa: E402
import platform  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import scipy.linalg  # noqa: E402
import scipy.optimize  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from bench_contact import NU, E, periodic_problem, score  # noqa: E402

from roughcontact.contact import SolverOptions, kkt_residual, solve  # noqa: E402

# ----------------------------------------------------------------- part 1

#: Peer libraries by import name. Each runs only where it imports (the
#: optional ``bench`` extra installs Tamaas and ContactMechanics).
PEERS = {"tamaas": "Tamaas", "ContactMechanics": "ContactMechanics"}
#: Our own discretisation of the periodic case (a different discrete problem).
LOVE = "roughcontact (PeriodicHalfSpace, Love)"
#: Peers named by the issue that have no runner here, and why.
NOT_COMPARED = {
    "SlipPY": "its latest release (0.5.2) installs on Python < 3.11 only; this project "
              "needs >= 3.11",
}


def importable(module: str) -> bool:
    """Whether ``module`` imports (an optional peer library)."""
    try:
        importlib.import_module(module)
    except ImportError:
        return False
    return True


def contactmechanics_run(grid, size, modulus, heights, interference, mean_pressure, tol,
                         element_area, hardness=None):
    """One cold ContactMechanics solve (load control at ``mean_pressure`` [Pa]), as a runner.

    ``interference`` is ``d - f`` [m] (its largest value scales the penetration
    tolerance); with ``hardness`` [Pa] the pressure is capped: the solver works
    in forces per grid point, so the cap is ``H dA`` (as its
    ``PlasticNonSmoothContactSystem`` converts it).
    """
    from ContactMechanics import PeriodicFFTElasticHalfSpace
    from ContactMechanics.Optimization import constrained_conjugate_gradients

    substrate = PeriodicFFTElasticHalfSpace((grid, grid), modulus, physical_sizes=(size, size))
    scale = float(np.abs(interference).max())
    force = mean_pressure * size * size
    cap = {} if hardness is None else {"hardness": hardness * element_area}
    start = time.perf_counter()
    solution = constrained_conjugate_gradients(
        substrate, heights, external_force=force, pentol=tol * scale,
        forcetol=tol * force / grid**2, maxiter=100000, **cap)
    wall = time.perf_counter() - start
    return (wall, np.asarray(solution.jac) / element_area, float(solution.nit),
            "" if solution.success else str(solution.message))


def periodic_runners(grid: int, tol: float, peers) -> tuple[dict, dict]:
    """Cold-solve runners of the periodic problem on a ``grid`` x ``grid`` grid.

    Returns ``(runners, context)``: each runner takes no argument and returns
    ``(wall [s], pressure (grid, grid) [Pa], iterations, note)``, with only the
    solve inside the timer (models, solvers and substrates are built before
    it, afresh for every run, so no run starts from another's solution).
    ``context`` holds the problem and our untimed reference solution, against
    which every pressure is compared.
    """
    operator, gap0, approach, size = periodic_problem(grid, spectral=True)
    # untimed: the target load
    reference = solve(operator, gap0, approach, options=SolverOptions(tol=tol))
    mean_pressure = reference.nominal_pressure
    heights = np.ascontiguousarray(-gap0)
    modulus = E / (1 - NU**2)

    def ours():
        start = time.perf_counter()
        result = solve(operator, gap0, approach, options=SolverOptions(tol=tol))
        wall = time.perf_counter() - start
        return wall, np.asarray(result.pressure).reshape(grid, grid), result.iterations, ""

    def tamaas():
        import tamaas as tm

        model = tm.ModelFactory.createModel(tm.model_type.basic_2d, [size, size], [grid, grid])
        model.E, model.nu = E, NU
        solver = tm.PolonskyKeerRey(model, heights, tol)
        solver.max_iter = 100000
        start = time.perf_counter()
        solver.solve(mean_pressure)
        wall = time.perf_counter() - start
        return wall, np.array(model.traction).reshape(grid, grid), float("nan"), ""

    def contactmechanics():
        return contactmechanics_run(grid, size, modulus, heights, approach - gap0,
                                    mean_pressure, tol, operator.element_area)

    # our own discretisation (Love element kernel): a different discrete problem
    operator_love, gap_love, approach_love, _ = periodic_problem(grid, spectral=False)

    def ours_love():
        start = time.perf_counter()
        result = solve(operator_love, gap_love, approach_love, options=SolverOptions(tol=tol))
        wall = time.perf_counter() - start
        return (wall, np.asarray(result.pressure).reshape(grid, grid), result.iterations,
                "own discretisation and approach: not comparable")

    runners = {"roughcontact (spectral)": ours}
    if "tamaas" in peers:
        runners["tamaas"] = tamaas
    if "ContactMechanics" in peers:
        runners["contactmechanics"] = contactmechanics
    runners[LOVE] = ours_love
    context = dict(operator=operator, gap0=gap0,
                   pressure=np.asarray(reference.pressure).reshape(grid, grid),
                   love=(operator_love, gap_love, approach_love))
    return runners, context



def alternate(runners: dict, repeats: int) -> tuple[dict, dict]:
    """Run every runner ``repeats`` times, alternating, the order rotated each round.

    Round r starts with the r-th runner (mod their number), so that none
    always follows the same other. Returns ``(walls, outputs)``: each
    runner's wall times [s], and what its last run returned after the wall
    time.
    """
    names = list(runners)
    walls = {name: [] for name in names}
    outputs = {}
    for round_ in range(repeats):
        shift = round_ % len(names)
        for name in names[shift:] + names[:shift]:
            wall, *outputs[name] = runners[name]()
            walls[name].append(wall)
    return walls, outputs


def periodic_case(grid: int, repeats: int, peers, tol: float = 1e-10) -> list[dict]:
    """Minimum wall time of ``repeats`` alternating cold solves per library.

    Round r runs the libraries in turn, the order rotated by r so that none
    always follows the same other; the minimum over the rounds is kept per
    library, and ``time_ratio`` is its minimum over ours.
    """
    runners, context = periodic_runners(grid, tol, peers)
    names = list(runners)
    walls, outputs = alternate(runners, repeats)
    p_ours = context["pressure"]
    best_ours = min(walls["roughcontact (spectral)"])
    rows = []
    for name in names:
        pressure, iterations, note = outputs[name]
        pressure = np.maximum(pressure, 0.0)
        row = dict(part="periodic", grid=grid, library=name, runs=len(walls[name]),
                   wall_min_s=min(walls[name]), spread=max(walls[name]) / min(walls[name]),
                   time_ratio=min(walls[name]) / best_ours, iterations=iterations,
                   contact=float(np.count_nonzero(pressure > 0) / pressure.size),
                   max_pressure_MPa=float(pressure.max() / 1e6),
                   mean_pressure_MPa=float(pressure.mean() / 1e6), note=note)
        if name != LOVE:  # the same discrete problem as ours: compare the solutions
            row.update(
                d_contact=float(np.count_nonzero((pressure > 0) != (p_ours > 0))
                                / pressure.size),
                rel_d_max_pressure=float(pressure.max() / p_ours.max() - 1),
                rel_d_mean_pressure=float(pressure.mean() / p_ours.mean() - 1),
                max_abs_dp_rel=float(np.abs(pressure - p_ours).max() / p_ours.max()),
                kkt_residual=score(context["operator"], context["gap0"], pressure))
        else:
            row.update(kkt_residual=kkt_residual(*context["love"], pressure))
        rows.append(row)
    return rows


# ----------------------------------------------------------------- part 1b

#: Quantile of the elastic contact pressures taken as the hardness: about 5 %
#: of the contact saturates once the cap is on (about 1 % of the area).
HARDNESS_QUANTILE = 0.95
#: A pressure within this fraction of H counts as saturated (the peers return
#: H up to rounding: ContactMechanics in force units, Tamaas scaled).
SATURATED_RTOL = 1e-9
#: Largest grid on which the dense bounded least-squares referee runs.
BVLS_MAX_GRID = 32
BVLS = "BVLS (scipy lsq_linear, dense)"


def capped_support(peers) -> tuple[list[str], dict]:
    """The importable peers that have a capped solver, and why the others are left out."""
    supported, missing = [], {}
    for module in peers:
        if module == "tamaas":
            import tamaas as tm

            if hasattr(tm, "KatoSaturated"):
                supported.append(module)
            else:
                missing["Tamaas (capped)"] = f"tamaas {tm.__version__} has no KatoSaturated"
        elif module == "ContactMechanics":
            import ContactMechanics
            from ContactMechanics.Optimization import constrained_conjugate_gradients

            parameters = inspect.signature(constrained_conjugate_gradients).parameters
            if "hardness" in parameters:
                supported.append(module)
            else:
                missing["ContactMechanics (capped)"] = (
                    f"ContactMechanics {ContactMechanics.__version__}: "
                    "constrained_conjugate_gradients takes no hardness")
    return supported, missing


def capped_runners(grid: int, tol: float, peers) -> tuple[dict, dict]:
    """Cold-solve runners of the capped periodic problem (0 <= p <= H) on one grid.

    The surface, kernel and approach of :func:`periodic_runners`; the cap
    ``H`` is the ``HARDNESS_QUANTILE`` of our elastic contact pressures at
    that approach. Ours solves by displacement control with ``hardness=H``;
    the peers by load control at our capped solution's mean pressure. Runners
    return ``(wall [s], pressure (grid, grid) [Pa], iterations, note)``;
    ``context`` holds the problem, ``H`` and our untimed reference.
    """
    operator, gap0, approach, size = periodic_problem(grid, spectral=True)
    elastic = np.asarray(solve(operator, gap0, approach,
                               options=SolverOptions(tol=tol)).pressure).ravel()
    hardness = float(np.quantile(elastic[elastic > 0], HARDNESS_QUANTILE))
    reference = solve(operator, gap0, approach, hardness=hardness,  # untimed
                      options=SolverOptions(tol=tol))
    mean_pressure = reference.nominal_pressure
    heights = np.ascontiguousarray(-gap0)
    modulus = E / (1 - NU**2)

    def ours():
        start = time.perf_counter()
        result = solve(operator, gap0, approach, hardness=hardness, options=SolverOptions(tol=tol))
        wall = time.perf_counter() - start
        return (wall, np.asarray(result.pressure).reshape(grid, grid), result.iterations,
                "" if result.converged else "not converged")

    def tamaas():
        # KatoSaturated steps in absolute units: in SI (E* ~ 5e8 Pa, heights
        # ~ 1e-5 m) it stalls or stops at a uniform pressure. Scaled by E*
        # (pressures) and the period (lengths) the discrete problem is the
        # same (u' = 2 p' / |q'| with u' = u / L, q' = q L, p' = p / E*).
        import tamaas as tm

        model = tm.ModelFactory.createModel(tm.model_type.basic_2d, [1.0, 1.0], [grid, grid])
        model.E, model.nu = 1.0, 0.0
        solver = tm.KatoSaturated(model, heights / size, tol, hardness / modulus)
        solver.max_iter = 100000
        solver.dump_freq = 100000
        start = time.perf_counter()
        solver.solve(mean_pressure / modulus)
        wall = time.perf_counter() - start
        return (wall, np.array(model.traction).reshape(grid, grid) * modulus, float("nan"),
                "dimensionless units (E* = 1, L = 1)")

    def contactmechanics():
        return contactmechanics_run(grid, size, modulus, heights, approach - gap0,
                                    mean_pressure, tol, operator.element_area, hardness)

    def bvls():
        # C has a zero eigenvalue (zero-mean kernel); C + c 11^T / n at the
        # approach d + c mean(p_ours) has the same solution and is positive
        # definite. min |L^T p - L^-1 b| over 0 <= p <= H, C = L L^T, b = d - f.
        n = grid * grid
        matrix = operator.matvec(np.eye(n))
        compliance = float(matrix[0, 0])
        start = time.perf_counter()
        factor = np.linalg.cholesky(0.5 * (matrix + matrix.T) + compliance / n)
        target = scipy.linalg.solve_triangular(
            factor, approach + compliance * mean_pressure - gap0.ravel(), lower=True)
        solution = scipy.optimize.lsq_linear(factor.T, target, bounds=(0.0, hardness),
                                             method="bvls", tol=1e-15, max_iter=50 * n)
        wall = time.perf_counter() - start
        return (wall, solution.x.reshape(grid, grid), float(solution.nit),
                "dense referee, displacement control" if solution.status > 0
                else f"BVLS: {solution.message}")

    runners = {"roughcontact (spectral)": ours}
    if "tamaas" in peers:
        runners["tamaas"] = tamaas
    if "ContactMechanics" in peers:
        runners["contactmechanics"] = contactmechanics
    if grid <= BVLS_MAX_GRID:
        runners[BVLS] = bvls
    context = dict(operator=operator, gap0=gap0, hardness=hardness,
                   pressure=np.asarray(reference.pressure).reshape(grid, grid))
    return runners, context


def capped_case(grid: int, repeats: int, peers, tol: float = 1e-10) -> list[dict]:
    """Capped periodic solves: minimum wall times and agreement with ours.

    Rounds as in :func:`periodic_case`. Every pressure is compared with our
    untimed reference: mean pressure (the load), contact and saturated
    (``p >= H (1 - SATURATED_RTOL)``) area fractions and the points where
    they differ, ``max |p - p_ours| / H``, and our capped KKT residual of it
    (approach fitted on its elastic contact).
    """
    runners, context = capped_runners(grid, tol, peers)
    hardness, p_ours = context["hardness"], context["pressure"]
    walls, outputs = alternate(runners, repeats)
    best_ours = min(walls["roughcontact (spectral)"])

    def plastic(pressure):
        return pressure >= hardness * (1 - SATURATED_RTOL)

    rows = []
    for name in runners:
        raw, iterations, note = outputs[name]
        pressure = np.clip(raw, 0.0, hardness)
        contact = pressure > 0
        rows.append(dict(
            part="capped", grid=grid, library=name, runs=len(walls[name]),
            wall_min_s=min(walls[name]), spread=max(walls[name]) / min(walls[name]),
            time_ratio=min(walls[name]) / best_ours, iterations=iterations,
            hardness_MPa=hardness / 1e6, max_p_over_H=float(raw.max() / hardness),
            mean_pressure_MPa=float(pressure.mean() / 1e6),
            rel_d_mean_pressure=float(pressure.mean() / p_ours.mean() - 1),
            contact=float(contact.mean()), plastic=float(plastic(pressure).mean()),
            plastic_share=float(plastic(pressure).sum() / max(contact.sum(), 1)),
            d_contact=float(np.mean(contact != (p_ours > 0))),
            d_plastic=float(np.mean(plastic(pressure) != plastic(p_ours))),
            max_abs_dp_over_H=float(np.abs(pressure - p_ours).max() / hardness),
            kkt_residual=score(context["operator"], context["gap0"], pressure, hardness),
            note=note))
    return rows


# ----------------------------------------------------------------- part 2

SIZE2, THICK, N = 9e-3, 1e-3, 60


def fe_matrix(nu: float, mesh: str, base: str) -> np.ndarray:
    """E * C of the FE block [m] (symmetric part), cached in /tmp."""
    from roughcontact.elasticity.influence import BlockGeometry, unit_modulus_influence

    cache = Path(f"/tmp/roughcontact_peers_{mesh}_{base}_nu{nu:g}.npy")
    if cache.exists():
        return np.load(cache)
    geom = BlockGeometry(size=(SIZE2, SIZE2), thickness=THICK, grid=(N, N), E=1.0, nu=nu,
                         base=base, mesh=mesh)
    matrix = unit_modulus_influence(geom)
    np.save(cache, matrix)
    return matrix


def cm_response(nu: float, load: np.ndarray, sub: int) -> np.ndarray:
    """ContactMechanics layer, E = 1: centre displacement [m] per element pressure.

    ``load`` (N, N) element pressures [Pa], index [iy, ix]. Each element is
    split into sub x sub grid points (sub odd) carrying point forces
    ``p * area / sub^2``; the displacement is read at the element centres.
    """
    from ContactMechanics import PeriodicFFTElasticHalfSpace

    n = N * sub
    layer = PeriodicFFTElasticHalfSpace((n, n), 1.0, physical_sizes=(SIZE2, SIZE2),
                                        thickness=THICK, poisson=nu)
    fine = np.kron(load, np.ones((sub, sub))) * layer.area_per_pt
    u = -layer.evaluate_disp(np.ascontiguousarray(fine.T)).T  # CM: forces < 0 push in
    return u[sub // 2 :: sub, sub // 2 :: sub]


def distance_map(iy: int, ix: int) -> np.ndarray:
    y, x = np.mgrid[0:N, 0:N]
    return np.hypot(y - iy, x - ix) * SIZE2 / N  # [m]


def compare(fe: np.ndarray, other: np.ndarray, dist: np.ndarray, centre) -> dict:
    """Relative differences of ``other`` against the FE response."""
    ref = fe[centre]

    def band(lo, hi):
        mask = (dist >= lo) & (dist < hi)
        return float(np.abs(other[mask] - fe[mask]).max() / ref)

    def ring(r):  # mean over the ring at distance ~ r, relative to the FE centre value
        mask = np.abs(dist - r) < 0.5 * SIZE2 / N
        return float(fe[mask].mean() / ref), float((other[mask] - fe[mask]).mean() / ref)

    return dict(
        rel_centre=float(other[centre] / ref - 1),
        near_0_0p5mm=band(1e-12, 0.5e-3), mid_0p5_2mm=band(0.5e-3, 2e-3),
        far_gt3mm=band(3e-3, 1.0),
        fe_ring_1mm=ring(1e-3)[0], d_ring_1mm=ring(1e-3)[1],
        fe_ring_2mm=ring(2e-3)[0], d_ring_2mm=ring(2e-3)[1],
        fe_far_over_centre=float(np.abs(fe[dist >= 3e-3]).max() / ref),
        other_far_over_centre=float(np.abs(other[dist >= 3e-3]).max() / ref),
        sum_ratio=float(other.sum() / fe.sum() - 1),
    )


def layer_case(meshes, subs, contactmechanics: bool = True) -> list[dict]:
    """FE block responses against ContactMechanics' layer (and the sliding base).

    Without ``contactmechanics`` only the sliding-against-clamped rows are made.
    """
    rows = []
    h = SIZE2 / N
    loads = {
        "centre element (30,30)": ((30, 30), lambda p: p.__setitem__((30, 30), 1.0)),
        "1.5 mm patch (10x10) at centre": ((30, 30), lambda p: p.__setitem__(
            (slice(25, 35), slice(25, 35)), 1.0)),
        "edge element (30,0)": ((30, 0), lambda p: p.__setitem__((30, 0), 1.0)),
    }
    for nu in (0.0, 0.3):
        for mesh in meshes:
            for base in ("clamped", "sliding"):
                if base == "sliding" and mesh != meshes[0]:
                    continue
                start = time.perf_counter()
                matrix = fe_matrix(nu, mesh, base)
                build = time.perf_counter() - start
                for name, (centre, fill) in loads.items():
                    p = np.zeros((N, N))
                    fill(p)
                    fe = (matrix @ p.ravel()).reshape(N, N)
                    dist = distance_map(*centre)
                    base_row = dict(part="layer", nu=nu, load=name, fe_mesh=mesh, fe_base=base,
                                    fe_build_s=build, fe_centre_Eu_over_h=fe[centre] / h)
                    if base == "sliding":  # against the clamped FE block, same mesh
                        clamped = (fe_matrix(nu, mesh, "clamped") @ p.ravel()).reshape(N, N)
                        base_row.update(fe_centre_Eu_over_h=clamped[centre] / h)
                        rows.append(dict(base_row, peer="FE sliding base (ref: FE clamped)",
                                         peer_centre_Eu_over_h=fe[centre] / h,
                                         **compare(clamped, fe, dist, centre)))
                        continue
                    for sub in subs if contactmechanics else ():
                        other = cm_response(nu, p, sub)
                        label = "CM point forces" if sub == 1 else f"CM sub r={sub}"
                        rows.append(dict(base_row, peer=label,
                                         peer_centre_Eu_over_h=other[centre] / h,
                                         **compare(fe, other, dist, centre)))
                print(f"layer nu={nu} {mesh} {base}: FE {build:.1f} s", flush=True)
    return rows


# ----------------------------------------------------------------- report


def fmt(table, columns) -> str:
    sub = table.reindex(columns=columns)
    return sub.to_markdown(index=False, floatfmt=".4g")


def main(argv=None) -> None:
    import pandas as pd

    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--repeats", type=int, default=3,
                        help="rounds of alternating cold solves; the minimum is kept (>= 3 "
                             "for numbers to quote)")
    parser.add_argument("--parts", nargs="+", choices=("periodic", "capped", "layer", "aspher"),
                        default=["periodic", "capped", "layer"],
                        help="aspher: benchmarks/peers_aspher.py on one thread (its own "
                             "report; run that script for two threads or other options)")
    parser.add_argument("--capped-grids", nargs="+", type=int, default=None,
                        help="grids of the capped part (default 32 256; --quick: 32 128); "
                             f"a BVLS referee runs on grids <= {BVLS_MAX_GRID}")
    parser.add_argument("--out", type=Path, default=ROOT / "results" / "benchmarks")
    args = parser.parse_args(argv)
    if args.repeats < 1:
        parser.error("--repeats must be at least 1")
    grids = (128,) if args.quick else (256, 512)
    capped_grids = args.capped_grids or ((32, 128) if args.quick else (32, 256))
    meshes = ("refined",) if args.quick else ("refined", "converged")
    subs = (1, 9) if args.quick else (1, 5, 15)
    peers = [module for module in PEERS if importable(module)]
    skipped = {PEERS[module]: "not importable (install the bench extra)"
               for module in PEERS if module not in peers}
    skipped.update(NOT_COMPARED)
    capped_peers, missing = capped_support(peers)
    if "capped" in args.parts:
        skipped.update(missing)
    for name, why in skipped.items():
        print(f"skipped {name}: {why}", flush=True)

    if "aspher" in args.parts:
        import peers_aspher

        peers_aspher.main(["--repeats", str(args.repeats), "--out", str(args.out)]
                          + (["--grids", "128"] if args.quick else []))
    rows = []
    for grid in grids if "periodic" in args.parts else ():
        start = time.perf_counter()
        rows += periodic_case(grid, args.repeats, peers)
        print(f"periodic {grid}: {time.perf_counter() - start:.1f} s", flush=True)
    for grid in capped_grids if "capped" in args.parts else ():
        start = time.perf_counter()
        rows += capped_case(grid, args.repeats, capped_peers)
        print(f"capped {grid}: {time.perf_counter() - start:.1f} s", flush=True)
    if "layer" in args.parts:
        rows += layer_case(meshes, subs, contactmechanics="ContactMechanics" in peers)

    args.out.mkdir(parents=True, exist_ok=True)
    table = pd.DataFrame(rows)
    table.to_csv(args.out / "peers.csv", index=False)
    periodic, capped, layer = (table[table.part == part] if rows else table
                               for part in ("periodic", "capped", "layer"))
    not_compared = "".join(f"- {name}: {why}\n" for name, why in skipped.items())
    sections = {
        "periodic": (
            "## 1. Periodic half-space (identical spectral problem, tol 1e-10)\n\n"
            f"Cold solves in {args.repeats} rounds, the libraries alternating (order rotated "
            "each round); wall_min_s: the fastest of a library's runs; time_ratio: that "
            "minimum over ours; spread: slowest over fastest run. "
            "d_contact: fraction of grid points whose contact state differs from ours; "
            "rel_d_*: relative difference to ours; max_abs_dp_rel: max |p - p_ours| / "
            "max p_ours; kkt_residual: our KKT residual of that library's pressure (the Love "
            "row: of its own problem).\n\n"
            + fmt(periodic, ["grid", "library", "runs", "wall_min_s", "time_ratio", "spread",
                             "iterations", "contact",
                             "max_pressure_MPa", "mean_pressure_MPa", "d_contact",
                             "rel_d_max_pressure", "rel_d_mean_pressure", "max_abs_dp_rel",
                             "kkt_residual", "note"])),
        "capped": (
            "## 1b. Periodic half-space with a hardness cap, 0 <= p <= H (identical "
            "spectral problem, tol 1e-10)\n\n"
            f"The surface, kernel and approach of part 1; H: the {HARDNESS_QUANTILE:g} "
            "quantile of our elastic contact pressures there. Ours: cg, displacement "
            "control, hardness=H; ContactMechanics: constrained_conjugate_gradients("
            "hardness=H dA); Tamaas: KatoSaturated(pmax=H) in dimensionless units (E* = 1, "
            "period 1); both peers at our mean pressure. "
            f"{BVLS}: an independent referee on the small grid (its time includes the "
            "Cholesky factorisation of the dense matrix). Rounds as in part 1. "
            "plastic: fraction of grid points at p >= H (1 - "
            f"{SATURATED_RTOL:g}); plastic_share: of the contact; d_contact, d_plastic: "
            "fraction of points whose state differs from ours; max_abs_dp_over_H: "
            "max |p - p_ours| / H; kkt_residual: our capped KKT residual of that pressure "
            "(approach fitted on its elastic contact 0 < p < H).\n\n"
            + fmt(capped, ["grid", "library", "runs", "wall_min_s", "time_ratio", "spread",
                           "iterations", "hardness_MPa", "mean_pressure_MPa",
                           "rel_d_mean_pressure", "contact", "plastic", "plastic_share",
                           "d_contact", "d_plastic", "max_p_over_H", "max_abs_dp_over_H",
                           "kkt_residual", "note"])),
        "layer": (
            "## 2. Finite layer, 9 x 9 mm, L = 1 mm, 60 x 60 (h = 0.15 mm), E = 1\n\n"
            "Reference: roughcontact FE block (free sides, clamped base) unless stated. "
            "E u / h at the loaded point; rel_centre = peer / FE - 1 there; near/mid/far: "
            "max |u_peer - u_FE| / u_FE(centre) over distances (0, 0.5), [0.5, 2), >= 3 mm; "
            "fe_ring_r: mean u_FE on the ring at r / u_FE(centre); d_ring_r: mean "
            "(u_peer - u_FE) there / u_FE(centre); *_far_over_centre: "
            "max |u| beyond 3 mm / u(centre); sum_ratio: total displacement ratio - 1.\n\n"
            + fmt(layer, ["nu", "load", "fe_mesh", "fe_base", "peer", "fe_centre_Eu_over_h",
                          "peer_centre_Eu_over_h", "rel_centre", "near_0_0p5mm",
                          "mid_0p5_2mm", "far_gt3mm", "fe_ring_1mm", "d_ring_1mm",
                          "fe_ring_2mm", "d_ring_2mm", "fe_far_over_centre",
                          "other_far_over_centre", "sum_ratio"])),
    }
    text = (
        "# roughcontact vs Tamaas and ContactMechanics\n\n"
        f"Machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        "1 thread (BLAS, OpenMP); wall times vary with load.\n\n"
        + (f"Not compared:\n\n{not_compared}\n" if not_compared else "")
        + "\n\n".join(body for part, body in sections.items() if part in args.parts)
        + "\n"
    )
    (args.out / "peers.md").write_text(text)
    print(text)
    print(f"wrote {args.out / 'peers.md'} and {args.out / 'peers.csv'}")


if __name__ == "__main__":
    main()
