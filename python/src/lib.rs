//! `stickslip._native`: the engine, sweeps and diagnosis of the stickslip
//! library, called in-process from Python (no subprocess, no files unless
//! asked for).
//!
//! The surface is deliberately small and flat: numbers, strings, JSON text
//! and packed little-endian `f64`/`u64` buffers go in and out, and the pure
//! Python layer (`stickslip/__init__.py`) turns them into numpy arrays,
//! xarray Datasets, pandas DataFrames and dicts. Each function mirrors what
//! the matching command of the command line does (`src/cli/*.rs`), with the
//! same checks, the same engine and the same output files.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::Instant;

use pyo3::exceptions::{PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use serde_json::{Value, json};

use stickslip::app::SweepRequest;
use stickslip::budget::{self, Cost, Force};
use stickslip::diagnose::report::{RunInfo, write_diagnosis_with};
use stickslip::diagnose::{DiagnoseSettings, diagnose_set};
use stickslip::engine::reduce::HISTOGRAM_BINS;
use stickslip::engine::{
    BackendChoice, BackendKind, Condition, Engine, GpuOptions, Job, Model, Oscillator, Point, Record, RunPlan,
};
use stickslip::io::{self, OutputSet, owned};
use stickslip::measure::{MIN_PERIODS, RunEntry, read_measurement_set, write_manifest, write_run_file};
use stickslip::sweep::{self, Grid, RefineSettings, Shard, SweepResult, SweepSettings};

/// A library error as a Python exception: bad input (a model key, a setting,
/// a measurement file) is a `ValueError`, a file system failure an
/// `OSError`, anything else (no GPU, a diverged run) a `RuntimeError`.
fn py_err(e: stickslip::Error) -> PyErr {
    use stickslip::Error as E;
    let text = e.to_string();
    match e {
        E::ModelSyntax { .. } | E::InvalidParameter { .. } | E::InvalidSetting { .. } | E::Measurement { .. } => {
            PyValueError::new_err(text)
        }
        E::Io { .. } => PyOSError::new_err(text),
        _ => PyRuntimeError::new_err(text),
    }
}

fn value_error(message: String) -> PyErr {
    PyValueError::new_err(message)
}

fn backend_choice(name: &str) -> PyResult<BackendChoice> {
    match name {
        "auto" => Ok(BackendChoice::Auto),
        "gpu" => Ok(BackendChoice::Gpu),
        "cpu" => Ok(BackendChoice::Cpu),
        other => Err(value_error(format!("invalid backend `{other}`: expected \"auto\", \"gpu\" or \"cpu\""))),
    }
}

/// Opened engines by (backend, whether a software GPU is allowed, steps per dispatch).
type Engines = Mutex<HashMap<(String, bool, u64), Arc<Engine>>>;

/// Engines by (backend, allow_software_gpu, steps per dispatch): opening a
/// GPU adapter and compiling the kernels takes a while, so a notebook opens
/// each once. Which backend a choice takes is [`Engine::open`]'s policy, the
/// command line's too: `gpu` refuses a software adapter (lavapipe) unless
/// `allow_software_gpu`, as `--allow-software-gpu`.
fn engine(choice: &str, allow_software_gpu: bool, steps_per_dispatch: u64) -> PyResult<Arc<Engine>> {
    static ENGINES: OnceLock<Engines> = OnceLock::new();
    let kind = backend_choice(choice)?;
    if steps_per_dispatch == 0 {
        return Err(value_error("invalid steps_per_dispatch: must be at least 1".into()));
    }
    let mut engines = ENGINES.get_or_init(Default::default).lock().unwrap_or_else(|p| p.into_inner());
    let key = (choice.to_string(), allow_software_gpu, steps_per_dispatch);
    if let Some(e) = engines.get(&key) {
        return Ok(e.clone());
    }
    let opened = Arc::new(Engine::open(kind, GpuOptions { steps_per_dispatch, allow_software_gpu }).map_err(py_err)?);
    engines.insert(key, opened.clone());
    Ok(opened)
}

/// Converts a JSON value (a model given as a Python dict) into TOML text.
fn json_to_toml(value: &Value) -> PyResult<String> {
    let table: toml::Table = toml::Table::try_from(value)
        .map_err(|e| value_error(format!("the model dict cannot be written as a model file: {e}")))?;
    toml::to_string(&table).map_err(|e| value_error(format!("the model dict cannot be written as a model file: {e}")))
}

/// Resolves a model: a model file, TOML text, a JSON dict, or the embedded
/// paper rig, with `--set`-style overrides applied, validated.
fn resolve_model(
    config: Option<PathBuf>,
    toml_text: Option<&str>,
    json_text: Option<&str>,
    set: &[String],
) -> PyResult<Model> {
    match (config, toml_text, json_text) {
        (Some(path), None, None) => Model::from_file(&path, set).map_err(py_err),
        (None, Some(text), None) => Model::from_toml_str(text, "model text", set).map_err(py_err),
        (None, None, Some(text)) => {
            let value: Value =
                serde_json::from_str(text).map_err(|e| value_error(format!("the model dict is not valid: {e}")))?;
            Model::from_toml_str(&json_to_toml(&value)?, "model dict", set).map_err(py_err)
        }
        (None, None, None) => Model::paper_rig(set).map_err(py_err),
        _ => Err(value_error("give at most one of a model file, model text or a model dict".into())),
    }
}

/// The package version (kept equal to the stickslip crate's).
#[pyfunction]
fn version() -> &'static str {
    env!("CARGO_PKG_VERSION")
}

