"""A cycle job's file: its dimensionless loading path, written once and checked on every read.

``results/cycles/<key>.h5`` (:data:`roughcontact.study.layout.cycle`) holds the
:class:`~roughcontact.contact.cycles.CycleResult` of a cycle job
(:mod:`roughcontact.study.cycle_records`) in the variables of
:mod:`roughcontact.contact.nondim` (lengths in sigma, pressures in ``E sigma / L``, the
nominal area 1): per surface and step the approach, load, areas, plastic volume,
permanent set, stiffness, residual and the probes' columns, the final plastic
displacement, the path; its attributes the job's params, the probes' settings, the
content hash of its datasets and those of the files it read, and the provenance. A
reader names the cycle job it expects: a file made for another one (another path,
surfaces, geometry, cap) or changed since it was written is refused with the command
that rebuilds it.
"""

from __future__ import annotations

import json
import os

import numpy as np

from roughcontact.contact.cycles import CycleResult, LoadingPath
from roughcontact.errors import StoredFileError
from roughcontact.hashes import arrays_sha256
from roughcontact.study.jobs.storage import (
    CONTACT_DEFINING,
    all_datasets,
    decoded,
    field_differences,
    json_attr,
    open_h5,
    parameters_error,
    probe_columns,
    rebuild,
    verify,
    write_h5,
)
from roughcontact.study.provenance import canonical_json

__all__ = ["CYCLE_ARRAYS", "read_cycle", "write_cycle"]

#: The ``(m, k)`` arrays of a cycle file (and ``plastic``, ``(m, n)``; ``path``, ``(k,)``).
CYCLE_ARRAYS = ("approach", "load", "nominal_pressure", "real_area_fraction",
                "plastic_area_fraction", "plastic_volume", "permanent_set",
                "contact_stiffness", "converged", "stiffness_converged", "residual")

#: The fields of a cycle job's params that define its file (its contact job's defining
#: fields, and the path).
CYCLE_DEFINING = ("peak", "cycles", "steps", "unload_to")


def _datasets(result: CycleResult) -> dict:
    return {**{name: getattr(result, name) for name in CYCLE_ARRAYS},
            "plastic": result.plastic, "path": np.asarray(result.path.values),
            **{name: result.probe_columns[name] for name in result.probe_columns}}


def write_cycle(path: str | os.PathLike, result: CycleResult, attrs: dict) -> dict:
    """Write a cycle job's dimensionless ``result`` with ``attrs`` (its ``job``'s params
    among them) and its hash; returns the attributes written."""
    datasets = _datasets(result)
    attrs = {"content_sha256": arrays_sha256(datasets), **attrs,
             **{probe.kind: canonical_json(probe.params())
                for probe in result.probe_columns.probes},
             "control": result.path.control, "hardness": float(result.hardness),
             "element_area": float(result.element_area)}
    write_h5(path, datasets, attrs)
    return attrs


def _check_job(path, attrs: dict, job: dict) -> None:
    """The file must have been made for the cycle job ``job`` (its params)."""
    found = json_attr(attrs.get("job")) or {}
    want = {**{k: job[k] for k in CYCLE_DEFINING},
            "contact": {k: job["contact"].get(k) for k in CONTACT_DEFINING}}
    got = {**{k: found.get(k) for k in CYCLE_DEFINING},
           "contact": {k: (found.get("contact") or {}).get(k) for k in CONTACT_DEFINING}}
    differences = field_differences(want, got, "job")
    if differences:
        raise parameters_error(path, differences)


def read_cycle(path: str | os.PathLike, *, job: dict | None = None
               ) -> tuple[CycleResult, dict]:
    """The dimensionless :class:`~roughcontact.contact.cycles.CycleResult` and attributes of
    a cycle file; with the cycle ``job`` (its ``params()``) the reader expects, the file
    must have been solved for it, one row per surface of its cell."""
    with open_h5(path) as f:
        attrs = decoded(f.attrs)
        if job is not None:
            _check_job(path, attrs, job)
        arrays = all_datasets(f)
    missing = [name for name in (*CYCLE_ARRAYS, "plastic", "path") if name not in arrays]
    if missing:
        raise StoredFileError(f"{path}: no {', '.join(missing)}; {rebuild(path)}", path)
    verify(path, attrs, arrays_sha256(arrays))
    count = None if job is None else job["contact"]["surface"]["count"]
    if count is not None and arrays["approach"].shape[0] != count:
        raise parameters_error(path, [("surfaces (rows of approach)", count,
                                       arrays["approach"].shape[0])])
    probed = probe_columns(path, attrs, arrays, known=(*CYCLE_ARRAYS, "plastic", "path"))
    if isinstance(attrs.get("seeds"), str):
        attrs["seeds"] = json.loads(attrs["seeds"])
    result = CycleResult(
        path=LoadingPath(tuple(arrays.pop("path")), str(attrs["control"])),
        **{name: arrays.pop(name) for name in CYCLE_ARRAYS}, plastic=arrays.pop("plastic"),
        pressure=None, hardness=float(attrs["hardness"]),
        element_area=float(attrs["element_area"]),
        probe_columns=probed)
    return result, attrs
