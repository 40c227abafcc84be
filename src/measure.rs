//! Reading measurement sets (`shared/spec/measurement-format.md`).
//!
//! A measurement set is a directory with `manifest.json`, the run files it
//! names (time series, CSV) and an optional summary table (CSV). All values
//! are SI: s, m, m/s, N, Hz.
//!
//! [`read_measurement_set`] refuses every kind of bad input that the spec
//! lists, with an [`Error::Measurement`] that names the file, the line (for
//! CSV files; the header is line 1) and what is wrong:
//!
//! - a missing or unreadable file (manifest, run file or summary);
//! - a `format` other than exactly `stickslip-measurements/1`;
//! - a missing required key or column;
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

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use serde_json::{Map, Value};

use crate::cpu::Sample;
use crate::error::{Error, Result};

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

/// One time-series record: a run file plus its manifest entry.
#[derive(Clone, Debug, PartialEq)]
pub struct Run {
    /// The run file (empty for records that did not come from a file).
    pub file: PathBuf,
    /// Excitation frequency, Hz (> 0).
    pub excitation_frequency_hz: f64,
    /// Base excitation amplitude, m (≥ 0).
    pub excitation_amplitude_m: f64,
    /// Nominal normal-force setting, N (≥ 0).
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
    /// Mean peak amplitude, m.
    pub peak_mean_m: f64,
    /// Variance of the peak amplitude, m² (≥ 0), if given.
    pub peak_var_m2: Option<f64>,
    /// Number of peaks behind the statistics, if given.
    pub n_peaks: Option<u64>,
    /// The row's line in the summary file (header = line 1).
    pub line: u64,
}

impl Run {
    /// A record made from simulated samples (`cpu::simulate_path` with a
    /// `Sampler`), with every channel present. `file` is left empty.
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
        if span > 0.0 {
            span / (n - 1) as f64
        } else {
            0.0
        }
    }

    /// Time the record covers, s: from its first sample to one interval past
    /// its last (`n` samples × interval); 0 when empty.
    pub fn duration_s(&self) -> f64 {
        let n = self.t_s.len();
        if n == 0 {
            0.0
        } else {
            n as f64 * self.sample_interval_s()
        }
    }
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
    let bytes = std::fs::read(&manifest_path).map_err(|e| {
        bad(
            &manifest_path,
            None,
            format!("cannot read the manifest: {e}"),
        )
    })?;
    let root: Value = serde_json::from_slice(&bytes).map_err(|e| {
        let line = (e.line() > 0).then_some(e.line() as u64);
        bad(&manifest_path, line, format!("not valid JSON: {e}"))
    })?;
    let manifest = Json {
        file: &manifest_path,
    };
    let top = root
        .as_object()
        .ok_or_else(|| bad(&manifest_path, None, "the manifest must be a JSON object"))?;

    match top.get("format") {
        None => return Err(manifest.missing("format")),
        Some(Value::String(s)) if s == FORMAT => {}
        Some(other) => {
            return Err(bad(
                &manifest_path,
                None,
                format!("`format` is {other}, expected \"{FORMAT}\""),
            ));
        }
    }
    let description = match top.get("description") {
        None | Some(Value::Null) => String::new(),
        Some(Value::String(s)) => s.clone(),
        Some(other) => {
            return Err(bad(
                &manifest_path,
                None,
                format!("`description` must be a string, found {}", kind(other)),
            ));
        }
    };

    let rig_value = top.get("rig").ok_or_else(|| manifest.missing("rig"))?;
    let rig_obj = manifest.object(rig_value, "rig")?;
    let rig = RigInfo {
        mass_kg: manifest.number(rig_obj, "rig", "mass_kg", Bound::Positive, "kg")?,
        natural_frequency_hz: manifest.number(
            rig_obj,
            "rig",
            "natural_frequency_hz",
            Bound::Positive,
            "Hz",
        )?,
        damping_ratio: manifest.number(rig_obj, "rig", "damping_ratio", Bound::NonNegative, "")?,
    };

    let run_values: &[Value] = match top.get("runs") {
        None | Some(Value::Null) => &[],
        Some(Value::Array(items)) => items,
        Some(other) => {
            return Err(bad(
                &manifest_path,
                None,
                format!("`runs` must be an array, found {}", kind(other)),
            ));
        }
    };
    let summary_name = match top.get("summary") {
        None | Some(Value::Null) => None,
        Some(Value::String(s)) => Some(s.clone()),
        Some(other) => {
            return Err(bad(
                &manifest_path,
                None,
                format!(
                    "`summary` must be a file name (string), found {}",
                    kind(other)
                ),
            ));
        }
    };
    if run_values.is_empty() && summary_name.is_none() {
        return Err(bad(
            &manifest_path,
            None,
            "the set has no runs and no summary; it needs at least one of them",
        ));
    }

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
                    format!("`{ctx}.file` must be a non-empty file name, found {other}"),
                ));
            }
        };
        let frequency =
            manifest.number(obj, &ctx, "excitation_frequency_hz", Bound::Positive, "Hz")?;
        let amplitude =
            manifest.number(obj, &ctx, "excitation_amplitude_m", Bound::NonNegative, "m")?;
        let force = manifest.number(obj, &ctx, "normal_force_n", Bound::NonNegative, "N")?;
        entries.push((file, frequency, amplitude, force));
    }

    let mut runs = Vec::with_capacity(entries.len());
    for (i, (file, frequency, amplitude, force)) in entries.into_iter().enumerate() {
        let path = dir.join(&file);
        runs.push(read_run_file(
            &path,
            &format!("runs[{i}]"),
            frequency,
            amplitude,
            force,
        )?);
    }

    let (summary, summary_file) = match summary_name {
        None => (Vec::new(), None),
        Some(name) => {
            let path = dir.join(&name);
            (read_summary_file(&path)?, Some(path))
        }
    };

    Ok(MeasurementSet {
        dir: dir.to_path_buf(),
        description,
        rig,
        runs,
        summary,
        summary_file,
    })
}

