"""An OpenSim model read as a robot (:meth:`gdimitate.Robot.from_osim`): the ``.osim`` file,
its joints and functions, its conversion to URDF, and the marker and table files that place its
soles. The readers of OpenSim's motion and force files are :mod:`gdimitate.io.opensim`'s."""
