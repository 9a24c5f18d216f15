"""Write the example "measurement" data/example_plateau_honed.xyz (a synthetic stand-in).

No real profilometer measurement can ship with the repository, so the example
of the measured-surface workflow (config/measured.yaml) uses this stand-in.
It is made by a process deliberately unlike the study's generator (a Johnson
translator and a linear filter, Section 2 of Kumar et al. 2006): a
two-process, plateau-honed surface as found on cylinder liners,

1. a fine Gaussian "plateau" (white noise smoothed by a Gaussian kernel of
   ``--plateau-corr-mm``, standard deviation ``--plateau-sigma-um``), its
   peaks removed by plateau honing: a smooth minimum with the level
   ``--plateau-cut-um`` (``c - s log(1 + exp((c - z) / s))``, rounding
   ``s``), plus a very fine finishing roughness;
2. deep honing grooves cut into it: ``--grooves`` straight valleys in each of
   two directions at +-``--hatch-deg`` to x (cross-hatch), each with a Gaussian
   cross-section of random depth (1-2.5 um) and width (0.05-0.08 mm) at a
   random position;
3. a tilt of the mounting (removed again by the import's plane fit), and a
   few points dropped from the deepest valleys, as optical instruments lose
   them on steep flanks (filled again by the import's ``fill_holes``);
   optionally (``--spikes``, none by default) points written at a wrong
   height, as instruments that write a lost point as a value rather than
   leaving it out do (dropouts: the import reports them and the
   ``outliers_sigma`` that removes them).

The result has a strong negative skewness and a high kurtosis that come from
the valleys, not from a Johnson law, and an anisotropic autocorrelation. It is
written as an ``x y z`` point list (x, y in mm, z in um) whose header states
that it is a synthetic stand-in, not a measurement.

Usage (from the repository root; the defaults give the committed file)::

    .venv/bin/python scripts/make_example_measurement.py
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from scipy import ndimage

from roughcontact.study.provenance import atomic_path


def plateau_honed(grid: int, spacing_mm: float, seed: int, *, plateau_sigma_um: float,
                  plateau_corr_mm: float, plateau_cut_um: float, grooves: int,
                  hatch_deg: float) -> np.ndarray:
    """Heights (grid, grid) [um] of a plateau-honed surface, axis 0 = y, axis 1 = x."""
    rng = np.random.default_rng(seed)

    def smooth_field(corr_mm, sigma_um):
        field = ndimage.gaussian_filter(rng.standard_normal((grid, grid)),
                                        corr_mm / spacing_mm, mode="wrap")
        return field / field.std() * sigma_um

    plateau = smooth_field(plateau_corr_mm, plateau_sigma_um)
    rounding = 0.12  # um: how sharply the honing stones cut the peaks off
    plateau = plateau_cut_um - rounding * np.logaddexp(0.0, (plateau_cut_um - plateau) / rounding)
    plateau += smooth_field(0.05, 0.04)  # finishing roughness on the plateaus
    y, x = np.mgrid[0:grid, 0:grid] * spacing_mm
    valleys = np.zeros((grid, grid))
    for angle in np.deg2rad([hatch_deg, -hatch_deg]):
        distance = -x * np.sin(angle) + y * np.cos(angle)  # from a line through the origin
        offsets = rng.uniform(distance.min(), distance.max(), grooves)
        depths = rng.uniform(1.0, 2.5, grooves)
        widths = rng.uniform(0.05, 0.08, grooves)
        for offset, depth, width in zip(offsets, depths, widths, strict=True):
            valleys += depth * np.exp(-(((distance - offset) / width) ** 2))
    return plateau - valleys


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", default="data/example_plateau_honed.xyz")
    parser.add_argument("--grid", type=int, default=64, help="points per side")
    parser.add_argument("--spacing-mm", type=float, default=0.1)
    parser.add_argument("--seed", type=int, default=2006)
    parser.add_argument("--plateau-sigma-um", type=float, default=0.5)
    parser.add_argument("--plateau-corr-mm", type=float, default=0.12)
    parser.add_argument("--plateau-cut-um", type=float, default=0.25)
    parser.add_argument("--grooves", type=int, default=7, help="grooves per hatch direction")
    parser.add_argument("--hatch-deg", type=float, default=25.0)
    parser.add_argument("--tilt-um-per-mm", type=float, nargs=2, default=[0.4, -0.25])
    parser.add_argument("--dropouts", type=int, default=10, help="points dropped from valleys")
    parser.add_argument("--spikes", type=int, default=0,
                        help="points written at --spike-um instead of their height")
    parser.add_argument("--spike-um", type=float, default=-20.0)
    args = parser.parse_args(argv)

    z = plateau_honed(args.grid, args.spacing_mm, args.seed,
                      plateau_sigma_um=args.plateau_sigma_um,
                      plateau_corr_mm=args.plateau_corr_mm,
                      plateau_cut_um=args.plateau_cut_um, grooves=args.grooves,
                      hatch_deg=args.hatch_deg)
    y, x = np.mgrid[0:args.grid, 0:args.grid] * args.spacing_mm
    z = z + args.tilt_um_per_mm[0] * x + args.tilt_um_per_mm[1] * y
    rng = np.random.default_rng(args.seed + 1)
    deepest = np.argsort(z - args.tilt_um_per_mm[0] * x - args.tilt_um_per_mm[1] * y,
                         axis=None)[: max(1, z.size // 50)]
    dropped = set(rng.choice(deepest, size=args.dropouts, replace=False).tolist())
    kept = np.setdiff1d(np.arange(z.size), list(dropped))
    z.ravel()[rng.choice(kept, size=args.spikes, replace=False)] = args.spike_um
    settings = {k: v for k, v in vars(args).items()  # no spikes: the committed file's
                if args.spikes or k not in ("spikes", "spike_um")}
    header = [
        "SYNTHETIC STAND-IN, NOT A MEASUREMENT.",
        "A plateau-honed (two-process) surface made by scripts/make_example_measurement.py",
        "for the example of the measured-surface workflow (config/measured.yaml):",
        "a truncated fine Gaussian plateau with cross-hatched honing grooves cut into it,",
        f"a tilt of {args.tilt_um_per_mm[0]:g}, {args.tilt_um_per_mm[1]:g} um/mm and "
        f"{args.dropouts} points dropped from the deepest valleys"
        + (f", {args.spikes} written at {args.spike_um:g} um." if args.spikes else "."),
        f"Settings: {settings}",
        f"Grid {args.grid} x {args.grid}, spacing {args.spacing_mm:g} mm; "
        "columns: x [mm], y [mm], z [um].",
    ]
    lines = [f"# {line}" for line in header]
    for k, (xv, yv, zv) in enumerate(zip(x.ravel(), y.ravel(), z.ravel(), strict=True)):
        if k not in dropped:
            lines.append(f"{xv:.3f} {yv:.3f} {zv:.4f}")
    out = Path(args.out)
    with atomic_path(out) as tmp:
        tmp.write_text("\n".join(lines) + "\n")
    print(f"wrote {out}: {len(lines) - len(header)} points of {args.grid}x{args.grid}")


if __name__ == "__main__":
    main()
