"""The conduction room: the block's thermal influence against its elastic one, and the
convergence of the spot conductance against its referees.

(a) Build time of the paper's block (9 mm x 9 mm, L = 10 mm, 60 x 60, clamped; the
    thermal model: isothermal base, insulated sides) by
    :func:`roughcontact.transport.conduction.unit_conductivity_influence` against
    :func:`roughcontact.elasticity.influence.unit_modulus_influence`, presets "paper"
    and "refined", alternated in one process, the minimum of ``--repeats`` builds each
    (goal: the thermal build at most half the elastic one).
(b) Holm (1967): an isothermal circular spot of radius a on a half-space, C / (4 k a) - 1
    for a / dx = 4 ... 64 (dense influence below 32, the free FFT operator from 32).
(c) Muzychka, Culham & Yovanovich (2003): a centred uniform-flux source (1 x 0.5 mm) on
    a 2 x 1 mm channel 0.5 mm thick, the source's mean temperature per watt against the
    series (tests/transport/test_conduction.py), grids 8 x 4 to 32 x 16, each preset.
(d) An isothermal centred square spot (1/4 of the side) on a 1 x 1 mm block 0.5 mm
    thick: the conductance for 8 ... 64 elements per side and its observed order.
(e) Barber (2003): the spot conductance over 2 K k / E* on half-spaces, K the tangent
    stiffness of the same set.

Writes results/benchmarks/conductance.md and conductance.csv.

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_thermal_influence.py  # ~3 min
"""

from __future__ import annotations

import argparse
import csv
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "transport"))

from test_conduction import muzychka_source_resistance  # noqa: E402  (the test's referee)

from roughcontact.contact.stiffness import tangent_stiffness  # noqa: E402
from roughcontact.elasticity.halfspace import halfspace_influence  # noqa: E402
from roughcontact.elasticity.influence import BlockGeometry, unit_modulus_influence  # noqa: E402
from roughcontact.transport.conduction import (  # noqa: E402
    block_thermal_influence,
    free_thermal_halfspace,
    full_contact_resistance,
    halfspace_thermal_influence,
    spot_conductance,
    unit_conductivity_influence,
)

OUT = Path(__file__).resolve().parents[1] / "results" / "benchmarks"


def build_times(repeats: int) -> list[dict]:
    rows = []
    for mesh in ("paper", "refined"):
        geom = BlockGeometry(mesh=mesh)
        thermal, elastic = [], []
        for _ in range(repeats):
            start = time.perf_counter()
            unit_conductivity_influence(geom)
            thermal.append(time.perf_counter() - start)
            start = time.perf_counter()
            unit_modulus_influence(geom)
            elastic.append(time.perf_counter() - start)
        rows.append({"study": "build", "case": mesh, "thermal_s": min(thermal),
                     "elastic_s": min(elastic), "ratio": min(thermal) / min(elastic)})
    return rows


def holm() -> list[dict]:
    rows = []
    for elements in (4, 8, 16, 32, 64):
        dx = 1.0 / elements
        n = 2 * elements + 2
        y, x = (np.mgrid[:n, :n] - (n - 1) / 2) * dx
        mask = np.hypot(x, y) < 1.0
        operator = halfspace_thermal_influence((n, n), (n * dx,) * 2) if elements < 32 \
            else free_thermal_halfspace((n, n), (n * dx,) * 2)
        spot = spot_conductance(operator, mask, element_area=dx * dx, tol=1e-12)
        radius = np.sqrt(mask.sum() * dx * dx / np.pi)
        rows.append({"study": "holm", "case": f"a/dx={elements}", "error": spot.conductance / 4 - 1,
                     "error_equal_area": spot.conductance / (4 * radius) - 1,
                     "products": spot.products})
    return rows


