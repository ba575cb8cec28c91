"""Section III and the controllers beside it: the law (10)-(22) as pure math (:mod:`.law`), its
compiled fast path (:mod:`.compiled`, numba), the Drake ``LeafSystem`` around them
(:mod:`.controller`), the ports any controller must have (:mod:`.interface`) and the baselines
the paper improves on (:mod:`.baselines`).

Importing this package imports neither numba nor a LeafSystem: import the module you use."""
