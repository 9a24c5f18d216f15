"""The verification matrix's seeded set (issue 42): ``pytest -m verification``.

The cells of ``test_verification_matrix.py`` on more cases: the core operators and the
issue's 32 x 32 paper-mesh block, eight random dense blocks (mesh, grid, aspect,
thickness and nu drawn from their seeds; condition numbers 1e1-1e7) and periodic and
spectral cells of aspect 64, each on three seeded surfaces, with every method (steepest
descent near full contact included) under both controls, with and without a cap. Over
the whole set: no result returned as converged that is not, no converged one flagged,
every cell converged (or refused with its message) and in agreement with scipy's.
Minutes on 2 cores; ``benchmarks/verification_matrix.py`` tabulates the same cells.
"""

from __future__ import annotations

import pytest
import verification as V

SEEDS = (1, 2, 3)
BODIES = V.seeded_bodies()

pytestmark = pytest.mark.verification


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("name", list(BODIES))
def test_seeded_cells(name, seed):
    body = BODIES[name]()
    failures = []
    for method in V.METHODS:
        for control in V.CONTROLS:
            for case in V.cases(body, seed):
                verdict = V.verify(body, method, control, case)
                expected = V.refusal_expected(body, method, case)
                if expected:
                    ok = verdict.refused is not None and expected in verdict.refused
                else:
                    ok = (verdict.refused is None and verdict.honest and verdict.converged
                          and verdict.agrees)
                if not ok:
                    failures.append(verdict)
    assert not failures, "\n".join(map(str, failures))
