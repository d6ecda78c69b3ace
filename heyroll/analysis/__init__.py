"""Validation analyses: how good the paper's series are, and how far a run can be trusted.

* :mod:`heyroll.analysis.series_error` — the truncated series (54)-(55) of the
  paper against Legendre's exact F, over amplitude and energy, and the
  paper's whole method for the first collision (solve (56) = (57) with the
  series) against the exact mpmath reference.
* :mod:`heyroll.analysis.horizon` — the predictability horizon of a scene
  (double vs quad collision sequences) and its largest Lyapunov exponent.

Both import heyoka only when a function needs the engine (the series
analysis does not, except through the exact reference's scene).
"""

from .series_error import (
    PaperMethodResult,
    SeriesErrorMap,
    SeriesErrorTable,
    exact_integral,
    paper_method_first_collision,
    series_error_map,
    series_error_maps,
    series_error_table,
    series_integral,
)

__all__ = [
    "PaperMethodResult",
    "SeriesErrorMap",
    "SeriesErrorTable",
    "exact_integral",
    "paper_method_first_collision",
    "series_error_map",
    "series_error_maps",
    "series_error_table",
    "series_integral",
    # horizon.py (imported on use: it needs heyoka)
    "HorizonResult",
    "LyapunovEstimate",
    "lyapunov_estimate",
    "predictability_horizon",
]


def __getattr__(name):
    if name in ("HorizonResult", "LyapunovEstimate", "lyapunov_estimate", "predictability_horizon"):
        from . import horizon

        return getattr(horizon, name)
    raise AttributeError(f"module 'heyroll.analysis' has no attribute {name!r}")
