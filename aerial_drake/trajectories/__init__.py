"""Reference trajectories: the reference sample and its packed vectors (:mod:`.reference`),
the paper's trajectory (27)-(33) (:mod:`.paper`) and the Drake source of it
(:mod:`.generator`, ``ReferenceGenerator``)."""
