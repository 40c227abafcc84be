//! One step of the friction law's indirect inference from a model's
//! replicate records ([`simulated_law`], [`step_law`]), and how far σ_μ
//! moves what a derived friction force shows ([`sigma_response`]).

use crate::diagnose::DiagnoseSettings;
use crate::diagnose::data::Data;
use crate::diagnose::law::{FrictionLaw, Spread};
use crate::diagnose::simulate::fitting_records;
use crate::engine::effects::{ColourForm, ColouredFrictionNoise};
use crate::engine::{Engine, Model};
use crate::error::Result;

/// The friction law fitted to the model's simulated replicates of the
/// fitting units, pooled like the measured fitting runs are, at the
/// measured law's Stribeck rate `c` (s/m). The measured law is the fit at
/// that `c` too (it is where its residual is smallest), so both sides of
/// the indirect inference are the same statistic, the linear fit at a
/// fixed `c`, one fit instead of the ~27 of a search over `c`. Its cost:
/// where the model misfits the data's speed distribution (a drift of the
/// normal force it lacks, in the benchmark), the simulated residual at that
/// `c` stays above the measured one whatever σ_μ is, and the step drives
/// σ_μ to its floor; searching `c` on both sides avoided that and did no
/// better over the benchmark (`benches/RESULTS.md`). The records are the
/// ones the model's score on the fitting units reads ([`fitting_records`]):
/// simulated once for both.
///
/// With it, how much more the friction's residual variance is in the data
/// than in the replicates, –²: condition by condition where any condition
/// has slipping samples on both sides, else the pooled laws' σ² apart
/// ([`crate::diagnose::simulate::FittingRecords::variance_gap`]).
pub(super) fn simulated_law(
    engine: &Engine,
    model: &Model,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
) -> Result<Option<(FrictionLaw, f64)>> {
    let records = fitting_records(engine, model, data, settings)?;
    let (Some(simulated), Some(measured)) = (records.law, data.measured_law) else { return Ok(None) };
    Ok(records.variance_gap(&data.measured_spreads(&records.units), measured.sigma.powi(2)).map(|gap| (simulated, gap)))
}

/// How far the replicates' friction residual variance moves per unit of
/// σ_μ² (–), which a σ step divides the variance gap by: one for one with
/// a recorded friction force; through a derived one's filter
/// ([`crate::diagnose::derived`]) a fraction, which depends on the noise's
/// spectrum: a white noise held for one interval is mostly smoothed away,
/// a noise correlated over many intervals mostly passes. The noise is a
/// sum of independent parts ([`noise_parts`]), whose variances add through
/// the filter, so the response is their responses weighted by their shares
/// of σ_μ². Each part's is measured once ([`part_response`]). One white
/// response for every model stepped a half-coloured noise's σ_μ about
/// twice too far, and its law steps swung about the σ_μ the data imply
/// instead of reaching it.
pub(super) fn sigma_response(
    engine: &Engine,
    model: &Model,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
) -> Result<f64> {
    if !data.derived.friction {
        return Ok(1.0);
    }
    let mut response = 0.0;
    for (share, part) in noise_parts(&model.effects.coloured_friction_noise).into_iter().filter(|p| p.0 > 0.0) {
        response += share * part_response(engine, model, &part, data, settings)?;
    }
    Ok(response)
}

