"""Audit of a contact study: every cell traceable, checkable and re-checkable.

:func:`audit_table` collects, for each study cell, what produced it (its
parameters, seeds, surfaces, influence matrix, solver settings, versions)
and whether it can be trusted (each file made for the cell's parameters,
convergence, realised moments against their targets, content hashes against
the files), and flags the cells that fail. :func:`verify_sample` first
checks that every stored file of every job was made for the job's
parameters (:func:`check_job_files`), then re-solves a seeded random sample
of stored contact batches from their stored inputs and compares the result
with what is stored: bit-identical for the same library versions.
"""

from __future__ import annotations

import json
import logging
import time
from functools import partial
from pathlib import Path
from types import MappingProxyType

import numpy as np
import pandas as pd

from roughcontact import __version__
from roughcontact.contact.aggregate import pressure_axis
from roughcontact.contact.cell import SWEEP_OPTIONS, aggregate_sweep
from roughcontact.contact.plausibility import (
    MAX_PRESSURE_OVER_E_STAR,
    MIN_CONTACT_ELEMENTS,
    implausible,
)
from roughcontact.errors import StoredFileError
from roughcontact.study import layout
from roughcontact.study.contact_records import ContactJob, StudyCell
from roughcontact.study.jobs.aggregation import validity_rows, validity_summary
from roughcontact.study.jobs.contact import contact_problem, read_counter, sweep_problem
from roughcontact.study.jobs.influence import certified_influence
from roughcontact.study.jobs.storage import (
    check_parameters,
    contact_datasets,
    read_contact,
    read_influence,
    read_surfaces,
)
from roughcontact.study.jobs.thermal import read_thermal
from roughcontact.study.provenance import atomic_path, git_commit
from roughcontact.units import MPA

log = logging.getLogger(__name__)

#: Relative error of the self compliance (diagonal of C) of each mesh preset at
#: the paper's 60 x 60 over 9 mm against the mesh-converged value, measured
#: with benchmarks/bench_influence.py (see roughcontact.influence). It is the
#: discretization error that dominates the real area and the peak pressure.
MESH_DIAGONAL_ERROR = {"paper": -0.82, "graded": -0.51, "refined": -0.024, "converged": -0.002}
#: The same for the matrix-free operators (roughcontact.operators): the hybrid's
#: interior diagonal with a "refined" coarse model (the outermost ring of
#: elements: up to 18 %); the half-space has no finite body to compare with.
OPERATOR_DIAGONAL_ERROR = {"hybrid": 0.009, "halfspace": float("nan")}
#: Relative tolerance on the moments of the "exact" generator's cells: every
#: realisation's sample Sk and Ku equal the targets to rounding (about 1e-13,
#: ``exact.target_heights``); surfaces stored before that correction (whose
#: midpoint quantiles had Ku 3.8 % low at (-1.5, 7)) are flagged.
EXACT_MOMENT_TOL = 1e-6

#: Realised moments further than this many standard errors from the target are flagged.
MOMENT_SIGMAS = 3.0
#: Nominal-pressure levels over a cell's range at which its shares above the hardness
#: are checked, unless told (the workflow passes contact.pressure_levels, the
#: aggregates' levels, so the audit's shares are the validity table's).
HARDNESS_LEVELS = 30


def _off_exactly(name: str, mean: float, se: float, goal: float) -> str | None:
    """The "exact" generator: every realisation has the same heights (rearranged) with
    the target moments, so the spread is round-off and the mean must be on target."""
    if abs(mean - goal) > EXACT_MOMENT_TOL * max(1.0, abs(goal)):
        return f"{name} off target"
    return None


def _off_statistically(name: str, mean: float, se: float, goal: float, *,
                       note: str = "") -> str | None:
    """A random generator: the mean further than ``MOMENT_SIGMAS`` standard errors away."""
    if se > 0 and abs(mean - goal) > MOMENT_SIGMAS * se:
        return f"{name} off target{note}"
    return None


#: How a generator's realised Sk and Ku are judged, by the cell's ``method``
#: (:func:`_off_statistically` for the others). The paper's method aims at the
#: process's moments, not a window's.
MOMENT_TESTS = MappingProxyType({
    "exact": _off_exactly,
    "paper": partial(_off_statistically, note=" (paper method: Eq 12-13 uncorrected)"),
})


