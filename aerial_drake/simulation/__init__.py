"""The closed loop and its runs: scenarios (:mod:`.scenarios`: dataclasses, loading, the one
validation pass, the shipped YAML files), actuators (:mod:`.actuators`), disturbance sources
(:mod:`.disturbances`), choosing the controller (:mod:`.controllers`), the configuration that
realises the reference (:mod:`.reference_pose`), the diagram (:mod:`.diagram`), simulating a
scenario (:mod:`.runner`), its log (:mod:`.run_log`), the tracking errors from the plant's
state (:mod:`.tracking`), measuring it (:mod:`.metrics`), the run folder and its files
(:mod:`.outputs`), clean stops on signals (:mod:`.interrupts`) and where a run went
non-finite (:mod:`.nonfinite`)."""
