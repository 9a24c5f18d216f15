"""Bodies of the workflow's influence jobs.

The surface jobs are in :mod:`roughcontact.study.jobs.surfaces`, the contact jobs
in :mod:`roughcontact.study.jobs.contact`. An *influence job* builds E * C of one
block geometry (a dense finite-element matrix or a matrix-free operator); a
*pair job* sums two bodies' models once, for the contact jobs with a compliant
counter body on a dense first body (Eq 17-18). The aggregation of a study's
cells is in :mod:`roughcontact.study.jobs.aggregation`.
"""

from __future__ import annotations

import dataclasses
import logging
import time

import numpy as np

from roughcontact.contact import counterface, halfspace_criterion
from roughcontact.elasticity import definiteness, influence, operators
from roughcontact.elasticity.halfspace import halfspace_influence
from roughcontact.elasticity.protocol import DenseInfluence
from roughcontact.errors import FactorizationError
from roughcontact.study.codec import in_unit
from roughcontact.study.config import BuildSettings
from roughcontact.study.counter_records import PairGeometry
from roughcontact.study.jobs.storage import (
    read_influence,
    read_pair,
    write_choice,
    write_influence,
    write_pair,
)
from roughcontact.study.memory_advice import memory_message
from roughcontact.study.provenance import (
    RunInfo,
    canonical_json,
    peak_rss_bytes,
    provenance,
)
from roughcontact.study.records import Geometry, InfluenceModel, coarse_geometry
from roughcontact.units import GB

log = logging.getLogger(__name__)

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
    run = RunInfo.of(config)  # the job's edge: the run it belongs to
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
        **provenance(run),
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
    (:func:`~roughcontact.study.jobs.storage.write_choice`) and returned. A
    geometry whose choice is its planned model shares that model's file and
    results with a study configured with it.
    """
    run = RunInfo.of(config)  # the job's edge: the run it belongs to
    geometry, model = Geometry.from_params(params), Geometry.from_params(planned)
    unit, attrs = read_influence(planned_path, geometry=planned)
    fe, fe_model = _criterion_matrix(unit, model)
    criterion, meets = _halfspace_choice(fe, fe_model, geometry, geometry.key)
    resolved = geometry.resolved(InfluenceModel.HALFSPACE if meets else model.operator)
    choice = {"geometry": geometry.params(), "geometry_key": geometry.key,
              "operator": resolved.operator.value, "resolved": resolved.params(),
              "resolved_key": resolved.key, **criterion, "measured_on": str(planned_path),
              "measured_on_sha256": attrs["content_sha256"], **provenance(run)}
    write_choice(out_path, choice)
    return choice


# ---------------------------------------------------------------------------
# Pair jobs: two bodies' influence models summed once (Eq 17-18)


def build_pair(params: dict, first_path, second_path, out_path, config=None) -> dict:
    """Sum two bodies' influence models once and write the pair (its file is shared by
    every contact job on the pair: ``results/influence/pairs/<key>.h5``).

    ``params``: the pair's :meth:`~roughcontact.study.counter_records.PairGeometry.params`;
    each influence file must have been made for its body's geometry. The sum is
    certified positive definite before it is written
    (:func:`~roughcontact.contact.counterface.pair_model`; a counter body treated as
    rigid writes no matrix). Returns the root attributes.
    """
    run = RunInfo.of(config)  # the job's edge: the run it belongs to
    pair = PairGeometry.from_params(params)
    start = time.perf_counter()
    bodies, hashes = [], {}
    for name, path, geometry in (("first", first_path, pair.first),
                                 ("second", second_path, pair.second)):
        unit, attrs = read_influence(path, geometry=geometry.params())
        bodies.append(certified_influence(unit, path, geometry))
        hashes[f"{name}_content_sha256"] = attrs["content_sha256"]
    model = counterface.pair_model(*bodies, pair.modulus_ratio, pair.rigid_share)
    matrix = None
    if model.unit is not None:
        definiteness.certify(model.unit, unit="m", advice=LOAD_ADVICE,
                             name=f"the pair of influence models {pair.key}")
        matrix = model.unit.matrix
    seconds = time.perf_counter() - start
    log.info("pair %s: %s in %.1f s", pair.key, "treated as rigid" if matrix is None
             else "summed", seconds)
    attrs = {"pair": pair.key, "params": canonical_json(pair.params()), **hashes,
             **model.attrs, "bulk_ratio": model.bulk_ratio, "build_seconds": seconds,
             **provenance(run)}
    return write_pair(out_path, matrix, model.weights, attrs)


def read_pair_model(path, pair: PairGeometry) -> tuple[counterface.PairModel, dict]:
    """The :class:`~roughcontact.contact.counterface.PairModel` of a pair file made for
    ``pair`` (checked, its sum certified again), and the content hashes a contact job
    records."""
    matrix, weights, attrs = read_pair(path, pair=pair.params())
    unit = None if matrix is None else certified_influence(matrix, path, pair.first)
    model = counterface.PairModel(unit, weights, float(attrs["bulk_ratio"]),
                      {"counter_compliance_share": float(attrs["counter_compliance_share"]),
                       "counter_treated_as_rigid": bool(attrs["counter_treated_as_rigid"])})
    return model, {"pair_content_sha256": attrs["content_sha256"],
                   "counter_influence_content_sha256": attrs["second_content_sha256"]}


__all__ = [
    "BUILD_ADVICE",
    "LOAD_ADVICE",
    "build_influence",
    "build_pair",
    "certified_influence",
    "choose_influence",
    "read_pair_model",
]
