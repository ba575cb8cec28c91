"""Pictures: the paper's figures (:mod:`.plots`, matplotlib; a run folder is read by
:mod:`aerial_drake.simulation.run_folder`, without it), a run's own or several runs'
(:mod:`.run_plots`), several controllers on one scenario (:mod:`.compare`), the Meshcat view,
overlays and replay (:mod:`.meshcat_view`), catching the live view (:mod:`.live`) and
headless-Chromium screenshots (:mod:`.screenshot`)."""
