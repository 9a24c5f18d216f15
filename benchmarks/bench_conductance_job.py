"""What the conductance adds to a contact job on the paper's block at 60 x 60.

The paper's block (9 x 9 mm, L = 10 mm, 60 x 60 elements, ``--mesh`` preset) and a
cell of ``--surfaces`` Gaussian surfaces (exponential-like spectrum, heights in units
of sigma) swept as a contact job sweeps them (:func:`roughcontact.contact.cell.sweep_cell`
with the job's options: mixed precision, the default method, the study's reach
P L / (E sigma) = 4, ``--steps`` approaches, batches of 20), twice: without a probe and
with the :class:`~roughcontact.transport.conduction.ConductanceProbe` through the
block (thermal and electrical columns, CG tol 1e-10). The two sweeps alternate, the
minimum of ``--repeats`` each, and the probe's own time inside the sweep (its
``measure`` calls, timed directly: the difference of two sweeps on a shared machine is
noise of its size); the thermal influence's build (its own job in a study) is timed
apart, against the elastic one's. The goal (at most +30 % of the contact job) is the
ratio ``(probe inside + thermal build) / plain sweep``.

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_conductance_job.py  # ~15 min
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import numpy as np

from roughcontact.contact import cell as cell_module
from roughcontact.contact.interface import InterfaceGrid
from roughcontact.elasticity.influence import BlockGeometry, unit_modulus_influence
from roughcontact.transport.conduction import BlockBody, ConductanceProbe
from roughcontact.transport.conduction.block import unit_conductivity_influence

SIZE, THICKNESS, N = 9e-3, 10e-3, 60


def _heights(m: int, n: int, seed: int = 5) -> np.ndarray:
    """``m`` Gaussian surfaces of unit rms height (correlation length about n / 18)."""
    rng = np.random.default_rng(seed)
    q = np.hypot(*np.meshgrid(np.fft.fftfreq(n), np.fft.fftfreq(n)))
    kernel = 1.0 / (1.0 + (q * n / 9.0) ** 2) ** 0.75
    z = np.real(np.fft.ifft2(np.fft.fft2(rng.standard_normal((m, n, n))) * kernel))
    z -= z.mean(axis=(1, 2), keepdims=True)
    return z / z.std(axis=(1, 2), keepdims=True)


class _Timed:
    """A probe that times its wrapped probe's ``measure`` (the probe's own cost inside the
    sweep, free of the other load on a shared machine)."""

    def __init__(self, probe):
        self.probe, self.seconds = probe, 0.0
        self.kind, self.columns = probe.kind, probe.columns

    def params(self):
        return self.probe.params()

    def measure(self, fields):
        start = time.perf_counter()
        out = self.probe.measure(fields)
        self.seconds += time.perf_counter() - start
        return out


def _sweep(unit, heights, geometry, steps, grid) -> tuple[float, object]:
    options = cell_module.SWEEP_OPTIONS.with_(batch_size=min(len(heights), 20))
    options = dataclasses.replace(options, interface=grid)
    start = time.perf_counter()
    result = cell_module.sweep_cell(unit, heights, geometry, 4.0, steps, options=options)
    return time.perf_counter() - start, result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--surfaces", type=int, default=60)
    parser.add_argument("--steps", type=int, default=30)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--mesh", default="paper")
    args = parser.parse_args()
    geometry = BlockGeometry(size=(SIZE, SIZE), thickness=THICKNESS, grid=(N, N),
                             mesh=args.mesh)
    builds = {"elastic": [], "thermal": []}
    for _ in range(2):
        start = time.perf_counter()
        unit = unit_modulus_influence(geometry)
        builds["elastic"].append(time.perf_counter() - start)
        start = time.perf_counter()
        unit_conductivity_influence(geometry)
        builds["thermal"].append(time.perf_counter() - start)
    body = BlockBody(BlockGeometry(size=(SIZE, SIZE), thickness=THICKNESS, grid=(N, N),
                                   mesh=args.mesh))
    heights = _heights(args.surfaces, N)
    spacing = (SIZE / N, SIZE / N)
    plain, probed, inside = [], [], []
    for _ in range(args.repeats):
        plain.append(_sweep(unit, heights, geometry, args.steps,
                            InterfaceGrid(spacing))[0])
        probe = ConductanceProbe(body, conductivity=50.0, resistivity=1.5e-7)
        probe.influence((N, N), spacing)  # built once per job: timed apart (builds)
        timed = _Timed(probe)
        seconds, result = _sweep(unit, heights, geometry, args.steps,
                                 InterfaceGrid(spacing, probes=(timed,)))
        probed.append(seconds)
        inside.append(timed.seconds)
    converged = result.probe_columns["conduction_converged"]
    base, extra, build = min(plain), min(inside), min(builds["thermal"])
    print(f"block {SIZE * 1e3:g} x {SIZE * 1e3:g} mm, L {THICKNESS * 1e3:g} mm, {N}^2, "
          f"mesh {args.mesh}; {args.surfaces} surfaces x {args.steps} steps; "
          f"minimum of {args.repeats}")
    print("| elastic build s | thermal build s | sweep s | with the probe s | probe inside s "
          "| (probe + thermal build) / sweep | converged |")
    print("|---:|---:|---:|---:|---:|---:|---:|")
    print(f"| {min(builds['elastic']):.1f} | {build:.1f} | {base:.1f} | {min(probed):.1f} | "
          f"{extra:.2f} | {(extra + build) / base:+.1%} | {converged.mean():.0%} |")


if __name__ == "__main__":
    main()