/// An [`Error::Measurement`].
fn bad(file: &Path, line: Option<u64>, message: impl Into<String>) -> Error {
    Error::Measurement {
        file: file.to_path_buf(),
        line,
        message: message.into(),
    }
}

/// What kind of JSON value `v` is, for messages.
fn kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}

/// Accepted range of a number.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Bound {
    /// Any finite number.
    Finite,
    /// Finite and ≥ 0.
    NonNegative,
    /// Finite and > 0.
    Positive,
}

impl Bound {
    /// `None` if `value` is acceptable, else what is wrong with it.
    fn violation(self, value: f64, unit: &str) -> Option<String> {
        let unit = if unit.is_empty() {
            String::new()
        } else {
            format!(" {unit}")
        };
        if !value.is_finite() {
            return Some(format!("{value} is not a finite number"));
        }
        match self {
            Bound::Finite => None,
            Bound::NonNegative if value < 0.0 => {
                Some(format!("{value} must not be negative (≥ 0{unit})"))
            }
            Bound::Positive if value < 0.0 => {
                Some(format!("{value} must not be negative (> 0{unit})"))
            }
            Bound::Positive if value == 0.0 => {
                Some(format!("{value} must be positive (> 0{unit})"))
            }
            _ => None,
        }
    }
}

/// Helpers that read manifest values with messages naming the manifest.
struct Json<'a> {
    file: &'a Path,
}

impl Json<'_> {
    fn missing(&self, key: &str) -> Error {
        bad(self.file, None, format!("missing required key `{key}`"))
    }

    fn object<'v>(&self, value: &'v Value, ctx: &str) -> Result<&'v Map<String, Value>> {
        value.as_object().ok_or_else(|| {
            bad(
                self.file,
                None,
                format!("`{ctx}` must be an object, found {}", kind(value)),
            )
        })
    }

    /// The required number `ctx.key`, checked against `bound`.
    fn number(
        &self,
        obj: &Map<String, Value>,
        ctx: &str,
        key: &str,
        bound: Bound,
        unit: &str,
    ) -> Result<f64> {
        let value = obj
            .get(key)
            .ok_or_else(|| self.missing(&format!("{ctx}.{key}")))?;
        let number = match value {
            Value::Number(n) => n.as_f64(),
            _ => None,
        }
        .ok_or_else(|| {
            bad(
                self.file,
                None,
                format!("`{ctx}.{key}` must be a number, found {value}"),
            )
        })?;
        match bound.violation(number, unit) {
            None => Ok(number),
            Some(problem) => Err(bad(self.file, None, format!("`{ctx}.{key}` = {problem}"))),
        }
    }
}