/// Parses a grid given as text, as `--frequencies`/`--normal-forces` do: a
/// comma list (`6,7,8`) or `START:STOP:COUNT`.
#[pyfunction]
fn parse_list(name: &str, text: &str) -> PyResult<Vec<f64>> {
    sweep::parse_list(name, text).map_err(py_err)
}

/// The resolved model as `(toml_text, json_text)`.
#[pyfunction]
#[pyo3(signature = (config=None, toml_text=None, json_text=None, set=Vec::new()))]
fn model(
    config: Option<PathBuf>,
    toml_text: Option<&str>,
    json_text: Option<&str>,
    set: Vec<String>,
) -> PyResult<(String, String)> {
    let m = resolve_model(config, toml_text, json_text, &set)?;
    let json = serde_json::to_string(&m).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    Ok((m.to_toml_string(), json))
}

/// Opens a backend and returns `(kind, description)` without running anything.
#[pyfunction]
#[pyo3(signature = (
    backend="auto", allow_software_gpu=false, steps_per_dispatch=stickslip::engine::gpu::DEFAULT_STEPS_PER_DISPATCH
))]
fn open_backend(
    py: Python<'_>,
    backend: &str,
    allow_software_gpu: bool,
    steps_per_dispatch: u64,
) -> PyResult<(String, String)> {
    let backend = backend.to_string();
    let e = py.detach(move || engine(&backend, allow_software_gpu, steps_per_dispatch))?;
    Ok((e.kind().name().to_string(), e.description().to_string()))
}

/// A sweep result as `(json, histograms)`: the JSON holds the rows of
/// `sweep.csv` and each point's histogram range; `histograms` is every
/// point's [`HISTOGRAM_BINS`] counts, point-major, as little-endian `u64`.
fn result_payload(result: &SweepResult, extra: Value) -> PyResult<(String, Vec<u8>)> {
    let rows: Vec<Value> = result
        .rows()
        .iter()
        .zip(&result.accumulators)
        .map(|(r, a)| {
            json!({
                "excitation_frequency_hz": r.excitation_frequency_hz,
                "normal_force_n": r.normal_force_n,
                "realisations": r.realisations,
                "peaks": r.peaks,
                "peak_mean_m": r.peak_mean_m,
                "peak_var_m2": r.peak_var_m2,
                "peak_p05_m": r.peak_p05_m,
                "peak_p50_m": r.peak_p50_m,
                "peak_p95_m": r.peak_p95_m,
                "stick_fraction": r.stick_fraction,
                "phase_mean_deg": r.phase_mean_deg,
                "phase_var_deg2": r.phase_var_deg2,
                "range_lo_m": a.range.lo_m,
                "range_hi_m": a.range.hi_m,
                "non_finite": a.non_finite,
            })
        })
        .collect();
    let mut histograms = Vec::with_capacity(result.accumulators.len() * HISTOGRAM_BINS as usize * 8);
    for a in &result.accumulators {
        if a.histogram.len() != HISTOGRAM_BINS as usize {
            return Err(PyRuntimeError::new_err(format!(
                "a histogram has {} bins, not {HISTOGRAM_BINS}",
                a.histogram.len()
            )));
        }
        for &count in &a.histogram {
            histograms.extend_from_slice(&count.to_le_bytes());
        }
    }
    let mut payload = json!({ "rows": rows, "histogram_bins": HISTOGRAM_BINS });
    if let (Value::Object(p), Value::Object(e)) = (&mut payload, extra) {
        p.extend(e);
    }
    Ok((payload.to_string(), histograms))
}

