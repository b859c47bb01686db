"""``simulate``: replay a plan in MuJoCo under the whole-body tracking controller and measure it.

The loop: the MuJoCo model of :mod:`~gdimitate.model.mjcf` steps every ``dt`` [s] (default
1 ms); every ``control_period`` [s] (default 1 ms, i.e. 1 kHz) the
:class:`~gdimitate.sim.controller.TrackingController` reads the simulated state, solves its QP
against the plan sampled at that time and sets the motor torques, held until the next control
step. The robot starts in the plan's first state. The contact forces on each foot are MuJoCo's
(``mj_contactForce`` of every floor–foot contact point, summed). The run stops at the end of
the plan (or ``duration``), or when the robot falls (:class:`~gdimitate.sim.metrics.
FallCriteria`) if ``stop_on_fall``.
"""

from __future__ import annotations

import contextlib
import time
import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np
import pinocchio as pin

from ..errors import GdimitateWarning, PlanError, SimulationError
from ..jsonable import jsonable
from ..model.contact import ContactForces
from ..model.mjcf import ModelOptions, SimModel, build_model
from ..model.motion import Motion
from ..model.robot import SIDES, Robot
from ..safety import check_array_size
from .controller import ControllerGains, TrackingController
from .metrics import (
    DirectionAgreement,
    FallCriteria,
    StanceSlip,
    cop_and_margin,
    direction_agreement,
    fall_time,
    saturation_fraction,
    stance_slip,
)
from .reference import Reference, check_plan

__all__ = ["Push", "SimMetrics", "SimResult", "simulate", "measure_contacts"]


@dataclass(frozen=True)
class Push:
    """An external force ``force`` ``(3,)`` [N] (world frame) on the floating base's centre of
    mass from ``start`` [s] (plan time) for ``duration`` [s]."""

    start: float
    duration: float
    force: tuple[float, float, float]

    def __post_init__(self) -> None:
        f = np.asarray(self.force, dtype=float)
        if f.shape != (3,) or not np.all(np.isfinite(f)):
            raise SimulationError(f"Push.force must be 3 finite numbers [N]; got {self.force!r}")
        if not (self.duration > 0 and np.isfinite(self.start)):
            raise SimulationError("Push.duration must be > 0 s and start finite")
        object.__setattr__(self, "force", tuple(float(x) for x in f))


