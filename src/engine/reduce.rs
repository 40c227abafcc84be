//! Exact reduction of peak amplitudes into per-point statistics
//! (`shaders/reduce.wgsl` is the kernel's half).
//!
//! Each peak `x` (m) is quantised against its grid point's histogram range:
//! `q = round((x − centre) / quantum)` in f32 (the same arithmetic on CPU and
//! GPU), with `quantum = (hi − lo) / 2^28`, about 4e-11 m for a 5 mm range.
//! Counts, `Σq` and `Σq²` are integers, so accumulating them in any order,
//! across dispatches, chunks or shards, gives the same bits. Quantiles come
//! from a fixed-range histogram of `HISTOGRAM_BINS` bins (the first and last
//! catch peaks below and above the range).
//!
//! **Peaks outside the range.** No statistic is taken from a point whose
//! peaks left its range: a peak beyond the range has no bin to place it
//! (a quantile there would be the range's edge), and one far beyond it is
//! clamped (its sums are no longer exact). The sums therefore also keep the
//! smallest and largest peak, and [`crate::engine::Engine::sums`] runs such
//! a point again (the same noise, so the same peaks) over
//! [`PointAccumulator::range_holding_peaks`], which holds every one of them.

use serde::{Deserialize, Serialize};

use crate::engine::model::Condition;
use crate::engine::oscillator::{PathResult, PeakRange};

/// Histogram bins per grid point, including the underflow and overflow bins.
pub const HISTOGRAM_BINS: u32 = 2048;
/// Quantisation steps across the histogram range.
pub const QUANTA_PER_RANGE: f64 = (1u64 << 28) as f64;
/// Stick-time units per excitation period (stick time is counted in T/2^20).
pub const STICK_UNITS_PER_PERIOD: f64 = (1u64 << 20) as f64;
/// Largest quantised peak magnitude: the largest f32 below 2^31.
pub const QUANTISE_LIMIT: f32 = 2_147_483_520.0;
/// Quantisation steps per unit of a phase's sine and versine (2^30).
pub const PHASE_QUANTA: f64 = (1u64 << 30) as f64;

/// Statistics of the peak amplitudes at one grid point (one `sweep.csv` row).
#[derive(Clone, Debug, PartialEq)]
pub struct PointStats {
    /// Hz
    pub excitation_frequency_hz: f64,
    /// Nominal normal force, N.
    pub normal_force_n: f64,
    /// Realisations behind the statistics.
    pub realisations: u32,
    /// Number of peaks behind the statistics.
    pub peaks: u64,
    /// Mean peak amplitude, m.
    pub peak_mean_m: f64,
    /// Unbiased variance of the peak amplitude, m².
    pub peak_var_m2: f64,
    /// 5%, 50% and 95% quantiles of the peak amplitude, m.
    pub peak_p05_m: f64,
    pub peak_p50_m: f64,
    pub peak_p95_m: f64,
    /// Share of measured time spent stuck, –.
    pub stick_fraction: f64,
    /// Circular mean of the per-period phase lag of the response's
    /// fundamental behind the base, degrees in (−180, 180]; NaN where the
    /// block stuck throughout every measured period (a block that never
    /// moves has no fundamental, so no lag: see [`PointAccumulator::moved`]).
    pub phase_mean_deg: f64,
    /// Circular variance of that phase, degrees² (see [`circular_mean_var`]);
    /// NaN where the mean is.
    pub phase_var_deg2: f64,
}

/// Circular mean (rad, in (−π, π]) and circular variance (rad²) of phases:
/// with `R̄` the mean resultant length, the variance is `n/(n−1) · (−2 ln R̄)`,
/// which for small spreads is the ordinary unbiased variance of the phases
/// (and stays defined for any spread). `(NaN, NaN)` for no phases.
pub fn circular_mean_var(phases_rad: &[f64]) -> (f64, f64) {
    let (s, c) = phases_rad.iter().fold((0.0, 0.0), |(s, c), p| (s + p.sin(), c + p.cos()));
    let versine: f64 = phases_rad.iter().map(|p| 2.0 * (0.5 * p).sin().powi(2)).sum();
    circular_from_sums(phases_rad.len() as f64, s, versine, s.atan2(c))
}