/// A CSV column the reader wants.
struct Column {
    name: &'static str,
    required: bool,
}

/// A CSV file read with its header checked: where each wanted column is.
struct Table {
    file: PathBuf,
    reader: csv::Reader<std::io::Cursor<Vec<u8>>>,
    /// Byte offsets of the line ends (`\n`, or a `\r` not followed by `\n`).
    line_ends: Vec<usize>,
    /// Field index of each wanted column, `None` where an optional one is absent.
    index: Vec<Option<usize>>,
}

impl Table {
    /// Reads `path`, parses the header and finds `columns`.
    /// `named_by` says which manifest key names the file (for messages).
    fn open(path: &Path, named_by: &str, columns: &[Column]) -> Result<Table> {
        let bytes = std::fs::read(path).map_err(|e| {
            bad(
                path,
                None,
                format!("cannot read the file named by {named_by}: {e}"),
            )
        })?;
        let line_ends = (0..bytes.len())
            .filter(|&i| {
                bytes[i] == b'\n' || (bytes[i] == b'\r' && bytes.get(i + 1) != Some(&b'\n'))
            })
            .collect();
        let reader = csv::ReaderBuilder::new()
            .has_headers(true)
            .trim(csv::Trim::All)
            .flexible(false)
            .from_reader(std::io::Cursor::new(bytes));
        let mut table = Table {
            file: path.to_path_buf(),
            reader,
            line_ends,
            index: Vec::new(),
        };
        let header = match table.reader.headers() {
            Ok(header) => header.clone(),
            Err(e) => return Err(table.csv_error(e)),
        };
        if header.iter().all(|h| h.is_empty()) {
            return Err(bad(
                path,
                Some(1),
                "the file is empty: a header row is required",
            ));
        }
        let header_line = header.position().map_or(1, |p| table.line(p.byte()));
        let mut positions: HashMap<&str, usize> = HashMap::new();
        for (i, name) in header.iter().enumerate() {
            if columns.iter().any(|c| c.name == name) && positions.insert(name, i).is_some() {
                return Err(bad(
                    path,
                    Some(header_line),
                    format!("column `{name}` appears more than once in the header"),
                ));
            }
        }
        let mut index = Vec::with_capacity(columns.len());
        for c in columns {
            let at = positions.get(c.name).copied();
            if at.is_none() && c.required {
                let have: Vec<&str> = header.iter().collect();
                return Err(bad(
                    path,
                    Some(header_line),
                    format!(
                        "missing required column `{}` (the header has: {})",
                        c.name,
                        have.join(", ")
                    ),
                ));
            }
            index.push(at);
        }
        table.index = index;
        Ok(table)
    }

    /// The line (counted from 1) of the record the csv reader places at
    /// byte `pos`. The reader's own line numbers are wrong for `\r\n` and
    /// `\r` line ends, and its byte offsets may point at the line end before
    /// a record, so line ends at `pos` are skipped first.
    fn line(&self, pos: u64) -> u64 {
        let bytes = self.reader.get_ref().get_ref();
        let mut start = usize::try_from(pos).unwrap_or(usize::MAX).min(bytes.len());
        while start < bytes.len() && matches!(bytes[start], b'\r' | b'\n') {
            start += 1;
        }
        1 + self.line_ends.partition_point(|&end| end < start) as u64
    }

    /// A csv-crate error as a measurement error with the line it happened on.
    fn csv_error(&self, e: csv::Error) -> Error {
        let file = &self.file;
        let line = e.position().map(|p| self.line(p.byte()));
        match e.kind() {
            csv::ErrorKind::UnequalLengths {
                expected_len, len, ..
            } => bad(
                file,
                line,
                format!("the row has {len} fields but the header has {expected_len}"),
            ),
            csv::ErrorKind::Utf8 { .. } => bad(file, line, "the row is not valid UTF-8 text"),
            csv::ErrorKind::Io(io) => bad(file, line, format!("cannot read the file: {io}")),
            _ => bad(file, line, format!("cannot read the file as CSV: {e}")),
        }
    }

