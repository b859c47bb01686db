"""Writing a motion out (and reading it back): CSV, NPZ, MuJoCo, LAFAN1, GMR, IsaacLab AMP
(:func:`~gdimitate.export_motion`). On the floor of :mod:`gdimitate.assess`: a result saves
itself through these writers."""
