"""Preparing a measured height map for the contact study.

The steps, in the order :func:`prepare` applies them (each recorded in
:attr:`roughcontact.surfaces.measured.Measurement.preparation`):

0. ``crop``: a window ``(x0, y0, Lx, Ly)`` [m] from the first point
   (:func:`crop_window`).
1. Holes (missing points, or points the instrument masked as undefined) are
   refused, or, if their fraction is at most ``fill_holes``, filled by a
   discrete Laplace (harmonic) interpolation of the heights less the
   least-squares plane of the known points (:func:`fill_missing`): every
   missing point equals the mean of its 4 neighbours (fewer at the edges,
   which gives a zero normal slope there), solved jointly for all missing
   points with a sparse direct solver. It reproduces any plane exactly, is
   second-order accurate inside a hole and first-order at the edges; it
   does not invent roughness, so a filled hole is smoother than the
   measured surface around it. Known points are not changed.
2. The least-squares plane ``a + b x + c y`` is removed (form and tilt of the
   mounting, :func:`remove_plane`), which also leaves heights of zero mean;
   with ``form_degree`` k >= 2, then the least-squares polynomial of total
   degree k in x and y (:func:`remove_polynomial`; k = 2 takes out a
   sphere's or a cylinder's form to second order). Heights that are then
   flat (:data:`FLAT_RELATIVE`: a constant map, or one that is its form)
   are refused.
3. ``outliers_sigma``: points farther than k sigma from the mean plane are
   counted, filled as holes and the form removed again.
4. ``decimate`` (an integer: means of k x k blocks, :func:`decimate`) or
   ``resample_grid`` ([nx, ny]: linear interpolation over the same plan
   size, :func:`resample`) gives the contact grid, and the mean is removed.

Heights in any unit (metres when called by
:func:`roughcontact.surfaces.measured.load_measurement`), spacings in metres;
arrays ``(ny, nx)``.
"""

from __future__ import annotations

import logging
import math

import numpy as np
import scipy  # its submodules load on first use (scipy's lazy attributes)

from roughcontact.errors import MeasurementError
from roughcontact.surfaces.defects import (
    SPIKE_ROBUST_SIGMAS,
    find_spikes,
    largest_complete_window,
    spikes_matter,
)
from roughcontact.surfaces.readers import MIN_POINTS

log = logging.getLogger(__name__)


def missing_message(source, missing: int, total: int, absent: int = 0) -> str:
    """How many points are missing, as a sentence naming the source."""
    detail = (f" ({absent} grid points absent from the point list, {missing - absent} nan)"
              if absent else " (nan values)")
    return (f"{source}: {missing} of {total} points ({100.0 * missing / total:.3g} %) are "
            f"missing{detail}")


