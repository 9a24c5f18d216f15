"""HDF5 files of the pipeline: one reader and one writer per file kind, each with its hash.

Every file is written atomically (temporary name, then rename), with units,
provenance and the SHA-256 of its datasets (``content_sha256``), and every
read checks that hash first: a file that is unreadable, has no hash or no
longer matches it raises :class:`~roughcontact.errors.StoredFileError` naming
the file (delete it, and the workflow rebuilds it), never a silent use.

A file is also never trusted by its name: each carries the parameters that
define it (a surface cell's ``params`` and ``study_seed``, a geometry's
``params``, a contact job's ``job``), and a reader given what its job
expects (``cell=``, ``geometry=``, ``job=``) compares them field by field,
and the shapes of the datasets with them, before it uses anything
(:func:`check_parameters`); a file copied or renamed from another one is
refused naming the field, the value expected and the value found, and the
command that rebuilds it.

Layout of a surface file (``results/surfaces/<cell>.h5``)::

    /heights        (m, ny, nx) float64  heights / sigma, zero mean per surface
    /seeds          (m,)        int64    white-noise seed of each surface
    /stats/mean, sigma, skew, kurt   (m,)  realised moments (Eq 2-5), heights / sigma
    /stats/corr_length_x, corr_length_y (m,) [m] lag of 10 % ACF decay
    attributes: cell, study_seed, spec (JSON), every spec field, the filter's
                S3 and S4, the input moments and Johnson curve, provenance,
                format_version; a cell whose surfaces were taken from a larger
                cell's file: surfaces_from and surfaces_from_sha256 (its path
                and content hash)

Layout of an influence file (``results/influence/<geometry>.h5``)::

    /unit_influence (n, n)  E * C [m] of a dense model, or
    /correction     (nc, nc) the finite-body correction [1/m] of a matrix-free
                    hybrid operator (none for the half-space)
    attributes: geometry, params, operator (dense, hybrid or halfspace), checks,
                content_sha256, provenance, format_version

Layout of a contact file (``results/contact/<surface cell>__<geometry>.h5``)::

    /<field>   (m, k)  every array of NondimSweep in CONTACT_ARRAYS (dimensionless;
               the dataset ``stiffness`` is the field ``normalized_stiffness``, k_P / E)
    /profile_ranks (R,) int64, /pressure_profile and /load_profile (m, k, R)
               float32: each solution's pressure and load profiles
               (:mod:`roughcontact.contact.validity`), when recorded
    /spot_count, /mean_spot_area, /perimeter, /corrected_real_area_fraction,
    /mean_gap (m, k), /spot_area_quantiles (m, k, S) and /gap_quantiles (m, k, G)
               float32: the interface quantities (:mod:`roughcontact.contact.interface`;
               lateral ones in m and m^2, gaps in units of sigma), when recorded
    /<column>  (m, k): every column of the probes the sweep recorded
               (:mod:`roughcontact.contact.probes`; in units of
               ``sigma**length_power``), under its name, e.g. the flow through the gap
               (:mod:`roughcontact.transport.probe`)
    /solved_by (m, k) ASCII: the method whose solution each step holds, only where a
               fallback answered some step (absent: every step is ``sweep_method``'s)
    attributes: job (JSON), each probe's settings (JSON) under its kind (``flow``; the
                probes are made again from them, :mod:`roughcontact.study.probes`),
                the NondimSweep settings (``sweep_*``; ``sweep_hardness``
                the dimensionless cap ``nondim_hardness`` H L / (E sigma), -1 for an
                elastic sweep), solver
                statistics, the content hashes of the contact arrays and of
                the surface and influence inputs, provenance, format_version

Arrays are row-major over y then x (axis 0 is y), the element ordering of the
influence matrices.

Every file carries the layout version it was written in (root attribute
``format_version``, :data:`FORMAT_VERSION`); a file without one is version 1.
What a version-1 file may lack, and the value that holds for it, is listed in
:data:`VERSION_1_LACKED` and filled by the readers in one place
(:func:`upgraded`); nothing past them repeats such a default. A file of a
newer version than this package writes is refused.
"""

