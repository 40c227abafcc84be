//! Calibrating the baseline to the data.
//!
//! With force channels, the friction law `μ(v) = a + b/(1 + c|v|)` and its
//! noise σ_μ come from a least-squares Stribeck fit of μ = |F|/N against
//! speed while slipping, matched between measured and simulated records by
//! indirect inference; σ_N and each condition's N0 come from the measured
//! normal force. Without force channels, the friction level `a` is solved so
//! that the simulated mean peaks match the measured ones.

use crate::diagnose::data::{Data, Unit};
use crate::diagnose::features::run_features;
use crate::diagnose::measure::Run;
use crate::diagnose::observable::Observable;
use crate::diagnose::score::{Score, score};
use crate::diagnose::simulate::{ensemble_path_stats, replicates_of};
use crate::diagnose::{DiagnoseSettings, mean};
use crate::engine::{Condition, Engine, Model};
use crate::error::Result;

/// Solves for the friction level `a` (with everything else fixed) so the
/// simulated mean peaks match the measured ones on the fitting units, on
/// average (relative), with small GPU ensembles. With `slope` (d residual /
/// d a, from the baseline's solve) one Newton step is taken; without it a
/// secant search runs and returns the slope it found.
fn solve_friction_level(
    model: &Model,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    engine: &Engine,
    slope: Option<f64>,
) -> Result<(Model, f64)> {
    let fit: Vec<&Unit> = data.units.iter().filter(|u| !u.heldout).collect();
    let conditions: Vec<Condition> =
        fit.iter().map(|u| data.simulated_condition(u, model, settings.warmup_cycles)).collect();
    let targets: Vec<f64> = data
        .units
        .iter()
        .zip(&data.measured)
        .filter(|(u, _)| !u.heldout)
        .map(|(_, m)| m.get(&Observable::PeakMeanM).copied().unwrap_or(f64::NAN))
        .collect();
    // The same window as the data: the records' (or summaries') length.
    let cycles = data
        .units
        .iter()
        .zip(&data.record_s)
        .filter(|(u, _)| !u.heldout)
        .map(|(u, s)| (s * u.condition.excitation_frequency_hz).round() as u32)
        .max()
        .unwrap_or(100);
    let residual = |a: f64| -> Result<f64> {
        let mut m = model.clone();
        m.friction.a = a;
        m.validate()?;
        let stats = ensemble_path_stats(
            engine,
            &m,
            &conditions,
            cycles,
            settings.ensemble_realisations.min(24),
            settings.seed ^ 0xA5A5,
            settings.warmup_cycles,
        )?;
        let errs: Vec<f64> = stats
            .iter()
            .zip(&targets)
            .filter(|(_, t)| t.is_finite() && **t > 0.0)
            .map(|(s, t)| mean(&s.iter().map(|p| p.peak_mean_m).collect::<Vec<_>>()) / t - 1.0)
            .collect();
        Ok(mean(&errs))
    };
    let lowest = (-model.friction.b).max(0.0);
    let with_a = |a: f64| {
        let mut out = model.clone();
        out.friction.a = a.clamp(lowest, 5.0);
        out
    };
    let mut a0 = model.friction.a.max(lowest);
    let mut r0 = residual(a0)?;
    if let Some(slope) = slope {
        return Ok((with_a(a0 - r0 / slope), slope));
    }
    let mut a1 = (a0 + 0.05).max(lowest + 0.01);
    let mut r1 = residual(a1)?;
    let mut slope = (r1 - r0) / (a1 - a0);
    for _ in 0..5 {
        if r1.abs() < 5e-4 || (r1 - r0).abs() < 1e-12 {
            break;
        }
        let a2 = (a1 - r1 * (a1 - a0) / (r1 - r0)).clamp(lowest, a1 + 0.5).min(5.0);
        (a0, r0) = (a1, r1);
        a1 = a2;
        r1 = residual(a1)?;
        if (a1 - a0).abs() > 1e-9 {
            slope = (r1 - r0) / (a1 - a0);
        }
    }
    let best = if r1.abs() <= r0.abs() { a1 } else { a0 };
    Ok((with_a(best), if slope.is_finite() && slope < 0.0 { slope } else { -1.0 }))
}

