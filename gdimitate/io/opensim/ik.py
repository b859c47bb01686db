"""Marker-based inverse kinematics: :func:`inverse_kinematics` (markers → :class:`Motion`).

Per frame, the weighted least-squares fit OpenSim's own inverse kinematics makes::

    q_k = argmin_q  Σ_i w_i ‖p_i(q) − m_i(t_k)‖²   s.t.  q within the model's joint limits

where ``p_i(q)`` is the position of the model's marker frame ``i`` (Pinocchio forward
kinematics; a robot converted from an ``.osim`` carries every model marker as a frame of the
same name) and ``m_i`` the measured marker. It is solved by Gauss–Newton steps taken as
Pink's differential-IK quadratic programs (one position-only :class:`pink.tasks.FrameTask`
per marker, weighted ``w_i``; Pink's configuration limit keeps every joint in its range),
warm-started from the previous frame. The first frame starts from the neutral pose with the
root placed by a rigid fit (Kabsch) of the markers on the root body, and takes more steps.

Markers missing in a frame (NaN) drop out of that frame's fit; markers the model lacks are
left out with a :class:`~gdimitate.errors.MarkerGapWarning` (and listed in
``IKResult.unused``). Spline-driven joints of a converted OpenSim model (e.g. a walker knee's
coupled axes, :func:`~gdimitate.opensim.follow_coordinates`) are not free: each marker task's
Jacobian carries them into their coordinate's column by the chain rule (the spline's slope,
central differences), their own columns are zero, and they are set from their coordinate
after every step.
"""

from __future__ import annotations

import functools
import warnings
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ...errors import InvalidInputError, MarkerGapWarning, OpenSimDataError, SolverError
from ...model.motion import Motion
from ...model.osim.joints import follow_coordinates
from ...model.osim.trc import Markers

__all__ = ["IKResult", "inverse_kinematics", "marker_frames"]


@dataclass(frozen=True)
class IKResult:
    """What :func:`inverse_kinematics` fitted: ``names`` (the markers used, ``n``);
    ``residuals`` ``(T, n)`` [m] distance between each model marker and the measured one
    (NaN where the marker was not seen); ``rms`` ``(T,)`` [m] per frame over the seen
    markers; ``unused`` (markers in the file the model lacks); ``iterations`` ``(T,)``."""

    names: tuple[str, ...]
    residuals: np.ndarray
    rms: np.ndarray
    unused: tuple[str, ...]
    iterations: np.ndarray

    def per_marker(self) -> dict[str, float]:
        """RMS residual [m] of each marker over the frames it was seen in."""
        return {n: float(np.sqrt(np.nanmean(self.residuals[:, i] ** 2)))
                for i, n in enumerate(self.names)}


def marker_frames(robot) -> dict[str, int]:
    """``{marker name: frame id}``: the robot's OpenSim marker frames (``robot.osim.markers``)
    or, for other robots, every frame (markers are matched by name)."""
    m = robot.model
    conv = getattr(robot, "osim", None)
    names = conv.markers if conv is not None else [f.name for f in m.frames]
    return {n: m.getFrameId(n) for n in names if m.existFrame(n)}


def _weights(names, weights) -> np.ndarray:
    if weights is None:
        return np.ones(len(names))
    w = np.array([float(weights.get(n, 1.0)) for n in names])
    unknown = sorted(set(weights) - set(names))
    if unknown:
        raise InvalidInputError(f"weights name markers neither the file nor the model has: "
                                f"{unknown}")
    if not np.all(np.isfinite(w)) or np.any(w < 0):
        raise InvalidInputError("marker weights must be finite and ≥ 0")
    return w


def _kabsch(A: np.ndarray, B: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """R, p minimising Σ‖R a + p − b‖² over rows of A, B (n, 3)."""
    ca, cb = A.mean(0), B.mean(0)
    U, _, Vt = np.linalg.svd((A - ca).T @ (B - cb))
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T))])
    R = Vt.T @ D @ U.T
    return R, cb - R @ ca


