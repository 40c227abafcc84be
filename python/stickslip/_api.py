"""The implementation of the ``stickslip`` package; import ``stickslip``, not
this module (its names are re-exported there)."""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

# Mesa's Vulkan loader probes Wayland and prints a misleading
# "XDG_RUNTIME_DIR is invalid" on headless machines (the command line does the same).
if "XDG_RUNTIME_DIR" not in os.environ:
    import tempfile

    os.environ["XDG_RUNTIME_DIR"] = tempfile.gettempdir()

import numpy as np
import pandas as pd

from . import _native

__version__: str = _native.version()

PathLike = Union[str, "os.PathLike[str]"]
ModelSpec = Union[None, PathLike, Mapping[str, Any]]
Overrides = Union[None, Mapping[str, Any], Sequence[str]]
Grid = Union[str, float, Iterable[float]]

#: Units of the statistics of a sweep (the columns of ``sweep.csv``).
UNITS: Dict[str, str] = {
    "frequency": "Hz",
    "normal_force": "N",
    "realisations": "1",
    "peaks": "1",
    "peak_mean_m": "m",
    "peak_var_m2": "m^2",
    "peak_quantile_m": "m",
    "peak_p05_m": "m",
    "peak_p50_m": "m",
    "peak_p95_m": "m",
    "stick_fraction": "1",
    "phase_mean_deg": "degree",
    "phase_var_deg2": "degree^2",
    "histogram_count": "1",
    "histogram_lo_m": "m",
    "histogram_hi_m": "m",
    "bin_centre_m": "m",
    "density_per_m": "1/m",
}

_DESCRIPTIONS: Dict[str, str] = {
    "frequency": "excitation frequency",
    "normal_force": "nominal normal force",
    "quantile": "probability of the peak-amplitude quantile",
    "bin": "histogram bin (0: below the range, last: above it)",
    "realisations": "realisations behind the statistics",
    "peaks": "peak amplitudes behind the statistics (one per measured period and realisation)",
    "peak_mean_m": "mean peak amplitude",
    "peak_var_m2": "unbiased variance of the peak amplitude",
    "peak_quantile_m": "quantiles of the peak amplitude (from the histogram)",
    "stick_fraction": "share of measured time spent stuck",
    "phase_mean_deg": "circular mean phase lag of the response's fundamental behind the base",
    "phase_var_deg2": "circular variance of that phase",
    "histogram_count": "peak amplitudes per histogram bin",
    "histogram_lo_m": "lower edge of the histogram's inner bins",
    "histogram_hi_m": "upper edge of the histogram's inner bins",
    "bin_centre_m": "centre of each inner histogram bin (NaN for the outer bins)",
    "density_per_m": "probability density of the peak amplitude in each inner bin (NaN for the outer bins)",
}

_QUANTILES = (0.05, 0.5, 0.95)

#: The columns of ``sweep.csv``, in its order.
SWEEP_COLUMNS = (
    "excitation_frequency_hz",
    "normal_force_n",
    "realisations",
    "peaks",
    "peak_mean_m",
    "peak_var_m2",
    "peak_p05_m",
    "peak_p50_m",
    "peak_p95_m",
    "stick_fraction",
    "phase_mean_deg",
    "phase_var_deg2",
)


# ----------------------------------------------------------------------------
# Models and overrides
# ----------------------------------------------------------------------------