/// Circular mean and variance from `n` phases' `Σ sin`, `Σ (1 − cos)` (the
/// versine, which keeps tiny spreads precise) and the mean angle.
fn circular_from_sums(n: f64, sum_sin: f64, sum_versine: f64, mean_rad: f64) -> (f64, f64) {
    if n < 1.0 {
        return (f64::NAN, f64::NAN);
    }
    // With C = n − V: 1 − R̄² = (n² − S² − C²)/n², and n² − C² = V (2n − V).
    let one_minus_r2 = ((sum_versine * (2.0 * n - sum_versine) - sum_sin * sum_sin) / (n * n)).clamp(0.0, 1.0);
    let var = if n > 1.0 { n / (n - 1.0) * -(-one_minus_r2).ln_1p() } else { 0.0 };
    (wrap_angle(mean_rad), var)
}

/// An angle wrapped into (−π, π], rad.
pub fn wrap_angle(rad: f64) -> f64 {
    let w = rad.rem_euclid(std::f64::consts::TAU);
    if w > std::f64::consts::PI { w - std::f64::consts::TAU } else { w }
}

/// The reduction's arithmetic on a point's range, as the kernel does it.
impl PeakRange {
    /// The phase reference, rad, as the kernel sees it (f32).
    pub fn phase_ref_f32(&self) -> f32 {
        self.phase_ref_rad as f32
    }

    /// The quantised sine and versine (`1 − cos`, as `2 sin²(d/2)`) of a
    /// phase's deviation `d` from the reference, in units of 2^-30.
    /// Mirrors `tally_period` in `reduce.wgsl` (which computes in f32).
    pub fn quantise_phase(&self, phase_rad: f64) -> (i64, u64) {
        let d = phase_rad - f64::from(self.phase_ref_f32());
        let sine = (d.sin() * PHASE_QUANTA).round_ties_even() as i64;
        let versine = (2.0 * (0.5 * d).sin().powi(2) * PHASE_QUANTA).round_ties_even() as u64;
        (sine, versine)
    }

    /// Centre of the range, m (as the kernel sees it, f32).
    pub fn centre_f32(&self) -> f32 {
        (0.5 * (self.lo_m + self.hi_m)) as f32
    }

    /// `1 / quantum`, 1/m (f32, as the kernel sees it).
    pub fn inv_quantum_f32(&self) -> f32 {
        (QUANTA_PER_RANGE / (self.hi_m - self.lo_m)) as f32
    }

    /// Quantum, m, exactly as used for the statistics.
    pub fn quantum_m(&self) -> f64 {
        1.0 / f64::from(self.inv_quantum_f32())
    }

    /// Inner bins per metre (f32, as the kernel sees it).
    pub fn bins_per_m_f32(&self) -> f32 {
        (f64::from(HISTOGRAM_BINS - 2) / (self.hi_m - self.lo_m)) as f32
    }

    /// The quantised peak and whether it was clamped (|q| ≥ 2^31 − 1).
    /// Mirrors `tally_period` in `reduce.wgsl`.
    pub fn quantise(&self, peak_m: f32) -> (i32, bool) {
        let q = ((peak_m - self.centre_f32()) * self.inv_quantum_f32()).round_ties_even();
        (q.clamp(-QUANTISE_LIMIT, QUANTISE_LIMIT) as i32, q.abs() > QUANTISE_LIMIT)
    }

    /// The histogram bin of a peak. Mirrors `histogram_bin` in `reduce.wgsl`.
    pub fn histogram_bin(&self, peak_m: f32) -> u32 {
        let position = (peak_m - self.lo_m as f32) * self.bins_per_m_f32();
        if position < 0.0 {
            0
        } else if position >= (HISTOGRAM_BINS - 2) as f32 {
            HISTOGRAM_BINS - 1
        } else {
            position as u32 + 1
        }
    }

    /// Edges of inner bin `b` (1..=BINS−2), m.
    pub fn bin_edges(&self, b: u32) -> (f64, f64) {
        let w = (self.hi_m - self.lo_m) / f64::from(HISTOGRAM_BINS - 2);
        (self.lo_m + f64::from(b - 1) * w, self.lo_m + f64::from(b) * w)
    }

