"""The physics check: a MuJoCo model of a robot and a whole-body QP tracking controller."""
