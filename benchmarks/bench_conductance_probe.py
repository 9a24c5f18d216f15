"""The conductance probe's cost per step against the contact solve's.

A sweep of ``--surfaces`` random surfaces (Gaussian, zero mean) over ``--steps``
approaches (0.1 to 0.8 of the mean separation), on 32 x 32 and 60 x 60 grids, twice: without a probe
and with :class:`~roughcontact.transport.conduction.ConductanceProbe` (thermal and
electrical columns, CG tol 1e-10). Two bodies: a periodic half-space (the elastic
operator and the thermal one by FFT) and a free one (the elastic dense matrix, the
thermal zero-padded FFT). The two sweeps alternate, the minimum of ``--repeats`` each;
the probe's cost is their difference, reported per step and as a ratio to the sweep
without it.

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_conductance_probe.py  # ~1 min
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from roughcontact.contact import SolverOptions, sweep
from roughcontact.contact.interface import InterfaceGrid
from roughcontact.elasticity.halfspace import PeriodicHalfSpace, halfspace_influence
from roughcontact.transport.conduction import ConductanceProbe, HalfSpaceBody

SIZE, E, NU = 1e-3, 2e8, 0.3


def _gaps(n: int, m: int, seed: int = 3) -> np.ndarray:
    rng = np.random.default_rng(seed)
    q = np.fft.fftfreq(n)
    kernel = np.exp(-(np.hypot(*np.meshgrid(q, q)) / 0.1) ** 2)
    z = np.real(np.fft.ifft2(np.fft.fft2(rng.standard_normal((m, n, n))) * kernel))
    z *= 1e-6 / z.std(axis=(1, 2), keepdims=True)
    return z.max(axis=(1, 2), keepdims=True) - z


def _time(operator, gaps, approaches, grid) -> float:
    start = time.perf_counter()
    sweep(operator, gaps, approaches, element_area=grid.element_area, interface=grid,
          options=SolverOptions(stiffness=False))
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--surfaces", type=int, default=4)
    parser.add_argument("--steps", type=int, default=8)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    print("| body | grid | sweep s/step | probe s/step | probe / sweep |")
    print("|---|---:|---:|---:|---:|")
    for periodic in (True, False):
        for n in (32, 60):
            spacing = (SIZE / n, SIZE / n)
            operator = (PeriodicHalfSpace(grid=(n, n), size=(SIZE, SIZE), E=E, nu=NU)
                        if periodic else halfspace_influence((n, n), (SIZE, SIZE), E, NU))
            gaps = _gaps(n, args.surfaces)
            approaches = np.linspace(0.1, 0.8, args.steps) * gaps.mean(axis=(1, 2)).min()
            probe = ConductanceProbe(HalfSpaceBody(periodic=periodic), conductivity=50.0,
                                     resistivity=1.7e-8)
            plain_grid = InterfaceGrid(spacing, periodic)
            probed_grid = InterfaceGrid(spacing, periodic, probes=(probe,))
            _time(operator, gaps, approaches, probed_grid)  # warm: the probe's influence
            plain, probed = [], []
            for _ in range(args.repeats):
                plain.append(_time(operator, gaps, approaches, plain_grid))
                probed.append(_time(operator, gaps, approaches, probed_grid))
            base, extra = min(plain), min(probed) - min(plain)
            print(f"| {'periodic' if periodic else 'free'} | {n}^2 | "
                  f"{base / args.steps:.4f} | {extra / args.steps:.4f} | {extra / base:.2f} |")


if __name__ == "__main__":
    main()