    /// A range with this one's phase reference whose inner bins hold every
    /// peak in `[lowest_m, highest_m]`: that interval widened by a thousandth
    /// of its span, a ten-thousandth of its magnitude and a thousandth of
    /// this range's width on each side (far more than the f32 rounding of the
    /// bin arithmetic). `None` when the result is not finite as f32 (peaks
    /// near the largest f32 cannot be binned).
    pub fn holding(&self, lowest_m: f64, highest_m: f64) -> Option<PeakRange> {
        let pad =
            1e-3 * (highest_m - lowest_m) + 1e-4 * lowest_m.abs().max(highest_m.abs()) + 1e-3 * (self.hi_m - self.lo_m);
        let range = PeakRange { lo_m: lowest_m - pad, hi_m: highest_m + pad, phase_ref_rad: self.phase_ref_rad };
        let as_f32 = [range.lo_m as f32, range.hi_m as f32, range.centre_f32(), range.inv_quantum_f32()];
        (as_f32.iter().all(|v| v.is_finite()) && range.lo_m < range.hi_m && range.bins_per_m_f32() > 0.0)
            .then_some(range)
    }
}

/// Exact integer sums for one grid point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PointAccumulator {
    pub range: PeakRange,
    /// Realisations behind the sums.
    pub realisations: u64,
    /// Measured excitation periods behind the sums (one peak each).
    pub peaks: u64,
    /// Σ q (quantised peaks).
    pub sum_q: i128,
    /// Σ q².
    pub sum_q2: u128,
    /// Σ stuck time, in units of T/2^20.
    pub stick_units: u64,
    /// Peaks whose quantised value had to be clamped (far outside the range).
    pub clamped: u64,
    /// Counts per bin; bin 0 is below the range, the last bin above it.
    pub histogram: Vec<u64>,
    /// Σ of the quantised sines of the phases' deviations from the reference.
    pub sum_phase_sin: i128,
    /// Σ of their quantised versines.
    pub sum_phase_versine: u128,
    /// Periods whose peak (as f32) or phase was not finite: they are counted
    /// here and nowhere else (never quantised or binned), and a backend
    /// refuses a result where this is not zero.
    #[serde(default)]
    pub non_finite: u64,
    /// The smallest and largest peak (as f32, m) added or merged here;
    /// `None` before any, and for sums read back from `accumulators.json`
    /// (which does not keep them). Exact in any order, like the sums.
    #[serde(skip)]
    pub peak_extremes_m: Option<(f32, f32)>,
}

impl PointAccumulator {
    pub fn new(range: PeakRange) -> Self {
        PointAccumulator {
            range,
            realisations: 0,
            peaks: 0,
            sum_q: 0,
            sum_q2: 0,
            stick_units: 0,
            clamped: 0,
            histogram: vec![0; HISTOGRAM_BINS as usize],
            sum_phase_sin: 0,
            sum_phase_versine: 0,
            non_finite: 0,
            peak_extremes_m: None,
        }
    }

    /// Adds one measured period: its peak (m), phase (rad) and stuck share
    /// of the period. A period whose peak (as f32) or phase is not finite is
    /// only counted in [`PointAccumulator::non_finite`]. Mirrors
    /// `tally_period` in `reduce.wgsl`.
    pub fn tally_period(&mut self, peak_m: f64, phase_rad: f64, stuck_share: f64) {
        let peak = peak_m as f32;
        if !(peak.is_finite() && phase_rad.is_finite()) {
            self.non_finite += 1;
            return;
        }
        let (q, clamped) = self.range.quantise(peak);
        let (sine, versine) = self.range.quantise_phase(phase_rad);
        self.sum_phase_sin += i128::from(sine);
        self.sum_phase_versine += u128::from(versine);
        self.peaks += 1;
        self.sum_q += i128::from(q);
        self.sum_q2 += (i128::from(q) * i128::from(q)) as u128;
        self.stick_units += stick_units(stuck_share);
        self.clamped += u64::from(clamped);
        self.histogram[self.range.histogram_bin(peak) as usize] += 1;
        self.peak_extremes_m = widest(self.peak_extremes_m, Some((peak, peak)));
    }

    /// Adds another accumulator of the same point (exact).
    pub fn merge(&mut self, other: &PointAccumulator) {
        assert_eq!(self.range, other.range, "merging accumulators of different points");
        self.realisations += other.realisations;
        self.peaks += other.peaks;
        self.sum_q += other.sum_q;
        self.sum_q2 += other.sum_q2;
        self.stick_units += other.stick_units;
        self.clamped += other.clamped;
        self.sum_phase_sin += other.sum_phase_sin;
        self.sum_phase_versine += other.sum_phase_versine;
        self.non_finite += other.non_finite;
        self.peak_extremes_m = widest(self.peak_extremes_m, other.peak_extremes_m);
        for (a, b) in self.histogram.iter_mut().zip(&other.histogram) {
            *a += b;
        }
    }

