"""roughcontact against its peers, Tamaas and ContactMechanics (run on demand).

Part 1, periodic half-space: one cold solve of the same periodic Gaussian
surface (exponential ACF, about 20 % contact, tol 1e-10) on 256 x 256 and
512 x 512 grids, with the spectral kernel ``2 / (E* |q|)`` shared by the three
libraries (``bench_contact.SpectralHalfSpace``), so they solve the identical
discrete problem: ours by displacement control, Tamaas (PolonskyKeerRey) and
ContactMechanics (constrained_conjugate_gradients) by load control at our
solution's mean pressure. One more row solves our own discretisation
(``PeriodicHalfSpace``: element-constant pressure, Love kernel) at its own
~20 % contact, for timing only (a different discrete problem).

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
isolates the effect of the base condition.

Usage::

    .venv/bin/python benchmarks/peers.py            # ~6-8 min
    .venv/bin/python benchmarks/peers.py --quick    # 128^2 only, "refined" mesh only

Writes ``results/benchmarks/peers.csv`` and ``peers.md``. FE matrices are
cached in /tmp (``roughcontact_peers_*.npy``).
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

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from bench_contact import NU, E, periodic_problem, score  # noqa: E402

from roughcontact.contact.solver import solve  # noqa: E402

# ----------------------------------------------------------------- part 1


def periodic_case(grid: int, tol: float = 1e-10) -> list[dict]:
    import tamaas as tm
    from ContactMechanics import PeriodicFFTElasticHalfSpace
    from ContactMechanics.Optimization import constrained_conjugate_gradients

    operator, gap0, approach, size = periodic_problem(grid, spectral=True)
    start = time.perf_counter()
    ours = solve(operator, gap0, approach, tol=tol)
    ours_wall = time.perf_counter() - start
    p_ours = np.asarray(ours.pressure).reshape(grid, grid)
    mean_pressure = ours.nominal_pressure
    heights = np.ascontiguousarray(-gap0)
    modulus = E / (1 - NU**2)
    rows = []

    def record(library, wall, pressure, iterations, note=""):
        pressure = np.maximum(pressure, 0.0)
        rows.append(dict(
            part="periodic", grid=grid, library=library, wall_s=wall,
            time_ratio=wall / ours_wall, iterations=iterations,
            contact=float(np.count_nonzero(pressure > 0) / pressure.size),
            max_pressure_MPa=float(pressure.max() / 1e6),
            mean_pressure_MPa=float(pressure.mean() / 1e6),
            d_contact=float(np.count_nonzero((pressure > 0) != (p_ours > 0)) / pressure.size),
            rel_d_max_pressure=float(pressure.max() / p_ours.max() - 1),
            rel_d_mean_pressure=float(pressure.mean() / p_ours.mean() - 1),
            max_abs_dp_rel=float(np.abs(pressure - p_ours).max() / p_ours.max()),
            kkt_residual=score(operator, gap0, pressure), note=note))

    record("roughcontact (spectral)", ours_wall, p_ours, ours.iterations)

    model = tm.ModelFactory.createModel(tm.model_type.basic_2d, [size, size], [grid, grid])
    model.E, model.nu = E, NU
    solver = tm.PolonskyKeerRey(model, heights, tol)
    solver.max_iter = 100000
    start = time.perf_counter()
    solver.solve(mean_pressure)
    wall = time.perf_counter() - start
    record("tamaas", wall, np.array(model.traction).reshape(grid, grid), float("nan"))

    substrate = PeriodicFFTElasticHalfSpace((grid, grid), modulus, physical_sizes=(size, size))
    scale = float(np.abs(approach - gap0).max())
    force = mean_pressure * size * size
    start = time.perf_counter()
    solution = constrained_conjugate_gradients(
        substrate, heights, external_force=force, pentol=tol * scale,
        forcetol=tol * force / grid**2, maxiter=100000)
    wall = time.perf_counter() - start
    record("contactmechanics", wall, np.asarray(solution.jac) / operator.element_area,
           float(solution.nit), "" if solution.success else str(solution.message))

    # our own discretisation (Love element kernel): a different discrete problem
    operator2, gap2, approach2, _ = periodic_problem(grid, spectral=False)
    start = time.perf_counter()
    own = solve(operator2, gap2, approach2, tol=tol)
    wall = time.perf_counter() - start
    p_own = np.asarray(own.pressure).reshape(grid, grid)
    rows.append(dict(
        part="periodic", grid=grid, library="roughcontact (PeriodicHalfSpace, Love)",
        wall_s=wall, time_ratio=wall / ours_wall, iterations=own.iterations,
        contact=own.real_area_fraction, max_pressure_MPa=float(p_own.max() / 1e6),
        mean_pressure_MPa=float(p_own.mean() / 1e6),
        kkt_residual=own.residual, note="own discretisation and approach: not comparable"))
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


def layer_case(meshes, subs) -> list[dict]:
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
                    for sub in subs:
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
    parser.add_argument("--out", type=Path, default=ROOT / "results" / "benchmarks")
    args = parser.parse_args(argv)
    grids = (128,) if args.quick else (256, 512)
    meshes = ("refined",) if args.quick else ("refined", "converged")
    subs = (1, 9) if args.quick else (1, 5, 15)

    rows = []
    for grid in grids:
        start = time.perf_counter()
        rows += periodic_case(grid)
        print(f"periodic {grid}: {time.perf_counter() - start:.1f} s", flush=True)
    rows += layer_case(meshes, subs)

    args.out.mkdir(parents=True, exist_ok=True)
    table = pd.DataFrame(rows)
    table.to_csv(args.out / "peers.csv", index=False)
    periodic = table[table.part == "periodic"]
    layer = table[table.part == "layer"]
    text = (
        "# roughcontact vs Tamaas and ContactMechanics\n\n"
        f"Machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        "1 thread (BLAS, OpenMP). Single cold solves; wall times vary with load.\n\n"
        "## 1. Periodic half-space (identical spectral problem, tol 1e-10)\n\n"
        "d_contact: fraction of grid points whose contact state differs from ours; rel_d_*: "
        "relative difference to ours; max_abs_dp_rel: max |p - p_ours| / max p_ours; "
        "kkt_residual: our KKT residual of that library's pressure.\n\n"
        + fmt(periodic, ["grid", "library", "wall_s", "time_ratio", "iterations", "contact",
                         "max_pressure_MPa", "mean_pressure_MPa", "d_contact",
                         "rel_d_max_pressure", "rel_d_mean_pressure", "max_abs_dp_rel",
                         "kkt_residual", "note"])
        + "\n\n## 2. Finite layer, 9 x 9 mm, L = 1 mm, 60 x 60 (h = 0.15 mm), E = 1\n\n"
        "Reference: roughcontact FE block (free sides, clamped base) unless stated. "
        "E u / h at the loaded point; rel_centre = peer / FE - 1 there; near/mid/far: "
        "max |u_peer - u_FE| / u_FE(centre) over distances (0, 0.5), [0.5, 2), >= 3 mm; "
        "fe_ring_r: mean u_FE on the ring at r / u_FE(centre); d_ring_r: mean (u_peer - u_FE) "
        "there / u_FE(centre); *_far_over_centre: "
        "max |u| beyond 3 mm / u(centre); sum_ratio: total displacement ratio - 1.\n\n"
        + fmt(layer, ["nu", "load", "fe_mesh", "fe_base", "peer", "fe_centre_Eu_over_h",
                      "peer_centre_Eu_over_h", "rel_centre", "near_0_0p5mm", "mid_0p5_2mm",
                      "far_gt3mm", "fe_ring_1mm", "d_ring_1mm", "fe_ring_2mm", "d_ring_2mm",
                      "fe_far_over_centre",
                      "other_far_over_centre", "sum_ratio"])
        + "\n"
    )
    (args.out / "peers.md").write_text(text)
    print(text)
    print(f"wrote {args.out / 'peers.md'} and {args.out / 'peers.csv'}")


if __name__ == "__main__":
    main()
