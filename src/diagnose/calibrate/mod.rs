//! Calibrating the baseline to the data.
//!
//! With force channels, the friction law `μ(v) = a + b/(1 + c|v|) + d v²`
//! and its noise σ_μ come from a least-squares fit of μ = |F|/N against
//! speed while slipping, within records (a level per record, so friction
//! that differs between loads is left to the effect that makes it instead
//! of bending the curve), matched between measured and simulated records by
//! indirect inference; σ_N and each condition's N0 come from the measured
//! normal force. Without force channels, the friction level `a` is solved so
//! that the simulated mean peaks match the measured ones (`level`). One
//! step of the indirect inference, and how far σ_μ moves a derived force's
//! residual, are `indirect`'s.

use crate::diagnose::data::Data;
use crate::diagnose::features::run_features;
use crate::diagnose::law::{self, FrictionLaw};
use crate::diagnose::observable::Observable;
use crate::diagnose::score::{Scope, Score, add_heldout, gap_of, score};
use crate::diagnose::simulate::fits_per_task;
use crate::diagnose::{DiagnoseSettings, mean};
use crate::engine::oscillator::Oscillator;
use crate::engine::reduce::wrap_angle;
use crate::engine::{Engine, Model};
use crate::error::{Error, Result};
use crate::measure::Run;
use rayon::prelude::*;

mod indirect;
mod level;

use indirect::{sigma_response, simulated_law, step_law};
use level::{ResponseTargets, scale_noise, solve_friction_level};

/// Calibrates the friction law of `model` to the data and scores it.
///
/// With friction channels this is indirect inference over the whole of
/// eq. 7: the same least-squares fit of `a + b/(1 + c|v|) + d v²`
/// ([`crate::diagnose::law::fit_friction_law`]) is run on the measured records and on the model's
/// simulated replicate records (which carry the data's measurement noise),
/// and `a`, `b`, `d` are moved by the difference (`c` stays the measured
/// law's) and σ_μ² by the difference of the residual variances within
/// records (each record's mean residual removed, so a friction level that changes with
/// the load or over time is left to the effect that makes it), condition by
/// condition ([`crate::diagnose::law::variance_gap`]). The fit's numbers are then
/// those of the data whatever else the model carries (`law_steps` steps, 0
/// for the baseline's [`LAW_STEPS`], each from the fitting units'
/// replicates alone), so an effect that
/// changes friction (hysteresis lowering it early in a slip, stiction raising
/// it, a noise that is coloured or skewed) is judged with the law and noise
/// level that the data imply *given that effect*, not the ones it distorted.
/// Without friction channels `a` is solved from the response (mean peaks,
/// GPU ensembles). The scores cover the units in `scope`.
pub(crate) fn calibrate_and_score(
    model: &Model,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    engine: &Engine,
    slope: Option<f64>,
    law_steps: usize,
    scope: Scope,
) -> Result<(Model, Vec<Score>, f64)> {
    if let Some(measured) = data.measured_law {
        let mut m = model.clone();
        let response = sigma_response(engine, &m, data, settings)?;
        for _ in 0..if law_steps == 0 { LAW_STEPS } else { law_steps } {
            let Some((simulated, gap)) = simulated_law(engine, &m, data, settings)? else { break };
            if crate::diagnose::tracing() {
                let law = |l: &FrictionLaw| format!("a {:.4} b {:.4} d {:.4} sigma {:.4}", l.a, l.b, l.d, l.sigma);
                eprintln!(
                    "law step: model sigma {:.4}; measured {}; simulated {}; variance gap {gap:.3e}; response {response:.3}",
                    m.friction.sigma,
                    law(&measured),
                    law(&simulated)
                );
            }
            step_law(&mut m, &measured, &simulated, gap, response);
        }
        let scores = score(engine, &m, data, settings, scope)?;
        return Ok((m, scores, slope.unwrap_or(-1.0)));
    }
    let Some(targets) = ResponseTargets::of(data) else {
        let scores = score(engine, model, data, settings, scope)?;
        return Ok((model.clone(), scores, slope.unwrap_or(-1.0)));
    };
    let baseline = slope.is_none();
    let (mut m, slope) = solve_friction_level(model, data, settings, engine, targets, slope)?;
    if let Some(spread) = targets.spread {
        // The baseline settles level and noise together; a trial takes one
        // step of each from where its model stands.
        for _ in 0..if baseline { NOISE_ROUNDS } else { 1 } {
            m = scale_noise(&m, data, settings, engine, spread)?;
            if baseline {
                m = solve_friction_level(&m, data, settings, engine, targets, Some(slope))?.0;
            }
        }
    }
    let scores = score(engine, &m, data, settings, scope)?;
    Ok((m, scores, slope))
}

