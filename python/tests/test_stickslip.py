"""Tests of the Python package: small grids, so they run in seconds on a CPU
(the GPU test runs the WGSL kernel on lavapipe where there is no GPU)."""

from __future__ import annotations

import json
import math
import os
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import xarray as xr

import stickslip


REPO = Path(__file__).resolve().parents[2]
FIGURE8 = REPO / "data" / "figure8"

# A tiny sweep: 2 frequencies x 1 force x 4 realisations x 20 measured cycles.
TINY = dict(frequencies=[6.5, 7.0], normal_forces=[16.39], realisations=4, warmup_cycles=10, cycles=20, seed=5)


# -- models -------------------------------------------------------------------


def test_model_is_the_paper_rig_and_takes_overrides():
    m = stickslip.model()
    assert m["rig"]["mass_kg"] == 1.028
    assert m["excitation"]["amplitude_m"] == 0.0025
    changed = stickslip.model(overrides={"friction.a": 0.3, "solver": {"steps_per_period": 512}})
    assert changed["friction"]["a"] == 0.3
    assert changed["solver"]["steps_per_period"] == 512
    # --set-style strings work too, and a dict model round-trips.
    assert stickslip.model(overrides=["friction.sigma=0.05"])["friction"]["sigma"] == 0.05
    assert stickslip.model(changed) == changed
    assert "[friction]" in stickslip.model_toml(changed)


def test_model_files_are_read(tmp_path):
    path = tmp_path / "rig.toml"
    path.write_text(stickslip.model_toml(overrides={"friction.a": 0.25}))
    assert stickslip.model(path)["friction"]["a"] == 0.25
    assert stickslip.model(str(path), overrides={"friction.a": 0.2})["friction"]["a"] == 0.2


def test_bad_models_and_settings_raise_value_errors():
    with pytest.raises(ValueError, match="rig.mass_kg"):
        stickslip.model(overrides={"rig.mass_kg": -1.0})
    with pytest.raises(ValueError, match="nosuchtable"):
        stickslip.model(overrides={"nosuchtable.x": 1})
    with pytest.raises(ValueError, match="backend"):
        stickslip.sweep(**{**TINY, "backend": "tpu"})
    with pytest.raises(ValueError, match="frequencies"):
        stickslip.sweep(**{**TINY, "frequencies": [-7.0], "backend": "cpu"})
    with pytest.raises(ValueError, match="more than once"):
        stickslip.sweep(**{**TINY, "frequencies": [7.0, 7.0], "backend": "cpu"})
    with pytest.raises(ValueError, match="realisations"):
        stickslip.sweep(**{**TINY, "realisations": 0, "backend": "cpu"})


def test_work_beyond_the_budget_raises_unless_forced(tmp_path):
    # A noise interval of 1e-9 s is 1.4e8 noise intervals per period at 7 Hz:
    # refused before anything runs or is written, naming Python's force=True.
    tiny_noise = {"noise.interval_s": 1e-9}
    started = time.monotonic()
    small = dict(frequencies=[7.0], normal_forces=[10.0], realisations=2, warmup_cycles=1, cycles=2, backend="cpu")
    with pytest.raises(ValueError, match=r"per period.*force=True") as refused:
        stickslip.sweep(**small, refine=False, overrides=tiny_noise, out=tmp_path / "s")
    assert "--force" not in str(refused.value) and "--realisations" not in str(refused.value)
    with pytest.raises(ValueError, match=r"refinement.*refine=False.*force=True"):
        stickslip.sweep(
            **{**small, "warmup_cycles": 16_000_000, "frequencies": "5:15:41", "normal_forces": "4,8,12,16"}
        )
    with pytest.raises(ValueError, match=r"simulate.*per period.*force=True"):
        stickslip.simulate(7.0, 16.39, realisations=1, duration=2.0, warmup_cycles=1, overrides=tiny_noise,
                           out=tmp_path / "r")
    with pytest.raises(ValueError, match=r"diagnose.*estimated.*force=True"):
        stickslip.diagnose(FIGURE8, out=tmp_path / "d", backend="cpu", realisations=1_000_000, progress=False)
    assert time.monotonic() - started < 20, "refusals come before any work"
    assert list(tmp_path.iterdir()) == [], "a refused run writes nothing"
    # force=True runs it: two measured periods (the fewest a variance
    # needs) of one realisation at 100 Hz with 1e7 noise intervals in each
    # of its three periods (a few seconds).
    forced = dict(frequencies=[100.0], normal_forces=[10.0], realisations=1, warmup_cycles=1, cycles=2,
                  backend="cpu", refine=False, overrides=tiny_noise)
    with pytest.raises(ValueError, match="per period"):
        stickslip.sweep(**forced)
    ds = stickslip.sweep(**forced, force=True, as_xarray=False)
    assert len(ds) == 1 and ds["peaks"].iloc[0] == 2


