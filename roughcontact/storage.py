"""HDF5 files of the pipeline: written atomically, with units and provenance.

Layout of a surface file (``results/surfaces/<cell>.h5``)::

    /heights        (m, ny, nx) float64  heights / sigma, zero mean per surface
    /seeds          (m,)        int64    white-noise seed of each surface
    /stats/mean, sigma, skew, kurt   (m,)  realised moments (Eq 2-5), heights / sigma
    /stats/corr_length_x, corr_length_y (m,) [m] lag of 10 % ACF decay
    attributes: cell, study_seed, spec (JSON), every spec field, the filter's
                S3 and S4, the input moments and Johnson curve, provenance

Arrays are row-major over y then x (axis 0 is y), the element ordering of the
influence matrices.
"""

from __future__ import annotations

import hashlib
import json
import os

import h5py
import numpy as np

from .provenance import atomic_path


def _attr_value(value):
    if isinstance(value, dict | list | tuple):
        return json.dumps(value)
    if value is None:
        return ""
    if isinstance(value, bool | np.bool_):
        return bool(value)
    return value


def write_h5(path: str | os.PathLike, datasets: dict, attrs: dict) -> None:
    """Write datasets and root attributes to ``path`` atomically.

    ``datasets`` maps a name (``"stats/skew"`` makes a group) to an array or to
    ``(array, {attribute: value})``; nested dicts and lists in attributes are
    stored as JSON text.
    """
    with atomic_path(path) as tmp:
        with h5py.File(tmp, "w") as f:
            for name, item in datasets.items():
                data, dattrs = item if isinstance(item, tuple) else (item, {})
                dset = f.create_dataset(name, data=np.asarray(data))
                for key, value in dattrs.items():
                    dset.attrs[key] = _attr_value(value)
            for key, value in attrs.items():
                f.attrs[key] = _attr_value(value)


def read_attrs(path: str | os.PathLike) -> dict:
    """Root attributes of an HDF5 file (JSON text left as text)."""
    with h5py.File(path, "r") as f:
        return {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}


def read_surfaces(path: str | os.PathLike, count: int | None = None) -> dict:
    """Read a surface file written by the ``surfaces`` rule.

    Returns a dict with ``heights`` (m, ny, nx, in units of sigma), ``seeds``,
    ``stats`` (dict of per-surface arrays), ``spec`` (dict) and ``attrs``.
    ``count`` limits how many surfaces are read (the first ``count``).
    """
    sl = slice(None) if count is None else slice(0, count)
    with h5py.File(path, "r") as f:
        out = {
            "heights": f["heights"][sl],
            "seeds": f["seeds"][sl],
            "stats": {k: f["stats"][k][sl] for k in f["stats"]},
            "attrs": {
                k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()
            },
        }
    out["spec"] = json.loads(out["attrs"]["spec"])
    return out


def array_sha256(array: np.ndarray) -> str:
    """SHA-256 of an array's bytes (C order): the content hash of an influence matrix."""
    return hashlib.sha256(np.ascontiguousarray(array).tobytes()).hexdigest()


def file_sha256(path: str | os.PathLike) -> str:
    """SHA-256 (hex) of a file's bytes, read in 1 MiB blocks: the identity of an input file."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def read_influence(path: str | os.PathLike) -> tuple[np.ndarray, dict]:
    """Read an influence file written by the ``influence`` rule.

    Returns ``(E * C [m], attributes)``; divide by Young's modulus for C [m/Pa].
    """
    with h5py.File(path, "r") as f:
        unit = f["unit_influence"][...]
        attrs = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}
    return unit, attrs
