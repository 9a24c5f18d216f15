"""The contact solver on large grids: the preconditioned CG against the previous CG path.

Cases
-----
``large``
    One Gaussian surface (exponential ACF, b = 9 mm * grid / 60 scaled with
    the grid so the element size is the paper's 0.15 mm, from
    ``bench_contact.gaussian_surfaces``, seed 512) on a ``grid x grid``
    free-space half-space (Love's elements, :func:`halfspace_operator`, E =
    5.11e8 Pa, nu = 0) and periodic half-space (:class:`SpectralHalfSpace`,
    the peers' 2 / (E* |q|)), at the approaches that carry P = 2.3e5 Pa
    (about 1 % contact) and 6e6 Pa (17-18 %), tol 1e-8, one thread. Two
    paths, alternated, minimum of ``--repeats`` (default 3) CPU times
    (``time.process_time``), operator build excluded:

    - ``old``: the library before issue 28, ``method="cg"`` with
      float64 products through the full zero-padded ``rfft2`` (free space) or
      ``rfft2`` (periodic), as ``BlockOperator`` and the benchmark's
      spectral operator computed them;
    - ``new``: ``method="auto"`` (``"pcg"``), ``precision="mixed"``, on the
      library's operators (pruned float32/float64 FFTs, stencil
      preconditioner, nested grids).

    Reported: CPU s, iterations, products (``matvecs``), the operator's
    memory, contact sets (elements that differ) and ``max |dp| / max p``.

The study cell on the finite block with the hybrid operator (pcg before and
after solving the surfaces of a batch together, and cg) is
``benchmarks/bench_hybrid_cell.py``.

Writes ``results/benchmarks/solver_large.csv`` and ``solver_large.md``.

Usage::

    .venv/bin/python benchmarks/bench_solver_large.py                      # 512^2
    .venv/bin/python benchmarks/bench_solver_large.py --grid 1024
"""

from __future__ import annotations

import os

for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import scipy.fft  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from bench_contact import gaussian_surfaces  # noqa: E402

from roughcontact import contact  # noqa: E402
from roughcontact.contact import SolverOptions  # noqa: E402
from roughcontact.elasticity.halfspace import SpectralHalfSpace, _element_kernel  # noqa: E402
from roughcontact.elasticity.operators import halfspace_operator  # noqa: E402

E = 5.11e8  # Young's modulus [Pa]
NU = 0.0
#: Mean pressures [Pa] of the two contact levels (about 1 % and 17-18 % contact at 512^2).
LOADS = (2.3e5, 6e6)
OUT = ROOT / "results" / "benchmarks"


class OldFreeSpace:
    """The previous free-space product: full zero-padded ``rfft2`` in float64 [m/Pa]."""

    mean_compliance = None

    def __init__(self, grid: int, size: float):
        n, dx = grid, size / grid
        kernel = _element_kernel(n, n, dx, dx, E, NU)
        full = np.zeros((2 * n, 2 * n))
        full[:n, :n] = kernel
        full[:n, n + 1:] = kernel[:, 1:][:, ::-1]
        full[n + 1:, :] = full[1:n, :][::-1]
        self.spectrum = scipy.fft.rfft2(full)
        self.grid, self.shape, self.element_area = (n, n), (n * n, n * n), dx * dx
        self._diagonal = np.full(n * n, kernel[0, 0])

    def diagonal(self):
        return self._diagonal

    def matvec(self, pressure):
        n = self.grid[0]
        p = np.asarray(pressure, dtype=float)
        fields = p.reshape(n * n, -1).T.reshape(-1, n, n)
        u = scipy.fft.irfft2(scipy.fft.rfft2(fields, s=(2 * n, 2 * n)) * self.spectrum,
                             s=(2 * n, 2 * n))[:, :n, :n]
        return np.ascontiguousarray(u).reshape(-1, n * n).T.reshape(p.shape)

    def nbytes(self) -> int:
        return int(self.spectrum.nbytes + self._diagonal.nbytes)


