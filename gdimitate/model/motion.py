"""``Motion``: a robot's joint trajectory on a time grid, with its feet's contact schedule."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InvalidInputError, TimeGridError, UnknownNameError

__all__ = ["Motion", "RobotRecord", "check_base_quaternion", "check_motion_layout",
           "check_time", "differentiate", "robot_layout"]

#: Largest |norm − 1| of a free-flyer's base quaternion read from a file (float32 rounding
#: is ~1e-7; a quaternion of another norm is not a rotation).
QUATERNION_TOL = 1e-5


def _floats(name: str, x: object, error: type[InvalidInputError] = InvalidInputError
            ) -> np.ndarray:
    """``x`` as a float array, or ``error`` naming ``name`` (an object array, strings, a
    ragged list, complex numbers)."""
    if isinstance(x, str | bytes | Mapping) or (
            isinstance(x, np.ndarray) and x.dtype.kind not in "biuf"):
        kind = x.dtype if isinstance(x, np.ndarray) else type(x).__name__
        raise error(f"{name} must be an array of real numbers; got {kind}")
    try:
        with np.errstate(all="ignore"):
            a = np.asarray(x)
            if a.dtype.kind not in "biuf":
                raise TypeError(a.dtype)
            return a.astype(float)
    except (TypeError, ValueError, OverflowError) as e:
        raise error(f"{name} must be an array of real numbers; got {type(x).__name__} "
                    f"({str(e)[:80]})") from None


def check_time(t: np.ndarray) -> np.ndarray:
    """Validate a time grid: 1-D, at least 2 samples, finite, strictly increasing [s]."""
    t = _floats("time", t, TimeGridError)
    if t.ndim != 1 or t.size < 2:
        raise TimeGridError(f"time must be a 1-D array of at least 2 samples; got shape {t.shape}")
    if not np.all(np.isfinite(t)):
        raise TimeGridError(f"time has NaN/inf at index {int(np.flatnonzero(~np.isfinite(t))[0])}")
    bad = np.flatnonzero(np.diff(t) <= 0)
    if bad.size:
        i = int(bad[0])
        raise TimeGridError(
            f"time must be strictly increasing; t[{i}]={t[i]!r} ≥ t[{i + 1}]={t[i + 1]!r}")
    return t


def check_base_quaternion(q: np.ndarray, base_nq: int, where: object) -> None:
    """Refuse a free-flyer motion ``q (T, nq)`` (``base_nq == 7``: x, y, z, qx, qy, qz, qw)
    whose base quaternion is not of unit norm (within :data:`QUATERNION_TOL`) in some frame:
    a zero quaternion is no orientation, and Pinocchio and MuJoCo would compute on NaN."""
    if base_nq != 7 or q.ndim != 2 or q.shape[1] < 7:
        return
    norm = np.linalg.norm(q[:, 3:7], axis=1)
    bad = np.flatnonzero(~(np.abs(norm - 1.0) <= QUATERNION_TOL))
    if bad.size:
        k = int(bad[0])
        raise InvalidInputError(
            f"{where}: the base quaternion (q columns 3–6: qx, qy, qz, qw) has norm "
            f"{norm[k]:.6g} at frame {k} ({bad.size} of {len(q)} frames are not unit "
            "quaternions); a free-flyer's orientation must be a unit quaternion — normalise "
            "it (a zero quaternion is no orientation)")


def robot_layout(robot) -> tuple[int, tuple[int, ...]]:
    """``(base_nq, joint_nq)`` of a :class:`~gdimitate.Robot`, from its Pinocchio model: the
    floating base's columns (7 free-flyer, 3 our planar base, 0 fixed) and each joint's."""
    m = robot.model
    base_nq = {"free": 7, "planar": 3}.get(str(robot.base), 0)
    return base_nq, tuple(int(m.joints[j].nq) for j in range(1, m.njoints))


#: Pinocchio joints whose configuration holds a unit-norm part: (first column, width) within
#: the joint's columns (a free-flyer's quaternion, a spherical joint's, an unbounded
#: revolute's cos/sin, a planar joint's cos/sin).
_UNIT_PARTS = {"JointModelFreeFlyer": (3, 4), "JointModelSpherical": (0, 4),
               "JointModelSphericalZYX": None, "JointModelPlanar": (2, 2)}


def _unit_parts(model) -> list[tuple[str, int, int]]:
    """``(joint name, first q column, width)`` of every unit-norm part of ``model``'s q."""
    out = []
    for j in range(1, model.njoints):
        jm = model.joints[j]
        short = jm.shortname()
        part = _UNIT_PARTS.get(short)
        if part is None and (short.startswith("JointModelRUB")
                             or "RevoluteUnbounded" in short):  # unbounded revolute
            part = (0, 2)
        if part is not None:
            out.append((str(model.names[j]), int(jm.idx_q) + part[0], part[1]))
    return out