@dataclass(frozen=True)
class SimMetrics:
    """What :func:`simulate` measured.

    ``fell`` and ``fall_time`` [s] (``None`` when it did not), ``fall_reason`` (``"height"``,
    ``"tilt"`` or ``""``), ``criteria`` (the thresholds); ``slip`` — one
    :class:`~gdimitate.sim.metrics.StanceSlip` per stance of each foot —, ``slip_max`` [m]
    (over stances that were loaded);
    ``force_vs_plan`` / ``force_vs_demo`` {side: :class:`~gdimitate.sim.metrics.
    DirectionAgreement`} (``force_vs_demo`` is ``None`` without ``demo_forces``);
    ``cop_margin_min`` {side: [m]} the smallest centre-of-pressure margin inside the sole while
    loaded (negative: outside); ``torque_saturation`` [-] fraction of samples × limited joints
    at their limit, ``torque_saturation_per_joint`` {joint: fraction}; ``joint_rmse`` [rad or
    m] RMS of simulated − planned actuated joint positions, ``joint_rmse_per_joint``;
    ``base_position_rmse`` [m]; ``qp_failures`` control steps whose QP failed (previous torques
    kept); ``ms_per_step`` wall-clock and ``cpu_ms_per_step`` this process's CPU milliseconds
    per simulation step (controller included; the CPU figure does not grow on a busy machine);
    ``plan_stance_foot_speed_max`` {side: [m/s]} the plan's own largest sole speed at a knot
    where it says that foot is in stance (a held foot cannot move: a plan whose stance foot
    moves — e.g. takes off during its last stance knot — asks the floor for a push that no
    foot on the floor gets).
    """

    fell: bool
    fall_time: float | None
    fall_reason: str
    criteria: FallCriteria
    slip: tuple[StanceSlip, ...]
    slip_max: float
    force_vs_plan: dict[str, DirectionAgreement]
    force_vs_demo: dict[str, DirectionAgreement] | None
    cop_margin_min: dict[str, float]
    torque_saturation: float
    torque_saturation_per_joint: dict[str, float]
    joint_rmse: float
    joint_rmse_per_joint: dict[str, float]
    base_position_rmse: float
    qp_failures: int
    ms_per_step: float
    cpu_ms_per_step: float
    plan_stance_foot_speed_max: dict[str, float]

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready summary (NaN → ``None``; per-stance slips as lists)."""
        def agree(d: dict[str, DirectionAgreement] | None) -> Any:
            return None if d is None else {s: jsonable(a.__dict__) for s, a in d.items()}

        return {
            "fell": self.fell, "fall_time_s": jsonable(self.fall_time),
            "fall_reason": self.fall_reason,
            "criteria": {"min_height_ratio": self.criteria.min_height_ratio,
                         "max_tilt_rad": self.criteria.max_tilt},
            "slip_max_m": jsonable(self.slip_max),
            "slip": [{"side": x.side, "start_s": x.start, "end_s": x.end,
                      "slip_m": jsonable(x.slip)} for x in self.slip],
            "force_vs_plan": agree(self.force_vs_plan),
            "force_vs_demo": agree(self.force_vs_demo),
            "cop_margin_min_m": jsonable(self.cop_margin_min),
            "torque_saturation": jsonable(self.torque_saturation),
            "torque_saturation_per_joint": jsonable(self.torque_saturation_per_joint),
            "joint_rmse": jsonable(self.joint_rmse),
            "joint_rmse_per_joint": jsonable(self.joint_rmse_per_joint),
            "base_position_rmse_m": jsonable(self.base_position_rmse),
            "qp_failures": self.qp_failures, "ms_per_step": jsonable(self.ms_per_step),
            "cpu_ms_per_step": jsonable(self.cpu_ms_per_step),
            "plan_stance_foot_speed_max_m_s": jsonable(self.plan_stance_foot_speed_max),
        }


@dataclass(frozen=True)
class SimResult:
    """A simulated run, sampled every control step (``N`` samples).

    ``t`` ``(N,)`` [s] (plan time); ``q`` ``(N, nq)``, ``v`` ``(N, nv)`` in Pinocchio's order and
    conventions; ``tau`` ``(N, nu)`` [N·m] motor torques (actuator order: ``actuated`` joint
    names); ``contact_forces`` {side: ``(N, 3)``} [N] force of the ground on the foot, world
    frame; ``contact_wrenches`` {side: ``(N, 6)``} the same as a wrench at the sole frame's
    origin in the sole frame (the plan's convention); ``cop`` {side: ``(N, 2)``} [m] centre of
    pressure in the sole frame, ``cop_margin`` {side: ``(N,)``} [m] (NaN unloaded);
    ``plan_q`` ``(N, nq)``, ``plan_stance`` {side: ``(N,)`` bool}, ``plan_forces`` {side:
    ``(N, 3)``} the plan sampled on this grid (forces in the world frame); ``qp_wrenches``
    {side: ``(N, 6)``}; ``demo_forces`` {side: ``(N, 3)``} or ``None`` (resampled);
    ``metrics`` (:class:`SimMetrics`); ``dt``, ``control_period`` [s]; ``joint_names``;
    ``actuated`` (joint names of the columns of ``tau``) and ``effort`` ``(nu,)`` their limits
    (inf: unlimited); ``base_height``, ``plan_base_height`` ``(N,)`` [m] and ``tilt`` ``(N,)``
    [rad] (what the fall criteria look at); ``base_nq``, ``joint_nq`` (as in ``Motion``).
    """

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    tau: np.ndarray
    contact_forces: dict[str, np.ndarray]
    contact_wrenches: dict[str, np.ndarray]
    cop: dict[str, np.ndarray]
    cop_margin: dict[str, np.ndarray]
    plan_q: np.ndarray
    plan_stance: dict[str, np.ndarray]
    plan_forces: dict[str, np.ndarray]
    qp_wrenches: dict[str, np.ndarray]
    demo_forces: dict[str, np.ndarray] | None
    metrics: SimMetrics
    dt: float
    control_period: float
    joint_names: tuple[str, ...]
    actuated: tuple[str, ...]
    effort: np.ndarray
    base_height: np.ndarray
    plan_base_height: np.ndarray
    tilt: np.ndarray
    base_nq: int
    joint_nq: tuple[int, ...]

    def motion(self) -> Motion:
        """The simulated trajectory as a :class:`~gdimitate.model.motion.Motion` (stance = the
        measured contact: normal force above 1 N)."""
        contact = {s: self.contact_wrenches[s][:, 2] > 1.0 for s in SIDES}
        return Motion(t=self.t, joint_names=self.joint_names, q=self.q, contact=contact,
                      base_nq=self.base_nq, joint_nq=self.joint_nq, v=self.v)

    def plan_motion(self) -> Motion:
        """The plan sampled on the simulation grid, as a Motion."""
        return Motion(t=self.t, joint_names=self.joint_names, q=self.plan_q,
                      contact=self.plan_stance, base_nq=self.base_nq, joint_nq=self.joint_nq)


def measure_contacts(sim: SimModel, data: mujoco.MjData) -> dict[str, np.ndarray]:
    """MuJoCo's contact wrench of the floor on each foot ``{side: (6,)}``: the force ``[0:3]``
    [N] in the world frame and its moment ``[3:6]`` [N·m] about the sole frame's origin, world
    frame."""
    out = {s: np.zeros(6) for s in SIDES}
    n = data.ncon
    if n == 0:
        return out
    con = data.contact
    geom = np.asarray(con.geom)[:n]
    frame = np.asarray(con.frame)[:n].reshape(n, 3, 3)  # rows: normal (geom1 → geom2), tangents
    pos = np.asarray(con.pos)[:n]
    buf = np.zeros(6)
    local = np.zeros((n, 3))
    for i in range(n):
        mujoco.mj_contactForce(sim.mj, data, i, buf)
        local[i] = buf[:3]
    f = np.einsum("nij,ni->nj", frame, local)  # force of geom1 on geom2, world frame
    for s, g in sim.foot_geom.items():
        on2 = (geom[:, 1] == g) & (geom[:, 0] == sim.floor_geom)
        on1 = (geom[:, 0] == g) & (geom[:, 1] == sim.floor_geom)
        if not (on2.any() or on1.any()):
            continue
        fs = np.where(on1[:, None], -f, f)[on1 | on2]
        r = pos[on1 | on2] - data.site_xpos[sim.sole_site[s]]
        m = np.stack([r[:, 1] * fs[:, 2] - r[:, 2] * fs[:, 1],
                      r[:, 2] * fs[:, 0] - r[:, 0] * fs[:, 2],
                      r[:, 0] * fs[:, 1] - r[:, 1] * fs[:, 0]], axis=1)
        out[s][:3] = fs.sum(axis=0)
        out[s][3:] = m.sum(axis=0)
    return out


def _demo_on_grid(demo: ContactForces, t: np.ndarray) -> tuple[dict, dict]:
    forces, present = {}, {}
    td = np.asarray(demo.t, dtype=float)
    for s in SIDES:
        if s not in demo.feet:
            raise PlanError(f"demo_forces has no {s!r} foot; it has {sorted(demo.feet)}")
        ft = demo.feet[s]
        forces[s] = np.column_stack([np.interp(t, td, ft.force[:, i]) for i in range(3)])
        inside = (t >= td[0]) & (t <= td[-1])
        k = np.clip(np.searchsorted(td, t), 0, td.size - 1)
        present[s] = inside & ft.contact[k]
    return forces, present


def simulate(robot: Robot, adapted: Any, *, demo_forces: ContactForces | None = None,
             gains: ControllerGains = ControllerGains(),  # noqa: B008 (frozen: immutable)
             dt: float = 0.001,
             duration: float | None = None, push: Push | None = None,
             control_period: float = 0.001, options: ModelOptions | None = None,
             fall: FallCriteria = FallCriteria(),  # noqa: B008 (frozen: immutable)
             stop_on_fall: bool = True) -> SimResult:
    """Simulate ``robot`` tracking the plan ``adapted`` (``.motion`` with v, a; ``.wrenches``;
    ``.contacts``, see :mod:`~gdimitate.sim.reference`) in MuJoCo and measure the run.

    ``dt`` [s]: simulation step; ``control_period`` [s]: controller period (a multiple of
    ``dt``); ``duration`` [s]: how long to run from the plan's first time (default: the plan's
    length; past its end the last knot is held); ``push``: an external force on the base;
    ``demo_forces``: the demonstrator's measured forces (own time grid, resampled by time) to
    compare the simulated force direction with; ``options``: MuJoCo model options (its
    ``timestep`` is replaced by ``dt``); ``fall``: fall thresholds.
    """
    plan = check_plan(robot, adapted)
    if not (0 < dt <= 0.01):
        raise SimulationError(f"dt must be in (0, 0.01] s; got {dt!r}")
    every = int(round(control_period / dt))
    if every < 1 or abs(every * dt - control_period) > 1e-9:
        raise SimulationError(f"control_period {control_period!r} s must be a multiple of dt "
                              f"{dt!r} s")
    opts = options or ModelOptions()
    opts = ModelOptions(**{**opts.__dict__, "timestep": dt})
    sim = build_model(robot, opts, contacts=plan.contacts)
    ref = Reference(robot, plan)
    ctl = TrackingController(sim, gains)
    t0 = ref.start
    dur = (ref.end - t0) if duration is None else float(duration)
    if not dur > 0:
        raise SimulationError(f"duration must be > 0 s; got {duration!r}")
    mo = plan.motion
    data = sim.new_data()
    m = robot.model
    nu = sim.idx_v_act.size
    n_ctrl = check_array_size(f"a {dur:g} s simulation record",
                              (np.floor(dur / control_period + 1e-9) + 1,
                               3 * m.nq + 2 * m.nv + nu))[0]
    rec = _Recorder(n_ctrl, m.nq, m.nv, nu)
    samples = ref.samples(t0 + control_period * np.arange(n_ctrl))
    wall, cpu = time.perf_counter(), time.process_time()
    with mujoco_warnings():
        sim.set_state(data, mo.q[0], mo.derivatives("a plan")[0][0])
        steps = _run(sim, data, ctl, rec, ref, samples, fall, push, stop_on_fall, t0,
                     control_period, every, dt, n_ctrl)
    fails = rec.fails
    ms = (1e3 * (time.perf_counter() - wall) / max(steps, 1),
          1e3 * (time.process_time() - cpu) / max(steps, 1))
    return _finish(robot, sim, plan, ref, rec, demo_forces, fall, fails, ms, dt,
                   control_period)


@contextlib.contextmanager
def mujoco_warnings() -> Iterator[list[str]]:
    """MuJoCo's warnings (NaN states, contact buffer overflow, …) collected into a list and
    raised once as a :class:`~gdimitate.errors.GdimitateWarning` when the block ends, instead
    of MuJoCo's default: appending them to ``MUJOCO_LOG.TXT`` in the working folder."""
    got: list[str] = []
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(got.append)
    try:
        yield got
    finally:
        mujoco.set_mju_user_warning(previous)
        if got:
            more = f" (and {len(got) - 1} more)" if len(got) > 1 else ""
            warnings.warn(f"MuJoCo: {got[0]}{more}", GdimitateWarning, stacklevel=3)