/// Checks grid values the way the command line does, naming the argument.
fn grid_values(name: &str, values: &[f64], check: fn(f64) -> Option<String>) -> PyResult<()> {
    if values.is_empty() {
        return Err(value_error(format!("invalid {name}: no values")));
    }
    if values.len() > Job::MAX_POINTS {
        return Err(value_error(format!(
            "invalid {name}: {} values; a grid may have at most {}",
            values.len(),
            Job::MAX_POINTS
        )));
    }
    for &v in values {
        if let Some(problem) = check(v) {
            return Err(value_error(format!("invalid {name}: `{v}`: {problem}")));
        }
    }
    // A value given twice would be one grid point written twice.
    for (i, v) in values.iter().enumerate() {
        if values[..i].contains(v) {
            return Err(value_error(format!("invalid {name}: `{v}` is given more than once; give each value once")));
        }
    }
    Ok(())
}

/// Runs a frequency × normal-force sweep (what `stickslip sweep` runs) and,
/// with `out`, writes its output set there as the command line does.
#[pyfunction]
#[pyo3(signature = (
    model_toml, frequencies_hz, normal_forces_n, realisations=64, warmup_cycles=100, cycles=100, seed=1,
    backend="auto", allow_software_gpu=false, refine=true, refine_max=RefineSettings::default().max_added,
    steps_per_dispatch=stickslip::engine::gpu::DEFAULT_STEPS_PER_DISPATCH, out=None,
    fig8_frequency_hz=Some(7.0), progress=false, force=false
))]
#[allow(clippy::too_many_arguments)]
fn run_sweep(
    py: Python<'_>,
    model_toml: &str,
    frequencies_hz: Vec<f64>,
    normal_forces_n: Vec<f64>,
    realisations: u32,
    warmup_cycles: u32,
    cycles: u32,
    seed: u64,
    backend: &str,
    allow_software_gpu: bool,
    refine: bool,
    refine_max: usize,
    steps_per_dispatch: u64,
    out: Option<PathBuf>,
    fig8_frequency_hz: Option<f64>,
    progress: bool,
    force: bool,
) -> PyResult<(String, Vec<u8>)> {
    use stickslip::engine::model::{excitation_frequency_problem, normal_force_problem};
    let model = Model::from_toml_str(model_toml, "model", &[]).map_err(py_err)?;
    grid_values("frequencies", &frequencies_hz, excitation_frequency_problem)?;
    grid_values("normal_forces", &normal_forces_n, normal_force_problem)?;
    let grid = Grid { frequencies_hz, normal_forces_n };
    let points_total = grid.frequencies_hz.len() * grid.normal_forces_n.len();
    if points_total > Job::MAX_POINTS {
        return Err(value_error(format!(
            "invalid grid: frequencies × normal_forces = {points_total} points, over the limit of {} per run",
            Job::MAX_POINTS
        )));
    }
    if let Some(f) = fig8_frequency_hz
        && !f.is_finite()
    {
        return Err(value_error(format!("invalid fig8_frequency: `{f}` is not a finite number")));
    }
    let settings = SweepSettings { realisations, plan: RunPlan { warmup_cycles, measured_cycles: cycles }, seed };
    let refine = refine.then_some(RefineSettings { max_added: refine_max, ..Default::default() });
    let request = SweepRequest { model, grid, settings, refine, shard: Shard::WHOLE, force: Force::keyword(force) };
    let prepared = py.detach(|| request.prepare(out.as_deref().map(|dir| (dir, "out")))).map_err(py_err)?;
    let added_hz = prepared.refinement.as_ref().map_or_else(Vec::new, |r| r.added_hz.clone());
    let backend = backend.to_string();
    let (result, description, kind, run_s) = py.detach(move || -> PyResult<_> {
        let engine = engine(&backend, allow_software_gpu, steps_per_dispatch)?;
        let mut last_percent = u64::MAX;
        let swept = prepared
            .run(&engine, fig8_frequency_hz, &mut |done, total| {
                if progress && total > 0 {
                    let percent = done * 100 / total;
                    if percent / 10 != last_percent / 10 {
                        last_percent = percent;
                        eprintln!("stickslip sweep: {percent:>3}%");
                    }
                }
            })
            .map_err(py_err)?;
        Ok((swept.result, engine.description().to_string(), engine.kind(), swept.run_s))
    })?;
    result_payload(
        &result,
        json!({
            "backend": kind.name(),
            "adapter": description,
            "run_s": run_s,
            "seed": seed,
            "warmup_cycles": warmup_cycles,
            "measured_cycles": cycles,
            "refined_frequencies_hz": added_hz,
            "stickslip_version": version(),
        }),
    )
}

