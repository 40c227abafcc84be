//! Shards: part K of N of a grid (`sweep --shard K/N`), its exact sums in
//! `accumulators.json`, and the merge that combines parts into exactly what
//! the unsharded run writes.

use std::path::Path;

use crate::engine::{BackendKind, Condition, PeakRange, PointAccumulator};
use crate::error::{Error, Result};
use crate::sweep::SweepResult;

/// One part of a grid split across machines: shard `index` of `count`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Shard {
    pub index: u32,
    pub count: u32,
}

impl Shard {
    /// The whole grid.
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    /// Parses `K/N` (zero-based `K < N`).
    pub fn parse(text: &str) -> Result<Shard> {
        let bad = |m: &str| Error::setting("--shard", format!("`{text}`: {m}"));
        let (k, n) = text.split_once('/').ok_or_else(|| bad("expected K/N, e.g. 0/4"))?;
        let index: u32 = k.trim().parse().map_err(|_| bad("K is not a whole number"))?;
        let count: u32 = n.trim().parse().map_err(|_| bad("N is not a whole number"))?;
        if count == 0 || index >= count {
            return Err(bad("need 0 <= K < N"));
        }
        Ok(Shard { index, count })
    }

    /// The contiguous range of grid-point indices this shard runs.
    pub fn points(&self, total: usize) -> std::ops::Range<usize> {
        let part = |k: u32| (total as u64 * u64::from(k) / u64::from(self.count)) as usize;
        part(self.index)..part(self.index + 1)
    }
}

/// What identifies a run: everything that determines its numbers. Shards
/// merge only when these are equal.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RunIdentity {
    pub model_toml: String,
    pub frequencies_hz: Vec<f64>,
    pub normal_forces_n: Vec<f64>,
    pub realisations: u32,
    pub warmup_cycles: u32,
    pub measured_cycles: u32,
    pub seed: u64,
    /// `gpu` or `cpu`: f32 and f64 paths differ in the last digits.
    pub backend: BackendKind,
}

/// The file `accumulators.json`: a run's (or shard's) exact per-point sums.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct AccumulatorFile {
    pub format: String,
    pub identity: RunIdentity,
    pub shard: Shard,
    pub points: Vec<StoredPoint>,
}

/// One point in `accumulators.json`; wide integers are decimal strings and
/// the histogram is sparse (`[bin, count]` pairs).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StoredPoint {
    pub excitation_frequency_hz: f64,
    pub normal_force_n: f64,
    pub range: PeakRange,
    pub realisations: u64,
    pub peaks: u64,
    pub sum_q: String,
    pub sum_q2: String,
    pub stick_units: u64,
    pub clamped: u64,
    pub sum_phase_sin: String,
    pub sum_phase_versine: String,
    pub histogram: Vec<(u32, u64)>,
}

/// Format tag of `accumulators.json`.
pub const ACCUMULATOR_FORMAT: &str = "stickslip-accumulators/2";

impl StoredPoint {
    fn from_accumulator(c: Condition, a: &PointAccumulator) -> Self {
        StoredPoint {
            excitation_frequency_hz: c.excitation_frequency_hz,
            normal_force_n: c.normal_force_n,
            range: a.range,
            realisations: a.realisations,
            peaks: a.peaks,
            sum_q: a.sum_q.to_string(),
            sum_q2: a.sum_q2.to_string(),
            stick_units: a.stick_units,
            clamped: a.clamped,
            sum_phase_sin: a.sum_phase_sin.to_string(),
            sum_phase_versine: a.sum_phase_versine.to_string(),
            histogram: a.histogram.iter().enumerate().filter(|(_, c)| **c > 0).map(|(b, c)| (b as u32, *c)).collect(),
        }
    }

    fn to_accumulator(&self, file: &Path) -> Result<(Condition, PointAccumulator)> {
        let bad = |m: String| Error::Measurement { file: file.to_path_buf(), line: None, message: m };
        let mut a = PointAccumulator::new(self.range);
        a.realisations = self.realisations;
        a.peaks = self.peaks;
        a.sum_q = self.sum_q.parse().map_err(|_| bad(format!("sum_q `{}` is not an integer", self.sum_q)))?;
        a.sum_q2 = self.sum_q2.parse().map_err(|_| bad(format!("sum_q2 `{}` is not an integer", self.sum_q2)))?;
        a.stick_units = self.stick_units;
        a.clamped = self.clamped;
        a.sum_phase_sin = self
            .sum_phase_sin
            .parse()
            .map_err(|_| bad(format!("sum_phase_sin `{}` is not an integer", self.sum_phase_sin)))?;
        a.sum_phase_versine = self
            .sum_phase_versine
            .parse()
            .map_err(|_| bad(format!("sum_phase_versine `{}` is not an integer", self.sum_phase_versine)))?;
        for &(b, c) in &self.histogram {
            *a.histogram.get_mut(b as usize).ok_or_else(|| bad(format!("histogram bin {b} out of range")))? = c;
        }
        let c =
            Condition { excitation_frequency_hz: self.excitation_frequency_hz, normal_force_n: self.normal_force_n };
        Ok((c, a))
    }
}

