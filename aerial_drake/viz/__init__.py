"""Pictures: the paper's figures (:mod:`.plots`, matplotlib), the Meshcat view, overlays and
replay (:mod:`.meshcat_view`) and headless-Chromium screenshots (:mod:`.screenshot`)."""