    /// Peaks that lie outside the range (in the first or last bin; a clamped
    /// peak is one of them). Its quantiles, and with clamped peaks its sums,
    /// are not to be used when this is not zero.
    pub fn outside_range(&self) -> u64 {
        self.histogram[0] + self.histogram[self.histogram.len() - 1]
    }

    /// The range a second run of this point needs so that every one of its
    /// peaks lies inside ([`PeakRange::holding`] its extremes); `None` when
    /// every peak already does, or when the extremes are unknown or cannot
    /// be binned.
    pub fn range_holding_peaks(&self) -> Option<PeakRange> {
        let (lowest, highest) = self.peak_extremes_m?;
        (self.outside_range() > 0).then(|| self.range.holding(f64::from(lowest), f64::from(highest)))?
    }

    /// Quantile from the histogram, interpolating linearly inside the bin
    /// and held within the lowest and highest peak (so the peaks of a block
    /// stuck throughout, all one value, give that value at every p, not a
    /// spread across their bin). Returns the range edge when the quantile
    /// falls outside the range.
    pub fn quantile(&self, p: f64) -> f64 {
        let target = p * self.peaks as f64;
        let mut below = 0.0;
        for (b, &count) in self.histogram.iter().enumerate() {
            let count = count as f64;
            if count > 0.0 && below + count >= target {
                let b = b as u32;
                if b == 0 {
                    return self.range.lo_m;
                }
                if b == HISTOGRAM_BINS - 1 {
                    return self.range.hi_m;
                }
                let (lo, hi) = self.range.bin_edges(b);
                let inside = lo + (hi - lo) * ((target - below) / count).clamp(0.0, 1.0);
                return match self.peak_extremes_m {
                    Some((lowest, highest)) => {
                        inside.clamp(f64::from(lowest), f64::from(highest).max(f64::from(lowest)))
                    }
                    None => inside,
                };
            }
            below += count;
        }
        f64::NAN
    }

    /// Mean (m) and unbiased variance (m²) from the exact sums:
    /// `n Σq² − (Σq)²` is formed exactly in 128-bit integers.
    pub fn moments(&self) -> (f64, f64) {
        let n = self.peaks as i128;
        let quantum = self.range.quantum_m();
        let mean_q = self.sum_q as f64 / self.peaks as f64;
        let var_q = if n > 1 {
            let spread = (n as u128)
                .checked_mul(self.sum_q2)
                .and_then(|a| i128::try_from(a).ok())
                .zip(self.sum_q.checked_mul(self.sum_q))
                .map(|(a, b)| (a - b) as f64)
                .unwrap_or_else(|| n as f64 * self.sum_q2 as f64 - (self.sum_q as f64).powi(2));
            spread / (n * (n - 1)) as f64
        } else {
            0.0
        };
        (f64::from(self.range.centre_f32()) + mean_q * quantum, var_q * quantum * quantum)
    }

    /// Whether the block moved in any measured period: `false` when every
    /// period was stuck throughout (stick fraction exactly 1), where the
    /// per-period fundamentals are round-off and their phases mean nothing.
    pub fn moved(&self) -> bool {
        (self.stick_units as f64) < STICK_UNITS_PER_PERIOD * self.peaks as f64
    }

    /// Circular mean (rad, in (−π, π]) and circular variance (rad²) of the
    /// phases, from the exact sums (see [`circular_mean_var`]); `(NaN, NaN)`
    /// where the block never moved ([`Self::moved`]).
    pub fn phase_moments(&self) -> (f64, f64) {
        if !self.moved() {
            return (f64::NAN, f64::NAN);
        }
        let (s, v) = (self.sum_phase_sin as f64 / PHASE_QUANTA, self.sum_phase_versine as f64 / PHASE_QUANTA);
        let n = self.peaks as f64;
        let mean = f64::from(self.range.phase_ref_f32()) + s.atan2(n - v);
        circular_from_sums(n, s, v, mean)
    }