def fill_missing(heights: np.ndarray, max_fraction: float = 0.0, *, source="heights",
                 absent: int = 0, window=None) -> tuple[np.ndarray, int]:
    """Fill missing (NaN) points by discrete Laplace interpolation.

    The least-squares plane of the known points is removed first and added
    back at the end. For the residual ``r``, ``sum_(j in N(i)) (r_j - r_i) = 0``
    is solved for every missing point ``i`` jointly, ``N(i)`` its 4 neighbours
    inside the grid (a zero normal slope of ``r`` at the edges), with the known
    points as boundary values. The matrix is a graph Laplacian with Dirichlet
    rows, symmetric positive definite whenever one point is known; it is solved
    by ``scipy.sparse.linalg.spsolve``. Planes are reproduced exactly, at the
    edges too; inside a hole the fill is smooth (it adds no roughness).

    Parameters
    ----------
    heights : ndarray (ny, nx)
        Heights [any unit] with NaN at missing points.
    max_fraction : float
        Largest fraction of missing points that may be filled (0: none).
    source : str
        Name of the data (the file) for messages.
    absent : int
        How many of the missing points were absent from a point list (for
        the message only).
    window : ((ix0, iy0), (dx, dy)), optional
        Where ``heights`` lie in the file (the first point's indices) and
        their spacing [m]: a refusal then also offers the ``crop_mm`` of the
        largest window without missing points
        (:func:`~roughcontact.surfaces.defects.largest_complete_window`).

    Returns
    -------
    (filled heights, number of points filled)

    Raises
    ------
    MeasurementError
        If more than ``max_fraction`` of the points are missing, with the
        count and fraction in the message, the smallest ``fill_holes`` that
        fills them and, with ``window``, the crop that leaves them out.
    """
    z = np.array(heights, dtype=float)
    missing = np.isnan(z)
    count = int(missing.sum())
    if count == 0:
        return z, 0
    fraction = count / z.size
    if fraction > max_fraction or count == z.size:
        crop = None if window is None else crop_advice(missing, *window)
        _refuse_missing(z.size, count, max_fraction, source, absent, crop)
    ny, nx = z.shape
    y, x = np.nonzero(~missing)
    design = np.column_stack([np.ones(x.size), x, y]).astype(float)
    coefficients, *_ = np.linalg.lstsq(design, z[~missing], rcond=None)
    iy, ix = np.mgrid[0:ny, 0:nx]
    plane = coefficients[0] + coefficients[1] * ix + coefficients[2] * iy
    z[missing] = _harmonic_fill(z - plane, missing) + plane[missing]
    log.info("%s: filled %d missing points (%.3g %%) by Laplace interpolation",
             source, count, 100 * fraction)
    return z, count


def crop_advice(missing: np.ndarray, origin, spacing) -> str | None:
    """``crop_mm: [x0, y0, Lx, Ly]`` of the largest window without missing points, for a
    map whose first point is point ``origin`` (ix0, iy0) of the file, spacing (dx, dy)
    [m]; None where no window of :data:`MIN_POINTS` per side has none missing."""
    found = largest_complete_window(missing)
    if found is None or min(found[2:]) < MIN_POINTS:
        return None
    ix0, iy0, nx, ny = found
    values = [(origin[0] + ix0) * spacing[0], (origin[1] + iy0) * spacing[1],
              nx * spacing[0], ny * spacing[1]]
    text = ", ".join(f"{v / 1e-3:.7g}" for v in values)
    return (f"crop_mm: [{text}] (the largest window without missing points, {nx} x {ny} "
            f"points, {100 * nx * ny / missing.size:.3g} % of the map)")


def _at_least(fraction: float) -> float:
    """``fraction`` rounded up to 3 significant digits (a ``fill_holes`` that admits it)."""
    scale = 10.0 ** (2 - math.floor(math.log10(fraction)))
    return math.ceil(fraction * scale * (1.0 - 1e-12)) / scale  # 1e-12: 0.2 stays 0.2


def _refuse_missing(total: int, count: int, max_fraction: float, source, absent: int,
                    crop: str | None = None):
    """Raise the MeasurementError of :func:`fill_missing` for too many missing points
    (``crop``: the :func:`crop_advice`, if any)."""
    fraction = count / total
    or_crop = "" if crop is None else f" Or leave them out: {crop}."
    most = 0.5  # the largest fill_holes the config allows (config/schema.yaml)
    if count == total or fraction > most:
        reason = ("no point is known, so there is nothing to interpolate from"
                  if count == total else
                  f"more than {100 * most:g} % of the map would be interpolated, beyond "
                  f"the largest fill_holes the study accepts ({most:g}, config/schema.yaml)")
        raise MeasurementError(
            f"{missing_message(source, count, total, absent)}: {reason}. The data "
            f"cannot be filled; repair {source} or re-export it from the instrument "
            f"software (with the missing points measured or cropped away).{or_crop}",
            source,
        )
    allowed = (f"fill_holes = {max_fraction:g} allows at most {100 * max_fraction:.3g} %"
               if max_fraction > 0 else "fill_holes is 0, so none may be missing")
    raise MeasurementError(
        f"{missing_message(source, count, total, absent)}; {allowed}. Raise fill_holes "
        f"to at least {_at_least(fraction):.3g} to fill them by interpolation, or repair "
        f"the data.{or_crop}",
        source,
    )