class OldPeriodic(OldFreeSpace):
    """The previous spectral operator of ``bench_contact``: ``rfft2`` in float64."""

    mean_compliance = 0.0

    def __init__(self, grid: int, size: float):
        n = grid
        q = np.hypot(*np.meshgrid(2 * np.pi * np.fft.rfftfreq(n, size / n),
                                  2 * np.pi * np.fft.fftfreq(n, size / n)))
        q[0, 0] = np.inf
        self.spectrum = 2.0 * (1 - NU**2) / (E * q)
        self.grid, self.shape, self.element_area = (n, n), (n * n, n * n), (size / n) ** 2
        self._diagonal = np.full(n * n, np.fft.irfft2(self.spectrum, s=(n, n))[0, 0])

    def matvec(self, pressure):
        n = self.grid[0]
        p = np.asarray(pressure, dtype=float)
        fields = p.reshape(n * n, -1).T.reshape(-1, n, n)
        u = scipy.fft.irfft2(scipy.fft.rfft2(fields) * self.spectrum, s=(n, n))
        return np.ascontiguousarray(u).reshape(-1, n * n).T.reshape(p.shape)


def operators_of(kind: str, grid: int, size: float):
    """(old, new) operators [m/Pa] of ``kind`` ("free" or "periodic")."""
    if kind == "free":
        new = halfspace_operator((grid, grid), (size, size), NU)  # E C [m], E = 1
        return OldFreeSpace(grid, size), new
    return OldPeriodic(grid, size), SpectralHalfSpace((grid, grid), (size, size), E, NU)


def timed(function, *args, **kwargs):
    start = time.process_time()
    out = function(*args, **kwargs)
    return time.process_time() - start, out


def case_large(grid: int, repeats: int) -> list[dict]:
    size = 9e-3 * grid / 60
    z = gaussian_surfaces(1, grid, size, seed=512)[0]
    gap = z.max() - z
    rows = []
    for kind in ("free", "periodic"):
        old, new = operators_of(kind, grid, size)
        # the free-space library operator is E C: pressures in units of E
        unit = 1.0 / E if kind == "free" else 1.0
        for load in LOADS:
            reference = contact.solve(new, gap, mean_pressure=load * unit,
                                      options=SolverOptions(tol=1e-8, precision="mixed"))
            d = reference.approach
            times = {"old": [], "new": []}
            results = {}
            for _ in range(repeats):
                t, results["old"] = timed(contact.solve, old, gap, d, method="cg", tol=1e-8,
                                          precision="mixed")
                times["old"].append(t)
                t, results["new"] = timed(contact.solve, new, gap, d, tol=1e-8,
                                          precision="mixed")
                times["new"].append(t)
            base = results["old"]
            for path, operator in (("old", old), ("new", new)):
                r = results[path]
                scale = 1.0 if path == "old" or kind == "periodic" else E
                rows.append(dict(
                    case="large", operator=kind, grid=grid, load_Pa=load, path=path,
                    method=r.method, cpu_s=min(times[path]), cpu_all_s=times[path],
                    iterations=r.iterations, matvecs=r.matvecs, residual=r.residual,
                    converged=r.converged, real_area_fraction=r.real_area_fraction,
                    operator_MB=operator.nbytes() / 1e6,
                    contact_set_differences=int((r.contact_set != base.contact_set).sum()),
                    max_dp_rel=float(np.abs(r.pressure * scale - base.pressure).max()
                                     / base.max_pressure)))
                print(rows[-1], flush=True)
    return rows


def write(rows: list[dict], name: str) -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    frame = pd.DataFrame(rows)
    path = OUT / f"{name}.csv"
    if path.exists():
        old = pd.read_csv(path)
        keep = ~old["case"].isin(frame["case"].unique())
        frame = pd.concat([old[keep], frame], ignore_index=True)
    frame.to_csv(path, index=False)
    lines = [f"# {name} ({time.strftime('%Y-%m-%d %H:%M')}, load {os.getloadavg()[0]:.1f})",
             "", frame.drop(columns=["cpu_all_s"], errors="ignore").to_markdown(index=False),
             ""]
    (OUT / f"{name}.md").write_text("\n".join(lines))


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--grid", type=int, default=512)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    write(case_large(args.grid, args.repeats), "solver_large")


if __name__ == "__main__":
    main()
