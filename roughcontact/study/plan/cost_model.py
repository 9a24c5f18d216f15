"""The cost model's file: the measured numbers the job resources are scaled from.

``config/cost_model.yaml`` holds every measured number of
:mod:`roughcontact.study.plan.resources` with what was measured; :func:`load_cost_model`
reads it and refuses one that lacks a key the formulas read.
"""

from __future__ import annotations

import os
from pathlib import Path
from types import MappingProxyType

import yaml

from roughcontact.study.config import SCHEMA

__all__ = ["COST_MODEL_FILE", "DOUBLE_BYTES", "MB", "SCHEMA_FILE", "load_cost_model"]

#: The stored cost model of the source tree.
COST_MODEL_FILE = SCHEMA.parent / "cost_model.yaml"
#: The configuration schema (its ``default:`` entries complete a config).
SCHEMA_FILE = SCHEMA
#: Bytes of one double-precision value.
DOUBLE_BYTES = 8
#: One megabyte [bytes] (decimal, as schedulers count memory).
MB = 1e6

_REQUIRED = {
    "runtime": ("margin", "start_min"),
    "contact": ("reference_elements", "dense_solve_seconds", "dense_exponent",
                "reference_tol_digits", "method_cost", "reference_reach",
                "matrix_free_solve_seconds", "matrix_free_reference_elements",
                "matrix_free_floor_seconds", "memory_base_mb", "dense_matrices",
                "dense_batch_arrays", "matrix_free_batch_arrays", "flow_solve_seconds",
                "flow_exponent", "flow_memory_mb", "flow_memory_reference_elements",
                "flow_memory_exponent", "flow_memory_floor_elements", "flow_field_arrays",
                "pivot_batch_surfaces", "pivot_transient_factors", "contact_fraction_slope"),
    "influence": ("anchor_seconds", "anchor_peak_gb", "exponent", "memory_margin_mb"),
    "conductance": ("solve_share", "build_share", "dense_arrays", "build_memory_share",
                    "fft_batch_arrays"),
    "cycles": ("step_share",),
    "surfaces": ("reference_elements", "exact_seconds", "filter_seconds", "exponent",
                 "calibration_seconds",
                 "memory_base_mb", "work_arrays"),
    "summaries": ("seconds",),
    "audit": ("base_seconds", "seconds_per_file", "memory_base_mb", "model_copies"),
    "convergence": ("base_seconds", "solve_seconds", "memory_base_mb", "memory_floor_mb"),
    "speed_vs_error": ("solver_seconds", "reference_surfaces", "grid_seconds",
                       "grid_reference_seconds", "grid_reference_side", "count_seconds",
                       "count_surfaces", "reference_elements", "memory_base_mb",
                       "dense_matrices"),
}


def _frozen(value):
    if isinstance(value, dict):
        return MappingProxyType({k: _frozen(v) for k, v in value.items()})
    return value


def load_cost_model(path: str | os.PathLike = COST_MODEL_FILE) -> MappingProxyType:
    """The cost-model file as read-only mappings, one per section of ``_REQUIRED``.

    Raises ``FileNotFoundError`` or ``ValueError`` naming the file (and the
    missing ``section.key``).
    """
    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text()) or {}
    except FileNotFoundError:
        raise FileNotFoundError(f"{path}: the cost model of the job resources is missing; "
                                f"restore it (git checkout -- config/cost_model.yaml)") from None
    missing = [f"{section}.{key}" for section, keys in _REQUIRED.items() for key in keys
               if key not in (data.get(section) or {})]
    if missing:
        raise ValueError(f"{path}: the cost model lacks {', '.join(missing)}")
    return _frozen(data)
