"""Deprecated: moved to :mod:`gdimitate.planar.sagittal` (planar angles) and
:mod:`gdimitate.kinematics` (frame and joint paths, stance from the soles, a robot's motion).
This module re-exports them and warns once when imported."""

import warnings

from .kinematics import frame_paths, joint_paths, kinematic_contact, robot_motion
from .planar.sagittal import compose_q, ground_base, leg_angles, torso_angle

__all__ = ["leg_angles", "compose_q", "frame_paths", "joint_paths", "ground_base",
           "kinematic_contact", "robot_motion", "torso_angle"]

warnings.warn("gdimitate.sagittal is deprecated: import the planar angles from "
              "gdimitate.planar.sagittal and the frame/joint paths, kinematic_contact and "
              "robot_motion from gdimitate.kinematics", DeprecationWarning, stacklevel=2)