/// The independent parts of a friction noise of colour `colour` (`None`:
/// white), each with its share of the noise's variance (–): `None` for a
/// white part, else a whole-variance `ar1` at its correlation time, or a
/// `hold`. The parts of every form are those of its simulation
/// ([`crate::engine::effects::ColouredFrictionNoise`]).
fn noise_parts(colour: &Option<ColouredFrictionNoise>) -> Vec<(f64, Option<ColouredFrictionNoise>)> {
    let Some(c) = colour.as_ref().filter(|c| c.correlation_time_s > 0.0) else { return vec![(1.0, None)] };
    let ar1 = |tau_s: f64| {
        Some(ColouredFrictionNoise { form: ColourForm::Ar1, correlation_time_s: tau_s, coloured_share: 1.0 })
    };
    let tau = c.correlation_time_s;
    let share = c.coloured_share.clamp(0.0, 1.0);
    match c.form {
        ColourForm::Ar1 => vec![(1.0 - share, None), (share, ar1(tau))],
        ColourForm::Hold => vec![(1.0, colour.clone())],
        ColourForm::TwoScale => vec![(0.5, None), (0.5, ar1(tau))],
        ColourForm::MultiScale => [0.25, 1.0, 4.0].iter().map(|f| (1.0 / 3.0, ar1(f * tau))).collect(),
        ColourForm::FastSlow => vec![(1.0 - share, ar1(tau)), (share, ar1(10.0 * tau))],
    }
}

/// The response to σ_μ² (–) of a noise that is wholly `part` (`None`:
/// white; see [`noise_parts`]), measured once per diagnosis on one model:
/// the first asked for a response (the initial baseline), with `part` put
/// on it and every unit fitted, as the gap's fall when σ_μ alone is raised
/// by a quarter, the replicates' noise the same. Read between successive
/// steps instead, it also carried what the law's move between them did to
/// the residual, and came out at either bound of its clamp: a step ten
/// times too long, or σ left short.
fn part_response(
    engine: &Engine,
    model: &Model,
    part: &Option<ColouredFrictionNoise>,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
) -> Result<f64> {
    let responses = &data.caches.sigma_response;
    if let Some(r) = responses.get(part) {
        return Ok(r);
    }
    let every_unit = data.view(None);
    let (on, on_settings, measured) = responses.measured_on(|| {
        let units: Vec<usize> = (0..every_unit.units.len()).collect();
        (model.clone(), *settings, every_unit.measured_spreads(&units))
    });
    let mut base = on;
    base.effects.coloured_friction_noise = part.clone();
    let mut raised = base.clone();
    raised.friction.sigma = 1.25 * base.friction.sigma.max(1e-3);
    // The gap to the spreads kept with that model: its data's, whichever
    // view asks (the data's own pooled σ² cancels in the fall).
    let gap = |m: &Model| -> Result<Option<f64>> {
        let records = fitting_records(engine, m, &every_unit, &on_settings)?;
        let at: Vec<Option<Spread>> = records.units.iter().map(|&u| measured[u]).collect();
        Ok(records.variance_gap(&at, 0.0))
    };
    let (Some(before), Some(after)) = (gap(&base)?, gap(&raised)?) else {
        return Ok(1.0);
    };
    let base_variance = base.friction.sigma.powi(2);
    let response = ((before - after) / (raised.friction.sigma.powi(2) - base_variance)).clamp(MIN_SIGMA_RESPONSE, 1.5);
    if crate::diagnose::tracing() {
        eprintln!(
            "sigma response {response:.3} for {} (gap {before:.3e} at sigma {:.4}, {after:.3e} at {:.4})",
            part.as_ref().map_or("a white noise".to_string(), |c| format!("{:?} {} s", c.form, c.correlation_time_s)),
            base.friction.sigma,
            raised.friction.sigma
        );
    }
    Ok(responses.insert(part, response))
}