# -- sweeps -------------------------------------------------------------------


@pytest.fixture(scope="module")
def tiny_cpu():
    return stickslip.sweep(**TINY, backend="cpu")


def test_sweep_returns_a_dataset_with_units(tiny_cpu):
    ds = tiny_cpu
    assert isinstance(ds, xr.Dataset)
    assert dict(ds.sizes) == {"frequency": 2, "normal_force": 1, "quantile": 3, "bin": 2048}
    assert list(ds.frequency.values) == [6.5, 7.0]
    assert list(ds.normal_force.values) == [16.39]
    for name in ["peak_mean_m", "peak_var_m2", "peak_quantile_m", "stick_fraction", "phase_mean_deg",
                 "phase_var_deg2", "density_per_m", "histogram_count"]:
        assert name in ds, name
        assert "units" in ds[name].attrs, name
    assert ds.peak_mean_m.attrs["units"] == "m"
    assert ds.peak_var_m2.attrs["units"] == "m^2"
    assert ds.frequency.attrs["units"] == "Hz"
    assert ds.normal_force.attrs["units"] == "N"
    assert ds.phase_mean_deg.attrs["units"] == "degree"
    assert ds.attrs["backend"] == "cpu"
    assert ds.attrs["seed"] == 5
    assert ds.attrs["measured_cycles"] == 20
    assert "[friction]" in ds.attrs["model_toml"]
    assert (ds.peaks == 4 * 20).all()
    assert (ds.realisations == 4).all()
    # Peaks at 7 Hz and 16.39 N are millimetres, quantiles ordered around the median.
    mean = ds.peak_mean_m.sel(frequency=7.0, normal_force=16.39).item()
    assert 1e-3 < mean < 1e-2
    q = ds.peak_quantile_m.sel(frequency=7.0, normal_force=16.39).values
    assert q[0] <= q[1] <= q[2]
    assert ((ds.stick_fraction >= 0) & (ds.stick_fraction <= 1)).all()
    # The inner bins' densities integrate to the share of peaks inside the range.
    width = (ds.histogram_hi_m - ds.histogram_lo_m) / 2046
    inside = (ds.density_per_m.isel(bin=slice(1, -1)) * width).sum("bin")
    outside = (ds.histogram_count.isel(bin=0) + ds.histogram_count.isel(bin=-1)) / ds.peaks
    np.testing.assert_allclose(inside + outside, 1.0, rtol=1e-12)


def test_sweep_is_reproducible_and_text_grids_parse(tiny_cpu):
    again = stickslip.sweep(frequencies="6.5,7", normal_forces="16.39:16.39:1",
                            **{k: v for k, v in TINY.items() if k not in ("frequencies", "normal_forces")},
                            backend="cpu")
    for name in tiny_cpu.data_vars:
        np.testing.assert_array_equal(tiny_cpu[name].values, again[name].values, err_msg=name)
    np.testing.assert_array_equal(tiny_cpu.histogram_count.values, again.histogram_count.values)


def test_overrides_change_the_result(tiny_cpu):
    stiffer = stickslip.sweep(**TINY, backend="cpu", overrides={"friction.a": 0.6})
    assert (stiffer.peak_mean_m < tiny_cpu.peak_mean_m).all()


