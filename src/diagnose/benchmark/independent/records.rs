//! The independent generator's records and sets: sampling, sensor noise, time origins, the writer, and the truth's own path statistics.

use super::*;

/// Where a record's time origin lies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TimeOrigin {
    /// `t` in the frame of `u = U0 cos(2π f t)` (the format's default).
    Model,
    /// Each record starts at a random base phase, `t` from 0; the manifest
    /// says `"time_origin": "free"`.
    Free,
}

/// Standard deviations of the Gaussian sensor noise on each channel.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SensorNoise {
    pub x_m: f64,
    pub v_m_per_s: f64,
    pub normal_force_n: f64,
    pub friction_force_n: f64,
    pub base_x_m: f64,
}

impl Default for SensorNoise {
    fn default() -> Self {
        SensorNoise { x_m: 2e-6, v_m_per_s: 2e-3, normal_force_n: 0.02, friction_force_n: 0.02, base_x_m: 2e-6 }
    }
}

/// How the records of a set are taken.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RecordShape {
    pub runs_per_condition: u32,
    /// Record length after the warm-up, s.
    pub duration_s: f64,
    /// Sampling rate, Hz.
    pub sample_rate_hz: f64,
    pub time_origin: TimeOrigin,
    /// Write the base displacement `u(t)` as a `base_x` column.
    pub base_x: bool,
    /// Write `t`, `x` (and `base_x`) alone, as a rig without velocity or
    /// force sensors would.
    pub displacement_only: bool,
    pub sensor: SensorNoise,
}

impl Default for RecordShape {
    /// Option A: one 50 s run per condition at 600 Hz, model time origin,
    /// no `base_x`.
    fn default() -> Self {
        RecordShape {
            runs_per_condition: 1,
            duration_s: 50.0,
            sample_rate_hz: 600.0,
            time_origin: TimeOrigin::Model,
            base_x: false,
            displacement_only: false,
            sensor: SensorNoise::default(),
        }
    }
}

impl RecordShape {
    /// Option B: a free time origin without `base_x`.
    pub fn free_origin() -> RecordShape {
        RecordShape { time_origin: TimeOrigin::Free, ..RecordShape::default() }
    }

    /// Option C: a free time origin with a `base_x` column.
    pub fn free_origin_with_base() -> RecordShape {
        RecordShape { time_origin: TimeOrigin::Free, base_x: true, ..RecordShape::default() }
    }

    pub(super) fn validate(&self, conditions: &[Condition]) -> Result<()> {
        if self.runs_per_condition == 0 {
            return Err(Error::setting("runs per condition", "must be at least 1"));
        }
        if !(self.duration_s.is_finite() && self.duration_s > 0.0) {
            return Err(Error::setting("record duration", format!("{} s must be positive", self.duration_s)));
        }
        if !(self.sample_rate_hz.is_finite() && self.sample_rate_hz > 0.0) {
            return Err(Error::setting("sample rate", format!("{} Hz must be positive", self.sample_rate_hz)));
        }
        let s = self.sensor;
        for value in [s.x_m, s.v_m_per_s, s.normal_force_n, s.friction_force_n, s.base_x_m] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(Error::setting("sensor noise", format!("{value} must be finite and ≥ 0")));
            }
        }
        for c in conditions {
            c.validate()?;
            if self.sample_rate_hz <= 2.0 * c.excitation_frequency_hz {
                return Err(Error::setting(
                    "sample rate",
                    format!("{} Hz does not resolve {} Hz", self.sample_rate_hz, c.excitation_frequency_hz),
                ));
            }
            if self.duration_s * c.excitation_frequency_hz < 10.0 {
                return Err(Error::setting(
                    "record duration",
                    format!("{} s holds fewer than ten periods at {} Hz", self.duration_s, c.excitation_frequency_hz),
                ));
            }
        }
        Ok(())
    }
}

/// One record's channels, SI units, sensor noise included.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct RecordColumns {
    pub t: Vec<f64>,
    pub x: Vec<f64>,
    pub v: Vec<f64>,
    pub normal_force: Vec<f64>,
    pub friction_force: Vec<f64>,
    /// The base displacement `u(t)`.
    pub base_x: Vec<f64>,
}

