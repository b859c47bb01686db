"""The physics check: replay a plan in MuJoCo under a whole-body QP tracking controller.

::

    import gdimitate as gd
    res = gd.sim.simulate(robot, adapted)            # adapted: .motion (v, a), .wrenches, .contacts
    res.metrics.fell, res.metrics.slip_max, res.metrics.force_vs_plan["left"]

Modules: :mod:`~.model` (the MuJoCo model built from the robot's ``pin.Model``, coordinate
maps), :mod:`~.reference` (the plan contract and its references in time), :mod:`~.controller`
(the QP tracking controller), :mod:`~.simulate` (the loop and :class:`SimResult`),
:mod:`~.metrics` (falls, slip, force direction, centre of pressure, torques, tracking),
:mod:`~.plots` (matplotlib figures), :mod:`~.animation` (plan and simulation side by side in
meshcat). Small plans for tests and demos live in :mod:`gdimitate.apps.scenarios`
(scenario code, not API).
"""

from ..model.mjcf import ModelOptions, SimModel, build_model
from .controller import ControllerGains, TrackingController, pendulum_frequency
from .metrics import DirectionAgreement, FallCriteria, StanceSlip
from .reference import Plan, Reference, check_plan
from .simulate import Push, SimMetrics, SimResult, measure_contacts, simulate

__all__ = [
    "ControllerGains",
    "DirectionAgreement",
    "FallCriteria",
    "ModelOptions",
    "Plan",
    "Push",
    "Reference",
    "SimMetrics",
    "SimModel",
    "SimResult",
    "StanceSlip",
    "TrackingController",
    "build_model",
    "check_plan",
    "measure_contacts",
    "pendulum_frequency",
    "simulate",
]
