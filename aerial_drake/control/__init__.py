"""Section III: the law (10)-(22) as pure math (:mod:`.law`), its compiled fast path
(:mod:`.compiled`, numba) and the Drake ``LeafSystem`` around them (:mod:`.controller`).

Importing this package imports neither numba nor the LeafSystem: import the module you use."""
