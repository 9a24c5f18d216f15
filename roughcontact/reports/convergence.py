"""Mesh convergence of the finite-element influence coefficients, and what it changes.

The influence matrix ``C`` of Eq 16 of Kumar et al. (2006) comes from a
finite-element model of the block (``roughcontact.influence``). Its near field
(the self compliance ``C_ii`` and the nearest neighbours) converges slowly
with the mesh; the paper's mesh (Table 1) makes ``C_ii`` about five times too
small. :func:`influence_convergence` measures, per mesh preset,

1. the cost of building ``E * C``: problem size, wall time and peak memory;
2. the dimensionless entries ``E * C_ij / h`` (h: contact element size) of
   the centre element's row: the self compliance, the neighbours at offsets
   (1, 0), (1, 1), (2, 0) and one far entry, and the row sum (for nu = 0 and
   a clamped base every row sums to L, Eq 37-38);
3. the rough-contact response that depends on them: for a few Gaussian
   surfaces swept over rigid approaches and read at given nominal pressures
   P exactly as the workflow's contact and aggregate jobs do, the normalized
   stiffness ``k_P = (L / A_n) dF/dd`` (Eq 33), the real area fraction, the
   peak pressure and the asperity deflection ``d_a = d - d_b`` (Eq 35, 45),

and the relative error of every number against a reference mesh (by default
the ``"converged"`` preset). It takes the block and the report's section as a
record, :class:`~roughcontact.study.config.ConvergenceSettings` (presets,
surfaces, sigma, b, pressures; the schema's defaults), e.g.
``influence_convergence(BlockGeometry(), ConvergenceSettings(presets=("paper",
"refined")))``. Love's elastic half-space (``halfspace_influence``)
is added as a row for comparison: it is the thick-block limit of the near
field, not of the bulk (its rows do not sum to L).

Peak memory is measured honestly by building each matrix in a fresh Python
process (``subprocess`` running this module's worker): ``ru_maxrss`` of that
process after the build is the peak resident set of the whole process
(interpreter, libraries, finite-element assembly and the sparse
factorization, including memory allocated inside MKL PARDISO, which
``tracemalloc`` would miss); ``memory_increase_GB`` subtracts the resident set
measured just before the build (after the imports). A subprocess rather than
``multiprocessing`` keeps it safe to call from scripts without a
``__main__`` guard (Snakemake ``script:``), which ``spawn`` would re-execute.

Richardson extrapolation needs three meshes of one family refined by a
constant ratio (here: ``MeshSpec`` objects that differ only in
``refinement``, e.g. 1, 2, 4) in the asymptotic range. The named presets are
not such a sequence (they differ in element type, grading and plan
coarsening), so for them no extrapolated row is produced and
``table.attrs["richardson"]`` says why.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import os
import re
import shutil
import socket
import tempfile
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from types import MappingProxyType
from typing import NamedTuple

import numpy as np
import pandas as pd
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from roughcontact.contact.cell import SWEEP_OPTIONS, sweep_and_aggregate
from roughcontact.elasticity.influence import GB, BlockGeometry, MeshSpec
from roughcontact.reports.build_worker import HALFSPACE, build, centre_entries, run_isolated
from roughcontact.reports.execution import dead_writers
from roughcontact.reports.plotting import save_figure
from roughcontact.study.config import BuildSettings, ConvergenceSettings
from roughcontact.study.jobs.storage import read_influence
from roughcontact.surfaces.spec import SurfaceSpec
from roughcontact.surfaces.synthetic import derive_seeds, generate_many

__all__ = [
    "COLUMNS",
    "CONTACT_COLUMNS",
    "CONTACT_QUANTITIES",
    "DEFAULT_BUILD",
    "DEFAULT_SETTINGS",
    "ENTRY_QUANTITIES",
    "HALFSPACE",
    "SCRATCH_PREFIX",
    "influence_convergence",
    "mesh_label",
    "plot_influence_convergence",
    "remove_stale_scratch",
    "richardson",
]

log = logging.getLogger("roughcontact.convergence")

#: Influence entries recorded per mesh (all E * C / h, dimensionless, except row sums).
ENTRY_QUANTITIES = ("self_compliance", "neighbour_1_0", "neighbour_1_1", "neighbour_2_0",
                    "far_entry", "row_sum_over_L")
#: Rough-contact quantities recorded per mesh and nominal pressure.
CONTACT_QUANTITIES = ("k_P_Pa", "real_area_fraction", "max_pressure_Pa", "approach_m",
                      "mean_plane_deflection_m", "asperity_deflection_m")

#: Each of ``CONTACT_QUANTITIES``: its column of the aggregated cell table
#: (:func:`roughcontact.contact.aggregate.aggregate_cell`, ``<column>_mean``).
CONTACT_COLUMNS = {"k_P_Pa": "normalized_stiffness", "real_area_fraction": "real_area_fraction",
                   "max_pressure_Pa": "max_pressure", "approach_m": "approach",
                   "mean_plane_deflection_m": "mean_plane_deflection",
                   "asperity_deflection_m": "asperity_deflection"}

#: Column -> (unit, description) of the table returned by ``influence_convergence``.
#: Every quantity q of ``ENTRY_QUANTITIES + CONTACT_QUANTITIES`` also has a column
#: ``q + "_error"``: the relative error q / q_reference - 1 (dimensionless).
COLUMNS = {
    "mesh": ("-", "mesh preset name, MeshSpec label, 'halfspace' or 'richardson'"),
    "kind": ("-", "'fe' (finite elements), 'halfspace' (Love) or 'richardson' (extrapolated)"),
    "element": ("-", "finite element type (hex8, hex20, hex27); empty for the half-space"),
    "refinement": ("1", "finite elements per contact element along x and y"),
    "nu": ("1", "Poisson's ratio"),
    "grid_x": ("1", "contact elements along x"),
    "grid_y": ("1", "contact elements along y"),
    "thickness_m": ("m", "block thickness L"),
    "element_size_m": ("m", "contact element size h = sqrt(hx hy)"),
    "dofs": ("1", "finite-element equations (0 for the half-space)"),
    "build_s": ("s", "wall time of building E*C (assembly, factorization, condensation)"),
    "peak_memory_GB": ("GB", "peak resident set of the build process (1e9 bytes)"),
    "memory_increase_GB": ("GB", "peak resident set minus the set before the build"),
    "estimate_GB": ("GB", "predicted peak memory (influence.estimate_cost)"),
    "self_compliance": ("1", "E C_cc / h at the centre element c"),
    "neighbour_1_0": ("1", "E C_c,c+(1,0) / h"),
    "neighbour_1_1": ("1", "E C_c,c+(1,1) / h"),
    "neighbour_2_0": ("1", "E C_c,c+(2,0) / h"),
    "far_entry": ("1", "E C_c,c+(far_offset,0) / h"),
    "far_offset": ("1", "x offset of far_entry [contact elements]"),
    "row_sum_over_L": ("1", "sum_j E C_cj / L (1 for nu = 0, Eq 38)"),
    "row_sum_max_error": ("1", "max over rows i of |sum_j E C_ij / L - 1|"),
    "pressure_Pa": ("Pa", "nominal pressure P = F / A_n"),
    "k_P_Pa": ("Pa", "normalized stiffness (L / A_n) dF/dd (Eq 33), mean over surfaces"),
    "real_area_fraction": ("1", "fraction of elements in contact, mean over surfaces"),
    "max_pressure_Pa": ("Pa", "largest element pressure, mean over surfaces"),
    "approach_m": ("m", "rigid approach d, mean over surfaces"),
    "mean_plane_deflection_m": ("m", "d_b = mean surface displacement (Eq 35)"),
    "asperity_deflection_m": ("m", "d_a = d - d_b (Eq 45), mean over surfaces"),
    "surfaces": ("1", "surfaces averaged"),
    "reached": ("-", "every surface reached this nominal pressure in the sweep"),
    "contact_s": ("s", "wall time of the contact sweeps"),
    "reference": ("-", "mesh the *_error columns compare against"),
    "note": ("-", "remarks (Richardson rows: the meshes and ratio used)"),
}

#: Rigid approaches per sweep (``pipeline.sweep_approaches``: geometric up to the end).
_SWEEP_STEPS = 40

#: The report's settings by default: the schema's (``reports.influence_convergence``).
DEFAULT_SETTINGS = ConvergenceSettings()
#: How the report builds its matrices by default: the sparse solver chosen by the
#: platform ("auto") and an estimated peak memory of at most 16 GB.
DEFAULT_BUILD = BuildSettings(solver="auto", max_bytes=16 * GB)

#: Scratch folders of the isolated builds (task and result files), in the system's
#: temporary folder: ``<SCRATCH_PREFIX><host>-<pid>-<random>``, one per build.
SCRATCH_PREFIX = "roughcontact-convergence-"


# ---------------------------------------------------------------------------
# Scratch folders of the isolated builds


def _scratch_owner() -> str:
    """``<host>-<pid>`` of this process, as it appears in its scratch folders' names."""
    return f"{socket.gethostname()}-{os.getpid()}"