    /// Adds one realisation's measured periods (CPU backend).
    pub fn add_path(&mut self, path: &PathResult, period_s: f64) {
        self.realisations += 1;
        for (&p, &phase) in path.peaks_m.iter().zip(&path.phases_rad) {
            self.tally_period(p, phase, 0.0);
        }
        self.stick_units += stick_units(path.stick_time_s / period_s);
    }

    /// The `sweep.csv` row.
    pub fn stats(&self, condition: Condition) -> PointStats {
        let (mean, var) = self.moments();
        let (phase_mean, phase_var) = self.phase_moments();
        PointStats {
            excitation_frequency_hz: condition.excitation_frequency_hz,
            normal_force_n: condition.normal_force_n,
            realisations: self.realisations as u32,
            peaks: self.peaks,
            peak_mean_m: mean,
            peak_var_m2: var,
            peak_p05_m: self.quantile(0.05),
            peak_p50_m: self.quantile(0.50),
            peak_p95_m: self.quantile(0.95),
            stick_fraction: self.stick_units as f64 / (STICK_UNITS_PER_PERIOD * self.peaks as f64),
            phase_mean_deg: phase_mean.to_degrees(),
            phase_var_deg2: phase_var.to_degrees().to_degrees(),
        }
    }
}

/// The wider of two (smallest, largest) pairs.
fn widest(a: Option<(f32, f32)>, b: Option<(f32, f32)>) -> Option<(f32, f32)> {
    match (a, b) {
        (Some((lo_a, hi_a)), Some((lo_b, hi_b))) => Some((lo_a.min(lo_b), hi_a.max(hi_b))),
        (one, None) | (None, one) => one,
    }
}