def _override_strings(overrides: Overrides) -> List[str]:
    """``--set``-style overrides: a dict ``{"friction.a": 0.3}`` (nested dicts
    are flattened to dotted keys) or a list of ``"KEY=VALUE"`` strings."""
    if overrides is None:
        return []
    if isinstance(overrides, str):
        return [overrides]
    if not isinstance(overrides, Mapping):
        return [str(o) for o in overrides]
    out: List[str] = []

    def walk(prefix: str, value: Any) -> None:
        if isinstance(value, Mapping):
            for k, v in value.items():
                walk(f"{prefix}.{k}" if prefix else str(k), v)
            return
        if isinstance(value, bool):
            text = "true" if value else "false"
        elif isinstance(value, (int, np.integer)):
            text = str(int(value))
        elif isinstance(value, (float, np.floating)):
            if not math.isfinite(float(value)):
                raise ValueError(f"invalid override {prefix}: {value} is not finite")
            text = repr(float(value))
        elif isinstance(value, str):
            text = json.dumps(value)
        else:
            raise TypeError(f"invalid override {prefix}: {value!r} is not a number, bool or string")
        out.append(f"{prefix}={text}")

    walk("", overrides)
    return out


def _strip_none(value: Any) -> Any:
    if isinstance(value, Mapping):
        return {str(k): _strip_none(v) for k, v in value.items() if v is not None}
    if isinstance(value, (list, tuple)):
        return [_strip_none(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def _resolve(model: ModelSpec, overrides: Overrides) -> Tuple[str, str]:
    sets = _override_strings(overrides)
    if model is None:
        return _native.model(set=sets)
    if isinstance(model, Mapping):
        return _native.model(json_text=json.dumps(_strip_none(model)), set=sets)
    if isinstance(model, (str, os.PathLike)):
        return _native.model(config=os.fspath(model), set=sets)
    raise TypeError(f"model must be None, a model file's path or a dict, not {type(model).__name__}")


def model(model: ModelSpec = None, overrides: Overrides = None) -> Dict[str, Any]:
    """The model as a nested dict, validated.

    ``model`` is ``None`` (the embedded paper rig), a model file (TOML) or a
    dict of the same shape (e.g. one this function returned, edited);
    ``overrides`` are ``--set``-style changes, ``{"friction.a": 0.3}``.
    """
    return json.loads(_resolve(model, overrides)[1])


def model_toml(model: ModelSpec = None, overrides: Overrides = None) -> str:
    """The model as the text of a model file (for ``stickslip sweep --config``)."""
    return _resolve(model, overrides)[0]


def backend(backend: str = "auto", *, allow_software_gpu: bool = False) -> Tuple[str, str]:
    """Opens a backend ("auto", "gpu" or "cpu") and returns ``(kind, description)``:
    ``kind`` is ``"gpu"`` (the WGSL kernel, f32) or ``"cpu"`` (the f64 reference).

    The command line's policy: ``"gpu"`` refuses a software adapter (Mesa's
    lavapipe) with a ``RuntimeError`` unless ``allow_software_gpu=True``
    (``--allow-software-gpu``); ``"auto"`` takes a hardware GPU, else the CPU."""
    return _native.open_backend(backend, allow_software_gpu=bool(allow_software_gpu))


# ----------------------------------------------------------------------------
# Sweeps
# ----------------------------------------------------------------------------


def _grid(name: str, values: Grid) -> List[float]:
    if isinstance(values, str):
        return list(_native.parse_list(name, values))
    if isinstance(values, (int, float, np.integer, np.floating)):
        return [float(values)]
    return [float(v) for v in np.asarray(list(values), dtype=float).ravel()]


def _have_xarray() -> bool:
    try:
        import xarray  # noqa: F401
    except ImportError:
        return False
    return True


def _payload_to_object(payload: str, histograms: bytes, attrs: Dict[str, Any], as_xarray: Optional[bool]):
    meta = json.loads(payload)
    rows = pd.DataFrame(meta.pop("rows"))
    bins = int(meta.pop("histogram_bins"))
    refined = meta.pop("refined_frequencies_hz", None)
    if refined is not None:
        attrs = {**attrs, "refined_frequencies_hz": [float(f) for f in refined]}
    counts = np.frombuffer(histograms, dtype="<u8").reshape(len(rows), bins)
    attrs = {**{k: v for k, v in meta.items() if not isinstance(v, (list, dict))}, **attrs}
    if as_xarray is None:
        as_xarray = _have_xarray()
    if not as_xarray:
        frame = rows[list(SWEEP_COLUMNS)].copy()
        frame.attrs.update(attrs)
        frame.attrs["units"] = {c: UNITS[c] for c in frame.columns if c in UNITS}
        frame.attrs["units"].update(excitation_frequency_hz="Hz", normal_force_n="N")
        return frame
    return _dataset(rows, counts, attrs)


def _dataset(rows: pd.DataFrame, counts: np.ndarray, attrs: Dict[str, Any]):
    import xarray as xr

    freqs = list(dict.fromkeys(rows["excitation_frequency_hz"].tolist()))
    forces = list(dict.fromkeys(rows["normal_force_n"].tolist()))
    nf, nn = len(freqs), len(forces)
    if nf * nn != len(rows):
        raise ValueError("the sweep's points do not form a frequency x normal-force grid")
    fi = rows["excitation_frequency_hz"].map({f: i for i, f in enumerate(freqs)}).to_numpy()
    ni = rows["normal_force_n"].map({n: i for i, n in enumerate(forces)}).to_numpy()
    order = np.lexsort((ni, fi))

    def grid(column: str) -> np.ndarray:
        return rows[column].to_numpy()[order].reshape(nf, nn)

    counts = counts[order].reshape(nf, nn, -1)
    bins = counts.shape[-1]
    lo, hi = grid("range_lo_m"), grid("range_hi_m")
    width = (hi - lo) / (bins - 2)
    inner = np.arange(bins, dtype=float) - 0.5
    centres = lo[..., None] + inner * width[..., None]
    centres[..., 0] = np.nan
    centres[..., -1] = np.nan
    peaks = grid("peaks").astype(float)
    with np.errstate(invalid="ignore", divide="ignore"):
        density = counts / (peaks[..., None] * width[..., None])
    density[..., 0] = np.nan
    density[..., -1] = np.nan
    quantiles = np.stack([grid("peak_p05_m"), grid("peak_p50_m"), grid("peak_p95_m")], axis=-1)
    fn = ("frequency", "normal_force")
    data = {
        "realisations": (fn, grid("realisations").astype(np.int64)),
        "peaks": (fn, grid("peaks").astype(np.int64)),
        "peak_mean_m": (fn, grid("peak_mean_m")),
        "peak_var_m2": (fn, grid("peak_var_m2")),
        "peak_quantile_m": (fn + ("quantile",), quantiles),
        "stick_fraction": (fn, grid("stick_fraction")),
        "phase_mean_deg": (fn, grid("phase_mean_deg")),
        "phase_var_deg2": (fn, grid("phase_var_deg2")),
        "histogram_count": (fn + ("bin",), counts),
        "histogram_lo_m": (fn, lo),
        "histogram_hi_m": (fn, hi),
        "bin_centre_m": (fn + ("bin",), centres),
        "density_per_m": (fn + ("bin",), density),
    }
    ds = xr.Dataset(
        {k: xr.Variable(dims, v) for k, (dims, v) in data.items()},
        coords={
            "frequency": ("frequency", np.asarray(freqs, dtype=float)),
            "normal_force": ("normal_force", np.asarray(forces, dtype=float)),
            "quantile": ("quantile", np.asarray(_QUANTILES)),
            "bin": ("bin", np.arange(bins)),
        },
        attrs={k: v for k, v in attrs.items() if v is not None},
    )
    for name in list(ds.data_vars) + ["frequency", "normal_force", "quantile", "bin"]:
        if name in UNITS:
            ds[name].attrs["units"] = UNITS[name]
        if name in _DESCRIPTIONS:
            ds[name].attrs["long_name"] = _DESCRIPTIONS[name]
    ds["quantile"].attrs["units"] = "1"
    return ds


def sweep(
    frequencies: Grid = "5:15:41",
    normal_forces: Grid = "4,8,12,16.39",
    *,
    realisations: int = 64,
    warmup_cycles: int = 100,
    cycles: int = 100,
    seed: int = 1,
    model: ModelSpec = None,
    overrides: Overrides = None,
    backend: str = "auto",
    allow_software_gpu: bool = False,
    refine: bool = True,
    refine_max: int = 16,
    out: Optional[PathLike] = None,
    plots: bool = True,
    fig8_frequency: float = 7.0,
    progress: bool = False,
    as_xarray: Optional[bool] = None,
    force: bool = False,
):
    """Runs a frequency x normal-force grid, as ``stickslip sweep`` does.

    ``frequencies`` (Hz) and ``normal_forces`` (N) are sequences, single
    numbers, or the command line's text (``"6,7,8"``, ``"5:15:41"``).
    ``cycles`` are the measured periods per realisation (one peak each),
    after ``warmup_cycles``. ``backend`` is ``"auto"`` (a hardware GPU, else
    the f64 CPU reference), ``"gpu"`` (a GPU; a software one such as lavapipe
    only with ``allow_software_gpu=True``, as ``--allow-software-gpu``) or
    ``"cpu"``. ``refine`` adds up to ``refine_max`` frequencies where the
    response changes fast (resonance, stick onset), as ``stickslip sweep``
    does unless ``--no-refine``; only increasing frequency lists of two or
    more are refined, and ``ds.attrs["refined_frequencies_hz"]`` lists what
    was added. With ``out``, the output set of the command line
    (``sweep.csv``, ``histograms.csv``, ``accumulators.json``, ``sweep.json``
    and, with ``plots``, the figures) is written there too.

    Returns an ``xarray.Dataset`` with dims ``frequency`` x ``normal_force``
    (plus ``quantile`` and histogram ``bin``), every variable with ``units``;
    without xarray (or with ``as_xarray=False``) a ``pandas.DataFrame`` of the
    ``sweep.csv`` rows. The run's backend, adapter, seed and timings are in
    ``attrs``.

    A sweep whose estimated work is beyond the cost budget (``docs/formats.md``,
    as the command line's) raises ``ValueError`` before anything runs, saying
    the estimate and the limit; ``force=True`` runs it anyway, as ``--force``.
    """
    toml_text, _ = _resolve(model, overrides)
    payload, hist = _native.run_sweep(
        toml_text,
        _grid("frequencies", frequencies),
        _grid("normal_forces", normal_forces),
        realisations=int(realisations),
        warmup_cycles=int(warmup_cycles),
        cycles=int(cycles),
        seed=int(seed),
        backend=backend,
        allow_software_gpu=bool(allow_software_gpu),
        refine=bool(refine),
        refine_max=int(refine_max),
        out=None if out is None else os.fspath(out),
        fig8_frequency_hz=float(fig8_frequency) if plots else None,
        progress=progress,
        force=bool(force),
    )
    attrs = {"model_toml": toml_text, "source": "stickslip.sweep"}
    if out is not None:
        attrs["out"] = os.fspath(out)
    return _payload_to_object(payload, hist, attrs, as_xarray)


def peak_density(
    ds, frequency: float, normal_force: float, bins: int = 40
) -> Tuple[np.ndarray, np.ndarray]:
    """The peak-amplitude density at the grid point nearest (frequency,
    normal_force), Figure 8 style: returns ``(centres_m, density_per_m)``.

    The histogram's inner bins are merged in groups aligned to its edges, so
    that about ``bins`` bins span the occupied range (no aliasing).
    """
    point = ds.sel(frequency=frequency, normal_force=normal_force, method="nearest")
    counts = np.asarray(point["histogram_count"].values, dtype=float)[1:-1]
    lo, hi = float(point["histogram_lo_m"]), float(point["histogram_hi_m"])
    total = float(point["peaks"])
    width = (hi - lo) / counts.size
    occupied = np.flatnonzero(counts)
    if occupied.size == 0 or total <= 0:
        return np.empty(0), np.empty(0)
    group = max(1, math.ceil((occupied[-1] - occupied[0] + 1) / max(1, int(bins))))
    start = occupied[0] - occupied[0] % group
    n = math.ceil((occupied[-1] + 1 - start) / group)
    padded = np.zeros(n * group)
    take = counts[start : start + n * group]
    padded[: take.size] = take
    merged = padded.reshape(n, group).sum(axis=1)
    centres = lo + (start + group * (np.arange(n) + 0.5)) * width
    return centres, merged / (total * group * width)


# ----------------------------------------------------------------------------
# Records
# ----------------------------------------------------------------------------


@dataclass
class Records:
    """Time-series records of one condition (every array in SI units).

    ``t_s`` has shape (samples,), from the record's start; the channels
    ``x_m``, ``v_m_per_s``, ``normal_force_n`` and ``friction_force_n`` have
    shape (records, samples). ``array`` is all five, (records, samples, 5),
    in the order t, x, v, N, F.
    """

    array: np.ndarray
    excitation_frequency_hz: float
    normal_force_n: float
    sample_rate_hz: float
    seed: Optional[int] = None
    files: List[str] = field(default_factory=list)

    CHANNELS = ("t", "x", "v", "normal_force", "friction_force")

    @property
    def t_s(self) -> np.ndarray:
        return self.array[0, :, 0]

    @property
    def x_m(self) -> np.ndarray:
        return self.array[:, :, 1]

    @property
    def v_m_per_s(self) -> np.ndarray:
        return self.array[:, :, 2]

    @property
    def normal_force(self) -> np.ndarray:
        return self.array[:, :, 3]

    @property
    def friction_force(self) -> np.ndarray:
        return self.array[:, :, 4]

    def __len__(self) -> int:
        return self.array.shape[0]

    def to_xarray(self):
        """An ``xarray.Dataset`` with dims record x t."""
        import xarray as xr

        ds = xr.Dataset(
            {
                "x": (("record", "t"), self.x_m, {"units": "m", "long_name": "block displacement"}),
                "v": (("record", "t"), self.v_m_per_s, {"units": "m/s", "long_name": "block velocity"}),
                "normal_force": (("record", "t"), self.normal_force, {"units": "N"}),
                "friction_force": (("record", "t"), self.friction_force, {"units": "N"}),
            },
            coords={"t": ("t", self.t_s, {"units": "s"}), "record": np.arange(len(self))},
            attrs={
                "excitation_frequency_hz": self.excitation_frequency_hz,
                "normal_force_n": self.normal_force_n,
                "sample_rate_hz": self.sample_rate_hz,
            },
        )
        if self.seed is not None:
            ds.attrs["seed"] = self.seed
        return ds


def simulate(
    frequency: float = 7.0,
    normal_force: float = 16.39,
    *,
    realisations: int = 3,
    duration: float = 50.0,
    sample_rate: float = 600.0,
    warmup_cycles: int = 100,
    seed: int = 1,
    model: ModelSpec = None,
    overrides: Overrides = None,
    out: Optional[PathLike] = None,
    force: bool = False,
) -> Records:
    """Time-series records of one condition, as ``stickslip simulate`` writes
    them: ``duration`` s sampled at ``sample_rate`` Hz after
    ``warmup_cycles`` periods, one record per realisation. Records always
    come from the exact f64 reference (the GPU kernel does not sample
    records). With ``out``, the run files and ``manifest.json`` are written
    there as well, a measurement set :func:`diagnose` can read. Work beyond
    the cost budget raises ``ValueError`` unless ``force=True``, as in
    :func:`sweep`."""
    toml_text, _ = _resolve(model, overrides)
    n, buffer = _native.run_simulate(
        toml_text,
        frequency_hz=float(frequency),
        normal_force_n=float(normal_force),
        realisations=int(realisations),
        duration_s=float(duration),
        sample_rate_hz=float(sample_rate),
        warmup_cycles=int(warmup_cycles),
        seed=int(seed),
        out=None if out is None else os.fspath(out),
        force=bool(force),
    )
    array = np.frombuffer(buffer, dtype="<f8").reshape(int(realisations), n, 5).copy()
    return Records(array, float(frequency), float(normal_force), float(sample_rate), int(seed))


# ----------------------------------------------------------------------------
# Diagnosis
# ----------------------------------------------------------------------------


@dataclass
class Diagnosis:
    """A diagnosis: ``report`` is ``report.json`` as Python objects;
    ``baseline_toml``/``fitted_toml`` are the two model files' text (and
    ``baseline``/``fitted`` the same as dicts, ready for :func:`sweep`);
    ``paths`` names the files when they were written or loaded."""

    report: Dict[str, Any]
    baseline_toml: str
    fitted_toml: str
    backend: Optional[str] = None
    paths: Dict[str, str] = field(default_factory=dict)

    @property
    def verdict(self) -> Dict[str, Any]:
        return self.report["verdict"]

    @property
    def effects(self) -> List[Dict[str, Any]]:
        """Every effect of the verdict, best first (``verdict.effects``)."""
        return self.report["verdict"]["effects"]

    @property
    def gap(self) -> Dict[str, Any]:
        return self.report["gap"]

    @property
    def baseline(self) -> Dict[str, Any]:
        return _toml_dict(self.baseline_toml)

    @property
    def fitted(self) -> Dict[str, Any]:
        return _toml_dict(self.fitted_toml)

    @property
    def locations(self) -> "pd.DataFrame":
        """Where the baseline departs from the data (|z| > 3), as a table."""
        return pd.DataFrame(self.report.get("locations", []))

    @property
    def candidates(self) -> "pd.DataFrame":
        return pd.DataFrame(self.report.get("candidates", []))


def _toml_dict(text: str) -> Dict[str, Any]:
    # The native side parses TOML; hand it over as text, get JSON back.
    return json.loads(_native.model(toml_text=text)[1])


def diagnose(
    path: PathLike,
    *,
    out: Optional[PathLike] = None,
    backend: str = "auto",
    allow_software_gpu: bool = False,
    seed: int = 20_251_122,
    replicates: int = 8,
    realisations: int = 64,
    progress: bool = True,
    force: bool = False,
    sample_rate_hz: Optional[float] = None,
) -> Diagnosis:
    """Diagnoses the gap between a measurement set (a directory with
    ``manifest.json``) and the model, as ``stickslip diagnose`` does: where,
    which effect, how far the gap shrinks. With ``out``, ``report.json``,
    ``report.html``, the charts and the two model files are written there.
    A diagnosis takes from seconds to minutes: each step is printed to stderr
    as it starts (``progress=False`` silences it). ``backend`` and
    ``allow_software_gpu`` are those of :func:`sweep`, and so is ``force``:
    a diagnosis estimated beyond the cost budget raises ``ValueError`` unless
    ``force=True``. ``sample_rate_hz`` thins each run to that rate by keeping
    every k-th sample (its rate divided by a whole number), for records
    sampled far faster than the response needs."""
    report, baseline, fitted, description = _native.run_diagnose(
        os.fspath(path),
        out=None if out is None else os.fspath(out),
        backend=backend,
        allow_software_gpu=bool(allow_software_gpu),
        seed=int(seed),
        replicates=int(replicates),
        realisations=int(realisations),
        progress=progress,
        force=bool(force),
        sample_rate_hz=None if sample_rate_hz is None else float(sample_rate_hz),
    )
    paths: Dict[str, str] = {}
    if out is not None:
        report_dict = json.loads(report)
        models = report_dict.get("models", {})
        paths = {"report": os.path.join(os.fspath(out), "report.json")}
        for key in ("baseline", "fitted"):
            if key in models:
                paths[key] = os.path.join(os.fspath(out), models[key])
    return Diagnosis(json.loads(report), baseline, fitted, description, paths)


# ----------------------------------------------------------------------------
# Loading output sets
# ----------------------------------------------------------------------------


def _load_run_file(path: Path) -> pd.DataFrame:
    return pd.read_csv(path)


def _load_measurements(directory: Path) -> Dict[str, Any]:
    manifest = json.loads((directory / "manifest.json").read_text(encoding="utf-8-sig"))
    summary = None
    if manifest.get("summary"):
        summary = pd.read_csv(directory / manifest["summary"])
    runs = []
    for entry in manifest.get("runs", []):
        frame = _load_run_file(directory / entry["file"])
        runs.append({**entry, "data": frame})
    result: Dict[str, Any] = {"kind": "measurements", "manifest": manifest, "summary": summary, "runs": runs}
    if (directory / "model.toml").is_file():
        result["model_toml"] = (directory / "model.toml").read_text(encoding="utf-8")
    return result


def _load_sweep(directory: Path, as_xarray: Optional[bool]):
    sidecar: Dict[str, Any] = {}
    if (directory / "sweep.json").is_file():
        sidecar = json.loads((directory / "sweep.json").read_text(encoding="utf-8"))
    if (directory / "accumulators.json").is_file():
        payload, hist = _native.read_sweep(os.fspath(directory))
        attrs: Dict[str, Any] = {"source": os.fspath(directory)}
        meta = json.loads(payload)
        attrs["model_toml"] = meta.get("model_toml")
        if "adapter" in sidecar:
            attrs["adapter"] = sidecar["adapter"]
        if "stickslip_version" in sidecar:
            attrs["stickslip_version"] = sidecar["stickslip_version"]
        timings = sidecar.get("timings") or {}
        if isinstance(timings, dict) and "run_s" in timings:
            attrs["run_s"] = timings["run_s"]
        shard = meta.get("shard")
        if shard and shard != [0, 1]:
            attrs["shard"] = f"{shard[0]}/{shard[1]}"
        return _payload_to_object(payload, hist, attrs, as_xarray)
    # Only sweep.csv: the statistics without histograms.
    frame = pd.read_csv(directory / "sweep.csv")
    frame.attrs.update(source=os.fspath(directory))
    frame.attrs["units"] = {c: UNITS[c] for c in frame.columns if c in UNITS}
    return frame


def load(directory: PathLike, *, as_xarray: Optional[bool] = None):
    """Reads an output set stickslip wrote, by what it holds:

    - a sweep (``accumulators.json``/``sweep.csv``): the Dataset (or DataFrame)
      :func:`sweep` returns, from the verified exact sums;
    - a diagnosis (``report.json``): a :class:`Diagnosis`;
    - a measurement set or ``stickslip simulate`` output (``manifest.json``):
      a dict with the manifest, the summary table and each run's records as a
      DataFrame (columns t, x, v, normal_force, friction_force).
    """
    d = Path(directory)
    if not d.is_dir():
        raise FileNotFoundError(f"{d}: not a directory")
    if (d / "report.json").is_file():
        report = json.loads((d / "report.json").read_text(encoding="utf-8"))
        models = report.get("models", {"baseline": "baseline-model.toml", "fitted": "fitted-model.toml"})
        texts = {}
        paths = {"report": os.fspath(d / "report.json")}
        for key in ("baseline", "fitted"):
            p = d / models.get(key, f"{key}-model.toml")
            texts[key] = p.read_text(encoding="utf-8") if p.is_file() else ""
            if p.is_file():
                paths[key] = os.fspath(p)
        return Diagnosis(report, texts["baseline"], texts["fitted"], None, paths)
    if (d / "accumulators.json").is_file() or (d / "sweep.csv").is_file():
        return _load_sweep(d, as_xarray)
    if (d / "manifest.json").is_file():
        return _load_measurements(d)
    raise ValueError(
        f"{d}: not a stickslip output set (no report.json, accumulators.json, sweep.csv or manifest.json)"
    )