def check_motion_layout(robot, motion: Motion, where: object,
                        error: type[InvalidInputError] = InvalidInputError,
                        recorded: bool = True) -> Motion:
    """``motion`` with the base layout of ``robot``'s model, refused unless it fits the robot
    — the same joints, each joint's q columns and ``v``/``a`` of width ``nv`` (``error``
    naming ``where``) — and unless every unit-norm part of q (a free-flyer's or spherical
    joint's quaternion, an unbounded revolute's cos/sin), found from the robot's model, has
    norm 1 within :data:`QUATERNION_TOL` in every frame (:class:`InvalidInputError` naming
    the joint and the frame). ``base_nq`` comes from the robot model, never from a file: a
    file's ``base_nq=0`` used to skip the quaternion check. ``recorded`` (a motion read from a
    file): a recorded ``base_nq`` that says free-flyer for a robot without one, or the reverse,
    is refused too (our planar base's three 1-DoF columns may be recorded as 0 or 3)."""
    base_nq, joint_nq = robot_layout(robot)
    if tuple(robot.joint_names) != motion.joint_names:
        raise error(f"{where}: the motion's joints {list(motion.joint_names)[:6]}… are not "
                    f"robot {robot.name!r}'s {list(robot.joint_names)[:6]}…")
    if motion.joint_nq != joint_nq or (recorded and (motion.base_nq == 7) != (base_nq == 7)):
        raise error(f"{where}: the motion records base_nq = {motion.base_nq} and joint_nq "
                    f"{list(motion.joint_nq)[:8]}…, robot {robot.name!r} has base_nq = "
                    f"{base_nq} ({robot.base} base) and joint_nq {list(joint_nq)[:8]}…: the "
                    "motion's layout is not its robot's")
    nv = int(robot.model.nv)
    for name in ("v", "a"):
        x = getattr(motion, name)
        if x is not None and x.shape[1] != nv:
            raise error(f"{where}: {name} has {x.shape[1]} columns; robot {robot.name!r} has "
                        f"nv = {nv}")
    for joint, c, w in _unit_parts(robot.model):
        norm = np.linalg.norm(motion.q[:, c:c + w], axis=1)
        bad = np.flatnonzero(~(np.abs(norm - 1.0) <= QUATERNION_TOL))
        if bad.size:
            k = int(bad[0])
            what = "quaternion" if w == 4 else "(cos, sin) pair"
            raise InvalidInputError(
                f"{where}: joint {joint!r}: its {what} (q columns {c}–{c + w - 1}) has norm "
                f"{norm[k]:.6g} at frame {k} ({bad.size} of {motion.T} frames are not of unit "
                "norm); it must be of unit norm — normalise it (a zero quaternion is no "
                "orientation)")
    return motion if motion.base_nq == base_nq else motion.replace(base_nq=base_nq)