def _moment_check(stats: dict, target: dict) -> tuple[dict, list[str]]:
    """Mean, standard error and z-score of the realised Sk, Ku and sigma (in units of the
    target sigma); flags for Sk and Ku off target (:data:`MOMENT_TESTS`)."""
    out, flags = {}, []
    m = len(stats["skew"])
    goals = {"skew": target["skew"], "kurt": target["kurt"], "sigma": 1.0}
    for name, goal in goals.items():
        values = np.asarray(stats[name], dtype=float)
        mean = float(values.mean())
        se = float(values.std(ddof=1) / np.sqrt(m)) if m > 1 else float("nan")
        out[f"realised_{name}_mean"] = mean
        out[f"realised_{name}_se"] = se
        out[f"realised_{name}_z"] = (mean - goal) / se if se > 0 else float("nan")
    off_target = MOMENT_TESTS.get(target.get("method"), _off_statistically)
    for name in ("skew", "kurt"):  # sigma: reported, not judged
        flag = off_target(name, out[f"realised_{name}_mean"], out[f"realised_{name}_se"],
                          goals[name])
        flags += [flag] if flag else []
    return out, flags


def audit_cell(study: str, index: int, cell: dict, root: str | Path = ".",
               levels: int = HARDNESS_LEVELS, study_seed: int | None = None,
               influences: dict | None = None) -> dict:
    """One row of the audit: parameters, provenance, checks and flags of a study cell.

    ``levels``: nominal-pressure levels of the hardness check (:func:`_hardness_check`).
    Each file must have been made for the cell (its surface cell and
    ``study_seed``, its geometry, its contact job), else the cell is flagged
    with the file, the field, the value expected and the value found.
    ``influences``: the attributes of the influence files already read and
    verified in this audit, by path and geometry (filled here): a matrix that many cells
    share (100 MB at 60 x 60) is read and hashed once, not once per cell.
    """
    root = Path(root)
    study_cell = StudyCell.from_params(cell)
    key = study_cell.contact_key
    surf_path = root / layout.surfaces(cell["surface_key"])
    infl_path = root / layout.influence(cell["geometry_key"])
    cont_path = root / layout.contact(key)
    s, g = cell["surface"], cell["geometry"]
    row = {
        "study": study, "cell": index,
        "sigma_um": cell["sigma_um"], "E_MPa": cell["E_MPa"],
        "skew": s["skew"], "kurt": s["kurt"], "b_mm": s["b_mm"][0],
        "size_mm": g["size_mm"][0], "grid": f"{g['grid'][0]}x{g['grid'][1]}",
        "nu": g["nu"], "thickness_mm": g["thickness_mm"], "base": g["base"],
        "mesh": g["mesh"], "accuracy": study_cell.accuracy.name,
        "surfaces": s["count"],
        "P_min_MPa": cell["pressure_MPa"][0], "P_max_MPa": cell["pressure_MPa"][1],
        "surface_cell": cell["surface_key"], "geometry": cell["geometry_key"],
        "contact_job": key,
        **{f"expected_{k}": v for k, v in study_cell.accuracy.errors().items()},
    }
    missing = [p.name for p in (surf_path, infl_path, cont_path) if not p.exists()]
    if missing:
        row["flags"] = "missing: " + ", ".join(missing)
        return row
    try:
        return _checked_cell(row, cell, surf_path, infl_path, cont_path, levels, study_seed,
                             {} if influences is None else influences)
    except StoredFileError as err:  # unreadable, made for another cell, or changed since
        log.warning("%s", err)
        row["flags"] = f"unusable file: {err}"
        return row


