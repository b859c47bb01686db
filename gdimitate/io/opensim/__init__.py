"""OpenSim models and data: ``.osim`` → URDF (Pinocchio), and the coordinate/force/marker files.

Model conversion (:mod:`.model`, :mod:`.joints`, :mod:`.urdf`)::

    from gdimitate.io.opensim import opensim_to_urdf, pelvis_to_freeflyer, read_osim
    urdf_path = opensim_to_urdf("subject01.osim")          # -> Path (temporary folder)
    robot = gdimitate.Robot.from_osim("subject01.osim")      # free-flyer, legs, soles set

* URDF joint names are the OpenSim coordinate names (``hip_flexion_r``, ``knee_angle_r``, …),
  values equal to OpenSim's (rad, m), so coordinate columns map by name.
* ``pelvis_to_freeflyer(values, model) -> np.ndarray (T, 7)``: the root joint's coordinates
  (``values``: name → (T,) array in rad and m, e.g. ``pelvis_tilt``, ``pelvis_list``,
  ``pelvis_rotation``, ``pelvis_tx``, ``pelvis_ty``, ``pelvis_tz``; ``model``: ``OsimModel`` or
  ``.osim`` path) → Pinocchio free-flyer ``q[:7] = [x, y, z, qx, qy, qz, qw]`` of the URDF's
  root link in OUR world frame (x forward, y left, z up).
* ``WORLD_FROM_OPENSIM`` (3×3): v_ours = WORLD_FROM_OPENSIM @ v_opensim (x = X, y = −Z,
  z = Y), for forces, centres of pressure and markers given in OpenSim's ground frame.

Data files (:mod:`.coordinates`, :mod:`.grf`, :mod:`.trc`, :mod:`.treadmill`)::

    motion = read_coordinates("walk_ik.mot", robot)        # -> Motion (rad, m; free-flyer q)
    forces = read_grf("walk_grf.mot", robot, "walk_grf.xml", t=motion.t)  # -> ContactForces
    markers = read_trc("walk.trc")                          # -> Markers (m, our world frame)
    motion = inverse_kinematics(robot, markers)             # -> Motion (marker-based IK)
    motion, forces = treadmill_to_overground(robot, motion.replace(contact=forces.contact),
                                             forces)        # belt speed added back
"""

from ...model.osim._table import Table, read_table
from ...model.osim.joints import (
    WORLD_FROM_OPENSIM,
    Approximation,
    follow_coordinates,
    pelvis_to_freeflyer,
)
from ...model.osim.model import OsimModel, read_osim
from ...model.osim.trc import Markers, read_trc
from ...model.osim.urdf import (
    EFFORT_LIMIT,
    VELOCITY_LIMIT,
    OsimConversion,
    convert_osim,
    opensim_to_urdf,
)
from .coordinates import read_coordinates
from .grf import CONTACT_THRESHOLD, ExternalForceSpec, read_external_loads, read_grf
from .ik import IKResult, inverse_kinematics
from .treadmill import belt_speed, treadmill_to_overground

__all__ = [
    "Table",
    "read_table",
    "follow_coordinates",
    "CONTACT_THRESHOLD",
    "EFFORT_LIMIT",
    "VELOCITY_LIMIT",
    "WORLD_FROM_OPENSIM",
    "Approximation",
    "OsimConversion",
    "OsimModel",
    "convert_osim",
    "opensim_to_urdf",
    "pelvis_to_freeflyer",
    "read_osim",
    # readers of motion, force and marker files
    "ExternalForceSpec",
    "IKResult",
    "inverse_kinematics",
    "Markers",
    "belt_speed",
    "read_coordinates",
    "read_external_loads",
    "read_grf",
    "read_trc",
    "treadmill_to_overground",
]