def test_dataframe_without_xarray(tiny_cpu):
    frame = stickslip.sweep(**TINY, backend="cpu", as_xarray=False)
    assert isinstance(frame, pd.DataFrame)
    assert list(frame.columns[:4]) == ["excitation_frequency_hz", "normal_force_n", "realisations", "peaks"]
    assert len(frame) == 2
    assert frame.attrs["units"]["peak_mean_m"] == "m"
    np.testing.assert_array_equal(frame.peak_mean_m.values, tiny_cpu.peak_mean_m.values[:, 0])


def test_sweep_writes_the_cli_output_set_and_load_reads_it(tmp_path, tiny_cpu):
    out = tmp_path / "sweep"
    ds = stickslip.sweep(**TINY, backend="cpu", out=out)
    for name in ["sweep.csv", "histograms.csv", "accumulators.json", "sweep.json", "fig8.png", "fig9a.svg"]:
        assert (out / name).is_file(), name
    loaded = stickslip.load(out)
    for name in ["peak_mean_m", "peak_var_m2", "peak_quantile_m", "stick_fraction", "phase_mean_deg",
                 "histogram_count", "density_per_m"]:
        np.testing.assert_array_equal(loaded[name].values, ds[name].values, err_msg=name)
    np.testing.assert_array_equal(loaded.peak_mean_m.values, tiny_cpu.peak_mean_m.values)
    assert loaded.attrs["backend"] == "cpu"
    assert loaded.peak_mean_m.attrs["units"] == "m"
    # sweep.csv itself agrees with the Dataset (written in e-notation, read back exactly).
    csv = pd.read_csv(out / "sweep.csv")
    np.testing.assert_allclose(csv.peak_mean_m.values, ds.peak_mean_m.values[:, 0], rtol=1e-15)


def test_peak_density_is_a_density(tiny_cpu):
    x, p = stickslip.peak_density(tiny_cpu, 7.0, 16.39, bins=20)
    assert x.shape == p.shape and 0 < x.size <= 21
    assert np.all(np.diff(x) > 0)
    width = x[1] - x[0]
    assert math.isclose((p * width).sum(), 1.0, rel_tol=1e-9)


def test_cpu_and_gpu_sweeps_agree():
    """The library's guarantee (tests/integration/sweep.rs): with common
    noise the GPU's f32 kernel and the f64 reference give the same number
    of peaks and means within a relative 1e-4, stick fractions within
    2e-3 and mean phases within 0.01 degree. (On a machine without a GPU
    this runs the kernel on lavapipe, which needs allow_software_gpu.)"""
    cpu = stickslip.sweep(**TINY, backend="cpu")
    gpu = stickslip.sweep(**TINY, backend="gpu", allow_software_gpu=True)
    assert gpu.attrs["backend"] == "gpu" and cpu.attrs["backend"] == "cpu"
    np.testing.assert_array_equal(gpu.peaks.values, cpu.peaks.values)
    np.testing.assert_allclose(gpu.peak_mean_m.values, cpu.peak_mean_m.values, rtol=1e-4)
    np.testing.assert_allclose(gpu.stick_fraction.values, cpu.stick_fraction.values, atol=2e-3)
    np.testing.assert_allclose(gpu.phase_mean_deg.values, cpu.phase_mean_deg.values, atol=1e-2)


def test_gpu_backend_refuses_a_software_adapter_unless_allowed():
    """The command line's policy: backend="gpu" takes a hardware GPU, and a
    software one (lavapipe) only with allow_software_gpu=True."""
    kind, description = stickslip.backend("gpu", allow_software_gpu=True)
    assert kind == "gpu"
    software = "(Cpu," in description or "(Other," in description
    if software:
        with pytest.raises(RuntimeError, match="allow_software_gpu"):
            stickslip.backend("gpu")
        with pytest.raises(RuntimeError, match="allow_software_gpu"):
            stickslip.sweep(**TINY, backend="gpu")
    else:
        assert stickslip.backend("gpu")[0] == "gpu"
    # auto never takes a software adapter.
    assert stickslip.backend("auto")[0] == ("cpu" if software else "gpu")