def _checked_cell(row: dict, cell: dict, surf_path, infl_path, cont_path, levels,
                  study_seed, influences: dict) -> dict:
    flags = []
    s, g = cell["surface"], cell["geometry"]
    surfaces = read_surfaces(surf_path, cell=s, study_seed=study_seed)
    row["study_seed"] = int(surfaces["attrs"]["study_seed"])
    row["seeds"] = " ".join(str(int(v)) for v in surfaces["seeds"])
    moments, moment_flags = _moment_check(surfaces["stats"], s)
    row.update(moments)
    flags += moment_flags

    # made for this geometry and verified against its content hash (once per file)
    checked = (str(infl_path), json.dumps(g, sort_keys=True))
    if checked not in influences:
        influences[checked] = read_influence(infl_path, geometry=g)[1]
    geometry_attrs = influences[checked]
    influence_hash = geometry_attrs["content_sha256"]
    row["operator"] = geometry_attrs["operator"]
    row["influence_sha256"] = influence_hash
    row["mesh_diagonal_error"] = (
        MESH_DIAGONAL_ERROR.get(g["mesh"], float("nan")) if row["operator"] == "dense"
        else OPERATOR_DIAGONAL_ERROR.get(row["operator"], float("nan")))

    stored, attrs = read_contact(cont_path, job=StudyCell.from_params(cell).job.params())
    arrays = contact_datasets(stored)
    row.update({
        "method": attrs["sweep_method"], "tol": float(attrs["sweep_tol"]),
        "precision": attrs["sweep_precision"],
        "worst_residual": float(attrs["worst_residual"]),
        "max_iterations": int(attrs["max_iterations"]),
        "total_iterations": int(attrs["total_iterations"]),
        "unconverged_steps": int(attrs["unconverged_steps"]),
        "unconverged_stiffness_steps": int(attrs["unconverged_stiffness_steps"]),
        "contact_wall_seconds": float(attrs["wall_seconds"]),
        "package_version": attrs["package_version"], "numpy_version": attrs["numpy_version"],
        "git_commit": attrs["git_commit"], "created": attrs["created"],
    })
    residual = arrays["residual"]
    if np.any(arrays["converged"] & ~(residual <= row["tol"])):
        flags.append("converged flag inconsistent with residual")
    if row["unconverged_steps"] or not arrays["converged"].all():
        flags.append(f"{int((~arrays['converged']).sum())} unconverged solves")
    if attrs.get("influence_content_sha256") != influence_hash:
        flags.append("solved on another influence matrix")
    if attrs.get("surfaces_content_sha256") != surfaces["content_sha256"]:
        flags.append("solved on other surfaces")
    flags += _hardness_check(row, cell, stored, levels)
    flags += _plausibility_check(row, cell, stored, levels)
    row["flags"] = "; ".join(flags)
    return row


def _plausibility_check(row: dict, cell: dict, stored, levels: int) -> list[str]:
    """The cell's results at its pressure levels against physical plausibility
    (:func:`roughcontact.contact.plausibility.implausible`: p_max beyond a multiple of
    E*, too few elements in contact), a flag per reason; in the row
    ``max_pressure_over_contact_modulus`` (p_max / E*) and ``contact_elements_at_P_max``
    (at the highest level with values)."""
    study_cell = StudyCell.from_params(cell)
    axis = pressure_axis(*study_cell.pressure_range, levels)
    _, frame = aggregate_sweep(stored, study_cell.height_scale, study_cell.E, axis,
                               hardness=study_cell.hardness)
    (nx, ny), nu = study_cell.geometry.grid, study_cell.geometry.nu
    valued = frame[frame["real_area_fraction_count"] > 0]
    row["max_pressure_over_contact_modulus"] = (
        float(np.nanmax(frame["max_pressure_mean"])) * (1.0 - nu * nu) / study_cell.E
        if len(valued) else float("nan"))
    row["contact_elements_at_P_max"] = (float(valued["real_area_fraction_mean"].iloc[-1])
                                        * nx * ny if len(valued) else float("nan"))
    _interface_columns(row, valued, study_cell)
    return [f"implausible: {reason}"
            for reason in implausible(frame, nx * ny, study_cell.E, nu)]