@dataclass(frozen=True)
class Motion:
    """A joint trajectory of one robot.

    - ``t`` ``(T,)`` [s], strictly increasing;
    - ``joint_names``: the robot's joints in Pinocchio order (without ``universe``);
    - ``q`` ``(T, nq)``: full Pinocchio configurations in that order [rad, m] — the floating base
      first where present (free-flyer: x, y, z, qx, qy, qz, qw; our planar models: ``base_x``,
      ``base_z``, ``base_pitch``), see :attr:`base`;
    - ``contact``: ``{"left": (T,) bool, "right": (T,) bool}``, True while the foot is in stance;
    - ``base_nq``: how many leading columns of ``q`` are the floating base (0, 3 or 7);
    - ``joint_nq``: columns per joint (same length as ``joint_names``);
    - ``v``, ``a`` ``(T, nv)`` or ``None``: velocity and acceleration in Pinocchio's
      conventions (a free-flyer's base twist in the base's LOCAL frame, linear first), where
      the motion carries them (an adaptor's output does; :func:`differentiate` adds them to a
      recorded one).
    """

    t: np.ndarray
    joint_names: tuple[str, ...]
    q: np.ndarray
    contact: Mapping[str, np.ndarray] = field(default_factory=dict)
    base_nq: int = 0
    joint_nq: tuple[int, ...] = ()
    v: np.ndarray | None = None
    a: np.ndarray | None = None

    def __post_init__(self) -> None:
        t = check_time(self.t)
        q = _floats("q", self.q)
        if isinstance(self.joint_names, str | bytes) or not all(
                isinstance(n, str) for n in self.joint_names):
            raise InvalidInputError(f"joint_names must be a sequence of str; got "
                                    f"{self.joint_names!r:.80}")
        names = tuple(self.joint_names)
        nqs = tuple(self.joint_nq) if len(self.joint_nq) else (1,) * len(names)
        if not all(isinstance(k, int | np.integer) and not isinstance(k, bool) and 1 <= k <= 7
                   for k in nqs):
            raise InvalidInputError(f"joint_nq must be integers 1…7 (columns of q per joint); "
                                    f"got {nqs!r:.80}")
        nqs = tuple(int(k) for k in nqs)
        if len(nqs) != len(names):
            raise InvalidInputError(f"joint_nq has {len(nqs)} entries for {len(names)} joints")
        if isinstance(self.base_nq, bool) or self.base_nq not in (0, 3, 7):
            raise InvalidInputError(f"base_nq must be 0 (fixed base), 3 (planar) or 7 "
                                    f"(free-flyer); got {self.base_nq!r:.40}")
        object.__setattr__(self, "base_nq", int(self.base_nq))
        if q.ndim != 2 or q.shape != (t.size, sum(nqs)):
            raise InvalidInputError(
                f"q must have shape (T, nq) = ({t.size}, {sum(nqs)}); got {q.shape}")
        if not np.all(np.isfinite(q)):
            r, c = np.argwhere(~np.isfinite(q))[0]
            raise InvalidInputError(f"q has NaN/inf at frame {r}, column {c}")
        contact = {}
        if not isinstance(self.contact, Mapping):
            raise InvalidInputError(f"contact must be a dict {{side: (T,) bool}}; got "
                                    f"{type(self.contact).__name__}")
        for side, c in dict(self.contact).items():
            c = _floats(f"contact[{side!r}]", c).astype(bool)
            if c.shape != t.shape:
                raise InvalidInputError(
                    f"contact[{side!r}] must have shape {t.shape}; got {c.shape}")
            contact[side] = c
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "q", q)
        object.__setattr__(self, "joint_names", names)
        object.__setattr__(self, "joint_nq", nqs)
        object.__setattr__(self, "contact", contact)
        for name in ("v", "a"):
            x = getattr(self, name)
            if x is None:
                continue
            x = _floats(name, x)
            if x.ndim != 2 or x.shape[0] != t.size:
                raise InvalidInputError(f"{name} must have shape (T, nv) with T = {t.size}; "
                                        f"got {x.shape}")
            if not np.all(np.isfinite(x)):
                r, c = np.argwhere(~np.isfinite(x))[0]
                raise InvalidInputError(f"{name} has NaN/inf at frame {r}, column {c}")
            object.__setattr__(self, name, x)

    # ------------------------------------------------------------------
    @property
    def T(self) -> int:
        """Number of frames."""
        return int(self.t.size)

    @property
    def dt(self) -> float:
        """Median time step [s]."""
        return float(np.median(np.diff(self.t)))

    @property
    def base(self) -> np.ndarray | None:
        """Floating-base trajectory ``(T, base_nq)`` or ``None`` for a fixed base."""
        return self.q[:, : self.base_nq] if self.base_nq else None

    def column(self, joint: str) -> np.ndarray:
        """Trajectory ``(T,)`` of a 1-DoF joint (``(T, k)`` for a k-column joint)."""
        try:
            i = self.joint_names.index(joint)
        except ValueError:
            raise UnknownNameError("joint", joint, self.joint_names) from None
        start = sum(self.joint_nq[:i])
        k = self.joint_nq[i]
        return self.q[:, start] if k == 1 else self.q[:, start : start + k]

    def velocity(self) -> np.ndarray:
        """Finite-difference joint velocity ``(T, nq)`` of q's columns [rad/s, m/s]
        (central differences, one-sided at the ends; quaternion columns differentiated as
        numbers)."""
        return np.gradient(self.q, self.t, axis=0)

    def derivatives(self, who: str) -> tuple[np.ndarray, np.ndarray]:
        """``(v, a)``, each ``(T, nv)`` [rad/s, m/s; rad/s², m/s²], or
        :class:`~gdimitate.errors.InvalidInputError` saying that ``who`` needs them and how to
        add them."""
        if self.v is None or self.a is None:
            raise InvalidInputError(
                f"{who} needs the motion's velocity and acceleration (motion.v, motion.a); add "
                "them with gdimitate.model.motion.differentiate(robot.model, motion, "
                "cutoff_hz=...)")
        return self.v, self.a

    def replace(self, **changes) -> Motion:
        """A copy with some fields replaced."""
        d: dict[str, Any] = dict(t=self.t, joint_names=self.joint_names, q=self.q,
                                 contact=self.contact, base_nq=self.base_nq,
                                 joint_nq=self.joint_nq, v=self.v, a=self.a)
        d.update(changes)
        return Motion(**d)

    def to_npz(self, path, robot=None, extra: Mapping[str, np.ndarray] | None = None) -> None:
        """Save as NPZ: ``t``, ``q``, ``joint_names``, ``joint_nq``, ``base_nq``,
        ``contact_left``, ``contact_right``, and ``v``, ``a`` where the motion has them.

        ``robot``: the :class:`~gdimitate.Robot` the motion belongs to; its
        :class:`RobotRecord` (``robot_name``, ``robot_kind``, ``robot_source`` — library
        name or model file path —, ``robot_urdf``, ``robot_fingerprint``,
        ``robot_package_dir``, ``robot_legs``, ``robot_contacts``) is stored so that the
        file is read back without naming the robot
        (:func:`gdimitate.io.demonstration.load_demonstration`). ``extra``: more arrays to store
        (e.g. ``wrench_left``); their names must not clash."""
        arrays: dict[str, Any] = dict(t=self.t, q=self.q,
                                      joint_names=np.array(self.joint_names),
                      joint_nq=np.array(self.joint_nq), base_nq=self.base_nq,
                      **{f"contact_{k}": v for k, v in self.contact.items()})
        for name in ("v", "a"):
            if getattr(self, name) is not None:
                arrays[name] = getattr(self, name)
        if robot is not None:
            if tuple(robot.joint_names) != self.joint_names:
                raise InvalidInputError(
                    f"robot {robot.name!r} has joints {list(robot.joint_names)[:6]}…, the "
                    f"motion {list(self.joint_names)[:6]}…: not this motion's robot")
            arrays.update(RobotRecord.of(robot).arrays())
        for k, v in dict(extra or {}).items():
            if k in arrays:
                raise InvalidInputError(f"extra array {k!r} clashes with a motion key")
            arrays[k] = np.asarray(v)
        np.savez(path, **arrays)

    @classmethod
    def from_npz(cls, path) -> Motion:
        """Load what :meth:`to_npz` wrote.

        Raises:
            FileFormatError: no such file, not an NPZ archive (empty, a CSV renamed ``.npz``,
                pickled objects, larger than :data:`gdimitate.safety.MAX_NPZ_BYTES` unpacked)
                or a key missing; the message names the file.
            InvalidInputError: arrays that do not make a valid motion (among them a
                free-flyer base quaternion that is not of unit norm,
                :func:`check_base_quaternion`).
        """
        from ..errors import FileFormatError
        from ..safety import open_npz

        with open_npz(path, ("t", "q", "joint_names", "joint_nq", "base_nq")) as z:
            contact = {k[8:]: z[k] for k in z.files if k.startswith("contact_")}
            layout = {}
            for key in ("joint_names", "joint_nq", "base_nq"):
                x = z[key]
                kinds = "U" if key == "joint_names" else "iu"
                if x.dtype.kind not in kinds or x.ndim != (0 if key == "base_nq" else 1):
                    raise FileFormatError(
                        f"{path}: {key!r} must be a {'scalar' if key == 'base_nq' else '1-D'} "
                        f"array of {'str' if kinds == 'U' else 'integers'}; got dtype "
                        f"{x.dtype}, shape {x.shape}")
                layout[key] = x
            try:
                motion = cls(t=z["t"], joint_names=tuple(str(s) for s in layout["joint_names"]),
                             q=z["q"], contact=contact, base_nq=int(layout["base_nq"]),
                             joint_nq=tuple(int(i) for i in layout["joint_nq"]),
                             v=z["v"] if "v" in z.files else None,
                             a=z["a"] if "a" in z.files else None)
            except InvalidInputError as e:  # name the file (TimeGridError stays one)
                raise type(e)(f"{path}: {e}") from None
        first = motion.joint_nq[0] if motion.joint_nq else 0
        if (first == 7) != (motion.base_nq == 7) or (
                motion.base_nq == 3 and motion.joint_nq[:3] != (1, 1, 1)):
            raise FileFormatError(
                f"{path}: base_nq = {motion.base_nq} contradicts joint_nq "
                f"{list(motion.joint_nq)[:4]}… (a free-flyer is one joint of 7 columns, base_nq "
                "7; our planar base three of 1, base_nq 3): the file's layout is inconsistent")
        for name in ("v", "a"):
            x = getattr(motion, name)
            if x is not None and x.shape[1] > motion.q.shape[1]:
                raise FileFormatError(f"{path}: {name} has {x.shape[1]} columns, more than q's "
                                      f"{motion.q.shape[1]} (nv ≤ nq)")
        if motion.v is not None and motion.a is not None and motion.v.shape != motion.a.shape:
            raise FileFormatError(f"{path}: v {motion.v.shape} and a {motion.a.shape} differ in "
                                  "shape")
        check_base_quaternion(motion.q, max(motion.base_nq, 7 if first == 7 else 0), path)
        return motion

    def to_csv(self, path, columns: list[str] | None = None) -> None:
        """Write ``time`` and 1-DoF joint columns (all by default) as CSV [s, rad]."""
        cols = columns or [n for n, k in zip(self.joint_names, self.joint_nq) if k == 1]
        data = np.column_stack([self.t] + [self.column(c) for c in cols])
        np.savetxt(path, data, delimiter=",", header=",".join(["time", *cols]), comments="",
                   fmt="%.9g")