def test_refinement_adds_frequencies_at_the_resonance():
    grid = dict(frequencies=[9.5, 10.0, 10.5], normal_forces=[4.0], realisations=2, warmup_cycles=30, cycles=5,
                backend="cpu")
    refined = stickslip.sweep(**grid)
    added = refined.attrs["refined_frequencies_hz"]
    assert 0 < len(added) <= 3
    assert refined.sizes["frequency"] == 3 + len(added)
    assert all(9.5 < f < 10.5 for f in added)
    assert list(refined.frequency.values) == sorted(refined.frequency.values)
    plain = stickslip.sweep(**grid, refine=False)
    assert plain.sizes["frequency"] == 3 and plain.attrs["refined_frequencies_hz"] == []
    # The base frequencies' statistics do not depend on the refinement.
    np.testing.assert_array_equal(plain.peak_mean_m.values, refined.peak_mean_m.sel(frequency=[9.5, 10.0, 10.5]).values)


def test_the_namespace_holds_only_the_api():
    names = dir(stickslip)
    for private in ("np", "pd", "os", "json", "tempfile", "math", "Path", "_native", "_api"):
        assert private not in names, private
    assert set(stickslip.__all__) <= set(names)
    assert {"sweep", "simulate", "diagnose", "load", "model"} <= set(names)


# -- records ------------------------------------------------------------------


def test_simulate_returns_arrays():
    rec = stickslip.simulate(7.0, 16.39, realisations=2, duration=2.0, sample_rate=600.0, warmup_cycles=10)
    assert rec.array.shape == (2, 1200, 5)
    assert rec.x_m.shape == (2, 1200) and rec.t_s.shape == (1200,)
    np.testing.assert_allclose(np.diff(rec.t_s), 1 / 600, rtol=1e-9)
    # Times are index / rate exactly (no float noise such as 0.0016666666666669272).
    np.testing.assert_array_equal(rec.t_s, np.arange(1200) / 600.0)
    assert np.isfinite(rec.array).all()
    assert 1e-3 < np.abs(rec.x_m).max() < 1e-2
    # The normal force fluctuates around 16.39 N; friction never exceeds mu_s N by much.
    assert abs(rec.normal_force.mean() - 16.39) < 0.1
    assert np.abs(rec.friction_force).max() < 2 * 16.39
    # Same seed, same records; another seed, other records.
    again = stickslip.simulate(7.0, 16.39, realisations=2, duration=2.0, warmup_cycles=10)
    np.testing.assert_array_equal(rec.array, again.array)
    other = stickslip.simulate(7.0, 16.39, realisations=2, duration=2.0, warmup_cycles=10, seed=2)
    assert not np.array_equal(rec.x_m, other.x_m)
    ds = rec.to_xarray()
    assert ds.x.attrs["units"] == "m" and ds.sizes["t"] == 1200


def test_simulate_writes_a_measurement_set_that_load_reads(tmp_path):
    out = tmp_path / "sim"
    rec = stickslip.simulate(7.0, 16.39, realisations=2, duration=2.0, warmup_cycles=10, out=out)
    assert (out / "manifest.json").is_file() and (out / "model.toml").is_file()
    loaded = stickslip.load(out)
    assert loaded["kind"] == "measurements"
    assert len(loaded["runs"]) == 2
    run = loaded["runs"][1]
    assert run["excitation_frequency_hz"] == 7.0 and run["normal_force_n"] == 16.39
    # Run files hold the shortest round-trip decimal of every f64: exact.
    np.testing.assert_array_equal(run["data"]["x"].to_numpy(), rec.x_m[1])
    np.testing.assert_array_equal(run["data"]["friction_force"].to_numpy(), rec.friction_force[1])


# -- diagnosis ----------------------------------------------------------------


