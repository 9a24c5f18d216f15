"""Accuracy presets and fallback mesh errors: measured data, read from ``config/``.

The numbers are measured by the speed-against-error report
(:mod:`roughcontact.reports.speed`) and stored in
``config/accuracy_presets.yaml``; nothing in code repeats them. Each run of
the report writes its own measurements in the same structure
(``results/reports/accuracy_presets.yaml``); the drift between the two::

    python -m roughcontact.study.presets --compare results/reports/accuracy_presets.yaml

prints, per preset and key, the stored value, the fresh one and the relative
drift ``|fresh / stored - 1|``, flags drifts above ``--rtol`` (default 0.25)
and exits 0, or 1 when the two files differ in structure (sections, preset
names or keys).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from types import MappingProxyType

import yaml

from roughcontact.study import layout

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
            f"`snakemake --cores 2 {layout.report('speed_vs_error.md')}`") from None
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

#: Relative drift above which ``--compare`` flags a value.
DRIFT_RTOL = 0.25


def _is_number(value) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def relative_drift(stored: float, fresh: float) -> float:
    """``|fresh / stored - 1|`` [-]; 0 when both are 0, inf when only ``stored`` is."""
    if stored == fresh:
        return 0.0
    if stored == 0:
        return math.inf
    return abs(fresh / stored - 1.0)


def structure_differences(stored: Mapping, fresh: Mapping) -> list[str]:
    """Sections, entries (presets or meshes) and keys present in only one of two presets
    files (as read by :func:`load_presets`); empty when the structures are equal."""
    differences = []

    def compare(names_a, names_b, where):
        differences.extend(f"{where}{name}: only in the stored file"
                           for name in names_a if name not in names_b)
        differences.extend(f"{where}{name}: only in the fresh file"
                           for name in names_b if name not in names_a)

    compare(list(stored), list(fresh), "section ")
    for section in (name for name in stored if name in fresh):
        compare(list(stored[section]), list(fresh[section]), f"{section}/")
        for entry in (name for name in stored[section] if name in fresh[section]):
            compare(list(stored[section][entry]), list(fresh[section][entry]),
                    f"{section}/{entry}: key ")
    return differences


def drift_table(stored: Mapping, fresh: Mapping, rtol: float = DRIFT_RTOL) -> list[dict]:
    """Per (section, entry, key) present in both files: stored value, fresh value,
    relative drift (:func:`relative_drift`; NaN for text) and ``flagged`` (drift above
    ``rtol``, or a text that changed)."""
    rows = []
    for section in (name for name in stored if name in fresh):
        for entry in (name for name in stored[section] if name in fresh[section]):
            old_values, new_values = stored[section][entry], fresh[section][entry]
            for key in (name for name in old_values if name in new_values):
                old, new = old_values[key], new_values[key]
                if _is_number(old) and _is_number(new):
                    drift = relative_drift(float(old), float(new))
                    flagged = drift > rtol
                else:
                    drift, flagged = math.nan, old != new
                rows.append({"section": section, "entry": entry, "key": key, "stored": old,
                             "fresh": new, "drift": drift, "flagged": flagged})
    return rows


def _format_value(value) -> str:
    return f"{value:.4g}" if _is_number(value) else str(value)


def _format_row(row: Mapping) -> str:
    drift = "" if math.isnan(row["drift"]) else f"{row['drift']:.1%}"
    mark = "  <-- DRIFT" if row["flagged"] else ""
    return (f"{row['section']:<21} {row['entry']:<10} {row['key']:<23} "
            f"{_format_value(row['stored']):>12} {_format_value(row['fresh']):>12} "
            f"{drift:>9}{mark}")


def compare_presets(stored_path: str | os.PathLike, fresh_path: str | os.PathLike,
                    rtol: float = DRIFT_RTOL, out=None) -> int:
    """Print the drift of ``fresh_path`` against ``stored_path`` (both presets files).

    Numbers are compared only (text values are printed when they differ);
    returns the exit status: 0, or 1 when the structures differ.
    """
    out = out or sys.stdout
    stored, fresh = load_presets(stored_path), load_presets(fresh_path)
    rows = drift_table(stored, fresh, rtol)
    print(f"stored: {stored_path}\nfresh:  {fresh_path}\n"
          f"relative drift |fresh / stored - 1|, flagged above {rtol:g}", file=out)
    print(f"{'section':<21} {'entry':<10} {'key':<23} {'stored':>12} {'fresh':>12} "
          f"{'drift':>9}", file=out)
    for row in rows:
        if _is_number(row["stored"]) or row["flagged"]:
            print(_format_row(row), file=out)
    flagged = sum(row["flagged"] for row in rows)
    print(f"{flagged} of {len(rows)} values drift above {rtol:g}", file=out)
    differences = structure_differences(stored, fresh)
    for line in differences:
        print(f"structure differs: {line}", file=out)
    return 1 if differences else 0


def main(argv: Sequence[str] | None = None) -> int:
    """Command line: ``--compare FRESH [--stored STORED] [--rtol RTOL]``."""
    parser = argparse.ArgumentParser(
        prog="python -m roughcontact.study.presets",
        description="Drift of freshly measured accuracy presets against the stored ones.")
    parser.add_argument("--compare", required=True, metavar="FRESH",
                        help="presets file written by the speed-against-error report")
    parser.add_argument("--stored", default=str(PRESETS_FILE),
                        help="stored presets file (default: %(default)s)")
    parser.add_argument("--rtol", type=float, default=DRIFT_RTOL,
                        help="relative drift flagged (default: %(default)s)")
    args = parser.parse_args(argv)
    return compare_presets(args.stored, args.compare, args.rtol)


if __name__ == "__main__":
    sys.exit(main())