impl SweepResult {
    /// The `accumulators.json` content for this result.
    pub fn to_file(&self, identity: &RunIdentity, shard: Shard) -> AccumulatorFile {
        AccumulatorFile {
            format: ACCUMULATOR_FORMAT.to_string(),
            identity: identity.clone(),
            shard,
            points: self
                .conditions
                .iter()
                .zip(&self.accumulators)
                .map(|(&c, a)| StoredPoint::from_accumulator(c, a))
                .collect(),
        }
    }
}

/// Reads `DIR/accumulators.json`.
pub fn read_accumulators(dir: &Path) -> Result<(AccumulatorFile, SweepResult)> {
    let path = dir.join("accumulators.json");
    let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
    let file: AccumulatorFile = serde_json::from_str(&text).map_err(|e| Error::Measurement {
        file: path.clone(),
        line: Some(e.line() as u64),
        message: e.to_string(),
    })?;
    if file.format != ACCUMULATOR_FORMAT {
        return Err(Error::Measurement {
            file: path,
            line: None,
            message: format!("format `{}` is not {ACCUMULATOR_FORMAT}", file.format),
        });
    }
    let mut result = SweepResult { conditions: Vec::new(), accumulators: Vec::new() };
    for p in &file.points {
        let (c, a) = p.to_accumulator(&path)?;
        result.conditions.push(c);
        result.accumulators.push(a);
    }
    Ok((file, result))
}

/// Combines shard outputs into the unsharded result. Refuses shards of
/// different runs (model, grid, settings, seed, backend), a shard given
/// twice, a missing shard, and shards whose point counts do not fit.
pub fn merge_shards(dirs: &[std::path::PathBuf]) -> Result<(RunIdentity, SweepResult)> {
    let first = dirs.first().ok_or_else(|| Error::setting("merge", "no shard directories given"))?;
    let mut parts = Vec::new();
    for dir in dirs {
        parts.push((dir, read_accumulators(dir)?));
    }
    let (_, (reference, _)) = &parts[0];
    let identity = reference.identity.clone();
    let count = reference.shard.count;
    for (dir, (file, _)) in &parts {
        let differs = |what: &str| {
            Error::Mismatch(format!(
                "cannot merge {} with {}: the shards differ in {what}",
                dir.display(),
                first.display()
            ))
        };
        let other = &file.identity;
        if other.model_toml != identity.model_toml {
            return Err(differs("their model"));
        }
        if other.seed != identity.seed {
            return Err(differs(&format!("their seed ({} vs {})", other.seed, identity.seed)));
        }
        if other.frequencies_hz != identity.frequencies_hz || other.normal_forces_n != identity.normal_forces_n {
            return Err(differs("their grid"));
        }
        if (other.realisations, other.warmup_cycles, other.measured_cycles)
            != (identity.realisations, identity.warmup_cycles, identity.measured_cycles)
        {
            return Err(differs("realisations or cycle counts"));
        }
        if other.backend != identity.backend {
            return Err(differs(&format!("backend ({} vs {})", other.backend.name(), identity.backend.name())));
        }
        if file.shard.count != count {
            return Err(differs(&format!("shard count ({} vs {count})", file.shard.count)));
        }
    }
    parts.sort_by_key(|(_, (f, _))| f.shard.index);
    for (expected, (dir, (file, _))) in parts.iter().enumerate() {
        if file.shard.index as usize != expected {
            let problem = if (file.shard.index as usize) < expected { "given twice" } else { "missing" };
            return Err(Error::Mismatch(format!("shard {expected}/{count} is {problem} (at {})", dir.display())));
        }
    }
    if parts.len() != count as usize {
        return Err(Error::Mismatch(format!("{} shards given, the run was split into {count}", parts.len())));
    }
    let total = identity.frequencies_hz.len() * identity.normal_forces_n.len();
    let mut merged = SweepResult { conditions: Vec::new(), accumulators: Vec::new() };
    for (dir, (file, result)) in parts {
        if result.conditions.len() != file.shard.points(total).len() {
            return Err(Error::Mismatch(format!(
                "{} holds {} points, its shard should hold {}",
                dir.display(),
                result.conditions.len(),
                file.shard.points(total).len()
            )));
        }
        merged.conditions.extend(result.conditions);
        merged.accumulators.extend(result.accumulators);
    }
    Ok((identity, merged))
}
