"""Pictures: a run folder loaded (:mod:`.run_data`, no matplotlib), the paper's figures
(:mod:`.plots`, matplotlib), a run's own or several runs' (:mod:`.run_plots`), several
controllers on one scenario (:mod:`.compare`), the Meshcat view, overlays and replay
(:mod:`.meshcat_view`), catching the live view (:mod:`.live`) and headless-Chromium
screenshots (:mod:`.screenshot`)."""