def remove_stale_scratch(root: str | os.PathLike | None = None) -> list[Path]:
    """Remove the scratch folders that killed reports left in ``root``.

    An isolated build keeps its task and result files in a folder
    ``<SCRATCH_PREFIX><host>-<pid>-<random>`` of ``root`` (default: the
    system's temporary folder, ``tempfile.gettempdir()``, which honours
    ``TMPDIR``) and removes it when the build ends; a report killed with
    SIGKILL (``kill -9``, the out-of-memory killer, a cluster's wall-time
    limit) cannot. Folders of this machine whose process no longer runs are
    removed; those of running processes, and of other machines (a shared
    ``TMPDIR``), are kept. Returns the removed folders.
    """
    root = Path(tempfile.gettempdir() if root is None else root)
    pattern = re.compile(rf"{re.escape(SCRATCH_PREFIX)}{re.escape(socket.gethostname())}"
                         r"-(\d+)-\w+")
    removed = []
    folders = (path for path in root.glob(SCRATCH_PREFIX + "*") if path.is_dir())
    for path, pid in dead_writers(folders, pattern):
        shutil.rmtree(path, ignore_errors=True)
        log.warning("removed %s, left by an interrupted report (process %s, no longer "
                    "running)", path, pid)
        removed.append(path)
    return removed