def _initial(robot, ids, X) -> np.ndarray:
    """Neutral pose with the free-flyer placed by a rigid fit of the root body's markers."""
    m = robot.model
    q = robot.neutral.copy()
    if robot.base != "free":
        return q
    d = m.createData()
    pin.framesForwardKinematics(m, d, q)
    root = [k for k, i in enumerate(ids) if m.frames[i].parentJoint == 1
            and np.all(np.isfinite(X[k]))]
    if len(root) < 3:
        seen = [k for k in range(len(ids)) if np.all(np.isfinite(X[k]))]
        q[:3] += np.mean(X[seen], 0) - np.mean([d.oMf[ids[k]].translation for k in seen], 0)
        return q
    M0 = pin.XYZQUATToSE3(q[:7])
    A = np.array([M0.actInv(d.oMf[ids[k]].translation) for k in root])  # in the root frame
    R, p = _kabsch(A, X[root])
    q[:7] = pin.SE3ToXYZQUAT(pin.SE3(R, p))
    return q


def _coupling(robot, plans):
    """``C(q)`` ``(nv, nv)``: identity but for each spline-driven joint, whose velocity is
    its spline's slope times its coordinate's (``v = C(q) v_free``)."""
    steps = [(robot.idx_v(st.coordinate), robot.idx_v(st.follows[0]),
              robot.idx_q(st.follows[0]), st.follows[1])
             for pl in plans for st in pl.steps if st.follows is not None]

    def C(q: np.ndarray) -> np.ndarray:
        M = np.eye(robot.model.nv)
        for vf, vd, qd, f in steps:
            h = 1e-6
            M[vf, vf] = 0.0
            M[vf, vd] = float((f(q[qd] + h) - f(q[qd] - h)) / (2 * h))
        return M

    return C


@functools.cache
def _task_class():
    """Pink's position task whose Jacobian is ``J·C(q)`` where a ``coupling`` is set."""
    from pink.tasks import FrameTask

    class CoupledFrameTask(FrameTask):
        coupling = None

        def compute_jacobian(self, configuration):
            J = super().compute_jacobian(configuration)
            return J if self.coupling is None else J @ self.coupling(configuration.q)

    return CoupledFrameTask


def _marker_task(name: str, cost: float, coupling):
    task = _task_class()(name, position_cost=cost, orientation_cost=0.0)
    task.coupling = coupling
    return task


