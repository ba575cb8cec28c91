"""The closed loop and its runs: scenarios (:mod:`.scenarios`, dataclasses, loading and the
shipped YAML files), actuators (:mod:`.actuators`), disturbance sources (:mod:`.disturbances`),
the diagram (:mod:`.diagram`), simulating a scenario (:mod:`.runner`) and measuring it
(:mod:`.metrics`)."""