/// Reads a sweep output set's `accumulators.json` (verified as `merge`
/// verifies it) into the same payload as [`run_sweep`].
#[pyfunction]
fn read_sweep(py: Python<'_>, dir: PathBuf) -> PyResult<(String, Vec<u8>)> {
    let (file, result) = py.detach(move || sweep::read_accumulators(&dir)).map_err(py_err)?;
    let id = &file.identity;
    result_payload(
        &result,
        json!({
            "backend": id.backend.name(),
            "seed": id.seed,
            "warmup_cycles": id.warmup_cycles,
            "measured_cycles": id.measured_cycles,
            "model_toml": id.model_toml,
            "frequencies_hz": id.frequencies_hz,
            "normal_forces_n": id.normal_forces_n,
            "shard": [file.shard.index, file.shard.count],
        }),
    )
}

/// Simulates time-series records of one condition (what `stickslip
/// simulate` runs): returns `(samples_per_record, buffer)` with the records
/// as little-endian `f64`, record-major, five channels per sample
/// (t, x, v, N, F). With `out`, also writes the run files and manifest.
#[pyfunction]
#[pyo3(signature = (
    model_toml, frequency_hz=7.0, normal_force_n=16.39, realisations=3, duration_s=50.0, sample_rate_hz=600.0,
    warmup_cycles=100, seed=1, out=None, force=false
))]
#[allow(clippy::too_many_arguments)]
fn run_simulate(
    py: Python<'_>,
    model_toml: &str,
    frequency_hz: f64,
    normal_force_n: f64,
    realisations: u32,
    duration_s: f64,
    sample_rate_hz: f64,
    warmup_cycles: u32,
    seed: u64,
    out: Option<PathBuf>,
    force: bool,
) -> PyResult<(usize, Vec<u8>)> {
    let model = Model::from_toml_str(model_toml, "model", &[]).map_err(py_err)?;
    let condition = Condition { excitation_frequency_hz: frequency_hz, normal_force_n };
    condition.validate_flags("frequency", "normal_force").map_err(py_err)?;
    Oscillator::new(&model, condition).map_err(py_err)?;
    if realisations == 0 || realisations > Job::MAX_REALISATIONS {
        return Err(value_error(format!(
            "invalid realisations: {realisations} must be between 1 and {}",
            Job::MAX_REALISATIONS
        )));
    }
    if !(sample_rate_hz.is_finite() && sample_rate_hz > 2.0 * frequency_hz) {
        return Err(value_error(format!(
            "invalid sample_rate: {sample_rate_hz} Hz; records must be sampled above twice the excitation \
             frequency ({} Hz)",
            2.0 * frequency_hz
        )));
    }
    if !(duration_s.is_finite() && duration_s * frequency_hz >= MIN_PERIODS) {
        return Err(value_error(format!(
            "invalid duration: {duration_s} s; a record must cover at least {MIN_PERIODS} excitation periods"
        )));
    }
    let interval_s = 1.0 / sample_rate_hz;
    let points = [Point::steady(&model, condition)];
    let job = Job {
        model: &model,
        points: &points,
        realisations,
        first_realisation: 0,
        seed,
        plan: RunPlan { warmup_cycles, measured_cycles: 0 },
        record: Record::Samples { interval_s, duration_s, at_noise_boundaries: false },
    };
    job.validate().map_err(py_err)?;
    // Records come from the f64 reference on every backend, so its budget applies.
    Cost::of_job(&job)
        .and_then(|cost| {
            cost.check(
                BackendKind::Cpu,
                budget::cpu_threads(),
                Force::keyword(force),
                "simulate",
                "lower realisations, duration or sample_rate, or raise noise.interval_s",
            )
        })
        .map_err(py_err)?;
    let prepared = match &out {
        Some(dir) => Some(OutputSet::prepare(dir, "out", owned::SIMULATION, &[]).map_err(py_err)?),
        None => None,
    };
    let records = py.detach(|| -> PyResult<_> {
        // Records come from the f64 reference on every backend (the kernel
        // does not sample records), as in the command line.
        let engine = Engine::cpu("simulate runs on the reference");
        let mut records =
            engine.records(&Job { record: Record::Sums, ..job }, interval_s, duration_s).map_err(py_err)?;
        stickslip::cli::exact_sample_times(&mut records, sample_rate_hz);
        if let Some(set) = prepared {
            let mut runs = Vec::new();
            for (r, samples) in records.iter().enumerate() {
                let file = format!("run-{frequency_hz:.3}hz-{normal_force_n:.3}n-r{r:03}.csv");
                write_run_file(&set.dir().join(&file), samples).map_err(py_err)?;
                runs.push(RunEntry {
                    file,
                    excitation_frequency_hz: frequency_hz,
                    excitation_amplitude_m: model.excitation.amplitude_m,
                    normal_force_n,
                });
            }
            let description = format!("simulated by stickslip {} (CPU f64 reference), seed {seed}", version());
            write_manifest(set.dir(), &description, &model, &runs).map_err(py_err)?;
            io::write_atomically(&set.dir().join("model.toml"), |w| w.write_all(model.to_toml_string().as_bytes()))
                .map_err(py_err)?;
            set.commit().map_err(py_err)?;
        }
        Ok(records)
    })?;
    let n = records.first().map_or(0, Vec::len);
    if records.iter().any(|r| r.len() != n) {
        return Err(PyRuntimeError::new_err("the records differ in length"));
    }
    let mut buffer = Vec::with_capacity(records.len() * n * 5 * 8);
    for s in records.iter().flatten() {
        for v in [s.t_s, s.x_m, s.v_m_per_s, s.normal_force_n, s.friction_force_n] {
            buffer.extend_from_slice(&v.to_le_bytes());
        }
    }
    Ok((n, buffer))
}

