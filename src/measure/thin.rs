//! Thinning a set's records to a lower sample rate by keeping every k-th
//! sample. A rig may record far faster than its response needs (the seed
//! paper's also at 100 kHz, beside 600 Hz): a diagnosis simulates each
//! record at its own rate, with the baseline's noise held over one sample
//! interval, so such records cost hours where a few hundred samples per
//! period would do. The samples kept are the record's own, point samples
//! as the simulated records' are (an average over each k would lower every
//! peak by its sinc, a systematic miss of several standard errors).

use super::json::bad;
use super::{MeasurementSet, Run, SAMPLING_TOLERANCE, fmt_rate_hz, sample_rate_hz};
use crate::engine::model::{fmt_value, limits};
use crate::error::{Error, Result};

/// `set` with every k-th sample of each run kept, k = the run's sample
/// rate / `rate_hz` (Hz), and how many runs that thinned (k > 1; summary
/// rows are kept as they are). Refused, naming the run, where `rate_hz` is
/// not the run's rate divided by a whole number (within
/// [`SAMPLING_TOLERANCE`]), or where the thinned record could not be
/// diagnosed: not sampled above twice its excitation frequency, or with a
/// sample interval outside the range the noise can be held over.
pub fn thinned(set: &MeasurementSet, rate_hz: f64) -> Result<(MeasurementSet, usize)> {
    check_sample_rate(rate_hz, "sample rate")?;
    let mut thinned_runs = 0;
    let mut runs = Vec::with_capacity(set.runs.len());
    for run in &set.runs {
        let rate = sample_rate_hz(run);
        let ratio = rate / rate_hz;
        let k = ratio.round();
        if k < 1.0 || (ratio - k).abs() > SAMPLING_TOLERANCE * ratio {
            return Err(bad(
                &run.file,
                None,
                format!(
                    "sampled at {} Hz, which a sample rate of {} Hz does not divide: keeping every k-th sample \
                     gives {} Hz, {} Hz, {} Hz, …",
                    fmt_rate_hz(rate),
                    fmt_rate_hz(rate_hz),
                    fmt_rate_hz(rate / 2.0),
                    fmt_rate_hz(rate / 3.0),
                    fmt_rate_hz(rate / 4.0)
                ),
            ));
        }
        let k = k as usize;
        let (dt_lo, dt_hi) = limits::NOISE_INTERVAL_S;
        let interval_s = run.sample_interval_s() * k as f64;
        if rate_hz <= 2.0 * run.excitation_frequency_hz || !(dt_lo..=dt_hi).contains(&interval_s) {
            return Err(bad(
                &run.file,
                None,
                format!(
                    "thinned to {} Hz, the record could not be diagnosed: it must stay sampled above twice its \
                     excitation frequency ({} Hz), with a sample interval of {}..{} s",
                    fmt_rate_hz(rate_hz),
                    fmt_value(2.0 * run.excitation_frequency_hz),
                    fmt_value(dt_lo),
                    fmt_value(dt_hi)
                ),
            ));
        }
        if k > 1 {
            thinned_runs += 1;
        }
        runs.push(every(run, k));
    }
    Ok((MeasurementSet { runs, ..set.clone() }, thinned_runs))
}

/// Refuses a sample rate (Hz) that is not a positive number, naming it
/// `what`.
pub fn check_sample_rate(rate_hz: f64, what: &str) -> Result<()> {
    if rate_hz.is_finite() && rate_hz > 0.0 {
        Ok(())
    } else {
        Err(Error::setting(what, format!("{rate_hz} Hz; a sample rate is a positive number")))
    }
}

/// `run` with every `k`-th sample kept, the first included.
fn every(run: &Run, k: usize) -> Run {
    let keep = |values: &Vec<f64>| values.iter().step_by(k).copied().collect();
    Run {
        t_s: keep(&run.t_s),
        x_m: keep(&run.x_m),
        v_m_per_s: run.v_m_per_s.as_ref().map(keep),
        normal_force: run.normal_force.as_ref().map(keep),
        friction_force: run.friction_force.as_ref().map(keep),
        ..run.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::{RigInfo, TimeOrigin};

    fn set_at(rate_hz: f64) -> MeasurementSet {
        let n = (rate_hz * 2.0) as usize;
        let t: Vec<f64> = (0..n).map(|i| i as f64 / rate_hz).collect();
        let x: Vec<f64> = t.iter().map(|t| (std::f64::consts::TAU * 7.0 * t).cos()).collect();
        let run = Run {
            file: "run.csv".into(),
            excitation_frequency_hz: 7.0,
            excitation_amplitude_m: 0.0025,
            normal_force_n: 16.0,
            t_s: t,
            x_m: x.clone(),
            v_m_per_s: Some(x.clone()),
            normal_force: None,
            friction_force: Some(x),
            time_origin: TimeOrigin::Model,
        };
        MeasurementSet {
            dir: ".".into(),
            description: String::new(),
            rig: RigInfo { mass_kg: 1.0, natural_frequency_hz: 10.0, damping_ratio: 0.01 },
            runs: vec![run],
            summary: Vec::new(),
            summary_file: None,
        }
    }

    #[test]
    fn every_kth_sample_is_kept_where_the_rate_divides() {
        let set = set_at(6000.0);
        let (thin, n) = thinned(&set, 600.0).unwrap();
        assert_eq!(n, 1);
        let (run, full) = (&thin.runs[0], &set.runs[0]);
        assert_eq!(run.t_s.len(), 1200);
        assert_eq!(run.t_s[3], full.t_s[30]);
        assert_eq!(run.x_m[7], full.x_m[70]);
        assert_eq!(run.friction_force.as_ref().unwrap()[5], full.friction_force.as_ref().unwrap()[50]);
        assert!((sample_rate_hz(run) - 600.0).abs() < 1e-6);
        // At its own rate a run is kept as it is.
        let (same, n) = thinned(&set, 6000.0).unwrap();
        assert_eq!((same.runs[0].clone(), n), (set.runs[0].clone(), 0));
    }

    #[test]
    fn a_rate_that_does_not_divide_or_cannot_be_diagnosed_is_refused() {
        let set = set_at(1000.0);
        let err = thinned(&set, 600.0).unwrap_err().to_string();
        assert!(err.contains("run.csv") && err.contains("does not divide") && err.contains("500 Hz"), "{err}");
        let err = thinned(&set, 10.0).unwrap_err().to_string();
        assert!(err.contains("twice its excitation frequency"), "{err}");
        assert!(thinned(&set, 2000.0).is_err());
        assert!(thinned(&set, f64::NAN).is_err());
    }
}
