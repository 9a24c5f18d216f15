"""Bodies of the workflow's jobs: surfaces, influence, contact.

A *surface job* generates the seeded realisations of one surface cell (or
imports a measured height map) and stores them in units of sigma. An
*influence job* builds E * C of one block geometry (a dense finite-element
matrix or a matrix-free operator). A *contact job* solves every surface of
one surface cell on one influence geometry through an approach sweep, in the
non-dimensional form of :mod:`roughcontact.contact.nondim`, and stores the result;
sigma and E never enter. The aggregation of a study's cells is in
:mod:`roughcontact.study.aggregation`.

A job takes its rule's params: the plain ``params()`` of the records of
:mod:`roughcontact.study.records`, which its first lines turn into those
records (the job's edge); everything after works on the records. The
layouts of the files are described in :mod:`roughcontact.study.storage`.
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import time
from typing import NamedTuple

import numpy as np

from roughcontact.contact import cell as cell_module
from roughcontact.contact import halfspace_criterion
from roughcontact.elasticity import definiteness, influence, operators
from roughcontact.elasticity.halfspace import halfspace_influence
from roughcontact.elasticity.protocol import DenseInfluence
from roughcontact.errors import FactorizationError, MeasurementError
from roughcontact.study import sources
from roughcontact.study.checks import memory_message
from roughcontact.study.config import BuildSettings, ContactSettings, in_unit
from roughcontact.study.provenance import (
    canonical_json,
    peak_rss_bytes,
    provenance,
)
from roughcontact.study.records import (
    SEEDED_PER_SURFACE,
    ContactJob,
    GeneratedCell,
    Generator,
    Geometry,
    InfluenceModel,
    MeasuredCell,
    coarse_geometry,
    surface_cell_from_params,
)
from roughcontact.study.storage import (
    read_influence,
    read_surfaces,
    write_choice,
    write_contact,
    write_influence,
    write_surfaces,
)
from roughcontact.surfaces import johnson, measured
from roughcontact.surfaces.calibration import calibrate_filter, input_moments, moment_transfer
from roughcontact.surfaces.exact import generate_exact
from roughcontact.surfaces.spectra import check_domain, filter_kernel
from roughcontact.surfaces.statistics import correlation_length, height_stats
from roughcontact.surfaces.synthetic import derive_seeds, generate_many
from roughcontact.units import GB, MM, UM

log = logging.getLogger(__name__)

#: Seconds between progress lines of a contact job within one batch.
PROGRESS_SECONDS = 30.0

#: Surfaces solved together in one call (the batch also fixes the rounding of the
#: matrix products, so a re-solve of the same batch is bit-identical).
BATCH_SIZE = 20


# ---------------------------------------------------------------------------
# Surface jobs: generated cells and measured surfaces, one layout


class _Surfaces(NamedTuple):
    """What a surface job made, beyond the layout every surface file shares."""

    heights: np.ndarray  # (m, ny, nx) in units of sigma
    seeds: tuple  # the seeds dataset: (array, attributes)
    corr_length: np.ndarray  # (m, 2) lags of 10 % ACF decay [m]
    spec: dict  # the surfaces' specification, SI
    attrs: dict  # root attributes of this kind of cell
    datasets: dict  # further datasets (``stats/...``)
    heights_attrs: dict  # further attributes of the heights


def build_surface_cell(params: dict, study_seed: int, path, config=None, *,
                       source: dict | None = None, source_path=None) -> dict:
    """Make a surface cell's surfaces and write them, with statistics, to ``path``.

    ``params``: the cell's :meth:`~roughcontact.study.records.GeneratedCell.params`
    (or a measured cell's). With ``source``, the params of a larger cell of the
    same statistics whose file is ``source_path``
    (:func:`~roughcontact.study.cells.surfaces_from`), its first surfaces are
    taken from that file (:func:`take_surfaces`) instead of generated.

    Heights are stored in units of sigma (dimensionless, zero mean per
    surface) with the realised moments (Eq 2-5) and 10 % ACF lags [m] per
    surface, the cell's ``params`` and ``spec`` and provenance as attributes.
    A generated cell (:func:`_generated_surfaces`) adds the seeds, the
    filter's transfer factors and the fitted Johnson curve of the white
    noise, and with a spectrum ``spectrum`` (its parameters, JSON),
    ``spectrum_kind`` and, for a table or measured PSD, ``spectrum_file`` and
    ``spectrum_file_sha256``; a measured cell (:func:`_measured_surfaces`) is
    one surface (seed -1) with its import and measured statistics. Returns
    the root attributes.
    """
    cell = surface_cell_from_params(params)
    if source is not None:
        return take_surfaces(cell, surface_cell_from_params(source), study_seed, source_path,
                             path, config)
    start = time.perf_counter()
    made = _SURFACE_JOBS[type(cell)](cell, study_seed)
    stats = height_stats(made.heights)
    unit = {"units": "1 (heights / sigma)"}
    datasets = {
        "heights": (made.heights, unit | {"layout": "(surface, y, x), row-major over y then x"}
                    | made.heights_attrs),
        "seeds": made.seeds,
        "stats/mean": (stats["mean"], unit),
        "stats/sigma": (stats["sigma"], unit),
        "stats/skew": (stats["skew"], {"units": "1"}),
        "stats/kurt": (stats["kurt"], {"units": "1 (Pearson, normal = 3)"}),
        "stats/corr_length_x": (made.corr_length[:, 0], {"units": "m"}),
        "stats/corr_length_y": (made.corr_length[:, 1], {"units": "m"}),
        **made.datasets,
    }
    attrs = {
        "cell": cell.key, "study_seed": int(study_seed), "method": cell.method.value,
        **made.attrs,
        "spec": canonical_json(made.spec),
        "params": canonical_json(cell.params()),
        **{f"spec_{k}": v for k, v in made.spec.items()},
        **provenance(config),
    }
    write_surfaces(path, datasets, attrs)
    log.info(
        "cell %s: %d surfaces in %.2f s; mean realised Sk %.3f (target %g), Ku %.3f (target %g)",
        cell.key, len(made.heights), time.perf_counter() - start,
        np.mean(stats["skew"]), cell.skew, np.mean(stats["kurt"]), cell.kurt,
    )
    return attrs


#: Root attributes of a surface file that are its own: never taken from the file of the
#: larger cell a smaller one takes its surfaces from (provenance is its own too).
OWN_ATTRIBUTES = ("cell", "params", "content_sha256", "format_version")


def check_surface_source(cell, source) -> None:
    """Raise ValueError unless ``cell`` may take its surfaces from the cell ``source``.

    Both must be generated by the same generator, one that makes each surface
    from its seed alone (:data:`~roughcontact.study.records.SEEDED_PER_SURFACE`),
    with the same statistics key (the seeds derive from it), and ``source``
    must have at least ``cell.count`` surfaces. The study seed is the file's
    to check (:func:`~roughcontact.study.storage.read_surfaces`).
    """
    refused = f"surface cell {cell.key} cannot take its surfaces from cell {source.key}"
    if cell.method not in SEEDED_PER_SURFACE:
        raise ValueError(f"{refused}: its method {cell.method.value} does not make each "
                         "surface from its seed alone")
    if source.method is not cell.method:
        raise ValueError(f"{refused}: that cell is made by method {source.method.value}, "
                         f"not {cell.method.value}")
    if source.statistics_key != cell.statistics_key:
        raise ValueError(f"{refused}: its statistics differ ({source.statistics_key}, not "
                         f"{cell.statistics_key}), and so do its seeds")
    if source.count < cell.count:
        raise ValueError(f"{refused}: it has {source.count} surfaces, fewer than the "
                         f"{cell.count} asked for")


def take_surfaces(cell: GeneratedCell, source: GeneratedCell, study_seed: int, source_path,
                  path, config=None) -> dict:
    """Write the first ``cell.count`` surfaces of the larger cell ``source`` as ``cell``.

    A generator of :data:`~roughcontact.study.records.SEEDED_PER_SURFACE`
    makes surface i from seed i of the statistics key alone, so they are the
    surfaces ``cell``'s own job would generate, bit for bit. The file
    ``source_path`` must have been made for ``source`` and ``study_seed``
    (:func:`~roughcontact.study.storage.read_surfaces`: parameters, shape and
    content hash) and ``source`` must fit (:func:`check_surface_source`). Every
    dataset (heights, seeds, per-surface statistics) is its first
    ``cell.count`` rows with its attributes; the root attributes are the
    source's (the generator's: calibration, filter, Johnson curve, spec,
    spectrum) but the cell's own :data:`OWN_ATTRIBUTES` and provenance, plus
    ``surfaces_from`` and ``surfaces_from_sha256`` naming the file taken from.
    Returns the root attributes.
    """
    check_surface_source(cell, source)
    start = time.perf_counter()
    stored = read_surfaces(source_path, cell.count, cell=source.params(), study_seed=study_seed)
    arrays = {"heights": stored["heights"], "seeds": stored["seeds"],
              **{f"stats/{name}": values for name, values in stored["stats"].items()}}
    if set(arrays) != set(stored["dataset_attrs"]):
        raise ValueError(f"{source_path}: datasets {sorted(stored['dataset_attrs'])}, not "
                         "only the per-surface ones of a generated cell")
    datasets = {name: (values, stored["dataset_attrs"][name])
                for name, values in arrays.items()}
    made = provenance(config)
    attrs = {
        **{k: v for k, v in stored["attrs"].items() if k not in OWN_ATTRIBUTES + tuple(made)},
        "cell": cell.key,
        "params": canonical_json(cell.params()),
        "surfaces_from": str(source_path),
        "surfaces_from_sha256": stored["content_sha256"],
        **made,
    }
    write_surfaces(path, datasets, attrs)
    log.info("cell %s: the first %d of the %d surfaces of %s taken from %s (content sha256 "
             "%s) in %.2f s; mean realised Sk %.3f (target %g), Ku %.3f (target %g)",
             cell.key, cell.count, source.count, source.key, source_path,
             stored["content_sha256"][:12], time.perf_counter() - start,
             np.mean(stored["stats"]["skew"]), cell.skew, np.mean(stored["stats"]["kurt"]),
             cell.kurt)
    return attrs


def _generated_surfaces(cell: GeneratedCell, study_seed: int) -> _Surfaces:
    """The seeded realisations of a generated cell, by its generator (:data:`_GENERATORS`)."""
    spec = cell.spec()
    seeds = derive_seeds(study_seed, cell.statistics_key, cell.count)
    heights, attrs, datasets = _GENERATORS[cell.method](cell, spec, seeds)
    lags = np.array([correlation_length(z, spec.spacing, spec.periodic) for z in heights])
    spectrum = cell.spectrum
    if spectrum is not None:
        attrs = {"spectrum": canonical_json(spectrum.params()), "spectrum_kind": spectrum.kind,
                 **attrs}
        if spectrum.file is not None:
            attrs |= {"spectrum_file": spectrum.file,
                      "spectrum_file_sha256": spectrum.file_sha256}
    return _Surfaces(heights, (seeds.astype(np.int64),
                               {"generator": "numpy.random.default_rng(seed)"}),
                     lags, spec.as_dict(), attrs, datasets, {})


def _filtered_surfaces(cell: GeneratedCell, spec, seeds, *, calibrated: bool) -> tuple:
    """The paper's filter (Eq 12-13); ``calibrated`` (``filter``): the white noise's
    moments aim at the process whose windows have the target expected sample moments."""
    key = cell.key
    kern = filter_kernel(spec)
    s3, s4 = moment_transfer(spec)
    attrs, process = {}, spec
    if calibrated:
        cal = calibrate_filter(spec)
        attrs = cal.as_attrs()
        process = dataclasses.replace(spec, skew=cal.skew, kurt=cal.kurt)
        log.info(
            "cell %s: calibrated process moments (%.4f, %.4f) for expected sample "
            "moments (%g, %g) (the paper's method would give %.4f, %.4f); %d surfaces, "
            "%.2f s", key, cal.skew, cal.kurt, cell.skew, cell.kurt,
            cal.paper_skew, cal.paper_kurt, cal.samples, cal.seconds)
    skew_x, kurt_x = input_moments(process)
    curve = johnson.fit(skew_x, kurt_x)
    attrs |= {
        "filter_S3": s3,
        "filter_S4": s4,
        "filter_clipped": kern.clipped,
        "input_skew": skew_x,
        "input_kurt": kurt_x,
        "johnson_family": curve.family,
        "johnson_params": [curve.gamma, curve.delta, curve.xi, curve.lam],
    }
    log.info("cell %s: S3 = %.4f, S4 = %.4f, white noise Sk_x = %.4f, Ku_x = %.4f (%s)",
             key, s3, s4, skew_x, kurt_x, curve.family)
    return generate_many(spec, seeds, method=cell.method.value), attrs, {}


def _exact_surfaces(cell: GeneratedCell, spec, seeds) -> tuple:
    """Iterative amplitude adjustment, with each surface's spectral error and convergence
    (the domain checked once for the cell)."""
    check_domain(spec)
    results = [generate_exact(spec, s) for s in seeds]
    datasets = {
        "stats/spectral_error": (
            np.array([r.spectral_error for _, r in results]),
            {"units": "1", "description": "relative L2 error of the Fourier amplitude"},
        ),
        "stats/converged": np.array([r.converged for _, r in results]),
    }
    return np.stack([z for z, _ in results]), {}, datasets


#: How each generator makes a cell's heights: (heights, attributes, datasets).
_GENERATORS = {
    Generator.FILTER: functools.partial(_filtered_surfaces, calibrated=True),
    Generator.PAPER: functools.partial(_filtered_surfaces, calibrated=False),
    Generator.EXACT: _exact_surfaces,
}


def _measured_surfaces(cell: MeasuredCell, study_seed: int) -> _Surfaces:
    """A measured surface as a cell of one surface (seed -1: none).

    Attributes: the source file and its SHA-256 (which must be the one the
    workflow was planned with), the import options, the measured statistics
    in SI (``measured_*``), the filled points, the removed plane, the Johnson
    law of the measured moments (for heights / sigma).
    """
    start = time.perf_counter()
    file = cell.source.file
    measurement = sources.load_measurement(cell.source)
    if measurement.sha256 != cell.file_sha256:
        raise MeasurementError(
            f"{file}: the file changed after the workflow was planned (sha256 "
            f"{measurement.sha256[:12]}, planned {cell.file_sha256[:12]}); run again", file)
    stats = measured.statistics(measurement, spectral=True)
    sigma = stats["sigma"]
    datasets = {
        "stats/filled_points": (np.array([stats["filled_points"]]),
                                {"units": "1", "description": "missing points filled by "
                                                             "Laplace interpolation"}),
        "stats/psd_q": (np.array(stats["psd_q"]),
                        {"units": "1/m", "description": "wavevectors of the isotropic PSD "
                                                        "(SurfaceTopography, from the area)"}),
        "stats/psd_C": (np.array(stats["psd_C"]),
                        {"units": "m^4", "description": "isotropic power spectral density"}),
    }
    spec = {"grid": stats["grid"], "size": stats["size"],
            "corr_length": [stats["corr_length_x"], stats["corr_length_y"]],
            "sigma": sigma, "skew": stats["skew"], "kurt": stats["kurt"],
            "acf": "measured", "periodic": False}
    attrs = {
        "source_file": file, "source_sha256": measurement.sha256,
        "import_options": canonical_json(cell.source.params()),
        **{f"import_{k}": v for k, v in cell.source.options().items() if v is not None},
        "preparation": canonical_json(measurement.preparation),
        "measured_sigma_m": sigma,
        "measured_skew": stats["skew"],
        "measured_kurt": stats["kurt"],
        "measured_corr_length_x_m": stats["corr_length_x"],
        "measured_corr_length_y_m": stats["corr_length_y"],
        "measured_spacing_m": stats["spacing"],
        "measured_rms_slope": stats["rms_slope"],
        "measured_rms_curvature_per_m": stats["rms_curvature"],
        "filled_points": stats["filled_points"],
        "filled_fraction": stats["filled_fraction"],
        "plane_offset_m": stats["plane_offset"],
        "plane_slope_x": stats["plane_slope_x"],
        "plane_slope_y": stats["plane_slope_y"],
        "johnson_family": stats["johnson_family"],
        "johnson_params": stats["johnson_params"],
        "johnson_of": "measured heights / sigma: [gamma, delta, xi, lambda]",
    }
    log.info(
        "measured cell %s from %s: %d x %d, sigma %.4g um, Sk %.4f, Ku %.4f, b %.4g x %.4g mm, "
        "rms slope %.4g, rms curvature %.4g 1/mm, %d points filled (%.3g %%), Johnson %s; "
        "%.2f s", cell.key, file, *stats["grid"], sigma / UM, stats["skew"],
        stats["kurt"], stats["corr_length_x"] / MM, stats["corr_length_y"] / MM,
        stats["rms_slope"], stats["rms_curvature"] * MM, stats["filled_points"],
        100 * stats["filled_fraction"], stats["johnson_family"], time.perf_counter() - start,
    )
    lags = np.array([[stats["corr_length_x"], stats["corr_length_y"]]])
    return _Surfaces((measurement.heights / sigma)[None],
                     (np.array([-1], dtype=np.int64), {"generator": "none: a measured surface"}),
                     lags, spec, attrs, datasets, {"source": file})


#: The surface job of each kind of surface cell.
_SURFACE_JOBS = {GeneratedCell: _generated_surfaces, MeasuredCell: _measured_surfaces}


# ---------------------------------------------------------------------------
# Influence jobs: the elastic body of a geometry


#: What to change when a built influence model is not positive definite.
BUILD_ADVICE = ("A finite-element mesh that does not resolve the block gives such a matrix: "
                "set body.mesh to refined or converged (they refine in plan until no element "
                "is wider than the block is thick), or body.operator to halfspace for a thick "
                "block (Love's half-space is positive definite).")
#: What to do when a stored influence model is not positive definite.
LOAD_ADVICE = ("Delete the file: the workflow rebuilds it, and the build refuses a model "
               "that is not positive definite, naming the config keys to change.")


def _certify_built(unit, key: str) -> definiteness.Certificate:
    """Certify the model of geometry ``key`` positive definite before it is written."""
    return definiteness.certify(unit, unit="m", advice=BUILD_ADVICE,
                                name=f"the influence model E * C of geometry {key}")


def certified_influence(unit, path, geometry: Geometry):
    """The influence model read from ``path``, certified positive definite once.

    A dense E * C [m] comes back as a
    :class:`~roughcontact.elasticity.protocol.DenseInfluence` of the
    geometry's grid, which keeps its certificate through the sweep's
    batches (:mod:`roughcontact.elasticity.definiteness`); a matrix-free
    operator keeps it itself.

    Raises
    ------
    roughcontact.errors.IndefiniteOperator
        Naming the file, with estimates of its extreme eigenvalues [m].
    """
    if isinstance(unit, np.ndarray):
        block = geometry.block()
        grid = block.grid if block.grid[0] * block.grid[1] == unit.shape[0] else None
        unit = DenseInfluence(unit, block.element_area, grid)
    definiteness.certify(unit, name=f"the influence file {path}", unit="m", advice=LOAD_ADVICE)
    return unit


def _dense_checks(unit: np.ndarray, geom, key: str) -> dict:
    nx, ny = geom.grid
    diag = np.diag(unit)
    certificate = _certify_built(unit, key)
    rows = unit.sum(axis=1)
    checks = {
        "asymmetry": float(np.abs(unit - unit.T).max() / np.abs(unit).max()),
        # the certificate's estimates: for Cholesky the smallest squared pivot (an upper
        # bound of the smallest eigenvalue) and the largest diagonal entry
        "certificate_smallest_m": certificate.smallest,
        "certificate_largest_m": certificate.largest,
        "row_sum_min_m": float(rows.min()),
        "row_sum_max_m": float(rows.max()),
        "centre_diagonal_m": float(diag[(ny // 2) * nx + nx // 2]),
    }
    checks["positive_definite"] = certificate.method
    return checks


def _operator_checks(op, geom, key: str) -> dict:
    nx, ny = geom.grid
    rows = op.matvec(np.ones(nx * ny))
    diag = op.diagonal()
    certificate = _certify_built(op, key)
    return {
        "row_sum_min_m": float(rows.min()),
        "row_sum_max_m": float(rows.max()),
        "centre_diagonal_m": float(diag[(ny // 2) * nx + nx // 2]),
        "min_diagonal_m": float(diag.min()),
        "positive_definite": certificate.method,
    }


def _dense_model(fe, geom, model, key: str) -> tuple:
    return fe, _dense_checks(fe, geom, key), {}


def _hybrid_model(fe, geom, model, key: str) -> tuple:
    unit = operators.hybrid_operator(geom, fe, model)
    return unit, _operator_checks(unit, geom, key), {"coarse_mesh": model.mesh}


def _halfspace_model(fe, geom, model, key: str) -> tuple:
    unit = operators.halfspace_operator(geom.grid, geom.size, geom.nu)
    extra = {} if fe is None else {"coarse_mesh": model.mesh}
    return unit, _operator_checks(unit, geom, key), extra


#: How each influence model is made from the finite-element model's E * C:
#: (model, checks, attributes).
_INFLUENCE_MODELS = {InfluenceModel.DENSE: _dense_model, InfluenceModel.HYBRID: _hybrid_model,
                     InfluenceModel.HALFSPACE: _halfspace_model}


def _halfspace_choice(fe, model, geometry: Geometry, key: str) -> tuple[dict, bool]:
    """``operator: auto``: the half-space errors measured on the coarse model's matrix
    ``fe``, and whether they are within the geometry's tolerance."""
    tolerance = dict(geometry.halfspace_tolerance)
    errors = halfspace_criterion.halfspace_errors(fe, model.grid, model.size, geometry.nu,
                                                  geometry.thickness)
    meets = halfspace_criterion.halfspace_meets(errors, tolerance)
    log.info("geometry %s: half-space errors measured on the %s grid %s: %s; tolerance %s: "
             "%s", key, model.mesh, model.grid, errors, tolerance,
             "use the half-space" if meets else "keep the finite body")
    return {"halfspace_errors": errors, "halfspace_tolerance": tolerance}, meets