def _run(sim, data, ctl, rec, ref, samples, fall, push, stop_on_fall, t0, control_period,
         every, dt, n_ctrl) -> int:
    """The control loop; returns the number of simulation steps (controller failures are
    counted in ``rec.fails``)."""
    base_body = sim.base_body
    steps = 0
    for k in range(n_ctrl):
        t = t0 + k * control_period
        q, v = sim.state(data)
        s = samples[k]
        out = ctl.step(q, v, s)
        rec.fails += out.status < 0
        data.ctrl[:] = out.tau
        rec.put(k, t, q, v, out, s, measure_contacts(sim, data), sim, data)
        height, plan_h, tilt = rec.base_state(k, sim, data, s)
        if stop_on_fall and (height < fall.min_height_ratio * plan_h or tilt > fall.max_tilt):
            rec.truncate(k + 1)
            break
        for _ in range(every):
            if push is not None and push.start <= t < push.start + push.duration:
                data.xfrc_applied[base_body, :3] = push.force
            else:
                data.xfrc_applied[base_body, :3] = 0.0
            mujoco.mj_step(sim.mj, data)
            steps += 1
            t += dt
    return steps


class _Recorder:
    """Preallocated arrays of one run."""

    def __init__(self, n: int, nq: int, nv: int, nu: int):
        z = np.zeros
        self.fails = 0
        self.t, self.q, self.v, self.tau = z(n), z((n, nq)), z((n, nv)), z((n, nu))
        self.plan_q = z((n, nq))
        self.wrench_world = {s: z((n, 6)) for s in SIDES}
        self.wrench_sole = {s: z((n, 6)) for s in SIDES}
        self.sole_xy = {s: z((n, 2)) for s in SIDES}
        self.stance = {s: np.zeros(n, bool) for s in SIDES}
        self.plan_force = {s: z((n, 3)) for s in SIDES}
        self.qp_wrench = {s: z((n, 6)) for s in SIDES}
        self.height, self.plan_height, self.tilt = z(n), z(n), z(n)
        self.n = n

    def put(self, k, t, q, v, out, s, wr, sim, data) -> None:
        self.t[k], self.q[k], self.v[k], self.tau[k] = t, q, v, out.tau
        self.plan_q[k] = s.q
        for sd in SIDES:
            R = data.site_xmat[sim.sole_site[sd]].reshape(3, 3)
            self.wrench_world[sd][k] = wr[sd]
            self.wrench_sole[sd][k] = np.r_[R.T @ wr[sd][:3], R.T @ wr[sd][3:]]
            self.sole_xy[sd][k] = data.site_xpos[sim.sole_site[sd]][:2]
            self.stance[sd][k] = s.stance[sd]
            self.plan_force[sd][k] = s.foot_rot[sd] @ s.wrench[sd][:3]
            self.qp_wrench[sd][k] = out.wrench[sd]

    def base_state(self, k, sim, data, s) -> tuple[float, float, float]:
        """Base height above the floor, the plan's, and the tilt from the plan [rad]."""
        b = sim.base_body
        R = data.xmat[b].reshape(3, 3)
        up_sim = R @ (s.base_rot.T @ np.array([0.0, 0.0, 1.0]))
        tilt = float(np.arccos(np.clip(up_sim[2], -1.0, 1.0)))
        height = float(data.xpos[b][2])
        plan_h = float(s.base_height)
        self.height[k], self.plan_height[k], self.tilt[k] = height, plan_h, tilt
        return height, plan_h, tilt

    def truncate(self, n: int) -> None:
        for name, val in list(self.__dict__.items()):
            if isinstance(val, np.ndarray) and val.shape[:1] == (self.n,):
                setattr(self, name, val[:n])
            elif isinstance(val, dict):
                setattr(self, name, {s: a[:n] for s, a in val.items()})
        self.n = n


