"""Measured height maps: import, unit conversion, hole filling, detrending, statistics.

A measured surface (from a profilometer or an optical instrument) enters the
study in place of a generated one. It is read from one of three formats:

- ``npy``: a NumPy ``.npy`` file holding one 2-D array of heights, axis 0 = y,
  axis 1 = x; the spacing comes from the configuration.
- ``text``: a grid of heights as text, one row of the file per y, one column
  per x, separated by commas, semicolons or white space; the spacing comes
  from the configuration. Lines starting with ``#`` (and anything after a
  ``#``) are comments.
- ``xyz``: a list of points ``x y z`` (same separators and comments), one per
  line, in any order, on a regular grid. The spacing is inferred from the
  coordinates and the grid is checked: every coordinate must lie on
  ``x0 + k dx`` within ``SPACING_RTOL`` of the spacing.

Missing points are written ``nan`` in grids; in point lists a grid point may
also be absent. Heights and lateral lengths are converted from the units the
configuration declares to SI (metres) at import; everything after that is SI.

The height map is then prepared for the contact study in this order:

1. Holes (missing points) are refused, or, if their fraction is at most
   ``fill_holes``, filled by a discrete Laplace (harmonic) interpolation of
   the heights less the least-squares plane of the known points: every
   missing point equals the mean of its 4 neighbours (fewer at the edges,
   which gives a zero normal slope there), solved jointly for all missing
   points with a sparse direct solver. It reproduces any plane exactly, is
   second-order accurate inside a hole and first-order at the edges; it
   does not invent roughness, so a filled hole is smoother than the
   measured surface around it. Known points are not changed.
2. The least-squares plane ``a + b x + c y`` is removed (form and tilt of the
   mounting), which also leaves heights of zero mean.

Its statistics are those of the generator's targets: sigma, skewness and
kurtosis (Eq 2-5 of Kumar et al. 2006, :func:`roughcontact.surfaces.synthetic.height_stats`),
the 10 % decay lags of the autocorrelation function (Eq 1,
:func:`roughcontact.surfaces.synthetic.correlation_length`, non-periodic estimate) and the
Johnson law with the same moments (:func:`roughcontact.surfaces.johnson.fit`).
Arrays are ``(ny, nx)``, row-major over y then x, as everywhere in the package.
"""

from __future__ import annotations

import logging
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy import sparse
from scipy.sparse import linalg as sparse_linalg

from roughcontact.errors import MeasurementError
from roughcontact.hashes import file_sha256
from roughcontact.surfaces import johnson
from roughcontact.surfaces.synthetic import correlation_length, height_stats

log = logging.getLogger(__name__)

FORMATS = ("npy", "text", "xyz")
#: Height units a configuration may declare, in metres.
HEIGHT_UNITS = {"nm": 1e-9, "um": 1e-6, "mm": 1e-3, "m": 1.0}
#: Lateral (x, y) units a configuration may declare, in metres.
LATERAL_UNITS = {"um": 1e-6, "mm": 1e-3, "m": 1.0}
#: A point-list coordinate may deviate from its grid line by this fraction of the spacing.
SPACING_RTOL = 0.01
#: Fewest points per side: below this the statistics are meaningless (as for SurfaceSpec).
MIN_POINTS = 4
#: Most points per side (the schema's limit of a grid).
MAX_POINTS = 4096

_SEPARATORS = re.compile(r"[,;]")


# --------------------------------------------------------------------------- reading


def _data_lines(path):
    """``(line number, text)`` of the non-empty, non-comment lines of a text file."""
    with open(path, encoding="utf-8", errors="replace") as f:
        for number, line in enumerate(f, start=1):
            text = line.split("#", 1)[0].strip()
            if text:
                yield number, text


def _fields(text: str) -> list[str]:
    if _SEPARATORS.search(text):
        return [token.strip() for token in _SEPARATORS.split(text)]
    return text.split()