def _harmonic_fill(residual: np.ndarray, missing: np.ndarray) -> np.ndarray:
    """Values at the ``missing`` points that equal the mean of their neighbours in the grid.

    Assembles the graph Laplacian of the missing points (4 neighbours inside
    the grid) with the known points of ``residual`` as boundary values, and
    solves it by ``scipy.sparse.linalg.spsolve``.
    """
    count = int(missing.sum())
    number = np.full(missing.shape, -1, dtype=np.int64)
    number[missing] = np.arange(count)
    diagonal = np.zeros(count)
    rhs = np.zeros(count)
    rows, cols = [], []
    for axis in (0, 1):
        for shift in (1, -1):
            # pairs (point, neighbour) along this axis and direction, inside the grid
            n = missing.shape[axis]
            here = [slice(None), slice(None)]
            there = [slice(None), slice(None)]
            here[axis] = slice(0, n - 1) if shift == 1 else slice(1, n)
            there[axis] = slice(1, n) if shift == 1 else slice(0, n - 1)
            hole = missing[tuple(here)]
            point = number[tuple(here)][hole]
            neighbour_missing = missing[tuple(there)][hole]
            neighbour = number[tuple(there)][hole]
            values = residual[tuple(there)][hole]
            np.add.at(diagonal, point, 1.0)
            np.add.at(rhs, point[~neighbour_missing], values[~neighbour_missing])
            rows.append(point[neighbour_missing])
            cols.append(neighbour[neighbour_missing])
    rows, cols = np.concatenate(rows), np.concatenate(cols)
    matrix = scipy.sparse.csr_matrix(
        (np.r_[diagonal, -np.ones(rows.size)],
         (np.r_[np.arange(count), rows], np.r_[np.arange(count), cols])),
        shape=(count, count),
    )
    return np.atleast_1d(scipy.sparse.linalg.spsolve(matrix.tocsc(), rhs))


def remove_plane(heights: np.ndarray, spacing) -> tuple[np.ndarray, tuple[float, float, float]]:
    """Subtract the least-squares plane ``a + b x + c y`` from heights ``(ny, nx)``.

    ``x = ix dx``, ``y = iy dy`` with ``spacing = (dx, dy)`` [m]. Returns the
    residual heights (zero mean, no tilt) and ``(a, b, c)``: the offset in
    the heights' unit and the slopes in height unit per metre.
    """
    z = np.asarray(heights, dtype=float)
    ny, nx = z.shape
    dx, dy = spacing
    y, x = np.meshgrid(np.arange(ny) * dy, np.arange(nx) * dx, indexing="ij")
    design = np.column_stack([np.ones(z.size), x.ravel() - x.mean(), y.ravel() - y.mean()])
    (a, b, c), *_ = np.linalg.lstsq(design, z.ravel(), rcond=None)
    residual = z - (a + b * (x - x.mean()) + c * (y - y.mean()))
    residual -= residual.mean()  # exact zero mean (the fit leaves a rounding-level one)
    return residual, (float(a - b * x.mean() - c * y.mean()), float(b), float(c))