from __future__ import annotations

import contextlib
import json
import os
from typing import TYPE_CHECKING

import h5py
import numpy as np

from roughcontact.errors import StoredFileError
from roughcontact.hashes import array_sha256, arrays_sha256
from roughcontact.study.provenance import atomic_path, canonical_json

if TYPE_CHECKING:
    from roughcontact.contact.curves import NondimSweep

#: Arrays of a contact file (the fields of NondimSweep that are stored), by dataset name.
CONTACT_ARRAYS = ("approach", "nominal_pressure", "mean_plane_deflection",
                  "real_area_fraction", "max_pressure", "stiffness", "iterations", "matvecs",
                  "residual", "converged", "stiffness_converged", "plastic_area_fraction")
#: NondimSweep field of a dataset named otherwise: ``stiffness`` is ``k_P / E``.
CONTACT_FIELDS = {"stiffness": "normalized_stiffness"}
#: Optional arrays of a contact file: the solutions' profiles, stored in single
#: precision (7 digits; the shares read from them are interpolated to about 1 %).
PROFILE_ARRAYS = ("profile_ranks", "pressure_profile", "load_profile")
#: Optional arrays of a contact file: the interface quantities
#: (:mod:`roughcontact.contact.interface`); the (m, k, S) and (m, k, G) quantiles in
#: single precision, like the profiles.
INTERFACE_ARRAYS = ("spot_count", "mean_spot_area", "perimeter",
                    "corrected_real_area_fraction", "mean_gap", "spot_area_quantiles",
                    "gap_quantiles")
#: Optional arrays of a contact file: of a pair of elastic bodies, the counter body's
#: mean-plane deflection (m, k) (:mod:`roughcontact.contact.counterface`).
COUNTER_ARRAYS = ("counter_deflection",)
#: Stored only where a fallback answered some step (:mod:`roughcontact.contact.retries`):
#: the method whose solution each step holds (fixed-length ASCII); absent, every step
#: holds the sweep's ``method``.
METHOD_ARRAYS = ("solved_by",)
#: Scalar settings of NondimSweep, stored as ``sweep_<name>`` attributes.
SWEEP_SETTINGS = ("thickness", "element_area", "n_elements", "method", "tol", "stiffness_tol",
                  "precision")


#: The layout version of the files this module writes (root attribute ``format_version``).
#: 2: every influence file names its ``operator`` (a dense matrix too) and every file
#: carries ``format_version``; 1: the files before (no ``format_version``).
FORMAT_VERSION = 2

#: Root attributes that a version-1 file of each kind may lack, with the value that holds
#: for it. Influence files from before the matrix-free operators held the dense
#: finite-element matrix and named no ``operator``; contact files from before the
#: hardness cap were elastic sweeps, ``sweep_hardness`` -1 (no cap).
VERSION_1_LACKED = {
    "surfaces": {},
    "influence": {"operator": "dense"},
    "contact": {"sweep_hardness": -1.0},
}


def upgraded(path, attrs: dict, kind: str) -> dict:
    """A file's root attributes in the current layout: a version-1 file (no
    ``format_version``) with what it lacked filled in (:data:`VERSION_1_LACKED` of its
    ``kind``); a file of a newer version than :data:`FORMAT_VERSION` raises
    :class:`StoredFileError`."""
    version = int(attrs["format_version"]) if "format_version" in attrs else 1
    if version > FORMAT_VERSION:
        raise StoredFileError(f"{path}: written in file format version {version} by a newer "
                              f"roughcontact (this one reads up to {FORMAT_VERSION}); update "
                              f"roughcontact, or {rebuild(path)}", path)
    if version == 1:
        return {**VERSION_1_LACKED.get(kind, {}), **attrs}  # pair files began in version 2
    return attrs


def _attr_value(value):
    if isinstance(value, dict | list | tuple):
        return json.dumps(value)
    if value is None:
        return ""
    if isinstance(value, bool | np.bool_):
        return bool(value)
    return value


def decoded(attrs) -> dict:
    """HDF5 attributes as a dict, byte strings decoded (JSON text left as text)."""
    return {k: (v.decode() if isinstance(v, bytes) else v) for k, v in attrs.items()}


