//! Shards: part K of N of a grid (`sweep --shard K/N`), its exact sums in
//! `accumulators.json`, and the merge that combines parts into exactly what
//! the unsharded run writes.
//!
//! **Integrity.** `accumulators.json` carries a SHA-256 digest of its
//! content, and [`read_accumulators`] refuses, naming the file (and the
//! point), a file that is not a regular file within
//! [`MAX_ACCUMULATOR_BYTES`](crate::io::MAX_ACCUMULATOR_BYTES), whose digest
//! does not match (edited, truncated, corrupted), or whose content breaks an
//! invariant that every honest shard satisfies:
//!
//! - the run identity is valid: the model file reads and validates, the grid
//!   flags' values are physical, and the sizes are within the engine's limits;
//! - the points are exactly the grid points of the shard, in order, each with
//!   the peak range the model gives it;
//! - every point has the run's realisations and realisations × measured
//!   cycles peaks; its histogram's bins exist, are sorted and total the peaks;
//! - every peak lies inside the point's range (none in the bins below and
//!   above it, none clamped), and a range other than the model's is the one
//!   that holds the point's stored extremes, which lie in its first and last
//!   occupied bins;
//! - Σq and Σq² lie within the bounds that the histogram's bins put on each
//!   quantised peak, and (Σq)² ≤ n Σq² (so no variance is negative);
//! - the stuck time is at most the measured time, clamped peaks lie in the
//!   end bins, and the phase sums lie within what n unit phasors can give.
//!
//! The digest detects accidents and careless edits, not forgery (anyone can
//! recompute it); the invariants keep a forged file physically consistent.

use std::path::Path;

use crate::engine::model::{excitation_frequency_problem, fmt_value, normal_force_problem};
use crate::engine::reduce::{HISTOGRAM_BINS, PHASE_QUANTA, QUANTISE_LIMIT, STICK_UNITS_PER_PERIOD};
use crate::engine::{BackendKind, Condition, Job, Model, PeakRange, PointAccumulator};
use crate::error::{Error, Result};
use crate::sweep::{Grid, SweepResult};
use crate::text::{excerpt, shown};

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
        let bad = |m: &str| Error::setting("--shard", format!("`{}`: {m}", excerpt(text, 30)));
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
    /// The digest of everything above.
    pub integrity: Integrity,
}

/// `accumulators.json`'s integrity check: a digest of the file's other
/// fields as stickslip writes them (compact JSON, in field order).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Integrity {
    /// `sha256`.
    pub algorithm: String,
    /// Lowercase hexadecimal.
    pub digest: String,
}

/// The digested part of an accumulator file.
#[derive(serde::Serialize)]
struct Content<'a> {
    format: &'a str,
    identity: &'a RunIdentity,
    shard: Shard,
    points: &'a [StoredPoint],
}

impl AccumulatorFile {
    /// The digest of the file's content (everything but `integrity`).
    pub fn content_digest(&self) -> String {
        let content =
            Content { format: &self.format, identity: &self.identity, shard: self.shard, points: &self.points };
        let bytes = serde_json::to_vec(&content).expect("accumulator content always serialises");
        sha256::hex(&sha256::digest(&bytes))
    }
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
    /// The smallest and largest peak (as f32), m; absent in format 3.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub peak_extremes_m: Option<(f32, f32)>,
}

/// Format tag of `accumulators.json` (4: with each point's peak extremes;
/// 3 had the same content without them, 2 without the integrity digest).
pub const ACCUMULATOR_FORMAT: &str = "stickslip-accumulators/4";