def _finite_element_matrix(geometry: Geometry, build: BuildSettings, model) -> tuple:
    """``(E C, cost)`` of the finite-element ``model`` a geometry's build solves (the
    half-space needs none: ``(None, zero cost)``), after its memory check."""
    if geometry.operator is InfluenceModel.HALFSPACE:  # Love alone
        return None, geometry.influence_cost(build)
    try:
        cost = influence.check_memory(model, build.max_bytes, build.solver)
    except influence.ModelTooLarge as err:  # name the config keys, not the Python argument
        peak = influence.estimate_cost(model, build.solver).peak_bytes
        raise influence.ModelTooLarge(memory_message(geometry, build, peak)) from err
    log.info(
        "geometry %s: operator %s; finite-element model %s grid %s, %d dofs, estimated peak "
        "%.2f GB (limit %.1f GB)", geometry.key, geometry.operator.value, model.mesh,
        model.grid, cost.dofs, cost.peak_bytes / GB, in_unit(build.max_bytes, GB),
    )
    try:
        fe = influence.unit_modulus_influence(model, solver=build.solver,
                                              max_bytes=build.max_bytes)
    except FactorizationError as err:  # name the geometry and its mesh
        raise FactorizationError(f"geometry {geometry.key} (body.mesh {model.mesh}, grid "
                                 f"{model.grid[0]} x {model.grid[1]}): {err}", err.solver,
                                 err.code) from err
    if not np.isfinite(fe).all():
        raise FloatingPointError(f"geometry {geometry.key}: the influence matrix has "
                                 "non-finite entries")
    return fe, cost