REBUILD = "delete it and run the workflow again to rebuild it"


@contextlib.contextmanager
def open_h5(path: str | os.PathLike):
    """``h5py.File(path, "r")``; an unreadable file raises :class:`StoredFileError`."""
    try:
        f = h5py.File(path, "r")
    except FileNotFoundError:
        raise
    except OSError as err:
        raise StoredFileError(f"{path}: not a readable HDF5 file (truncated or damaged: "
                              f"{err}); {rebuild(path)}", path) from None
    try:
        yield f
    except (OSError, KeyError) as err:
        raise StoredFileError(f"{path}: a dataset cannot be read (truncated or damaged: "
                              f"{err}); {rebuild(path)}", path) from None
    finally:
        f.close()


def datasets_sha256(datasets: dict) -> str:
    """``content_sha256`` of a file's datasets (name -> array; :func:`arrays_sha256`)."""
    return arrays_sha256({name: np.asarray(item[0] if isinstance(item, tuple) else item)
                          for name, item in datasets.items()})


def all_datasets(f) -> dict:
    arrays = {}
    f.visititems(lambda name, obj: arrays.__setitem__(name, obj[()])
                 if isinstance(obj, h5py.Dataset) else None)
    return arrays


def verify(path, attrs: dict, computed: str) -> None:
    """Raise :class:`StoredFileError` unless ``computed`` is the file's ``content_sha256``."""
    stored = attrs.get("content_sha256")
    if not stored:
        raise StoredFileError(f"{path}: no content hash (written by an older version of "
                              f"roughcontact, or not by it); {rebuild(path)}", path)
    if stored != computed:
        raise StoredFileError(
            f"{path}: its datasets no longer match the hash written with them (sha256 "
            f"{computed[:12]}, written {stored[:12]}): the file was changed or damaged after "
            f"it was made; {rebuild(path)}", path)


def rebuild(path) -> str:
    """The advice of a refusal: how the workflow rebuilds the stored file ``path``."""
    return (f"delete it and run the workflow again to rebuild it (rm {path}, then the same "
            "snakemake command: it remakes the file and every result made from it)")


#: The fields of a contact job's ``params()`` that define its file (its surfaces, geometry,
#: sweep end and cap; the accuracy preset's name and expected errors only label it).
CONTACT_DEFINING = ("surface", "geometry", "pressure_end", "hardness")


def json_attr(value):
    """An attribute stored as JSON text, parsed (None when absent or not JSON)."""
    if not isinstance(value, str) or not value:
        return value if isinstance(value, dict) else None
    try:
        return json.loads(value)
    except ValueError:
        return None


def _same(expected, found) -> bool:
    """Equal values; numbers to a relative 1e-9 (a bool is no number here)."""
    flags = (bool, np.bool_)
    if isinstance(expected, flags) or isinstance(found, flags):
        return isinstance(expected, flags) and isinstance(found, flags) \
            and bool(expected) == bool(found)
    numbers = (int, float, np.number)
    if isinstance(expected, numbers) and isinstance(found, numbers):
        return bool(np.isclose(float(expected), float(found), rtol=1e-9, atol=0.0))
    return expected == found


def field_differences(expected, found, where: str = "") -> list[tuple[str, object, object]]:
    """``(field, expected, found)`` of every field where ``found`` differs (nested dicts
    field by field, dotted paths)."""
    if isinstance(expected, dict) and isinstance(found, dict):
        out = []
        for key in sorted(set(expected) | set(found), key=str):
            out += field_differences(expected.get(key), found.get(key),
                                f"{where}.{key}" if where else str(key))
        return out
    if isinstance(expected, list | tuple) and isinstance(found, list | tuple) \
            and len(expected) == len(found):
        if all(_same(a, b) if not isinstance(a, dict | list) else not field_differences(a, b)
               for a, b in zip(expected, found, strict=True)):
            return []
        return [(where, expected, found)]
    return [] if _same(expected, found) else [(where, expected, found)]


