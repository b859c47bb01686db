"""The robot model: motions, robots and their loaders, legs, kinematics, sole contacts, the
model files (URDF generation and checks, MJCF, meshes, self-collision geometry, the symbolic
model) and anthropometry. The lowest floor above :mod:`gdimitate.errors`: it reads no
demonstration and adapts nothing."""