/// One step of the indirect inference, in curve space: the model's law
/// μ(v) is moved at the measured slipping speeds' deciles by what the
/// measured fit and the fit on its own simulated records differ by there,
/// and a, b, d are refitted to the moved curve at the model's own Stribeck
/// rate c (linear least squares, so the step is continuous and cannot
/// wander off along the directions in which a, b, c and d trade off; c
/// itself is the model's: the measured records' fit, or for a force
/// derived from `x` the one [`super::calibrate_baseline`] chose).
/// `response`: how far the simulated residual variance moves per unit of
/// σ_μ² (1 with recorded channels; a derived friction force, read through
/// a smoothing filter, passes a fraction of the noise, [`crate::diagnose::derived`]).
/// `variance_gap`: how much more the friction's residual variance is in
/// the data than in the replicates, –² ([`simulated_law`]).
pub(super) fn step_law(
    model: &mut Model,
    measured: &FrictionLaw,
    simulated: &FrictionLaw,
    variance_gap: f64,
    response: f64,
) {
    if let Some(law) = FrictionLaw::of(model).moved(measured, simulated) {
        let f = &mut model.friction;
        f.a = law.a.max(0.0);
        f.b = law.b.max(-f.a);
        f.d = law.d;
    }
    let f = &mut model.friction;
    let variance = f.sigma.powi(2) + variance_gap / response;
    f.sigma = variance.max((0.1 * measured.sigma).powi(2)).sqrt().max(SIGMA_STEP_MIN_SHARE * f.sigma);
}

/// A law step lowers σ_μ to no less than this share of what it was. The
/// σ step is a Newton step that takes the simulated residual variance to
/// move one for one with σ_μ²; an effect whose form differs from the
/// data's (a friction memory of another shape, in a trial of the search)
/// adds a structured residual of its own, and one full step can then take
/// σ_μ straight to its floor, hiding the effect behind a noise level no
/// trial had tried. Repeated steps still reach a σ_μ the data imply; a
/// single step cannot collapse it.
const SIGMA_STEP_MIN_SHARE: f64 = 0.5;

/// The least response of the simulated residual variance to σ_μ² a σ step
/// assumes: a step is then at most ten times the variance gap.
const MIN_SIGMA_RESPONSE: f64 = 0.1;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::effects::Form;

    /// Every form's parts carry the whole variance, each part is white or a
    /// whole-variance `ar1` (a `hold` is its own), and a noise that is not
    /// coloured is one white part.
    #[test]
    fn a_noise_s_parts_share_its_whole_variance() {
        for &form in ColourForm::ALL {
            for share in [0.0, 0.3, 1.0] {
                let colour = Some(ColouredFrictionNoise { form, correlation_time_s: 0.02, coloured_share: share });
                let parts = noise_parts(&colour);
                let total: f64 = parts.iter().map(|p| p.0).sum();
                assert!((total - 1.0).abs() < 1e-12, "{form:?} at {share}: {parts:?}");
                for (_, part) in &parts {
                    if let Some(p) = part.as_ref().filter(|p| p.form != ColourForm::Hold) {
                        assert!(p.form == ColourForm::Ar1 && p.coloured_share == 1.0, "{form:?}: {parts:?}");
                    }
                }
            }
        }
        assert_eq!(noise_parts(&None), vec![(1.0, None)]);
        let white = Some(ColouredFrictionNoise { form: ColourForm::Ar1, correlation_time_s: 0.0, coloured_share: 1.0 });
        assert_eq!(noise_parts(&white), vec![(1.0, None)]);
    }

    #[test]
    fn a_law_step_at_most_halves_sigma_and_otherwise_takes_the_newton_step() {
        let mut model = Model::default();
        model.friction.sigma = 0.03;
        let law = |sigma: f64| FrictionLaw {
            sigma,
            anchors_m_per_s: std::array::from_fn(|k| 0.01 * (k + 1) as f64),
            ..FrictionLaw::of(&model)
        };
        let gap = |simulated: f64| 0.02f64.powi(2) - simulated * simulated;
        // The simulated residual far above the measured one (a trial's
        // effect adds a residual of its own): the full step would end at
        // the floor, 0.1 × 0.02; it ends at half of 0.03.
        let mut m = model.clone();
        step_law(&mut m, &law(0.02), &law(0.1), gap(0.1), 1.0);
        assert!((m.friction.sigma - 0.015).abs() < 1e-12, "sigma {}", m.friction.sigma);
        // A moderate step down and a step up are the Newton step itself:
        // σ² + measured² − simulated².
        for simulated in [0.025, 0.01] {
            let mut m = model.clone();
            step_law(&mut m, &law(0.02), &law(simulated), gap(simulated), 1.0);
            let expected = (0.03f64.powi(2) + 0.02f64.powi(2) - simulated * simulated).sqrt();
            assert!((m.friction.sigma - expected).abs() < 1e-12, "simulated {simulated}: sigma {}", m.friction.sigma);
        }
    }
}

