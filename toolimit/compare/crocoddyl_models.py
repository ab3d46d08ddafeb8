"""Crocoddyl action models of :class:`BaseTrackingProblem` (Python models with analytic derivatives).

Transcription (PROBLEM.md): the state is ``x_k = q_k`` (Euclidean) and every node has the control
``u_k = [db_k (n_base), v_{k+1} (n_arm)]`` with dynamics ``q_{k+1} = q_k + B_k u_k``.

* node 0: ``B_0 = [[I, 0], [0, dt I]]``: db_0 places the base freely (no cost, box +-10 never
  active); q_0 is fixed, so the node pays only ``1/2 w_v |v_1|^2``;
* nodes k >= 1: ``B_k = [[0, 0], [0, dt I]]``, the base is frozen exactly; db_k is a dummy control
  with cost ``1/2 |db_k|^2`` (it stays 0); the node pays pose and limit costs on q_k against P_k
  plus ``1/2 w_v |v_{k+1}|^2``;
* terminal node T: pose and limit costs on q_T against P_T.

Every node has the same nu because crocoddyl 3.2.1's SolverBoxFDDP sizes its box-QP from node 0.
Hessians are Gauss-Newton (J^T J, plus w_lim on the diagonal of joints outside their limits).

Importing this module needs crocoddyl (the ``compare`` extra).
"""

from __future__ import annotations

import numpy as np

from toolimit.compare.tracking_problem import BaseTrackingProblem, pose_residual, pose_residual_and_jacobian

try:
    import crocoddyl
except ImportError as error:  # pragma: no cover - depends on the environment
    raise ImportError(
        "the Crocoddyl comparison needs crocoddyl, an optional dependency: "
        'install it with `pip install -e ".[compare]"`'
    ) from error

BASE_CONTROL_BOX = 10.0  # metres (or radians) per node: wide enough never to be active


class TrackingNodeData(crocoddyl.ActionDataAbstract):
    """Crocoddyl's node data plus the node's own Pinocchio data (calc and calcDiff run per node)."""

    def __init__(self, model: TrackingNodeModel) -> None:
        crocoddyl.ActionDataAbstract.__init__(self, model)
        self.pinocchio = model.problem.model.createData()
        self.Fx = np.eye(model.state.nx)
        self.Fu = model.control_matrix
        self.Luu = np.diag(model.control_weights)


class TrackingNodeModel(crocoddyl.ActionModelAbstract):
    """Node ``k`` (0..T) of the transcription; node T is the terminal model."""

    def __init__(self, problem: BaseTrackingProblem, node: int) -> None:
        if not 0 <= node <= problem.horizon:
            raise ValueError(f"node must be in 0..{problem.horizon}, got {node}")
        nq = problem.model.nq
        crocoddyl.ActionModelAbstract.__init__(self, crocoddyl.StateVector(nq), nq, 0)
        self.problem = problem
        self.node = node
        self.target = problem.target(node) if node >= 1 else None
        n_base = problem.n_base
        self.control_matrix = np.zeros((nq, nq))
        self.control_matrix[n_base:, n_base:] = problem.dt * np.eye(problem.n_arm)
        if node == 0:
            self.control_matrix[:n_base, :n_base] = np.eye(n_base)
        # Diagonal of Luu: free base at node 0, unit-weight dummy afterwards; w_v on the arm.
        base_weight = 0.0 if node == 0 else 1.0
        self.control_weights = np.concatenate([np.full(n_base, base_weight), np.full(problem.n_arm, problem.w_v)])
        bound = np.concatenate([np.full(n_base, BASE_CONTROL_BOX), problem.velocity_limit])
        self.u_lb = -bound
        self.u_ub = bound

    def createData(self) -> TrackingNodeData:
        return TrackingNodeData(self)

    def _state_cost(self, data: TrackingNodeData, x: np.ndarray) -> float:
        if self.target is None:
            return 0.0
        residual = pose_residual(self.problem, data.pinocchio, x, self.target)
        excess = self.problem.limit_excess(x[self.problem.n_base :])
        return 0.5 * float(residual @ residual) + 0.5 * self.problem.w_lim * float(excess @ excess)

    def calc(self, data: TrackingNodeData, x: np.ndarray, u: np.ndarray | None = None) -> None:
        cost = self._state_cost(data, x)
        if u is None:  # terminal node (crocoddyl calls calc(data, x))
            data.xnext = x
        else:
            data.xnext = x + self.control_matrix @ u
            cost += 0.5 * float(u @ (self.control_weights * u))
        data.cost = cost

    def calcDiff(self, data: TrackingNodeData, x: np.ndarray, u: np.ndarray | None = None) -> None:
        nq = self.problem.model.nq
        Lx = np.zeros(nq)
        Lxx = np.zeros((nq, nq))
        if self.target is not None:
            residual, jacobian = pose_residual_and_jacobian(self.problem, data.pinocchio, x, self.target)
            Lx += jacobian.T @ residual
            Lxx += jacobian.T @ jacobian
            n_base = self.problem.n_base
            excess = self.problem.limit_excess(x[n_base:])
            Lx[n_base:] += self.problem.w_lim * excess
            outside = n_base + np.flatnonzero(excess != 0.0)
            Lxx[outside, outside] += self.problem.w_lim
        data.Lx = Lx
        data.Lxx = Lxx
        if u is not None:
            data.Lu = self.control_weights * u


def shooting_problem(problem: BaseTrackingProblem, x0: np.ndarray) -> crocoddyl.ShootingProblem:
    """The Crocoddyl shooting problem: T running nodes 0..T-1 and the terminal node T."""
    running = [TrackingNodeModel(problem, k) for k in range(problem.horizon)]
    terminal = TrackingNodeModel(problem, problem.horizon)
    return crocoddyl.ShootingProblem(np.asarray(x0, dtype=float), running, terminal)