def build_influence(params: dict, path, *, solver: str, max_memory_gb: float,
                    config=None) -> dict:
    """Build E * C of one geometry and write it, with checks and provenance, to ``path``.

    ``params``: the geometry's :meth:`~roughcontact.study.records.Geometry.params`;
    ``solver`` and ``max_memory_gb`` the ``body`` section's
    (:class:`~roughcontact.study.config.BuildSettings`). The influence model is
    the geometry's ``operator``: dense (the
    finite-element matrix, the paper's), hybrid (matrix-free: Love's
    half-space plus a coarse finite-element correction,
    :mod:`roughcontact.elasticity.operators`), half-space (Love only) or auto (dense
    up to 64 x 64 elements, hybrid above; then the half-space instead when
    :func:`roughcontact.contact.halfspace_criterion.halfspace_errors`, measured on the coarse
    model, is within the geometry's ``halfspace_tolerance`` for every
    quantity it names).

    The peak memory is estimated first; a geometry that would not fit raises
    :class:`~roughcontact.influence.ModelTooLarge` with the estimate and the
    options before anything is built (the half-space builds no finite-element
    model). Returns the root attributes.
    """
    geometry = Geometry.from_params(params)
    build = BuildSettings.from_section({"solver": solver, "max_memory_gb": max_memory_gb})
    key, block = geometry.key, geometry.block()
    operator = geometry.planned_model(build.max_bytes)
    model = geometry.finite_element_model(build.max_bytes)
    start = time.perf_counter()
    fe, cost = _finite_element_matrix(geometry, build, model)
    criterion = {}
    if geometry.operator is InfluenceModel.AUTO:
        criterion, meets = _halfspace_choice(fe, model, geometry, key)
        if meets:
            operator = InfluenceModel.HALFSPACE
    unit, checks, model_attrs = _INFLUENCE_MODELS[operator](fe, block, model, key)
    del fe
    seconds = time.perf_counter() - start
    log.info("geometry %s: %s built in %.1f s; checks %s", key, operator.value, seconds, checks)
    params = geometry.params()
    attrs = {
        "geometry": key,
        "params": canonical_json(params),
        **{f"geometry_{k}": v for k, v in params.items()},
        "operator": operator.value,
        "operator_requested": geometry.operator.value,
        **model_attrs,
        **criterion,
        "mesh_spec": canonical_json(dataclasses.asdict(model.mesh_spec)),
        "dofs": int(cost.dofs),
        "estimated_peak_gb": cost.peak_bytes / GB,
        "build_seconds": seconds,
        "peak_rss_gb": peak_rss_bytes() / GB,
        "solver": build.solver,
        **{f"check_{k}": v for k, v in checks.items()},
        **provenance(config),
    }
    return write_influence(path, unit, attrs)


