"""Reference trajectories: the reference sample and its packed vectors (:mod:`.reference`),
the ``trajectory:`` section (:mod:`.params`), the kinds (paper (27)-(33) :mod:`.paper`, hover
:mod:`.hover`, waypoints :mod:`.waypoints`, python :mod:`.python_kind`) behind one entry point
(:mod:`.kinds`: ``reference_of``, ``evaluate_reference``, ``sample_reference``), and the Drake
source of any of them (:mod:`.generator`, ``ReferenceGenerator``)."""
