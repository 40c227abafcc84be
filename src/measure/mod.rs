//! Reading measurement sets (`docs/formats.md`).
//!
//! A measurement set is a directory with `manifest.json`, the run files it
//! names (time series, CSV) and an optional summary table (CSV). All values
//! are SI: s, m, m/s, N, Hz.
//!
//! [`read_measurement_set`] refuses every kind of bad input that the spec
//! lists, with an [`Error::Measurement`](crate::Error::Measurement) that names the file, the line (for
//! CSV files; the header is line 1) and what is wrong:
//!
//! - a missing or unreadable file (manifest, run file or summary);
//! - a `format` other than exactly `stickslip-measurements/1`;
//! - a missing required key or column (a summary row needs at least one of
//!   `peak_mean_m` and `phase_mean_deg`; its other statistics may be blank);
//! - a value that is not a finite number;
//! - a mass or frequency that is not positive (zero is refused as well as
//!   negative values; also a negative damping ratio, excitation amplitude,
//!   normal force or variance);
//! - time that does not strictly increase;
//! - a record shorter than ten excitation periods;
//! - a set with neither runs nor summary rows.
//!
//! In addition, because the spec says records are uniformly sampled, a run
//! whose sample interval anywhere differs from the record's median interval
//! by more than 1 % ([`SAMPLING_TOLERANCE`]) is refused. Unknown manifest keys
//! and extra CSV columns are ignored; columns may come in any order.
//!
//! Hostile input is refused too (issue 11):
//!
//! - **Confinement.** Every file the manifest names (and the manifest itself)
//!   must resolve, after following links, inside the set's directory. An
//!   absolute name, a `..` that climbs out or a link that leads out is
//!   refused by name, without the file being opened.
//! - **Bounded reading.** Each file must be a regular file (a FIFO, device or
//!   directory is refused at once, never blocking) within its limit
//!   ([`MAX_MANIFEST_BYTES`](crate::io::MAX_MANIFEST_BYTES),
//!   [`MAX_TABLE_FILE_BYTES`](crate::io::MAX_TABLE_FILE_BYTES)), and the set's
//!   files together within [`MAX_SET_BYTES`](crate::io::MAX_SET_BYTES). A
//!   UTF-8 byte-order mark is accepted. Messages quote at most a short,
//!   escaped excerpt of a file of the set.
//! - **Physical ranges.** Masses, frequencies, amplitudes, forces and the
//!   damping ratio must lie in the model's ranges
//!   ([`limits`](crate::engine::model::limits)), so a set the simulator cannot
//!   run is refused here, not half-way through a diagnosis.
//! - **Sampling.** A record must be sampled above twice its excitation
//!   frequency (Nyquist), with an interval the simulator can hold noise over.
//! - **Channel conventions.** A `v` column must be the rate of change of
//!   `x` (not its mirror image, not in another unit, not a dead channel),
//!   and a friction force must oppose the block's motion where it moves
//!   fastest, not push it along (a reversed sign), and be what the equation
//!   of motion puts on the block at the excitation's harmonics: see
//!   `channels`.
//! - **Summary counts.** `n_peaks` must be at least 1 (2 with a variance) and
//!   at most the periods one simulated record may run.

mod channels;
pub(crate) use channels::fast_motion;
mod csv;
mod json;
mod thin;
mod write;

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::engine::Sample;
use crate::engine::model::{fmt_value, limits};
use crate::error::Result;
use crate::{io, text};
use json::{Bound, Json, bad, kind};

pub use thin::{check_sample_rate, thinned};
pub use write::{RunEntry, write_manifest, write_run_file};

/// The only accepted value of the manifest's `format` key.
pub const FORMAT: &str = "stickslip-measurements/1";

/// Relative deviation of any sample interval from the record's median
/// interval above which a run file is refused as not uniformly sampled.
pub const SAMPLING_TOLERANCE: f64 = 0.01;

/// Shortest accepted record, in excitation periods.
pub const MIN_PERIODS: f64 = 10.0;

