"""Reading measured height maps from files, in SI units.

A measured surface (from a profilometer, an optical instrument or an AFM)
enters the study in place of a generated one. Formats (``format``):

- ``auto`` (the default): chosen by the file's name (:func:`resolve_format`).
  ``.npy``, ``.xyz`` and ``.csv`` files are read as below; every other file
  by SurfaceTopography (ContactEngineering) in the instrument's format its
  suffix names (x3p, sur, opd, plu, datx, MetroPro dat, al3d, frt, Gwyddion
  and text exports, ...; :func:`read_instrument`), which must parse the
  file: a file that does not is refused, naming the file and the format.
  A suffix no format claims (``.di``, ``.bin``, ...) is read by content, as
  ``instrument``. SurfaceTopography gives the height unit, the pixel size and
  the instrument's mask of undefined points from the file's metadata.
- ``instrument``: through SurfaceTopography, the format recognised by the
  file's content whatever its name, among the formats that check a
  signature (:data:`UNSIGNED_FORMATS`, which would read any file of the
  right size, only from files named for them).
- ``npy``: a NumPy ``.npy`` file holding one 2-D array of heights, axis 0 = y,
  axis 1 = x (:func:`read_npy`); the spacing comes from the configuration.
- ``text``: a grid of heights as text, one row of the file per y, one column
  per x (:func:`read_text_grid`). The separator is the first line's: ``;``,
  else a tab, else ``,``, else white space. Decimal commas (``1,234;2,345``,
  as instruments set to a German or French locale write them) are read with
  ``;`` or tab separators (``decimal: auto`` or ``","``), or with white space
  when ``decimal: ","`` says so; a line that could be read two ways is
  refused. Lines starting with ``#`` (and anything after a ``#``) are
  comments.
- ``xyz``: a list of points ``x y z`` (same separators and comments), one per
  line, in any order, on a regular grid (:func:`read_xyz`). The spacing is
  inferred from the coordinates and the grid is checked: every coordinate
  must lie on ``x0 + k dx`` within ``SPACING_RTOL`` of the spacing.

:func:`read_heights` reads any of them and converts to metres. The height
unit and the spacing are needed only where the file does not carry them,
and refused where they contradict it. Missing points are written ``nan`` in
grids; in point lists a grid point may also be absent. Arrays are
``(ny, nx)``, row-major over y then x.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from roughcontact.errors import MeasurementError

FORMATS = ("auto", "instrument", "npy", "text", "xyz")
#: Formats ``auto`` reads with our own readers, by the file's suffix; every
#: other file goes to SurfaceTopography.
OWN_SUFFIXES = {".npy": "npy", ".xyz": "xyz", ".csv": "text"}
#: Height units a configuration may declare, in metres.
HEIGHT_UNITS = {"nm": 1e-9, "um": 1e-6, "mm": 1e-3, "m": 1.0}
#: Units SurfaceTopography reports for a file's heights and lengths, in metres.
INSTRUMENT_UNITS = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "\u00b5m": 1e-6, "\u03bcm": 1e-6,
                    "nm": 1e-9, "pm": 1e-12, "\u00c5": 1e-10, "A": 1e-10}
#: SurfaceTopography's formats without a signature at the start of the file: their
#: readers take any file of the right size (``hgt``: any 2 n^2 bytes, as a map of
#: n x n 16-bit heights), so they read only files named for them.
UNSIGNED_FORMATS = ("hgt", "nms")
#: SurfaceTopography's plain-text formats: a suffix either claims admits both.
TEXT_FORMATS = ("xyz", "asc")
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


def _reader_formats(path, by_content: bool) -> tuple[list, str]:
    """SurfaceTopography's reader classes that may read ``path``, in the library's order,
    and what chose them (for messages).

    By name (``by_content`` False, ``format: auto``): the readers whose formats
    claim the file's suffix (:meth:`file_extensions`; a plain-text suffix
    admits both plain-text readers, :data:`TEXT_FORMATS`). By content (``format:
    instrument``, or a suffix no format claims): every reader but the formats
    without a signature (:data:`UNSIGNED_FORMATS`), which would take any file
    of the right size, unless the file is named for them.
    """
    from SurfaceTopography.IO import readers

    suffix = Path(path).suffix.lower().lstrip(".")
    named = {r.format() for r in readers if suffix and suffix in r.file_extensions()}
    if named & set(TEXT_FORMATS):
        named |= set(TEXT_FORMATS)
    if named and not by_content:
        return [r for r in readers if r.format() in named], f"its suffix .{suffix}"
    return ([r for r in readers if r.format() not in UNSIGNED_FORMATS or r.format() in named],
            "its content")


def _open_instrument(path, by_content: bool):
    """The reader object of :func:`read_instrument`: the first of :func:`_reader_formats`
    that opens the file (readers whose signature the file's first bytes rule out are
    skipped), or a MeasurementError naming the file, the formats tried and why."""
    from SurfaceTopography.IO import _instantiate_reader
    from SurfaceTopography.IO.Reader import MagicMatch

    candidates, chosen_by = _reader_formats(path, by_content)
    with open(path, "rb") as f:
        head = f.read(512)
    failures = []
    for reader in candidates:
        if reader.can_read(head) == MagicMatch.NO:
            failures.append((reader, "its signature is not at the start of the file"))
            continue
        try:
            opened = _instantiate_reader(reader, str(path), None)
        except Exception as err:  # the reader's own reasons, quoted in the message
            failures.append((reader, " ".join(str(err).split())[:160] or type(err).__name__))
            continue
        if opened.channels:
            return opened
        failures.append((reader, "it holds no data channel"))
    if chosen_by == "its content":
        raise MeasurementError(
            f"{path}: not a format SurfaceTopography recognises by its content (it reads x3p, "
            "sur, opd, plu, datx, MetroPro dat, al3d, frt, di, Gwyddion, ...; formats "
            f"without a signature ({', '.join(UNSIGNED_FORMATS)}) only from files named for "
            "them). For a text grid use format: text, for a point list format: xyz, for a "
            "NumPy array format: npy.", path)
    tried = "; ".join(f"{r.name()} ({r.format()}): {why}" for r, why in failures)
    which = ("the format" if len(failures) == 1 else "any of the formats")
    raise MeasurementError(
        f"{path}: not readable as {which} {chosen_by} names ({tried}). The file is damaged, "
        "or in another format: re-export it from the instrument's software, or, if it is "
        "in another format, give it that format's suffix or set format: instrument (the "
        "format recognised by the file's content).", path)


def read_instrument(path: str | os.PathLike, channel: int | str | None = None, *,
                    by_content: bool = False) -> InstrumentData:
    """Read an instrument's file through SurfaceTopography, in the format its name says.

    The reader is chosen by the file's suffix (:func:`_reader_formats`: ``.sur``
    the Digital Surf reader, ``.x3p`` the X3P reader, ...) and the file must
    parse as that format; with ``by_content`` (``format: instrument``), or for a
    suffix no format claims, by the file's content, among the formats that
    check a signature. ``channel``: index or name of the data channel
    (default: the file's default channel, the height channel of most
    instruments). Line scans (1-D profiles) are refused: the contact study
    needs a height map.
    """
    reader = _open_instrument(path, by_content)
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


# --------------------------------------------------------------------------- any format, in SI


def unit_scale(value: str, table: dict, what: str) -> float:
    """Metres per ``value`` from a unit table; ValueError naming ``what`` if unknown."""
    if value not in table:
        raise ValueError(f"{what} must be one of {sorted(table)}; got {value!r}")
    return table[value]


def resolve_format(path, format: str) -> str:
    """The reader of ``path``: ``format``, or for ``auto`` the one its suffix names
    (:data:`OWN_SUFFIXES`), else ``named``: an instrument's format, the one its suffix
    says (:func:`read_instrument`)."""
    if format not in FORMATS:
        raise ValueError(f"format must be one of {FORMATS}; got {format!r}")
    if format != "auto":
        return format
    return OWN_SUFFIXES.get(Path(path).suffix.lower(), "named")


def read_heights(path: Path, kind: str, *, height_unit, lateral_unit, spacing, channel, decimal):
    """Raw heights [m] of a file in format ``kind`` (resolved, :func:`resolve_format`).

    ``height_unit`` and ``spacing`` [m] are the configuration's (None where it
    gives none), the other options those of the readers. Returns ``(heights
    (ny, nx) [m] with NaN at missing points, (dx, dy) [m], points absent from a
    point list, what the file said)``: the last a dict for the provenance
    (``reader``, and for instrument files ``channel``, ``file_unit``,
    ``masked_points``, ``file_spacing_m``).
    """
    return _READERS[kind](path, kind, height_unit=height_unit, lateral_unit=lateral_unit,
                          spacing=spacing, channel=channel, decimal=decimal)


def _read_instrument_file(path, kind, *, height_unit, lateral_unit, spacing, channel, decimal):
    """:func:`read_heights` for an instrument's file: the unit and pixel size from the file;
    its format by its content (``instrument``) or its name (``named``)."""
    data = read_instrument(path, channel, by_content=kind == "instrument")
    said = {"reader": data.reader, "channel": data.channel, "file_unit": data.unit,
            "masked_points": data.masked}
    if data.unit is not None:
        file_scale = unit_scale(data.unit, INSTRUMENT_UNITS, f"{path}: the file's unit")
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
    return data.heights * scale, spacing, 0, said


def _height_scale(path, kind: str, height_unit) -> float:
    """Metres per height unit of a file that does not carry its unit (npy, text, xyz)."""
    if height_unit is None:
        raise ValueError(f"{path}: a {kind} file does not carry its height unit; set "
                         "height_unit (nm, um, mm or m)")
    return HEIGHT_UNITS[height_unit]


def _read_xyz_file(path, kind, *, height_unit, lateral_unit, spacing, channel, decimal):
    """:func:`read_heights` for a point list: the spacing from its coordinates."""
    scale = _height_scale(path, kind, height_unit)
    if spacing is not None:
        raise ValueError(f"{path}: an xyz point list gives its own spacing; drop the spacing")
    lateral = unit_scale(lateral_unit, LATERAL_UNITS, "lateral_unit")
    raw, (dx, dy), absent = read_xyz(path, lateral_unit)
    return raw * scale, (dx * lateral, dy * lateral), absent, {"reader": kind}


def _grid_reader(read):
    """:func:`read_heights` for a grid file read by ``read(path, decimal)``: spacing given."""

    def read_grid(path, kind, *, height_unit, lateral_unit, spacing, channel, decimal):
        scale = _height_scale(path, kind, height_unit)
        if spacing is None:
            raise ValueError(f"{path}: a {kind} grid needs its spacing (dx, dy)")
        return read(path, decimal) * scale, spacing, 0, {"reader": kind}

    return read_grid


#: The reader of each format :func:`resolve_format` gives.
_READERS = {
    "instrument": _read_instrument_file,
    "named": _read_instrument_file,
    "xyz": _read_xyz_file,
    "npy": _grid_reader(lambda path, decimal: read_npy(path)),
    "text": _grid_reader(read_text_grid),
}