def _interface_columns(row: dict, valued, study_cell) -> None:
    """The cell's spots and gap at its highest pressure level with values (columns
    ``spots_at_P_max``, ``mean_spot_elements_at_P_max``: the mean spot area in elements,
    below about 4 the spots are not resolved and their count and the corrected area say
    little (docs/method/interface.md), and ``mean_gap_over_sigma_at_P_max``); NaN where no
    level has values."""
    if not len(valued):
        for name in ("spots_at_P_max", "mean_spot_elements_at_P_max",
                     "mean_gap_over_sigma_at_P_max"):
            row[name] = float("nan")
        return
    last = valued.iloc[-1]
    (lx, ly), (nx, ny) = study_cell.geometry.size, study_cell.geometry.grid
    row["spots_at_P_max"] = float(last["spot_count_mean"])
    row["mean_spot_elements_at_P_max"] = float(last["mean_spot_area_mean"]) * nx * ny / (lx * ly)
    row["mean_gap_over_sigma_at_P_max"] = (float(last["mean_gap_mean"])
                                           / study_cell.height_scale)


def _hardness_check(row: dict, cell: dict, stored, levels: int) -> list[str]:
    """Shares of an elastic cell above its hardness values (no solve); a flag per value
    where the mean share of the real area or load exceeds the cell's threshold."""
    if cell.get("cap_MPa") is not None:
        row["cap_MPa"] = float(cell["cap_MPa"])
        row["max_plastic_area_fraction"] = float(stored.plastic_area_fraction.max())
        return []
    flags = []
    axis = pressure_axis(*(p * MPA for p in cell["pressure_MPa"]), levels)
    for part in validity_rows(StudyCell.from_params(cell), stored, axis):
        H = float(part["hardness_MPa"].iloc[0])
        summary = validity_summary(part)
        row[f"area_above_{H:g}MPa"] = summary["max_area_above"]
        row[f"load_above_{H:g}MPa"] = summary["max_load_above"]
        if summary["first_flagged_MPa"] is not None:
            flags.append(
                f"elastic beyond the hardness {H:g} MPa from P = "
                f"{summary['first_flagged_MPa']:.3g} MPa (up to "
                f"{100 * summary['max_area_above']:.1f} % of the real area and "
                f"{100 * summary['max_load_above']:.1f} % of the load above it; threshold "
                f"{100 * float(part['threshold'].iloc[0]):g} %)")
    return flags


def audit_table(studies: dict[str, list[dict]], root: str | Path = ".",
                levels: int = HARDNESS_LEVELS, study_seed: int | None = None) -> pd.DataFrame:
    """The audit rows of every cell of every study (``{name: contact_cells}``);
    ``levels`` and ``study_seed`` as in :func:`audit_cell`."""
    influences = {}
    rows = [audit_cell(name, i, cell, root, levels, study_seed, influences)
            for name, cells in studies.items() for i, cell in enumerate(cells)]
    table = pd.DataFrame(rows)
    table["flagged"] = table["flags"].fillna("") != ""
    return table


def write_audit(table: pd.DataFrame, csv_path, md_path, *, config_hash: str = "") -> None:
    """The audit as CSV (every column) and Markdown (flagged cells first)."""
    with atomic_path(csv_path) as tmp:
        table.to_csv(tmp, index=False)
    flagged = table[table["flagged"]]
    lines = [
        "# Audit of the contact study",
        "",
        f"{len(table)} cells in {table['study'].nunique()} studies; "
        f"{len(flagged)} flagged. Config hash {config_hash or 'n/a'}; "
        f"audited at git commit {git_commit()}.",
        "",
        "Checks: every file made for its cell's parameters (surface cell and seed, "
        "geometry, contact job); every solve converged (KKT residual <= tol); realised "
        "mean Sk and Ku "
        f"within {MOMENT_SIGMAS:g} standard errors of the target; the contact result, "
        "its influence matrix and its surfaces unchanged since the solve (content "
        "hashes); the results physically plausible (peak pressure at most "
        f"{MAX_PRESSURE_OVER_E_STAR:g} E*, at least {MIN_CONTACT_ELEMENTS} elements in "
        "contact at the highest pressure). `mesh_diagonal_error`: relative error of the "
        "self compliance of the mesh preset at 60 x 60 (the error that dominates real area "
        "and peak pressure).",
        "",
        "## Flagged cells",
        "",
    ]
    if flagged.empty:
        lines.append("None.")
    else:
        for _, r in flagged.iterrows():
            lines.append(f"- **{r['study']} cell {r['cell']}** ({r['contact_job']}): {r['flags']}")
    columns = ["study", "cell", "skew", "kurt", "b_mm", "size_mm", "nu", "mesh", "sigma_um",
               "surfaces", "realised_skew_mean", "realised_kurt_mean", "worst_residual",
               "unconverged_steps", "mesh_diagonal_error", "contact_wall_seconds", "flagged"]
    present = [c for c in columns if c in table]
    lines += ["", "## All cells", "", "| " + " | ".join(present) + " |",
              "|" + "---|" * len(present)]
    for _, r in table[present].iterrows():
        cells = [f"{v:.4g}" if isinstance(v, float) else str(v) for v in r]
        lines.append("| " + " | ".join(cells) + " |")
    lines += ["", "Full columns (seeds, hashes, versions, solver statistics): audit.csv."]
    with atomic_path(md_path) as tmp:
        Path(tmp).write_text("\n".join(lines) + "\n")