/// The previous format, still read: its points have no extremes, so each
/// must have its model's range.
const ACCUMULATOR_FORMAT_3: &str = "stickslip-accumulators/3";

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
            peak_extremes_m: a.peak_extremes_m,
        }
    }

    fn to_accumulator(&self, file: &Path) -> Result<(Condition, PointAccumulator)> {
        let bad = |m: String| Error::Measurement { file: file.to_path_buf(), line: None, message: m };
        let not_integer = |name: &str, text: &str| bad(format!("{name} `{}` is not an integer", excerpt(text, 48)));
        let mut a = PointAccumulator::new(self.range);
        a.realisations = self.realisations;
        a.peaks = self.peaks;
        a.sum_q = self.sum_q.parse().map_err(|_| not_integer("sum_q", &self.sum_q))?;
        a.sum_q2 = self.sum_q2.parse().map_err(|_| not_integer("sum_q2", &self.sum_q2))?;
        a.stick_units = self.stick_units;
        a.clamped = self.clamped;
        a.sum_phase_sin = self.sum_phase_sin.parse().map_err(|_| not_integer("sum_phase_sin", &self.sum_phase_sin))?;
        a.sum_phase_versine =
            self.sum_phase_versine.parse().map_err(|_| not_integer("sum_phase_versine", &self.sum_phase_versine))?;
        let mut previous = None;
        for &(b, c) in &self.histogram {
            if previous.is_some_and(|p| b <= p) || c == 0 {
                return Err(bad(format!("histogram entry [{b}, {c}]: bins must be listed once, in order, non-empty")));
            }
            previous = Some(b);
            *a.histogram.get_mut(b as usize).ok_or_else(|| bad(format!("histogram bin {b} out of range")))? = c;
        }
        a.peak_extremes_m = self.peak_extremes_m;
        let c =
            Condition { excitation_frequency_hz: self.excitation_frequency_hz, normal_force_n: self.normal_force_n };
        Ok((c, a))
    }
}

impl SweepResult {
    /// The `accumulators.json` content for this result.
    pub fn to_file(&self, identity: &RunIdentity, shard: Shard) -> AccumulatorFile {
        let mut file = AccumulatorFile {
            format: ACCUMULATOR_FORMAT.to_string(),
            identity: identity.clone(),
            shard,
            points: self
                .conditions
                .iter()
                .zip(&self.accumulators)
                .map(|(&c, a)| StoredPoint::from_accumulator(c, a))
                .collect(),
            integrity: Integrity { algorithm: "sha256".into(), digest: String::new() },
        };
        file.integrity.digest = file.content_digest();
        file
    }
}

/// Reads `DIR/accumulators.json` and verifies it (see the module
/// documentation): a file that fails any check is refused by name.
pub fn read_accumulators(dir: &Path) -> Result<(AccumulatorFile, SweepResult)> {
    let path = dir.join("accumulators.json");
    let refuse = |line: Option<u64>, message: String| Error::Measurement { file: path.clone(), line, message };
    let bytes = crate::io::read_bounded(&path, crate::io::MAX_ACCUMULATOR_BYTES)
        .map_err(|e| refuse(None, format!("cannot read it: {e}")))?;
    // The format first, so an older or foreign file is named as such.
    let value: serde_json::Value = crate::io::parse_json(&bytes).map_err(|e| {
        refuse(
            (e.line() > 0).then_some(e.line() as u64),
            format!("not a complete accumulator file (truncated or edited?): {}", excerpt(&e.to_string(), 160)),
        )
    })?;
    match value.get("format").and_then(|f| f.as_str()) {
        Some(ACCUMULATOR_FORMAT | ACCUMULATOR_FORMAT_3) => {}
        Some("stickslip-accumulators/2") => {
            return Err(refuse(
                None,
                "format stickslip-accumulators/2 has no integrity check; re-run this shard with this version".into(),
            ));
        }
        other => {
            let shown = other.map_or("missing".to_string(), |f| format!("`{}`", excerpt(f, 60)));
            return Err(refuse(None, format!("format {shown} is not {ACCUMULATOR_FORMAT}")));
        }
    }
    let file: AccumulatorFile = serde_json::from_value(value)
        .map_err(|e| refuse(None, format!("not a valid accumulator file: {}", excerpt(&e.to_string(), 160))))?;
    if file.integrity.algorithm != "sha256" || file.integrity.digest != file.content_digest() {
        return Err(refuse(
            None,
            "its content does not match its integrity digest: the file was edited, truncated or corrupted after \
             stickslip wrote it; re-run this shard"
                .into(),
        ));
    }
    let mut result = SweepResult { conditions: Vec::new(), accumulators: Vec::new() };
    for p in &file.points {
        let (c, a) = p.to_accumulator(&path)?;
        result.conditions.push(c);
        result.accumulators.push(a);
    }
    verify(&file, &result).map_err(|m| refuse(None, m))?;
    Ok((file, result))
}