def _shown(value) -> str:
    """A value of a parameter as the message shows it (JSON; numbers to 12 digits)."""
    if value is None:
        return "(not set)"
    if isinstance(value, float):
        return f"{value:.12g}"
    text = json.dumps(value) if isinstance(value, str | list | dict) else str(value)
    return text if len(text) <= 160 else text[:150] + " ..."


def parameters_error(path, differences: list[tuple[str, object, object]]) -> StoredFileError:
    """The refusal of a file made for other parameters than its name and the config say."""
    shown = [f"{field} = {_shown(found)} in the file, {_shown(expected)} expected"
             for field, expected, found in differences[:4]]
    more = f" (and {len(differences) - 4} more)" if len(differences) > 4 else ""
    return StoredFileError(
        f"{path}: made for other parameters than its name and the configuration say: "
        + "; ".join(shown) + more + ". A file copied or renamed from another one, or made by "
        f"another configuration, is never used; {rebuild(path)}", path)


def _expected(cell=None, geometry=None, job=None, study_seed=None) -> dict:
    """Root attribute -> the value a reader expects of it (see :func:`check_parameters`)."""
    expected = {}
    if cell is not None:
        expected["params"] = cell
    if geometry is not None:
        expected["params"] = geometry
    if job is not None:
        expected["job"] = {k: job.get(k) for k in CONTACT_DEFINING}
    if study_seed is not None:
        expected["study_seed"] = int(study_seed)
    return expected


def check_attributes(path, attrs: dict, expected: dict) -> None:
    """Raise :func:`parameters_error` unless a file's root attributes ``attrs`` hold the
    ``expected`` values (attribute -> value; a dict is compared with the attribute's JSON
    field by field)."""
    differences = []
    for name, want in expected.items():
        found = attrs.get(name)
        if name == "job":
            found = json_attr(found)
            found = None if found is None else {k: found.get(k) for k in CONTACT_DEFINING}
        elif isinstance(want, dict):
            found = json_attr(found)
        elif isinstance(found, np.generic):
            found = found.item()
        if isinstance(want, dict) and isinstance(found, dict):
            differences += field_differences(want, found)
        elif not _same(want, found):
            differences.append((name, want, found))
    if differences:
        raise parameters_error(path, differences)


def _check_shape(path, name: str, shape: tuple, expected: tuple, what: str) -> None:
    """Raise :func:`parameters_error` unless a dataset's ``shape`` is the ``expected`` one."""
    if tuple(shape) != tuple(expected):
        raise parameters_error(path, [(f"shape of {name} ({what})", list(expected),
                                       list(shape))])


def check_parameters(path: str | os.PathLike, *, cell: dict | None = None,
                     geometry: dict | None = None, job: dict | None = None,
                     study_seed: int | None = None) -> dict:
    """Check the parameters a stored file was made for against what its reader expects.

    ``cell``: a surface cell's :meth:`~roughcontact.study.records.GeneratedCell.params`
    (the ``params`` attribute of a surface file, with ``study_seed``);
    ``geometry``: a geometry's :meth:`~roughcontact.study.records.Geometry.params`
    (of an influence file); ``job``: a contact job's
    :meth:`~roughcontact.study.contact_records.ContactJob.params` (the fields of
    :data:`CONTACT_DEFINING` of a contact file's ``job``). Numbers agree to a
    relative 1e-9. Only the attributes are read (no dataset, no hash: the
    readers check those). Raises :class:`StoredFileError` naming the file,
    each field that differs with the value expected and found, and the
    command that rebuilds it. Returns the attributes.
    """
    with open_h5(path) as f:
        attrs = decoded(f.attrs)
    check_attributes(path, attrs, _expected(cell, geometry, job, study_seed))
    return attrs