def _stance_speed(plan, ref: Reference) -> dict[str, float]:
    out = {}
    for s in SIDES:
        st = plan.motion.contact[s]
        speed = np.linalg.norm(ref.foot_va[s][:, 0, :3], axis=1)
        out[s] = float(speed[st].max()) if st.any() else 0.0
    return out


def _finish(robot, sim, plan, ref, rec, demo_forces, fall, fails, ms, dt, period
            ) -> SimResult:
    m = robot.model
    t = rec.t
    ft, reason = fall_time(t, rec.height, rec.plan_height, rec.tilt, fall)
    mg = robot.mass * float(np.linalg.norm(m.gravity.linear))
    min_force = 0.01 * mg
    slips = []
    for s in SIDES:
        slips += stance_slip(t, s, rec.sole_xy[s], rec.stance[s],
                             rec.wrench_world[s][:, 2] > min_force)
    cop, margin = {}, {}
    for s in SIDES:
        cop[s], margin[s] = cop_and_margin(sim.contacts[s], rec.wrench_sole[s], min_force)
    loaded = {s: rec.wrench_world[s][:, 2] > min_force for s in SIDES}
    plan_loaded = {s: rec.stance[s] & (rec.plan_force[s][:, 2] > min_force) for s in SIDES}
    single = {"left": rec.stance["left"] & ~rec.stance["right"],
              "right": rec.stance["right"] & ~rec.stance["left"]}
    vs_plan = {s: direction_agreement(rec.wrench_world[s][:, :3], rec.plan_force[s],
                                      loaded[s] & plan_loaded[s], single[s]) for s in SIDES}
    vs_demo, demo = None, None
    if demo_forces is not None:
        demo, present = _demo_on_grid(demo_forces, t)
        vs_demo = {s: direction_agreement(rec.wrench_world[s][:, :3], demo[s],
                                          loaded[s] & present[s], single[s]) for s in SIDES}
    act_names = tuple(m.names[j] for j in sim.actuated)
    sat, per = saturation_fraction(rec.tau, sim.effort)
    dq = np.array([pin.difference(m, qp, qs) for qp, qs in zip(rec.plan_q, rec.q)])
    dqa = dq[:, sim.idx_v_act] if dq.size else np.zeros((0, sim.idx_v_act.size))
    per_joint = np.sqrt(np.mean(dqa**2, axis=0)) if dqa.size else np.full(len(act_names), np.nan)
    base_err = _base_position_error(robot, rec)
    metrics = SimMetrics(
        fell=ft is not None, fall_time=ft, fall_reason=reason, criteria=fall,
        slip=tuple(slips),
        slip_max=max((x.slip for x in slips if np.isfinite(x.slip)), default=0.0),
        force_vs_plan=vs_plan, force_vs_demo=vs_demo,
        cop_margin_min={s: float(np.nanmin(margin[s])) if np.any(np.isfinite(margin[s]))
                        else float("nan") for s in SIDES},
        torque_saturation=sat,
        torque_saturation_per_joint={n: float(x) for n, x in zip(act_names, per)},
        joint_rmse=float(np.sqrt(np.mean(dqa**2))) if dqa.size else float("nan"),
        joint_rmse_per_joint={n: float(x) for n, x in zip(act_names, per_joint)},
        base_position_rmse=base_err, qp_failures=int(fails), ms_per_step=float(ms[0]),
        cpu_ms_per_step=float(ms[1]),
        plan_stance_foot_speed_max=_stance_speed(plan, ref))
    mo = plan.motion
    return SimResult(
        t=t, q=rec.q, v=rec.v, tau=rec.tau,
        contact_forces={s: rec.wrench_world[s][:, :3].copy() for s in SIDES},
        contact_wrenches=rec.wrench_sole, cop=cop, cop_margin=margin, plan_q=rec.plan_q,
        plan_stance=rec.stance, plan_forces=rec.plan_force, qp_wrenches=rec.qp_wrench,
        demo_forces=demo, metrics=metrics, dt=float(dt), control_period=float(period),
        joint_names=robot.joint_names, actuated=act_names, effort=sim.effort.copy(),
        base_height=rec.height, plan_base_height=rec.plan_height, tilt=rec.tilt,
        base_nq=mo.base_nq,
        joint_nq=mo.joint_nq)


def _base_position_error(robot: Robot, rec: _Recorder) -> float:
    if rec.t.size == 0:
        return float("nan")
    if robot.base == "free":
        e = rec.q[:, :3] - rec.plan_q[:, :3]
    else:
        cols = [robot.idx_q("base_x"), robot.idx_q("base_z")]
        e = rec.q[:, cols] - rec.plan_q[:, cols]
    return float(np.sqrt(np.mean(np.sum(e**2, axis=1))))