    /// Calls `row(line, values)` for every data row; `values[j]` is the
    /// finite number in wanted column `j` (`None` for absent optional columns).
    fn for_each_row(
        mut self,
        columns: &[Column],
        mut row: impl FnMut(u64, &[Option<f64>]) -> Result<()>,
    ) -> Result<()> {
        let mut record = csv::StringRecord::new();
        let mut values = vec![None; columns.len()];
        loop {
            match self.reader.read_record(&mut record) {
                Ok(true) => {}
                Ok(false) => return Ok(()),
                Err(e) => return Err(self.csv_error(e)),
            }
            let line = record.position().map_or(0, |p| self.line(p.byte()));
            for (j, c) in columns.iter().enumerate() {
                values[j] = match self.index[j] {
                    None => None,
                    Some(i) => Some(parse_number(
                        &self.file,
                        line,
                        c.name,
                        record.get(i).unwrap_or(""),
                    )?),
                };
            }
            row(line, &values)?;
        }
    }
}

/// The finite number in one CSV field.
fn parse_number(file: &Path, line: u64, column: &str, text: &str) -> Result<f64> {
    let value: f64 = text.parse().map_err(|_| {
        let shown = if text.is_empty() {
            "an empty field".to_string()
        } else {
            format!("`{text}`")
        };
        bad(
            file,
            Some(line),
            format!("column `{column}`: {shown} is not a number"),
        )
    })?;
    if value.is_finite() {
        Ok(value)
    } else {
        Err(bad(
            file,
            Some(line),
            format!("column `{column}`: `{text}` is not a finite number"),
        ))
    }
}

const RUN_COLUMNS: [Column; 5] = [
    Column {
        name: "t",
        required: true,
    },
    Column {
        name: "x",
        required: true,
    },
    Column {
        name: "v",
        required: false,
    },
    Column {
        name: "normal_force",
        required: false,
    },
    Column {
        name: "friction_force",
        required: false,
    },
];

/// Reads and checks one run file; the manifest entry `ctx` named it.
fn read_run_file(
    path: &Path,
    ctx: &str,
    frequency_hz: f64,
    amplitude_m: f64,
    force_n: f64,
) -> Result<Run> {
    let table = Table::open(path, &format!("manifest.json {ctx}.file"), &RUN_COLUMNS)?;
    let has = |j: usize| table.index[j].is_some();
    let (has_v, has_n, has_f) = (has(2), has(3), has(4));
    let mut t_s = Vec::new();
    let mut x_m = Vec::new();
    let mut v = Vec::new();
    let mut normal = Vec::new();
    let mut friction = Vec::new();
    let mut lines = Vec::new();
    table.for_each_row(&RUN_COLUMNS, |line, values| {
        let t = values[0].unwrap_or(f64::NAN);
        match t_s.last() {
            Some(&previous) if t <= previous => {
                return Err(bad(
                    path,
                    Some(line),
                    format!("time does not increase: t = {t} s follows t = {previous} s"),
                ));
            }
            _ => {}
        }
        t_s.push(t);
        x_m.push(values[1].unwrap_or(f64::NAN));
        lines.push(line);
        if let Some(value) = values[2] {
            v.push(value);
        }
        if let Some(value) = values[3] {
            normal.push(value);
        }
        if let Some(value) = values[4] {
            friction.push(value);
        }
        Ok(())
    })?;

    let n = t_s.len();
    let period_s = 1.0 / frequency_hz;
    let needed = format!(
        "at least {MIN_PERIODS} excitation periods ({:.6} s at {frequency_hz} Hz) are required",
        MIN_PERIODS * period_s
    );
    if n < 2 {
        return Err(bad(
            path,
            None,
            format!("the record has {n} sample(s); {needed}"),
        ));
    }
    let mut intervals: Vec<f64> = t_s.windows(2).map(|w| w[1] - w[0]).collect();
    intervals.sort_by(f64::total_cmp);
    let median = intervals[intervals.len() / 2];
    for (i, w) in t_s.windows(2).enumerate() {
        let dt = w[1] - w[0];
        if (dt - median).abs() > SAMPLING_TOLERANCE * median {
            return Err(bad(
                path,
                Some(lines[i + 1]),
                format!(
                    "the sample interval {dt} s (from t = {} s) differs from the record's median interval \
                     {median} s by more than {}%: records must be uniformly sampled",
                    w[0],
                    SAMPLING_TOLERANCE * 100.0
                ),
            ));
        }
    }
    let duration_s = t_s[n - 1] - t_s[0] + median;
    if duration_s < MIN_PERIODS * period_s * (1.0 - 1e-9) {
        return Err(bad(
            path,
            None,
            format!(
                "the record is too short: {n} samples cover {duration_s:.6} s = {:.3} excitation periods; {needed}",
                duration_s / period_s
            ),
        ));
    }
    Ok(Run {
        file: path.to_path_buf(),
        excitation_frequency_hz: frequency_hz,
        excitation_amplitude_m: amplitude_m,
        normal_force_n: force_n,
        t_s,
        x_m,
        v_m_per_s: has_v.then_some(v),
        normal_force: has_n.then_some(normal),
        friction_force: has_f.then_some(friction),
    })
}