/// A measurement set as read from its directory.
#[derive(Clone, Debug, PartialEq)]
pub struct MeasurementSet {
    /// The directory the set was read from.
    pub dir: PathBuf,
    /// Free text from the manifest (empty when absent).
    pub description: String,
    /// The rig without friction contact.
    pub rig: RigInfo,
    /// Time-series records, in manifest order.
    pub runs: Vec<Run>,
    /// Per-condition statistics from the summary table, in file order.
    pub summary: Vec<SummaryRow>,
    /// The summary table's path, when the manifest names one.
    pub summary_file: Option<PathBuf>,
}

/// The manifest's `rig`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigInfo {
    /// Block mass, kg (> 0).
    pub mass_kg: f64,
    /// Natural frequency without friction contact, Hz (> 0).
    pub natural_frequency_hz: f64,
    /// Viscous damping ratio, dimensionless (≥ 0).
    pub damping_ratio: f64,
}

impl RigInfo {
    /// The leaf springs' stiffness k = m (2π f0)², N/m.
    pub fn stiffness_n_per_m(&self) -> f64 {
        self.mass_kg * (std::f64::consts::TAU * self.natural_frequency_hz).powi(2)
    }

    /// The viscous damping c = 2 ζ √(k m), N s/m.
    pub fn damping_n_s_per_m(&self) -> f64 {
        2.0 * self.damping_ratio * (self.stiffness_n_per_m() * self.mass_kg).sqrt()
    }
}

/// One time-series record: a run file plus its manifest entry.
#[derive(Clone, Debug, PartialEq)]
pub struct Run {
    /// The run file (empty for records that did not come from a file).
    pub file: PathBuf,
    /// Excitation frequency, Hz (> 0).
    pub excitation_frequency_hz: f64,
    /// Base excitation amplitude, m (> 0 in a measurement set).
    pub excitation_amplitude_m: f64,
    /// Nominal normal-force setting, N (> 0 in a measurement set).
    pub normal_force_n: f64,
    /// Sample times, s, strictly increasing and uniformly spaced.
    pub t_s: Vec<f64>,
    /// Block displacement relative to the friction element, m.
    pub x_m: Vec<f64>,
    /// Block velocity, m/s, if recorded.
    pub v_m_per_s: Option<Vec<f64>>,
    /// Measured normal force, N, if recorded.
    pub normal_force: Option<Vec<f64>>,
    /// Friction force on the block, N, if recorded.
    pub friction_force: Option<Vec<f64>>,
    /// Where the record's time origin lies relative to the base's motion.
    pub time_origin: TimeOrigin,
}

/// How a run's time relates to the base motion `u = U0 cos(Ω t)` of the
/// model, which every absolute phase (the response's lag behind the base,
/// the normal force's harmonics) is read against.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum TimeOrigin {
    /// `t` is in the model's frame (the format's default).
    #[default]
    Model,
    /// The record starts at an unknown phase of the base (`"time_origin":
    /// "free"` on the run or the manifest): no absolute phase is read
    /// from it.
    Free,
    /// The run has a `base_x` column: its `t` was moved into the model's
    /// frame by the base phase fitted to that column. `shift_s` is what was
    /// subtracted from `t`, s; `amplitude_m` the fitted base amplitude, m.
    BaseChannel { shift_s: f64, amplitude_m: f64 },
}

impl TimeOrigin {
    /// Whether absolute phases may be read from the run.
    pub fn phase_known(self) -> bool {
        self != TimeOrigin::Free
    }
}

/// One row of a summary table: statistics of one condition.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SummaryRow {
    /// Excitation frequency, Hz (> 0).
    pub excitation_frequency_hz: f64,
    /// Base excitation amplitude, m (≥ 0).
    pub excitation_amplitude_m: f64,
    /// Mean normal force, N (≥ 0).
    pub normal_force_mean_n: f64,
    /// Variance of the normal force, N² (≥ 0), if given.
    pub normal_force_var_n2: Option<f64>,
    /// Mean peak amplitude, m, if given.
    pub peak_mean_m: Option<f64>,
    /// Variance of the peak amplitude, m² (≥ 0), if given.
    pub peak_var_m2: Option<f64>,
    /// Number of peaks behind the statistics, if given.
    pub n_peaks: Option<u64>,
    /// Mean phase lag of the response's fundamental behind the base,
    /// degrees, if given (`interfaces.md`).
    pub phase_mean_deg: Option<f64>,
    /// Variance of that phase, degrees² (≥ 0), if given.
    pub phase_var_deg2: Option<f64>,
    /// The row's line in the summary file (header = line 1).
    pub line: u64,
}

