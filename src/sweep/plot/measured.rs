//! Measured statistics as the sweep figures draw them: a measurement set's
//! summary rows and record peaks per condition ([`MeasuredPoint`]), and the
//! simulated curve each is set against ([`pair`]).

use super::same_load;
use crate::diagnose::features::period_peaks;
use crate::engine::Condition;
use crate::measure::MeasurementSet;

/// Measured statistics of one condition, drawn over the simulation.
#[derive(Clone, Debug, PartialEq)]
pub struct MeasuredPoint {
    /// Hz
    pub excitation_frequency_hz: f64,
    /// Nominal (or mean) normal force, N.
    pub normal_force_n: f64,
    /// Mean peak amplitude, m.
    pub peak_mean_m: f64,
    /// Variance of the peak amplitude, m², when known.
    pub peak_var_m2: Option<f64>,
    /// Peaks behind the statistics, when known.
    pub n_peaks: Option<u64>,
    /// Mean phase lag behind the base, degrees, and its variance, degrees², when known.
    pub phase_deg: Option<(f64, Option<f64>)>,
    /// The per-period peaks themselves (m), when the set has records.
    pub peaks_m: Vec<f64>,
}

impl MeasuredPoint {
    /// The standard error of the mean peak, m (0 when unknown).
    pub fn mean_standard_error_m(&self) -> f64 {
        match (self.peak_var_m2, self.n_peaks) {
            (Some(v), Some(n)) if n > 0 => (v.max(0.0) / n as f64).sqrt(),
            _ => 0.0,
        }
    }

    /// Whether this is the grid point `c`: its frequency (within 1e-6) and
    /// its normal force (within 1%).
    pub fn matches(&self, c: &Condition) -> bool {
        (self.excitation_frequency_hz - c.excitation_frequency_hz).abs() <= 1e-6 * c.excitation_frequency_hz.abs()
            && same_load(self.normal_force_n, c.normal_force_n)
    }
}

/// A measurement set's statistics per condition: its summary rows, and the
/// per-period peaks of its records (which give the statistics of a
/// condition without a summary row), read on the periods a diagnosis reads
/// ([`period_peaks`]).
pub fn measured_points(set: &MeasurementSet) -> Vec<MeasuredPoint> {
    let mut points: Vec<MeasuredPoint> = set
        .summary
        .iter()
        .filter_map(|r| {
            Some(MeasuredPoint {
                excitation_frequency_hz: r.excitation_frequency_hz,
                normal_force_n: r.normal_force_mean_n,
                peak_mean_m: r.peak_mean_m?,
                peak_var_m2: r.peak_var_m2,
                n_peaks: r.n_peaks,
                phase_deg: r.phase_mean_deg.map(|m| (m, r.phase_var_deg2)),
                peaks_m: Vec::new(),
            })
        })
        .collect();
    for run in &set.runs {
        let peaks = period_peaks(run);
        let cond =
            Condition { excitation_frequency_hz: run.excitation_frequency_hz, normal_force_n: run.normal_force_n };
        match points.iter_mut().find(|p| p.matches(&cond)) {
            Some(p) => p.peaks_m.extend(peaks),
            None => points.push(MeasuredPoint {
                excitation_frequency_hz: run.excitation_frequency_hz,
                normal_force_n: run.normal_force_n,
                peak_mean_m: f64::NAN,
                peak_var_m2: None,
                n_peaks: None,
                phase_deg: None,
                peaks_m: peaks,
            }),
        }
    }
    for p in &mut points {
        if !p.peak_mean_m.is_finite() && p.peaks_m.len() > 1 {
            let n = p.peaks_m.len() as f64;
            let mean = p.peaks_m.iter().sum::<f64>() / n;
            p.peak_mean_m = mean;
            p.peak_var_m2 = Some(p.peaks_m.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0));
            p.n_peaks = Some(p.peaks_m.len() as u64);
        }
    }
    points.retain(|p| p.peak_mean_m.is_finite());
    points
}

/// A measured point's simulated counterpart: the curve of its normal force
/// (within 1%), else the curve of the nearest simulated normal force.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pairing {
    /// Index of the curve (normal forces in increasing order).
    pub curve: usize,
    /// The curve's normal force, N.
    pub force_n: f64,
    /// Whether the curve is at the measured load (else the nearest one).
    pub same_load: bool,
}

/// Pairs a measured point with a curve of `forces` (increasing).
pub fn pair(forces: &[f64], m: &MeasuredPoint) -> Option<Pairing> {
    let (curve, &force_n) = forces
        .iter()
        .enumerate()
        .min_by(|(_, a), (_, b)| (*a - m.normal_force_n).abs().total_cmp(&(*b - m.normal_force_n).abs()))?;
    Some(Pairing { curve, force_n, same_load: same_load(force_n, m.normal_force_n) })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plot_pairs_measured_loads_with_their_own_or_the_nearest_curve() {
        let point = |n: f64| MeasuredPoint {
            excitation_frequency_hz: 7.0,
            normal_force_n: n,
            peak_mean_m: 4e-3,
            peak_var_m2: None,
            n_peaks: None,
            phase_deg: None,
            peaks_m: Vec::new(),
        };
        let forces = [4.0, 8.0, 12.0, 16.39];
        assert_eq!(pair(&forces, &point(16.39)), Some(Pairing { curve: 3, force_n: 16.39, same_load: true }));
        assert_eq!(pair(&forces, &point(16.4)).map(|p| p.same_load), Some(true));
        assert_eq!(pair(&forces, &point(7.519)), Some(Pairing { curve: 1, force_n: 8.0, same_load: false }));
        assert_eq!(pair(&forces, &point(15.3)).map(|p| p.force_n), Some(16.39));
        assert_eq!(pair(&[], &point(1.0)), None);
    }
}