def _criterion_matrix(unit, planned: Geometry) -> tuple:
    """The finite-element matrix [m] the half-space criterion is measured on, and its
    model: a dense model's matrix, or a hybrid operator's coarse model (its correction
    times the coarse element area plus Love's coarse matrix, as the build made it)."""
    if not isinstance(unit, operators.BlockOperator):
        return unit, planned.block()
    coarse = coarse_geometry(planned.block())
    fe = unit.correction * (coarse.spacing[0] * coarse.spacing[1])
    return fe + halfspace_influence(coarse.grid, coarse.size, 1.0, coarse.nu), coarse


def choose_influence(params: dict, planned: dict, planned_path, out_path,
                     config=None) -> dict:
    """Resolve an ``operator: auto`` geometry: the half-space, or its planned model.

    ``params``: the auto geometry's :meth:`~roughcontact.study.records.Geometry.params`;
    ``planned``: its planned candidate's (dense or hybrid,
    :meth:`~roughcontact.study.records.Geometry.candidates`), whose influence file
    ``planned_path`` must have been made for it. The half-space errors
    (:func:`roughcontact.contact.halfspace_criterion.halfspace_errors`) are
    measured on the planned model's finite-element matrix (:func:`_criterion_matrix`);
    within the geometry's ``halfspace_tolerance`` the half-space is chosen,
    else the planned model. The choice (the geometry, the chosen ``operator``,
    the ``resolved`` geometry and its key, the errors and tolerance, the
    planned file's content hash, provenance) is written to ``out_path``
    (:func:`~roughcontact.study.storage.write_choice`) and returned. A
    geometry whose choice is its planned model shares that model's file and
    results with a study configured with it.
    """
    geometry, model = Geometry.from_params(params), Geometry.from_params(planned)
    unit, attrs = read_influence(planned_path, geometry=planned)
    fe, fe_model = _criterion_matrix(unit, model)
    criterion, meets = _halfspace_choice(fe, fe_model, geometry, geometry.key)
    resolved = geometry.resolved(InfluenceModel.HALFSPACE if meets else model.operator)
    choice = {"geometry": geometry.params(), "geometry_key": geometry.key,
              "operator": resolved.operator.value, "resolved": resolved.params(),
              "resolved_key": resolved.key, **criterion, "measured_on": str(planned_path),
              "measured_on_sha256": attrs["content_sha256"], **provenance(config)}
    write_choice(out_path, choice)
    return choice


