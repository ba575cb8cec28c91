"""Studies built from runs: the paper's two-case run of Section IV (:mod:`.paper`), one
scenario under several controllers (:mod:`.compare`), and how the commands report errors and
exit statuses (:mod:`.reporting`)."""