_RECORD_KINDS = ("library", "urdf", "osim", "bvh", "memory")


@dataclass(frozen=True)
class RobotRecord:
    """What a motion file records about its robot (keys ``robot_<field>`` in the NPZ).

    ``name``; ``kind``: ``"library"`` (``source`` = the library name), ``"urdf"``,
    ``"osim"`` or ``"bvh"`` (``source`` = the model or BVH file's absolute path) or
    ``"memory"`` (a model built in memory: it cannot be rebuilt from the file);
    ``fingerprint``: :attr:`Robot.fingerprint`; ``package_dir``: the URDF's package folder
    (``""`` for none); ``legs``/``contacts``: JSON of the ``legs=``/``contacts=`` given to
    :meth:`Robot.load` (``""`` when detected); ``urdf``: the URDF file the model was read
    from (``""`` for in-memory models; for ``.osim``/``.bvh`` robots a converted file that
    may be temporary); ``massless``: JSON list of the ``massless_joints=`` given to
    :meth:`Robot.load` (``""`` for none; a library robot's presets are not repeated)."""

    name: str
    kind: str
    source: str
    fingerprint: str
    package_dir: str = ""
    legs: str = ""
    contacts: str = ""
    urdf: str = ""
    massless: str = ""

    @classmethod
    def of(cls, robot) -> RobotRecord:
        """The record of a :class:`~gdimitate.Robot`."""
        import json

        from .library import list_robots

        def plain(x):  # a SoleContact → its fields
            return {k: getattr(x, k) for k in ("frame", "half_length", "half_width", "mu")}

        given = getattr(robot, "load_args", None) or {}
        legs = json.dumps(given["legs"]) if given.get("legs") is not None else ""
        contacts = (json.dumps(given["contacts"], default=plain)
                    if given.get("contacts") is not None else "")
        pkg = str(Path(robot.package_dir).resolve()) if robot.package_dir else ""
        if getattr(robot, "osim", None) is not None and robot.osim.model.path is not None:
            kind, source = "osim", str(Path(robot.osim.model.path).resolve())
        elif getattr(robot, "bvh_info", None) is not None:
            kind, source = "bvh", str(Path(robot.bvh_info.path).resolve())
        elif robot.name in list_robots() and given.get("spec", robot.name) == robot.name:
            kind, source = "library", robot.name
        elif robot.urdf_path is not None:
            kind, source = "urdf", str(Path(robot.urdf_path).resolve())
        else:
            kind, source = "memory", ""
        urdf = str(Path(robot.urdf_path).resolve()) if robot.urdf_path else ""
        massless = (json.dumps(list(given["massless_joints"]))
                    if given.get("massless_joints") else "")
        return cls(robot.name, kind, source, robot.fingerprint, pkg, legs, contacts, urdf,
                   massless)

    def arrays(self) -> dict[str, np.ndarray]:
        """The NPZ entries (``robot_<field>`` → 0-d string array)."""
        return {f"robot_{k}": np.array(getattr(self, k))
                for k in ("name", "kind", "source", "fingerprint", "package_dir", "legs",
                          "contacts", "urdf", "massless")}

    @classmethod
    def from_npz(cls, path) -> RobotRecord | None:
        """The record stored in an NPZ motion file, or ``None`` if it has none (a file
        written without ``robot=``)."""
        from ..safety import open_npz

        with open_npz(path) as z:
            if "robot_name" not in z.files:
                return None
            rec = cls(**{k: str(z[f"robot_{k}"]) for k in
                         ("name", "kind", "source", "fingerprint", "package_dir", "legs",
                          "contacts", "urdf", "massless") if f"robot_{k}" in z.files})
        if rec.kind not in _RECORD_KINDS:
            raise InvalidInputError(f"{path}: robot_kind {rec.kind!r} is not one of "
                                    f"{_RECORD_KINDS}")
        return rec