#[cfg(test)]
mod derived_tests {
    use super::*;
    use crate::diagnose::calibrate::calibrate_and_score;
    use crate::diagnose::derived::DerivedChannels;
    use crate::diagnose::derived::with_derived_channels;
    use crate::diagnose::score::Scope;
    use crate::measure::MeasurementSet;

    /// Records of `truth` (noise from `seed`) with the displacement alone,
    /// their other channels derived from it.
    fn x_alone(truth: &Model, seed: u64) -> (MeasurementSet, DerivedChannels) {
        let (derived_set, derived) =
            with_derived_channels(&crate::diagnose::synthetic::displacement_only_set(truth, seed));
        (derived_set.expect("derived"), derived)
    }

    fn settings() -> DiagnoseSettings {
        DiagnoseSettings { replicates: 8, warmup_cycles: 5, ..DiagnoseSettings::default() }
    }

    /// Through a derived friction force's filter the replicates' residual
    /// variance moves by a fraction of σ_μ² (measured once, with the law
    /// held), and σ_μ calibrated with that fraction comes back from half
    /// as much again as the truth's in the baseline's three steps.
    #[test]
    fn sigma_through_a_derived_force_is_stepped_by_the_filters_measured_response() {
        let truth = Model::paper_rig(&[]).expect("the paper rig");
        let (set, derived) = x_alone(&truth, 5);
        let data = Data::new(&set, derived).expect("data");
        let (engine, settings) = (Engine::cpu("test"), settings());
        let mut start = truth.clone();
        start.friction.sigma *= 1.5;
        let response = sigma_response(&engine, &start, &data, &settings).expect("response");
        assert!(response > MIN_SIGMA_RESPONSE && response < 0.8, "a fraction, not a bound: {response}");
        let (m, _, _) =
            calibrate_and_score(&start, &data, &settings, &engine, None, 0, Scope::Fitting).expect("calibrated");
        let off = m.friction.sigma / truth.friction.sigma - 1.0;
        assert!(off.abs() < 0.15, "sigma {} against the truth's {}", m.friction.sigma, truth.friction.sigma);
    }

    /// A noise correlated over many hold intervals passes the filter more
    /// than a white one of the same variance: its response is measured on
    /// its own (on the model the white one was measured on), and σ_μ of a
    /// truth whose noise is mostly coloured comes back from half as much
    /// again in the baseline's three steps, as a white one's does.
    #[test]
    fn a_coloured_noise_has_its_own_response_through_a_derived_force() {
        let mut truth = Model::paper_rig(&[]).expect("the paper rig");
        let white = truth.clone();
        truth.effects.coloured_friction_noise =
            Some(ColouredFrictionNoise { form: ColourForm::Ar1, correlation_time_s: 0.05, coloured_share: 0.8 });
        let (set, derived) = x_alone(&truth, 6);
        let data = Data::new(&set, derived).expect("data");
        let (engine, settings) = (Engine::cpu("test"), settings());
        let white_response = sigma_response(&engine, &white, &data, &settings).expect("white response");
        let coloured_response = sigma_response(&engine, &truth, &data, &settings).expect("coloured response");
        assert!(
            coloured_response > 1.5 * white_response,
            "coloured {coloured_response} against white {white_response}"
        );
        let mut start = truth.clone();
        start.friction.sigma *= 1.5;
        let (m, _, _) =
            calibrate_and_score(&start, &data, &settings, &engine, None, 0, Scope::Fitting).expect("calibrated");
        let off = m.friction.sigma / truth.friction.sigma - 1.0;
        assert!(off.abs() < 0.15, "sigma {} against the truth's {}", m.friction.sigma, truth.friction.sigma);
    }
}