# ---------------------------------------------------------------------------
# One mesh: build, entries, contact (runs in a fresh process)


def mesh_label(mesh: str | MeshSpec) -> str:
    """Short name of a preset or an explicit ``MeshSpec``."""
    if isinstance(mesh, str):
        return mesh
    if mesh.layers is not None:
        through = f"{mesh.layers} layers"
    else:
        through = f"graded {mesh.top_layer:g}/{mesh.growth:g}"
    coarse = "" if mesh.coarsen_at is None else f" coarsen {mesh.coarsen_at:g}"
    return f"{mesh.element} r{mesh.refinement} {through}{coarse}"


def _contact_response(ec: np.ndarray, geom: BlockGeometry, task: dict) -> dict:
    """Sweep the task's surfaces on ``C = ec / E`` and read them at the task's pressures.

    The steps of a workflow contact job and its aggregation
    (:func:`roughcontact.contact.cell.sweep_and_aggregate`), so that the
    report's numbers are read off the sweeps as the figures' are: geometric
    approaches up to an end that reaches 1.1 times the largest target
    pressure on every surface without a trial solve, every surface in one
    batch, tangent stiffness at every step, each surface's curves read as a
    power law between its solved steps (unconverged steps excluded), then
    averaged over the surfaces at equal P, as the paper's curves.
    """
    sigma = float(task["sigma"])
    heights = task["heights"] / sigma
    pressures = np.asarray(task["pressures"], dtype=float)
    sweep, physical, frame = sweep_and_aggregate(
        ec, heights, geom, sigma=sigma, pressures=pressures, steps=_SWEEP_STEPS, reach=1.1,
        options=SWEEP_OPTIONS.with_(method="auto", tol=task["tol"], precision="double"))
    if not sweep.converged.all():
        log.warning("contact sweep: %d of %d solves did not converge",
                    int((~sweep.converged).sum()), sweep.converged.size)
    return {name: frame[f"{column}_mean"].to_numpy()
            for name, column in CONTACT_COLUMNS.items()} | {
        "reached": physical.nominal_pressure[:, -1].min() >= pressures,
        "surfaces": heights.shape[0]}


