"""What a contact sweep records of the flow through each of its solutions' gaps.

A :class:`FlowProbe` is a probe (:class:`~roughcontact.contact.probes.Probe`) a sweep
is given (through its interface grid,
:class:`~roughcontact.contact.interface.InterfaceGrid`, ``probes``): at every step it
solves the flow (:func:`~roughcontact.transport.flow.solve_flow`) through the gap of
every surface, in each of its ``directions``, and gives the sweep its columns
(:func:`flow_columns`, named ``<quantity>_<d>`` by :func:`column_name`):

:data:`CONDUCTANCE`
    the effective conductance ``K`` along ``d`` [gap unit cubed: m^3 in SI, sigma^3
    in the dimensionless form];
:data:`FACTOR`
    ``K / mean(g)^3`` [-]: against a flat gap of the same mean gap (0 where sealed,
    full contact included);
:data:`PRESSURE_FACTOR`
    ``K / h^3`` [-], Patir & Cheng's (1978) pressure flow factor, with ``h`` the
    nominal separation of the flat and the undeformed mean plane of the rough
    surface, ``mean(f) - d`` (``f`` the initial separations, ``d`` the approach);
    0 where sealed, NaN where the gap leaks and ``h <= 0`` (the flat below the
    undeformed mean plane: the factor is not defined there);
:data:`CONNECTED`
    the free space connects inlet to outlet (bool);
:data:`BALANCE`
    ``|D - Q_out| / D`` [-], the relative disagreement of the flow's two measures
    (:attr:`~roughcontact.transport.flow.FlowResult.balance`: the dissipation the
    conductance is read from and the flow through the outlet), 0 where sealed. A step
    whose balance exceeds ``balance_tol`` after the flow's retry (iterative refinement)
    is flagged like an unconverged contact solve: its conductance and factors are
    recorded as NaN (so the aggregation, which reads finite values only, leaves it
    out, and the cell's table counts it), its balance kept, and a warning on the
    ``roughcontact.transport`` logger names the surfaces.

The gap a flow sees is the solution's gap with the elements in contact
(``p > 0``) closed, and closed too where it is at most ``closed_below`` times the
field's largest gap (default 1e-7, ten times the sweeps' default KKT tolerance:
the solver's gap is zero in contact only to its tolerance, and an element at the
edge of a spot may have ``p = 0`` with a gap of rounding size; left open, a chain
of them would let the free space percolate through gaps that carry ``(1e-7)^3``
of the flow of the widest, and the sealing point would come late).
:data:`NO_FLOW` records nothing: the flow setting of a study without flow (a sweep
without flow is given no probe at all).

These names are the flow's only spelling: the study's leak rate (:data:`LEAK_RATE`,
:mod:`roughcontact.study.flow_settings`), its percolation thresholds and the leakage
figure read the columns through :func:`column_name`.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import ClassVar

import numpy as np

from roughcontact.contact.probes import Column, SolvedFields
from roughcontact.transport.flow import (
    BALANCE_TOL,
    FACE_RULES,
    FLOW_DIRECTIONS,
    HARMONIC,
    PERIODIC,
    SEALED,
    BandedCholesky,
    DirectSolver,
    FaceRule,
    FlowSetup,
    JacobiCG,
    solve_flow,
)

__all__ = ["BALANCE", "CONDUCTANCE", "CONNECTED", "FACTOR", "FLOW_COLUMNS", "FLOW_QUANTITIES",
           "LEAK_RATE", "NO_FLOW", "PRESSURE_FACTOR", "SIDE_CHOICES", "FlowProbe",
           "column_name", "flow_column_names", "flow_columns", "probe_from_params"]

logger = logging.getLogger("roughcontact.transport")

#: Balances this close are the same to rounding (a re-solve's comparison,
#: :attr:`~roughcontact.contact.probes.Column.rounding`): the balance measures rounding
#: itself (1e-16 to 1e-8 on the fields measured), far below the tolerance.
BALANCE_ROUNDING = 1e-3 * BALANCE_TOL

#: The quantities of a direction's columns, in order (module docstring).
CONDUCTANCE, FACTOR, PRESSURE_FACTOR, CONNECTED, BALANCE = (
    "flow_conductance", "flow_factor", "pressure_flow_factor", "flow_connected",
    "flow_balance")
FLOW_QUANTITIES = (CONDUCTANCE, FACTOR, PRESSURE_FACTOR, CONNECTED, BALANCE)
#: The leak rate of a seal, ``Q = K W dp / (12 eta L)`` [m^3/s]
#: (:meth:`~roughcontact.transport.flow.Seal.leak_rate`), named like the columns
#: (``leak_rate_<d>``) in the study's tables.
LEAK_RATE = "leak_rate"
#: The sides a probe may put parallel to the flow: those of the grid (periodic on a
#: periodic grid, sealed on a finite block's), periodic or sealed.
SIDE_CHOICES = MappingProxyType({"grid": None, "periodic": PERIODIC, "sealed": SEALED})


def column_name(quantity: str, direction: str) -> str:
    """The name of ``quantity`` (:data:`FLOW_QUANTITIES` or :data:`LEAK_RATE`) along
    ``direction``: ``<quantity>_<direction>``."""
    return f"{quantity}_{direction}"


def flow_columns(direction: str) -> tuple[Column, ...]:
    """The columns (:class:`~roughcontact.contact.probes.Column`) of the flow along
    ``direction``, in the order of :data:`FLOW_QUANTITIES`."""
    d = direction
    return (
        Column(column_name(CONDUCTANCE, d), "m^3",
               f"K_{d}, effective conductance along {d} (Reynolds equation, local cubic "
               "law): the cube of the flat gap that carries the same flow", length_power=3),
        Column(column_name(FACTOR, d), "1",
               f"phi_{d} = K_{d} / mean(g)^3, against a flat gap of the mean gap (0 where "
               "sealed)"),
        Column(column_name(PRESSURE_FACTOR, d), "1",
               f"phi_{d} = K_{d} / h^3, h = mean(f) - d the nominal separation of the "
               "undeformed mean planes (Patir & Cheng 1978; 0 where sealed)"),
        Column(column_name(CONNECTED, d), "1",
               f"share of surfaces whose free space connects inlet to outlet along {d} "
               "(still leaking; each surface's state at its step nearest in log P)",
               dtype=bool),
        Column(column_name(BALANCE, d), "1",
               f"|D - Q_out| / D along {d}: relative disagreement of the flow's "
               "dissipation (K's measure) and its flow through the outlet (0 where sealed; "
               "above the probe's balance_tol: K flagged, NaN)",
               rounding=BALANCE_ROUNDING),
    )


def _along(directions) -> tuple[Column, ...]:
    """The columns of the flow along ``directions``, in the order x, y."""
    return tuple(column for direction in FLOW_DIRECTIONS if direction in directions
                 for column in flow_columns(direction))


def flow_column_names(directions) -> tuple[str, ...]:
    """The names of the columns of a probe flowing along ``directions``, in the order x, y."""
    return tuple(column.name for column in _along(directions))


#: Every flow column a sweep may hold.
FLOW_COLUMNS = flow_column_names(FLOW_DIRECTIONS)


@dataclass(frozen=True)
class FlowProbe:
    """The flow a sweep records at every step (module docstring).

    Parameters
    ----------
    directions : tuple of {"x", "y"}
        Directions of the flow, each solved on its own (empty: :data:`NO_FLOW`).
    sides : {"grid", "periodic", "sealed"}
        The sides parallel to the flow (:data:`SIDE_CHOICES`).
    face_rule : FaceRule
        :data:`~roughcontact.transport.flow.HARMONIC` (default) or ``ARITHMETIC``.
    solver : BandedCholesky, DirectSolver or JacobiCG
        The linear solver (:mod:`roughcontact.transport.flow`); default the band
        Cholesky factorisation, SuperLU where the band is too wide (periodic sides,
        fields over 256 elements along the flow): 180 of the study's 60 x 60 gaps
        along x in 1.83 s against SuperLU's 2.63 s (``benchmarks/bench_flow_cost.py``).
    closed_below : float
        Gaps at most this share of the field's largest are closed (module docstring).
    balance_tol : float
        The largest balance a step's conductance is recorded with (module docstring,
        :attr:`~roughcontact.transport.flow.FlowSetup.balance_tol`).
    """

    #: The name its settings are stored under (:class:`~roughcontact.contact.probes.Probe`).
    kind: ClassVar[str] = "flow"

    directions: tuple[str, ...] = FLOW_DIRECTIONS
    sides: str = "grid"
    face_rule: FaceRule = HARMONIC
    solver: BandedCholesky | DirectSolver | JacobiCG = field(default=BandedCholesky(),
                                                            repr=False)
    closed_below: float = 1e-7
    balance_tol: float = BALANCE_TOL

    def __post_init__(self):
        directions = tuple(self.directions)
        unknown = [d for d in directions if d not in FLOW_DIRECTIONS]
        if unknown or len(set(directions)) != len(directions):
            raise ValueError(f"directions must be distinct, each one of {FLOW_DIRECTIONS}, "
                             f"got {self.directions!r}")
        object.__setattr__(self, "directions", directions)
        if self.sides not in SIDE_CHOICES:
            raise ValueError(f"sides must be one of {tuple(SIDE_CHOICES)}, got {self.sides!r}")
        if not (0.0 <= float(self.closed_below) < 1.0):
            raise ValueError(f"closed_below must be in [0, 1), got {self.closed_below!r}")
        if not (float(self.balance_tol) > 0.0):
            raise ValueError(f"balance_tol must be positive, got {self.balance_tol!r}")
        if not isinstance(self.face_rule, FaceRule):
            raise ValueError(f"face_rule must be one of the FaceRule values "
                             f"{tuple(FACE_RULES)}, got {self.face_rule!r}")

    @property
    def columns(self) -> tuple[Column, ...]:
        """The columns it records (:func:`flow_columns`), in the order x, y; empty for
        :data:`NO_FLOW`."""
        return _along(self.directions)

    @property
    def names(self) -> tuple[str, ...]:
        """The names of its :attr:`columns` (:func:`flow_column_names`)."""
        return flow_column_names(self.directions)

    def params(self) -> dict:
        """Its settings as plain values (a stored file's record of what was solved)."""
        return {"directions": list(self.directions), "sides": self.sides,
                "face_rule": self.face_rule.name, "closed_below": self.closed_below,
                "balance_tol": self.balance_tol}

    def measure(self, fields: SolvedFields) -> dict:
        """The flow columns (module docstring) of the solutions of ``fields`` (pressure and
        gap (..., ny, nx), nominal separations (...) [gap unit], on elements of sides
        ``spacing`` ``(dx, dy)`` [m] of a grid that is ``periodic`` or not): name ->
        array of the leading shape."""
        if not self.directions:
            return {}
        gap = np.maximum(fields.gap, 0.0)
        floor = self.closed_below * gap.max(axis=(-2, -1), keepdims=True)
        open_gap = np.where((np.asarray(fields.pressure) > 0.0) | (gap <= floor), 0.0, gap)
        sides = SIDE_CHOICES[self.sides] or (PERIODIC if fields.periodic else SEALED)
        h = np.asarray(fields.separation, dtype=float)
        positive = h > 0.0
        out = {}
        for direction in self.directions:
            result = solve_flow(open_gap, FlowSetup(fields.spacing, direction, sides,
                                                    self.face_rule, self.solver,
                                                    self.balance_tol))
            sealed = ~result.connected  # no flow: both factors are 0, even at full contact
            flagged = ~result.balanced
            with np.errstate(invalid="ignore", divide="ignore"):
                pressure_factor = np.where(
                    positive, result.conductance / np.where(positive, h, 1.0) ** 3, np.nan)
            columns = {CONDUCTANCE: result.conductance,
                       FACTOR: np.where(sealed, 0.0, result.flow_factor),
                       PRESSURE_FACTOR: np.where(sealed, 0.0, pressure_factor)}
            for quantity, values in columns.items():
                out[column_name(quantity, direction)] = np.where(flagged, np.nan, values)
            out[column_name(CONNECTED, direction)] = result.connected
            out[column_name(BALANCE, direction)] = result.balance
            if flagged.any():
                _warn_flagged(direction, result, flagged)
        return out


def _warn_flagged(direction: str, result, flagged) -> None:
    """A warning naming the fields (flat indices of the probe's stack) whose flow along
    ``direction`` stayed off balance after the retry."""
    where = np.flatnonzero(np.ravel(flagged))
    logger.warning(
        "flow along %s off balance for %d of %d fields (indices %s; balance up to %.3g, "
        "tolerance %.3g) after a retry with iterative refinement; their conductance "
        "recorded as NaN, flagged in %s", direction, where.size, np.size(flagged),
        where[:10].tolist(), float(np.nanmax(np.where(flagged, result.balance, 0.0))),
        result.balance_tol, column_name(BALANCE, direction))


#: A flow probe that records nothing (the flow setting of a study without flow).
NO_FLOW = FlowProbe(directions=())


def probe_from_params(params: dict | None) -> FlowProbe:
    """The probe of stored settings (:meth:`FlowProbe.params`; None or empty: none)."""
    if not params:
        return NO_FLOW
    return FlowProbe(directions=tuple(params["directions"]), sides=str(params["sides"]),
                     face_rule=FACE_RULES[params["face_rule"]],
                     closed_below=float(params["closed_below"]),
                     # a file written before the balance was recorded has no tolerance:
                     # read as the default, its missing balance column then refused
                     balance_tol=float(params.get("balance_tol", BALANCE_TOL)))
