"""The optimal adaptor's streaming mode: a demonstration adapted frame by frame as it arrives
(:class:`~gdimitate.StreamingAdaptor`, :mod:`.adaptor`), a per-frame QP (:mod:`.receding`) on
the same targets and limits as the trajectory mode, the frame reference that keeps the feet
and the heading (:mod:`.frameref`) and the worker that audits committed frames off the hot
path (:mod:`.verdict_worker`)."""