/// Calibrates the friction law of `model` to the data and scores it.
///
/// With friction channels this is indirect inference: the same
/// least-squares Stribeck fit (`fit_friction_law_at`, at the measured data's
/// best `c`) is run on the measured records and on the model's simulated
/// replicate records, and `a`, `b` and σ_μ are moved by the difference
/// (σ_μ² by the difference of the residual variances). The fit's numbers are
/// then those of the data whatever else the model carries (two steps, each
/// from the fitting units' replicates alone), so an effect that
/// changes friction (hysteresis lowering it early in a slip, stiction raising
/// it, a noise that is coloured or skewed) is judged with the law and noise
/// level that the data imply *given that effect*, not the ones it distorted.
/// Without friction channels `a` is solved from the response (mean peaks,
/// GPU ensembles).
pub(crate) fn calibrate_and_score(
    model: &Model,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    engine: &Engine,
    slope: Option<f64>,
) -> Result<(Model, Vec<Score>, f64)> {
    if let Some(measured) = data.measured_law {
        let mut m = model.clone();
        m.friction.c = measured.c;
        for _ in 0..LAW_STEPS {
            let Some(simulated) = simulated_law(engine, &m, data, settings, measured.c)? else { break };
            m.friction.b += measured.b - simulated.b;
            m.friction.a = (m.friction.a + measured.a - simulated.a).max((-m.friction.b).max(0.0));
            let variance = m.friction.sigma.powi(2) + measured.sigma.powi(2) - simulated.sigma.powi(2);
            m.friction.sigma = variance.max((0.1 * measured.sigma).powi(2)).sqrt();
        }
        let scores = score(engine, &m, data, settings)?;
        return Ok((m, scores, slope.unwrap_or(-1.0)));
    }
    let (m, slope) = solve_friction_level(model, data, settings, engine, slope)?;
    let scores = score(engine, &m, data, settings)?;
    Ok((m, scores, slope))
}

/// The friction law fitted at `c` to the model's simulated replicates of the
/// fitting units, pooled like the measured fitting runs are.
fn simulated_law(
    engine: &Engine,
    model: &Model,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    c: f64,
) -> Result<Option<FrictionLaw>> {
    let units: Vec<usize> =
        (0..data.units.len()).filter(|&i| !data.units[i].heldout && data.units[i].summary.is_none()).collect();
    let runs: Vec<Run> = replicates_of(engine, model, data, settings, &units)?.into_iter().flatten().collect();
    Ok(fit_friction_law_at(&runs.iter().collect::<Vec<_>>(), c))
}

/// The baseline from the data, before solving for `a`.
pub(crate) fn initial_baseline(data: &Data<'_>) -> Result<Model> {
    let set = data.set;
    let mut m = Model::default();
    m.rig.mass_kg = set.rig.mass_kg;
    m.rig.natural_frequency_hz = set.rig.natural_frequency_hz;
    m.rig.damping_ratio = set.rig.damping_ratio;
    m.excitation.amplitude_m = set
        .runs
        .first()
        .map(|r| r.excitation_amplitude_m)
        .or_else(|| set.summary.first().map(|s| s.excitation_amplitude_m))
        .unwrap_or(m.excitation.amplitude_m);
    m.noise.interval_s = data.sample_interval_s;
    let fit_runs: Vec<&Run> =
        data.units.iter().filter(|u| !u.heldout).flat_map(|u| u.runs.iter().map(|&r| &data.set.runs[r])).collect();
    // σ_N: what the measured N varies by once its mean, straight-line drift
    // and first four harmonics are removed (summary: its stated variance).
    let n_vars: Vec<f64> = fit_runs
        .iter()
        .filter_map(|r| run_features(r).normal_force.and_then(|n| n.residual_var_n2.or(Some(n.var_n2))))
        .collect();
    let summary_vars: Vec<f64> = set.summary.iter().filter_map(|s| s.normal_force_var_n2).collect();
    if !n_vars.is_empty() {
        m.normal_force.sigma = mean(&n_vars).sqrt();
    } else if !summary_vars.is_empty() {
        m.normal_force.sigma = mean(&summary_vars).sqrt();
    }
    // The friction law from the force channels, where recorded.
    if let Some(law) = data.measured_law {
        m.friction.a = law.a;
        m.friction.b = law.b;
        m.friction.c = law.c;
        m.friction.d = 0.0;
        m.friction.sigma = law.sigma;
    }
    m.validate()?;
    Ok(m)
}

/// A Stribeck law `μ(v) = a + b / (1 + c |v|)` fitted to slipping samples,
/// with the residual standard deviation around it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct FrictionLaw {
    /// –
    pub(crate) a: f64,
    /// –
    pub(crate) b: f64,
    /// s/m
    pub(crate) c: f64,
    /// Residual standard deviation of μ, –.
    pub(crate) sigma: f64,
}

/// Steps of the friction law's indirect inference (each simulates the
/// fitting units' replicates once).
const LAW_STEPS: usize = 2;

