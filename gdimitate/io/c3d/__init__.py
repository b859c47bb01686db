"""Gait-lab C3D files: markers and force plates in, with the plates' forces on the feet.

::

    trial = gd.c3d.read_c3d("walk.c3d")           # -> C3DTrial (ezc3d reads the file)
    trial.markers                                 # Markers: names, xyz (T, n, 3) [m], t, rate
    trial.plates[0].force, trial.plates[0].cop    # (T, 3) [N], (T, 3) [m] (NaN unloaded)
    forces = trial.contact_forces(robot, motion)  # ContactForces: plates to feet by proximity
    gd.c3d.write_c3d("out.c3d", markers, plates)  # the reverse (synthetic trials, conversions)

:mod:`.reader` reads, :mod:`.plates` assigns plates to feet, :mod:`.writer` writes
(:func:`gdimitate.io.gait.write_subject01_c3d` writes the shipped trial as a lab's C3D).
"""

from .plates import assign_plates
from .reader import C3DTrial, ForcePlate, read_c3d
from .writer import write_c3d

__all__ = ["C3DTrial", "ForcePlate", "assign_plates", "read_c3d", "write_c3d"]