# ---------------------------------------------------------------------------
# Contact jobs


def _progress_log():
    """A progress callback of a sweep: a line per batch, and a heartbeat every
    :data:`PROGRESS_SECONDS` within a long batch (large grids)."""
    last = [time.perf_counter()]

    def progress(report):
        now = time.perf_counter()
        if report.step == report.steps_total:
            log.info("  surfaces %d/%d done, %d steps, %.1f s elapsed, %d unconverged",
                     report.surfaces_done, report.surfaces_total, report.steps_total,
                     report.elapsed, report.unconverged)
        elif now - last[0] > PROGRESS_SECONDS:
            log.info("  step %d/%d of the batch ending at surface %d/%d, %.1f s elapsed",
                     report.step, report.steps_total, report.surfaces_done,
                     report.surfaces_total, report.elapsed)
        else:
            return
        last[0] = now

    return progress


def _solver_stats(result, seconds: float) -> dict:
    """The solver statistics a contact file records."""
    return {
        "unconverged_steps": int((~result.converged).sum()),
        "unconverged_stiffness_steps": int((~result.stiffness_converged).sum()),
        "worst_residual": float(result.residual.max()),
        "total_iterations": int(result.iterations.sum()),
        "max_iterations": int(result.iterations.max()),
        "total_matvecs": int(result.matvecs.sum()),
        "max_plastic_area_fraction": float(result.plastic_area_fraction.max()),
        "wall_seconds": seconds,
    }


