"""stickslip from Python: ensembles of a stochastic stick-slip friction oscillator.

The engine runs in-process (the Rust library through PyO3, no subprocess):

- :func:`sweep` runs a frequency x normal-force grid and returns an
  ``xarray.Dataset`` (a ``pandas.DataFrame`` when xarray is not installed),
  every variable with its ``units`` attribute;
- :func:`simulate` returns time-series records (t, x, v, N, F) as numpy arrays;
- :func:`diagnose` diagnoses a measurement set and returns the report as
  Python objects, with the baseline and fitted model files;
- :func:`load` reads any output set stickslip wrote (a sweep, a diagnosis, a
  simulated or measured set);
- :func:`model` resolves a model (file, dict or the embedded paper rig, with
  ``--set``-style overrides) into a dict.

Everything is in SI units (m, s, N, Hz); phases are in degrees.
"""

from ._api import (
    SWEEP_COLUMNS,
    UNITS,
    Diagnosis,
    Records,
    __version__,
    backend,
    diagnose,
    load,
    model,
    model_toml,
    peak_density,
    simulate,
    sweep,
)

__all__ = [
    "Diagnosis",
    "Records",
    "SWEEP_COLUMNS",
    "UNITS",
    "backend",
    "diagnose",
    "load",
    "model",
    "model_toml",
    "peak_density",
    "simulate",
    "sweep",
    "__version__",
]


def __dir__():
    # What `dir(stickslip)` and tab completion offer: the API, not the
    # submodules (`_api`, `_native`) it is made of.
    return sorted(__all__)
