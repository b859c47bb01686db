"""The adaptor's entry points: :func:`~gdimitate.adapt` (:mod:`.adaptor`, the one place that
picks the method and the mode) and :func:`~gdimitate.repair` (:mod:`.repairer`, a robot's motion
adapted onto itself). Above the planar and optimal adaptors they call, below the simulator, the
walk and the command line."""