impl Run {
    /// A record made from simulated samples (the engine's records), with
    /// every channel present. `file` is left empty.
    pub fn from_samples(
        samples: &[Sample],
        excitation_frequency_hz: f64,
        excitation_amplitude_m: f64,
        normal_force_n: f64,
    ) -> Run {
        Run {
            file: PathBuf::new(),
            excitation_frequency_hz,
            excitation_amplitude_m,
            normal_force_n,
            t_s: samples.iter().map(|s| s.t_s).collect(),
            x_m: samples.iter().map(|s| s.x_m).collect(),
            v_m_per_s: Some(samples.iter().map(|s| s.v_m_per_s).collect()),
            normal_force: Some(samples.iter().map(|s| s.normal_force_n).collect()),
            friction_force: Some(samples.iter().map(|s| s.friction_force_n).collect()),
            time_origin: TimeOrigin::Model,
        }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t_s.len()
    }

    /// Whether the record has no samples.
    pub fn is_empty(&self) -> bool {
        self.t_s.is_empty()
    }

    /// Mean sample interval, s (0 with fewer than two samples).
    pub fn sample_interval_s(&self) -> f64 {
        let n = self.t_s.len();
        if n < 2 {
            return 0.0;
        }
        let span = self.t_s[n - 1] - self.t_s[0];
        if span > 0.0 { span / (n - 1) as f64 } else { 0.0 }
    }

    /// Time the record covers, s: from its first sample to one interval past
    /// its last (`n` samples × interval); 0 when empty.
    pub fn duration_s(&self) -> f64 {
        let n = self.t_s.len();
        if n == 0 { 0.0 } else { n as f64 * self.sample_interval_s() }
    }
}

/// A sample rate (Hz) for messages, rounded to six decimals (a rate of
/// 600 Hz read from sample times is 600.0000000000001).
pub(crate) fn fmt_rate_hz(rate_hz: f64) -> String {
    fmt_value((rate_hz * 1e6).round() / 1e6)
}

/// Sample rate of a record, Hz, from its mean sample interval; 0 for a
/// record with fewer than two samples.
pub fn sample_rate_hz(run: &Run) -> f64 {
    let dt = run.sample_interval_s();
    if dt > 0.0 { 1.0 / dt } else { 0.0 }
}

