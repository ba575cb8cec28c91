"""The settings of the Lyapunov and region-of-attraction studies: full and ``--fast``."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class AnalysisSettings:
    """The Lyapunov and region-of-attraction studies' settings. The defaults are the full
    study (``aerial-drake analyze``, about 3 minutes on two cores) and the defaults of
    :func:`lyapunov_scenario`, :func:`lyapunov_study` and :func:`region_of_attraction`;
    :meth:`fast` is ``--fast`` (a smoke test: the error-controlled integrator's first 0.1 s
    at 1e-8 alone costs ~10 s)."""

    lyapunov_duration: float = 2.0  # s
    lyapunov_accuracy: float = 1e-8  # runge_kutta3's error-control accuracy
    roa_scales: tuple[float, ...] = (1.0, 2.0, 4.0, 6.0, 8.0)  # offset sizes (ROA_UNIT)
    roa_samples: int = 6  # runs per size
    roa_duration: float = 1.0  # s, per run

    @classmethod
    def fast(cls) -> AnalysisSettings:
        return cls(lyapunov_duration=0.1, lyapunov_accuracy=1e-6, roa_scales=(1.0, 6.0),
                   roa_samples=1, roa_duration=0.2)


FULL_SETTINGS = AnalysisSettings()
FAST_SETTINGS = AnalysisSettings.fast()