def _run_task(task: dict) -> dict:
    """One mesh: its matrix (read from the workflow's build, or built, in a fresh process
    when ``task["isolated"]``), its centre entries and (optionally) its contact response."""
    stored = task.get("stored")
    if stored is not None:  # built by the workflow's influence rule: reuse it and its costs
        ec, attrs = read_influence(stored)
        row = {
            "dofs": int(attrs["dofs"]), "build_s": float(attrs["build_seconds"]),
            "estimate_GB": float(attrs["estimated_peak_gb"]),
            "peak_memory_GB": float(attrs.get("peak_rss_gb", math.nan)),
            "memory_increase_GB": math.nan,
            **centre_entries(ec, task["geometry"], task["far"]),
        }
    else:
        build_task = {k: v for k, v in task.items() if k not in ("heights", "pressures")}
        # isolated: its scratch folder is named after this process (remove_stale_scratch)
        ec, row = (run_isolated(build_task, prefix=f"{SCRATCH_PREFIX}{_scratch_owner()}-")
                   if task["isolated"] else build(build_task))
    if task.get("heights") is not None:
        start = time.perf_counter()
        row |= _contact_response(ec, task["geometry"], task)
        row["contact_s"] = time.perf_counter() - start
    return row


# ---------------------------------------------------------------------------
# Richardson extrapolation


def richardson(coarse: float, medium: float, fine: float, ratio: float,
               orders: tuple[float, float] = (0.5, 6.0)) -> tuple[float, float]:
    """Richardson extrapolation of three solutions on meshes refined by ``ratio``.

    With errors ``e ~ a h^p`` and h shrinking by ``ratio`` from coarse to
    medium to fine, the observed order is
    ``p = ln((coarse - medium) / (medium - fine)) / ln(ratio)`` and the
    extrapolated value ``fine + (fine - medium) / (ratio^p - 1)``.

    Returns ``(value, p)``; ``(nan, nan)`` when it does not apply: the
    differences change sign (oscillating, not asymptotic) or p lies outside
    ``orders``. Equal fine and medium values are returned as they are (p = inf).
    """
    values = (coarse, medium, fine)
    if not all(math.isfinite(v) for v in values) or not ratio > 1.0:
        return math.nan, math.nan
    d_coarse, d_fine = coarse - medium, medium - fine
    if d_fine == 0.0:
        return (fine, math.inf) if d_coarse == 0.0 else (math.nan, math.nan)
    if d_coarse / d_fine <= 0.0:
        return math.nan, math.nan
    p = math.log(d_coarse / d_fine) / math.log(ratio)
    if not orders[0] <= p <= orders[1]:
        return math.nan, p
    return fine + (fine - medium) / (ratio**p - 1.0), p


def _refinement_sequence(meshes: Sequence[tuple[str, MeshSpec]]):
    """First three meshes (in order) that differ only in ``refinement``, by a constant ratio."""
    def family(spec: MeshSpec) -> tuple:
        return dataclasses.replace(spec, refinement=1)

    for i, (_, a) in enumerate(meshes):
        for j in range(i + 1, len(meshes)):
            b = meshes[j][1]
            for k in range(j + 1, len(meshes)):
                c = meshes[k][1]
                if not family(a) == family(b) == family(c):
                    continue
                if b.refinement * b.refinement == a.refinement * c.refinement and \
                        a.refinement < b.refinement:
                    return meshes[i][0], meshes[j][0], meshes[k][0], b.refinement / a.refinement
    return None


# ---------------------------------------------------------------------------
# The study


class _MeshJob(NamedTuple):
    """One mesh of the study (or Love's half-space): what is built and how it is labelled."""

    label: str
    kind: str  # "fe" or HALFSPACE
    geometry: BlockGeometry
    element: str  # finite element type; "" for the half-space
    refinement: int  # finite elements per contact element; 0 for the half-space
    stored: str | os.PathLike | None  # the workflow's build of this mesh, if any


def _mesh_jobs(base: BlockGeometry, presets, labels: list[str], halfspace: bool,
               stored: Mapping) -> list[_MeshJob]:
    """The meshes to build, in order: ``presets`` on ``base``, then the half-space."""
    jobs = []
    for label, preset in zip(labels, presets, strict=True):
        geometry = dataclasses.replace(base, mesh=preset)
        spec = geometry.mesh_spec
        jobs.append(_MeshJob(label, "fe", geometry, spec.element, spec.refinement,
                             stored.get(label)))
    if halfspace:
        jobs.append(_MeshJob(HALFSPACE, HALFSPACE, base, "", 0, None))
    return jobs