def inverse_kinematics(robot, markers: Markers, weights: dict[str, float] | None = None, *,
                       iterations: int = 8, first_iterations: int = 60, tol: float = 1e-7,
                       return_result: bool = False):
    """Fit ``robot`` to measured ``markers`` frame by frame → :class:`~gdimitate.Motion`.

    ``robot``: a :class:`~gdimitate.Robot` whose frames are named after the markers (e.g.
    :meth:`Robot.from_osim`); ``markers``: :class:`~gdimitate.opensim.Markers` (from
    :func:`~gdimitate.opensim.read_trc` or :func:`gdimitate.io.c3d.read_c3d`, metres, our world
    frame); ``weights``: ``{marker: w ≥ 0}`` (default 1 each). ``iterations``: Gauss–Newton
    steps per frame after the first (``first_iterations``), stopping earlier when a step
    moves q by less than ``tol`` [rad or m]. Returns the motion (``q`` ``(T, nq)`` on
    ``markers.t``, no contacts), or ``(motion, IKResult)`` with ``return_result=True``.

    Raises :class:`~gdimitate.errors.OpenSimDataError` when fewer than 3 of the file's
    markers are model frames, :class:`~gdimitate.errors.InvalidInputError` for bad weights
    and :class:`~gdimitate.errors.SolverError` if the QP solver fails."""
    import pink
    from pink.limits import ConfigurationLimit

    frames = marker_frames(robot)
    names = [n for n in markers.names if n in frames]
    unused = tuple(n for n in markers.names if n not in frames)
    if len(names) < 3:
        raise OpenSimDataError(
            f"{markers.source or 'markers'}: only {len(names)} of its markers are frames of "
            f"robot {robot.name!r} ({names}); marker names must match the model's "
            f"(model: {sorted(frames)[:10]}…, file: {list(markers.names)[:10]}…)")
    if unused:
        warnings.warn(f"markers not on the model, left out of the fit: {list(unused)}",
                      MarkerGapWarning, stacklevel=2)
    w = _weights(names, weights)
    cols = [markers.names.index(n) for n in names]
    X = markers.xyz[:, cols]  # (T, n, 3)
    ids = [frames[n] for n in names]
    m = robot.model
    plans = [p for p in getattr(getattr(robot, "osim", None), "plans", ())
             if any(st.follows is not None for st in p.steps)]
    coupling = _coupling(robot, plans) if plans else None
    tasks = [_marker_task(n, float(np.sqrt(wi)), coupling) for n, wi in zip(names, w)]
    limits = [ConfigurationLimit(m, config_limit_gain=0.9)]
    config = pink.Configuration(m, m.createData(), _initial(robot, ids, X[0]))
    T = markers.t.size
    Q = np.empty((T, m.nq))
    its = np.zeros(T, int)
    for k in range(T):
        seen = [i for i in range(len(names)) if np.all(np.isfinite(X[k, i])) and w[i] > 0]
        for i in seen:
            tasks[i].set_target(pin.SE3(np.eye(3), X[k, i]))
        active = [tasks[i] for i in seen]
        for it in range(first_iterations if k == 0 else iterations):
            try:
                v = pink.solve_ik(config, active, 1.0, solver="daqp", damping=1e-9,
                                  limits=limits)
            except Exception as e:  # pink.exceptions.NoSolutionFound, a QP solver's error
                raise _no_solution(robot, markers, names, ids, X[k], seen, k, e) from None
            if not np.all(np.isfinite(v)):
                raise _no_solution(robot, markers, names, ids, X[k], seen, k, "a non-finite step")
            config.integrate_inplace(v, 1.0)
            if plans:
                config.update(follow_coordinates(plans, config.q[None].copy(), robot.idx_q)[0])
            its[k] = it + 1
            if np.max(np.abs(v)) < tol:
                break
        Q[k] = config.q
    motion = Motion(markers.t.copy(), robot.joint_names, Q, base_nq=7 if robot.base == "free"
                    else 0, joint_nq=tuple(m.joints[j].nq for j in range(1, m.njoints)))
    if not return_result:
        return motion
    return motion, _result(robot, Q, ids, X, names, unused, its)


def _no_solution(robot, markers: Markers, names, ids, Xk: np.ndarray, seen, k: int, why
                 ) -> SolverError:
    """The error for a frame the marker fit cannot solve: the file, the frame, the markers
    farthest from the model (a corrupt value shows as one marker metres away)."""
    m, d = robot.model, robot.model.createData()
    pin.framesForwardKinematics(m, d, robot.neutral)
    far = sorted(seen, key=lambda i: -float(np.linalg.norm(Xk[i] - np.median(Xk[seen], 0))))
    shown = ", ".join(f"{names[i]} at {np.round(Xk[i], 3).tolist()} m" for i in far[:3])
    return SolverError(
        f"{markers.source or 'markers'}: marker IK found no solution in frame {k + 1} (t = "
        f"{markers.t[k]:g} s; {why}); the markers farthest from the others there: {shown}. "
        "Check that frame for corrupt positions (mark them as not seen, or cut the frame) "
        "and that the markers belong to this model")


def _result(robot, Q, ids, X, names, unused, its) -> IKResult:
    m, d = robot.model, robot.model.createData()
    res = np.empty(X.shape[:2])
    for k, q in enumerate(Q):
        pin.framesForwardKinematics(m, d, q)
        P = np.array([d.oMf[i].translation for i in ids])
        res[k] = np.linalg.norm(P - X[k], axis=1)
    rms = np.sqrt(np.nanmean(res ** 2, axis=1))
    return IKResult(tuple(names), res, rms, tuple(unused), its)