def _numbers(tokens: list[str], path, number: int) -> list[float]:
    """The tokens of one line as floats (``nan`` allowed), or a MeasurementError."""
    try:
        values = [float(token) for token in tokens]
    except ValueError:
        values = None
    if values is not None and not any(math.isinf(v) for v in values):
        return values
    for column, token in enumerate(tokens, start=1):
        try:
            value = float(token)
        except ValueError:
            what = "an empty field" if token == "" else f"{token!r}, which is not a number"
            raise MeasurementError(
                f"{path}, line {number}, column {column}: {what}. Heights must be numbers; "
                "write a missing point as nan and start comment lines with #.",
                path, number,
            ) from None
        if math.isinf(value):
            raise MeasurementError(
                f"{path}, line {number}, column {column}: {token!r} is infinite; write a "
                "missing point as nan.", path, number,
            )
    raise AssertionError("unreachable")  # pragma: no cover


def read_npy(path: str | os.PathLike) -> np.ndarray:
    """Heights ``(ny, nx)`` in the file's unit from a ``.npy`` file (2-D, real)."""
    try:
        data = np.load(path, allow_pickle=False)
    except ValueError as err:
        raise MeasurementError(f"{path}: not a plain NumPy array file ({err})", path) from err
    if not isinstance(data, np.ndarray):  # an .npz archive
        data.close()
        raise MeasurementError(f"{path}: an .npz archive; save one array with numpy.save", path)
    if data.ndim != 2:
        raise MeasurementError(
            f"{path}: expected a 2-D array of heights (axis 0 = y, axis 1 = x); "
            f"got shape {data.shape}", path,
        )
    if not (np.issubdtype(data.dtype, np.integer) or np.issubdtype(data.dtype, np.floating)):
        raise MeasurementError(f"{path}: expected real numbers; got dtype {data.dtype}", path)
    data = data.astype(float)
    if np.isinf(data).any():
        iy, ix = np.argwhere(np.isinf(data))[0]
        raise MeasurementError(
            f"{path}: {int(np.isinf(data).sum())} infinite heights (first at row {iy}, "
            f"column {ix}); mark missing points as nan", path,
        )
    return data


def read_text_grid(path: str | os.PathLike) -> np.ndarray:
    """Heights ``(ny, nx)`` in the file's unit from a text grid (a row per y).

    Fields are separated by commas or semicolons where a line has them, else
    by white space. Every data row must have as many values as the first.
    """
    rows, width, first = [], None, None
    for number, text in _data_lines(path):
        tokens = _fields(text)
        if width is None:
            width, first = len(tokens), number
        elif len(tokens) != width:
            raise MeasurementError(
                f"{path}, line {number}: {len(tokens)} values, but the first data row "
                f"(line {first}) has {width}; every row of a grid must have the same "
                "number of columns (write missing points as nan)", path, number,
            )
        rows.append(_numbers(tokens, path, number))
    if not rows:
        raise MeasurementError(f"{path}: no data rows (only comments or blank lines)", path)
    return np.array(rows, dtype=float)


def _lattice(values: np.ndarray, axis: str, path, unit: str) -> tuple[float, float, np.ndarray]:
    """Origin, spacing and grid index of point coordinates along one axis.

    Each gap between successive distinct coordinates must be a whole number
    of the smallest gap, within ``SPACING_RTOL`` (a missing column is allowed:
    it becomes missing points); the spacing is then fitted by least squares
    to all coordinates (which averages out coordinates rounded in print), and
    every coordinate must lie within ``SPACING_RTOL`` of the spacing from its
    grid line. Otherwise the grid is not uniform.
    """
    levels = np.unique(values)
    if levels.size < MIN_POINTS:
        raise MeasurementError(
            f"{path}: only {levels.size} distinct {axis} coordinates; a surface needs at "
            f"least {MIN_POINTS} points along {axis}", path,
        )
    span = levels[-1] - levels[0]
    levels = levels[np.r_[True, np.diff(levels) > 1e-9 * span]]  # printing jitter
    gaps = np.diff(levels)
    smallest = float(gaps.min())
    ratio = gaps / smallest
    whole = np.rint(ratio)
    grid_line = np.r_[0.0, np.cumsum(whole)]
    centred = grid_line - grid_line.mean()
    step = float(centred @ (levels - levels.mean()) / (centred @ centred))
    origin = float(levels.mean() - step * grid_line.mean())
    drift = np.abs(levels - origin - step * grid_line) / step
    off_grid = np.r_[False, np.abs(ratio - whole) > SPACING_RTOL * whole] | (drift > SPACING_RTOL)
    if off_grid.any() or smallest < 0.5 * np.median(gaps):
        seen = sorted({float(f"{g:.4g}") for g in gaps})
        shown = ", ".join(f"{g:g}" for g in seen[:8]) + (", ..." if len(seen) > 8 else "")
        where = levels[off_grid][0] if off_grid.any() else levels[1:][np.argmin(gaps)]
        raise MeasurementError(
            f"{path}: the {axis} spacing is not uniform: spacings seen {shown} {unit} "
            f"({len(seen)} distinct values; {axis} = {where:g} {unit} is not on the grid of "
            f"spacing {smallest:g} {unit} from {levels[0]:g} {unit}). Resample the "
            "measurement onto a regular grid.", path,
        )
    count = int(grid_line[-1]) + 1
    if count > MAX_POINTS:
        raise MeasurementError(
            f"{path}: the {axis} coordinates span {count} grid lines at spacing {step:g} "
            f"{unit}, more than {MAX_POINTS}", path,
        )
    index = np.rint((values - origin) / step).astype(np.int64)
    return origin, step, index


