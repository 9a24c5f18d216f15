"""The two records every solve takes: the checked Problem and the SolverOptions.

A problem made once and solved several ways gives what the short keyword forms give
(the same operations: bit for bit); the records refuse bad values when made, naming
the field; the cell's options route each name to its record.
"""

import dataclasses

import numpy as np
import pytest

from roughcontact import contact
from roughcontact.contact import Problem, SolverOptions
from roughcontact.contact.interface import InterfaceGrid
from roughcontact.contact.methods import Solver
from roughcontact.contact.nondim import CELL_SOLVER, CellOptions
from roughcontact.elasticity.halfspace import halfspace_influence

N, SIZE, E, NU = 12, 1e-3, 1e9, 0.3
AREA = (SIZE / N) ** 2


@pytest.fixture(scope="module")
def rough():
    """A 12 x 12 half-space matrix [m/Pa] and three rough surfaces' gaps [m]."""
    matrix = halfspace_influence((N, N), (SIZE, SIZE), E, NU)
    z = np.random.default_rng(3).standard_normal((3, N, N)) * 1e-6
    return matrix, z.max(axis=(1, 2), keepdims=True) - z


def test_a_problem_made_once_sweeps_as_the_short_form(rough):
    matrix, gaps = rough
    approaches = np.geomspace(0.5e-6, 3e-6, 5)
    grid = InterfaceGrid((SIZE / N, SIZE / N))
    options = SolverOptions(method="cg", tol=1e-10, profile=True)
    problem = Problem.of(matrix, gaps, hardness=1.5e7, interface=grid, element_area=AREA)
    once = contact.sweep_problem(problem, approaches, options=options)
    again = contact.sweep_problem(problem, approaches, options=options.with_(method="pivot"))
    short = contact.sweep(matrix, gaps, approaches, hardness=1.5e7, interface=grid,
                          element_area=AREA, options=options)
    for name in ("load", "real_area_fraction", "plastic_area_fraction", "contact_stiffness",
                 "perimeter", "mean_gap", "pressure_profile", "iterations"):
        np.testing.assert_array_equal(getattr(once, name), getattr(short, name), err_msg=name)
    assert once.converged.all() and again.converged.all()
    assert (once.method, again.method) == ("cg", "pivot")
    assert once.plastic_area_fraction[:, -1].min() > 0  # the cap is the problem's
    np.testing.assert_allclose(again.load, once.load, rtol=1e-7)


def test_solve_problem_returns_one_result_per_surface_as_solve_many(rough):
    matrix, gaps = rough
    problem = Problem.of(matrix, gaps, element_area=AREA)
    options = SolverOptions(method="cg", tol=1e-11)
    results = contact.solve_problem(problem, mean_pressure=2e6, options=options)
    many = contact.solve_many(matrix, gaps, mean_pressure=2e6, element_area=AREA,
                              options=options)
    assert len(results) == 3
    for result, other in zip(results, many, strict=True):
        np.testing.assert_array_equal(result.pressure, other.pressure)
        assert result.nominal_pressure == pytest.approx(2e6, rel=1e-8)


def test_a_problem_is_checked_once_when_made(rough):
    matrix, gaps = rough
    problem = Problem.of(matrix, gaps[0], hardness=np.inf, element_area=AREA, batched=False)
    assert problem.gaps.shape == (1, N * N) and problem.shape == (N, N)
    assert problem.hardness is None  # +inf: no cap
    assert problem.operator.element_area == AREA
    with pytest.raises(ValueError, match="gap0"):
        Problem.of(matrix, gaps, element_area=AREA, batched=False)
    with pytest.raises(ValueError, match="gaps0"):
        Problem.of(matrix, gaps[:, :5], element_area=AREA)
    with pytest.raises(ValueError, match="hardness"):
        Problem.of(matrix, gaps, hardness=-1.0, element_area=AREA)
    with pytest.raises(ValueError, match="element_area"):
        Problem.of(matrix, gaps)
    with pytest.raises(ValueError, match="interface quantities need surfaces"):
        Problem.of(matrix, gaps.reshape(3, -1), interface=InterfaceGrid((1e-4, 1e-4)),
                   element_area=AREA)


@pytest.mark.parametrize(("change", "name"), [
    ({"tol": 0.0}, "tol"),
    ({"tol": np.nan}, "tol"),
    ({"load_tol": -1e-8}, "load_tol"),
    ({"max_iter": -1}, "max_iter"),
    ({"max_iter": 2.5}, "max_iter"),
    ({"precision": "half"}, "precision"),
    ({"stiffness_tol": 0.0}, "stiffness_tol"),
])
def test_options_refuse_a_bad_value_when_made(change, name):
    with pytest.raises(ValueError, match=name):
        SolverOptions(**change)
    with pytest.raises(ValueError, match=name):
        SolverOptions().with_(**change)


def test_options_hold_checked_values_and_the_method_is_looked_up_by_name(rough):
    options = SolverOptions(tol=np.float32(1e-6), stiffness=0, retries=1)
    assert type(options.tol) is float and options.stiffness is False and options.retries is True
    matrix, gaps = rough
    problem = Problem.of(matrix, gaps, element_area=AREA)
    assert Solver.of(problem, SolverOptions()).method.name == "pivot"  # "auto", dense
    assert Solver.of(problem, SolverOptions(retries=False)).fallbacks == ()
    with pytest.raises(ValueError, match="method must be one of"):
        Solver.of(problem, SolverOptions(method="newton"))


def test_cell_options_route_each_name_to_its_record():
    options = CellOptions().with_(method="pivot", tol=1e-9, batch_size=2, nondim_hardness=0.5)
    assert options.solver == CELL_SOLVER.with_(method="pivot", tol=1e-9)
    assert (options.batch_size, options.nondim_hardness) == (2, 0.5)
    assert CellOptions().solver == SolverOptions(method="cg", tol=1e-8)
    assert CellOptions().with_() == CellOptions()
    with pytest.raises(TypeError):
        CellOptions().with_(tolerance=1e-9)
    with pytest.raises(ValueError, match="tol"):
        CellOptions().with_(tol=-1.0)
    assert {field.name for field in dataclasses.fields(CellOptions)} == {
        "solver", "batch_size", "progress", "nondim_hardness", "interface"}
