//! When a realisation's noise intervals begin and when a record is sampled:
//! the arithmetic both backends share, on the 32.32 fixed-point noise
//! boundaries of [`Oscillator::noise_interval_fixed`]. Boundary `j` lies at
//! `j · noise_interval_fixed / 2^32` excitation periods from the run's start.

use crate::engine::oscillator::Oscillator;

/// Fixed-point `2^32`.
pub(crate) const FIXED_ONE: f64 = 4_294_967_296.0;

/// Whether a record sampled every `sample_interval_s` (s) is taken at the
/// noise-interval boundaries themselves: asked for (`at_noise_boundaries`),
/// the noise is on, and the interval is the noise's to 1e-9. Both backends
/// decide with this test (the GPU kernel samples only such records).
pub(crate) fn samples_at_noise_boundaries(osc: &Oscillator, sample_interval_s: f64, at_noise_boundaries: bool) -> bool {
    let noisy = osc.noise_interval_fixed != Oscillator::NOISELESS_INTERVAL;
    at_noise_boundaries && noisy && (sample_interval_s / osc.noise_interval_s - 1.0).abs() < 1e-9
}

/// Index of the first noise interval a noise-aligned record samples: the
/// interval that starts at the first boundary at or after the end of
/// `warmup_cycles` periods.
pub(crate) fn first_sampled_interval(osc: &Oscillator, warmup_cycles: u32) -> u64 {
    first_boundary_from(osc, u64::from(warmup_cycles))
}

/// Index of the first noise boundary at or after the start of period
/// `periods` (`ceil(periods · 2^32 / interval)` in the 32.32 fixed point
/// both backends share): also how many boundaries `j ≥ 0` lie before it,
/// and the most any `periods` consecutive periods hold.
pub(crate) fn first_boundary_from(osc: &Oscillator, periods: u64) -> u64 {
    (u128::from(periods) << 32).div_ceil(u128::from(osc.noise_interval_fixed)) as u64
}

/// Excitation periods a record of `seconds` (s) integrates after its
/// warm-up: one more than it spans, so the last sample is always reached.
pub(crate) fn record_cycles(osc: &Oscillator, seconds: f64) -> u32 {
    (seconds / osc.period_s).ceil() as u32 + 1
}

/// Time (s from the run's start) at which noise interval `interval` (≥ 1)
/// begins, in the arithmetic the CPU's `run_period` gives an aligned sample
/// there: the boundary's period start plus its position in the period, both
/// from the 32.32 fixed-point boundary `interval · noise_interval_fixed`.
pub(crate) fn noise_boundary_time_s(osc: &Oscillator, interval: u64) -> f64 {
    let boundary = u128::from(interval) * u128::from(osc.noise_interval_fixed);
    let period_start_s = (boundary >> 32) as u64 as f64 * osc.period_s;
    let noise_t = (boundary as u64 & 0xFFFF_FFFF) as f64 / FIXED_ONE * osc.period_s;
    period_start_s + noise_t
}