/// Stuck share of a period in units of T/2^20. Mirrors the kernel.
pub fn stick_units(stuck_share: f64) -> u64 {
    ((stuck_share as f32) * STICK_UNITS_PER_PERIOD as f32).round_ties_even() as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    fn range() -> PeakRange {
        PeakRange { lo_m: -1e-3, hi_m: 3e-3, phase_ref_rad: 0.3 }
    }

    #[test]
    fn moments_match_direct_computation() {
        let mut acc = PointAccumulator::new(range());
        let peaks: Vec<f64> = (0..1000).map(|i| 1e-3 + 1e-4 * ((i as f64) * 0.37).sin()).collect();
        for &p in &peaks {
            acc.tally_period(p, 0.3, 0.0);
        }
        let n = peaks.len() as f64;
        let mean = peaks.iter().sum::<f64>() / n;
        let var = peaks.iter().map(|p| (p - mean).powi(2)).sum::<f64>() / (n - 1.0);
        let (m, v) = acc.moments();
        assert!((m / mean - 1.0).abs() < 1e-7, "{m} vs {mean}");
        assert!((v / var - 1.0).abs() < 1e-5, "{v} vs {var}");
    }

    #[test]
    fn merging_is_exact_in_any_order() {
        let peaks: Vec<f64> = (0..500).map(|i| 1e-3 * (1.0 + 0.3 * ((i as f64) * 1.7).cos())).collect();
        let mut whole = PointAccumulator::new(range());
        peaks.iter().for_each(|&p| whole.tally_period(p, 0.3, 0.25));
        let mut a = PointAccumulator::new(range());
        let mut b = PointAccumulator::new(range());
        peaks[..123].iter().for_each(|&p| a.tally_period(p, 0.3, 0.25));
        peaks[123..].iter().rev().for_each(|&p| b.tally_period(p, 0.3, 0.25));
        b.merge(&a);
        assert_eq!(whole, b);
        assert_eq!(whole.stats(Condition { excitation_frequency_hz: 7.0, normal_force_n: 1.0 }).stick_fraction, 0.25);
    }

    #[test]
    fn a_block_stuck_throughout_has_no_phase() {
        let mut acc = PointAccumulator::new(range());
        (0..100).for_each(|i| acc.tally_period(1e-3, 0.1 * f64::from(i), 1.0));
        assert!(!acc.moved());
        let stats = acc.stats(Condition { excitation_frequency_hz: 7.0, normal_force_n: 1.0 });
        assert_eq!(stats.stick_fraction, 1.0);
        assert!(stats.phase_mean_deg.is_nan() && stats.phase_var_deg2.is_nan());
        // One period with a little motion gives the phases back.
        acc.tally_period(1e-3, 0.3, 0.9);
        assert!(acc.moved());
        assert!(acc.phase_moments().0.is_finite());
    }

    #[test]
    fn phase_sums_give_the_circular_mean_and_variance() {
        let mut acc = PointAccumulator::new(range());
        let phases: Vec<f64> = (0..2000).map(|i| 2.5 + 0.01 * ((i as f64) * 0.77).sin()).collect();
        phases.iter().for_each(|&p| acc.tally_period(1e-3, p, 0.0));
        let (mean, var) = acc.phase_moments();
        let (direct_mean, direct_var) = circular_mean_var(&phases);
        let n = phases.len() as f64;
        let linear_mean = phases.iter().sum::<f64>() / n;
        let linear_var = phases.iter().map(|p| (p - linear_mean).powi(2)).sum::<f64>() / (n - 1.0);
        assert!((mean - linear_mean).abs() < 1e-8, "{mean} vs {linear_mean}");
        assert!((direct_mean - linear_mean).abs() < 1e-8, "{direct_mean} vs {linear_mean}");
        assert!((var / linear_var - 1.0).abs() < 1e-3, "{var} vs {linear_var}");
        assert!((direct_var / linear_var - 1.0).abs() < 1e-3, "{direct_var} vs {linear_var}");
        // Wrapped phases near ±π average to π, not 0.
        let (wrapped, _) = circular_mean_var(&[3.1, -3.1, 3.12, -3.12]);
        assert!((wrapped.abs() - std::f64::consts::PI).abs() < 1e-9, "{wrapped}");
    }

    #[test]
    fn histogram_quantiles_are_close_to_exact() {
        let mut acc = PointAccumulator::new(range());
        let peaks: Vec<f64> = (0..10_000).map(|i| 1e-3 + 2e-4 * (i as f64 / 10_000.0)).collect();
        peaks.iter().for_each(|&p| acc.tally_period(p, 0.3, 0.0));
        let bin = 4e-3 / f64::from(HISTOGRAM_BINS - 2);
        assert!((acc.quantile(0.5) - 1.1e-3).abs() < bin);
        assert!((acc.quantile(0.05) - 1.01e-3).abs() < bin);
    }

    #[test]
    fn the_quantiles_of_one_repeated_peak_are_that_peak() {
        let mut acc = PointAccumulator::new(range());
        let peak = 1.2345e-3;
        (0..500).for_each(|_| acc.tally_period(peak, 0.3, 0.0));
        for p in [0.05, 0.5, 0.95] {
            // The peak as the accumulator keeps it (f32), not spread across its bin.
            assert_eq!(acc.quantile(p), f64::from(peak as f32), "p {p}");
        }
    }

    /// Peaks far outside the range (clamped ones among them) are counted,
    /// and the range their extremes ask for holds every one of them, with
    /// exact sums and quantiles inside it.
    #[test]
    fn peaks_outside_the_range_ask_for_a_range_that_holds_them() {
        let peaks: Vec<f64> = (0..1000).map(|i| 0.5 + 1e-3 * (i as f64 * 0.37).sin()).collect();
        let mut acc = PointAccumulator::new(range());
        peaks.iter().for_each(|&p| acc.tally_period(p, 0.3, 0.0));
        assert_eq!((acc.outside_range(), acc.clamped), (1000, 1000));
        let wide = acc.range_holding_peaks().expect("a range that holds them");
        let mut again = PointAccumulator::new(wide);
        peaks.iter().for_each(|&p| again.tally_period(p, 0.3, 0.0));
        assert_eq!((again.outside_range(), again.clamped, again.range_holding_peaks()), (0, 0, None));
        let n = peaks.len() as f64;
        let mean = peaks.iter().sum::<f64>() / n;
        assert!((again.moments().0 - mean).abs() < 1e-7, "{} vs {mean}", again.moments().0);
        let mut sorted = peaks.clone();
        sorted.sort_by(f64::total_cmp);
        let bin = (wide.hi_m - wide.lo_m) / f64::from(HISTOGRAM_BINS - 2);
        assert!((again.quantile(0.5) - sorted[500]).abs() < 2.0 * bin);
        // Inside the range nothing is asked for.
        let mut inside = PointAccumulator::new(range());
        inside.tally_period(1e-3, 0.3, 0.0);
        assert_eq!(inside.range_holding_peaks(), None);
    }
}
