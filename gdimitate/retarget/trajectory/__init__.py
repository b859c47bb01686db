"""The optimal adaptor's trajectory mode: one nonlinear program over every knot of a
demonstration (:mod:`.problem`, its derivatives compiled to C and cached by :mod:`.codegen`),
solved by IPOPT (:mod:`.solve`) from a warm start (:mod:`.initial`) with its stopping rules
(:mod:`.stopping`, :mod:`.interrupt`), the wrenches' polish (:mod:`.polish`) and the periodic
seam of a gait cycle (:mod:`.periodic`). The formulation's parts, targets and limits are the
streaming mode's too (:mod:`gdimitate.retarget`)."""