/// Stribeck decay rates `c` (s/m) the law is fitted over.
const LAW_C_GRID: [f64; 7] = [0.0, 2.0, 5.0, 10.0, 20.0, 40.0, 80.0];

/// The law with the smallest residual over [`LAW_C_GRID`]; `None` without
/// force channels or with fewer than 50 slipping samples.
pub(crate) fn fit_friction_law(runs: &[&Run]) -> Option<FrictionLaw> {
    LAW_C_GRID
        .iter()
        .filter_map(|&c| fit_friction_law_at(runs, c))
        .filter(|law| law.a >= 0.0 && law.a + law.b >= 0.0)
        .min_by(|x, y| x.sigma.total_cmp(&y.sigma))
}

/// Least squares of μ = |F|/N against speed on slipping samples (|v| above
/// 5% of the record's largest, friction opposing motion) at a given `c`:
/// linear in (a, b) with basis (1, 1/(1 + c|v|)). `None` with too few
/// samples. The fit is not constrained (as a statistic of simulated records
/// it must be the same function as on the measured ones).
fn fit_friction_law_at(runs: &[&Run], c: f64) -> Option<FrictionLaw> {
    let mut speeds = Vec::new();
    let mut mus = Vec::new();
    for r in runs {
        let (Some(v), Some(f), Some(n)) = (&r.v_m_per_s, &r.friction_force, &r.normal_force) else { continue };
        let vmax = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for i in 0..v.len() {
            if v[i].abs() > 0.05 * vmax && f[i] * v[i] < 0.0 && n[i] > 0.0 {
                speeds.push(v[i].abs());
                mus.push(f[i].abs() / n[i]);
            }
        }
    }
    if mus.len() < 50 {
        return None;
    }
    let basis: Vec<f64> = speeds.iter().map(|s| 1.0 / (1.0 + c * s)).collect();
    let (n, sx, sy) = (mus.len() as f64, basis.iter().sum::<f64>(), mus.iter().sum::<f64>());
    let sxx: f64 = basis.iter().map(|x| x * x).sum();
    let sxy: f64 = basis.iter().zip(&mus).map(|(x, y)| x * y).sum();
    let det = n * sxx - sx * sx;
    let (a, b) = if c == 0.0 || det.abs() < 1e-12 {
        (sy / n, 0.0)
    } else {
        ((sxx * sy - sx * sxy) / det, (n * sxy - sx * sy) / det)
    };
    let rss: f64 = basis.iter().zip(&mus).map(|(x, y)| (y - a - b * x).powi(2)).sum();
    Some(FrictionLaw { a, b, c, sigma: (rss / (n - 2.0)).sqrt() })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::Sample;
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    /// A record sliding back and forth at 1 Hz with friction from a known
    /// Stribeck law plus Gaussian noise of sd `sigma`.
    fn record(a: f64, b: f64, c: f64, sigma: f64, seed: u64) -> Run {
        let mut rng = StdRng::seed_from_u64(seed);
        let samples: Vec<Sample> = (0..12_000)
            .map(|i| {
                let t_s = f64::from(i) / 600.0;
                let v = 0.2 * (std::f64::consts::TAU * t_s).sin();
                let (u1, u2): (f64, f64) = (rng.random::<f64>().max(1e-300), rng.random());
                let noise = sigma * (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
                let mu = a + b / (1.0 + c * v.abs()) + noise;
                Sample { t_s, x_m: 0.0, v_m_per_s: v, normal_force_n: 10.0, friction_force_n: -v.signum() * mu * 10.0 }
            })
            .collect();
        Run::from_samples(&samples, 1.0, 1e-3, 10.0)
    }

    #[test]
    fn friction_law_fit_recovers_a_known_law() {
        let run = record(0.25, 0.1, 20.0, 0.04, 1);
        let law = fit_friction_law(&[&run]).unwrap();
        assert_eq!(law.c, 20.0, "{law:?}");
        assert!((law.a - 0.25).abs() < 0.005 && (law.b - 0.1).abs() < 0.01, "{law:?}");
        assert!((law.sigma / 0.04 - 1.0).abs() < 0.03, "{law:?}");
        // At a fixed c the fit is the unconstrained least squares, so a law
        // with friction falling below zero at rest is still reported.
        let rising = fit_friction_law_at(&[&record(0.4, -0.3, 80.0, 0.0, 2)], 80.0).unwrap();
        assert!((rising.b + 0.3).abs() < 1e-6 && (rising.a - 0.4).abs() < 1e-6, "{rising:?}");
        assert!(fit_friction_law(&[&record(0.4, -0.5, 80.0, 0.0, 2)]).is_none_or(|l| l.a + l.b >= 0.0));
    }
}