/// The invariants of an honest accumulator file; the message names the point.
fn verify(file: &AccumulatorFile, result: &SweepResult) -> std::result::Result<(), String> {
    let id = &file.identity;
    let model = Model::from_toml_str(&id.model_toml, "identity.model_toml", &[])
        .map_err(|e| format!("its model does not validate: {e}"))?;
    if id.frequencies_hz.is_empty() || id.normal_forces_n.is_empty() {
        return Err("its grid is empty".into());
    }
    for &f in &id.frequencies_hz {
        if let Some(p) = excitation_frequency_problem(f) {
            return Err(format!("grid frequency {}: {p}", fmt_value(f)));
        }
    }
    for &n in &id.normal_forces_n {
        if let Some(p) = normal_force_problem(n) {
            return Err(format!("grid normal force {}: {p}", fmt_value(n)));
        }
    }
    let total = id.frequencies_hz.len().saturating_mul(id.normal_forces_n.len());
    if total > Job::MAX_POINTS {
        return Err(format!("its grid has {total} points, more than the limit of {}", Job::MAX_POINTS));
    }
    if id.realisations == 0 || id.realisations > Job::MAX_REALISATIONS {
        return Err(format!("{} realisations per point is outside 1..={}", id.realisations, Job::MAX_REALISATIONS));
    }
    let cycles = u64::from(id.warmup_cycles) + u64::from(id.measured_cycles);
    if id.measured_cycles == 0 || cycles > Job::MAX_CYCLES {
        return Err(format!("{} + {} cycles are outside the limits", id.warmup_cycles, id.measured_cycles));
    }
    let peaks = u64::from(id.realisations) * u64::from(id.measured_cycles);
    if peaks > Job::MAX_PEAKS_PER_POINT {
        return Err(format!("{peaks} peaks per point exceed the limit"));
    }
    let shard = file.shard;
    if shard.count == 0 || shard.index >= shard.count {
        return Err(format!("shard {}/{} is not a part of a grid", shard.index, shard.count));
    }
    let range = shard.points(total);
    if result.conditions.len() != range.len() {
        return Err(format!(
            "it holds {} points; shard {}/{} of a {total}-point grid holds {}",
            result.conditions.len(),
            shard.index,
            shard.count,
            range.len()
        ));
    }
    let grid = Grid { frequencies_hz: id.frequencies_hz.clone(), normal_forces_n: id.normal_forces_n.clone() };
    let expected = &grid.conditions()[range.clone()];
    for (j, ((c, a), want)) in result.conditions.iter().zip(&result.accumulators).zip(expected).enumerate() {
        let at = format!("point {j} ({})", c.describe());
        if c.excitation_frequency_hz.to_bits() != want.excitation_frequency_hz.to_bits()
            || c.normal_force_n.to_bits() != want.normal_force_n.to_bits()
        {
            return Err(format!("{at} is not grid point {} ({}) of its grid", range.start + j, want.describe()));
        }
        // A range other than the model's is the one that holds the point's
        // extremes, one of which lies outside the model's range.
        let own = PeakRange::for_point(&model, *c);
        let widened = a.peak_extremes_m.is_some_and(|(lo, hi)| {
            let left_own = own.histogram_bin(lo) == 0 || own.histogram_bin(hi) == HISTOGRAM_BINS - 1;
            left_own && own.holding(f64::from(lo), f64::from(hi)) == Some(a.range)
        });
        if a.range != own && !widened {
            return Err(format!(
                "{at}: its peak range is neither the one its model gives nor the one that holds its peaks"
            ));
        }
        verify_point(a, id).map_err(|m| format!("{at}: {m}"))?;
    }
    Ok(())
}

