"""Matsuoka neural-oscillator banks: simulation, closed forms, entrainment analysis, tuning."""

from .bank import MatsuokaBank, OscillatorTimeGridError, Trace, default_x0
from .params import (
    MatsuokaParams,
    NoOscillationError,
    OscillatorWarning,
    StepTooLargeError,
)

__all__ = [
    "MatsuokaBank",
    "MatsuokaParams",
    "NoOscillationError",
    "OscillatorTimeGridError",
    "OscillatorWarning",
    "StepTooLargeError",
    "Trace",
    "default_x0",
]
