"""Judging a motion: its metrics (force direction, limits), the contact wrenches that explain
it, the physical audit, the verdict every output prints, and the adaptor's result type
(:class:`~gdimitate.AdaptedMotion`) with the solver record it holds. Above the model and the
readers, below every adaptor."""