def _checked_pressures(presets, surfaces: int, pressures) -> np.ndarray:
    """``pressures`` [Pa] as an array, after checking the study's arguments."""
    if not presets:
        raise ValueError("presets must name at least one mesh")
    if surfaces < 0 or int(surfaces) != surfaces:
        raise ValueError(f"surfaces must be a non-negative integer, got {surfaces!r}")
    pressures = np.asarray(pressures, dtype=float)
    if surfaces and (pressures.ndim != 1 or pressures.size == 0 or not (pressures > 0).all()):
        raise ValueError(f"pressures must be positive nominal pressures [Pa], got {pressures!r}")
    return pressures


def _reference_label(labels: list[str], reference: str | None, halfspace: bool) -> str:
    """The mesh the errors compare against: ``reference``, else "converged" if measured,
    else the last preset; checked to be one of the meshes."""
    if len(set(labels)) != len(labels):
        raise ValueError(f"presets must be distinct, got {labels}")
    if reference is None:
        reference = "converged" if "converged" in labels else labels[-1]
    if reference not in labels and not (halfspace and reference == HALFSPACE):
        raise ValueError(f"reference {reference!r} is not one of the meshes {labels}")
    return reference


def _study_surfaces(base: BlockGeometry, settings: ConvergenceSettings,
                    seed: int) -> np.ndarray | None:
    """The Gaussian surfaces [m] of ``settings`` every mesh is pressed with (None without a
    contact part)."""
    if not settings.surfaces:
        return None
    spec = SurfaceSpec(grid=base.grid, size=base.size,
                       corr_length=(settings.corr_length,) * 2, sigma=settings.sigma)
    return generate_many(spec, derive_seeds(seed, "influence_convergence", settings.surfaces))


def _measure(jobs: list[_MeshJob], common: Mapping, contact: bool,
             progress: Callable[[str], None] | None) -> list[dict]:
    """Build (or read) and measure each mesh of ``jobs``: the tidy rows of all of them."""
    start = time.perf_counter()
    rows = []
    for job in jobs:
        geom = job.geometry
        result = _run_task({"label": job.label, "kind": job.kind, "geometry": geom, **common,
                            "stored": job.stored})
        info = {
            "mesh": job.label, "kind": job.kind, "element": job.element,
            "refinement": job.refinement, "nu": geom.nu,
            "grid_x": geom.grid[0], "grid_y": geom.grid[1], "thickness_m": geom.thickness,
            "element_size_m": math.sqrt(geom.spacing[0] * geom.spacing[1]),
        }
        rows.extend(_tidy_rows(info | result, common["pressures"] if contact else None))
        message = (f"{job.label}: {result['dofs']} dofs, built in {result['build_s']:.1f} s, "
                   f"peak {result['peak_memory_GB']:.2f} GB, E*C_cc/h = "
                   f"{result['self_compliance']:.4f}"
                   + (f", contact {result['contact_s']:.1f} s" if contact else "")
                   + f"; elapsed {time.perf_counter() - start:.1f} s")
        log.info(message)
        if progress is not None:
            progress(message)
    return rows


