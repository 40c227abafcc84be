//! Run files and summary tables: CSV read with the header checked, every
//! field a finite number, and errors that name the file and line.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use super::channels;
use super::json::{Bound, bad};
use super::{MIN_PERIODS, Run, SAMPLING_TOLERANCE, SummaryRow, TimeOrigin, fmt_rate_hz};
use crate::engine::Job;
use crate::engine::model::{fmt_bound, fmt_value, limits};
use crate::error::{Error, Result};
use crate::text::{EXCERPT_CHARS, excerpt};

/// A CSV column the reader wants.
struct Column {
    name: &'static str,
    required: bool,
    /// An empty field means "not given" for this row (summary statistics a
    /// row may lack); otherwise an empty field is refused.
    blank_allowed: bool,
}

impl Column {
    const fn required(name: &'static str) -> Column {
        Column { name, required: true, blank_allowed: false }
    }

    const fn optional(name: &'static str) -> Column {
        Column { name, required: false, blank_allowed: false }
    }

    const fn per_row(name: &'static str) -> Column {
        Column { name, required: false, blank_allowed: true }
    }
}

/// A CSV file read with its header checked: where each wanted column is.
struct Table {
    file: PathBuf,
    reader: csv::Reader<std::io::Cursor<Vec<u8>>>,
    /// Byte offsets of the line ends (`\n`, or a `\r` not followed by `\n`).
    line_ends: Vec<usize>,
    /// Field index of each wanted column, `None` where an optional one is absent.
    index: Vec<Option<usize>>,
    /// The header's line (counted from 1).
    header_line: u64,
}

