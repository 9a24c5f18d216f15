"""Loading, unloading, reloading (roughcontact.contact.cycles): the cost of a step on
each leg, and the energy identity as the steps shrink.

Part 1, cost: ``--surfaces`` Gaussian surfaces (1 um rms height) on the paper's block
(9 x 9 mm, L = 10 mm, 60 x 60, paper mesh, E 210 GPa, nu 0.3), capped at ``H`` = 2 GPa,
through two cycles of ``--steps`` steps a leg (load to the peak approach, unload to 0,
reload, unload) with the default solver (pivoting on the dense matrix) and the tangent
stiffness at every step. Each step's solve and tangent are timed inside the sweep (the
library's ``solve_many`` and tangent wrapped by timers), and the steps are grouped by
leg: the first loading, the unloadings, the reloading. The goal: an unloading step costs
no more than a loading one.

Part 2, the energy identity: the work of the load around the first cycle against the
plastic work ``H V_p`` of the stored plastic field, per surface, for 5 to 40 steps a
leg (periodic half-space of 1 x 1 mm, 64 x 64, the same surfaces' statistics: a
correlation length of 7 elements, 0.11 mm).

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_cycles.py   # ~3 min
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from roughcontact.contact import cycles
from roughcontact.contact.cycles import LoadingPath, cycle_sweep, loop_work
from roughcontact.elasticity.halfspace import PeriodicHalfSpace
from roughcontact.elasticity.influence import BlockGeometry, unit_modulus_influence

E, NU, H = 2.1e11, 0.3, 2e9


def _separations(m: int, n: int, seed: int = 3) -> np.ndarray:
    rng = np.random.default_rng(seed)
    q = np.hypot(*np.meshgrid(np.fft.fftfreq(n), np.fft.fftfreq(n)))
    z = np.real(np.fft.ifft2(np.fft.fft2(rng.standard_normal((m, n, n)))
                             * np.exp(-(q * n / 9.0) ** 2)))
    z *= 1e-6 / z.std(axis=(1, 2), keepdims=True)
    return (z.max(axis=(1, 2), keepdims=True) - z).reshape(m, -1)


def _timed(function, seconds: list):
    def wrapped(*args, **kwargs):
        start = time.perf_counter()
        out = function(*args, **kwargs)
        seconds.append(time.perf_counter() - start)
        return out
    return wrapped


def cost(surfaces: int, steps: int) -> None:
    geometry = BlockGeometry(size=(9e-3, 9e-3), thickness=10e-3, grid=(60, 60), mesh="paper",
                             E=E, nu=NU)
    matrix = unit_modulus_influence(geometry) / E
    f = _separations(surfaces, 60)
    path = LoadingPath.cycles(1.6e-6, steps, cycles=2)
    solves, tangents = [], []
    original = (cycles.solve_many, cycles._tangent)
    cycles.solve_many = _timed(original[0], solves)
    cycles._tangent = _timed(original[1], tangents)
    try:
        result = cycle_sweep(matrix, f, path, H, element_area=geometry.element_area)
    finally:
        cycles.solve_many, cycles._tangent = original
    per_step = np.array(solves) + np.array(tangents)
    legs = {"first loading": slice(1, steps + 1), "unloading": np.r_[steps + 1:2 * steps + 1,
                                                                     3 * steps + 1:4 * steps + 1],
            "reloading": slice(2 * steps + 1, 3 * steps + 1)}
    first = per_step[legs["first loading"]].mean()
    print(f"paper's block 60^2, {surfaces} surfaces, {steps} steps a leg, two cycles, H "
          f"{H / 1e9:g} GPa; converged {result.converged.mean():.0%}; at the peak: real "
          f"area {np.nanmean(result.real_area_fraction[:, steps]):.2%}, plastic area "
          f"{np.nanmean(result.plastic_area_fraction[:, steps]):.2%}")
    print("| leg | s per step (solve + tangent) | against the first loading |")
    print("|---|---:|---:|")
    for name, where in legs.items():
        mean = per_step[where].mean()
        print(f"| {name} | {mean:.3f} | {mean / first:.2f} |")


def energy(surfaces: int) -> None:
    operator = PeriodicHalfSpace(grid=(64, 64), size=(1e-3, 1e-3), E=E, nu=NU)
    f = _separations(surfaces, 64, seed=5)
    print("| steps a leg | max abs(W / (H V_p) - 1) | mean | V_p [um^3] |")
    print("|---:|---:|---:|---:|")
    for steps in (5, 10, 20, 40):
        result = cycle_sweep(operator, f, LoadingPath.cycles(1.6e-6, steps), H)
        error = loop_work(result) / (H * result.plastic_volume[:, -1]) - 1
        print(f"| {steps} | {np.abs(error).max():.2e} | {error.mean():+.2e} | "
              f"{result.plastic_volume[:, -1].mean() * 1e18:.4g} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--surfaces", type=int, default=20)
    parser.add_argument("--steps", type=int, default=10)
    args = parser.parse_args()
    cost(args.surfaces, args.steps)
    energy(args.surfaces)


if __name__ == "__main__":
    main()