/// Reads and checks the measurement set in `dir` (its `manifest.json` and
/// the files that names). See the module documentation for what is refused.
pub fn read_measurement_set(dir: &Path) -> Result<MeasurementSet> {
    let manifest_path = dir.join("manifest.json");
    let root = std::fs::canonicalize(dir).map_err(|e| {
        bad(&manifest_path, None, format!("cannot read the manifest: the set's directory cannot be opened: {e}"))
    })?;
    let mut budget = io::MAX_SET_BYTES;
    let bytes =
        read_inside(&root, dir, "manifest.json", &manifest_path, "the manifest", io::MAX_MANIFEST_BYTES, &mut budget)?;
    let root_value: Value = io::parse_json(io::strip_bom(&bytes)).map_err(|e| {
        let line = (e.line() > 0).then_some(e.line() as u64);
        bad(&manifest_path, line, format!("not valid JSON: {}", text::excerpt(&e.to_string(), 160)))
    })?;
    let root_json = &root_value;
    let manifest = Json { file: &manifest_path };
    let top = root_json.as_object().ok_or_else(|| bad(&manifest_path, None, "the manifest must be a JSON object"))?;
    let quote = |v: &Value| text::excerpt(&v.to_string(), text::EXCERPT_CHARS);

    match top.get("format") {
        None => return Err(manifest.missing("format")),
        Some(Value::String(s)) if s == FORMAT => {}
        Some(other) => {
            return Err(bad(&manifest_path, None, format!("`format` is {}, expected \"{FORMAT}\"", quote(other))));
        }
    }
    let description = match top.get("description") {
        None | Some(Value::Null) => String::new(),
        Some(Value::String(s)) => s.clone(),
        Some(other) => {
            return Err(bad(&manifest_path, None, format!("`description` must be a string, found {}", kind(other))));
        }
    };

    let rig_value = top.get("rig").ok_or_else(|| manifest.missing("rig"))?;
    let rig_obj = manifest.object(rig_value, "rig")?;
    let (m_lo, m_hi) = limits::MASS_KG;
    let (f_lo, f_hi) = limits::FREQUENCY_HZ;
    let rig = RigInfo {
        mass_kg: manifest.number(rig_obj, "rig", "mass_kg", Bound::within(m_lo, m_hi), "kg")?,
        natural_frequency_hz: manifest.number(
            rig_obj,
            "rig",
            "natural_frequency_hz",
            Bound::within(f_lo, f_hi),
            "Hz",
        )?,
        damping_ratio: manifest.number(
            rig_obj,
            "rig",
            "damping_ratio",
            Bound::within(0.0, limits::DAMPING_RATIO_BELOW * (1.0 - f64::EPSILON)),
            "",
        )?,
    };

    let run_values: &[Value] = match top.get("runs") {
        None | Some(Value::Null) => &[],
        Some(Value::Array(items)) => items,
        Some(other) => {
            return Err(bad(&manifest_path, None, format!("`runs` must be an array, found {}", kind(other))));
        }
    };
    let summary_name = match top.get("summary") {
        None | Some(Value::Null) => None,
        Some(Value::String(s)) if !s.is_empty() => Some(s.clone()),
        Some(other) => {
            return Err(bad(
                &manifest_path,
                None,
                format!("`summary` must be a file name (string), found {}", quote(other)),
            ));
        }
    };
    if run_values.is_empty() && summary_name.is_none() {
        return Err(bad(&manifest_path, None, "the set has no runs and no summary; it needs at least one of them"));
    }
    let set_origin = time_origin(top.get("time_origin"), "time_origin", &manifest_path)?;

    // Check every manifest entry before touching the files it names.
    let mut entries = Vec::with_capacity(run_values.len());
    for (i, value) in run_values.iter().enumerate() {
        let ctx = format!("runs[{i}]");
        let obj = manifest.object(value, &ctx)?;
        let file = match obj.get("file") {
            None => return Err(manifest.missing(&format!("{ctx}.file"))),
            Some(Value::String(s)) if !s.is_empty() => s.clone(),
            Some(other) => {
                return Err(bad(
                    &manifest_path,
                    None,
                    format!("`{ctx}.file` must be a non-empty file name, found {}", quote(other)),
                ));
            }
        };
        let frequency = manifest.number(obj, &ctx, "excitation_frequency_hz", Bound::within(f_lo, f_hi), "Hz")?;
        // A run is driven by the base and pressed by the friction element:
        // with no excitation the model's block stays at rest, and with no
        // normal force there is no friction to diagnose.
        let amplitude =
            manifest.number(obj, &ctx, "excitation_amplitude_m", Bound::positive(limits::AMPLITUDE_MAX_M), "m")?;
        let force = manifest.number(obj, &ctx, "normal_force_n", Bound::positive(limits::FORCE_MAX_N), "N")?;
        let free = time_origin(obj.get("time_origin"), &format!("{ctx}.time_origin"), &manifest_path)?;
        entries.push((file, frequency, amplitude, force, free || set_origin));
    }

    // One file is one record: listed twice, it would be one record counted
    // twice, or one record of two conditions.
    let mut resolved: Vec<PathBuf> = Vec::with_capacity(entries.len());
    for (i, (file, frequency, _, force, _)) in entries.iter().enumerate() {
        let io::Confined::Inside(path) = io::confine(&root, file) else { continue };
        if let Some(j) = resolved.iter().position(|p| *p == path) {
            let (other, other_frequency, _, other_force, _) = &entries[j];
            return Err(bad(
                &manifest_path,
                None,
                format!(
                    "runs[{i}].file `{}` ({} Hz, {} N) is the same file as runs[{j}].file `{}` ({} Hz, {} N): \
                     one record is one run; list each file once",
                    crate::text::excerpt(file, 120),
                    fmt_value(*frequency),
                    fmt_value(*force),
                    crate::text::excerpt(other, 120),
                    fmt_value(*other_frequency),
                    fmt_value(*other_force)
                ),
            ));
        }
        resolved.push(path);
    }

    let mut runs = Vec::with_capacity(entries.len());
    for (i, (file, frequency, amplitude, force, free)) in entries.into_iter().enumerate() {
        let ctx = format!("runs[{i}]");
        let named_by = format!("manifest.json {ctx}.file");
        let path = dir.join(&file);
        let bytes = read_inside(&root, dir, &file, &manifest_path, &named_by, io::MAX_TABLE_FILE_BYTES, &mut budget)?;
        let run = csv::read_run_file(&path, bytes, frequency, amplitude, force, free)?;
        channels::check_displacement_scale(&run, &rig)?;
        channels::check_force_balance(&run, &rig)?;
        runs.push(run);
    }

    let (summary, summary_file) = match summary_name {
        None => (Vec::new(), None),
        Some(name) => {
            let path = dir.join(&name);
            let bytes = read_inside(
                &root,
                dir,
                &name,
                &manifest_path,
                "manifest.json summary",
                io::MAX_TABLE_FILE_BYTES,
                &mut budget,
            )?;
            (csv::read_summary_file(&path, bytes)?, Some(path))
        }
    };

    Ok(MeasurementSet { dir: dir.to_path_buf(), description, rig, runs, summary, summary_file })
}