/// The invariants of one point's sums.
fn verify_point(a: &PointAccumulator, id: &RunIdentity) -> std::result::Result<(), String> {
    let n = u64::from(id.realisations) * u64::from(id.measured_cycles);
    if a.realisations != u64::from(id.realisations) {
        return Err(format!("{} realisations, the run has {}", a.realisations, id.realisations));
    }
    if a.peaks != n {
        return Err(format!(
            "{} peaks, but {} realisations × {} cycles give {n}",
            a.peaks, a.realisations, id.measured_cycles
        ));
    }
    let total: u128 = a.histogram.iter().map(|&c| u128::from(c)).sum();
    if total != u128::from(n) {
        return Err(format!("its histogram holds {total} peaks, not {n}"));
    }
    let last = a.histogram.len() - 1;
    if a.outside_range() > 0 || a.clamped > 0 {
        return Err(format!(
            "{} of its peaks lie outside its range ({} clamped): its quantiles would sit at the range's edge; \
             re-run it with this version, which runs such a point again over a range that holds its peaks",
            a.outside_range(),
            a.clamped
        ));
    }
    if let Some((lo, hi)) = a.peak_extremes_m {
        let occupied = |b: u32| a.histogram[b as usize] > 0;
        let first = (0..=last as u32).find(|&b| occupied(b));
        let final_bin = (0..=last as u32).rev().find(|&b| occupied(b));
        if !(lo <= hi && first == Some(a.range.histogram_bin(lo)) && final_bin == Some(a.range.histogram_bin(hi))) {
            return Err(format!(
                "its peak extremes {lo:e} and {hi:e} m do not lie in its first and last occupied bins"
            ));
        }
    }
    let stuck_periods = a.stick_units as f64 / STICK_UNITS_PER_PERIOD;
    if stuck_periods > n as f64 * (1.0 + 1e-6) {
        return Err(format!("a stuck time of {} periods exceeds its {n} measured periods", fmt_value(stuck_periods)));
    }
    // Each quantised peak lies within what its bin allows (with a margin for
    // the f32 arithmetic), so Σq and Σq² lie within the sums of those bounds.
    let centre = f64::from(a.range.centre_f32());
    let per_m = f64::from(a.range.inv_quantum_f32());
    let limit = f64::from(QUANTISE_LIMIT);
    let slack = 4096.0;
    let q_at = |x: f64| (x - centre) * per_m;
    let (mut lo_sum, mut hi_sum, mut lo_sq, mut hi_sq) = (0i128, 0i128, 0u128, 0u128);
    for (b, &count) in a.histogram.iter().enumerate() {
        if count == 0 {
            continue;
        }
        let (lo, hi) = match b {
            0 => (-limit, q_at(a.range.lo_m) + slack),
            b if b == last => (q_at(a.range.hi_m) - slack, limit),
            b => {
                let (l, h) = a.range.bin_edges(b as u32);
                (q_at(l) - slack, q_at(h) + slack)
            }
        };
        let (lo, hi) = (lo.max(-limit).floor() as i128, hi.min(limit).ceil() as i128);
        let c = i128::from(count);
        lo_sum += c * lo;
        hi_sum += c * hi;
        let (lo2, hi2) = ((lo * lo) as u128, (hi * hi) as u128);
        let min_sq = if lo <= 0 && hi >= 0 { 0 } else { lo2.min(hi2) };
        lo_sq += count as u128 * min_sq;
        hi_sq += count as u128 * lo2.max(hi2);
    }
    if !(lo_sum..=hi_sum).contains(&a.sum_q) {
        return Err(format!("Σq = {} lies outside the {lo_sum}..={hi_sum} its histogram allows", a.sum_q));
    }
    if !(lo_sq..=hi_sq).contains(&a.sum_q2) {
        return Err(format!("Σq² = {} lies outside the {lo_sq}..={hi_sq} its histogram allows", a.sum_q2));
    }
    let spread = (n as f64) * a.sum_q2 as f64 - (a.sum_q as f64) * (a.sum_q as f64);
    if spread < -1e-9 * (n as f64) * (a.sum_q2 as f64).max(1.0) {
        return Err("(Σq)² exceeds n Σq²: its variance would be negative".into());
    }
    // Phases: each term is a quantised (sin d, 1 − cos d) of a unit phasor.
    let quanta = PHASE_QUANTA;
    let (s, v, nf) = (a.sum_phase_sin as f64, a.sum_phase_versine as f64, n as f64);
    if s.abs() > nf * (quanta + 1.0) || v < 0.0 || v > nf * (2.0 * quanta + 1.0) {
        return Err("its phase sums exceed what its peaks' phases can give".into());
    }
    let c = nf * quanta - v;
    if s * s + c * c > (nf * (quanta + 1.0)).powi(2) * (1.0 + 1e-12) {
        return Err("its phase sums are longer than the sum of its peaks' unit phasors".into());
    }
    Ok(())
}