pub(super) struct Sampler {
    pub(super) next: u64,
    pub(super) index: u64,
    pub(super) sample_interval_s: f64,
    pub(super) dt: f64,
    pub(super) u0: f64,
    pub(super) out: RecordColumns,
}

impl Sampler {
    /// The step nearest to sample `i`'s time.
    pub(super) fn step_of(&self, i: u64) -> u64 {
        (i as f64 * self.sample_interval_s / self.dt).round() as u64
    }
}

impl Sink for Sampler {
    fn step(&mut self, n: u64, _t: f64, cos: f64, _sin: f64, x: f64, v: f64, normal: f64, friction: f64) {
        if n != self.next {
            return;
        }
        self.out.t.push(self.index as f64 * self.sample_interval_s);
        self.out.x.push(x);
        self.out.v.push(v);
        self.out.normal_force.push(normal);
        self.out.friction_force.push(friction);
        self.out.base_x.push(self.u0 * cos);
        self.index += 1;
        self.next = self.step_of(self.index);
    }
}

/// Simulates run `run` of condition `index` of a set (as [`write_set`]
/// writes it): noise-free channels first, then the sensor noise of `shape`.
pub fn simulate_run(
    truth: &IndependentTruth,
    condition: Condition,
    index: usize,
    run: u32,
    shape: &RecordShape,
    seed: u64,
) -> Result<RecordColumns> {
    truth.validate()?;
    shape.validate(&[condition])?;
    let plant = Plant::new(truth, condition);
    let path = record_path(index, run);
    let phase0 = match shape.time_origin {
        TimeOrigin::Model => 0.0,
        TimeOrigin::Free => TAU * Gauss::new(seed, path, streams::ORIGIN).uniform(),
    };
    let samples = (shape.duration_s * shape.sample_rate_hz).round() as u64;
    let sample_interval_s = 1.0 / shape.sample_rate_hz;
    let mut grid = Grid::new(truth, condition.excitation_frequency_hz, shape.duration_s);
    let mut sampler =
        Sampler { next: 0, index: 0, sample_interval_s, dt: grid.dt, u0: plant.u0, out: RecordColumns::default() };
    grid.record_steps = sampler.step_of(samples - 1) + 1;
    simulate(&plant, grid, seed, path, phase0, &mut sampler);
    let mut out = sampler.out;
    let mut sensor = Gauss::new(seed, path, streams::SENSOR);
    let s = shape.sensor;
    for i in 0..out.t.len() {
        out.x[i] += s.x_m * sensor.normal();
        out.v[i] += s.v_m_per_s * sensor.normal();
        out.normal_force[i] += s.normal_force_n * sensor.normal();
        out.friction_force[i] += s.friction_force_n * sensor.normal();
        out.base_x[i] += s.base_x_m * sensor.normal();
    }
    Ok(out)
}

/// Where [`write_set`] puts the truth of the set in `dir`: `truth.json` in
/// `dir`'s parent (next to the data directory, never inside it — so give
/// each set's data directory a parent of its own, e.g. `set-07/data`).
pub fn truth_path(dir: &Path) -> PathBuf {
    dir.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new(".")).join("truth.json")
}

/// The data file of run `run` of condition `index`.
pub(super) fn run_file(index: usize, run: u32) -> String {
    format!("run-{index:02}-{run}.csv")
}