def write_h5(path: str | os.PathLike, datasets: dict, attrs: dict) -> None:
    """Write datasets and root attributes to ``path`` atomically.

    ``datasets`` maps a name (``"stats/skew"`` makes a group) to an array or to
    ``(array, {attribute: value})``; nested dicts and lists in attributes are
    stored as JSON text. Without a ``content_sha256`` in ``attrs``, the hash of
    every dataset (:func:`datasets_sha256`) is added; ``format_version`` is always
    :data:`FORMAT_VERSION` (the layout written here).
    """
    if "content_sha256" not in attrs:
        attrs = {**attrs, "content_sha256": datasets_sha256(datasets)}
    attrs = {**attrs, "format_version": FORMAT_VERSION}
    with atomic_path(path) as tmp:
        with h5py.File(tmp, "w") as f:
            for name, item in datasets.items():
                data, dattrs = item if isinstance(item, tuple) else (item, {})
                dset = f.create_dataset(name, data=np.asarray(data))
                for key, value in dattrs.items():
                    dset.attrs[key] = _attr_value(value)
            for key, value in attrs.items():
                f.attrs[key] = _attr_value(value)


# ---------------------------------------------------------------------------
# Surface files


def write_surfaces(path: str | os.PathLike, datasets: dict, attrs: dict) -> None:
    """Write a surface cell (``heights``, ``seeds``, ``stats/*``; layout above)."""
    write_h5(path, datasets, attrs)


def read_surfaces(path: str | os.PathLike, count: int | None = None, *,
                  cell: dict | None = None, study_seed: int | None = None) -> dict:
    """Read a surface file written by the ``surfaces`` rule.

    Returns a dict with ``heights`` (m, ny, nx, in units of sigma), ``seeds``,
    ``stats`` (dict of per-surface arrays), ``spec`` (dict), ``attrs`` and
    ``dataset_attrs`` (dataset name -> its attributes: units, layout).
    ``count`` limits how many surfaces are read (the first ``count``). With
    the ``cell`` (its ``params()``) and ``study_seed`` the job expects, the
    file must have been made for them (:func:`check_parameters`), its
    heights of shape (count, ny, nx) of the cell.
    """
    sl = slice(None) if count is None else slice(0, count)
    with open_h5(path) as f:
        attrs = upgraded(path, decoded(f.attrs), "surfaces")
        check_attributes(path, attrs, _expected(cell=cell, study_seed=study_seed))
        arrays = all_datasets(f)
        dataset_attrs = {name: decoded(f[name].attrs) for name in arrays}
    verify(path, attrs, arrays_sha256(arrays))
    if cell is not None and "heights" in arrays:
        nx, ny = cell["grid"]
        _check_shape(path, "heights", arrays["heights"].shape, (cell["count"], ny, nx),
                     "surfaces, ny, nx")
    stats = {name.split("/", 1)[1]: value for name, value in arrays.items()
             if name.startswith("stats/")}
    return {
        "heights": arrays["heights"][sl],
        "seeds": arrays["seeds"][sl],
        "stats": {k: (v if k.startswith("psd_") else v[sl]) for k, v in stats.items()},
        "attrs": attrs,
        "dataset_attrs": dataset_attrs,
        "content_sha256": attrs["content_sha256"],
        "spec": json.loads(attrs["spec"]),
    }


# ---------------------------------------------------------------------------
# Influence files: a dense matrix or a matrix-free operator


def _is_operator(unit) -> bool:
    """Whether ``unit`` is a matrix-free
    :class:`~roughcontact.elasticity.operators.BlockOperator` (imported here: a job that
    reads only surfaces or contact files, or a figure, does not load the operators and
    the solvers behind them)."""
    from roughcontact.elasticity.operators import BlockOperator

    return isinstance(unit, BlockOperator)


def influence_sha256(unit) -> str:
    """Content hash of a stored influence model (matrix, or the operator's correction)."""
    if _is_operator(unit):
        return array_sha256(unit.correction) if unit.correction is not None else \
            array_sha256(np.asarray(unit.grid + unit.size + (unit.nu,), dtype=float))
    return array_sha256(unit)