def influence_convergence(
    base: BlockGeometry, settings: ConvergenceSettings = DEFAULT_SETTINGS, *,
    build: BuildSettings = DEFAULT_BUILD, halfspace: bool = True, reference: str | None = None,
    far: int = 10, tol: float = 1e-10, seed: int = 2006, isolate: bool = True,
    stored: Mapping[str, str | os.PathLike] | None = None,
    progress: Callable[[str], None] | None = None,
) -> pd.DataFrame:
    """Cost, influence entries and rough-contact response per mesh, with errors.

    For each mesh of ``settings.presets`` (and Love's half-space when
    ``halfspace``), ``E * C`` of ``base`` with that mesh: its cost, its centre
    row's entries and the response of ``settings.surfaces`` Gaussian surfaces
    (exponential ACF, Eq 1; seeds ``derive_seeds(seed, "influence_convergence",
    surfaces)``, the same for every mesh) swept over rigid approaches (Eq 27)
    and read at each of ``settings.pressures`` as the workflow's contact and
    aggregate jobs do: k_P (Eq 33), real area fraction, peak pressure, d, d_b
    (Eq 35) and d_a (Eq 45), each averaged over the surfaces at equal P.

    Parameters
    ----------
    base : BlockGeometry
        Block, grid, E, nu and support; its ``mesh`` is replaced by each preset.
    settings : ConvergenceSettings
        The report's section (default: the schema's): ``presets`` (keys of
        ``influence.MESH_PRESETS`` or explicit ``MeshSpec`` objects, coarse to
        fine), ``surfaces`` per mesh (0: no contact part, its columns NaN),
        their height std ``sigma`` and ACF correlation length ``corr_length``
        [m], and the nominal ``pressures`` P [Pa] where the contact is read.
    build : BuildSettings
        Sparse solver and memory limit [bytes] of ``influence.unit_modulus_influence``
        (an estimate above it raises ``ModelTooLarge`` before building).
    halfspace : bool
        Add Love's half-space (``kind == "halfspace"``) as a row.
    reference : str, optional
        Mesh label the ``*_error`` columns compare against; default
        ``"converged"`` when present, else the last mesh of the presets.
    far, tol, seed : int, float, int
        x offset of ``far_entry`` [contact elements], clipped to the grid; the
        KKT tolerance of the contact solves; the surfaces' root seed.
    isolate : bool
        Build each matrix in a fresh Python process (default: an honest
        per-build peak memory); ``False`` builds here and leaves the memory
        columns NaN (ru_maxrss is process-wide and monotone).
    stored : mapping, optional
        Preset name -> influence file of the workflow's ``influence`` rule for
        ``base`` with that mesh: read instead of built, with the build time and
        peak memory that build recorded.
    progress : callable, optional
        Given a line after each mesh (also logged at INFO on ``roughcontact.convergence``).

    Returns
    -------
    pandas.DataFrame
        One row per mesh and pressure (tidy); columns and units in ``COLUMNS``
        (also ``table.attrs["units"]``); ``q_error = q / q_reference - 1`` for
        every quantity q of ``ENTRY_QUANTITIES`` and ``CONTACT_QUANTITIES``.
        Three meshes differing only in ``refinement`` by a constant ratio add
        ``kind == "richardson"`` rows (module docstring);
        ``table.attrs["richardson"]`` says what was done or why nothing was.
    """
    presets, surfaces = settings.presets, settings.surfaces
    pressures = _checked_pressures(presets, surfaces, settings.pressures)
    meshes = [(mesh_label(p), dataclasses.replace(base, mesh=p).mesh_spec) for p in presets]
    labels = [label for label, _ in meshes]
    reference = _reference_label(labels, reference, halfspace)
    remove_stale_scratch()
    common = {"far": far, "solver": build.solver, "max_bytes": float(build.max_bytes),
              "tol": tol, "heights": _study_surfaces(base, settings, seed),
              "sigma": settings.sigma, "pressures": pressures, "isolated": isolate}
    jobs = _mesh_jobs(base, presets, labels, halfspace, stored or {})
    table = pd.DataFrame(_measure(jobs, common, bool(surfaces), progress))
    table, note = _add_richardson(table, meshes)
    table = _add_errors(table, reference)
    table.attrs["units"] = {k: v[0] for k, v in COLUMNS.items()}
    table.attrs["richardson"] = note
    log.info("Richardson extrapolation: %s", note)
    columns = [c for c in COLUMNS if c in table] + [c for c in table if c not in COLUMNS]
    return table[columns]


def _tidy_rows(result: dict, pressures: np.ndarray | None) -> list[dict]:
    """One row per pressure (or one row without the contact part)."""
    scalar = {k: v for k, v in result.items() if k not in CONTACT_QUANTITIES + ("reached",)}
    if pressures is None:
        return [scalar | {"pressure_Pa": math.nan} | dict.fromkeys(CONTACT_QUANTITIES, math.nan)]
    return [scalar | {"pressure_Pa": float(p), "reached": bool(result["reached"][i])}
            | {q: float(result[q][i]) for q in CONTACT_QUANTITIES}
            for i, p in enumerate(pressures)]