def read_xyz(path: str | os.PathLike, lateral_unit: str = "mm"):
    """Heights on the grid of an ``x y z`` point list, in the file's height unit.

    Returns ``(heights (ny, nx), (dx, dy) in lateral_unit, absent)``: grid
    points that no line gives are NaN in ``heights`` and counted in
    ``absent``. A grid point given twice is an error naming both lines.
    """
    points, lines = [], []
    for number, text in _data_lines(path):
        tokens = _fields(text)
        if len(tokens) != 3:
            raise MeasurementError(
                f"{path}, line {number}: {len(tokens)} values, expected 3 (x y z)",
                path, number,
            )
        values = _numbers(tokens, path, number)
        if math.isnan(values[0]) or math.isnan(values[1]):
            raise MeasurementError(
                f"{path}, line {number}: the coordinates must be numbers, not nan", path, number,
            )
        points.append(values)
        lines.append(number)
    if not points:
        raise MeasurementError(f"{path}: no data rows (only comments or blank lines)", path)
    points = np.array(points, dtype=float)
    _, dx, ix = _lattice(points[:, 0], "x", path, lateral_unit)
    _, dy, iy = _lattice(points[:, 1], "y", path, lateral_unit)
    nx, ny = int(ix.max()) + 1, int(iy.max()) + 1
    flat = iy * nx + ix
    order = np.argsort(flat, kind="stable")
    repeated = np.nonzero(np.diff(flat[order]) == 0)[0]
    if repeated.size:
        first, second = sorted((lines[order[repeated[0]]], lines[order[repeated[0] + 1]]))
        x, y = points[order[repeated[0]], :2]
        raise MeasurementError(
            f"{path}, line {second}: the point (x, y) = ({x:g}, {y:g}) {lateral_unit} "
            f"repeats line {first}", path, second,
        )
    heights = np.full(ny * nx, np.nan)
    heights[flat] = points[:, 2]
    absent = ny * nx - len(points)
    return heights.reshape(ny, nx), (dx, dy), absent


# --------------------------------------------------------------------------- preparing


def missing_message(source, missing: int, total: int, absent: int = 0) -> str:
    """How many points are missing, as a sentence naming the source."""
    detail = (f" ({absent} grid points absent from the point list, {missing - absent} nan)"
              if absent else " (nan values)")
    return (f"{source}: {missing} of {total} points ({100.0 * missing / total:.3g} %) are "
            f"missing{detail}")


