"""Stage 3, contact: a rigid flat pressed onto rough surfaces on an elastic body.

The solver minimizes the complementary energy with p >= 0 (Eq 27 of Kumar
et al. 2006) for one or many surfaces and through approach sweeps, one
module per part: ``problem`` (what is solved, ``Problem``, and how,
``SolverOptions``: the two records every solve takes), ``methods`` (the methods
by name, ``solve``, ``solve_many``), ``cg``, ``steepest``, ``pivot`` and ``pcg`` (one
algorithm each, ``iteration`` the projected iteration the first two share;
``pcg`` the preconditioned CG of the grid FFT operators, ``nested`` its
coarse-grid starts), ``loads`` (load control by an outer solve on the
approach), ``sweeps`` (the
approach loop and its warm starts), ``stiffness`` (the tangent dF/dd),
``kkt`` (the residual every method stops on), ``result`` (the results all
methods return), ``checks`` (input checks) and ``products`` (the products
C p, double or mixed precision). ``validity`` reads from a solution how much
of it lies above a hardness; ``nondim`` solves a cell once in dimensionless
form and rescales it to any sigma and E (Eq 28-32); ``aggregate`` averages
a cell's surfaces at equal nominal pressure; ``cell`` is the one
sweep-then-aggregate recipe the workflow, the reports and the audit share;
``halfspace_criterion`` measures, by solving, whether the half-space model
is enough for a geometry; ``interface`` reads off a solution its contact
spots, perimeter, perimeter-corrected real area and gaps; ``probes`` says what
a probe is (what a sweep measures beyond pressure and load, e.g. the flow of
:mod:`roughcontact.transport`: columns the sweep stores without naming them);
``counterface`` makes the equivalent problem of two rough, elastic bodies (Eq
17-18); ``cycles`` sweeps a loading path that may rise and fall, keeping the pressure
cap's permanent set (loading, unloading, reloading).

The solver's public names are importable from here: ``from roughcontact
import contact; contact.solve(...)``, with the options as one record:
``contact.sweep(C, gaps, approaches, element_area=dA,
options=contact.SolverOptions(method="pivot", tol=1e-10))``.
"""

from roughcontact.contact.cycles import (
    CycleResult,
    LoadingPath,
    cycle_summary,
    cycle_sweep,
    cycle_to_physical,
    loop_work,
)
from roughcontact.contact.kkt import kkt_residual
from roughcontact.contact.methods import (
    METHODS,
    PRECISIONS,
    resolve_method,
    solve,
    solve_many,
    solve_problem,
)
from roughcontact.contact.problem import Problem, SolverOptions
from roughcontact.contact.result import ContactResult, SweepResult
from roughcontact.contact.stiffness import tangent_stiffness
from roughcontact.contact.sweeps import sweep, sweep_problem

__all__ = [
    "METHODS",
    "PRECISIONS",
    "ContactResult",
    "CycleResult",
    "LoadingPath",
    "Problem",
    "SolverOptions",
    "SweepResult",
    "cycle_summary",
    "cycle_sweep",
    "cycle_to_physical",
    "kkt_residual",
    "loop_work",
    "resolve_method",
    "solve",
    "solve_many",
    "solve_problem",
    "sweep",
    "sweep_problem",
    "tangent_stiffness",
]
