"""``Robot``: a Pinocchio model with its legs and soles, for any leg joint axes.

Each leg is named by its hip, knee and ankle joints and its sole frame (detected from the
model's names and chains, or given: :mod:`gdimitate.model.legs`) and measured at the neutral pose
(:class:`~gdimitate.model.legs.Leg`). The robot's own "forward/left/up" is measured too (legs point
down, the left hip is on the left), so Y-up models such as example-robot-data's ``human`` or
iCub (x backwards) are turned to face +x with z up by a constant base rotation
:attr:`Robot.base_rotation`. The soles' rectangles are measured from the feet's geometry
(:func:`gdimitate.model.contact.sole_contacts`).

Nothing here asks a leg to move in the sagittal plane: the paper's planar measurements (joint
signs and offsets for Eq. (1)) are :func:`gdimitate.planar.sagittal_leg`'s, computed when asked.
Loading from files is :mod:`gdimitate.model.loading`'s (the ``from_*``/``load`` class methods),
the URDF checks :mod:`gdimitate.model.urdfcheck`'s.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from ..errors import ContactError, UnknownNameError
from ..types import BaseKind
from . import loading
from .contact import SoleContact, sole_contacts
from .legs import (
    LEG_PRESETS,
    SIDES,
    Leg,
    measure_leg,
    measure_orientation,
    resolve_leg_names,
    sole_from_geometry,
)
from .library import MASSLESS_PRESETS
from .urdfcheck import INERTIA_TOL, check_urdf_joints, check_urdf_physics
from .urdfgen import PLANAR_BASE, PlanarBipedSpec

#: ``Leg``, ``SIDES``, ``PLANAR_BASE``, the presets and the URDF checks are re-exported (their
#: homes: :mod:`gdimitate.model.legs`, :mod:`gdimitate.model.kinematics`,
#: :mod:`gdimitate.model.library`,
#: :mod:`gdimitate.model.urdfcheck`)
__all__ = ["INERTIA_TOL", "LEG_PRESETS", "Leg", "MASSLESS_PRESETS", "PLANAR_BASE", "Robot",
           "SIDES", "base_kind", "check_urdf_joints", "check_urdf_physics"]

LegNames = Mapping[str, Mapping[str, str | None]]


def base_kind(model: pin.Model) -> BaseKind:
    """``"planar"`` (our ``base_x``, ``base_z``, ``base_pitch`` joints), ``"free"`` (a
    free-flyer root joint) or ``"fixed"``."""
    names = list(model.names)[1:]
    if all(b in names for b in PLANAR_BASE):
        return "planar"
    if model.njoints > 1 and model.joints[1].shortname() == "JointModelFreeFlyer":
        return "free"
    return "fixed"


class Robot:
    """A robot model (Pinocchio) with its legs and soles, any leg joint axes.

    Attributes: ``name``; ``model``/``data`` (``pin.Model``/``pin.Data``); ``visual_model``
    (``pin.GeometryModel`` or ``None`` when the URDF has no visual geometry); ``legs``
    (``{"left": Leg, "right": Leg}``); ``base`` (:data:`~gdimitate.types.BaseKind`:
    ``"planar"``, ``"free"`` or ``"fixed"``; :attr:`floating`); ``base_rotation`` (3×3, turns
    the model to face +x with z up); ``neutral`` (``(nq,)``, the neutral pose standing on
    z = 0); ``package_dir``; ``urdf_path`` (``None`` for in-memory models); ``contacts``
    (``{"left": SoleContact, "right": SoleContact}``, the flat-foot contacts of
    :mod:`gdimitate.model.contact`, measured from the feet's geometry unless given; empty for
    point-footed robots such as Bolt; ``contact_problems`` says why a foot has none);
    ``collision_model`` (``pin.GeometryModel`` or ``None``).

    ``contacts=`` overrides the measured soles: per side a :class:`~gdimitate.contact.SoleContact`
    or a mapping with ``half_length``, ``half_width`` [m] and optionally ``frame`` (default: the
    measured sole centre) and ``mu`` (default :data:`~gdimitate.contact.DEFAULT_MU`).
    """

    base: BaseKind
    spec: PlanarBipedSpec
    osim: Any
    bvh_info: Any
    load_args: dict[str, Any]

    def __init__(self, name: str, model: pin.Model, visual_model: pin.GeometryModel | None,
                 legs: LegNames | None = None,
                 package_dir: Path | None = None, urdf_path: Path | None = None,
                 contacts: Mapping[str, SoleContact | Mapping] | None = None,
                 collision_model: pin.GeometryModel | None = None):
        self.name = name
        self.model = model
        self.data = model.createData()
        has_geometry = visual_model is not None and visual_model.ngeoms > 0
        self.visual_model = visual_model if has_geometry else None
        has_collision = collision_model is not None and collision_model.ngeoms > 0
        self.collision_model = collision_model if has_collision else None
        self.package_dir = package_dir
        self.urdf_path = urdf_path
        self.base = base_kind(model)
        names = resolve_leg_names(self, legs)
        self.base_rotation = measure_orientation(self, names)
        for s in SIDES:
            names[s]["sole"] = sole_from_geometry(self, s, names[s])
        self.legs: dict[str, Leg] = {s: measure_leg(self, s, names[s]) for s in SIDES}
        self.neutral = self._grounded_neutral()
        self.contacts, self.contact_problems = sole_contacts(self, contacts)
        if self.contacts:
            self.neutral = self._ground(self.neutral, [c.frame for c in self.contacts.values()])

    # ------------------------------------------------------------------ loading
    @classmethod
    def from_urdf(cls, path: str | Path, legs: LegNames | None = None, *,
                  name: str | None = None,
                  package_dir: str | Path | Sequence[str | Path] | None = None,
                  floating: bool | None = None,
                  contacts: Mapping[str, SoleContact | Mapping] | None = None,
                  massless_joints: Iterable[str] = ()) -> Robot:
        """Load a URDF. ``legs``: ``{"left": {"hip":…, "knee":…, "ankle":…, "sole":…},
        "right": {…}}`` (joint/frame names), auto-detected from names when omitted.

        ``floating``: add a free-flyer root joint (default: yes, unless the URDF already has
        our planar base joints). ``package_dir``: folder (or folders) resolving
        ``package://`` meshes (default: the URDF's folder). ``contacts``: sole rectangles
        overriding the measured ones (see :class:`Robot`). ``massless_joints``: moving joints
        whose subtree may be massless (see :func:`check_urdf_physics`).

        Before Pinocchio reads the file it is checked (``docs/security.md``): its size, link
        count and depth (:mod:`gdimitate.safety`), its inertial data
        (:func:`check_urdf_physics`), and every mesh reference, which must resolve inside the
        URDF's folder or a package directory (:func:`gdimitate.model.meshes.confine_meshes`).

        Raises:
            URDFError: naming the file and the link or mesh at fault
                (:class:`~gdimitate.errors.MeshPathError`,
                :class:`~gdimitate.errors.URDFLimitError` for the specific cases).
        """
        return loading.from_urdf(cls, path, legs, name=name, package_dir=package_dir,
                                 floating=floating, contacts=contacts,
                                 massless_joints=massless_joints)

    @classmethod
    def from_osim(cls, path: str | Path, *, name: str | None = None,
                  markers: Any = None) -> Robot:
        """An OpenSim model (``.osim``, 3.x or 4.x) converted by
        :func:`gdimitate.io.opensim.convert_osim` (into a temporary folder that is removed once
        the URDF is loaded: :attr:`urdf_path` is ``None``; write the URDF yourself with
        :func:`gdimitate.io.opensim.opensim_to_urdf`) and loaded with a free-flyer. Joint names
        are the OpenSim coordinate names; the legs (hip flexion, knee and ankle joints from the
        model's topology, the sole frame under the ankle) and the sole rectangles (the foot
        boxes) are passed explicitly. The conversion report is kept as ``robot.osim``
        (:class:`~gdimitate.opensim.OsimConversion`). ``markers``: a marker trial of the
        subject (``.trc`` path or ``Markers``) that puts the soles on the lab floor below the
        feet's markers (else they lie at the bones; ``robot.osim.sole_height`` says which).
        Raises :class:`~gdimitate.errors.OsimError` for a model that cannot be converted."""
        return loading.from_osim(cls, path, name=name, markers=markers)

    @classmethod
    def from_spec(cls, spec: PlanarBipedSpec) -> Robot:
        """Build one of our planar bipeds from its spec (the same text ``urdf/`` holds)."""
        return loading.from_spec(cls, spec)

    @classmethod
    def from_library(cls, name: str) -> Robot:
        """A named robot: our planar models (``hoap2``, ``case1_demonstrator``, …) or an
        example-robot-data model (``human``, ``talos``, ``romeo``, ``icub``, ``g1``, ``bolt``).
        :func:`gdimitate.list_robots` lists the names."""
        return loading.from_library(cls, name)

    @classmethod
    def load(cls, spec: str | Path, *, package_dir: str | Path | None = None,
             contacts: Mapping[str, SoleContact | Mapping] | None = None,
             legs: LegNames | None = None, massless_joints: Iterable[str] = ()) -> Robot:
        """A robot from a library name (:func:`gdimitate.list_robots`) or a model file path
        (``.urdf``: :meth:`from_urdf` with ``legs``, ``package_dir``, ``contacts`` and
        ``massless_joints``; ``.osim``: :meth:`from_osim`, whose legs, soles and masses come
        from the model). ``massless_joints``: moving joints allowed to carry no mass (on a
        library robot: added to its presets).

        ``contacts``/``legs`` on a library robot override its presets (its URDF is loaded
        with them). Raises :class:`UnknownRobotError` (listing the names) for a name that is
        neither a library robot nor an existing file, :class:`InvalidInputError` for
        ``legs``/``contacts`` on an ``.osim`` or an unknown extension. The arguments are kept
        as ``robot.load_args`` (motion files record them)."""
        return loading.load(cls, spec, package_dir=package_dir, contacts=contacts, legs=legs,
                            massless_joints=massless_joints)

    @property
    def fingerprint(self) -> str:
        """A short hash (16 hex digits) of the model: joint names and types, joint
        placements, link inertias (mass, centre of mass, rotational inertia) and position,
        velocity and effort limits, rounded to 1e-9 (so a URDF re-read from its text gives the
        same one). Motion files record it to check that they are read with their robot."""
        import hashlib

        m = self.model
        h = hashlib.sha256()
        for j in range(1, m.njoints):
            h.update(f"{m.names[j]}:{m.joints[j].shortname()};".encode())
        arrays = [np.array([X.homogeneous for X in m.jointPlacements]),
                  np.array([[I.mass, *I.lever, *I.inertia.ravel()] for I in m.inertias]),
                  m.lowerPositionLimit, m.upperPositionLimit, m.velocityLimit, m.effortLimit]
        for a in arrays:
            a = np.clip(np.nan_to_num(np.asarray(a, dtype=float)), -1e20, 1e20)
            h.update((np.round(a, 9) + 0.0).tobytes())  # + 0.0: no negative zeros
        return h.hexdigest()[:16]

    # ------------------------------------------------------------------ standing
    def require_contacts(self) -> dict[str, SoleContact]:
        """:attr:`contacts` of both feet, or :class:`ContactError` saying why a foot has none
        and how to pass ``contacts=``."""
        missing = [s for s in SIDES if s not in self.contacts]
        if missing:
            why = "; ".join(self.contact_problems.get(s, f"the {s} leg has no ankle (point foot)")
                            for s in missing)
            raise ContactError(f"{self.name}: no flat-foot contact for {missing}: {why}")
        return self.contacts

    @property
    def floating(self) -> bool:
        """Whether the base moves (a free-flyer or our planar base), i.e. ``base != "fixed"``."""
        return self.base != "fixed"

    def _ground(self, q: np.ndarray, frames: list[str]) -> np.ndarray:
        """``q`` with the base lowered (or raised) so that the lowest of ``frames`` is at z = 0."""
        q = q.copy()
        pin.framesForwardKinematics(self.model, self.data, q)
        zmin = min(float(self.data.oMf[self.frame_id(f)].translation[2]) for f in frames)
        if self.base == "free":
            q[2] -= zmin
        elif self.base == "planar":
            q[self.idx_q("base_z")] -= zmin
        return q

    def _grounded_neutral(self) -> np.ndarray:
        """Pinocchio's neutral pose with 1-DoF joints moved inside their position limits
        (e.g. iCub's elbows, whose range excludes 0), base turned and lowered onto z = 0."""
        m = self.model
        q = pin.neutral(m)
        for j in range(1, m.njoints):
            jm = m.joints[j]
            if jm.nq == 1 and m.names[j] not in PLANAR_BASE:
                lo, hi = m.lowerPositionLimit[jm.idx_q], m.upperPositionLimit[jm.idx_q]
                if np.isfinite(lo) and np.isfinite(hi) and lo <= hi:
                    q[jm.idx_q] = min(max(q[jm.idx_q], lo), hi)
        if self.base == "free":
            q[3:7] = pin.Quaternion(self.base_rotation).coeffs()
        return self._ground(q, [self.legs[s].sole for s in SIDES])

    # ------------------------------------------------------------------ queries
    @property
    def joint_names(self) -> tuple[str, ...]:
        """Model joint names in Pinocchio order (without ``universe``)."""
        return tuple(self.model.names)[1:]

    @property
    def mass(self) -> float:
        """Total mass [kg] (Pinocchio)."""
        return float(pin.computeTotalMass(self.model))

    def idx_q(self, joint: str) -> int:
        """Index in q of a 1-DoF joint (the first index for multi-DoF joints)."""
        if not self.model.existJointName(joint):
            raise UnknownNameError("joint", joint, self.joint_names)
        return int(self.model.joints[self.model.getJointId(joint)].idx_q)

    def idx_v(self, joint: str) -> int:
        """Index in v of a joint (the first for multi-DoF joints)."""
        if not self.model.existJointName(joint):
            raise UnknownNameError("joint", joint, self.joint_names)
        return int(self.model.joints[self.model.getJointId(joint)].idx_v)

    def frame_id(self, frame: str) -> int:
        """Pinocchio frame id; :class:`UnknownNameError` lists the valid names."""
        if not self.model.existFrame(frame):
            raise UnknownNameError("frame", frame, [f.name for f in self.model.frames])
        return int(self.model.getFrameId(frame))

    def com(self, q: np.ndarray) -> np.ndarray:
        """Whole-body centre of mass [m] for q ``(nq,)`` → ``(3,)`` or ``(T, nq)`` → ``(T, 3)``."""
        q = np.asarray(q, dtype=float)
        if q.ndim == 1:
            return pin.centerOfMass(self.model, self.data, q).copy()
        return np.array([pin.centerOfMass(self.model, self.data, qi) for qi in q])

    def __repr__(self) -> str:
        L = self.legs["left"]
        return (f"Robot({self.name!r}, base={self.base}, nq={self.model.nq}, "
                f"mass={self.mass:.2f} kg, "
                f"thigh={L.thigh:.4f} m, shank={L.shank:.4f} m, foot={L.foot:.4f} m)")