def muzychka() -> list[dict]:
    rows = []
    size, thickness, k = (2e-3, 1e-3), 0.5e-3, 20.0
    expected = muzychka_source_resistance(size, (1e-3, 0.5e-3), thickness, k, terms=1200)
    for mesh in ("paper", "refined", "converged"):
        for n in (8, 16, 32):
            grid = (n, n // 2)
            geom = BlockGeometry(size=size, thickness=thickness, grid=grid, mesh=mesh)
            resistance = block_thermal_influence(geom, k)
            iy, ix = np.divmod(np.arange(grid[0] * grid[1]), grid[0])
            source = (ix >= n // 4) & (ix < 3 * n // 4) & (iy >= n // 8) & (iy < 3 * n // 8)
            mean = resistance[np.ix_(source, source)].sum() / source.sum()
            value = mean / (source.sum() * geom.element_area)
            rows.append({"study": "muzychka", "case": f"{mesh} {grid[0]}x{grid[1]}",
                         "value": value, "error": value / expected - 1})
    return rows


def block_spot() -> list[dict]:
    rows = []
    for mesh, sides in (("refined", (8, 16, 32, 64)), ("converged", (8, 16, 32))):
        values = []
        for n in sides:
            geom = BlockGeometry(size=(1e-3, 1e-3), thickness=0.5e-3, grid=(n, n), mesh=mesh)
            resistance = block_thermal_influence(geom, 1.0)
            iy, ix = np.divmod(np.arange(n * n), n)
            spot_set = (ix >= 3 * n // 8) & (ix < 5 * n // 8) & (iy >= 3 * n // 8) \
                & (iy < 5 * n // 8)
            bulk = full_contact_resistance(resistance, element_area=geom.element_area)
            spot = spot_conductance(resistance, spot_set, bulk_resistance=bulk,
                                    element_area=geom.element_area, tol=1e-12)
            values.append(spot.conductance)
            order = np.log2((values[-2] - values[-3]) / (values[-1] - values[-2])) \
                if len(values) >= 3 else np.nan
            rows.append({"study": "block_spot", "case": f"{mesh} {n}x{n}",
                         "value": spot.conductance, "bulk_share": spot.bulk_share,
                         "order": order})
    return rows


def barber() -> list[dict]:
    rows = []
    n, size = 24, (2e-3, 2e-3)
    rng = np.random.default_rng(1)
    q = np.fft.fftfreq(n)
    field = np.fft.ifft2(np.fft.fft2(rng.standard_normal((n, n)))
                         * np.exp(-60.0 * (q[:, None] ** 2 + q[None, :] ** 2))).real
    area = size[0] * size[1] / n**2
    for fraction in (0.05, 0.2, 0.6):
        contact = field > np.quantile(field, 1.0 - fraction)
        K = tangent_stiffness(halfspace_influence((n, n), size, 210e9, 0.3),
                              contact.astype(float).ravel(), element_area=area, tol=1e-11)
        C = spot_conductance(halfspace_thermal_influence((n, n), size, 45.0), contact,
                             element_area=area, tol=1e-11).conductance
        rows.append({"study": "barber", "case": f"fraction={fraction}",
                     "error": C / (2 * K * 45.0 * (1 - 0.09) / 210e9) - 1})
    return rows


def markdown(rows: list[dict]) -> str:
    load = os.getloadavg()[0]
    lines = [f"# Conduction: build times and convergence ({time.strftime('%Y-%m-%d')}, "
             f"{os.cpu_count()} cores, load {load:.1f})", ""]
    for study in ("build", "holm", "muzychka", "block_spot", "barber"):
        part = [r for r in rows if r["study"] == study]
        keys = [k for k in part[0] if k != "study"]
        lines += [f"## {study}", "", "| " + " | ".join(keys) + " |",
                  "|" + "---|" * len(keys)]
        lines += ["| " + " | ".join(f"{r[k]:.4g}" if isinstance(r[k], float) else str(r[k])
                                    for k in keys) + " |" for r in part]
        lines.append("")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    rows = build_times(args.repeats) + holm() + muzychka() + block_spot() + barber()
    OUT.mkdir(parents=True, exist_ok=True)
    keys = sorted({k for r in rows for k in r})
    with open(OUT / "conductance.csv", "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=keys)
        writer.writeheader()
        writer.writerows(rows)
    (OUT / "conductance.md").write_text(markdown(rows))
    print(markdown(rows))


if __name__ == "__main__":
    main()