def remove_polynomial(heights: np.ndarray, spacing, degree: int) -> tuple[np.ndarray, list]:
    """Subtract the least-squares polynomial of total degree ``degree`` in x and y.

    Coordinates are centred and scaled to [-1, 1] for conditioning; returns the
    residual (zero mean) and the coefficients of the monomials
    ``xs^i ys^j`` (i + j <= degree, in the order i, then j) in the heights' unit.
    """
    z = np.asarray(heights, dtype=float)
    ny, nx = z.shape
    xs = np.linspace(-1.0, 1.0, nx) if nx > 1 else np.zeros(1)
    ys = np.linspace(-1.0, 1.0, ny) if ny > 1 else np.zeros(1)
    y, x = np.meshgrid(ys, xs, indexing="ij")
    powers = [(i, j) for i in range(degree + 1) for j in range(degree + 1 - i)]
    design = np.column_stack([(x**i * y**j).ravel() for i, j in powers])
    coefficients, *_ = np.linalg.lstsq(design, z.ravel(), rcond=None)
    residual = z - (design @ coefficients).reshape(z.shape)
    residual -= residual.mean()
    return residual, [float(c) for c in coefficients]


def crop_window(heights: np.ndarray, spacing, window, source="heights"):
    """The points of ``window = (x0, y0, Lx, Ly)`` [m] (from the first point, lengths
    rounded to whole points) and ``(ix0, iy0, nx, ny)``; refused outside the grid."""
    ny, nx = heights.shape
    x0, y0, lx, ly = (float(v) for v in window)
    ix0, iy0 = round(x0 / spacing[0]), round(y0 / spacing[1])
    cx, cy = round(lx / spacing[0]), round(ly / spacing[1])
    if min(x0, y0) < 0 or cx < MIN_POINTS or cy < MIN_POINTS or ix0 + cx > nx or iy0 + cy > ny:
        raise MeasurementError(
            f"{source}: crop window x {x0:g}..{x0 + lx:g} m, y {y0:g}..{y0 + ly:g} m "
            f"({cx} x {cy} points from ({ix0}, {iy0})) does not lie within the "
            f"measurement ({nx * spacing[0]:g} x {ny * spacing[1]:g} m, {nx} x {ny} points) "
            f"or has fewer than {MIN_POINTS} points along a side", source,
        )
    return heights[iy0:iy0 + cy, ix0:ix0 + cx], (ix0, iy0, cx, cy)


def decimate(heights: np.ndarray, factor: int) -> np.ndarray:
    """Means of ``factor`` x ``factor`` blocks (a trailing partial block is dropped)."""
    ny, nx = heights.shape
    my, mx = ny // factor, nx // factor
    blocks = heights[:my * factor, :mx * factor].reshape(my, factor, mx, factor)
    return blocks.mean(axis=(1, 3))


def resample(heights: np.ndarray, spacing, grid) -> tuple[np.ndarray, tuple[float, float]]:
    """Linear interpolation onto ``grid = (nx, ny)`` points over the same plan size.

    Points are cell centres of both grids (point k at ``(k + 1/2) L / n``);
    returns the heights and the new spacing [m].
    """
    ny, nx = heights.shape
    gx, gy = (int(v) for v in grid)
    lx, ly = nx * spacing[0], ny * spacing[1]
    old_x = (np.arange(nx) + 0.5) * spacing[0]
    old_y = (np.arange(ny) + 0.5) * spacing[1]
    new_x = np.clip((np.arange(gx) + 0.5) * lx / gx, old_x[0], old_x[-1])
    new_y = np.clip((np.arange(gy) + 0.5) * ly / gy, old_y[0], old_y[-1])
    interpolate = scipy.interpolate.RegularGridInterpolator((old_y, old_x), heights)
    yy, xx = np.meshgrid(new_y, new_x, indexing="ij")
    values = interpolate(np.column_stack([yy.ravel(), xx.ravel()])).reshape(gy, gx)
    return values, (lx / gx, ly / gy)