impl Table {
    /// Parses the content `bytes` of `path`: the header, and where `columns` are.
    fn open(path: &Path, bytes: Vec<u8>, columns: &[Column]) -> Result<Table> {
        let line_ends = (0..bytes.len())
            .filter(|&i| bytes[i] == b'\n' || (bytes[i] == b'\r' && bytes.get(i + 1) != Some(&b'\n')))
            .collect();
        let reader = csv::ReaderBuilder::new()
            .has_headers(true)
            .trim(csv::Trim::All)
            .flexible(false)
            .from_reader(std::io::Cursor::new(bytes));
        let mut table = Table { file: path.to_path_buf(), reader, line_ends, index: Vec::new(), header_line: 1 };
        let header = match table.reader.headers() {
            Ok(header) => header.clone(),
            Err(e) => return Err(table.csv_error(e)),
        };
        if header.iter().all(|h| h.is_empty()) {
            return Err(bad(path, Some(1), "the file is empty: a header row is required"));
        }
        let header_line = header.position().map_or(1, |p| table.line(p.byte()));
        table.header_line = header_line;
        let mut positions: HashMap<&str, usize> = HashMap::new();
        for (i, name) in header.iter().enumerate() {
            if columns.iter().any(|c| c.name == name) && positions.insert(name, i).is_some() {
                return Err(bad(
                    path,
                    Some(header_line),
                    format!("column `{}` appears more than once in the header", excerpt(name, EXCERPT_CHARS)),
                ));
            }
        }
        let mut index = Vec::with_capacity(columns.len());
        for c in columns {
            let at = positions.get(c.name).copied();
            if at.is_none() && c.required {
                let have: Vec<String> = header.iter().take(8).map(|h| excerpt(h, 24)).collect();
                let more = if header.len() > 8 { format!(" and {} more", header.len() - 8) } else { String::new() };
                return Err(bad(
                    path,
                    Some(header_line),
                    format!("missing required column `{}` (the header has: {}{more})", c.name, have.join(", ")),
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
            csv::ErrorKind::UnequalLengths { expected_len, len, .. } => {
                bad(file, line, format!("the row has {len} fields but the header has {expected_len}"))
            }
            csv::ErrorKind::Utf8 { .. } => bad(file, line, "the row is not valid UTF-8 text"),
            csv::ErrorKind::Io(io) => bad(file, line, format!("cannot read the file: {io}")),
            _ => bad(file, line, format!("cannot read the file as CSV: {}", excerpt(&e.to_string(), 160))),
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
                values[j] = match self.index[j].map(|i| record.get(i).unwrap_or("")) {
                    None => None,
                    Some("") if c.blank_allowed => None,
                    Some(text) => Some(parse_number(&self.file, line, c.name, text)?),
                };
            }
            row(line, &values)?;
        }
    }
}

/// The finite number in one CSV field.
fn parse_number(file: &Path, line: u64, column: &str, text: &str) -> Result<f64> {
    let value: f64 = text.parse().map_err(|_| {
        let shown =
            if text.is_empty() { "an empty field".to_string() } else { format!("`{}`", excerpt(text, EXCERPT_CHARS)) };
        bad(file, Some(line), format!("column `{column}`: {shown} is not a number"))
    })?;
    if value.is_finite() {
        Ok(value)
    } else {
        Err(bad(
            file,
            Some(line),
            format!("column `{column}`: `{}` is not a finite number", excerpt(text, EXCERPT_CHARS)),
        ))
    }
}

const RUN_COLUMNS: [Column; 6] = [
    Column::required("t"),
    Column::required("x"),
    Column::optional("v"),
    Column::optional("normal_force"),
    Column::optional("friction_force"),
    Column::optional("base_x"),
];

/// The physically plausible range and unit of each of [`RUN_COLUMNS`]
/// (`docs/formats.md`): displacements within ±10 m, speeds within ±1e4 m/s,
/// a normal force within ±1e6 N (a sample may dip below zero with the
/// sensor's noise; the record's mean may not, [`read_run_file`]) and a
/// friction force within ±1e8 N (the largest force times the largest
/// friction coefficient).
fn run_column_bound(j: usize) -> (Bound, &'static str) {
    let (x, v, n) = (limits::DISPLACEMENT_MAX_M, limits::SPEED_MAX_M_PER_S, limits::FORCE_MAX_N);
    let f = n * limits::FRICTION_COEFFICIENT_MAX;
    match j {
        0 => (Bound::Finite, "s"),
        2 => (Bound::within(-v, v), "m/s"),
        3 => (Bound::within(-n, n), "N"),
        4 => (Bound::within(-f, f), "N"),
        _ => (Bound::within(-x, x), "m"),
    }
}

/// `value` of column `j` of `columns` if it lies in `bound`, else the
/// refusal naming the file, the line and the column.
fn within_bound(path: &Path, line: u64, columns: &[Column], j: usize, value: f64, bound: (Bound, &str)) -> Result<f64> {
    match bound.0.violation(value, bound.1) {
        None => Ok(value),
        Some(problem) => Err(bad(path, Some(line), format!("column `{}`: {problem}", columns[j].name))),
    }
}

/// The factor by which a record's mean measured normal force may differ
/// from its run's nominal setting before the two are taken to be in
/// different units: wear and drift move a load by tens of percent.
const NOMINAL_FORCE_FACTOR: f64 = 3.0;

/// Checks one run file's content (`bytes`, read from `path`).
pub(super) fn read_run_file(
    path: &Path,
    bytes: Vec<u8>,
    frequency_hz: f64,
    amplitude_m: f64,
    force_n: f64,
    free_origin: bool,
) -> Result<Run> {
    let table = Table::open(path, bytes, &RUN_COLUMNS)?;
    let has = |j: usize| table.index[j].is_some();
    let (has_v, has_n, has_f, has_base) = (has(2), has(3), has(4), has(5));
    let mut base = Vec::new();
    let mut t_s = Vec::new();
    let mut x_m = Vec::new();
    let mut v = Vec::new();
    let mut normal = Vec::new();
    let mut friction = Vec::new();
    let mut lines = Vec::new();
    table.for_each_row(&RUN_COLUMNS, |line, values| {
        for (j, value) in values.iter().enumerate() {
            if let Some(value) = *value {
                within_bound(path, line, &RUN_COLUMNS, j, value, run_column_bound(j))?;
            }
        }
        let t = values[0].unwrap_or(f64::NAN);
        match t_s.last() {
            Some(&previous) if t <= previous => {
                return Err(bad(
                    path,
                    Some(line),
                    format!("time does not increase: t = {} s follows t = {} s", fmt_value(t), fmt_value(previous)),
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
        if let Some(value) = values[5] {
            base.push(value);
        }
        Ok(())
    })?;

    // A contact cannot pull: a record whose measured normal force is
    // negative on average has its sign reversed (or is not a normal force).
    let mean_force = normal.iter().sum::<f64>() / normal.len().max(1) as f64;
    if mean_force < 0.0 {
        let first = normal.iter().position(|&v| v < 0.0).map_or(0, |i| lines[i]);
        return Err(bad(
            path,
            Some(first),
            format!(
                "column `normal_force`: its mean over the record, {} N, is negative (the first negative value is on \
                 this line): a contact cannot pull, so the sign convention is reversed or this is not the normal \
                 force",
                fmt_value(mean_force)
            ),
        ));
    }
    // The measured force is the nominal setting plus what moves it (noise,
    // harmonics, drift, wear): tens of percent, not a factor of
    // [`NOMINAL_FORCE_FACTOR`], which is a unit (kN for N) or a setting that
    // is not in newtons.
    if has_n && !normal.is_empty() && force_n > 0.0 {
        let ratio = mean_force / force_n;
        if !(1.0 / NOMINAL_FORCE_FACTOR..=NOMINAL_FORCE_FACTOR).contains(&ratio) {
            return Err(bad(
                path,
                None,
                format!(
                    "column `normal_force`: its mean over the record, {} N, is {} times the run's nominal \
                     normal_force_n, {} N: both are in newtons, and the measured force swings about its setting",
                    fmt_value(mean_force),
                    fmt_value((ratio * 1e3).round() / 1e3),
                    fmt_value(force_n)
                ),
            ));
        }
    }
    let n = t_s.len();
    let period_s = 1.0 / frequency_hz;
    let needed = format!(
        "at least {MIN_PERIODS} excitation periods ({:.6} s at {frequency_hz} Hz) are required",
        MIN_PERIODS * period_s
    );
    if n < 2 {
        return Err(bad(path, None, format!("the record has {n} sample(s); {needed}")));
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
                    "the sample interval {} s (from t = {} s) differs from the record's median interval \
                     {} s by more than {}%: records must be uniformly sampled",
                    fmt_value(dt),
                    fmt_value(w[0]),
                    fmt_value(median),
                    SAMPLING_TOLERANCE * 100.0
                ),
            ));
        }
    }
    let (dt_lo, dt_hi) = limits::NOISE_INTERVAL_S;
    if !(dt_lo..=dt_hi).contains(&median) {
        return Err(bad(
            path,
            None,
            format!(
                "the sample interval {} s lies outside {}..{} s (the simulated replicates hold their noise over \
                 one sample interval)",
                fmt_value(median),
                fmt_bound(dt_lo),
                fmt_bound(dt_hi)
            ),
        ));
    }
    let rate_hz = 1.0 / median;
    if rate_hz <= 2.0 * frequency_hz {
        return Err(bad(
            path,
            None,
            format!(
                "the record is sampled at {} Hz, not above twice its excitation frequency ({} Hz; the Nyquist \
                 rate): its periods and peaks cannot be resolved",
                fmt_rate_hz(rate_hz),
                fmt_value(2.0 * frequency_hz)
            ),
        ));
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
    if has_v {
        channels::check_velocity(path, &t_s, &x_m, &v)?;
    }
    if has_f {
        channels::check_friction(path, &t_s, &x_m, &friction)?;
    }
    let time_origin = if has_base {
        let base = base_phase(&t_s, &base, frequency_hz).ok_or_else(|| {
            bad(
                path,
                None,
                "column `base_x`: the base does not move at the excitation frequency (no phase can be read)",
            )
        })?;
        check_base(path, &base, frequency_hz, amplitude_m)?;
        for t in &mut t_s {
            *t -= base.shift_s;
        }
        TimeOrigin::BaseChannel { shift_s: base.shift_s, amplitude_m: base.amplitude_m }
    } else if free_origin {
        TimeOrigin::Free
    } else {
        TimeOrigin::Model
    };
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
        time_origin,
    })
}

/// The fewest of a `base_x` column's variance about its mean that a
/// sinusoid at the excitation frequency must explain, –: a shaker's base
/// moves as one, up to its sensor's noise and a few per cent of harmonics;
/// a column at another frequency (or the manifest's frequency wrong)
/// leaves most of it, and a phase read against it would mean nothing.
pub(crate) const BASE_SINUSOID_SHARE_MIN: f64 = 0.9;

/// The largest factor by which a `base_x` column's amplitude at the
/// excitation frequency may differ from the run's `excitation_amplitude_m`
/// either way: the model is driven by the latter, so a base measured far
/// from it means one of the two is not what it claims (a column in
/// millimetres, say).
pub(crate) const BASE_AMPLITUDE_FACTOR_MAX: f64 = 2.0;

/// The base read from a `base_x` column ([`base_phase`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct BaseFit {
    /// The shift `s` of `base_x ≈ c + R cos(Ω (t − s))` within one period, s:
    /// subtracting it from `t` puts the record in the frame of `u = U0 cos(Ω t)`.
    pub(crate) shift_s: f64,
    /// The amplitude `R`, m.
    pub(crate) amplitude_m: f64,
    /// The share of the column's variance about its mean that the sinusoid
    /// explains, –.
    pub(crate) share: f64,
}

