"""Studies built from runs: the paper's two-case run of Section IV (:mod:`.paper`)."""
