"""Bodies of the workflow's surface jobs: generated cells and measured surfaces.

A *surface job* generates the seeded realisations of one surface cell (or
imports a measured height map, or takes the first surfaces of a larger cell of
the same statistics) and stores them in units of sigma, one layout for every
kind of cell (:mod:`roughcontact.study.jobs.storage`). The influence and contact
jobs are in :mod:`roughcontact.study.jobs.influence`.

A job takes its rule's params: the plain ``params()`` of the records of
:mod:`roughcontact.study.records`, which its first lines turn into those
records (the job's edge); everything after works on the records.
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import time
from typing import NamedTuple

import numpy as np

from roughcontact.errors import InfeasibleMoments, MeasurementError
from roughcontact.study import sources
from roughcontact.study.jobs.storage import read_surfaces, write_surfaces
from roughcontact.study.provenance import NO_RUN, RunInfo, canonical_json, provenance
from roughcontact.study.records import (
    SEEDED_PER_SURFACE,
    GeneratedCell,
    Generator,
    MeasuredCell,
    surface_cell_from_params,
)
from roughcontact.surfaces import johnson, measured
from roughcontact.surfaces.calibration import calibrate_filter, input_moments, moment_transfer
from roughcontact.surfaces.exact import generate_exact
from roughcontact.surfaces.spectra import check_domain, filter_kernel
from roughcontact.surfaces.statistics import correlation_length, height_stats
from roughcontact.surfaces.synthetic import derive_seeds, generate_many
from roughcontact.units import MM, UM

__all__ = ["OWN_ATTRIBUTES", "build_surface_cell", "check_surface_source", "take_surfaces"]

log = logging.getLogger(__name__)




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
    (:func:`~roughcontact.study.plan.cells.surfaces_from`), its first surfaces are
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
    run = RunInfo.of(config)  # the job's edge: the run it belongs to
    cell = surface_cell_from_params(params)
    if source is not None:
        return take_surfaces(cell, surface_cell_from_params(source), study_seed, source_path,
                             path, run)
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
        **provenance(run),
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
    to check (:func:`~roughcontact.study.jobs.storage.read_surfaces`).
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
                  path, run: RunInfo = NO_RUN) -> dict:
    """Write the first ``cell.count`` surfaces of the larger cell ``source`` as ``cell``.

    A generator of :data:`~roughcontact.study.records.SEEDED_PER_SURFACE`
    makes surface i from seed i of the statistics key alone, so they are the
    surfaces ``cell``'s own job would generate, bit for bit. The file
    ``source_path`` must have been made for ``source`` and ``study_seed``
    (:func:`~roughcontact.study.jobs.storage.read_surfaces`: parameters, shape and
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
    made = provenance(run)
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


def _calibration(key: str, spec):
    """The filter's calibration of cell ``key`` (:func:`calibrate_filter`). The plan leaves
    a target near the reachable region's edge to the job
    (:func:`roughcontact.study.plan.checks.check_feasible`): one it cannot reach ends the
    job with the message the plan gives, the cell's key first."""
    try:
        return calibrate_filter(spec)
    except InfeasibleMoments as err:
        raise InfeasibleMoments(f"{key}: {err}") from None


def _filtered_surfaces(cell: GeneratedCell, spec, seeds, *, calibrated: bool) -> tuple:
    """The paper's filter (Eq 12-13); ``calibrated`` (``filter``): the white noise's
    moments aim at the process whose windows have the target expected sample moments."""
    key = cell.key
    kern = filter_kernel(spec)
    s3, s4 = moment_transfer(spec)
    attrs, process = {}, spec
    if calibrated:
        cal = _calibration(key, spec)
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