/// Whether a manifest's `time_origin` value (at `key`) declares a free time
/// origin: absent or `null` is the model's frame, `"free"` a free one;
/// anything else is refused by name.
fn time_origin(value: Option<&Value>, key: &str, manifest: &Path) -> Result<bool> {
    match value {
        None | Some(Value::Null) => Ok(false),
        Some(Value::String(s)) if s == "free" => Ok(true),
        Some(other) => Err(bad(
            manifest,
            None,
            format!(
                "`{key}` is {}; the only value it takes is \"free\" (the record starts at an unknown phase of \
                 the base); leave it out when `t` is in the frame of u = U0 cos(2π f t), or give a `base_x` column",
                text::excerpt(&other.to_string(), text::EXCERPT_CHARS)
            ),
        )),
    }
}

/// Reads the file `name` of the set whose directory is `dir` (canonical:
/// `root`), refusing, without reading it, a name that leads outside the set
/// (an absolute path, `..`, or a link), and anything that is not a regular
/// file within `limit` bytes or the set's remaining byte `budget`.
fn read_inside(
    root: &Path,
    dir: &Path,
    name: &str,
    manifest: &Path,
    named_by: &str,
    limit: u64,
    budget: &mut u64,
) -> Result<Vec<u8>> {
    let path = dir.join(name);
    let cannot = |problem: String| {
        let what = if name == "manifest.json" && named_by == "the manifest" {
            "cannot read the manifest".to_string()
        } else {
            format!("cannot read the file named by {named_by}")
        };
        bad(&path, None, format!("{what}: {problem}"))
    };
    let resolved = match io::confine(root, name) {
        io::Confined::Inside(p) => p,
        io::Confined::Outside => {
            return Err(bad(
                manifest,
                None,
                format!(
                    "{named_by} `{}` leads outside the measurement set (an absolute path, `..` or a link that \
                     leaves it); every file of a set must lie inside its directory, and this one was not read",
                    text::excerpt(name, 120)
                ),
            ));
        }
        io::Confined::Unresolved(e) => return Err(cannot(e.to_string())),
    };
    let bytes = io::read_bounded(&resolved, limit.min(*budget)).map_err(|e| match e {
        io::ReadRefusal::TooLarge { .. } if *budget < limit => {
            cannot(format!("{e}: the set's files together may hold at most {} bytes", io::MAX_SET_BYTES))
        }
        e => cannot(e.to_string()),
    })?;
    *budget -= bytes.len() as u64;
    Ok(bytes)
}