def influence_datasets(unit) -> tuple[dict, dict]:
    """Datasets and attributes that store ``unit`` (a matrix or a :class:`BlockOperator`)."""
    if not _is_operator(unit):
        return {"unit_influence": (unit, {
            "units": "m (E * C: displacement per unit pressure times Young's modulus)",
            "layout": "C[i, j]: displacement at the centre of element i per unit "
                      "pressure on element j; elements row-major over y then x",
        })}, {"operator": "dense"}
    attrs = {"operator": unit.kind, "operator_grid": list(unit.grid),
             "operator_size_m": list(unit.size), "operator_nu": unit.nu}
    datasets = {}
    if unit.correction is not None:
        attrs["coarse_grid"] = list(unit.coarse_grid)
        datasets["correction"] = (unit.correction, {
            "units": "1/m (E * C of the coarse finite-element model minus Love's half-space, "
                     "per unit coarse element area)",
            "layout": "coarse elements row-major over y then x",
        })
    return datasets, attrs


def write_influence(path: str | os.PathLike, unit, attrs: dict) -> dict:
    """Write an influence model with ``attrs`` and its ``content_sha256``; returns the attrs."""
    datasets, model_attrs = influence_datasets(unit)
    attrs = {**attrs, **model_attrs, "content_sha256": influence_sha256(unit)}
    write_h5(path, datasets, attrs)
    return attrs


def _influence_shape(path, unit, geometry: dict) -> None:
    """The stored model's grid against the ``grid`` of the geometry a reader expects."""
    nx, ny = geometry["grid"]
    if _is_operator(unit):
        _check_shape(path, "the operator's grid", unit.grid, (nx, ny), "nx, ny")
    else:
        _check_shape(path, "unit_influence", unit.shape, (nx * ny, nx * ny),
                     f"n x n for the {nx} x {ny} grid")


def read_influence(path: str | os.PathLike, *, geometry: dict | None = None):
    """``(E C, attributes)`` of an influence file: a dense ndarray [m] or a :class:`BlockOperator`.

    Divide by Young's modulus for C [m/Pa]. With the ``geometry`` (its
    ``params()``) the job expects, the file must have been made for it
    (:func:`check_parameters`, before any dataset is read), its model on the
    geometry's grid.
    """
    with open_h5(path) as f:
        attrs = upgraded(path, decoded(f.attrs), "influence")
        check_attributes(path, attrs, _expected(geometry=geometry))
        if "unit_influence" in f:
            unit = f["unit_influence"][...]
            verify(path, attrs, influence_sha256(unit))
            if geometry is not None:
                _influence_shape(path, unit, geometry)
            return unit, attrs
        correction = f["correction"][...] if "correction" in f else None

    def pair(value):
        return tuple(json.loads(value)) if isinstance(value, str) else tuple(value)

    kind = attrs.get("operator")  # None: not an influence file
    if kind not in ("hybrid", "halfspace"):
        raise StoredFileError(f"{path}: not an influence file (no unit_influence dataset, and "
                              f"no matrix-free operator: operator attribute {kind!r}); "
                              f"{rebuild(path)}", path)
    from roughcontact.elasticity.operators import BlockOperator

    try:
        coarse = pair(attrs["coarse_grid"]) if correction is not None else None
        op = BlockOperator(grid=pair(attrs["operator_grid"]),
                           size=pair(attrs["operator_size_m"]),
                           nu=float(attrs["operator_nu"]), correction=correction,
                           coarse_grid=coarse)
    except (KeyError, TypeError, ValueError) as err:
        raise StoredFileError(f"{path}: its {kind} operator cannot be made from the stored "
                              f"attributes and correction ({err}); {rebuild(path)}",
                              path) from None
    verify(path, attrs, influence_sha256(op))
    if geometry is not None:
        _influence_shape(path, op, geometry)
    return op, attrs


# ---------------------------------------------------------------------------
# Choices of operator: auto (JSON)


# ---------------------------------------------------------------------------
# Pair files: two bodies' dense influence models summed once (Eq 17-18)


