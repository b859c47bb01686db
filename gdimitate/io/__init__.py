"""Demonstrations in: the readers of OpenSim, BVH and C3D files (and the C3D writer), live
motion-capture sources, the shipped gait data and :func:`~gdimitate.load_demonstration`, which
picks the reader by the file's type. Above :mod:`gdimitate.model` (the readers build motions
and robots), below everything that judges or adapts a motion."""