/// Diagnoses a measurement set (what `stickslip diagnose` runs): returns
/// `(report_json, baseline_toml, fitted_toml, backend_description)`. With
/// `out`, also writes the report, the model files and the charts there.
#[pyfunction]
#[pyo3(signature = (
    dir, out=None, backend="auto", allow_software_gpu=false, seed=20_251_122, replicates=8, realisations=64, progress=true,
    force=false, sample_rate_hz=None
))]
#[allow(clippy::too_many_arguments)]
fn run_diagnose(
    py: Python<'_>,
    dir: PathBuf,
    out: Option<PathBuf>,
    backend: &str,
    allow_software_gpu: bool,
    seed: u64,
    replicates: u32,
    realisations: u32,
    progress: bool,
    force: bool,
    sample_rate_hz: Option<f64>,
) -> PyResult<(String, String, String, String)> {
    let settings = DiagnoseSettings {
        seed,
        replicates,
        ensemble_realisations: realisations,
        sample_rate_hz,
        ..DiagnoseSettings::default()
    };
    settings.check(false).map_err(py_err)?;
    let set = read_measurement_set(&dir).map_err(py_err)?;
    let prepared = match &out {
        Some(o) => Some(OutputSet::prepare(o, "out", owned::DIAGNOSIS, &[dir.as_path()]).map_err(py_err)?),
        None => None,
    };
    let backend = backend.to_string();
    py.detach(move || -> PyResult<_> {
        let engine = engine(&backend, allow_software_gpu, stickslip::engine::gpu::DEFAULT_STEPS_PER_DISPATCH)?;
        if progress {
            eprintln!("stickslip diagnose: backend: {}", engine.description());
        }
        Cost::of_diagnosis(&set, &settings)
            .check(
                engine.kind(),
                budget::cpu_threads(),
                Force::keyword(force),
                "diagnose",
                "lower replicates or realisations, thin the records with sample_rate_hz, or give fewer or shorter \
                 records",
            )
            .map_err(py_err)?;
        let started = Instant::now();
        let diagnosis = diagnose_set(&set, &settings, &engine, &mut |step| {
            if progress {
                eprintln!("stickslip diagnose: {step}");
            }
        })
        .map_err(py_err)?;
        let elapsed = started.elapsed().as_secs_f64();
        let report = match prepared {
            Some(set) => {
                let run = RunInfo { seed: Some(seed), backend: Some(engine.description().to_string()) };
                let report =
                    write_diagnosis_with(set.dir(), &diagnosis, Path::new(&dir), elapsed, &run).map_err(py_err)?;
                set.commit().map_err(py_err)?;
                report
            }
            None => diagnosis.report(&dir, elapsed),
        };
        let json = serde_json::to_string(&report).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        Ok((json, diagnosis.baseline.to_toml_string(), diagnosis.fitted.to_toml_string(), engine.description().into()))
    })
}

/// The native half of the `stickslip` Python package.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(version, m)?)?;
    m.add_function(wrap_pyfunction!(model, m)?)?;
    m.add_function(wrap_pyfunction!(parse_list, m)?)?;
    m.add_function(wrap_pyfunction!(open_backend, m)?)?;
    m.add_function(wrap_pyfunction!(run_sweep, m)?)?;
    m.add_function(wrap_pyfunction!(read_sweep, m)?)?;
    m.add_function(wrap_pyfunction!(run_simulate, m)?)?;
    m.add_function(wrap_pyfunction!(run_diagnose, m)?)?;
    m.add("HISTOGRAM_BINS", HISTOGRAM_BINS)?;
    Ok(())
}