def write_pair(path: str | os.PathLike, matrix, weights, attrs: dict) -> dict:
    """Write a pair of bodies' equivalent influence model (``results/influence/pairs/
    <pair>.h5``): ``/unit_influence`` (n, n) ``E1 C1 + (E1 / E2) E2 C2`` [m] and
    ``/counter_weights`` (n,) the counter body's deflection weights [m], both absent
    when the counter body is treated as rigid, with ``attrs`` (the pair's ``params``,
    the compliance share and the choice) and the content hash; returns the attrs."""
    datasets = {} if matrix is None else {
        "unit_influence": (np.asarray(matrix), {
            "units": "m (E1 C1 + (E1 / E2) E2 C2: the pair in the first body's modulus)"}),
        "counter_weights": (np.asarray(weights), {
            "units": "m (w: the counter body's mean deflection is w . p E1)"})}
    attrs = {**attrs, "content_sha256": datasets_sha256(datasets)}
    write_h5(path, datasets, attrs)
    return attrs


def read_pair(path: str | os.PathLike, *, pair: dict | None = None) -> tuple:
    """``(matrix or None, weights or None, attributes)`` of a pair file
    (:func:`write_pair`). With the ``pair`` (its ``params()``) the reader expects, the
    file must have been made for it (:func:`check_parameters`); its datasets are
    checked against their hash."""
    with open_h5(path) as f:
        attrs = upgraded(path, decoded(f.attrs), "pair")
        check_attributes(path, attrs, _expected(geometry=pair))
        arrays = all_datasets(f)
    verify(path, attrs, arrays_sha256(arrays))
    return arrays.get("unit_influence"), arrays.get("counter_weights"), attrs


def write_choice(path: str | os.PathLike, choice: dict) -> None:
    """Write the choice of an ``operator: auto`` geometry (JSON, atomically)."""
    with atomic_path(path) as tmp:
        with open(tmp, "w") as f:
            json.dump(choice, f, indent=1, sort_keys=True)


def read_choice(path: str | os.PathLike, *, geometry: dict | None = None) -> dict:
    """The choice of an ``operator: auto`` geometry (:func:`write_choice`); with the
    ``geometry`` (its ``params()``) a reader expects, it must have been made for it
    (:func:`check_attributes`)."""
    try:
        with open(path) as f:
            choice = json.load(f)
    except ValueError as err:
        raise StoredFileError(f"{path}: not a choice of operator: auto (not JSON: {err}); "
                              f"{rebuild(path)}", path) from None
    if geometry is not None:
        check_attributes(path, choice, {"geometry": geometry})
    return choice


# ---------------------------------------------------------------------------
# Contact files


def contact_datasets(sweep: NondimSweep) -> dict:
    """The arrays a contact file stores for ``sweep`` (profiles in single precision)."""
    datasets = {name: np.asarray(getattr(sweep, CONTACT_FIELDS.get(name, name)))
                for name in CONTACT_ARRAYS}
    if sweep.pressure_profile is not None:
        datasets["profile_ranks"] = np.asarray(sweep.profile_ranks, dtype=np.int64)
        for name in PROFILE_ARRAYS[1:]:
            datasets[name] = np.asarray(getattr(sweep, name), dtype=np.float32)
    if sweep.mean_gap is not None:
        for name in INTERFACE_ARRAYS:
            single = name.endswith("_quantiles")
            datasets[name] = np.asarray(getattr(sweep, name),
                                        dtype=np.float32 if single else None)
    for name in COUNTER_ARRAYS:
        if getattr(sweep, name) is not None:
            datasets[name] = np.asarray(getattr(sweep, name))
    if (sweep.solved_by != sweep.method).any():
        datasets["solved_by"] = np.char.encode(sweep.solved_by, "ascii")
    datasets.update({name: np.asarray(values) for name, values in sweep.probe_columns.items()})
    return datasets


def contact_sha256(sweep: NondimSweep) -> str:
    """Content hash of a contact sweep's stored arrays (:func:`contact_datasets`)."""
    return arrays_sha256(contact_datasets(sweep))


def write_contact(path: str | os.PathLike, sweep: NondimSweep, attrs: dict) -> dict:
    """Write a contact job's sweep with ``attrs`` and its hash; returns the attributes written.

    The attributes gain ``content_sha256`` (:func:`contact_sha256`), the settings of
    each of the sweep's probes (JSON) under its ``kind`` and the sweep's settings as
    ``sweep_<name>``.
    """
    datasets = contact_datasets(sweep)
    attrs = {
        "content_sha256": arrays_sha256(datasets),
        **attrs,
        **{probe.kind: canonical_json(probe.params()) for probe in sweep.probe_columns.probes},
        **{f"sweep_{k}": getattr(sweep, k) for k in SWEEP_SETTINGS},
        "sweep_max_iter": -1 if sweep.max_iter is None else sweep.max_iter,
        "sweep_hardness": -1.0 if sweep.nondim_hardness is None else float(sweep.nondim_hardness),
    }
    write_h5(path, datasets, attrs)
    return attrs


