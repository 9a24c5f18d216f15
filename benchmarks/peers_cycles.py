"""Loading, unloading, reloading against ContactMechanics' plastic system (run on demand).

The same periodic problem in both codes: a Gaussian surface of rms gradient 0.08 on a
``--grid``^2 periodic cell of unit period (the setting of ContactMechanics issue #68,
whose users saw its plastic solves stop converging above P = 0.07 E*), E* = 1, the
spectral kernel ``2 / (E* |q|)`` (ours:
:class:`~roughcontact.elasticity.halfspace.SpectralHalfSpace`, theirs:
``PeriodicFFTElasticHalfSpace``), penetration hardness H = 0.1 E*. Both are
driven along one path under load control (their ``external_force``; ours
``LoadingPath(..., control="mean_pressure")``): up to ``--peak`` E* in ``--steps`` steps,
down to a tenth of it, up again and down. Theirs: ``make_plastic_system`` with a
``PlasticTopography`` (after each successful minimisation it adds the saturated points'
gaps to the plastic displacement: the model of :mod:`roughcontact.contact.cycles`), tol
``pentol = 1e-10``; a step that fails is recorded and the path goes on from its state.

Per step: both mean pressures, contact and plastic areas, plastic volumes and
``max |p - p_ours| / H``, each code's success, and the wall time of each path.

Peers are optional (the ``bench`` extra, in an environment of its own)::

    python benchmarks/peers_cycles.py --grid 128 --peak 0.09   # ~2 min
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from roughcontact.contact import SolverOptions
from roughcontact.contact.cycles import LoadingPath, cycle_sweep
from roughcontact.elasticity.halfspace import SpectralHalfSpace

HARDNESS = 0.1  # E*


def _heights(n: int, seed: int = 68) -> np.ndarray:
    """A periodic Gaussian surface of unit period with rms gradient 0.08 (self-affine,
    H = 0.8, rolled off below q = 4 * 2 pi)."""
    rng = np.random.default_rng(seed)
    q = 2 * np.pi * np.hypot(*np.meshgrid(np.fft.fftfreq(n, 1 / n), np.fft.fftfreq(n, 1 / n)))
    psd = np.where(q > 0, np.maximum(q, 8 * np.pi) ** (-2 - 2 * 0.8), 0.0)
    z = np.real(np.fft.ifft2(np.fft.fft2(rng.standard_normal((n, n))) * np.sqrt(psd)))
    dx = 1.0 / n
    gradient = np.sqrt(np.mean(((np.roll(z, -1, 1) - z) / dx) ** 2
                               + ((np.roll(z, -1, 0) - z) / dx) ** 2))
    return z * 0.08 / gradient


def ours(heights, path):
    n = heights.shape[0]
    operator = SpectralHalfSpace((n, n), (1.0, 1.0), 1.0, 0.0)
    gaps = (heights.max() - heights).reshape(1, -1)
    start = time.perf_counter()
    result = cycle_sweep(operator, gaps, path, HARDNESS,
                         options=SolverOptions(return_fields=True, stiffness=False))
    return result, time.perf_counter() - start


def theirs(heights, path):
    from ContactMechanics import PeriodicFFTElasticHalfSpace, make_plastic_system
    from SurfaceTopography import PlasticTopography, Topography

    n = heights.shape[0]
    topography = PlasticTopography(Topography(heights, physical_sizes=(1.0, 1.0),
                                              periodic=True), HARDNESS)
    system = make_plastic_system(topography, PeriodicFFTElasticHalfSpace(
        (n, n), 1.0, physical_sizes=(1.0, 1.0)))
    area = 1.0 / n**2
    rows = []
    start = time.perf_counter()
    for pressure in path.values:
        solution = system.minimize_proxy(external_force=pressure, pentol=1e-10, maxiter=100000)
        p = np.asarray(solution.jac) / area
        rows.append((bool(solution.success), p.copy(),
                     float(-topography.plastic_displ.sum() * area), int(solution.nit)))
    return rows, time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--grid", type=int, default=128)
    parser.add_argument("--peak", type=float, default=0.09, help="peak mean pressure [E*]")
    parser.add_argument("--steps", type=int, default=6)
    args = parser.parse_args()
    heights = _heights(args.grid)
    path = LoadingPath.cycles(args.peak, args.steps, unload_to=args.peak / 10, cycles=2,
                              control="mean_pressure")
    path = LoadingPath(path.values[1:], path.control)  # no zero-load step: theirs needs a load
    mine, my_seconds = ours(heights, path)
    peer, peer_seconds = theirs(heights, path)
    print(f"{args.grid}^2, rms gradient 0.08, H = {HARDNESS} E*, load control to "
          f"{args.peak} E*; wall time: ours {my_seconds:.1f} s, ContactMechanics "
          f"{peer_seconds:.1f} s")
    print("| step | P / E* | ours converged | theirs success | contact ours / theirs | "
          "plastic ours / theirs | V_p ours / theirs | max abs(dp) / H |")
    print("|---:|---:|:---:|:---:|---:|---:|---:|---:|")
    for k, value in enumerate(path.values):
        ok, p, volume, _ = peer[k]
        p_ours = mine.pressure[0, k]
        print(f"| {k} | {value:.4g} | {bool(mine.converged[0, k])} | {ok} | "
              f"{mine.real_area_fraction[0, k]:.4f} / {np.mean(p > 0):.4f} | "
              f"{mine.plastic_area_fraction[0, k]:.4f} / "
              f"{np.mean(p >= HARDNESS * (1 - 1e-9)):.4f} | "
              f"{mine.plastic_volume[0, k]:.4g} / {volume:.4g} | "
              f"{np.abs(p_ours - p.ravel()).max() / HARDNESS:.1e} |")


if __name__ == "__main__":
    main()