/// The base's phase in a record's own time: `base_x ≈ c + R cos(Ω (t − s))`
/// fitted by least squares at the excitation frequency. `None` where the
/// base does not move at that frequency.
pub(crate) fn base_phase(t_s: &[f64], base_x_m: &[f64], frequency_hz: f64) -> Option<BaseFit> {
    let omega = std::f64::consts::TAU * frequency_hz;
    let n = t_s.len().min(base_x_m.len());
    let (coefficients, _) = crate::diagnose::features::least_squares(
        n,
        3,
        |i, row| {
            let (s, c) = (omega * t_s[i]).sin_cos();
            row.copy_from_slice(&[1.0, c, s]);
        },
        |i| base_x_m[i],
    )?;
    let (mean, a, b) = (coefficients[0], coefficients[1], coefficients[2]);
    let amplitude = a.hypot(b);
    let scale = base_x_m.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if amplitude.is_nan() || amplitude <= 1e-6 * scale.max(1e-12) {
        return None;
    }
    // The residual summed sample by sample (the normal equations' own
    // would cancel for a column that is nearly all sinusoid).
    let (mut residual, mut total) = (0.0, 0.0);
    for i in 0..n {
        let (s, c) = (omega * t_s[i]).sin_cos();
        residual += (base_x_m[i] - mean - a * c - b * s).powi(2);
        total += (base_x_m[i] - mean).powi(2);
    }
    // a cos Ωt + b sin Ωt = R cos(Ωt − ψ), ψ = atan2(b, a): s = ψ / Ω.
    let psi = b.atan2(a).rem_euclid(std::f64::consts::TAU);
    let share = if total > 0.0 { (1.0 - residual / total).max(0.0) } else { 0.0 };
    Some(BaseFit { shift_s: psi / omega, amplitude_m: amplitude, share })
}