def remove_outliers(heights: np.ndarray, spacing, sigmas: float, form_degree: int, *,
                    source="heights") -> tuple[np.ndarray, int]:
    """Step 3: the points of ``heights`` (form removed, zero mean) farther than ``sigmas``
    standard deviations from the mean plane, filled as holes (:func:`fill_missing`), and
    the form of degree ``form_degree`` removed again. Returns the heights and the count."""
    far = np.abs(heights) > float(sigmas) * heights.std()
    count = int(far.sum())
    if not count:
        return heights, 0
    log.info("%s: %d points beyond %g sigma filled as holes", source, count, sigmas)
    heights, _ = fill_missing(np.where(far, np.nan, heights), 1.0 - 1e-12,
                              source=f"{source} (outliers)")
    heights, _ = remove_plane(heights, spacing)
    if form_degree > 1:
        heights, _ = remove_polynomial(heights, spacing, int(form_degree))
    return heights, count


def _clearing_sigmas(formed: np.ndarray, spacing, form_degree: int, source):
    """The ``outliers_sigma`` that leaves no spikes that matter in ``formed`` (the
    heights before step 3), with the kurtosis it gives, or None. Tried from just
    below the nearest spike downwards (a spike may hide another: the standard
    deviation shrinks when the first are filled)."""
    spikes = find_spikes(formed)
    nearest = float(np.abs(formed[spikes]).min() / formed.std())
    sigmas = math.floor(0.99 * nearest * 10.0 ** (1 - math.floor(math.log10(nearest))))
    sigmas /= 10.0 ** (1 - math.floor(math.log10(nearest)))
    while sigmas >= 3.0:
        cleared, _ = remove_outliers(formed, spacing, sigmas, form_degree, source=source)
        if not spikes_matter(cleared, find_spikes(cleared))[0]:
            return sigmas, spikes_matter(cleared, find_spikes(cleared))[1]
        sigmas = round(0.8 * sigmas, 1)
    return None


def _report_spikes(formed: np.ndarray, heights: np.ndarray, spacing, form_degree: int,
                   source) -> int:
    """Count the spikes and dropouts left in ``heights`` (after step 3;
    :func:`~roughcontact.surfaces.defects.find_spikes`) and, where they change the
    kurtosis (:func:`~roughcontact.surfaces.defects.spikes_matter`), log a warning with
    the ``outliers_sigma`` that removes them (tested on ``formed``, the heights
    before step 3)."""
    spikes = find_spikes(heights)
    matter, with_them, without = spikes_matter(heights, spikes)
    if not matter:
        return int(spikes.sum())
    iy, ix = np.unravel_index(int(np.argmax(np.where(spikes, np.abs(heights), -1.0))),
                              heights.shape)
    clearing = _clearing_sigmas(formed, spacing, form_degree, source)
    advice = ("mark them missing in the file (nan) and set fill_holes" if clearing is None else
              f"set surface.outliers_sigma: {clearing[0]:g} to fill them as holes (Ku "
              f"{clearing[1]:.3g} then), or mark them missing in the file")
    log.warning(
        "%s: %d points (%.2g %%) lie more than %g robust standard deviations from the "
        "median height (the farthest at x = %.4g mm, y = %.4g mm): spikes or dropouts of "
        "the instrument, not the surface. They give Ku = %.4g; without them Ku = %.3g. To "
        "leave them out, %s.", source, int(spikes.sum()), 100 * spikes.mean(),
        SPIKE_ROBUST_SIGMAS, ix * spacing[0] / 1e-3, iy * spacing[1] / 1e-3, with_them,
        without, advice)
    return int(spikes.sum())


#: Heights whose standard deviation, with the form removed, is at most this fraction of
#: their largest magnitude are flat: what is left is the rounding of the least-squares
#: fit in double precision (4e-16 of the heights of a constant 32 x 32 map), not
#: roughness. A map stored in single precision resolves 6e-8 of its magnitude, a 16-bit
#: instrument map 3e-5: any measured roughness lies far above the threshold.
FLAT_RELATIVE = 1e-12