def _add_richardson(table: pd.DataFrame, meshes) -> tuple[pd.DataFrame, str]:
    """Append extrapolated rows when three meshes form a refinement sequence."""

    found = _refinement_sequence(meshes)
    if found is None:
        return table, ("not applied: no three meshes differ only in refinement by a constant "
                       "ratio (the named presets change element, grading and coarsening, "
                       "so they are not one refined mesh family)")
    coarse, medium, fine, ratio = found
    quantities = ENTRY_QUANTITIES + CONTACT_QUANTITIES
    parts = {label: table[table["mesh"] == label].reset_index(drop=True)
             for label in (coarse, medium, fine)}
    extrapolated = parts[fine].copy()
    orders = {}
    for q in quantities:
        values, ps = [], []
        for i in range(len(extrapolated)):
            v, p = richardson(parts[coarse][q][i], parts[medium][q][i], parts[fine][q][i], ratio)
            values.append(v)
            ps.append(p)
        extrapolated[q] = values
        orders[q] = ps
    for column in ("dofs", "build_s", "peak_memory_GB", "memory_increase_GB", "estimate_GB",
                   "contact_s", "row_sum_max_error"):
        if column in extrapolated:
            extrapolated[column] = math.nan
    extrapolated["mesh"] = "richardson"
    extrapolated["kind"] = "richardson"
    note = (f"applied to {coarse} / {medium} / {fine} (ratio {ratio:g}); NaN where the "
            f"differences change sign or the observed order lies outside [0.5, 6]; observed "
            "orders: " + ", ".join(f"{q} {np.nanmean(v) if np.isfinite(v).any() else math.nan:.2f}"
                                   for q, v in orders.items()))
    extrapolated["note"] = note
    return pd.concat([table, extrapolated], ignore_index=True), note


def _add_errors(table: pd.DataFrame, reference: str) -> pd.DataFrame:
    """Relative errors ``q / q_reference - 1`` (matched by pressure for contact quantities)."""
    ref = table[table["mesh"] == reference]
    table = table.copy()
    for q in ENTRY_QUANTITIES:
        table[q + "_error"] = table[q] / ref[q].iloc[0] - 1.0
    for q in CONTACT_QUANTITIES:
        by_pressure = dict(zip(ref["pressure_Pa"], ref[q], strict=True))
        ref_values = table["pressure_Pa"].map(by_pressure).astype(float)
        table[q + "_error"] = table[q] / ref_values - 1.0
    table["reference"] = reference
    if "note" not in table:
        table["note"] = ""
    table["note"] = table["note"].fillna("")
    return table


# ---------------------------------------------------------------------------
# Figure

#: Centre-row entries drawn in panels (a) and (b), in order of their offsets.
PLOTTED_ENTRIES = ("self_compliance", "neighbour_1_0", "neighbour_1_1", "neighbour_2_0",
                   "far_entry")
#: Line style of each kind of row that is not a finite-element mesh.
KIND_LINESTYLES = MappingProxyType({HALFSPACE: "--", "richardson": ":"})
#: Contact panels (c)-(e): quantity, scale to the axis unit, axis label, title.
CONTACT_PANELS = (("k_P_Pa", 1e-6, "$k_P$ [MPa]", "(c) normalized stiffness $k_P$ (Eq 33)"),
                  ("real_area_fraction", 100.0, "real contact area $A_r / A_n$ [%]",
                   "(d) real contact area"),
                  ("max_pressure_Pa", 1e-6, r"peak pressure $p_\max$ [MPa]",
                   "(e) peak contact pressure"))


def _entry_ticks(first: pd.DataFrame) -> list[str]:
    """Offsets (x, y) of :data:`PLOTTED_ENTRIES` from the centre element, as tick labels."""
    return ["(0,0)", "(1,0)", "(1,1)", "(2,0)", f"({int(first['far_offset'].max())},0)"]


def _plot_entries(ax, first: pd.DataFrame, styles: Mapping) -> None:
    """(a) the centre row's entries E C / h of each mesh."""
    for mesh, style in styles.items():
        ax.plot(range(len(PLOTTED_ENTRIES)), first.loc[mesh, list(PLOTTED_ENTRIES)].to_numpy(float),
                **style)
    ax.set_xticks(range(len(PLOTTED_ENTRIES)), _entry_ticks(first))
    ax.set_yscale("log")
    ax.set_xlabel("offset from the centre element $(x, y)$")
    ax.set_ylabel(r"$E\,C / h$ [-]")
    ax.set_title("(a) influence coefficients, centre row")
    ax.legend(fontsize=8)