def fill_missing(heights: np.ndarray, max_fraction: float = 0.0, *, source="heights",
               absent: int = 0) -> tuple[np.ndarray, int]:
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

    Returns
    -------
    (filled heights, number of points filled)

    Raises
    ------
    MeasurementError
        If more than ``max_fraction`` of the points are missing, with the
        count and fraction in the message.
    """
    z = np.array(heights, dtype=float)
    missing = np.isnan(z)
    count = int(missing.sum())
    if count == 0:
        return z, 0
    fraction = count / z.size
    if fraction > max_fraction or count == z.size:
        allowed = (f"fill_holes = {max_fraction:g} allows at most {100 * max_fraction:.3g} %"
                   if max_fraction > 0 else "fill_holes is 0, so none may be missing")
        raise MeasurementError(
            f"{missing_message(source, count, z.size, absent)}; {allowed}. Raise fill_holes "
            f"to at least {fraction:.3g} to fill them by interpolation, or repair the data.",
            source,
        )
    ny, nx = z.shape
    y, x = np.nonzero(~missing)
    design = np.column_stack([np.ones(x.size), x, y]).astype(float)
    coefficients, *_ = np.linalg.lstsq(design, z[~missing], rcond=None)
    iy, ix = np.mgrid[0:ny, 0:nx]
    plane = coefficients[0] + coefficients[1] * ix + coefficients[2] * iy
    residual = z - plane
    number = np.full(z.shape, -1, dtype=np.int64)
    number[missing] = np.arange(count)
    diagonal = np.zeros(count)
    rhs = np.zeros(count)
    rows, cols = [], []
    for axis in (0, 1):
        for shift in (1, -1):
            # pairs (point, neighbour) along this axis and direction, inside the grid
            n = z.shape[axis]
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
    matrix = sparse.csr_matrix(
        (np.r_[diagonal, -np.ones(rows.size)],
         (np.r_[np.arange(count), rows], np.r_[np.arange(count), cols])),
        shape=(count, count),
    )
    z[missing] = np.atleast_1d(sparse_linalg.spsolve(matrix.tocsc(), rhs)) + plane[missing]
    log.info("%s: filled %d missing points (%.3g %%) by Laplace interpolation",
             source, count, 100 * fraction)
    return z, count


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


# --------------------------------------------------------------------------- the measurement


@dataclass(frozen=True)
class Measurement:
    """A measured surface, imported and prepared for the contact study.

    Attributes
    ----------
    heights : ndarray (ny, nx)
        Heights [m]: holes filled, least-squares plane removed (zero mean).
    spacing : (dx, dy)
        Grid spacing [m].
    source : str
        The file it was read from.
    sha256 : str
        SHA-256 of the file's bytes.
    options : dict
        The import options (format, units, spacing, fill_holes) as given.
    filled : int
        Number of missing points filled by interpolation.
    plane : (a, b, c)
        The removed plane ``a + b x + c y``: offset [m], slopes [1].
    """

    heights: np.ndarray
    spacing: tuple[float, float]
    source: str
    sha256: str
    options: dict = field(default_factory=dict)
    filled: int = 0
    plane: tuple[float, float, float] = (0.0, 0.0, 0.0)

    @property
    def grid(self) -> tuple[int, int]:
        """Points ``(nx, ny)``."""
        return (self.heights.shape[1], self.heights.shape[0])

    @property
    def size(self) -> tuple[float, float]:
        """Side lengths ``(Lx, Ly) = (nx dx, ny dy)`` [m], as for generated surfaces."""
        return (self.grid[0] * self.spacing[0], self.grid[1] * self.spacing[1])

    @property
    def filled_fraction(self) -> float:
        """Fraction of the points that were filled."""
        return self.filled / self.heights.size


def _unit(value: str, table: dict, what: str) -> float:
    if value not in table:
        raise ValueError(f"{what} must be one of {sorted(table)}; got {value!r}")
    return table[value]


def load_measurement(path: str | os.PathLike, format: str, *, height_unit: str,
                     lateral_unit: str = "mm", spacing=None,
                     fill_holes: float = 0.0) -> Measurement:
    """Import a measured height map and prepare it (holes, plane) in SI units.

    Parameters
    ----------
    path : path-like
        The file.
    format : {"npy", "text", "xyz"}
        See the module documentation.
    height_unit : {"nm", "um", "mm", "m"}
        Unit of the heights in the file.
    lateral_unit : {"um", "mm", "m"}
        Unit of the x, y coordinates of an ``xyz`` file.
    spacing : (dx, dy) [m], optional
        Grid spacing of ``npy`` and ``text`` grids (required there); not
        allowed for ``xyz`` files, whose spacing is inferred.
    fill_holes : float
        Largest fraction of missing points to fill (:func:`fill_missing`).

    Raises
    ------
    MeasurementError
        For a file that cannot be used, naming the file and the line, the
        missing fraction or the non-uniform axis.
    ValueError
        For inconsistent options (unknown unit or format, spacing missing or
        given where it is inferred).
    """
    path = Path(path)
    if format not in FORMATS:
        raise ValueError(f"format must be one of {FORMATS}; got {format!r}")
    scale = _unit(height_unit, HEIGHT_UNITS, "height_unit")
    lateral = _unit(lateral_unit, LATERAL_UNITS, "lateral_unit")
    if not 0.0 <= float(fill_holes) < 1.0:
        raise ValueError(f"fill_holes must be a fraction in [0, 1); got {fill_holes!r}")
    if not path.is_file():
        raise MeasurementError(f"{path}: no such file", path)
    absent = 0
    if format == "xyz":
        if spacing is not None:
            raise ValueError(f"{path}: an xyz point list gives its own spacing; drop the spacing")
        raw, (dx, dy), absent = read_xyz(path, lateral_unit)
        spacing = (dx * lateral, dy * lateral)
    else:
        if spacing is None:
            raise ValueError(f"{path}: a {format} grid needs its spacing (dx, dy)")
        raw = read_npy(path) if format == "npy" else read_text_grid(path)
        spacing = tuple(float(v) for v in np.broadcast_to(np.asarray(spacing, float), (2,)))
        if not all(math.isfinite(v) and v > 0 for v in spacing):
            raise ValueError(f"spacing must be positive and finite [m]; got {spacing!r}")
    ny, nx = raw.shape
    if min(nx, ny) < MIN_POINTS:
        raise MeasurementError(
            f"{path}: a {nx} x {ny} grid (nx x ny); a surface needs at least {MIN_POINTS} "
            "points along each axis", path,
        )
    filled_raw, filled = fill_missing(raw, float(fill_holes), source=str(path), absent=absent)
    heights, plane = remove_plane(filled_raw * scale, spacing)
    if not np.ptp(heights) > 1e-12 * max(np.ptp(filled_raw * scale), np.finfo(float).tiny):
        raise MeasurementError(f"{path}: the heights are a plane (no roughness left)", path)
    options = {"format": format, "height_unit": height_unit, "lateral_unit": lateral_unit,
               "spacing": None if format == "xyz" else list(spacing),
               "fill_holes": float(fill_holes)}
    return Measurement(heights, (float(spacing[0]), float(spacing[1])), str(path),
                       file_sha256(path), options, filled, plane)


def statistics(measurement: Measurement) -> dict:
    """Height statistics of a measurement and the Johnson law of its moments.

    Returns plain values: ``sigma`` [m], ``skew``, ``kurt`` (Pearson), ``mean``
    [m] (zero after detrending), ``corr_length_x``, ``corr_length_y`` [m]
    (lags of 10 % ACF decay, non-periodic estimate; NaN if the ACF stays
    above 10 % over half the length), ``grid`` [nx, ny], ``size`` [Lx, Ly] [m],
    ``spacing`` [dx, dy] [m], ``filled_points``, ``filled_fraction``, the
    removed plane (``plane_offset`` [m], ``plane_slope_x``, ``plane_slope_y``),
    and ``johnson_family`` with ``johnson_params`` ``[gamma, delta, xi, lam]``
    of the law fitted to (Sk, Ku) for heights in units of sigma (zero mean,
    unit standard deviation).
    """
    z = measurement.heights
    moments = height_stats(z)
    bx, by = correlation_length(z, measurement.spacing, periodic=False)
    curve = johnson.fit(moments["skew"], moments["kurt"])
    return {
        "sigma": moments["sigma"],
        "skew": moments["skew"],
        "kurt": moments["kurt"],
        "mean": moments["mean"],
        "corr_length_x": float(bx),
        "corr_length_y": float(by),
        "grid": list(measurement.grid),
        "size": list(measurement.size),
        "spacing": list(measurement.spacing),
        "filled_points": int(measurement.filled),
        "filled_fraction": float(measurement.filled_fraction),
        "plane_offset": measurement.plane[0],
        "plane_slope_x": measurement.plane[1],
        "plane_slope_y": measurement.plane[2],
        "johnson_family": curve.family,
        "johnson_params": [curve.gamma, curve.delta, curve.xi, curve.lam],
    }


__all__ = [
    "FORMATS",
    "HEIGHT_UNITS",
    "LATERAL_UNITS",
    "Measurement",
    "fill_missing",
    "file_sha256",
    "load_measurement",
    "read_npy",
    "read_text_grid",
    "read_xyz",
    "remove_plane",
    "statistics",
]
