"""Studies built from runs: the paper's two-case run of Section IV (:mod:`.paper`), one
scenario under several controllers (:mod:`.compare`), both on the batch runner
(:mod:`.batch`) with their metrics as text (:mod:`.summary`), and studies on Dask
(:mod:`.spec`, :mod:`.study`). Library functions with typed arguments; the command line
(:mod:`aerial_drake.cli`) parses and prints."""
