"""Accuracy presets and fallback mesh errors: measured data, read from ``config/``.

The numbers are measured by the speed-against-error report
(:mod:`roughcontact.reports.speed`) and stored in
``config/accuracy_presets.yaml``; nothing in code repeats them.
"""

from __future__ import annotations

import os
from pathlib import Path
from types import MappingProxyType

import yaml

#: The stored presets file of the source tree.
PRESETS_FILE = Path(__file__).resolve().parents[2] / "config" / "accuracy_presets.yaml"


def _frozen(value):
    if isinstance(value, dict):
        return MappingProxyType({k: _frozen(v) for k, v in value.items()})
    return value


def load_presets(path: str | os.PathLike = PRESETS_FILE) -> MappingProxyType:
    """The presets file as read-only mappings: ``accuracy_presets`` and ``fallback_mesh_errors``."""
    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text())
    except FileNotFoundError:
        raise FileNotFoundError(
            f"{path}: the accuracy presets file is missing; restore it from the repository "
            f"(git checkout -- config/accuracy_presets.yaml) or regenerate it with "
            f"`snakemake --cores 2 results/reports/speed_vs_error.md`") from None
    missing = {"accuracy_presets", "fallback_mesh_errors"} - set(data or {})
    if missing:
        raise ValueError(f"{path}: expected the sections accuracy_presets and "
                         f"fallback_mesh_errors; missing {sorted(missing)}")
    return _frozen(data)


_STORED = load_presets()
#: Accuracy presets (``accuracy: paper|fast|converged`` in a config).
ACCURACY_PRESETS = _STORED["accuracy_presets"]
#: Mesh errors used when no influence-convergence table is given.
FALLBACK_MESH_ERRORS = _STORED["fallback_mesh_errors"]
