"""The cost of the whole-body problem, one task per module. A task is a residual at one knot
(``residual(knot)``, SX, already multiplied by the square root of its weight, which is a
parameter); the problem sums the squared residuals over the knots and divides by their number.
Weights: :class:`gdimitate.retarget.params.Weights`."""

from . import joints, keypoints, smoothness, wrench

TASKS = (keypoints, joints, smoothness, wrench)

__all__ = ["TASKS", "joints", "keypoints", "smoothness", "wrench"]

#: Index of each weight in the knot's ``weights`` parameter block.
WEIGHT_INDEX = {"height": 0, "placement": 1, "shank": 2, "thigh": 3, "torso": 4,
                "smoothness": 5, "wrench": 6, "foot": 7, "elastic": 8}