/// Writes a measurement set simulated from `truth` at `conditions` into
/// `dir` (`manifest.json` and one CSV per run), and the truth with the
/// set's shape and seed into [`truth_path`]`(dir)`. The manifest says
/// nothing of the truth. Same inputs, same bytes.
pub fn write_set(
    dir: &Path,
    truth: &IndependentTruth,
    conditions: &[Condition],
    shape: &RecordShape,
    seed: u64,
) -> Result<()> {
    truth.validate()?;
    if conditions.is_empty() {
        return Err(Error::setting("conditions", "a set needs at least one condition"));
    }
    shape.validate(conditions)?;
    let jobs: Vec<(usize, u32)> =
        (0..conditions.len()).flat_map(|i| (0..shape.runs_per_condition).map(move |r| (i, r))).collect();
    let records: Vec<RecordColumns> = jobs
        .par_iter()
        .map(|&(i, r)| simulate_run(truth, conditions[i], i, r, shape, seed))
        .collect::<Result<Vec<_>>>()?;
    create_dir(dir)?;
    let mut runs = Vec::new();
    for (&(i, r), record) in jobs.iter().zip(&records) {
        let file = run_file(i, r);
        write_run(&dir.join(&file), record, shape)?;
        runs.push(serde_json::json!({
            "file": file,
            "excitation_frequency_hz": conditions[i].excitation_frequency_hz,
            "excitation_amplitude_m": truth.rig.excitation_amplitude_m,
            "normal_force_n": conditions[i].normal_force_n,
        }));
    }
    let mut manifest = serde_json::json!({
        "format": "stickslip-measurements/1",
        "description": "synthetic measurement set from stickslip's independent generator (benchmark-diagnosis)",
        "rig": {
            "mass_kg": truth.rig.mass_kg,
            "natural_frequency_hz": truth.rig.natural_frequency_hz,
            "damping_ratio": truth.rig.damping_ratio,
        },
        "runs": runs,
    });
    if shape.time_origin == TimeOrigin::Free {
        manifest["time_origin"] = serde_json::json!("free");
    }
    write_json(&dir.join("manifest.json"), &manifest)?;
    let truth_file = serde_json::json!({
        "truth": truth,
        "data_directory": dir.file_name().map(|n| n.to_string_lossy().into_owned()),
        "set_seed": seed,
        "record_shape": shape,
        "conditions": conditions
            .iter()
            .map(|c| serde_json::json!({
                "excitation_frequency_hz": c.excitation_frequency_hz,
                "normal_force_n": c.normal_force_n,
            }))
            .collect::<Vec<_>>(),
    });
    write_json(&truth_path(dir), &truth_file)
}

pub(super) fn write_json(path: &Path, value: &serde_json::Value) -> Result<()> {
    write_atomically(path, |w| {
        serde_json::to_writer_pretty(&mut *w, value)?;
        writeln!(w)
    })
}

pub(super) fn write_run(path: &Path, r: &RecordColumns, shape: &RecordShape) -> Result<()> {
    let (all, base_x) = (!shape.displacement_only, shape.base_x);
    write_atomically(path, |w| {
        write!(w, "t,x{}", if all { ",v,normal_force,friction_force" } else { "" })?;
        writeln!(w, "{}", if base_x { ",base_x" } else { "" })?;
        for i in 0..r.t.len() {
            write!(w, "{},{}", r.t[i], r.x[i])?;
            if all {
                write!(w, ",{},{},{}", r.v[i], r.normal_force[i], r.friction_force[i])?;
            }
            if base_x {
                write!(w, ",{}", r.base_x[i])?;
            }
            writeln!(w)?;
        }
        Ok(())
    })
}

// ---------------------------------------------------------------------------
// Truth statistics
// ---------------------------------------------------------------------------

/// One realisation's statistics over the whole periods of its record.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PathStat {
    /// Mean of the per-period peaks (largest `x` in each period), m.
    pub peak_mean_m: f64,
    /// Sample variance of the per-period peaks, m².
    pub peak_var_m2: f64,
    /// Circular mean of the per-period phase lag of the response's
    /// fundamental behind the base (`interfaces.md`), degrees in (−180, 180].
    pub phase_mean_deg: f64,
    /// Circular variance of that lag, `n/(n−1) · (−2 ln R̄)`, degrees².
    pub phase_var_deg2: f64,
    /// Share of the record's time spent stuck (Karnopp rest), –.
    pub stick_fraction: f64,
    /// Periods behind the statistics.
    pub periods: u32,
}

pub(super) struct PeriodStats {
    pub(super) dt: f64,
    /// The time (less half a step) at which the current period ends.
    pub(super) boundary: f64,
    pub(super) period_s: f64,
    pub(super) periods: u32,
    pub(super) current: u32,
    pub(super) peak: f64,
    pub(super) a: f64,
    pub(super) b: f64,
    pub(super) peaks: Vec<f64>,
    pub(super) phases: Vec<f64>,
    pub(super) stuck_steps: u64,
    pub(super) steps: u64,
}