def _job_files(root: Path, key: str, job: dict, study_seed: int | None = None) -> dict:
    """The files of the contact job ``key`` (``job``: its ``params()``) by kind, each with
    the parameters it must have been made for (:func:`check_parameters`): the files
    the job reads (:meth:`~roughcontact.study.contact_records.ContactJob.files`: its
    surfaces and influence, a counter body's) and its contact file."""
    files = {name: (root / file.path, file.made_for)
             for name, file in ContactJob.from_params(job).files(study_seed).items()}
    files["contact"] = (root / layout.contact(key), {"job": job})
    return files


def check_job_files(jobs: dict[str, dict], root: str | Path = ".",
                    study_seed: int | None = None) -> None:
    """Check that every file of every contact job was made for the job's parameters.

    ``jobs``: contact key -> the job's ``params()``. Each job's surface file
    must hold its surface cell (and ``study_seed``), its influence file its
    geometry, its contact file its job, and a counter body's files its counter
    body (:func:`check_parameters`: the attributes only, so every file is checked,
    not a sample). Raises :class:`StoredFileError` naming each file that is not,
    with the field, the values expected and found, and the command that rebuilds it.
    """
    problems, checked = [], set()
    for key, job in jobs.items():
        for path, expected in _job_files(Path(root), key, job, study_seed).values():
            if path in checked:
                continue
            checked.add(path)
            try:
                check_parameters(path, **expected)
            except StoredFileError as err:
                problems.append(str(err))
    if problems:
        raise StoredFileError(f"{len(problems)} stored files were not made for the jobs that "
                              "read them (no batch was re-solved):\n  " + "\n  ".join(problems))


def _stored_batches(jobs: dict[str, dict], root: Path) -> list[tuple[str, int, int]]:
    """Every stored batch of the jobs' contact files: (job key, first, end) surfaces."""
    candidates = []
    for key in sorted(jobs):
        _, attrs = read_contact(root / layout.contact(key))
        m = len(attrs["seeds"])
        size = int(attrs.get("batch_size", m))
        candidates += [(key, start, min(m, start + size)) for start in range(0, m, size)]
    return candidates


def _compare(stored, again, rows: slice) -> tuple[bool, float]:
    """Whether the re-solved batch ``again`` equals the ``rows`` of the ``stored``
    sweep bit for bit, and its largest relative difference in the continuous columns
    (the probes' float columns among them; their yes/no states compared bit for bit
    only, and NaN equal to NaN, e.g. a factor not defined where it was not)."""
    worst, identical = 0.0, True
    continuous = ("approach", "nominal_pressure", "mean_plane_deflection",
                  "real_area_fraction", "max_pressure", "normalized_stiffness")
    if stored.mean_gap is not None:
        continuous += ("mean_gap",)
        # counted on the contact set: one element entering contact at a tolerance's
        # edge changes them by a step, so they are compared bit for bit only
        for name in ("spot_count", "perimeter", "corrected_real_area_fraction"):
            identical &= bool(np.array_equal(getattr(stored, name)[rows],
                                             getattr(again, name)))
    for column in stored.probe_columns.specs:
        a, b = stored.probe_columns[column.name][rows], again.probe_columns[column.name]
        identical &= bool(np.array_equal(a, b, equal_nan=not column.state))
        if not column.state:
            worst = max(worst, _relative_difference(a, b, column.rounding))
    for name in continuous:
        a = getattr(stored, name)[rows]
        b = getattr(again, name)
        identical &= bool(np.array_equal(a, b))
        worst = max(worst, _relative_difference(a, b))
    return identical, worst


