"""The matrix-free thermal block against the dense one, and its cost beyond 64 x 64.

(a) The paper's block (9 x 9 mm, L = 10 mm), 60 x 60, "refined" mesh: the hybrid
    thermal influence (:func:`roughcontact.transport.conduction.hybrid_thermal_influence`)
    with a 30 x 30 coarse model and with the default one
    (:func:`~roughcontact.elasticity.operators.default_coarse_grid`: 60 x 60 here, the
    fine grid itself) against the dense ``unit_conductivity_influence``: the largest
    relative error of the diagonal at least 3 elements from the sides, and of the spot
    conductance ``1^T (k R_AA)^-1 1`` of 5 Gaussian random surfaces (filtered noise,
    correlation length 0.6 mm) cut at 5, 10 and 20 % contact (the hybrid's by the
    probe's CG, tol 1e-10; the dense one's by Cholesky).
(b) 128 x 128 (default coarse model 64 x 64): build time (the coarse dense solve and
    the operator) and the time of one product; no dense referee.

Prints a markdown table.

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_thermal_hybrid.py   # ~1 min
"""

from __future__ import annotations

import time

import numpy as np
import scipy.linalg

from roughcontact.elasticity.influence import BlockGeometry
from roughcontact.transport.conduction import (
    hybrid_coarse_geometry,
    hybrid_thermal_influence,
    spot_conductance,
    unit_conductivity_influence,
)

FRACTIONS = (0.05, 0.10, 0.20)
SURFACES = 5


def gaussian_sets(grid: int, side: float, correlation: float, seed: int = 11):
    """Contact sets (fraction, mask) of ``SURFACES`` Gaussian surfaces (white noise
    filtered by a Gaussian of the correlation length) cut at each contact fraction."""
    rng = np.random.default_rng(seed)
    q = np.fft.fftfreq(grid, d=side / grid)
    qx, qy = np.meshgrid(q, q)
    spectrum = np.exp(-(np.pi * correlation) ** 2 * (qx**2 + qy**2) / 2)
    out = []
    for _ in range(SURFACES):
        height = np.fft.ifft2(np.fft.fft2(rng.standard_normal((grid, grid))) * spectrum).real
        for fraction in FRACTIONS:
            out.append((fraction, (height > np.quantile(height, 1 - fraction)).ravel()))
    return out


def dense_spot(matrix: np.ndarray, contact: np.ndarray) -> float:
    factor = scipy.linalg.cho_factor(matrix[np.ix_(contact, contact)])
    return float(scipy.linalg.cho_solve(factor, np.ones(contact.sum())).sum())


def accuracy(geom: BlockGeometry) -> list[dict]:
    n = geom.grid[0]
    start = time.perf_counter()
    dense = unit_conductivity_influence(geom)
    dense_time = time.perf_counter() - start
    iy, ix = np.divmod(np.arange(n * n), n)
    edge = np.minimum(np.minimum(ix, n - 1 - ix), np.minimum(iy, n - 1 - iy))
    sets = gaussian_sets(n, geom.size[0], 0.6e-3)
    referee = [dense_spot(dense, contact) for _, contact in sets]
    rows = []
    for label, coarse in (("30 x 30", hybrid_coarse_geometry(geom, (30, 30))),
                          ("default", hybrid_coarse_geometry(geom))):
        start = time.perf_counter()
        op = hybrid_thermal_influence(geom, coarse=coarse)
        build = time.perf_counter() - start
        diagonal = op.diagonal() / np.diag(dense) - 1
        row = {"grid": f"{n} x {n}", "coarse": f"{label} ({coarse.grid[0]})",
               "build_s": build, "dense_s": dense_time,
               "diag_interior": np.max(np.abs(diagonal[edge >= 3])),
               "diag_ring": np.max(np.abs(diagonal[edge == 0]))}
        for fraction in FRACTIONS:
            errors, products = [], []
            for (f, contact), want in zip(sets, referee, strict=True):
                if f != fraction:
                    continue
                spot = spot_conductance(op, contact, tol=1e-10)
                errors.append(spot.conductance / (op.element_area * want) - 1)
                products.append(spot.products)
            row[f"spot_{fraction:.2f}"] = (min(errors), max(errors), max(products))
        rows.append(row)
    return rows


def cost(geom: BlockGeometry, repeats: int = 5) -> dict:
    start = time.perf_counter()
    op = hybrid_thermal_influence(geom)
    build = time.perf_counter() - start
    field = np.random.default_rng(0).random(geom.n_elements)
    op.matvec(field)
    start = time.perf_counter()
    for _ in range(repeats):
        op.matvec(field)
    return {"grid": f"{geom.grid[0]} x {geom.grid[1]}", "build_s": build,
            "product_s": (time.perf_counter() - start) / repeats,
            "coarse": hybrid_coarse_geometry(geom).grid[0],
            "nbytes": getattr(op.operator, "base", op.operator).nbytes()}


def main() -> None:
    block = BlockGeometry(size=(9e-3, 9e-3), thickness=10e-3, grid=(60, 60), mesh="refined")
    rows = accuracy(block)
    print("| fine | coarse | build s | max interior diag err | max ring diag err | "
          + " | ".join(f"spot err {100 * f:.0f} % (min, max; CG products)" for f in FRACTIONS)
          + " |")
    print("|---|---|---:|---:|---:|" + "---:|" * len(FRACTIONS))
    for row in rows:
        spots = " | ".join(f"{100 * lo:+.2f} %, {100 * hi:+.2f} % ({k})"
                           for lo, hi, k in (row[f"spot_{f:.2f}"] for f in FRACTIONS))
        print(f"| {row['grid']} | {row['coarse']} | {row['build_s']:.1f} | "
              f"{100 * row['diag_interior']:.1f} % | {100 * row['diag_ring']:.1f} % | {spots} |")
    print(f"\ndense thermal build at 60 x 60: {rows[0]['dense_s']:.1f} s\n")
    big = cost(BlockGeometry(size=(9e-3, 9e-3), thickness=10e-3, grid=(128, 128),
                             mesh="refined"))
    print("| fine | coarse | build s | product s | operator MB |")
    print("|---|---:|---:|---:|---:|")
    print(f"| {big['grid']} | {big['coarse']} | {big['build_s']:.1f} | "
          f"{big['product_s']:.4f} | {big['nbytes'] / 1e6:.0f} |")


if __name__ == "__main__":
    main()