impl PeriodStats {
    pub(super) fn close(&mut self) {
        if self.peak.is_finite() {
            self.peaks.push(self.peak);
            self.phases.push(self.b.atan2(self.a));
        }
        self.peak = f64::NEG_INFINITY;
        self.a = 0.0;
        self.b = 0.0;
        self.current += 1;
    }
}

impl Sink for PeriodStats {
    fn step(&mut self, n: u64, t: f64, cos: f64, sin: f64, x: f64, v: f64, _normal: f64, _friction: f64) {
        let _ = n;
        while t >= self.boundary {
            self.close();
            self.boundary = if self.current < self.periods {
                f64::from(self.current + 1) * self.period_s - 0.5 * self.dt
            } else {
                f64::INFINITY
            };
        }
        if self.current >= self.periods {
            return;
        }
        self.peak = self.peak.max(x);
        self.a += x * cos;
        self.b += x * sin;
        self.steps += 1;
        if v == 0.0 {
            self.stuck_steps += 1;
        }
    }
}

pub(super) fn path_stat(p: &PeriodStats) -> PathStat {
    let n = p.peaks.len() as f64;
    let mean = p.peaks.iter().sum::<f64>() / n.max(1.0);
    let var = if n > 1.0 { p.peaks.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0) } else { 0.0 };
    let (s, c) = p.phases.iter().fold((0.0, 0.0), |(s, c), ph| (s + ph.sin(), c + ph.cos()));
    let r = ((s * s + c * c).sqrt() / n.max(1.0)).clamp(1e-300, 1.0);
    let phase_var = if n > 1.0 { n / (n - 1.0) * (-2.0 * r.ln()) } else { 0.0 };
    let mut mean_phase = s.atan2(c).to_degrees();
    if mean_phase <= -180.0 {
        mean_phase += 360.0;
    }
    PathStat {
        peak_mean_m: mean,
        peak_var_m2: var,
        phase_mean_deg: mean_phase,
        phase_var_deg2: phase_var.to_degrees().to_degrees(),
        stick_fraction: p.stuck_steps as f64 / (p.steps.max(1)) as f64,
        periods: p.peaks.len() as u32,
    }
}

/// Simulates `paths` independent realisations of `truth` at each of
/// `conditions` (model time origin, the truth's warm-up) over the whole
/// excitation periods of a record of `duration_s`, and returns per
/// condition, per path: the mean and variance of the per-period peaks and
/// the circular mean (and variance) of the per-period phase lag. Paths are
/// independent of any written set's runs; parallel over conditions × paths
/// and deterministic (same seed, same numbers, whatever the threads).
pub fn truth_path_stats(
    truth: &IndependentTruth,
    conditions: &[Condition],
    duration_s: f64,
    paths: u32,
    seed: u64,
) -> Vec<Vec<PathStat>> {
    if paths == 0 {
        return vec![Vec::new(); conditions.len()];
    }
    let jobs: Vec<(usize, u32)> = (0..conditions.len()).flat_map(|i| (0..paths).map(move |p| (i, p))).collect();
    let stats: Vec<PathStat> = jobs
        .par_iter()
        .map(|&(i, p)| {
            let c = conditions[i];
            let plant = Plant::new(truth, c);
            let periods = (duration_s * c.excitation_frequency_hz).floor().max(1.0) as u32;
            let period_s = 1.0 / c.excitation_frequency_hz;
            let mut grid = Grid::new(truth, c.excitation_frequency_hz, duration_s);
            grid.record_steps = (f64::from(periods) * period_s / grid.dt).ceil() as u64 + 1;
            let mut sink = PeriodStats {
                dt: grid.dt,
                boundary: period_s - 0.5 * grid.dt,
                period_s,
                periods,
                current: 0,
                peak: f64::NEG_INFINITY,
                a: 0.0,
                b: 0.0,
                peaks: Vec::with_capacity(periods as usize),
                phases: Vec::with_capacity(periods as usize),
                stuck_steps: 0,
                steps: 0,
            };
            simulate(&plant, grid, seed, stats_path(i, p), 0.0, &mut sink);
            while sink.current < sink.periods {
                sink.close();
            }
            path_stat(&sink)
        })
        .collect();
    stats.chunks(paths as usize).map(<[PathStat]>::to_vec).collect()
}
