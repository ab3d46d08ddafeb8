"""The terms of the tracking cost J, each defined once: its value and its quadratic model.

J = pose + velocity + posture (see :mod:`toolimit.trajopt.problem` for the formula). Each term gives
its value at (base, q) and, around an SQP iterate, its Gauss-Newton model in the step
``x = (db, dq_1..dq_T)`` (active base coordinates, m and rad; joint-position steps, rad) as the
blocks of the QP's fixed sparsity pattern (:class:`QuadraticModel`), together with the change of
that model along a step (the SQP's predicted decrease). A new term is one class with these three
methods, added to ``TrackingProblem.terms``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np


@dataclass(frozen=True)
class Point:
    """A trajectory where J is evaluated.

    Attributes:
        base: (3,) base x, y (m), yaw (rad).
        q: (T+1, N) joint trajectory, rad (q[0] fixed).
        dt: time step, s.
        residuals: (T, 6) weighted pose residuals W log6(P_t^-1 M(q_t)) (m, then rad).
    """

    base: np.ndarray
    q: np.ndarray
    dt: float
    residuals: np.ndarray

    @property
    def velocity(self) -> np.ndarray:
        """(T, N) joint velocities, rad/s."""
        return np.diff(self.q, axis=0) / self.dt


@dataclass(frozen=True)
class Iterate(Point):
    """A point where the SQP builds its QP, with the residuals' Jacobians.

    Attributes:
        jac_base: (T, 6, nb) d residual_t / d(active base coordinates).
        jac_arm: (T, 6, N) d residual_t / d q_t.
    """

    jac_base: np.ndarray
    jac_arm: np.ndarray


@dataclass(frozen=True)
class QuadraticModel:
    """A term's model ``g'x + x'Hx / 2`` in the step x, as blocks of the QP pattern (None: zero).

    Attributes:
        gradient_base: (nb,); gradient_steps: (T, N).
        hessian_base: (nb, nb); hessian_cross: (T, nb, N) base-step t; hessian_steps: (T, N, N)
            step t-step t; hessian_next: (T-1,) the same coupling of every joint of step t with itself
            at step t + 1 (a diagonal block).
        hessian_diagonal: (T,) added to the diagonal of step t's block (per-joint terms).
    """

    gradient_steps: np.ndarray
    gradient_base: np.ndarray | None = None
    hessian_base: np.ndarray | None = None
    hessian_cross: np.ndarray | None = None
    hessian_steps: np.ndarray | None = None
    hessian_diagonal: np.ndarray | None = None
    hessian_next: np.ndarray | None = None


class CostTerm(Protocol):
    """One term of J."""

    @property
    def name(self) -> str:
        """The term's key in ``TrackingProblem.cost_terms``."""

    def value(self, at: Point) -> float:
        """The term at ``at``."""

    def model(self, at: Iterate) -> QuadraticModel:
        """The term's Gauss-Newton model around ``at``."""

    def model_change(self, at: Iterate, d_base: np.ndarray, d_q: np.ndarray) -> tuple[float, float]:
        """The model's change along the step d_base (nb,), d_q (T, N): its first-order and
        second-order parts (the SQP adds them in a fixed order, so J's prediction is reproducible)."""


class PoseTerm:
    """1/2 sum_t |W log6(P_t^-1 M(b, q_t))|^2, linearised by Gauss-Newton (r + J x)."""

    name = "pose"

    def value(self, at: Point) -> float:
        return 0.5 * float(np.sum(at.residuals**2))

    def model(self, at: Iterate) -> QuadraticModel:
        return QuadraticModel(
            gradient_base=np.einsum("tki,tk->i", at.jac_base, at.residuals),
            gradient_steps=np.einsum("tki,tk->ti", at.jac_arm, at.residuals),
            hessian_base=np.einsum("tki,tkj->ij", at.jac_base, at.jac_base),
            hessian_cross=np.einsum("tki,tkj->tij", at.jac_base, at.jac_arm),
            hessian_steps=np.einsum("tki,tkj->tij", at.jac_arm, at.jac_arm),
        )

    def model_change(self, at: Iterate, d_base: np.ndarray, d_q: np.ndarray) -> tuple[float, float]:
        d_residual = at.jac_base @ d_base + np.einsum("tki,ti->tk", at.jac_arm, d_q)
        return float(np.sum(at.residuals * d_residual)), 0.5 * float(np.sum(d_residual**2))


@dataclass(frozen=True)
class VelocityTerm:
    """1/2 w_v sum_t |v_t|^2 with v_t = (q_t - q_{t-1}) / dt: exactly quadratic in the steps."""

    weight: float
    name: str = "velocity"

    def value(self, at: Point) -> float:
        return 0.5 * self.weight * float(np.sum(at.velocity**2))

    def model(self, at: Iterate) -> QuadraticModel:
        velocity = at.velocity
        next_velocity = np.vstack([velocity[1:], np.zeros((1, velocity.shape[1]))])
        w = self.weight / at.dt**2
        diagonal = np.full(len(velocity), 2.0 * w)  # dq_t appears in v_t and v_{t+1} (not beyond T)
        diagonal[-1] = w
        return QuadraticModel(
            gradient_steps=self.weight / at.dt * (velocity - next_velocity),
            hessian_diagonal=diagonal,
            hessian_next=np.full(len(velocity) - 1, -w),
        )

    def model_change(self, at: Iterate, d_base: np.ndarray, d_q: np.ndarray) -> tuple[float, float]:
        d_velocity = np.diff(np.vstack([np.zeros((1, d_q.shape[1])), d_q]), axis=0) / at.dt
        return self.weight * float(np.sum(at.velocity * d_velocity)), 0.5 * self.weight * float(np.sum(d_velocity**2))


@dataclass(frozen=True)
class PostureTerm:
    """1/2 w_p sum_t |q_t - q_0|^2: keeps a redundant arm near its start posture."""

    weight: float
    q_start: np.ndarray
    name: str = "posture"

    def value(self, at: Point) -> float:
        return 0.5 * self.weight * float(np.sum((at.q[1:] - self.q_start) ** 2))

    def model(self, at: Iterate) -> QuadraticModel:
        return QuadraticModel(
            gradient_steps=self.weight * (at.q[1:] - self.q_start),
            hessian_diagonal=np.full(len(at.q) - 1, self.weight),
        )

    def model_change(self, at: Iterate, d_base: np.ndarray, d_q: np.ndarray) -> tuple[float, float]:
        return self.weight * float(np.sum((at.q[1:] - self.q_start) * d_q)), 0.5 * self.weight * float(np.sum(d_q**2))
