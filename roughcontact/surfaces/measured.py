"""Measured height maps: import, unit conversion, preparation, statistics.

A measured surface (from a profilometer, an optical instrument or an AFM)
enters the study in place of a generated one. Formats (``format``):

- ``auto`` (the default): chosen by the file. ``.npy``, ``.xyz`` and ``.csv``
  files are read as below; every other file by SurfaceTopography
  (ContactEngineering), which recognises the instrument's own format by its
  content (x3p, sur, opd, plu, datx, MetroPro, al3d, frt, di, Gwyddion and
  other text exports, ...; :data:`INSTRUMENT_FORMATS`) and gives the height
  unit, the pixel size and the instrument's mask of undefined points from
  the file's metadata.
- ``instrument``: through SurfaceTopography, whatever the file's name.
- ``npy``: a NumPy ``.npy`` file holding one 2-D array of heights, axis 0 = y,
  axis 1 = x; the spacing comes from the configuration.
- ``text``: a grid of heights as text, one row of the file per y, one column
  per x. The separator is the first line's: ``;``, else a tab, else ``,``,
  else white space. Decimal commas (``1,234;2,345``, as instruments set to a
  German or French locale write them) are read with ``;`` or tab separators
  (``decimal: auto`` or ``","``), or with white space when ``decimal: ","``
  says so; a line that could be read two ways is refused. Lines starting
  with ``#`` (and anything after a ``#``) are comments.
- ``xyz``: a list of points ``x y z`` (same separators and comments), one per
  line, in any order, on a regular grid. The spacing is inferred from the
  coordinates and the grid is checked: every coordinate must lie on
  ``x0 + k dx`` within ``SPACING_RTOL`` of the spacing.

The height unit and the spacing are needed only where the file does not
carry them, and refused where they contradict it.
Missing points are written ``nan`` in grids; in point lists a grid point may
also be absent. Heights and lateral lengths are converted from the units the
configuration declares to SI (metres) at import; everything after that is SI.

The height map is then prepared for the contact study in this order (each
step recorded in :attr:`Measurement.preparation`):

0. ``crop``: a window ``(x0, y0, Lx, Ly)`` [m] from the first point.
1. Holes (missing points, or points the instrument masked as undefined) are
   refused, or, if their fraction is at most
   ``fill_holes``, filled by a discrete Laplace (harmonic) interpolation of
   the heights less the least-squares plane of the known points: every
   missing point equals the mean of its 4 neighbours (fewer at the edges,
   which gives a zero normal slope there), solved jointly for all missing
   points with a sparse direct solver. It reproduces any plane exactly, is
   second-order accurate inside a hole and first-order at the edges; it
   does not invent roughness, so a filled hole is smoother than the
   measured surface around it. Known points are not changed.
2. The least-squares plane ``a + b x + c y`` is removed (form and tilt of the
   mounting), which also leaves heights of zero mean; with ``form_degree``
   k >= 2, then the least-squares polynomial of total degree k in x and y
   (k = 2 takes out a sphere's or a cylinder's form to second order).
3. ``outliers_sigma``: points farther than k sigma from the mean plane are
   counted, filled as holes and the form removed again.
4. ``decimate`` (an integer: means of k x k blocks) or ``resample_grid``
   ([nx, ny]: linear interpolation over the same plan size) gives the
   contact grid, and the mean is removed.

Its statistics are those of the generator's targets: sigma, skewness and
kurtosis (Eq 2-5 of Kumar et al. 2006, :func:`roughcontact.surfaces.synthetic.height_stats`),
the 10 % decay lags of the autocorrelation function (Eq 1,
:func:`roughcontact.surfaces.synthetic.correlation_length`, non-periodic estimate; NaN,
with a warning, where it does not fall to 10 % within half the window) and the
Johnson law with the same moments (:func:`roughcontact.surfaces.johnson.fit`);
with ``spectral=True`` also the rms slope, the rms curvature and the isotropic
power spectral density, computed by SurfaceTopography.
Arrays are ``(ny, nx)``, row-major over y then x, as everywhere in the package.

An isotropic PSD can also stand in for the autocorrelation of generated
surfaces (``SurfaceSpec(acf="psd")``): :func:`psd_table_from_measurement`
takes it from a measurement, :func:`read_psd_table` from a CSV table.
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
from scipy.interpolate import RegularGridInterpolator
from scipy.sparse import linalg as sparse_linalg

from roughcontact.errors import MeasurementError
from roughcontact.hashes import file_sha256
from roughcontact.surfaces import johnson
from roughcontact.surfaces.synthetic import check_psd_table, correlation_length, height_stats
from roughcontact.units import MM

log = logging.getLogger(__name__)

FORMATS = ("auto", "instrument", "npy", "text", "xyz")
#: Formats ``auto`` reads with our own readers, by the file's suffix; every
#: other file goes to SurfaceTopography.
OWN_SUFFIXES = {".npy": "npy", ".xyz": "xyz", ".csv": "text"}
#: Height units a configuration may declare, in metres.
HEIGHT_UNITS = {"nm": 1e-9, "um": 1e-6, "mm": 1e-3, "m": 1.0}
#: Units SurfaceTopography reports for a file's heights and lengths, in metres.
INSTRUMENT_UNITS = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "\u00b5m": 1e-6, "\u03bcm": 1e-6,
                    "nm": 1e-9, "pm": 1e-12, "\u00c5": 1e-10, "A": 1e-10}
#: Decimal separators of text grids.
DECIMALS = ("auto", ".", ",")
#: A length the configuration gives for a file that carries its own must agree to this.
CONTRADICTION_RTOL = 1e-6
#: Lateral (x, y) units a configuration may declare, in metres.
LATERAL_UNITS = {"um": 1e-6, "mm": 1e-3, "m": 1.0}
#: A point-list coordinate may deviate from its grid line by this fraction of the spacing.
SPACING_RTOL = 0.01
#: Fewest points per side: below this the statistics are meaningless (as for SurfaceSpec).
MIN_POINTS = 4
#: Most points per side (the schema's limit of a grid).
MAX_POINTS = 4096

_SEPARATORS = re.compile(r"[,;]")
_NUMBER = re.compile(r"^[+-]?(\d+([.,]\d*)?|[.,]\d+)([eE][+-]?\d+)?$|^[+-]?(nan|inf|infinity)$",
                     re.IGNORECASE)


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


def _dialect(text: str, decimal: str, path, number: int) -> tuple[str | None, str]:
    """Separator (None: white space) and decimal mark of a text grid, from its first
    data line ``text`` and the ``decimal`` option (``auto``, ``.`` or ``,``)."""
    if decimal not in DECIMALS:
        raise ValueError(f"decimal must be one of {DECIMALS}; got {decimal!r}")
    separator = ";" if ";" in text else "\t" if "\t" in text else None
    if separator is None and "," in text:
        if decimal == ",":
            if re.search(r"\d\s+[+-]?\d", text):
                return None, ","  # white space between values, commas inside them
            raise MeasurementError(
                f"{path}, line {number}: decimal: ',' but the values are separated by "
                "commas too; separate them by ';', tabs or white space", path, number,
            )
        if re.search(r"\d\s+[+-]?\d", text):
            raise MeasurementError(
                f"{path}, line {number}: commas and white space both separate numbers "
                f"({text[:40]!r}...), so the line can be read two ways (decimal commas, or "
                "comma-separated values). Set the surface's decimal option: decimal: ',' "
                "(white space separates values) or decimal: '.' (commas separate values).",
                path, number,
            )
        return ",", "."
    if decimal == "auto":
        decimal = "," if separator is not None and "," in text else "."
    return separator, decimal


def _split(text: str, separator: str | None, decimal: str) -> list[str]:
    tokens = text.split() if separator is None else [t.strip() for t in text.split(separator)]
    return [t.replace(",", ".") for t in tokens] if decimal == "," else tokens


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


def read_text_grid(path: str | os.PathLike, decimal: str = "auto") -> np.ndarray:
    """Heights ``(ny, nx)`` in the file's unit from a text grid (a row per y).

    The separator and the decimal mark are the first data line's (module
    documentation); every data row must have as many values as the first.
    A first line that is not numbers is a header: refused with a message
    saying so (comment it with ``#``, or read the file with ``format: auto``
    when an instrument wrote it).
    """
    rows, width, first, dialect = [], None, None, None
    for number, text in _data_lines(path):
        if dialect is None:
            dialect = _dialect(text, decimal, path, number)
        tokens = _split(text, *dialect)
        if width is None:
            width, first = len(tokens), number
            if not all(_NUMBER.match(t) for t in tokens):
                raise MeasurementError(
                    f"{path}, line {number}: the first data line is not numbers "
                    f"({text[:60]!r}): a header? Start header lines with #, or, for an "
                    "instrument's text export, use format: auto.", path, number,
                )
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


@dataclass(frozen=True)
class InstrumentData:
    """A height map as SurfaceTopography reads it from an instrument's file.

    ``heights`` ``(ny, nx)`` in ``unit`` (NaN where the instrument marked a
    point undefined), ``spacing`` ``(dx, dy)`` in ``unit``; ``unit`` and
    ``spacing`` are None where the file does not carry them. ``reader`` names
    the format, ``channel`` the data channel read (of ``channels``).
    """

    heights: np.ndarray
    spacing: tuple[float, float] | None
    unit: str | None
    masked: int
    reader: str
    channel: str
    channels: tuple[str, ...]


def read_instrument(path: str | os.PathLike, channel: int | str | None = None) -> InstrumentData:
    """Read an instrument's file through SurfaceTopography (format by content).

    ``channel``: index or name of the data channel (default: the file's
    default channel, the height channel of most instruments). Line scans
    (1-D profiles) are refused: the contact study needs a height map.
    """
    # SurfaceTopography takes 1-3 s to import: only runs that read instrument files pay it
    from SurfaceTopography import open_topography
    from SurfaceTopography.Exceptions import CannotDetectFileFormat

    try:
        reader = open_topography(str(path))
    except CannotDetectFileFormat:
        raise MeasurementError(
            f"{path}: not a format SurfaceTopography recognises (it reads x3p, sur, opd, "
            "plu, datx, MetroPro dat, al3d, frt, di, Gwyddion, ... by content). For a text "
            "grid use format: text, for a point list format: xyz, for a NumPy array "
            "format: npy.", path,
        ) from None
    except Exception as err:  # a reader that recognised the file but failed to parse it
        raise MeasurementError(f"{path}: SurfaceTopography could not read it ({err})",
                               path) from err
    names = tuple(str(c.name) for c in reader.channels)
    if channel is None:
        index = reader.default_channel.index
    elif isinstance(channel, str):
        if channel not in names:
            raise MeasurementError(f"{path}: no channel {channel!r}; the file has {list(names)}",
                                   path)
        index = names.index(channel)
    else:
        index = int(channel)
        if not 0 <= index < len(names):
            raise MeasurementError(f"{path}: channel {index} does not exist; the file has "
                                   f"{len(names)}: {list(names)}", path)
    info = reader.channels[index]
    if info.dim != 2:
        raise MeasurementError(
            f"{path}: channel {names[index]!r} is a line scan (a 1-D profile of "
            f"{info.nb_grid_pts[0]} points), not a height map; the contact study needs a "
            "2-D measurement of an area", path,
        )
    unit = info.unit
    sizes = info.physical_sizes
    try:
        topography = reader.topography(channel_index=index,
                                       **({} if unit is not None else {"unit": "m"}),
                                       **({} if sizes is not None else
                                          {"physical_sizes": tuple(info.nb_grid_pts)}))
    except Exception as err:
        raise MeasurementError(f"{path}: SurfaceTopography could not read channel "
                               f"{names[index]!r} ({err})", path) from err
    raw = topography.heights()
    mask = np.ma.getmaskarray(raw)
    heights = np.where(mask, np.nan, np.ma.getdata(raw)).astype(float).T.copy()
    nx, ny = topography.nb_grid_pts
    spacing = None if sizes is None else (float(sizes[0]) / nx, float(sizes[1]) / ny)
    return InstrumentData(heights, spacing, None if unit is None else str(unit),
                          int(mask.sum()), type(reader).__name__, names[index], names)


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
        most = 0.5  # the largest fill_holes the config allows (config/schema.yaml)
        if count == z.size or fraction > most:
            reason = ("no point is known, so there is nothing to interpolate from"
                      if count == z.size else
                      f"more than {100 * most:g} % of the map would be interpolated, beyond "
                      f"the largest fill_holes the study accepts ({most:g}, config/schema.yaml)")
            raise MeasurementError(
                f"{missing_message(source, count, z.size, absent)}: {reason}. The data "
                f"cannot be filled; repair {source} or re-export it from the instrument "
                "software (with the missing points measured or cropped away).",
                source,
            )
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
    interpolate = RegularGridInterpolator((old_y, old_x), heights)
    yy, xx = np.meshgrid(new_y, new_x, indexing="ij")
    values = interpolate(np.column_stack([yy.ravel(), xx.ravel()])).reshape(gy, gx)
    return values, (lx / gx, ly / gy)


# --------------------------------------------------------------------------- the measurement


@dataclass(frozen=True)
class Measurement:
    """A measured surface, imported and prepared for the contact study.

    Attributes
    ----------
    heights : ndarray (ny, nx)
        Heights [m]: holes filled, form removed, resampled (zero mean).
    spacing : (dx, dy)
        Grid spacing [m].
    source : str
        The file it was read from.
    sha256 : str
        SHA-256 of the file's bytes.
    options : dict
        The import and preparation options as given.
    filled : int
        Number of missing points filled by interpolation.
    plane : (a, b, c)
        The removed plane ``a + b x + c y``: offset [m], slopes [1].
    preparation : dict
        What was done, for the provenance: the reader and channel, the units
        and pixel size from the file, the crop window in points, the masked,
        filled and outlier points, the form's polynomial coefficients, the
        resampling.
    """

    heights: np.ndarray
    spacing: tuple[float, float]
    source: str
    sha256: str
    options: dict = field(default_factory=dict)
    filled: int = 0
    plane: tuple[float, float, float] = (0.0, 0.0, 0.0)
    preparation: dict = field(default_factory=dict)

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


def _pair_m(value, what: str) -> tuple[float, float]:
    pair = tuple(float(v) for v in np.broadcast_to(np.asarray(value, float), (2,)))
    if not all(math.isfinite(v) and v > 0 for v in pair):
        raise ValueError(f"{what} must be positive and finite [m]; got {value!r}")
    return pair


def resolve_format(path, format: str) -> str:
    """The reader of ``path``: ``format``, or for ``auto`` the one its suffix names
    (:data:`OWN_SUFFIXES`), else ``instrument``."""
    if format not in FORMATS:
        raise ValueError(f"format must be one of {FORMATS}; got {format!r}")
    if format != "auto":
        return format
    return OWN_SUFFIXES.get(Path(path).suffix.lower(), "instrument")


def _read(path: Path, kind: str, *, height_unit, lateral_unit, spacing, channel, decimal):
    """Raw heights [m] (NaN: missing), spacing [m], absent points, and what the file said."""
    said = {"reader": kind}
    absent = 0
    if kind == "instrument":
        data = read_instrument(path, channel)
        said.update(reader=data.reader, channel=data.channel, file_unit=data.unit,
                    masked_points=data.masked)
        if data.unit is not None:
            file_scale = _unit(data.unit, INSTRUMENT_UNITS, f"{path}: the file's unit")
            if height_unit is not None and \
                    not math.isclose(HEIGHT_UNITS[height_unit], file_scale, rel_tol=1e-12):
                raise ValueError(
                    f"{path}: height_unit {height_unit!r} contradicts the file, whose heights "
                    f"are in {data.unit}; drop height_unit (the file's unit is used)")
            scale = file_scale
        elif height_unit is None:
            raise ValueError(f"{path}: the file does not say the unit of its heights; set "
                             "height_unit (nm, um, mm or m)")
        else:
            scale = HEIGHT_UNITS[height_unit]
        if data.spacing is not None:
            file_spacing = (data.spacing[0] * scale, data.spacing[1] * scale)
            if spacing is not None and not all(
                    math.isclose(a, b, rel_tol=CONTRADICTION_RTOL)
                    for a, b in zip(spacing, file_spacing, strict=True)):
                raise ValueError(
                    f"{path}: spacing {spacing[0]:g} x {spacing[1]:g} m contradicts the file's "
                    f"pixel size {file_spacing[0]:g} x {file_spacing[1]:g} m; drop spacing_mm")
            spacing = file_spacing
        elif spacing is None:
            raise ValueError(f"{path}: the file does not say its pixel size; set spacing_mm "
                             "([dx, dy])")
        said["file_spacing_m"] = list(spacing)
        return data.heights * scale, spacing, absent, said
    if height_unit is None:
        raise ValueError(f"{path}: a {kind} file does not carry its height unit; set "
                         "height_unit (nm, um, mm or m)")
    scale = HEIGHT_UNITS[height_unit]
    if kind == "xyz":
        if spacing is not None:
            raise ValueError(f"{path}: an xyz point list gives its own spacing; drop the spacing")
        lateral = _unit(lateral_unit, LATERAL_UNITS, "lateral_unit")
        raw, (dx, dy), absent = read_xyz(path, lateral_unit)
        return raw * scale, (dx * lateral, dy * lateral), absent, said
    if spacing is None:
        raise ValueError(f"{path}: a {kind} grid needs its spacing (dx, dy)")
    raw = read_npy(path) if kind == "npy" else read_text_grid(path, decimal)
    return raw * scale, spacing, absent, said


def load_measurement(path: str | os.PathLike, format: str = "auto", *,
                     height_unit: str | None = None, lateral_unit: str = "mm", spacing=None,
                     fill_holes: float = 0.0, channel: int | str | None = None,
                     decimal: str = "auto", crop=None, form_degree: int = 1,
                     outliers_sigma: float | None = None, decimate_by: int | None = None,
                     resample_grid=None) -> Measurement:
    """Import a measured height map and prepare it for the study, in SI units.

    Parameters
    ----------
    path : path-like
        The file.
    format : {"auto", "instrument", "npy", "text", "xyz"}
        See the module documentation; ``auto`` chooses by the file.
    height_unit : {"nm", "um", "mm", "m"}, optional
        Unit of the heights, where the file does not say (npy, text, xyz and
        instrument files without units); refused where it contradicts the file.
    lateral_unit : {"um", "mm", "m"}
        Unit of the x, y coordinates of an ``xyz`` file.
    spacing : (dx, dy) [m], optional
        Grid spacing, where the file does not say (npy and text grids);
        refused for ``xyz`` files and where it contradicts an instrument file.
    fill_holes : float
        Largest fraction of missing or masked points to fill (:func:`fill_missing`).
    channel : int or str, optional
        Data channel of an instrument file (default: the file's default).
    decimal : {"auto", ".", ","}
        Decimal mark of a text grid.
    crop : (x0, y0, Lx, Ly) [m], optional
        Window from the first point (:func:`crop_window`), before anything else.
    form_degree : int
        1: the least-squares plane is removed; k >= 2: then the polynomial of
        total degree k (:func:`remove_polynomial`).
    outliers_sigma : float, optional
        Points farther than this many sigma from the mean plane are filled as
        holes (counted in ``preparation``), and the form removed again.
    decimate_by : int, optional
        Means of k x k blocks (:func:`decimate`).
    resample_grid : (nx, ny), optional
        Linear interpolation onto this grid over the same plan size (:func:`resample`).

    Raises
    ------
    MeasurementError
        For a file that cannot be used, naming the file and the line, the
        missing fraction, the non-uniform axis or the format.
    ValueError
        For inconsistent options (unknown unit or format, a unit or spacing
        missing, or contradicting the file).
    """
    path = Path(path)
    kind = resolve_format(path, format)
    if height_unit is not None:
        _unit(height_unit, HEIGHT_UNITS, "height_unit")
    if not 0.0 <= float(fill_holes) < 1.0:
        raise ValueError(f"fill_holes must be a fraction in [0, 1); got {fill_holes!r}")
    if int(form_degree) != form_degree or not 1 <= form_degree <= 6:
        raise ValueError(f"form_degree must be an integer from 1 (plane) to 6; got "
                         f"{form_degree!r}")
    if decimate_by is not None and resample_grid is not None:
        raise ValueError("give decimate or resample_grid, not both")
    if not path.is_file():
        raise MeasurementError(f"{path}: no such file", path)
    spacing = given = None if spacing is None else _pair_m(spacing, "spacing")
    raw, spacing, absent, said = _read(path, kind, height_unit=height_unit,
                                       lateral_unit=lateral_unit, spacing=spacing,
                                       channel=channel, decimal=decimal)
    ny, nx = raw.shape
    if min(nx, ny) < MIN_POINTS:
        raise MeasurementError(
            f"{path}: a {nx} x {ny} grid (nx x ny); a surface needs at least {MIN_POINTS} "
            "points along each axis", path,
        )
    preparation = {**said, "file_grid": [nx, ny]}
    if crop is not None:
        raw, window = crop_window(raw, spacing, crop, str(path))
        preparation["crop_points"] = list(window)
    filled_raw, filled = fill_missing(raw, float(fill_holes), source=str(path), absent=absent)
    heights, plane = remove_plane(filled_raw, spacing)
    if not np.ptp(heights) > 1e-12 * max(np.ptp(filled_raw), np.finfo(float).tiny):
        raise MeasurementError(f"{path}: the heights are a plane (no roughness left)", path)
    if form_degree > 1:
        heights, coefficients = remove_polynomial(heights, spacing, int(form_degree))
        preparation["form_coefficients"] = coefficients
    if outliers_sigma is not None:
        far = np.abs(heights) > float(outliers_sigma) * heights.std()
        preparation["outliers"] = int(far.sum())
        if far.any():
            log.info("%s: %d points beyond %g sigma filled as holes", path, int(far.sum()),
                     outliers_sigma)
            heights, _ = fill_missing(np.where(far, np.nan, heights), 1.0 - 1e-12,
                                      source=f"{path} (outliers)")
            heights, _ = remove_plane(heights, spacing)
            if form_degree > 1:
                heights, _ = remove_polynomial(heights, spacing, int(form_degree))
    if decimate_by is not None:
        heights = decimate(heights, int(decimate_by))
        spacing = (spacing[0] * decimate_by, spacing[1] * decimate_by)
        heights = heights - heights.mean()
        preparation["decimated_by"] = int(decimate_by)
    elif resample_grid is not None:
        heights, spacing = resample(heights, spacing, resample_grid)
        heights = heights - heights.mean()
        preparation["resampled_to"] = [int(v) for v in resample_grid]
    options = {"format": format, "height_unit": height_unit, "lateral_unit": lateral_unit,
               "spacing": None if given is None else list(given),
               "fill_holes": float(fill_holes), "channel": channel, "decimal": decimal,
               "crop": None if crop is None else [float(v) for v in crop],
               "form_degree": int(form_degree), "outliers_sigma": outliers_sigma,
               "decimate": decimate_by,
               "resample_grid": None if resample_grid is None else list(resample_grid)}
    return Measurement(heights, (float(spacing[0]), float(spacing[1])), str(path),
                       file_sha256(path), options, filled, plane, preparation)


def statistics(measurement: Measurement, spectral: bool = False) -> dict:
    """Height statistics of a measurement and the Johnson law of its moments.

    Returns plain values: ``sigma`` [m], ``skew``, ``kurt`` (Pearson), ``mean``
    [m] (zero after detrending), ``corr_length_x``, ``corr_length_y`` [m]
    (lags of 10 % ACF decay, non-periodic estimate; NaN, with a warning that
    names the direction, where the ACF stays above 10 % over half the
    window), ``grid`` [nx, ny], ``size`` [Lx, Ly] [m],
    ``spacing`` [dx, dy] [m], ``filled_points``, ``filled_fraction``, the
    removed plane (``plane_offset`` [m], ``plane_slope_x``, ``plane_slope_y``),
    and ``johnson_family`` with ``johnson_params`` ``[gamma, delta, xi, lam]``
    of the law fitted to (Sk, Ku) for heights in units of sigma (zero mean,
    unit standard deviation).

    With ``spectral``, by SurfaceTopography on the prepared heights (not
    periodic): ``rms_slope`` [1] (rms gradient), ``rms_curvature`` [1/m]
    (from the area's Laplacian) and the isotropic power spectral density
    ``psd_q`` [1/m] (wavevectors) and ``psd_C`` [m^4].
    """
    z = measurement.heights
    moments = height_stats(z)
    bx, by = correlation_length(z, measurement.spacing, periodic=False)
    for name, value, side in (("x", bx, measurement.size[0]), ("y", by, measurement.size[1])):
        if not math.isfinite(value):
            log.warning(
                "%s: the %s autocorrelation does not fall to 10 %% within half the window "
                "(%.4g mm): corr_length_%s is NaN. A form or waviness is left: remove it "
                "(form_degree: 2 or more), or measure (or crop) a window several "
                "correlation lengths wide.", measurement.source, name, side / 2e-3, name)
    curve = johnson.fit(moments["skew"], moments["kurt"])
    stats = {
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
    if spectral:
        stats.update(spectral_statistics(measurement))
    return stats


def spectral_statistics(measurement: Measurement) -> dict:
    """``rms_slope``, ``rms_curvature``, ``psd_q`` and ``psd_C`` of :func:`statistics`."""
    # SurfaceTopography takes 1-3 s to import: only the jobs that store these pay it
    from SurfaceTopography import Topography

    topography = Topography(np.ascontiguousarray(measurement.heights.T), measurement.size,
                            periodic=False, unit="m")
    q, C = (np.ma.filled(np.ma.asarray(v, dtype=float), np.nan)
            for v in topography.power_spectrum_from_area())
    keep = np.isfinite(q) & np.isfinite(C) & (q > 0)
    return {
        "rms_slope": float(topography.rms_gradient()),
        "rms_curvature": float(topography.rms_curvature_from_area()),
        "psd_q": [float(v) for v in q[keep]],
        "psd_C": [float(v) for v in C[keep]],
    }


#: Columns of a PSD table file (:func:`read_psd_table`).
PSD_COLUMNS = ("q_per_mm", "C")


def psd_table_from_measurement(measurement: Measurement) -> tuple[tuple[float, float], ...]:
    """The isotropic PSD of a measurement as a ``SurfaceSpec(acf="psd")`` table.

    ``psd_q`` [1/m] and ``psd_C`` [m^4] of :func:`spectral_statistics`
    (SurfaceTopography's ``power_spectrum_from_area`` on the prepared,
    non-periodic heights), without the bins whose q or C is not finite or not
    positive, sorted by q (a repeated q keeps its first bin). Returns
    ``((q, C), ...)`` checked by
    :func:`roughcontact.surfaces.synthetic.check_psd_table`.
    """
    spectral = spectral_statistics(measurement)
    q = np.asarray(spectral["psd_q"], dtype=float)
    c = np.asarray(spectral["psd_C"], dtype=float)
    keep = np.isfinite(q) & np.isfinite(c) & (q > 0) & (c > 0)
    q, c = q[keep], c[keep]
    q, first = np.unique(q, return_index=True)
    return check_psd_table(np.column_stack([q, c[first]]),
                           f"{measurement.source}: the measured PSD")


def read_psd_table(path: str | os.PathLike) -> tuple[tuple[float, float], ...]:
    """An isotropic PSD table from a CSV file with columns ``q_per_mm,C``.

    ``q_per_mm`` is the wavenumber magnitude ``q = 2 pi / wavelength`` [1/mm]
    (so a 1 mm wavelength is 6.283), positive and strictly increasing; ``C``
    the isotropic 2-D PSD ``C(q) >= 0`` in any unit (only its shape matters).
    Read with pandas (a header line, comma separators; other columns are
    refused). Returns ``((q [1/m], C), ...)`` for ``SurfaceSpec(acf="psd")``.

    Raises
    ------
    MeasurementError
        When the file is missing, cannot be parsed, has other columns or
        non-numeric values, or its table is not a valid PSD
        (:func:`roughcontact.surfaces.synthetic.check_psd_table`).
    """
    import pandas as pd

    path = Path(path)
    if not path.is_file():
        raise MeasurementError(f"{path}: no such file (a PSD table with columns "
                               f"{','.join(PSD_COLUMNS)})", path)
    try:
        frame = pd.read_csv(path, comment="#", skipinitialspace=True)
    except (ValueError, pd.errors.ParserError, UnicodeDecodeError) as err:
        raise MeasurementError(f"{path}: not a CSV table ({err}); write a header line "
                               f"{','.join(PSD_COLUMNS)} and one row per wavenumber", path
                               ) from None
    columns = [str(c).strip() for c in frame.columns]
    if columns != list(PSD_COLUMNS):
        raise MeasurementError(
            f"{path}: columns {columns}; expected exactly {list(PSD_COLUMNS)}: q = 2 pi / "
            "wavelength in 1/mm, and the isotropic PSD C(q) in any unit", path)
    values = frame.apply(pd.to_numeric, errors="coerce")
    bad = values.isna().any(axis=1).to_numpy().nonzero()[0]
    if bad.size:
        row = int(bad[0])
        raise MeasurementError(f"{path}: row {row + 1} of the table, "
                               f"{frame.iloc[row].tolist()}, is not two numbers (q_per_mm, C)",
                               path)
    table = values.to_numpy(dtype=float) * np.array([1.0 / MM, 1.0])
    try:
        return check_psd_table(table, f"{path} (q in 1/m)")
    except ValueError as err:
        raise MeasurementError(str(err), path) from None


__all__ = [
    "FORMATS",
    "PSD_COLUMNS",
    "InstrumentData",
    "HEIGHT_UNITS",
    "LATERAL_UNITS",
    "Measurement",
    "crop_window",
    "decimate",
    "fill_missing",
    "file_sha256",
    "load_measurement",
    "psd_table_from_measurement",
    "read_psd_table",
    "read_instrument",
    "read_npy",
    "read_text_grid",
    "read_xyz",
    "remove_plane",
    "remove_polynomial",
    "resample",
    "resolve_format",
    "spectral_statistics",
    "statistics",
]
