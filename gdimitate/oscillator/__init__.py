"""Matsuoka neural-oscillator banks (docs/design.md §7): simulation, closed forms, entrainment
analysis,
Arnold tongues and the self-adjusting adaptor that tunes a network to replay joint motion."""

from .adaptive import AdaptiveRun, adapt_frequency
from .analysis import (
    Entrainment,
    PhasePlane,
    Spectrum,
    crossing_times,
    entrainment,
    free_running_frequency,
    frequency_ratio,
    measured_frequency,
    phase_locking_value,
    phase_plane,
    relative_phase,
    spectrum,
    time_to_lock,
)
from .bank import MatsuokaBank, OscillatorTimeGridError, Trace, default_x0
from .closed_form import natural_amplitude, natural_frequency, tau_r_for_frequency
from .params import (
    MatsuokaParams,
    NoOscillationError,
    OscillatorWarning,
    StepTooLargeError,
    validate_params,
)
from .selfadjust import SelfAdjustResult, self_adjust, state_features
from .teaching import FourierTeacher, fit_teacher
from .tongue import ArnoldTongue, arnold_tongue

__all__ = [
    "AdaptiveRun",
    "ArnoldTongue",
    "Entrainment",
    "FourierTeacher",
    "MatsuokaBank",
    "MatsuokaParams",
    "NoOscillationError",
    "OscillatorTimeGridError",
    "OscillatorWarning",
    "PhasePlane",
    "SelfAdjustResult",
    "Spectrum",
    "StepTooLargeError",
    "Trace",
    "adapt_frequency",
    "arnold_tongue",
    "crossing_times",
    "default_x0",
    "entrainment",
    "fit_teacher",
    "free_running_frequency",
    "frequency_ratio",
    "measured_frequency",
    "natural_amplitude",
    "natural_frequency",
    "phase_locking_value",
    "phase_plane",
    "relative_phase",
    "self_adjust",
    "spectrum",
    "state_features",
    "tau_r_for_frequency",
    "time_to_lock",
    "validate_params",
]