/// Rounds of noise scaling and level solving that calibrate a baseline
/// without friction channels.
const NOISE_ROUNDS: usize = 3;

/// Steps of the friction law's indirect inference for the baseline (each
/// simulates the fitting units' replicates once); a candidate's trial takes
/// one, from the calibrated baseline's law.
const LAW_STEPS: usize = 3;

/// Law-only recalibration steps after a model was calibrated, at most
/// this many: each moves the friction law one more step of the indirect
/// inference with nothing else changed.
pub(crate) const POLISH_STEPS: usize = 3;

/// Further law-only steps from a calibrated model and its scores, kept while
/// they lower the fitting gap, at most [`POLISH_STEPS`]. A search carries the
/// law one step per trial, so when an effect's strength moved a lot the law
/// is still on its way to the one the data imply with that effect; scoring
/// the next round against it would credit any further effect with the
/// remaining steps of the law (a second effect "explaining" what one more
/// law step explains). A no-op without friction channels (no law to step).
/// `scores` may cover the fitting units only ([`Scope::Fitting`]): the steps
/// are judged by the fitting gap, and the held-out units are scored once,
/// for the model kept; the result covers every unit.
pub(crate) fn converge_law(
    model: Model,
    scores: Vec<Score>,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    engine: &Engine,
) -> Result<(Model, Vec<Score>)> {
    let (mut model, mut scores) = (model, scores);
    let mut complete = scores.iter().any(|s| s.heldout) || !data.has_heldout();
    if data.measured_law.is_some() {
        for _ in 0..POLISH_STEPS {
            let (m, s, _) = calibrate_and_score(&model, data, settings, engine, None, 1, Scope::Fitting)?;
            if gap_of(&s, false) >= gap_of(&scores, false) {
                break;
            }
            (model, scores, complete) = (m, s, false);
        }
    }
    if !complete {
        scores = add_heldout(engine, &model, data, settings, scores)?;
    }
    Ok((model, scores))
}

/// `model` with its friction law moved one step towards the data from what
/// scoring it gave (`scores`, on the view's fitting units), without a
/// simulation of its own: with force channels one step of the indirect
/// inference from its replicate records (those that scored it); without
/// them, a Newton step of the friction level `a` on `slope` (d level error /
/// d a) from the mean level error of its scores; unchanged where neither
/// applies.
pub(crate) fn law_step(
    model: &Model,
    scores: &[Score],
    slope: f64,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    engine: &Engine,
) -> Result<Model> {
    let mut m = model.clone();
    if let Some(measured) = data.measured_law {
        if let Some((simulated, gap)) = simulated_law(engine, model, data, settings)? {
            let response = sigma_response(engine, model, data, settings)?;
            step_law(&mut m, &measured, &simulated, gap, response);
        }
        return Ok(m);
    }
    let Some(targets) = ResponseTargets::of(data) else { return Ok(m) };
    let errors: Vec<f64> = scores
        .iter()
        .filter(|s| !s.heldout && s.observable == targets.level && s.measured.is_finite())
        .filter_map(|s| match targets.level {
            Observable::PeakMeanM => (s.measured > 0.0).then(|| s.simulated / s.measured - 1.0),
            _ => Some(wrap_angle((s.simulated - s.measured).to_radians())),
        })
        .collect();
    if !errors.is_empty() && slope.is_finite() && slope != 0.0 {
        let lowest = (-m.friction.b).max(0.0);
        m.friction.a = (m.friction.a - mean(&errors) / slope).clamp(lowest, (m.friction.a + 0.5).min(5.0));
    }
    Ok(m)
}

/// A calibrated model, its scores and the friction level's slope (see
/// [`calibrate_and_score`]).
type Calibrated = (Model, Vec<Score>, f64);