/// Combines shard outputs into the unsharded result. Refuses shards of
/// different runs (model, grid, settings, seed, backend), a shard given
/// twice, a missing shard, and shards whose point counts do not fit.
pub fn merge_shards(dirs: &[std::path::PathBuf]) -> Result<(RunIdentity, SweepResult)> {
    let first = dirs.first().ok_or_else(|| Error::setting("merge", "no shard directories given"))?;
    let canonical: Vec<Option<std::path::PathBuf>> = dirs.iter().map(|d| std::fs::canonicalize(d).ok()).collect();
    for (i, c) in canonical.iter().enumerate() {
        if let Some(j) = c.as_ref().and_then(|c| canonical[..i].iter().position(|o| o.as_ref() == Some(c))) {
            return Err(Error::Mismatch(format!(
                "shard directory {} is given twice (as `{}` and `{}`)",
                shown(&dirs[i]),
                shown(&dirs[j]),
                shown(&dirs[i])
            )));
        }
    }
    let mut parts = Vec::new();
    for dir in dirs {
        parts.push((dir, read_accumulators(dir)?));
    }
    let (_, (reference, _)) = &parts[0];
    let identity = reference.identity.clone();
    let count = reference.shard.count;
    for (dir, (file, _)) in &parts {
        let differs = |what: &str| {
            Error::Mismatch(format!("cannot merge {} with {}: the shards differ in {what}", shown(dir), shown(first)))
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
    for pair in parts.windows(2) {
        let ((a_dir, (a, _)), (b_dir, (b, _))) = (&pair[0], &pair[1]);
        if a.shard.index == b.shard.index {
            return Err(Error::Mismatch(format!(
                "shard {}/{count} is given twice: {} and {}",
                a.shard.index,
                shown(a_dir),
                shown(b_dir)
            )));
        }
    }
    // Indices are distinct and below `count` (each file was verified): the first gap is missing.
    if let Some(missing) = (0..count).find(|&k| parts.get(k as usize).is_none_or(|(_, (f, _))| f.shard.index != k)) {
        return Err(Error::Mismatch(format!(
            "shard {missing}/{count} is missing ({} of {count} shards given)",
            parts.len()
        )));
    }
    let total = identity.frequencies_hz.len() * identity.normal_forces_n.len();
    let mut merged = SweepResult { conditions: Vec::new(), accumulators: Vec::new() };
    for (dir, (file, result)) in parts {
        if result.conditions.len() != file.shard.points(total).len() {
            return Err(Error::Mismatch(format!(
                "{} holds {} points, its shard should hold {}",
                shown(dir),
                result.conditions.len(),
                file.shard.points(total).len()
            )));
        }
        merged.conditions.extend(result.conditions);
        merged.accumulators.extend(result.accumulators);
    }
    Ok((identity, merged))
}

/// SHA-256 (FIPS 180-4), for the accumulator files' digest.
mod sha256 {
    const K: [u32; 64] = [
        0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4, 0xab1c5ed5, 0xd807aa98,
        0x12835b01, 0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe, 0x9bdc06a7, 0xc19bf174, 0xe49b69c1, 0xefbe4786,
        0x0fc19dc6, 0x240ca1cc, 0x2de92c6f, 0x4a7484aa, 0x5cb0a9dc, 0x76f988da, 0x983e5152, 0xa831c66d, 0xb00327c8,
        0xbf597fc7, 0xc6e00bf3, 0xd5a79147, 0x06ca6351, 0x14292967, 0x27b70a85, 0x2e1b2138, 0x4d2c6dfc, 0x53380d13,
        0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85, 0xa2bfe8a1, 0xa81a664b, 0xc24b8b70, 0xc76c51a3, 0xd192e819,
        0xd6990624, 0xf40e3585, 0x106aa070, 0x19a4c116, 0x1e376c08, 0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a,
        0x5b9cca4f, 0x682e6ff3, 0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208, 0x90befffa, 0xa4506ceb, 0xbef9a3f7,
        0xc67178f2,
    ];

    fn compress(h: &mut [u32; 8], block: &[u8]) {
        let mut w = [0u32; 64];
        for (i, word) in block.chunks_exact(4).enumerate() {
            w[i] = u32::from_be_bytes([word[0], word[1], word[2], word[3]]);
        }
        for i in 16..64 {
            let s0 = w[i - 15].rotate_right(7) ^ w[i - 15].rotate_right(18) ^ (w[i - 15] >> 3);
            let s1 = w[i - 2].rotate_right(17) ^ w[i - 2].rotate_right(19) ^ (w[i - 2] >> 10);
            w[i] = w[i - 16].wrapping_add(s0).wrapping_add(w[i - 7]).wrapping_add(s1);
        }
        let [mut a, mut b, mut c, mut d, mut e, mut f, mut g, mut hh] = *h;
        for i in 0..64 {
            let s1 = e.rotate_right(6) ^ e.rotate_right(11) ^ e.rotate_right(25);
            let ch = (e & f) ^ (!e & g);
            let t1 = hh.wrapping_add(s1).wrapping_add(ch).wrapping_add(K[i]).wrapping_add(w[i]);
            let s0 = a.rotate_right(2) ^ a.rotate_right(13) ^ a.rotate_right(22);
            let maj = (a & b) ^ (a & c) ^ (b & c);
            let t2 = s0.wrapping_add(maj);
            hh = g;
            g = f;
            f = e;
            e = d.wrapping_add(t1);
            d = c;
            c = b;
            b = a;
            a = t1.wrapping_add(t2);
        }
        for (x, y) in h.iter_mut().zip([a, b, c, d, e, f, g, hh]) {
            *x = x.wrapping_add(y);
        }
    }

    /// The SHA-256 digest of `data`.
    pub(super) fn digest(data: &[u8]) -> [u8; 32] {
        let mut h: [u32; 8] =
            [0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a, 0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19];
        let mut blocks = data.chunks_exact(64);
        for block in &mut blocks {
            compress(&mut h, block);
        }
        let rest = blocks.remainder();
        let mut tail = [0u8; 128];
        tail[..rest.len()].copy_from_slice(rest);
        tail[rest.len()] = 0x80;
        let len = if rest.len() < 56 { 64 } else { 128 };
        tail[len - 8..len].copy_from_slice(&((data.len() as u64).wrapping_mul(8)).to_be_bytes());
        for block in tail[..len].chunks_exact(64) {
            compress(&mut h, block);
        }
        let mut out = [0u8; 32];
        for (chunk, word) in out.chunks_exact_mut(4).zip(h) {
            chunk.copy_from_slice(&word.to_be_bytes());
        }
        out
    }

    /// Lowercase hexadecimal.
    pub(super) fn hex(bytes: &[u8]) -> String {
        bytes.iter().map(|b| format!("{b:02x}")).collect()
    }

    #[cfg(test)]
    mod tests {
        use super::*;

        #[test]
        fn known_digests() {
            assert_eq!(hex(&digest(b"")), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
            assert_eq!(hex(&digest(b"abc")), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
            let long = b"abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq";
            assert_eq!(hex(&digest(long)), "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
            let million = vec![b'a'; 1_000_000];
            assert_eq!(hex(&digest(&million)), "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
        }
    }
}