const SUMMARY_COLUMNS: [Column; 7] = [
    Column {
        name: "excitation_frequency_hz",
        required: true,
    },
    Column {
        name: "excitation_amplitude_m",
        required: true,
    },
    Column {
        name: "normal_force_mean_n",
        required: true,
    },
    Column {
        name: "normal_force_var_n2",
        required: false,
    },
    Column {
        name: "peak_mean_m",
        required: true,
    },
    Column {
        name: "peak_var_m2",
        required: false,
    },
    Column {
        name: "n_peaks",
        required: false,
    },
];

/// Reads and checks the summary table.
fn read_summary_file(path: &Path) -> Result<Vec<SummaryRow>> {
    let table = Table::open(path, "manifest.json summary", &SUMMARY_COLUMNS)?;
    let mut rows = Vec::new();
    table.for_each_row(&SUMMARY_COLUMNS, |line, values| {
        let check = |j: usize, bound: Bound, unit: &str| -> Result<Option<f64>> {
            match values[j] {
                None => Ok(None),
                Some(value) => match bound.violation(value, unit) {
                    None => Ok(Some(value)),
                    Some(problem) => Err(bad(
                        path,
                        Some(line),
                        format!("column `{}`: {problem}", SUMMARY_COLUMNS[j].name),
                    )),
                },
            }
        };
        // Required columns are always present here (`Table::open` checked).
        let required = |j: usize, bound: Bound, unit: &str| -> Result<f64> {
            check(j, bound, unit).map(|v| v.unwrap_or(f64::NAN))
        };
        let n_peaks = match values[6] {
            None => None,
            Some(value)
                if value >= 0.0 && value.fract() == 0.0 && value <= 9_007_199_254_740_992.0 =>
            {
                Some(value as u64)
            }
            Some(value) => {
                return Err(bad(
                    path,
                    Some(line),
                    format!("column `n_peaks`: {value} is not a whole number ≥ 0"),
                ));
            }
        };
        rows.push(SummaryRow {
            excitation_frequency_hz: required(0, Bound::Positive, "Hz")?,
            excitation_amplitude_m: required(1, Bound::NonNegative, "m")?,
            normal_force_mean_n: required(2, Bound::NonNegative, "N")?,
            normal_force_var_n2: check(3, Bound::NonNegative, "N²")?,
            peak_mean_m: required(4, Bound::Finite, "m")?,
            peak_var_m2: check(5, Bound::NonNegative, "m²")?,
            n_peaks,
            line,
        });
        Ok(())
    })?;
    if rows.is_empty() {
        return Err(bad(
            path,
            None,
            "the summary table has a header but no rows",
        ));
    }
    Ok(rows)
}