/// The baseline calibrated to the data, its scores at every unit and the
/// friction level's slope ([`calibrate_and_score`], then [`converge_law`]).
///
/// A friction force derived from `x` does not pin the Stribeck rate `c`
/// (see [`initial_baseline`]), yet the rate sets the law's friction at
/// rest, `a + b`, which the law's fit only extrapolates to: the slowest
/// slips it reads are blurred, and a block held throughout reads none.
/// Held at a rate far from the rig's, a law that matches the sliding
/// friction can break away at a tenth less than the rig does, and its
/// replicates then slide at a load where the data's block never moves
/// (peak means hundreds of noise units apart). The data as a whole do pin
/// it: the baseline is calibrated at each rate of
/// [`DERIVED_RATE_GRID_S_PER_M`], then a quarter-decade either side of the
/// best, and the rate whose calibrated baseline fits the fitting units best
/// is kept. The rates are compared as a search compares its trials, on
/// half the replicates ([`DiagnoseSettings::for_search`]); the kept one is
/// then stepped on all of them. With a recorded force the rate is the
/// data's, and one calibration is made.
pub(crate) fn calibrate_baseline(data: &Data<'_>, settings: &DiagnoseSettings, engine: &Engine) -> Result<Calibrated> {
    let converged = |(baseline, scores, slope): Calibrated| -> Result<Calibrated> {
        let (baseline, scores) = converge_law(baseline, scores, data, settings, engine)?;
        Ok((baseline, scores, slope))
    };
    if !searches_rate(data) {
        let start = initial_baseline(data, None)?;
        return converged(calibrate_and_score(&start, data, settings, engine, None, 0, Scope::All)?);
    }
    let search = settings.for_search();
    // The filter's response to σ_μ is measured on this model, on every
    // replicate (each colour of the noise a model later carries too).
    sigma_response(engine, &initial_baseline(data, Some(DERIVED_RATE_GRID_S_PER_M[0]))?, data, settings)?;
    // (fitting gap, rate in s/m, the baseline calibrated at it on the
    // search's replicates)
    let at = |rate: f64| -> Result<(f64, f64, Calibrated)> {
        let start = initial_baseline(data, Some(rate))?;
        let calibrated = calibrate_and_score(&start, data, &search, engine, None, 0, Scope::Fitting)?;
        let gap = gap_of(&calibrated.1, false);
        if crate::diagnose::tracing() {
            eprintln!("baseline at Stribeck rate {rate:.3} s/m: fitting gap {gap:.4}");
        }
        Ok((gap, rate, calibrated))
    };
    // The index of the best fit so far (a gap that is NaN sorts last).
    let best = |tried: &[(f64, f64, Calibrated)]| {
        (0..tried.len()).min_by(|&i, &j| tried[i].0.total_cmp(&tried[j].0)).expect("the rate grid is not empty")
    };
    // Each rate's calibration is independent of the others': side by side
    // ([`fits_per_task`]). (Trace lines interleave.)
    let at_each = |rates: &[f64]| -> Result<Vec<(f64, f64, Calibrated)>> {
        rates.par_iter().with_min_len(fits_per_task(engine)).map(|&rate| at(rate)).collect()
    };
    let mut tried = at_each(&DERIVED_RATE_GRID_S_PER_M)?;
    let around = tried[best(&tried)].1;
    let half_step = (DERIVED_RATE_GRID_S_PER_M[1] / DERIVED_RATE_GRID_S_PER_M[0]).sqrt();
    tried.extend(at_each(&[around / half_step, around * half_step])?);
    let kept = tried.swap_remove(best(&tried)).2.0;
    // On every replicate: one more step of its law, then on while the steps
    // lower the fitting gap.
    converged(calibrate_and_score(&kept, data, settings, engine, None, 1, Scope::Fitting)?)
}

/// Whether [`calibrate_baseline`] searches the Stribeck rate: where the
/// friction force is derived from `x` and gives a law.
pub(crate) fn searches_rate(data: &Data<'_>) -> bool {
    data.derived.friction && data.measured_law.is_some()
}

/// The Stribeck rates (s/m) a baseline with a friction force derived from
/// `x` is calibrated at first ([`calibrate_baseline`]): half-decade steps
/// through the paper's 20 s/m. With the refinement about the best, the
/// rates reach from 1.1 to 112 s/m.
pub(crate) const DERIVED_RATE_GRID_S_PER_M: [f64; 4] = [2.0, 6.32, 20.0, 63.2];

/// How many rates [`calibrate_baseline`] calibrates a baseline at: the
/// grid's and the two about its best.
pub(crate) const DERIVED_RATES_TRIED: usize = DERIVED_RATE_GRID_S_PER_M.len() + 2;