def test_diagnose_thins_records_to_a_sample_rate(tmp_path):
    data = tmp_path / "sim"
    stickslip.simulate(7.0, 16.39, realisations=1, duration=10.0, sample_rate=1200.0, warmup_cycles=10, out=data)
    d = stickslip.diagnose(data, backend="cpu", replicates=2, sample_rate_hz=600, progress=False)
    assert any("thinned to 600" in n for n in d.report["notes"]), d.report["notes"]
    with pytest.raises(ValueError, match="does not divide"):
        stickslip.diagnose(data, backend="cpu", replicates=2, sample_rate_hz=500, progress=False)
    with pytest.raises(ValueError, match="invalid sample_rate_hz"):
        stickslip.diagnose(data, backend="cpu", sample_rate_hz=0, progress=False)
    with pytest.raises(ValueError, match="invalid replicates"):
        stickslip.diagnose(data, backend="cpu", replicates=1, progress=False)


def test_diagnose_figure8_and_load_the_report(tmp_path, capfd):
    out = tmp_path / "diagnosis"
    d = stickslip.diagnose(FIGURE8, out=out, backend="cpu", realisations=8, replicates=2)
    # Progress goes to stderr by default, one line per step.
    assert "stickslip diagnose:" in capfd.readouterr().err
    r = d.report
    assert r["format"].startswith("stickslip-diagnosis/")
    assert isinstance(r["verdict"]["effect"], str)
    assert 0.0 <= r["verdict"]["confidence"] <= 1.0
    assert isinstance(d.effects, list)
    for e in d.effects:
        assert {"effect", "form", "confidence", "share_of_gap", "parameters"} <= set(e)
    if d.effects:
        assert d.effects[0]["effect"] == r["verdict"]["effect"]
    assert {"baseline", "after", "shrink"} <= set(d.gap)
    assert isinstance(d.locations, pd.DataFrame)
    # The model files, as text and as dicts a sweep takes.
    assert "[friction]" in d.baseline_toml and "[friction]" in d.fitted_toml
    assert d.baseline["rig"]["mass_kg"] == pytest.approx(1.028)
    assert set(d.paths) >= {"report", "baseline", "fitted"}
    assert Path(d.paths["fitted"]).read_text().endswith(d.fitted_toml)
    fitted = stickslip.sweep([7.0], [16.39], realisations=4, warmup_cycles=10, cycles=10, model=d.fitted,
                             backend="cpu")
    assert fitted.peak_mean_m.size == 1
    # load() reads the diagnosis back.
    loaded = stickslip.load(out)
    assert isinstance(loaded, stickslip.Diagnosis)
    assert loaded.verdict == json.loads(json.dumps(r["verdict"]))
    assert loaded.fitted == d.fitted


def test_load_reads_a_measurement_set():
    m = stickslip.load(FIGURE8)
    assert m["kind"] == "measurements"
    assert list(m["summary"].normal_force_mean_n) == [7.519, 11.5, 15.3, 16.39]
    assert m["runs"] == []


def test_load_refuses_what_is_not_an_output_set(tmp_path):
    with pytest.raises(ValueError, match="not a stickslip output set"):
        stickslip.load(tmp_path)
    with pytest.raises(FileNotFoundError):
        stickslip.load(tmp_path / "missing")


def test_the_readme_example_reproduces_figure_8d(monkeypatch):
    """The README's "From Python" example runs as written (from the
    repository root) and lands on the paper's Figure 8(d) statistics."""
    import matplotlib

    matplotlib.use("Agg")
    text = (REPO / "README.md").read_text(encoding="utf-8")
    section = text[text.index("## From Python"):]
    code = section[section.index("```python") + len("```python"):]
    code = code[: code.index("```")]
    monkeypatch.chdir(REPO)
    scope: dict = {}
    exec(compile(code, "README.md (From Python)", "exec"), scope)
    ds = scope["ds"]
    assert ds.peak_mean_m.item() == pytest.approx(3.854e-3, rel=0.01)
    assert ds.peak_var_m2.item() == pytest.approx(2.80e-8, rel=0.25)
    import matplotlib.pyplot as plt

    plt.close("all")
