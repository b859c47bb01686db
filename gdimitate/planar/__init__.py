"""The paper's planar case (docs/design.md §4), in its own corner of the package.

Yang and Chong's ICAR 2005 adaptor is planar: two-link legs in the sagittal plane, matched by
Eq. (1). Everything that needs a leg to be that planar leg lives here, but for the
measurement of a robot's legs as planar legs, which lies in the model floor (the gait-lab
reader of the paper's planar human composes q with it, below this floor):

- :mod:`~gdimitate.planar.twolink`: Eq. (1) (:func:`eq1`), the two-link leg's forward and
  inverse kinematics (:func:`fk2`, :func:`ik2`);
- :mod:`~gdimitate.model.sagittal`: a robot's legs as planar legs (:func:`sagittal_leg`:
  joint signs and offsets, measured when asked — only for legs whose joints turn about the
  lateral axis), between q and the planar angles (:func:`leg_angles`, :func:`compose_q`) and
  the anchor-foot base placement (:func:`ground_base`);
- :mod:`~gdimitate.planar.analytic`: the ``"analytic"`` (Eq. 1) and ``"copy"`` adaptors
  (:func:`adapt_planar`), which :func:`gdimitate.adapt` dispatches to;
- :mod:`~gdimitate.planar.walking`: the paper's Fig. 3 walking generator
  (:func:`walking_motion`).

The 3-D core (:class:`~gdimitate.Robot`, :mod:`gdimitate.model.kinematics`, the optimal adaptor,
the audit) takes any leg axes and imports nothing from here, except the optimal adaptor's warm
start, which tries Eq. (1) first and falls back to the neutral pose when a leg is not planar.
"""

from ..model.sagittal import (
    SagittalLeg,
    compose_q,
    ground_base,
    leg_angles,
    sagittal_leg,
    torso_angle,
)
from .analytic import adapt_planar, check_pair
from .twolink import ROUNDOFF, Eq1Result, eq1, fk2, ik2
from .walking import HUMAN_GAIT, ROBOT_GAIT, GaitSpec, walking_motion

__all__ = ["Eq1Result", "GaitSpec", "HUMAN_GAIT", "ROBOT_GAIT", "ROUNDOFF", "SagittalLeg",
           "adapt_planar", "check_pair", "compose_q", "eq1", "fk2", "ground_base", "ik2",
           "leg_angles", "sagittal_leg", "torso_angle", "walking_motion"]