/// The baseline before calibration: the rig and excitation from the
/// manifest, σ_N from the data, and the friction law read from the force
/// channels; where the force is derived from `x`, at the Stribeck rate
/// `rate` (s/m; `None`: the paper's).
fn initial_baseline(data: &Data<'_>, rate: Option<f64>) -> Result<Model> {
    let set = data.set;
    let mut m = Model::default();
    if let Some(c) = rate {
        m.friction.c = c;
    }
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
    // The friction law from the force channels, recorded or derived. The
    // rate that fits a recorded force best is the rig's. Through a derived
    // force's filter it is not (a stick's onset blurred over the window
    // reads as a drop tens of times faster), and the rate the data's and
    // the replicates' fits read does not follow the model's closely enough
    // to be inferred from: the model takes a given rate (the paper's, or
    // one of [`calibrate_baseline`]'s grid), and `a`, `b` and `d` are
    // inferred at it, starting from the data's curve read at that rate. Not
    // from the terms read at the data's own rate: where that rate is slow,
    // a and b trade off along the near-constant 1/(1 + c |v|) (a 1.40,
    // b −1.00 at c = 1 s/m for a curve near 0.45), a law far from the
    // data's at the model's rate.
    if let Some(measured) = data.measured_law {
        let law = if data.derived.friction {
            law::fit_friction_law_at(&fit_runs, &data.reading(), m.friction.c).unwrap_or(measured)
        } else {
            m.friction.c = measured.c;
            measured
        };
        m.friction.a = law.a.max(0.0);
        m.friction.b = law.b.max(-m.friction.a);
        m.friction.d = law.d;
        m.friction.sigma = law.sigma;
    }
    m.validate().map_err(|e| named_by_manifest(data, e))?;
    // A rig the oscillator cannot integrate at some condition (one far
    // stiffer than the excitation is slow) is the manifest's.
    for unit in &data.units {
        Oscillator::new(&m, unit.condition).map_err(|e| named_by_manifest(data, e))?;
    }
    Ok(m)
}

/// What the report says where the baseline's σ_N (N) is not read from the
/// data: with friction channels (recorded or derived) the law and σ_μ come
/// from them, and σ_N from a normal-force channel or a stated variance;
/// with neither, `baseline`'s σ_N is the paper's. `None` where the data
/// give σ_N, or where the response sets it (no friction channels).
pub(crate) fn assumed_normal_force_noise_note(data: &Data<'_>, baseline: &Model) -> Option<String> {
    (data.measured_law.is_some() && !data.states_normal_force_noise()).then(|| {
        format!(
            "no run records the normal force and no summary states its variance, so the normal force's noise is \
             not read from the data: the baseline keeps σ_N = {:.3} N (the paper's). μ is read as the friction \
             force over the nominal load, so a σ_N unlike the rig's moves into σ_μ, most at the lightest loads; a \
             normal-force channel settles it",
            baseline.normal_force.sigma
        )
    })
}

/// An error in a parameter of the model that the manifest's `rig` gave,
/// or in the friction law the baseline was calibrated to from the records,
/// named by the measurement set instead of as a model parameter the user
/// never wrote. Other errors pass through.
pub(crate) fn named_by_manifest(data: &Data<'_>, e: Error) -> Error {
    let manifest = data.set.dir.join("manifest.json");
    match e {
        Error::InvalidParameter { key, value, message } if key.starts_with("rig.") => {
            Error::Measurement { file: manifest, line: None, message: format!("`{key}` = {value}: {message}") }
        }
        Error::InvalidParameter { key, value, message } if key.starts_with("friction.") => {
            let read = match (data.measured_law.is_some(), data.derived.friction) {
                (true, true) => {
                    "the friction derived from the displacement through the equation of motion with the rig's \
                     mass, natural frequency and damping ratio"
                }
                (true, false) => "the recorded friction and normal forces",
                (false, _) => "the response at the rig's mass, natural frequency and damping ratio",
            };
            Error::Measurement {
                file: manifest,
                line: None,
                message: format!(
                    "calibrating the baseline to these records took `{key}` to {value}, and {message}. It was \
                     read from {read}, so the records and the manifest disagree: check `rig` (mass_kg, \
                     natural_frequency_hz, damping_ratio) and each run's normal_force_n and excitation against \
                     the rig that made the records"
                ),
            }
        }
        other => other,
    }
}
