"""The channel layout of a live mocap stream: one sample's numbers → the demonstrator's
configuration and stance flags.

A sample is a BVH skeleton's frame line plus the stance of each foot, each number named by
its channel label (the order does not matter; other channels are ignored):

- ``<Joint>.<Channel>`` for every channel of the skeleton's HIERARCHY, e.g. ``Hips.Xposition``,
  ``LeftUpLeg.Zrotation``: the number a BVH MOTION line holds there (the skeleton file's length
  unit, degrees);
- ``contact.left``, ``contact.right``: 1 while that foot is in stance, 0 in swing (a force
  plate's or an insole's threshold, or the mocap system's foot-contact events; values ≥ 0.5
  are stance).

The skeleton is a BVH file (:func:`gdimitate.bvh.read_bvh`: the unit, the up axis and the floor
height are the file's, found from its frames as for a BVH demonstration), so a frame received
live gives the same configuration as the file's own frame would (:meth:`BVHLayout.decode`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from ...errors import GdimitateError
from ...model.robot import Robot
from ..bvh import channel_rotation, parse_bvh, read_bvh
from .stance import CausalStance

__all__ = ["CONTACT_LABELS", "BVHLayout", "Layout", "LiveSourceError"]

#: the stance channels' labels, by side
CONTACT_LABELS = {"left": "contact.left", "right": "contact.right"}


class LiveSourceError(GdimitateError):
    """A live source that cannot be used: no such stream, a channel missing, a frame that is
    not a number, the stream gone."""


class Layout:
    """What a channel layout gives (:class:`BVHLayout`,
    :class:`~gdimitate.live.coordinates.OpenSimLayout`): ``robot`` (the demonstrator),
    ``labels`` (its channels, the stance's last), ``frame_time`` [s] (the default frame
    period), :meth:`decode` of one sample, :meth:`warm_up_samples`."""

    robot: Robot
    labels: tuple[str, ...]
    frame_time: float
    path: Path

    def columns(self, labels: list[str] | tuple[str, ...]) -> np.ndarray:
        """``(len(self.labels),)`` int: where each of this layout's channels is among a
        stream's channel ``labels``, −1 for the two stance channels where the stream has
        neither (the stance is then detected: :meth:`decode`); :class:`LiveSourceError`
        naming the missing ones."""
        where = {label: i for i, label in enumerate(labels)}
        stance = list(CONTACT_LABELS.values())
        if not any(label in where for label in stance):
            where.update({label: -1 for label in stance})
        missing = [label for label in self.labels if label not in where]
        if missing:
            raise LiveSourceError(
                f"the stream lacks {len(missing)} channel(s) of {self.path.name} and the "
                f"stance: {', '.join(missing[:8])}{' …' if len(missing) > 8 else ''} "
                "(docs/guide/streaming.md)")
        return np.array([where[label] for label in self.labels], int)

    _detector: CausalStance | None = None

    def reset(self) -> None:
        """Forget the previous frame."""
        if self._detector is not None:
            self._detector.reset()

    def decode(self, sample: np.ndarray, t: float = 0.0) -> tuple[np.ndarray, dict[str, bool]]:
        """One sample ``(len(labels),)`` at time ``t`` [s] → ``(q (nq,), {side: stance})``;
        NaN in both stance channels: the stance detected from the feet
        (:class:`~gdimitate.live.stance.CausalStance`, which reads ``t``)."""
        raise NotImplementedError

    def warm_up_samples(self, k: int) -> np.ndarray:
        """``(k, len(labels))``: frames to warm the adaptor up on before a stream."""
        raise NotImplementedError

    def _checked(self, sample: np.ndarray) -> tuple[np.ndarray, dict[str, bool] | None]:
        """The sample as floats (:class:`LiveSourceError` unless ``len(labels)`` finite
        numbers, the stance's two possibly both NaN) and its stance (None: to detect)."""
        x = np.asarray(sample, float)
        stance = x[-2:]
        detect = x.shape == (len(self.labels),) and bool(np.all(np.isnan(stance)))
        if x.shape != (len(self.labels),) or not np.all(np.isfinite(x[:-2])) or not (
                detect or np.all(np.isfinite(stance))):
            raise LiveSourceError(f"a frame of {x.size} numbers, not {len(self.labels)} finite "
                                  "ones, in the layout of " + self.path.name)
        return x, None if detect else {s: bool(stance[k] >= 0.5)
                                       for k, s in enumerate(CONTACT_LABELS)}

    def _stance(self, t: float, q: np.ndarray, given: dict[str, bool] | None
                ) -> dict[str, bool]:
        """The stance given, else detected from ``q`` at ``t``."""
        if given is not None:
            return given
        if self._detector is None:
            self._detector = CausalStance(self.robot)
        return self._detector(t, q)


class BVHLayout(Layout):
    """The channel layout of a BVH skeleton (module docstring).

    ``skeleton``: a BVH file (its HIERARCHY names the channels; its frames set the unit and the
    floor, as :func:`~gdimitate.bvh.read_bvh` finds them). Attributes: ``robot`` (the
    demonstrator), ``labels`` (``n_channels + 2`` channel labels: the frame line's, then the two
    stance channels), ``frame_time`` [s] (the file's), ``path``."""

    def __init__(self, skeleton: str | Path):
        self.path = Path(skeleton)
        self.robot, self._motion = read_bvh(self.path)
        info = self.robot.bvh_info
        self._bvh = parse_bvh(self.path)
        self._info = info
        self.frame_time = float(info.frame_time)
        channels = [f"{j.name}.{c}" for j in self._bvh.joints for c in j.channels]
        self.labels: tuple[str, ...] = (*channels, *CONTACT_LABELS.values())
        model = self.robot.model
        where = [(cj.column, model.joints[model.getJointId(cj.joint)].idx_q,
                  cj.channel.endswith("rotation")) for cj in info.channels if cj.joint is not None]
        self._rot = np.array([(c, i) for c, i, r in where if r], int).reshape(-1, 2)
        self._pos = np.array([(c, i) for c, i, r in where if not r], int).reshape(-1, 2)
        self._angles = self._rot[:, 1]  # q entries of rotation channels (unwrapped)
        root = self._bvh.joints[0]
        self._root = [(root.column + k, c) for k, c in enumerate(root.channels)]
        self._neutral = np.zeros(model.nq)
        self._previous: np.ndarray | None = None

    @property
    def file_samples(self) -> np.ndarray:
        """``(T, len(labels))``: the skeleton file's own frames in this layout (its reference
        frame left out where :func:`~gdimitate.bvh.read_bvh` skips it), stance as it detects
        it — what a mocap system replaying the file would send."""
        skip = 1 if self._info.skipped_first_frame else 0
        rows = self._bvh.frames[skip:]
        c = self._motion.contact
        return np.column_stack([rows, c["left"], c["right"]]).astype(float)

    def warm_up_samples(self, k: int) -> np.ndarray:
        """The file's first ``k`` frames (:attr:`file_samples`)."""
        return self.file_samples[:k]

    def reset(self) -> None:
        """Forget the previous frame (angles are unwrapped against it)."""
        super().reset()
        self._previous = None

    def _q(self, x: np.ndarray) -> np.ndarray:
        """:func:`~gdimitate.bvh.bvh_to_q` of one frame line ``x``, its per-channel look-ups
        done once (bvh_to_q's on one line: ~8 ms for the CMU skeleton's 96 channels)."""
        info, C = self._info, self._info.turn
        p = np.array(self._bvh.joints[0].offset, float)
        R = np.eye(3)
        for col, c in self._root:
            if c.endswith("position"):
                p["XYZ".index(c[0])] += x[col]
            else:
                R = R @ channel_rotation(c, np.deg2rad(x[col]))
        q = self._neutral.copy()
        q[:3] = C @ (p * info.scale)
        q[3:7] = Rotation.from_matrix(C @ R @ C.T).as_quat()  # x, y, z, w
        q[self._rot[:, 1]] = np.deg2rad(x[self._rot[:, 0]])
        q[self._pos[:, 1]] = x[self._pos[:, 0]] * info.scale
        return q

    def decode(self, sample: np.ndarray, t: float = 0.0) -> tuple[np.ndarray, dict[str, bool]]:
        """One sample ``(len(labels),)`` in this layout's order at time ``t`` [s] → ``(q (nq,),
        {side: stance})`` (the stance's channels both NaN: detected, :meth:`Layout.decode`):
        the configuration :func:`~gdimitate.bvh.read_bvh` gives the same frame (base in metres
        on the floor z = 0, quaternion x, y, z, w; angles [rad]), each angle within π of the
        previous frame's and the quaternion on its side (a frame line's 179° → −179° is a
        2° turn); :class:`LiveSourceError` for a number that is not finite."""
        x, contact = self._checked(sample)
        info = self._info
        q = self._q(x)
        if info.grounded:
            q[2] -= info.floor
        p = self._previous
        if p is not None:
            i = self._angles
            q[i] = p[i] + (q[i] - p[i] + np.pi) % (2 * np.pi) - np.pi
            if float(q[3:7] @ p[3:7]) < 0:
                q[3:7] *= -1
        self._previous = q.copy()
        return q, self._stance(t, q, contact)