/// Refuses a `base_x` column that is not the base the run declares: one
/// that a sinusoid at the excitation frequency (Hz) does not explain
/// ([`BASE_SINUSOID_SHARE_MIN`]), or whose amplitude there is beyond
/// [`BASE_AMPLITUDE_FACTOR_MAX`] of the declared `amplitude_m` (m; not
/// checked where that is 0).
fn check_base(path: &Path, base: &BaseFit, frequency_hz: f64, amplitude_m: f64) -> Result<()> {
    if base.share < BASE_SINUSOID_SHARE_MIN {
        return Err(bad(
            path,
            None,
            format!(
                "column `base_x`: the base does not move as a sinusoid at the excitation frequency ({} Hz): one \
                 explains {:.1}% of its variance, and at least {:.0}% is needed to read a phase against it (is the \
                 column the base's displacement, and `excitation_frequency_hz` the frequency it moves at?)",
                fmt_value(frequency_hz),
                100.0 * base.share,
                100.0 * BASE_SINUSOID_SHARE_MIN
            ),
        ));
    }
    let ratio = base.amplitude_m / amplitude_m;
    if amplitude_m > 0.0 && !(1.0 / BASE_AMPLITUDE_FACTOR_MAX..=BASE_AMPLITUDE_FACTOR_MAX).contains(&ratio) {
        return Err(bad(
            path,
            None,
            format!(
                "column `base_x`: the base moves {} m at the excitation frequency, {} times the run's \
                 `excitation_amplitude_m` ({} m); the two may differ by at most a factor {} (is the column in metres?)",
                fmt_value(base.amplitude_m),
                if (0.01..1000.0).contains(&ratio) { format!("{ratio:.3}") } else { format!("{ratio:.3e}") },
                fmt_value(amplitude_m),
                fmt_value(BASE_AMPLITUDE_FACTOR_MAX)
            ),
        ));
    }
    Ok(())
}

const SUMMARY_COLUMNS: [Column; 9] = [
    Column::required("excitation_frequency_hz"),
    Column::required("excitation_amplitude_m"),
    Column::required("normal_force_mean_n"),
    Column::per_row("normal_force_var_n2"),
    Column::per_row("peak_mean_m"),
    Column::per_row("peak_var_m2"),
    Column::per_row("n_peaks"),
    Column::per_row("phase_mean_deg"),
    Column::per_row("phase_var_deg2"),
];

