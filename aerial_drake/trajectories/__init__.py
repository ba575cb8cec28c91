"""Reference trajectories: the reference sample and its packed vectors (:mod:`.reference`),
the ``trajectory:`` section (:mod:`.params`), the kinds (paper (27)-(33) :mod:`.paper`, hover
:mod:`.hover`, waypoints :mod:`.waypoints` with its checks :mod:`.waypoint_checks` and its
``mode: through`` knot derivatives :mod:`.through`, python :mod:`.python_kind`, sampled for
a run onto splines :mod:`.sampled`; the waypoints and sampled python kinds evaluated by the
compiled :mod:`.spline_kernel`) in one
registry with one entry point (:mod:`.kinds`: ``REFERENCE_KINDS``, ``validate_trajectory``,
``reference_of``), the Drake source of any of them (:mod:`.generator`,
``ReferenceGenerator``), the test that a sampled reference is as smooth as the law needs
(:mod:`.continuity`), and any kind's x_d planned for the arm's margin (:mod:`.com_planning`,
its postures' margins :mod:`.com_margins`; option ``com_planning``)."""