#: Degree of the least-squares polynomial that extends a motion past its ends before the
#: low-pass filter (cubic: the acceleration keeps its local slope instead of the odd
#: reflection's zero at the edge).
EDGE_DEGREE = 3


def _extend_ends(q: np.ndarray, t: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """``q`` ``(T, nq)`` on ``t`` ``(T,)`` extended by ``n`` frames at each end ``→ (T + 2n,
    nq), (T + 2n,)``: each end continues the cubic least-squares fit to its own last ``n``
    frames (at least ``EDGE_DEGREE + 2``, at most ``T``), on the median time step."""
    h = float(np.median(np.diff(t)))
    w = min(max(n, EDGE_DEGREE + 2), t.size)
    ends = []
    for sl, tnew in ((slice(0, w), t[0] - h * np.arange(n, 0, -1)),
                     (slice(t.size - w, t.size), t[-1] + h * np.arange(1, n + 1))):
        t0 = t[sl][0]
        coef = np.linalg.lstsq(np.vander(t[sl] - t0, EDGE_DEGREE + 1), q[sl], rcond=None)[0]
        ends.append((np.vander(tnew - t0, EDGE_DEGREE + 1) @ coef, tnew))
    return (np.vstack([ends[0][0], q, ends[1][0]]), np.concatenate([ends[0][1], t, ends[1][1]]))


def differentiate(model, motion: Motion, cutoff_hz: float | None = None) -> Motion:
    """``motion`` with ``v`` and ``a`` ``(T, nv)`` from its ``q`` in Pinocchio's conventions.

    ``model``: the robot's ``pin.Model``. Velocities are central differences on the manifold
    (``pin.difference`` between the neighbours, divided by their time gap), accelerations the
    same differences of ``v`` (free-flyer twists differenced as vectors in the base frame, an
    O(h) approximation of the exact one). ``cutoff_hz``: first low-pass ``q``'s columns with a
    zero-phase 4th-order Butterworth filter at that frequency [Hz] (OpenSim's
    inverse-dynamics tool filters coordinates at 6 Hz), the base quaternion re-normalised.
    Filtered, the clip's edges are handled by extending it first by ``n = round(2·fs/cutoff)``
    frames (one third of a second at 6 Hz) at each end — a cubic least-squares fit to the
    ``n`` frames nearest each end, continued — then filtering, differencing centrally across
    the edge and cutting the extension off (a zero-phase filter's own odd-reflection padding
    forces the acceleration at the edge to zero: the `dynamics` push estimate of a single
    support at a clip's edge was off by up to r = 0.79 against the measured forces).
    Unfiltered, the ends are one-sided differences.
    """
    import pinocchio as pin

    q = motion.q.copy()
    t = motion.t
    if q.shape[1] != model.nq:
        raise InvalidInputError(f"motion has {q.shape[1]} q columns; the model has nq = "
                                f"{model.nq}")
    n = 0
    if cutoff_hz is not None:
        from scipy.signal import butter, filtfilt

        fs = 1.0 / float(np.median(np.diff(t)))
        if not (0 < cutoff_hz < fs / 2):
            raise InvalidInputError(f"cutoff_hz must be in (0, {fs / 2:g}) Hz for a "
                                    f"{fs:g} Hz motion; got {cutoff_hz!r}")
        if t.size <= 15:
            raise InvalidInputError("a filtered motion needs more than 15 frames")
        n = max(1, int(round(2.0 * fs / cutoff_hz)))
        q, t = _extend_ends(q, t, n)
        b, a_ = butter(4, cutoff_hz / (fs / 2))
        q = filtfilt(b, a_, q, axis=0)
        if motion.base_nq == 7:
            q[:, 3:7] /= np.linalg.norm(q[:, 3:7], axis=1, keepdims=True)
    T = t.size

    def diff(i: int, j: int, x=None) -> np.ndarray:
        if x is None:
            return pin.difference(model, q[i], q[j]) / (t[j] - t[i])
        return (x[j] - x[i]) / (t[j] - t[i])

    idx = [(max(k - 1, 0), min(k + 1, T - 1)) for k in range(T)]
    v = np.array([diff(i, j) for i, j in idx])
    acc = np.array([diff(i, j, v) for i, j in idx])
    keep = slice(n, T - n)
    return motion.replace(q=q[keep], v=v[keep], a=acc[keep])