/// Reads and checks the summary table.
pub(super) fn read_summary_file(path: &Path, bytes: Vec<u8>) -> Result<Vec<SummaryRow>> {
    let table = Table::open(path, bytes, &SUMMARY_COLUMNS)?;
    if table.index[4].is_none() && table.index[7].is_none() {
        return Err(bad(
            path,
            Some(table.header_line),
            "missing required column `peak_mean_m` (or `phase_mean_deg`, for a table of phases only)",
        ));
    }
    let mut rows = Vec::new();
    table.for_each_row(&SUMMARY_COLUMNS, |line, values| {
        let check = |j: usize, bound: Bound, unit: &str| -> Result<Option<f64>> {
            values[j].map(|value| within_bound(path, line, &SUMMARY_COLUMNS, j, value, (bound, unit))).transpose()
        };
        // Required columns are always present here (`Table::open` checked).
        let required = |j: usize, bound: Bound, unit: &str| -> Result<f64> {
            check(j, bound, unit).map(|v| v.unwrap_or(f64::NAN))
        };
        let n_peaks = match values[6] {
            None => None,
            // A whole number too large for a u64 is counted as the largest
            // (the limit below then names it).
            Some(value) if value >= 0.0 && value.fract() == 0.0 => Some(value.min(u64::MAX as f64) as u64),
            Some(value) => {
                return Err(bad(
                    path,
                    Some(line),
                    format!("column `n_peaks`: {} is not a whole number ≥ 0", fmt_value(value)),
                ));
            }
        };
        let gives_variance = values[5].is_some() || values[8].is_some();
        match n_peaks {
            Some(0) => {
                return Err(bad(path, Some(line), "column `n_peaks`: 0 peaks cannot give a statistic (at least 1)"));
            }
            Some(1) if gives_variance => {
                return Err(bad(path, Some(line), "column `n_peaks`: a variance needs at least 2 peaks, not 1"));
            }
            Some(n) if n > Job::MAX_CYCLES => {
                return Err(bad(
                    path,
                    Some(line),
                    format!(
                        "column `n_peaks`: {n} is more than {} (the most periods one simulated record may run)",
                        Job::MAX_CYCLES
                    ),
                ));
            }
            _ => {}
        }
        let (displacement, phase) = (limits::DISPLACEMENT_MAX_M, limits::PHASE_MAX_DEG);
        let peak_mean_m = check(4, Bound::within(0.0, displacement), "m")?;
        let phase_mean_deg = check(7, Bound::Range { lo: -phase, hi: phase, lo_open: true }, "degrees")?;
        if peak_mean_m.is_none() && phase_mean_deg.is_none() {
            return Err(bad(
                path,
                Some(line),
                "the row gives neither `peak_mean_m` nor `phase_mean_deg`; a summary row needs at least one of them",
            ));
        }
        let (f_lo, f_hi) = limits::FREQUENCY_HZ;
        let force_max = limits::FORCE_MAX_N;
        rows.push(SummaryRow {
            excitation_frequency_hz: required(0, Bound::within(f_lo, f_hi), "Hz")?,
            excitation_amplitude_m: required(1, Bound::positive(limits::AMPLITUDE_MAX_M), "m")?,
            normal_force_mean_n: required(2, Bound::positive(force_max), "N")?,
            normal_force_var_n2: check(3, Bound::within(0.0, force_max * force_max), "N²")?,
            peak_mean_m,
            peak_var_m2: check(5, Bound::within(0.0, displacement * displacement), "m²")?,
            n_peaks,
            phase_mean_deg,
            phase_var_deg2: check(8, Bound::within(0.0, phase * phase), "degrees²")?,
            line,
        });
        Ok(())
    })?;
    if rows.is_empty() {
        return Err(bad(path, None, "the summary table has a header but no rows"));
    }
    // A condition is given once: two rows of it would be two answers to one question.
    let condition = |r: &SummaryRow| (r.excitation_frequency_hz, r.excitation_amplitude_m, r.normal_force_mean_n);
    for (k, row) in rows.iter().enumerate() {
        if let Some(first) = rows[..k].iter().find(|r| condition(r) == condition(row)) {
            let same = SummaryRow { line: first.line, ..*row } == *first;
            return Err(bad(
                path,
                Some(row.line),
                format!(
                    "the condition {} Hz, {} m, {} N is also on line {}{}; give each condition once",
                    fmt_value(row.excitation_frequency_hz),
                    fmt_value(row.excitation_amplitude_m),
                    fmt_value(row.normal_force_mean_n),
                    first.line,
                    if same { " (with the same values)" } else { ", with different values" }
                ),
            ));
        }
    }
    Ok(rows)
}