def _relative_difference(stored, again, rounding: float = 0.0) -> float:
    """The largest ``|a - b| / max(|a|, 1e-12 max |a|, rounding)`` of two columns: 0 where
    they are equal (NaN and NaN included) or differ by at most ``rounding``, infinite where
    one is NaN and the other not."""
    a, b = np.asarray(stored, dtype=float), np.asarray(again, dtype=float)
    same = (a == b) | (np.isnan(a) & np.isnan(b)) | (np.abs(a - b) <= rounding)
    if same.all():
        return 0.0
    scale = np.maximum(np.maximum(np.abs(a), np.nanmax(np.abs(a)) * 1e-12), rounding)
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.abs(a - b) / scale
    return float(np.where(same, 0.0, np.where(np.isnan(ratio), np.inf, ratio)).max())


def verify_sample(jobs: dict[str, dict], sample: int, seed: int, settings: dict,
                  root: str | Path = ".", rtol: float | None = None,
                  study_seed: int | None = None) -> pd.DataFrame:
    """Re-solve a seeded random sample of stored contact batches and compare.

    First every stored file of every job must have been made for it
    (:func:`check_job_files`: a file copied over another one is refused, even
    where re-solving it would reproduce it bit for bit). A batch (the
    surfaces solved together, ``batch_size`` of the file) is
    re-solved from the stored surfaces and influence matrix with the stored
    settings and approaches. Same library versions: the arrays must be
    bit-identical. Otherwise (another version, or a source tree with
    uncommitted changes) they must agree within ``rtol`` (default ``100 * tol``
    of the solve) in the load, area and stiffness columns.
    """
    root = Path(root)
    check_job_files(jobs, root, study_seed)
    rng = np.random.default_rng(seed)
    candidates = _stored_batches(jobs, root)
    picks = rng.choice(len(candidates), size=min(sample, len(candidates)), replace=False)
    rows = []
    for pick in sorted(picks):
        key, first, last = candidates[pick]
        job = jobs[key]
        files = {kind: path for kind, (path, _) in _job_files(root, key, job).items()}
        stored, attrs = read_contact(files["contact"], job=job)
        surfaces = read_surfaces(files["surfaces"], cell=job["surface"], study_seed=study_seed)
        record = ContactJob.from_params(job)
        unit = certified_influence(read_influence(files["influence"],
                                                  geometry=job["geometry"])[0],
                                   files["influence"], record.geometry)
        counter, _ = read_counter(record, files, study_seed)
        problem = contact_problem(record, surfaces["heights"], unit, counter,
                                  record.thermal.seeded(stored.probe_columns.probes, files,
                                                        read_thermal))
        start = time.perf_counter()
        options = SWEEP_OPTIONS.with_(method=stored.method, tol=stored.tol,
                                      precision=stored.precision, max_iter=stored.max_iter)
        again = sweep_problem(record, problem, stored.approach.shape[1], options,
                              rows=slice(first, last))
        seconds = time.perf_counter() - start
        commit = git_commit()
        same_versions = (attrs["package_version"] == __version__
                         and attrs["numpy_version"] == np.__version__
                         and attrs["git_commit"] == commit and not commit.endswith("-dirty"))
        identical, worst = _compare(stored, again, slice(first, last))
        limit = rtol if rtol is not None else 100 * stored.tol
        ok = identical if same_versions else worst <= limit
        rows.append({
            "contact_job": key, "surfaces": f"{first}-{last - 1}", "identical": identical,
            "max_relative_difference": worst, "same_versions": same_versions,
            "criterion": "bit-identical" if same_versions else f"relative <= {limit:.1e}",
            "ok": ok, "seconds": seconds,
        })
        (log.info if ok else log.error)("verify %s surfaces %d-%d: identical %s, max rel "
                                        "diff %.3g (%.1f s)", key, first, last - 1,
                                        identical, worst, seconds)
    return pd.DataFrame(rows)