def solve_contact_job(params: dict, surfaces_path, influence_path, out_path, settings: dict,
                      config=None) -> dict:
    """Solve one contact job and write its non-dimensional sweep to ``out_path``.

    ``params``: the job's :meth:`~roughcontact.study.records.ContactJob.params`,
    whose record ``job`` holds the surface cell, the geometry, the
    non-dimensional pressure P L / (E sigma) the sweep must reach and a capped
    job's cap H L / (E sigma); ``settings`` the solver's
    (:meth:`~roughcontact.study.config.ContactSettings.params`). The surface
    and influence files must have been made for the job's cell (and the
    configuration's ``study_seed``) and geometry, else
    :class:`~roughcontact.errors.StoredFileError` names the file and the
    field that differs. Returns the root attributes written.
    """
    job, settings = ContactJob.from_params(params), ContactSettings.from_section(settings)
    start = time.perf_counter()
    # each input must have been made for this job (not only carry its name)
    surfaces = read_surfaces(surfaces_path, cell=job.surface.params(),
                             study_seed=None if config is None else config["study_seed"])
    unit, geometry_attrs = read_influence(influence_path, geometry=job.geometry.params())
    unit = certified_influence(unit, influence_path, job.geometry)
    heights = surfaces["heights"]
    m = heights.shape[0]
    name = f"{job.surface.key}__{job.geometry.key}"
    nx, ny = job.geometry.grid
    if heights.shape[1:] != (ny, nx):
        raise ValueError(
            f"surfaces {surfaces_path} have shape {heights.shape[1:]} but geometry "
            f"{job.geometry.key} has a {ny} x {nx} (ny x nx) contact grid"
        )
    hardness = job.nondim_hardness
    log.info("contact %s: %d surfaces x %d steps, sweep to P L / (E sigma) = %g; "
             "method %s, tol %.1e, precision %s, influence %s, %s", name, m, settings.steps,
             job.pressure_end, settings.method, settings.tol, settings.precision,
             geometry_attrs["operator"],
             "elastic" if hardness is None else f"pressure capped at H L / (E sigma) = "
             f"{hardness:.6g}")
    result = cell_module.sweep_cell(unit, heights, job.geometry.block(), job.pressure_end,
                                    settings.steps, method=settings.method, tol=settings.tol,
                                    precision=settings.precision, batch_size=min(m, BATCH_SIZE),
                                    progress=_progress_log(), nondim_hardness=hardness)
    log.info("approach d/sigma %.3g .. %.3g", result.approach[0, 0], result.approach[0, -1])
    reached = result.nominal_pressure[:, -1].min()
    if reached < job.pressure_end:
        log.warning("the sweep reached P L / (E sigma) = %.3g on its least loaded surface, "
                    "below the %.3g asked for: higher pressure levels rest on fewer surfaces",
                    reached, job.pressure_end)
    stats = _solver_stats(result, time.perf_counter() - start)
    (log.warning if stats["unconverged_steps"] else log.info)("contact %s: %s", name, stats)
    attrs = {
        "batch_size": min(m, BATCH_SIZE),
        "job": canonical_json(job.params()),
        **stats,
        "surfaces_content_sha256": surfaces["content_sha256"],
        "influence_content_sha256": geometry_attrs["content_sha256"],
        "seeds": surfaces["seeds"].tolist(),
        **provenance(config),
    }
    return write_contact(out_path, result, attrs)


__all__ = [
    "BATCH_SIZE",
    "BUILD_ADVICE",
    "LOAD_ADVICE",
    "build_influence",
    "choose_influence",
    "build_surface_cell",
    "certified_influence",
    "check_surface_source",
    "take_surfaces",
    "solve_contact_job",
]