def _refuse_flat(heights: np.ndarray, raw: np.ndarray, form_degree: int, source) -> None:
    """Raise :class:`MeasurementError` if ``heights`` (``raw`` [m] less its form of degree
    ``form_degree``) are flat (:data:`FLAT_RELATIVE`): a constant map, or one that is
    its form. Checked before any statistic is taken, whose values (a correlation length,
    Sk, Ku of rounding noise) would only mislead."""
    sigma, magnitude = float(heights.std()), float(np.abs(raw).max())
    if sigma > FLAT_RELATIVE * magnitude:
        return
    form = "plane" if form_degree == 1 else f"polynomial of degree {form_degree}"
    raise MeasurementError(
        f"{source}: the heights are flat (a constant or a {form}): with the least-squares "
        f"{form} removed their standard deviation is {sigma / 1e-6:.3g} um on heights of up "
        f"to {magnitude / 1e-6:.3g} um, the rounding of the fit, not roughness. Check that "
        "the file holds the height map meant (in an instrument file, surface.channel "
        "selects another data channel)", source)


def prepare(raw: np.ndarray, spacing, *, source, absent: int = 0, crop=None,
            fill_holes: float = 0.0, form_degree: int = 1, outliers_sigma: float | None = None,
            decimate_by: int | None = None, resample_grid=None):
    """Steps 0-4 of the module documentation on raw heights ``(ny, nx)`` [m] with NaN holes.

    ``spacing`` (dx, dy) [m]; ``source`` names the data (the file) in messages;
    ``absent`` counts the holes that were absent from a point list; the other
    options as :class:`roughcontact.surfaces.measured.ImportOptions` holds
    them. Returns ``(heights [m] of zero mean, spacing [m], points filled,
    removed plane (a, b, c), steps)``, ``steps`` a dict for the provenance
    (``file_grid``, ``crop_points``, ``missing_points`` (in the cropped window),
    ``form_coefficients``, ``outliers``, ``spikes`` (left after step 3),
    ``decimated_by``, ``resampled_to``).

    Raises
    ------
    MeasurementError
        For a grid of fewer than :data:`~roughcontact.surfaces.readers.MIN_POINTS`
        points along an axis, a crop window outside it, too many holes, or
        heights that are flat (:data:`FLAT_RELATIVE`: constant, or their form).
    """
    ny, nx = raw.shape
    if min(nx, ny) < MIN_POINTS:
        raise MeasurementError(
            f"{source}: a {nx} x {ny} grid (nx x ny); a surface needs at least {MIN_POINTS} "
            "points along each axis", source,
        )
    steps = {"file_grid": [nx, ny]}
    if crop is not None:
        raw, window = crop_window(raw, spacing, crop, str(source))
        steps["crop_points"] = list(window)
    steps["missing_points"] = int(np.isnan(raw).sum())  # in the window: those to fill
    origin = steps["crop_points"][:2] if crop is not None else (0, 0)
    filled_raw, filled = fill_missing(raw, float(fill_holes), source=str(source), absent=absent,
                                      window=(origin, spacing))
    heights, plane = remove_plane(filled_raw, spacing)
    if form_degree > 1:
        heights, coefficients = remove_polynomial(heights, spacing, int(form_degree))
        steps["form_coefficients"] = coefficients
    _refuse_flat(heights, filled_raw, form_degree, source)
    formed = heights
    if outliers_sigma is not None:
        heights, steps["outliers"] = remove_outliers(heights, spacing, outliers_sigma,
                                                     form_degree, source=source)
    steps["spikes"] = _report_spikes(formed, heights, spacing, form_degree, source)
    if decimate_by is not None:
        heights = decimate(heights, int(decimate_by))
        spacing = (spacing[0] * decimate_by, spacing[1] * decimate_by)
        heights = heights - heights.mean()
        steps["decimated_by"] = int(decimate_by)
    elif resample_grid is not None:
        heights, spacing = resample(heights, spacing, resample_grid)
        heights = heights - heights.mean()
        steps["resampled_to"] = [int(v) for v in resample_grid]
    return heights, spacing, filled, plane, steps
