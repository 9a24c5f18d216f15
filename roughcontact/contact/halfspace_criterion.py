"""When is Love's half-space enough for a block? A measured, quantity-dependent criterion.

``operator: auto`` replaces the finite block by the half-space only where
solving both models on the same surfaces shows errors within the study's
tolerance (:func:`halfspace_errors`, :func:`halfspace_meets`).
"""

from __future__ import annotations

import numpy as np

from roughcontact.contact import nondim
from roughcontact.elasticity.operators import halfspace_operator
from roughcontact.surfaces.spec import SurfaceSpec
from roughcontact.surfaces.synthetic import generate_many

__all__ = ["CALIBRATION", "CRITERION_QUANTITIES", "halfspace_errors", "halfspace_meets"]

#: Calibration of :func:`halfspace_errors`: Gaussian surfaces with correlation
#: length ``b_fraction`` of the plan size (the paper's 1 mm on 9 mm) at the
#: non-dimensional nominal pressures ``P L / (E sigma)`` (0.1, 1, 4 are 0.13,
#: 1.25 and 5 MPa for the paper's sigma = 24.5 um, E = 511 MPa).
CALIBRATION = {"surfaces": 2, "b_fraction": 1.0 / 9.0, "pressures": (0.1, 1.0, 4.0),
               "seed": 2006, "steps": 16}
#: Quantities the criterion measures: NondimSweep attribute of each.
CRITERION_QUANTITIES = {"k_P": "normalized_stiffness", "real_area": "real_area_fraction",
                        "max_pressure": "max_pressure"}


def _mean_curves(sweep, pressures) -> dict:
    """Surface-mean of each criterion quantity at the nominal pressures (interpolated)."""
    out = {}
    for name, attr in CRITERION_QUANTITIES.items():
        values = getattr(sweep, attr)
        rows = [np.interp(pressures, sweep.nominal_pressure[s], values[s], right=np.nan)
                for s in range(values.shape[0])]
        out[name] = np.nanmean(np.array(rows), axis=0)
    return out


def halfspace_errors(block_unit, grid, size, nu: float, thickness: float,
                     calibration: dict | None = None) -> dict:
    """Relative errors of the half-space model against a block model, measured by solving.

    Both models solve the same Gaussian surfaces (``CALIBRATION``) on the
    grid of ``block_unit`` (a coarse grid is enough: the two models differ by
    a correction that is smooth on the scale of the block), and the surface
    means of k_P (tangent), real area and peak pressure are compared at equal
    nominal pressure.

    Parameters
    ----------
    block_unit : ndarray (n, n) or operator
        ``E C`` [m] of the block on ``grid``.
    grid, size, nu, thickness
        Its contact grid ``(nx, ny)``, plan size [m], Poisson's ratio and
        thickness L [m].
    calibration : dict, optional
        Overrides of ``CALIBRATION``.

    Returns
    -------
    dict
        ``{"k_P": e, "real_area": e, "max_pressure": e}``, each the largest
        ``|half-space / block - 1|`` over the calibration pressures.
    """
    cal = {**CALIBRATION, **(calibration or {})}
    nx, ny = (int(g) for g in grid)
    lx, ly = (float(s) for s in size)
    spec = SurfaceSpec(grid=(nx, ny), size=(lx, ly), sigma=1.0,
                       corr_length=(cal["b_fraction"] * lx, cal["b_fraction"] * ly),
                       skew=0.0, kurt=3.0)
    heights = generate_many(spec, cal["seed"] + np.arange(cal["surfaces"]))
    half = halfspace_operator((nx, ny), (lx, ly), nu)
    pressures = np.asarray(cal["pressures"], dtype=float)
    element_area = lx * ly / (nx * ny)
    curves = []
    for model in (block_unit, half):
        # bulk compliance of the model per unit uniform pressure, in units of L
        uniform = np.ones(nx * ny)
        bulk = float(np.mean(model @ uniform)) / thickness
        end = 1.1 * max(1.0, bulk) * pressures[-1] + float(heights.max())
        approaches = np.geomspace(end / 1e3, end, int(cal["steps"]))
        sweep = nondim.solve_cell(model, heights, thickness=thickness,
                                  element_area=element_area, approaches=approaches,
                                  options=nondim.CellOptions().with_(method="cg", tol=1e-8))
        curves.append(_mean_curves(sweep, pressures))
    block, hs = curves
    return {name: float(np.nanmax(np.abs(hs[name] / block[name] - 1.0)))
            for name in CRITERION_QUANTITIES}


def halfspace_meets(errors: dict, tolerance: dict) -> bool:
    """True when every quantity with a tolerance (not None) has an error within it."""
    checked = {k: v for k, v in tolerance.items() if v is not None}
    unknown = set(checked) - set(errors)
    if unknown:
        raise ValueError(f"tolerance names unknown quantities {sorted(unknown)}; "
                         f"known: {sorted(errors)}")
    return all(errors[k] <= v for k, v in checked.items())