def _plot_entry_errors(ax, first: pd.DataFrame, meshes: list[str], reference) -> None:
    """(b) |relative error| of each entry against the reference mesh (dotted: 5 %)."""
    compared = [m for m in meshes if m != reference and first.loc[m, "kind"] != "richardson"]
    width = 0.8 / len(PLOTTED_ENTRIES)
    for k, (q, tick) in enumerate(zip(PLOTTED_ENTRIES, _entry_ticks(first), strict=True)):
        errors = first.loc[compared, q + "_error"].abs().to_numpy(float)
        ax.bar(np.arange(len(compared)) + (k - (len(PLOTTED_ENTRIES) - 1) / 2) * width,
               np.where(errors > 0, errors, np.nan), width, label=tick)
    ax.set_xticks(range(len(compared)),
                  [f"{m}\n{int(first.loc[m, 'dofs'])} dofs" if first.loc[m, "dofs"] else m
                   for m in compared], fontsize=8)
    ax.set_yscale("log")
    ax.axhline(0.05, color="grey", linewidth=0.8, linestyle=":")
    ax.set_ylabel(f"|relative error| vs {reference}")
    ax.set_title(r"(b) error of $E\,C / h$ per offset $(x, y)$")
    ax.legend(fontsize=8, ncol=2)


def _plot_contact(axes, table: pd.DataFrame, styles: Mapping) -> None:
    """(c)-(e) the contact quantities of :data:`CONTACT_PANELS` against nominal pressure."""
    for ax, (q, scale, ylabel, title) in zip(axes, CONTACT_PANELS, strict=True):
        for mesh, style in styles.items():
            rows = table[table["mesh"] == mesh]
            ax.plot(rows["pressure_Pa"] * 1e-6, rows[q] * scale, **style)
        ax.set_xlabel("nominal pressure $P$ [MPa]")
        ax.set_ylabel(ylabel)
        ax.set_title(title)
        ax.grid(alpha=0.3)
    axes[-1].set_yscale("log")


def _plot_cost(ax, first: pd.DataFrame, meshes: list[str]) -> None:
    """(f) build time and peak memory of each mesh."""
    x = np.arange(len(meshes))
    ax.bar(x - 0.2, first["build_s"].to_numpy(float), 0.4, color="C0", label="build time [s]")
    ax.set_xticks(x, meshes, rotation=20, fontsize=8)
    ax.set_ylabel("build time [s]")
    twin = ax.twinx()
    twin.bar(x + 0.2, first["peak_memory_GB"].to_numpy(float), 0.4, color="C1",
             label="peak memory [GB]")
    twin.set_ylabel("peak memory [GB]")
    ax.set_ylim(0, 1.3 * np.nanmax(first["build_s"].to_numpy(float)))
    twin.set_ylim(0, 1.3 * np.nanmax(first["peak_memory_GB"].to_numpy(float)))
    ax.set_title(r"(f) cost of building $E\,C$")
    ax.legend(loc="upper left", fontsize=8)
    twin.legend(loc="upper center", fontsize=8)


def plot_influence_convergence(table: pd.DataFrame, path_png: str | os.PathLike) -> Figure:
    """Six-panel summary of an ``influence_convergence`` table, saved as PNG (Agg).

    Panels: (a) centre-row entries E C / h per mesh; (b) |relative error| of
    each entry against the reference mesh (dotted line: 5 %); (c) k_P, (d)
    real area fraction and (e) peak pressure against nominal pressure per
    mesh; (f) build time and peak memory per mesh. The half-space is drawn
    dashed, the reference mesh thick; symbols are typeset (mathtext).
    Returns the figure.
    """
    meshes = list(dict.fromkeys(table["mesh"]))
    reference = table["reference"].iloc[0] if "reference" in table else None
    first = table.drop_duplicates("mesh").set_index("mesh").loc[meshes]
    fig = Figure(figsize=(15, 9), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(2, 3)
    styles = {mesh: {"color": f"C{i}",
                     "linestyle": KIND_LINESTYLES.get(first.loc[mesh, "kind"], "-"),
                     "linewidth": 2.5 if mesh == reference else 1.3, "marker": "o", "label": mesh}
              for i, mesh in enumerate(meshes)}
    _plot_entries(axes[0, 0], first, styles)
    _plot_entry_errors(axes[0, 1], first, meshes, reference)
    _plot_contact([axes[0, 2], axes[1, 0], axes[1, 1]], table, styles)
    _plot_cost(axes[1, 2], first, meshes)
    row = table.iloc[0]
    fig.suptitle(f"Influence-coefficient mesh convergence: {int(row['grid_x'])} x "
                 f"{int(row['grid_y'])} contact elements of "
                 f"{row['element_size_m'] * 1e3:.3g} mm, $L$ = {row['thickness_m'] * 1e3:g} mm, "
                 f"$\\nu$ = {row['nu']:g}; errors against {reference}")
    save_figure(fig, path_png)
    return fig