def read_contact(path: str | os.PathLike, *,
                 job: dict | None = None) -> tuple[NondimSweep, dict]:
    """The :class:`~roughcontact.contact.curves.NondimSweep` and attributes of a contact file.

    With the ``job`` (its ``params()``) the reader expects, the file must have
    been solved for it (:func:`check_parameters`: surfaces, geometry, sweep
    end and cap), one row per surface of the job's cell. The probes it was solved
    with are made again from their stored settings
    (:func:`roughcontact.study.probes.probes_from_attrs`), their columns read under
    their names.
    """
    with open_h5(path) as f:
        attrs = upgraded(path, decoded(f.attrs), "contact")
        check_attributes(path, attrs, _expected(job=job))
        missing = [name for name in CONTACT_ARRAYS if name not in f]
        if missing:
            raise StoredFileError(f"{path}: no {', '.join(missing)} (written by an older "
                                  f"version of roughcontact); {rebuild(path)}", path)
        arrays = all_datasets(f)
    verify(path, attrs, arrays_sha256(arrays))
    probed = probe_columns(path, attrs, arrays)
    if job is not None:
        count = job["surface"]["count"]
        _check_shape(path, "approach", arrays["approach"].shape[:1], (count,), "surfaces")
    settings = {k: attrs[f"sweep_{k}"] for k in SWEEP_SETTINGS}
    settings["n_elements"] = int(settings["n_elements"])
    for key in ("method", "precision"):
        settings[key] = str(settings[key])
    if isinstance(attrs.get("seeds"), str):  # stored as JSON text
        attrs["seeds"] = json.loads(attrs["seeds"])
    max_iter = int(attrs["sweep_max_iter"])
    hardness = float(attrs["sweep_hardness"])
    fields = {CONTACT_FIELDS.get(name, name): values for name, values in arrays.items()}
    if "solved_by" in fields:
        fields["solved_by"] = np.char.decode(fields["solved_by"], "ascii")
    from roughcontact.contact.curves import NondimSweep

    return NondimSweep(**fields, **settings, max_iter=None if max_iter < 0 else max_iter,
                       nondim_hardness=None if hardness < 0 else hardness,
                       probe_columns=probed), attrs


def probe_columns(path, attrs: dict, arrays: dict, known=None):
    """The :class:`~roughcontact.contact.probes.ProbeColumns` of a contact file (or of a
    file whose own datasets are ``known``, e.g. a cycle file): its probes made again
    from their stored settings (:func:`roughcontact.study.probes.probes_from_attrs`),
    their columns taken out of ``arrays`` (every dataset of the file); a column
    missing, or a dataset that is neither the file's own nor a probe's column, raises
    :class:`StoredFileError`."""
    from roughcontact.contact.probes import ProbeColumns
    from roughcontact.study.probes import probes_from_attrs

    probes = probes_from_attrs(attrs)
    names = [column.name for probe in probes for column in probe.columns]
    absent = [name for name in names if name not in arrays]
    if known is None:
        known = (CONTACT_ARRAYS + PROFILE_ARRAYS + INTERFACE_ARRAYS + COUNTER_ARRAYS
                 + METHOD_ARRAYS)
    unknown = sorted(set(arrays) - set(known) - set(names))
    if absent or unknown:
        raise StoredFileError(
            f"{path}: " + (f"no {', '.join(absent)} of the probes it names; " if absent
                           else "")
            + (f"datasets {', '.join(unknown)} of no probe it names (a probe this "
               f"roughcontact does not know?); " if unknown else "") + rebuild(path), path)
    return ProbeColumns(probes, {name: arrays.pop(name) for name in names})
