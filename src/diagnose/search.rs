//! Attribution and verdict.
//!
//! Each effect is screened by its signature ([`signature_excess`]): only
//! effects whose form-agnostic trace stands out of the noise are fitted.
//! Each form of a screened effect ([`Variant`]) is fitted by a coordinate
//! search, with the baseline's friction law recalibrated at every trial, so
//! an effect cannot win by shifting the baseline. The search runs on half
//! the replicates ([`search_replicates`]); the effect's best form is then
//! recalibrated and scored on all of them. Effects are added by
//! forward selection: the one that lowers the held-out gap most is kept if
//! it lowers both the held-out and the fitting gaps by more than their
//! noise and closes a real share of what is left of the gap
//! ([`MIN_LEADING_SHARE`]); the next is searched on top of it, and so on
//! (from the second effect on, the best candidate that passes, not only
//! the first by the held-out gap). An effect that
//! makes the response itself (peak amplitude, phase) worse where the fit
//! did not look, beyond that loss's noise, is not kept however much it
//! improves the features: it traded the prediction for the attribution. A
//! further effect (added on top of a named one) is held to the comparison's
//! own noise: it must not make that response worse at all beyond it, and
//! it must close more of the key gap than every other effect of its round
//! that keeps the response does, beyond that gap's noise ([`stands_out`]):
//! a fall that any effect would give is the leftover misfit of the forms
//! already in, not an attribution.

use std::collections::BTreeMap;

use crate::diagnose::calibrate::{calibrate_and_score, converge_law};
use crate::diagnose::candidates::{Context, NULL_HUBER, Param, Variant, bent, signature_excess, variants};
use crate::diagnose::data::Data;
use crate::diagnose::score::{HUBER_K, Scope, Score, add_heldout, count_of, gap_of, score};
use crate::diagnose::{Candidate, DiagnoseSettings, Unexplained};
use crate::engine::{Effect, Engine, Model};
use crate::error::{Error, Result};

/// An effect is fitted only when its signature stands this many noise units
/// above pure noise in the current model's scores (see
/// [`signature_excess`]); the largest few are fitted.
pub(crate) const SCREEN_EXCESS: f64 = 3.0;

/// At most this many effects are fitted per round (those with the largest
/// signature excess).
const SCREEN_MAX: usize = 3;

/// At most this many effects are named.
pub(crate) const MAX_EFFECTS: usize = 3;

/// Each effect must close at least this share of the key gap left above
/// the noise floor when it is added. For the leading effect that is the
/// baseline's explainable gap: a verdict explains a real share of the gap,
/// not a sliver of a calibration failure (below it the verdict is `none`
/// and the report lists the misfit). For a further effect it is what the
/// effects before it left: a second effect is judged against what there is
/// still to explain, not against a gap the first one already closed.
pub(crate) const MIN_LEADING_SHARE: f64 = 0.3;

/// A further effect that closes this share of what is left of the fitting
/// gap may close less than [`MIN_LEADING_SHARE`] of the held-out one (it
/// must still lower it beyond its noise; see [`fits_far_better`]).
const FIT_SHARE: f64 = 0.5;

/// The mean Huber loss of z-scores under pure noise with the spread known
/// (about 0.98, see [`crate::diagnose::score::HUBER_K`]): the lowest gap a
/// model can be expected to reach.
const HUBER_FLOOR: f64 = 0.98;

/// Moves per parameter in one direction in the coordinate search (of 1, 2,
/// 4, … steps: up to 7 steps away), besides the first probe of the other
/// direction and one move back from an overshoot.
const STEPS_PER_PARAM: usize = 3;

/// Prints one trial's gap and worst observables (`STICKSLIP_DEBUG=1`).
fn debug_trial(variant: &Variant, values: &[f64], trial: &Model, scores: &[Score], g: f64) {
    // The five largest |z| of the fitting (or held-out) units.
    let top = |heldout: bool| -> String {
        let mut w: Vec<&Score> = scores.iter().filter(|s| s.heldout == heldout).collect();
        w.sort_by(|a, b| b.z.abs().total_cmp(&a.z.abs()));
        w.iter()
            .take(5)
            .map(|s| format!("{}@{:.1}N {:+.1}", s.observable, s.normal_force_n, s.z))
            .collect::<Vec<_>>()
            .join("; ")
    };
    eprintln!(
        "{} [{}] {values:?}: a {:.4} b {:.4} c {:.2} d {:.4} sigma {:.4} gap {g:.2} ho {:.2} | {} || held out: {}",
        variant.effect,
        variant.form,
        trial.friction.a,
        trial.friction.b,
        trial.friction.c,
        trial.friction.d,
        trial.friction.sigma,
        gap_of(scores, true),
        top(false),
        top(true)
    );
}

/// One trial: the model with a variant's parameters, recalibrated.
struct Trial {
    values: Vec<f64>,
    model: Model,
    scores: Vec<Score>,
    gap_fit: f64,
}

/// Evaluates one set of parameter values on top of `base` (whose friction
/// law is the starting point of `law_steps` steps of its recalibration);
/// `None` when they give no valid model.
#[allow(clippy::too_many_arguments)]
fn evaluate(
    variant: &Variant,
    values: &[f64],
    base: &Model,
    law_steps: usize,
    slope: f64,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    engine: &Engine,
) -> Result<Option<Trial>> {
    let trial = (variant.apply)(base, values);
    if trial.validate().is_err() {
        return Ok(None);
    }
    // A trial whose parameters drive the oscillator out of range (friction
    // turned negative, say) is not a model of the data: it is passed over
    // like an invalid one instead of ending the diagnosis.
    let (model, scores, _) =
        match calibrate_and_score(&trial, data, settings, engine, Some(slope), law_steps, Scope::Fitting) {
            Err(Error::Diverged { point, message }) => {
                if std::env::var_os("STICKSLIP_DEBUG").is_some() {
                    eprintln!("{} [{}] {values:?}: diverged at {point}: {message}", variant.effect, variant.form);
                }
                return Ok(None);
            }
            other => other?,
        };
    let gap_fit = gap_of(&scores, false);
    if std::env::var_os("STICKSLIP_DEBUG").is_some() {
        debug_trial(variant, values, &model, &scores, gap_fit);
    }
    Ok(Some(Trial { values: values.to_vec(), model, scores, gap_fit }))
}

/// A point of a [`coordinate_search`]: its parameter values and the gap
/// it is judged by (lower is better).
trait SearchPoint {
    fn values(&self) -> &[f64];
    fn gap(&self) -> f64;
}

impl SearchPoint for Trial {
    fn values(&self) -> &[f64] {
        &self.values
    }

    fn gap(&self) -> f64 {
        self.gap_fit
    }
}

/// A coordinate search from `start`: each parameter in turn is stepped up
/// or down while that helps, by moves that double (at most
/// [`STEPS_PER_PARAM`] in one direction), then the first parameter once more
/// at half its step. `evaluate(best, values)` gives the point at `values`
/// starting from the current best (`None`: no valid model there); a move is
/// kept when it lowers the gap.
fn coordinate_search<T: SearchPoint>(
    params: &[Param],
    start: T,
    mut evaluate: impl FnMut(&T, &[f64]) -> Result<Option<T>>,
) -> Result<T> {
    let mut best = start;
    // Values already tried from the current best and rejected: a move
    // clamped at a bound can land on one again, and the same values on the
    // same best give the same point (the simulation is deterministic).
    let mut rejected: Vec<Vec<f64>> = Vec::new();
    let mut try_move = |best: &mut T, i: usize, k: f64| -> Result<bool> {
        let mut values = best.values().to_vec();
        values[i] = params[i].moved(values[i], k);
        if values[i] == best.values()[i] || rejected.contains(&values) {
            return Ok(false);
        }
        match evaluate(best, &values)? {
            Some(t) if t.gap() < best.gap() => {
                *best = t;
                rejected.clear();
                Ok(true)
            }
            _ => {
                rejected.push(values);
                Ok(false)
            }
        }
    };
    for i in 0..params.len() {
        let mut direction = 1.0;
        if !try_move(&mut best, i, direction)? {
            direction = -1.0;
            if !try_move(&mut best, i, direction)? {
                continue;
            }
        }
        // Then moves of 2, 4, … steps while they help, and one of half the
        // size that overshot: a start several steps off (a slope read from
        // a misfit that the effect itself distorts) is reached in a few
        // trials instead of being cut short while the gap still falls.
        let mut size = 1.0;
        let mut overshot = false;
        for _ in 1..STEPS_PER_PARAM {
            size *= 2.0;
            if !try_move(&mut best, i, direction * size)? {
                try_move(&mut best, i, direction * size / 2.0)?;
                overshot = true;
                break;
            }
        }
        // Every move helped, the last one the largest: the best may lie
        // between its ends as well as beyond, so a move back by half of it
        // is tried. Seed 15 set 11 of the benchmark (an exponential load
        // dependence): the slope went 0.0011 → 0.0036 → 0.018 per newton,
        // past the data's 0.0073, and the law carried along held it there.
        if !overshot && size > 1.0 {
            try_move(&mut best, i, -direction * size / 2.0)?;
        }
    }
    if !params.is_empty() && !try_move(&mut best, 0, 0.5)? {
        try_move(&mut best, 0, -0.5)?;
    }
    Ok(best)
}

/// Fits one variant on top of `base` by a [`coordinate_search`] on the
/// fitting gap from the data-driven start. The friction law is carried
/// from the best trial to the next (two recalibration steps at the start,
/// one per trial after), so over a search it converges to the law the data
/// imply *with* this effect instead of staying near the baseline's, which
/// the effect itself may have distorted. The search and the returned scores
/// use [`search_replicates`].
fn fit_variant(
    variant: &Variant,
    base: &Model,
    slope: f64,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    engine: &Engine,
) -> Result<Option<Trial>> {
    let search = DiagnoseSettings { replicates: search_replicates(settings.replicates), ..*settings };
    let settings = &search;
    let Some(start) = evaluate(variant, &variant.start(), base, 2, slope, data, settings, engine)? else {
        return Ok(None);
    };
    let mut best = coordinate_search(&variant.params, start, |best: &Trial, values: &[f64]| {
        evaluate(variant, values, &best.model, 1, slope, data, settings, engine)
    })?;
    best.scores = add_heldout(engine, &best.model, data, settings, best.scores)?;
    Ok(Some(best))
}

/// Replicates per condition in the coordinate search of a form's
/// parameters: half of the diagnosis's (at least 4, at most all). Trials
/// are compared with each other on the same noise paths, so halving the
/// replicates moves the search's choices little while halving its cost,
/// the bulk of a diagnosis. The forms of one effect are ranked on these
/// replicates too; the best form is then recalibrated and scored on all of
/// them before effects are compared.
fn search_replicates(replicates: u32) -> u32 {
    (replicates / 2).max(4).min(replicates)
}

/// The noise a fall of the mean Huber loss over `k` scores must beat:
/// 3·sqrt(2/k) (the noise of a mean of k values of about z²) plus 0.5 for
/// the replicate estimate of each z's spread.
pub(crate) fn gap_noise(k: usize) -> f64 {
    3.0 * (2.0 / k.max(1) as f64).sqrt() + 0.5
}

/// The calibrated baseline's scale of every response score, by (unit,
/// observable): the fixed yardstick of [`keeps_the_response`].
type Yardstick = BTreeMap<ScoreKey, f64>;

/// A score's (unit, observable).
type ScoreKey = (usize, crate::diagnose::observable::Observable);

fn yardstick(baseline_scores: &[Score]) -> Yardstick {
    baseline_scores.iter().filter(|s| s.observable.is_response()).map(|s| ((s.unit, s.observable), s.scale)).collect()
}

/// Mean Huber loss of z over the response observables
/// ([`crate::diagnose::observable::Observable::is_response`]) of the
/// held-out units where there are any (else the fitting ones), each z
/// measured in the calibrated baseline's scale, and how many there are.
///
/// The fixed scale matters: divided by its own replicates' spread, a model
/// that widens every distribution (a strongly coloured friction noise, say)
/// looks closer to the data everywhere while its mean and variance move
/// away from them.
fn response_gap(scores: &[Score], has_heldout: bool, yardstick: &Yardstick) -> (f64, usize) {
    let losses = response_losses(scores, has_heldout, yardstick);
    let k = losses.len();
    (if k == 0 { 0.0 } else { losses.iter().map(|(_, (loss, _))| loss).sum::<f64>() / k as f64 }, k)
}

/// The response scores of the held-out units where there are any (else
/// the fitting ones), in the scores' order, each by (unit, observable) with
/// its Huber loss in the baseline's yardstick and that loss's variance from
/// the simulated mean alone (the score's [`Score::simulated_share`] of its
/// scale², carried through the loss by its slope; see [`response_rise`]).
fn response_losses(scores: &[Score], has_heldout: bool, yardstick: &Yardstick) -> Vec<(ScoreKey, (f64, f64))> {
    scores
        .iter()
        .filter(|s| s.heldout == has_heldout && s.observable.is_response())
        .map(|s| {
            let y = yardstick.get(&(s.unit, s.observable)).copied().unwrap_or(s.scale);
            let u = s.z * s.scale / y;
            let slope = (2.0 * u).clamp(-2.0 * HUBER_K, 2.0 * HUBER_K);
            let variance = slope * slope * s.simulated_share * (s.scale / y).powi(2);
            ((s.unit, s.observable), (crate::diagnose::score::huber(u), variance))
        })
        .collect()
}

/// Whether `candidate` keeps the response where the fit did not look: its
/// response loss there rises above `current`'s by no more than three times
/// the noise of that rise. A set without response observables passes.
///
/// The bound: each z² is (bias + noise)² over a spread estimated from
/// `replicates` simulated records, so a mean R of k of them varies by about
/// sqrt((2 + 4R)/k) with the spread known, and by a further
/// sqrt(2/(replicates − 1))·R/sqrt(k) from the spread's estimate, for both
/// models. Measured in the baseline's fixed yardstick the spread's estimate
/// is shared by both losses, so this is far looser than the comparison's
/// own noise ([`response_rise`]; 3 sd ≈ 85 against ≈ 6 at a loss of 100).
/// It is kept, deliberately loose, for the leading effect only (see
/// [`further_keeps_the_response`]).
fn keeps_the_response(
    current: &[Score],
    candidate: &[Score],
    has_heldout: bool,
    replicates: u32,
    yardstick: &Yardstick,
) -> bool {
    let (before, k) = response_gap(current, has_heldout, yardstick);
    let (after, _) = response_gap(candidate, has_heldout, yardstick);
    if k == 0 {
        return true;
    }
    let spread_rel_var = 2.0 / f64::from(replicates.max(2) - 1);
    let variance = 2.0 * (spread_rel_var * before * before + 2.0 + 4.0 * before) / k as f64;
    after - before <= 3.0 * variance.sqrt()
}

/// The rise of the response loss from `current` to `candidate` on the same
/// units (held-out where there are any), in the baseline's yardstick, and
/// the standard deviation of that rise from the simulated means alone: both
/// models are compared with the same measured values, so only each
/// model's replicate mean adds noise (its variance is the score's
/// [`Score::simulated_share`] of its scale², carried through the Huber loss
/// by its slope). Replicates share their seeds between models, so this
/// overstates the noise, never understates it.
fn response_rise(current: &[Score], candidate: &[Score], has_heldout: bool, yardstick: &Yardstick) -> (f64, f64) {
    let picked = |scores: &[Score]| -> BTreeMap<ScoreKey, (f64, f64)> {
        response_losses(scores, has_heldout, yardstick).into_iter().collect()
    };
    let (before, after) = (picked(current), picked(candidate));
    let (mut rise, mut variance, mut k) = (0.0, 0.0, 0usize);
    for (key, (loss_b, var_b)) in &before {
        if let Some((loss_a, var_a)) = after.get(key) {
            rise += loss_a - loss_b;
            variance += var_a + var_b;
            k += 1;
        }
    }
    if k == 0 {
        return (0.0, 0.0);
    }
    (rise / k as f64, variance.sqrt() / k as f64)
}

/// Whether a further effect (one added on top of a named one) keeps the
/// response where the fit did not look: its response loss there rises above
/// `current`'s by no more than three standard deviations of that rise's
/// own noise ([`response_rise`]). A further effect is where a fit goes
/// after what the leading effect's form left over (a hysteresis in a form
/// no candidate has leaves skewed friction residuals, which a non-Gaussian
/// noise then "explains"); such an addition predicts the rig's response at
/// an unseen condition worse, which this refuses. The leading effect is
/// held to the looser [`keeps_the_response`]: its form may be imperfect,
/// and against a baseline that misfits everywhere the right effect in an
/// approximate form can still move the response a little the wrong way.
fn further_keeps_the_response(
    current: &[Score],
    candidate: &[Score],
    has_heldout: bool,
    yardstick: &Yardstick,
) -> bool {
    let (rise, sd) = response_rise(current, candidate, has_heldout, yardstick);
    rise <= 3.0 * sd
}

/// Whether `candidate` keeps the response where the fit did not look by
/// the rule of its place in the selection: [`keeps_the_response`] for the
/// leading effect (`leading`), [`further_keeps_the_response`] for a
/// further one.
fn keeps_the_response_as(
    leading: bool,
    current: &[Score],
    candidate: &[Score],
    has_heldout: bool,
    replicates: u32,
    ruler: &Yardstick,
) -> bool {
    if leading {
        keeps_the_response(current, candidate, has_heldout, replicates, ruler)
    } else {
        further_keeps_the_response(current, candidate, has_heldout, ruler)
    }
}

/// Whether a candidate taking the (fitting, key) gaps from `before` to
/// `after` lowers both by more than their `noise` and closes at least
/// [`MIN_LEADING_SHARE`] of what is left of the key gap above the noise
/// floor, or, where `exempt` (a further effect that repairs the held-out
/// response, [`repairs_the_response`], or fits far better,
/// [`fits_far_better`]), the first two alone.
fn closes_enough(before: (f64, f64), after: (f64, f64), noise: (f64, f64), exempt: bool) -> bool {
    let left = (before.1 - NULL_HUBER).max(1e-9);
    let fall = (before.0 - after.0, before.1 - after.1);
    fall.1 > noise.1 && fall.0 > noise.0 && (fall.1 / left >= MIN_LEADING_SHARE || exempt)
}

/// Whether a further effect takes the fitting gap from `before` to `after`
/// by at least [`FIT_SHARE`] of what is left of it above the noise floor.
/// The held-out load level lies between the fitted ones, where a law of
/// friction against load fitted to the outer levels adds least: at the
/// middle of two fitted loads a straight line gives the mean of their
/// friction, as a load-independent law fitted to both does. A load
/// dependence under a coloured noise (seed 17 set 15 of the blind
/// benchmark) took the fitting gap from 46.7 to 10.0 and the held-out one
/// only from 17.1 to 12.7 (28% of what was left, short of
/// [`MIN_LEADING_SHARE`]); named, the fitted model's error against the
/// generator's truth at the withheld level fell by 97% of the baseline's
/// instead of 43%.
fn fits_far_better(before: f64, after: f64) -> bool {
    before - after >= FIT_SHARE * (before - NULL_HUBER)
}

/// Whether a further effect closes a real share of what is left of the
/// response gap where the fit did not look: its response loss falls by more
/// than three standard deviations of that fall's noise ([`response_rise`])
/// and by at least [`MIN_LEADING_SHARE`] of the response loss above the
/// noise floor. The key gap counts every observable and the response few
/// of them, so an effect that the response needs (a load dependence under
/// a coloured noise that dominates the friction features) can close little
/// of the key gap; this admits it on the response alone, still only if it
/// lowers both gaps beyond their noise (see [`select`]).
fn repairs_the_response(current: &[Score], candidate: &[Score], has_heldout: bool, ruler: &Yardstick) -> bool {
    let (rise, sd) = response_rise(current, candidate, has_heldout, ruler);
    let (before, _) = response_gap(current, has_heldout, ruler);
    rise < -3.0 * sd && -rise >= MIN_LEADING_SHARE * (before - NULL_HUBER)
}

/// How a form's best trial ranks against the other forms of its effect
/// (lower is better): its key gap (held-out where there are held-out units,
/// else `gap_fit`) plus its response loss there in the baseline's
/// yardstick ([`response_gap`]). Between forms of one effect the
/// attribution is the same; what differs is how the fitted model predicts.
/// The key gap counts every observable and the response (peaks, phases) is
/// few of them, so the response is counted once more: a form that fits the
/// friction features a little better but leaves the response where the
/// baseline had it loses to one that predicts it (seed 13 set 4 of the
/// benchmark: a `lag` hysteresis with key gap 28.8 and the response moved
/// by +1.2 against a build-up form with 31.4 and −77).
fn form_rank(scores: &[Score], gap_fit: f64, has_heldout: bool, ruler: &Yardstick) -> f64 {
    let key = if has_heldout { gap_of(scores, true) } else { gap_fit };
    key + response_gap(scores, has_heldout, ruler).0
}

/// How a form's best trial ranks against the other forms of its effect
/// (lower is better): first whether the selection would refuse it for the
/// response it predicts where the fit did not look
/// ([`keeps_the_response_as`], against `base_scores`, the round's starting
/// model; `leading` for the first round), then [`form_rank`]. A form the
/// selection would refuse cannot stand for its effect while another form
/// would pass: the 18-run seed-21 set of normal-force harmonics with a
/// skewed outlier noise (a `mixture`, no candidate's form) chose the
/// symmetric heavy-tailed `tukey_h` for the noise, held-out key gap 7.8
/// against the skew form's 11.4 (from 72), but its response loss rose from
/// 2.7 to 5.0 (sd 0.34) against the skew's 2.8, and the selection then
/// refused the noise altogether.
fn form_order(
    leading: bool,
    base_scores: &[Score],
    trial: &Trial,
    has_heldout: bool,
    replicates: u32,
    ruler: &Yardstick,
) -> (bool, f64) {
    let keeps = keeps_the_response_as(leading, base_scores, &trial.scores, has_heldout, replicates, ruler);
    (!keeps, form_rank(&trial.scores, trial.gap_fit, has_heldout, ruler))
}

/// The effects to fit, largest signature excess first: those above
/// [`SCREEN_EXCESS`], at most [`SCREEN_MAX`] of them, and any that tie
/// with the last one kept. Effects whose signatures share an observable
/// tie exactly when it is their largest excess (a coloured noise and a
/// hysteresis both read the residual autocorrelation); which of them is
/// fitted must not be settled by the order of [`Effect::ALL`]. Seed 17 set
/// 15 of the blind benchmark (a load dependence and a coloured noise in
/// its withheld `multi_scale` form): the two stood at 437.0 behind a load
/// dependence and a stiction, only the hysteresis was fitted, and its
/// `lag` form stood in for the colour.
fn screen(mut excess: Vec<(Effect, f64)>) -> Vec<(Effect, f64)> {
    excess.retain(|(_, x)| *x > SCREEN_EXCESS);
    excess.sort_by(|a, b| b.1.total_cmp(&a.1));
    if let Some(&(_, cut)) = excess.get(SCREEN_MAX - 1) {
        excess.retain(|(_, x)| *x >= cut);
    }
    excess
}

/// The best candidate for each screened effect on top of `base`.
#[allow(clippy::too_many_arguments)]
fn round(
    base: &Model,
    base_scores: &[Score],
    named: &[Effect],
    slope: f64,
    ruler: &Yardstick,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    engine: &Engine,
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<Candidate>> {
    let (g0_fit, g0_ho) = (gap_of(base_scores, false), gap_of(base_scores, true));
    let fit_noise = gap_noise(count_of(base_scores, false));
    let excess: Vec<(Effect, f64)> =
        Effect::ALL.iter().filter(|e| !named.contains(e)).map(|&e| (e, signature_excess(e, base_scores))).collect();
    if std::env::var_os("STICKSLIP_DEBUG").is_some() {
        let all: Vec<String> = excess.iter().map(|(e, x)| format!("{e} {x:.1}")).collect();
        eprintln!("screen (after {named:?}): {}", all.join(", "));
    }
    let screened = screen(excess);
    let ctx = Context::new(data, base, base_scores, settings.warmup_cycles);
    let mut out = Vec::new();
    for (effect, excess) in screened {
        progress(&format!("trying {effect} (signature {excess:.1} noise units above the baseline)"));
        // Every form that fitted: its trial, name and parameters.
        let mut fitted: Vec<(Trial, &'static str, BTreeMap<String, f64>)> = Vec::new();
        let leading = named.is_empty();
        let rank = |t: &Trial| form_order(leading, base_scores, t, data.has_heldout(), settings.replicates, ruler);
        let mut forms: std::collections::VecDeque<Variant> = variants(effect, &ctx).into();
        while let Some(variant) = forms.pop_front() {
            let variant = &variant;
            if let Some(t) = fit_variant(variant, base, slope, data, settings, engine)? {
                // A form that fitted may be bent further (a slope that
                // steepens with load), searched from where it fitted.
                if g0_fit - t.gap_fit > fit_noise
                    && let Some(b) = bent(effect, variant.form, &t.values, &ctx)
                {
                    forms.push_back(b);
                }
                if std::env::var_os("STICKSLIP_DEBUG").is_some() {
                    eprintln!(
                        "form {effect} [{}] {:?}: fit {:.2} key {:.2} response {:.2} refused for it {} rank {:.2}",
                        variant.form,
                        t.values,
                        t.gap_fit,
                        gap_of(&t.scores, data.has_heldout()),
                        response_gap(&t.scores, data.has_heldout(), ruler).0,
                        rank(&t).0,
                        rank(&t).1
                    );
                }
                let parameters = variant.describe(&t.values);
                fitted.push((t, variant.form, parameters));
            }
        }
        // Best first; a stable sort keeps the search's order among ties.
        fitted.sort_by(|a, b| {
            let (ra, rb) = (rank(&a.0), rank(&b.0));
            ra.0.cmp(&rb.0).then(ra.1.total_cmp(&rb.1))
        });
        // The best form on every replicate. For a further effect, where
        // the selection would refuse it there for the response it
        // predicts, the next form in the order stands for the effect
        // instead if it would not (the search ranked the forms on half the
        // replicates; see [`form_order`]). The 18-run seed-23 set 7
        // (normal-force harmonics with a skewed `mixture` noise): the
        // symmetric `tukey_h` ranked first on half the replicates (key gap
        // 5.8 against the skew form's 9.6, from 66) and on all of them
        // raised the response loss 4.69 → 5.88 (sd 0.38), so the noise was
        // refused; the skew form keeps it (4.64) at key gap 6.4. A leading
        // effect keeps its first form: the looser rule it is held to
        // ([`keeps_the_response`]) would let a second form that fits far
        // worse lead instead (set 8: a coloured noise's second form, key
        // gap 55 where the first had 16, then led a wrong pair).
        let forms_tried = if leading { 1 } else { 2 };
        let chosen = first_kept(fitted, forms_tried, |(t, form, parameters)| {
            let Some(t) = on_every_replicate(t, slope, data, settings, engine)? else { return Ok(None) };
            let keeps =
                keeps_the_response_as(leading, base_scores, &t.scores, data.has_heldout(), settings.replicates, ruler);
            if std::env::var_os("STICKSLIP_DEBUG").is_some() {
                eprintln!("form {effect} [{form}] on every replicate: refused for it {}", !keeps);
            }
            Ok(Some(((t, form, parameters), keeps)))
        })?;
        let Some((t, form, parameters)) = chosen else { continue };
        let gap_heldout = gap_of(&t.scores, true);
        let mut worst: Vec<&Score> = t.scores.iter().collect();
        worst.sort_by(|a, b| b.z.abs().total_cmp(&a.z.abs()));
        out.push(Candidate {
            effect,
            form,
            signature_excess: excess,
            gap_fit: t.gap_fit,
            gap_heldout,
            shrink: if g0_fit > 0.0 { (g0_fit - t.gap_fit) / g0_fit } else { 0.0 },
            heldout_shrink: (data.has_heldout() && g0_ho > 0.0).then(|| (g0_ho - gap_heldout) / g0_ho),
            parameters,
            unexplained: worst
                .iter()
                .take(5)
                .map(|s| Unexplained {
                    observable: s.observable,
                    excitation_frequency_hz: s.excitation_frequency_hz,
                    normal_force_n: s.normal_force_n,
                    z: s.z,
                })
                .collect(),
            model: t.model,
            scores: t.scores,
        });
    }
    rank_effects(&mut out, (g0_fit, if data.has_heldout() { g0_ho } else { g0_fit }), data.has_heldout(), ruler);
    Ok(out)
}

/// Of the first `tries` of `ranked` (best first), judged in turn by
/// `judge` (the item as judged and whether it is kept; `None`: it could not
/// be judged), the first one kept, else the first one judged.
fn first_kept<T>(
    ranked: Vec<T>,
    tries: usize,
    mut judge: impl FnMut(T) -> Result<Option<(T, bool)>>,
) -> Result<Option<T>> {
    let mut first = None;
    for item in ranked.into_iter().take(tries) {
        match judge(item)? {
            Some((judged, true)) => return Ok(Some(judged)),
            Some((judged, false)) if first.is_none() => first = Some(judged),
            _ => {}
        }
    }
    Ok(first)
}

/// A form's best trial on every replicate: one more step of the law (the
/// extra replicates' law differs from the search's by their sampling
/// noise), then the law carried to where this effect's data imply it, so
/// the effect is compared (and the next round searched) from a law that
/// has stopped moving. `None` where the model diverges.
fn on_every_replicate(
    t: Trial,
    slope: f64,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    engine: &Engine,
) -> Result<Option<Trial>> {
    let (model, scores, _) = match calibrate_and_score(&t.model, data, settings, engine, Some(slope), 1, Scope::Fitting)
    {
        Err(Error::Diverged { .. }) => return Ok(None),
        other => other?,
    };
    let (model, scores) = converge_law(model, scores, data, settings, engine)?;
    let (model, scores) = keep_the_better_law(model, scores, &t.model, data, settings, engine)?;
    Ok(Some(Trial { gap_fit: gap_of(&scores, false), values: t.values, model, scores }))
}

/// The round's best form with its law stepped on every replicate and
/// carried to convergence (`converged`, scored on every unit), unless it
/// ends fitting worse, beyond the gap's noise, than the search's law
/// (`searched`) scored on the same replicates: then the searched law.
///
/// Summary sets too, where the step is the level's and the noise's solve
/// on the table: on the phase-only load dependence of seed 14 the search
/// found the data's slope (0.0100 per newton against the truth's 0.0099,
/// key gap 27.5 from 145 on half the replicates), and the step on every
/// replicate moved the level a until the fitting gap went 52 → 117; the
/// key gap then fell only to 122 and the verdict was `none`. Keeping the
/// searched law named it (key gap 62). The paper's Figure 8 diagnosis is
/// unchanged by it.
///
/// A law step reads the measured law against the simulated one as if the
/// trial's effect had the data's form. Where it has another (the 18-run
/// seed-21 set hides a friction memory in the withheld `rational` form),
/// the effect's structured residual moves the law the wrong way: that
/// one step took the best memory form's fitting gap from 70 to 117, no
/// later step brought it back, and the verdict was `none`. The comparison
/// is made after convergence: on two of seed 11's sets the first step
/// raised the gap beyond its noise and later steps took it lower than the
/// searched law's (keeping the searched law there added a spurious second
/// effect and cut a confidence from 0.97 to 0.88).
fn keep_the_better_law(
    converged: Model,
    converged_scores: Vec<Score>,
    searched: &Model,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    engine: &Engine,
) -> Result<(Model, Vec<Score>)> {
    let searched_scores = match score(engine, searched, data, settings, Scope::Fitting) {
        Err(Error::Diverged { .. }) => return Ok((converged, converged_scores)),
        other => other?,
    };
    let (after, before, k) =
        (gap_of(&converged_scores, false), gap_of(&searched_scores, false), count_of(&converged_scores, false));
    Ok(if step_made_it_worse(after, before, k) {
        let searched_scores = add_heldout(engine, searched, data, settings, searched_scores)?;
        (searched.clone(), searched_scores)
    } else {
        (converged, converged_scores)
    })
}

/// Whether the stepped law's fitting gap `stepped` stands above the
/// unstepped law's `searched`, over `k` fitting scores, by more than the
/// gap's noise.
fn step_made_it_worse(stepped: f64, searched: f64, k: usize) -> bool {
    stepped - searched > gap_noise(k)
}

/// How a candidate ranks against the other effects of its round where
/// their key gaps tie ([`rank_effects`]; lower is better): like its forms
/// ([`form_rank`]), its key gap plus its response loss where the fit did
/// not look.
fn effect_rank(c: &Candidate, has_heldout: bool, ruler: &Yardstick) -> f64 {
    form_rank(&c.scores, c.gap_fit, has_heldout, ruler)
}

/// The candidate's key gap: held-out where there are held-out units.
pub(crate) fn key_gap(c: &Candidate, has_heldout: bool) -> f64 {
    if has_heldout { c.gap_heldout } else { c.gap_fit }
}

/// Key gaps within this share of the best candidate's fall of the key gap
/// (from `key_before`) tie.
const RANK_TIE_SHARE: f64 = 0.1;

/// Orders a round's candidates best first: by key gap, except that those
/// that tie with the best one are ordered among themselves by
/// [`effect_rank`]. A candidate ties when its key gap is within
/// [`RANK_TIE_SHARE`] of the best one's fall of the key gap (from
/// `before`'s key gap), or when, with held-out units, it closes a larger
/// share of the fitting gap than the best one by more than the share of the
/// held-out gap it closes less: neither is then the better fit, and which
/// one predicts the response decides (the 18-run seed-22 set 8, a load
/// dependence under a coloured noise: a hysteresis led with held-out gap
/// 148 against a load dependence's 164, from 245, while it left the
/// fitting gap at 389 against 135, from 889, and the held-out response at
/// 711 against 609). Two effects that fit the features about equally well
/// (a stiction released over a slip length and a friction that lags its
/// law look alike in μ near breakaway) are told apart the same way: on the
/// benchmark's seed 15 set 9, a hysteresis with key gap 27.4 and a
/// stiction with 29.1, from 69.5, left response losses of 23.1 and 12.8
/// (from 41.3); the truth was a stiction. Beyond a tie the key gap alone
/// decides: the leading one of two effects may not predict the response
/// by itself (seed 11 set 15: a coloured noise that takes the key gap
/// from 179 to 13 needs the load dependence beside it for the response),
/// and an effect that closes far less of the gap is not a better
/// attribution because its one model happens to predict the peaks.
fn rank_effects(candidates: &mut [Candidate], before: (f64, f64), has_heldout: bool, ruler: &Yardstick) {
    let (fit_before, key_before) = before;
    candidates.sort_by(|a, b| key_gap(a, has_heldout).total_cmp(&key_gap(b, has_heldout)));
    let Some((best_key, best_fit)) = candidates.first().map(|c| (key_gap(c, has_heldout), c.gap_fit)) else {
        return;
    };
    let tie = RANK_TIE_SHARE * (key_before - best_key).max(0.0);
    let ties = |c: &Candidate| {
        let behind = key_gap(c, has_heldout) - best_key;
        let ahead_in_fit = best_fit - c.gap_fit;
        behind <= tie || (has_heldout && ahead_in_fit / fit_before.max(1e-9) > behind / key_before.max(1e-9))
    };
    // The tied ones first (a stable sort keeps the key order elsewhere),
    // ordered among themselves by their rank.
    candidates.sort_by_key(|c| !ties(c));
    let tied = candidates.iter().take_while(|c| ties(c)).count();
    candidates[..tied]
        .sort_by(|a, b| effect_rank(a, has_heldout, ruler).total_cmp(&effect_rank(b, has_heldout, ruler)));
}

/// One step of the forward selection that was kept.
#[derive(Clone, Debug)]
pub(crate) struct Step {
    pub(crate) candidate: Candidate,
    /// The gaps (fitting, key) before this effect was added; the key gap is
    /// the held-out one where there are held-out units, else the fitting one.
    pub(crate) before: (f64, f64),
    /// The key gap after it was added.
    pub(crate) after_key: f64,
    /// How far the best rival effect of the same round stays behind it, as
    /// a share of how far it moved things from the model it was added to
    /// (that model standing in for the rival when there was none), –: the
    /// larger of this share in the key gap and in [`effect_rank`] (a rival
    /// that fits as well but predicts the response far worse is as far
    /// behind as one that fits far worse).
    pub(crate) separation: f64,
}

/// What the forward selection found.
pub(crate) struct Selection {
    pub(crate) steps: Vec<Step>,
    /// Every candidate of the first round, best first.
    pub(crate) first_round: Vec<Candidate>,
    pub(crate) noise_fit: f64,
    pub(crate) noise_heldout: f64,
}

/// Forward selection from the calibrated baseline.
pub(crate) fn select(
    baseline: &Model,
    baseline_scores: &[Score],
    slope: f64,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    engine: &Engine,
    progress: &mut dyn FnMut(&str),
) -> Result<Selection> {
    let has_heldout = data.has_heldout();
    let noise_fit = gap_noise(count_of(baseline_scores, false));
    let noise_heldout = gap_noise(count_of(baseline_scores, has_heldout));
    let key_of = |scores: &[Score]| gap_of(scores, has_heldout);
    let ruler = yardstick(baseline_scores);
    let mut steps: Vec<Step> = Vec::new();
    let mut first_round = Vec::new();
    let (mut model, mut scores) = (baseline.clone(), baseline_scores.to_vec());
    while steps.len() < MAX_EFFECTS {
        let (g_fit, g_key) = (gap_of(&scores, false), key_of(&scores));
        // No effect can pass the gate below when the key gap is already
        // within its noise of the floor that even the true model only
        // reaches in expectation: skip the search.
        if g_key - HUBER_FLOOR <= noise_heldout {
            break;
        }
        let named: Vec<Effect> = steps.iter().map(|s| s.candidate.effect).collect();
        let candidates = round(&model, &scores, &named, slope, &ruler, data, settings, engine, progress)?;
        if steps.is_empty() {
            first_round = candidates.clone();
        }
        let key = |c: &Candidate| key_gap(c, has_heldout);
        if std::env::var_os("STICKSLIP_DEBUG").is_some() {
            for c in &candidates {
                let (before, k) = response_gap(&scores, has_heldout, &ruler);
                let (rise, rise_sd) = response_rise(&scores, &c.scores, has_heldout, &ruler);
                eprintln!(
                    "round {}: {} key {:.2} (from {g_key:.2}) fit {:.2} response {before:.2} -> {:.2} over {k} (rise {rise:+.2}, its noise sd {rise_sd:.2})",
                    steps.len(),
                    c.effect,
                    key(c),
                    c.gap_fit,
                    response_gap(&c.scores, has_heldout, &ruler).0,
                );
            }
        }
        // The best candidate that does not worsen the response where the
        // fit did not look (see the module's documentation) and that
        // lowers both gaps beyond their noise by a real share of what is
        // left (or, for a further effect, repairs the response or fits far
        // better); a further effect must also close more of the key gap
        // than its rivals ([`stands_out`]). For the leading effect only the
        // best is considered: when it fails, the verdict is `none`, not a
        // worse-fitting effect. A further effect
        // is the best one that passes: a rival that fits the held-out units
        // better but the fitting ones worse (it trades one for the other)
        // does not end the search.
        let leading = steps.is_empty();
        let keeps = |c: &Candidate| {
            keeps_the_response_as(leading, &scores, &c.scores, has_heldout, settings.replicates, &ruler)
        };
        let repairs = |c: &Candidate| repairs_the_response(&scores, &c.scores, has_heldout, &ruler);
        let passes = |c: &Candidate| {
            let exempt = !leading && (repairs(c) || fits_far_better(g_fit, c.gap_fit));
            closes_enough((g_fit, g_key), (c.gap_fit, key(c)), (noise_fit, noise_heldout), exempt)
        };
        let best = if leading {
            candidates.iter().find(|c| keeps(c)).filter(|c| passes(c))
        } else {
            candidates.iter().find(|c| {
                keeps(c) && passes(c) && stands_out(c, &candidates, &keeps, &repairs, g_key, has_heldout, noise_heldout)
            })
        };
        let step_of = |best: &Candidate| Step {
            candidate: best.clone(),
            before: (g_fit, g_key),
            after_key: key(best),
            separation: separation(best, &candidates, &keeps, &scores, has_heldout, &ruler),
        };
        if let Some(best) = best {
            let step = step_of(best);
            (model, scores) = (best.model.clone(), best.scores.clone());
            steps.push(step);
            continue;
        }
        // No leading effect passed. One that fell short only of the share
        // of the key gap, while it predicts the response better, may need
        // a second effect beside it: look one effect ahead of it (see
        // [`pair_ahead`]).
        if !leading {
            break;
        }
        let ahead = |c: &&Candidate| worth_looking_ahead(&scores, c, has_heldout, settings.replicates, &ruler);
        let Some(first) = candidates.iter().find(ahead) else {
            break;
        };
        let Some(second) = pair_ahead(first, baseline_scores, &ruler, slope, data, settings, engine, progress)? else {
            break;
        };
        let first = step_of(first);
        (model, scores) = (second.candidate.model.clone(), second.candidate.scores.clone());
        steps.extend([first, second]);
    }
    Ok(Selection { steps, first_round, noise_fit, noise_heldout })
}

/// Whether a further effect `c` lowers the key gap (from `g_key`) by more
/// than any other effect of its round that `keeps` the response does,
/// beyond the key gap's `noise` (a rival the selection would refuse for
/// the response it predicts is no alternative).
/// Once the leading effect is in, what is left is often the misfit of its
/// form (an effect in a form no candidate has): any further effect closes
/// some of it by its flexibility alone, and the one that closes a little
/// more is no attribution. Seed 16 set 16 of the blind benchmark (a
/// hysteresis in the withheld `rational` form and normal-force harmonics):
/// on top of both, a coloured noise, a non-Gaussian noise and a load
/// dependence took the key gap from 5.37 to 3.45, 4.09 and 4.14, and the
/// coloured noise was named as a third effect. A real further effect
/// stands out of its rivals: the same set's hysteresis 5.4 from 61.6
/// against 35.3 and 47.2; a load dependence under a coloured noise (seed
/// 17 set 15) 12.7 from 17.1 against 17.5 and 18.8. Nor is a rival that
/// leaves the response where it was an alternative to an effect that
/// `repairs` it ([`repairs_the_response`]): seed 32 set 15 (a load
/// dependence under a coloured noise, the noise named first), the load
/// dependence took the key gap from 28.2 to 20.4 and the response loss
/// from 668 to 187 (sd 23), a stiction the key gap to 19.8 and the
/// response to 650 (sd 21), and the load dependence was not named.
fn stands_out(
    c: &Candidate,
    candidates: &[Candidate],
    keeps: &dyn Fn(&Candidate) -> bool,
    repairs: &dyn Fn(&Candidate) -> bool,
    g_key: f64,
    has_heldout: bool,
    noise: f64,
) -> bool {
    let fall = |c: &Candidate| g_key - key_gap(c, has_heldout);
    let needs_repair = repairs(c);
    let rival = candidates
        .iter()
        .filter(|r| r.effect != c.effect && keeps(r) && (!needs_repair || repairs(r)))
        .map(fall)
        .fold(0.0, f64::max);
    fall(c) - rival > noise
}

/// How far the best rival of `best` among a round's `candidates` (one of
/// another effect that `keeps` the response too) stays behind it, as a
/// share of how far `best` moved things from `current` (which stands in
/// for the rival when there is none): the larger of this share in the key
/// gap and in [`effect_rank`] ([`Step::separation`]).
fn separation(
    best: &Candidate,
    candidates: &[Candidate],
    keeps: &dyn Fn(&Candidate) -> bool,
    current: &[Score],
    has_heldout: bool,
    ruler: &Yardstick,
) -> f64 {
    let key = |c: &Candidate| key_gap(c, has_heldout);
    let rank = |c: &Candidate| effect_rank(c, has_heldout, ruler);
    let (g_fit, g_key) = (gap_of(current, false), gap_of(current, has_heldout));
    let rank_before = form_rank(current, g_fit, has_heldout, ruler);
    let runner_up = candidates.iter().find(|c| c.effect != best.effect && keeps(c));
    let behind = |of: &dyn Fn(&Candidate) -> f64, before: f64| {
        (runner_up.map_or(before, of) - of(best)) / (before - of(best)).max(1e-9)
    };
    behind(&key, g_key).max(behind(&rank, rank_before)).clamp(0.0, 1.0)
}

/// Whether a leading candidate that was not named is worth a look one
/// effect ahead ([`pair_ahead`]): it keeps the response where the fit did
/// not look ([`keeps_the_response`]), lowers both gaps from `current`'s
/// beyond their noise (short of the share a leading effect must close),
/// and predicts that response better, beyond three standard deviations of
/// the difference's noise ([`response_rise`]).
fn worth_looking_ahead(
    current: &[Score],
    c: &Candidate,
    has_heldout: bool,
    replicates: u32,
    ruler: &Yardstick,
) -> bool {
    let before = (gap_of(current, false), gap_of(current, has_heldout));
    let noise = (gap_noise(count_of(current, false)), gap_noise(count_of(current, has_heldout)));
    let (rise, sd) = response_rise(current, &c.scores, has_heldout, ruler);
    keeps_the_response(current, &c.scores, has_heldout, replicates, ruler)
        && closes_enough(before, (c.gap_fit, key_gap(c, has_heldout)), noise, true)
        && rise < -3.0 * sd
}

/// Whether `second`, searched on top of `first` ([`pair_ahead`]), makes a
/// pair with it: as a further effect it keeps the response
/// ([`further_keeps_the_response`]) and lowers both gaps beyond their noise
/// by a real share of what `first` left, or repairs the response
/// ([`closes_enough`], [`repairs_the_response`]); and the two together
/// close what a leading effect must of the calibrated baseline's
/// (`baseline_scores`) gaps and predict the response better than it beyond
/// three standard deviations of the difference's noise.
fn pair_passes(
    baseline_scores: &[Score],
    first: &Candidate,
    second: &Candidate,
    has_heldout: bool,
    ruler: &Yardstick,
) -> bool {
    let gaps = |c: &Candidate| (c.gap_fit, key_gap(c, has_heldout));
    let baseline = (gap_of(baseline_scores, false), gap_of(baseline_scores, has_heldout));
    // Every gap here counts the same scores.
    let noise = (gap_noise(count_of(baseline_scores, false)), gap_noise(count_of(baseline_scores, has_heldout)));
    let repairs = repairs_the_response(&first.scores, &second.scores, has_heldout, ruler);
    let (rise, sd) = response_rise(baseline_scores, &second.scores, has_heldout, ruler);
    further_keeps_the_response(&first.scores, &second.scores, has_heldout, ruler)
        && closes_enough(gaps(first), gaps(second), noise, repairs)
        && closes_enough(baseline, gaps(second), noise, false)
        && rise < -3.0 * sd
}

/// One effect looked ahead of a leading candidate, `first`, that was not
/// named alone but is [`worth_looking_ahead`]: the next round is searched
/// on top of it, and its best effect that makes a pair with it
/// ([`pair_passes`]) is returned as the second step.
///
/// Forward selection adds one effect at a time and so misses two effects
/// of which the one that explains most of the features fakes the other:
/// the 18-run seed-23 set 8 (a strong load dependence under a moderate
/// coloured noise) had a coloured noise at the search's longest
/// correlation time (0.83 s, where the truth's parts are 3–53 ms) take the
/// held-out key gap from 213 to 16 by widening every simulated
/// distribution, while the response loss, in the baseline's fixed scale,
/// rose from 689 to 1029; the load dependence lowered the response to 563
/// but closed only 19% of the key gap, so the verdict was `none`. Searched
/// on top of the load dependence, the noise is fitted where the load
/// misfit no longer pulls it: key gap 173 → 3.6, response 563 → 50 (689
/// for the baseline), truth shrink at the withheld load 0.99.
#[allow(clippy::too_many_arguments)]
fn pair_ahead(
    first: &Candidate,
    baseline_scores: &[Score],
    ruler: &Yardstick,
    slope: f64,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    engine: &Engine,
    progress: &mut dyn FnMut(&str),
) -> Result<Option<Step>> {
    let has_heldout = data.has_heldout();
    let current = &first.scores;
    let before = (first.gap_fit, key_gap(first, has_heldout));
    progress(&format!("{} closed too little of the gap alone; looking one effect ahead of it", first.effect));
    let candidates = round(&first.model, current, &[first.effect], slope, ruler, data, settings, engine, progress)?;
    let keeps = |c: &Candidate| further_keeps_the_response(current, &c.scores, has_heldout, ruler);
    let passes = |c: &Candidate| pair_passes(baseline_scores, first, c, has_heldout, ruler);
    if std::env::var_os("STICKSLIP_DEBUG").is_some() {
        for c in &candidates {
            let (rise, sd) = response_rise(baseline_scores, &c.scores, has_heldout, ruler);
            eprintln!(
                "ahead of {}: {} key {:.2} (from {:.2}) fit {:.2} (from {:.2}) response against the baseline {rise:+.2} (sd {sd:.2}) passes {}",
                first.effect,
                c.effect,
                key_gap(c, has_heldout),
                before.1,
                c.gap_fit,
                before.0,
                passes(c)
            );
        }
    }
    Ok(candidates.iter().find(|c| passes(c)).map(|second| Step {
        candidate: second.clone(),
        before,
        after_key: key_gap(second, has_heldout),
        separation: separation(second, &candidates, &keeps, current, has_heldout, ruler),
    }))
}

/// What each named effect carries of the fitted model's response, in the
/// steps' order ([`response_weights`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ResponseWeight {
    /// How far the simulated response statistics at the fitting units move
    /// when the effect alone is taken out of the fitted model
    /// ([`response_move`]): a mean squared move in spreads, –.
    pub(crate) moved: f64,
    /// The standard deviation of `moved`, –.
    pub(crate) moved_sd: f64,
    /// How much the response loss at the held-out units rises without the
    /// effect, and that rise's standard deviation ([`response_rise`], in
    /// the calibrated baseline's yardstick; –); `None` without held-out
    /// units.
    pub(crate) heldout_rise: Option<(f64, f64)>,
}

/// What each named effect carries of the fitted model's response: how far
/// the simulated response statistics (peak and phase means and variances)
/// at the fitting units move when that effect alone is taken out of the
/// fitted model, nothing else changed ([`response_move`]), and how much the
/// response loss at the held-out units rises then ([`response_rise`]), in
/// the steps' order. `None` for an effect without which the model does not
/// run. Empty for fewer than two effects: there is nothing to weigh.
///
/// The move is weighed at the fitting units, not the held-out ones: an
/// effect is weighed where the fit saw it act. A load dependence is fitted
/// about the data's mean load, which is the held-out interior load level,
/// so taking it out moves nothing there however much the friction changes
/// across the loads; on the blind benchmark's load dependence under a
/// coloured noise the held-out response then kept the coloured noise first
/// on seeds 15 and 26 (its removal raised the held-out loss 229 ± 4
/// against the load dependence's 3 ± 6 on seed 26), while at the fitting
/// units the load dependence moved the response 47.9 against 34.1. The
/// held-out rise says whether the response where the fit did not look
/// wants the effect at all ([`response_leader`]).
pub(crate) fn response_weights(
    steps: &[Step],
    baseline_scores: &[Score],
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    engine: &Engine,
) -> Result<Vec<Option<ResponseWeight>>> {
    let Some(last) = steps.last().filter(|_| steps.len() >= 2) else { return Ok(Vec::new()) };
    let ruler = yardstick(baseline_scores);
    let has_heldout = data.has_heldout();
    let scope = if has_heldout { Scope::All } else { Scope::Fitting };
    let fitted = score(engine, &last.candidate.model, data, settings, scope)?;
    steps
        .iter()
        .map(|s| {
            let mut without = last.candidate.model.clone();
            without.effects.remove(s.candidate.effect);
            match score(engine, &without, data, settings, scope) {
                Ok(scores) => {
                    let (moved, moved_sd) = response_move(&fitted, &scores);
                    let heldout_rise = has_heldout.then(|| response_rise(&fitted, &scores, true, &ruler));
                    Ok(Some(ResponseWeight { moved, moved_sd, heldout_rise }))
                }
                Err(Error::Diverged { .. }) => Ok(None),
                Err(e) => Err(e),
            }
        })
        .collect()
}

/// The mean over the fitting units' response observables of
/// ((simulated without − simulated with) / spread)², the spread being the
/// `fitted` score's and a phase's move taken on the circle (as the scores'
/// comparison takes its differences: −179° to 179° is a move of 2°, not
/// 358°), and the standard deviation of that mean from the simulated
/// means' own noise: each move δ is seen as δ + e with e of
/// variance at most 2s (s the simulated mean's share of the spread², for
/// each model; less, as the two share their replicates' seeds), so each
/// squared move varies by sqrt(8 s δ² + 8 s²). Unitless; (0, 0) where no
/// response observable is scored.
pub(crate) fn response_move(fitted: &[Score], without: &[Score]) -> (f64, f64) {
    let moved: BTreeMap<ScoreKey, f64> = without
        .iter()
        .filter(|s| !s.heldout && s.observable.is_response())
        .map(|s| ((s.unit, s.observable), s.simulated))
        .collect();
    let (mut sum, mut variance, mut k) = (0.0, 0.0, 0usize);
    for s in fitted.iter().filter(|s| !s.heldout && s.observable.is_response() && s.scale > 0.0) {
        let Some(&other) = moved.get(&(s.unit, s.observable)) else { continue };
        let move_by = if s.observable.is_angle_deg() {
            crate::engine::reduce::wrap_angle((other - s.simulated).to_radians()).to_degrees()
        } else {
            other - s.simulated
        };
        let square = (move_by / s.scale).powi(2);
        if !square.is_finite() {
            continue;
        }
        let share = s.simulated_share;
        sum += square;
        variance += 8.0 * share * square + 8.0 * share * share;
        k += 1;
    }
    if k == 0 { (0.0, 0.0) } else { (sum / k as f64, variance.sqrt() / k as f64) }
}

/// How many standard deviations of the difference another effect's
/// response weight must exceed the first added one's by to lead
/// ([`response_leader`]). The standard deviation is that of
/// [`response_move`], which overstates the noise (the two models compared
/// share their replicates' seeds), so one of them is already a real
/// difference.
const RESPONSE_LEAD_SDS: f64 = 1.0;

/// The least move of the response ([`ResponseWeight::moved`], a mean
/// squared move in spreads) with which another effect can lead: below one
/// spread of the comparison at each condition, one measured run could not
/// tell the model with the effect from the model without it. On seed 29
/// set 2 of the blind benchmark (a non-Gaussian noise, and a spurious
/// coloured noise added after it) the two moved the response 0.46 and
/// 0.85: neither shapes it.
const MIN_LEADING_MOVE: f64 = 1.0;

/// Which of several named effects leads, by index into the steps: the
/// first added (it closed the most of the key gap) unless another one's
/// removal moves the fitted model's response more, by more than
/// [`RESPONSE_LEAD_SDS`] standard deviations of the difference and by at
/// least [`MIN_LEADING_MOVE`], and the response where the fit did not look
/// does not refute it: its removal must not lower the held-out response
/// loss by more than [`RESPONSE_LEAD_SDS`] standard deviations (seed 29
/// set 2: without the spurious coloured noise the held-out loss fell by
/// 1.58 ± 0.68, without the true non-Gaussian one it rose by 2.94 ± 0.97).
///
/// The key gap counts every observable, and some effects are seen by many
/// of them with little noise: a normal-force harmonic of a tenth of N0 is
/// plain in the normal-force channel and closes most of the key gap, while
/// a hysteresis beside it is what moves the peaks (seed 11 set 16 of the
/// benchmark: taking the harmonics out moves the fitting units' response
/// by 74 squared spreads, the hysteresis by 2 359). And the key gap is
/// held out at an interior load, where a load dependence shows least (seed
/// 26 set 15: a coloured noise closed it from 109 to 8 first; at the
/// fitting units the load dependence moves the response 48, the noise 34).
/// What a researcher asks of the leading effect is what shapes the
/// frequency response, so where the response tells them apart it decides.
pub(crate) fn response_leader(weights: &[Option<ResponseWeight>]) -> usize {
    let Some(Some(first)) = weights.first() else { return 0 };
    let (mut lead, mut most) = (0, first.moved);
    for (i, w) in weights.iter().enumerate().skip(1) {
        let Some(w) = w else { continue };
        let beyond_noise = w.moved - first.moved > RESPONSE_LEAD_SDS * first.moved_sd.hypot(w.moved_sd);
        let not_refuted = w.heldout_rise.is_none_or(|(rise, sd)| rise >= -RESPONSE_LEAD_SDS * sd);
        if w.moved > most && w.moved >= MIN_LEADING_MOVE && beyond_noise && not_refuted {
            (lead, most) = (i, w.moved);
        }
    }
    lead
}

/// The confidence in a kept step, from three things that must all hold for
/// an attribution to be right: its fall of the key gap beats the noise
/// (`margin`, in noise thresholds), it explains much of the baseline's
/// explainable gap (`share`), and it beats the best rival effect by much of
/// its own move of the rank ([`Step::separation`]: a rival that explains
/// and predicts nearly as much means the data cannot tell them apart). The verdict's reliability on the blind
/// benchmark is printed as a table beside it.
pub(crate) fn confidence(step: &Step, noise: f64, explainable: f64) -> f64 {
    let fallen = step.before.1 - step.after_key;
    let margin = (fallen / noise).max(0.0);
    let share = (fallen / explainable.max(1e-9)).clamp(0.0, 1.0);
    let separation = step.separation;
    let strength = 1.0 - (-(margin - 1.0).max(0.0) / 2.0).exp();
    (strength * (share * separation).sqrt()).clamp(0.0, 0.99)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::observable::Observable;

    /// A held-out score of `observable` at `unit` with z = `z` and scale 1.
    fn score(unit: usize, observable: Observable, z: f64) -> Score {
        crate::diagnose::score::test_score(unit, observable, z, true)
    }

    /// A round's candidate for `effect` with fitting gap `gap_fit` and the
    /// (held-out) `scores`.
    fn test_candidate(effect: Effect, gap_fit: f64, scores: &[Score]) -> Candidate {
        Candidate {
            effect,
            form: "",
            signature_excess: 10.0,
            gap_fit,
            gap_heldout: gap_of(scores, true),
            shrink: 0.0,
            heldout_shrink: None,
            parameters: BTreeMap::new(),
            unexplained: Vec::new(),
            model: crate::engine::Model::default(),
            scores: scores.to_vec(),
        }
    }

    /// Seed 11 set 15 of the benchmark: load dependence on top of a coloured
    /// noise that took the key gap from 179.2 to 13.2. It takes the key gap
    /// to 9.4 and the fitting gap from 32.3 to 5.8: 32% of what was left,
    /// though 2% of the baseline's gap. Its noise thresholds are about 1.2.
    /// The seed-21 `rational` memory: its law step raised the fitting gap
    /// from 70 to 117, where a few hundred fitting scores put the gap's
    /// noise under 1. A step within the noise is kept.
    #[test]
    fn a_law_step_is_undone_only_when_it_worsens_the_fit_beyond_noise() {
        assert!(step_made_it_worse(117.0, 70.0, 430));
        assert!(!step_made_it_worse(70.5, 70.0, 430));
        assert!(!step_made_it_worse(60.0, 70.0, 430));
        let noise = gap_noise(430);
        assert!(!step_made_it_worse(70.0 + 0.9 * noise, 70.0, 430));
        assert!(step_made_it_worse(70.0 + 1.1 * noise, 70.0, 430));
    }

    #[test]
    fn a_further_effect_is_judged_against_what_is_left() {
        let noise = (1.2, 1.2);
        assert!(closes_enough((32.27, 13.18), (5.84, 9.39), noise, false));
        // The same fall against the baseline's whole gap would not be a
        // real share of it ...
        assert!(!closes_enough((200.0, 179.23), (196.21, 175.44), noise, false));
        // ... nor one within the noise, or one that trades the fitting
        // gap for the held-out one, whatever the response says.
        assert!(!closes_enough((32.27, 13.18), (5.84, 12.3), noise, true));
        assert!(!closes_enough((32.27, 13.18), (45.09, 9.39), noise, true));
        // A response repair admits a real fall short of the share.
        assert!(closes_enough((32.27, 13.18), (5.84, 11.0), noise, true));
        assert!(!closes_enough((32.27, 13.18), (5.84, 11.0), noise, false));
    }

    #[test]
    fn effects_that_tie_at_the_screens_cut_are_fitted_together() {
        // Seed 17 set 15 of the blind benchmark, first round.
        let excess = vec![
            (Effect::NormalForceHarmonics, 0.5),
            (Effect::NonGaussianFriction, 0.5),
            (Effect::FrictionHysteresis, 437.0),
            (Effect::ColouredFrictionNoise, 437.0),
            (Effect::Stiction, 516.4),
            (Effect::LoadDependentFriction, 1041.4),
            (Effect::NormalForceDrift, 83.4),
        ];
        let fitted: Vec<Effect> = screen(excess.clone()).into_iter().map(|(e, _)| e).collect();
        assert_eq!(
            fitted,
            [
                Effect::LoadDependentFriction,
                Effect::Stiction,
                Effect::FrictionHysteresis,
                Effect::ColouredFrictionNoise
            ]
        );
        // Without the tie the cut is three, and none below the threshold.
        let mut apart = excess;
        apart[3].1 = 436.9;
        assert_eq!(screen(apart).len(), SCREEN_MAX);
        assert!(screen(vec![(Effect::Stiction, 2.9), (Effect::NormalForceDrift, 3.1)]).len() == 1);
    }

    #[test]
    fn a_further_effect_must_close_more_than_any_rival_does() {
        // Seed 16 set 16 of the blind benchmark, third round: from a key gap
        // of 5.37, three effects take it to 3.45, 4.09 and 4.14.
        let with_key = |effect, key: f64| test_candidate(effect, 6.0, &[score(0, Observable::PeakMeanM, key.sqrt())]);
        let round = [
            with_key(Effect::ColouredFrictionNoise, 3.45),
            with_key(Effect::NonGaussianFriction, 4.09),
            with_key(Effect::LoadDependentFriction, 4.14),
        ];
        let key = |c: &Candidate| key_gap(c, true);
        assert!((key(&round[0]) - 3.45).abs() < 1e-9, "the premise: z² below the Huber bend");
        let all = |_: &Candidate| true;
        let none = |_: &Candidate| false;
        assert!(!stands_out(&round[0], &round, &all, &none, 5.37, true, 1.0));
        // Alone in its round, far ahead of its rivals, or ahead of all
        // those the response admits, it stands out.
        assert!(stands_out(&round[0], &round[..1], &all, &none, 5.37, true, 1.0));
        let ahead = [with_key(Effect::FrictionHysteresis, 5.37), with_key(Effect::Stiction, 35.3)];
        assert!(stands_out(&ahead[0], &ahead, &all, &none, 61.6, true, 1.0));
        let keeps_only_the_noise = |c: &Candidate| c.effect == Effect::ColouredFrictionNoise;
        assert!(stands_out(&round[0], &round, &keeps_only_the_noise, &none, 5.37, true, 1.0));
        // Seed 32 set 15, second round: a load dependence that repairs the
        // response (668 -> 187) against a stiction that closes a little
        // more of the key gap and leaves the response where it was (the
        // key gaps a quarter of the set's, below the Huber bend). The
        // stiction is no alternative to it; the other way round it is.
        let pair = [with_key(Effect::Stiction, 19.83 / 4.0), with_key(Effect::LoadDependentFriction, 20.40 / 4.0)];
        let repairs_load = |c: &Candidate| c.effect == Effect::LoadDependentFriction;
        assert!(!stands_out(&pair[1], &pair, &all, &none, 28.23 / 4.0, true, 1.0));
        assert!(stands_out(&pair[1], &pair, &all, &repairs_load, 28.23 / 4.0, true, 1.0));
        assert!(!stands_out(&pair[0], &pair, &all, &repairs_load, 28.23 / 4.0, true, 1.0));
    }

    #[test]
    fn a_further_effect_that_fits_far_better_needs_no_share_of_the_held_out_gap() {
        // Seed 17 set 15 of the blind benchmark: a load dependence on top of
        // a coloured noise.
        assert!(fits_far_better(46.69, 9.97));
        assert!(!fits_far_better(46.69, 30.0));
        let noise = (1.2, 1.2);
        assert!(!closes_enough((46.69, 17.11), (9.97, 12.71), noise, false), "the premise: 28% of the held-out gap");
        assert!(closes_enough((46.69, 17.11), (9.97, 12.71), noise, fits_far_better(46.69, 9.97)));
    }

    /// A point of a test objective of the coordinate search.
    struct Probe {
        values: Vec<f64>,
        gap: f64,
    }

    impl SearchPoint for Probe {
        fn values(&self) -> &[f64] {
            &self.values
        }

        fn gap(&self) -> f64 {
            self.gap
        }
    }

    #[test]
    fn a_search_whose_every_move_helped_looks_back_between_its_last_two_points() {
        // A gap that falls steeply up to the best slope and rises gently
        // beyond it, searched from about five steps (factor 1.5) below: the
        // moves ×1.5, ×2.25 and ×5.06 all help, the last one to 2.5 times
        // the best. Looking back by half of it lands at 1.1 times the best;
        // without, the closing half step stops at twice the best.
        let best_slope = 0.0073;
        let gap = |v: f64| 3.0 * (best_slope / v).ln().max(0.0) + 0.5 * (v / best_slope).ln().max(0.0);
        let probe = |values: &[f64]| Probe { values: values.to_vec(), gap: gap(values[0]) };
        let params = [Param::log("strength_per_n", 0.00106, 1.5, -1.0, 1.0)];
        let found = coordinate_search(&params, probe(&[0.00106]), |_, values| Ok(Some(probe(values)))).unwrap();
        let off = (found.values[0] / best_slope).ln().abs();
        assert!(off < 1.2f64.ln(), "found {} against {best_slope}", found.values[0]);
    }

    #[test]
    fn a_form_whose_response_the_selection_refuses_ranks_behind_one_it_keeps() {
        // Eight response units and a hundred feature units; the round
        // starts from a model that predicts the response (z = 1) and
        // misfits the features (z = 8).
        let with = |response: f64, feature: f64| -> Vec<Score> {
            let peaks = (0..8).map(|u| score(u, Observable::PeakMeanM, response));
            peaks.chain((10..110).map(|u| score(u, Observable::FrictionMuMean, feature))).collect()
        };
        let base = with(1.0, 8.0);
        let ruler = yardstick(&base);
        let trial = |scores: Vec<Score>| Trial { values: Vec::new(), model: Model::default(), gap_fit: 0.0, scores };
        // Form T fits the features perfectly and moves the response off
        // (z = 2.5); form S fits them worse and keeps the response.
        let (t, s) = (trial(with(2.5, 0.0)), trial(with(1.0, 2.6)));
        let rank = |t: &Trial| form_rank(&t.scores, t.gap_fit, true, &ruler);
        assert!(rank(&t) < rank(&s), "the premise: T ranks first by its gaps");
        assert!(!further_keeps_the_response(&base, &t.scores, true, &ruler), "the premise: T would be refused");
        assert!(further_keeps_the_response(&base, &s.scores, true, &ruler));
        let order = |t: &Trial| form_order(false, &base, t, true, 8, &ruler);
        assert!(order(&s) < order(&t), "a further effect's form: S, which the selection keeps, must rank first");
        // Where both are kept the gaps decide as before.
        let t_kept = trial(with(1.2, 0.0));
        assert!(further_keeps_the_response(&base, &t_kept.scores, true, &ruler));
        assert!(order(&t_kept) < order(&s));
    }

    #[test]
    fn two_effects_of_which_neither_passes_alone_are_named_together_only_on_the_response() {
        // Eight held-out response units, a hundred held-out and a hundred
        // fitting feature units: the 18-run seed-23 set 8 in small.
        let with = |response: f64, feature: f64, fitting: f64| -> Vec<Score> {
            let peaks = (0..8).map(|u| score(u, Observable::PeakMeanM, response));
            let held = (10..110).map(|u| score(u, Observable::FrictionMuMean, feature));
            let fit =
                (200..300).map(|u| crate::diagnose::score::test_score(u, Observable::FrictionMuMean, fitting, false));
            peaks.chain(held).chain(fit).collect()
        };
        let candidate = |effect: Effect, scores: Vec<Score>| test_candidate(effect, gap_of(&scores, false), &scores);
        let baseline = with(20.0, 14.0, 14.0);
        let ruler = yardstick(&baseline);
        let gaps = |c: &Candidate| (c.gap_fit, key_gap(c, true));
        let baseline_gaps = (gap_of(&baseline, false), gap_of(&baseline, true));
        let noise = (gap_noise(100), gap_noise(108));
        // A load dependence predicts the response better and lowers both
        // gaps, but closes too small a share of the key gap to be named.
        let load = candidate(Effect::LoadDependentFriction, with(15.0, 12.5, 11.0));
        assert!(!closes_enough(baseline_gaps, gaps(&load), noise, false), "the premise: it is not named alone");
        assert!(worth_looking_ahead(&baseline, &load, true, 8, &ruler));
        // One that fits the features by widening every distribution, the
        // response worse, or one that leaves the response, is not.
        let widening = candidate(Effect::ColouredFrictionNoise, with(25.0, 1.0, 1.0));
        assert!(
            keeps_the_response(&baseline, &widening.scores, true, 8, &ruler),
            "the premise: within the loose bound"
        );
        assert!(!worth_looking_ahead(&baseline, &widening, true, 8, &ruler));
        let unmoved = candidate(Effect::Stiction, with(20.0, 12.5, 11.0));
        assert!(!worth_looking_ahead(&baseline, &unmoved, true, 8, &ruler));
        // The noise searched on top of it: the pair fits and predicts.
        let both = candidate(Effect::ColouredFrictionNoise, with(1.0, 1.0, 1.0));
        assert!(pair_passes(&baseline, &load, &both, true, &ruler));
        // Not a second effect that spoils the response the first predicts,
        // nor a pair that closes too little of the baseline's key gap.
        let spoils = candidate(Effect::ColouredFrictionNoise, with(18.0, 1.0, 1.0));
        assert!(!pair_passes(&baseline, &load, &spoils, true, &ruler));
        let little = candidate(Effect::ColouredFrictionNoise, with(1.0, 12.0, 10.0));
        assert!(closes_enough(gaps(&load), gaps(&little), noise, true), "the premise: it passes as a further effect");
        assert!(!pair_passes(&baseline, &load, &little, true, &ruler));
    }

    #[test]
    fn the_next_form_stands_for_an_effect_only_where_the_first_is_refused() {
        // Forms judged by whether they are kept (true) or refused (false);
        // None where they could not be judged (a model that diverged).
        let choose = |verdicts: &[Option<bool>], tries: usize| -> Option<usize> {
            let ranked: Vec<usize> = (0..verdicts.len()).collect();
            let mut judged = Vec::new();
            let out = first_kept(ranked, tries, |i| {
                judged.push(i);
                Ok(verdicts[i].map(|kept| (i, kept)))
            })
            .unwrap();
            assert!(judged.len() <= tries, "judged {judged:?}, at most {tries}");
            out
        };
        // The first kept is taken, and nothing after it is judged.
        assert_eq!(choose(&[Some(true), Some(true)], 2), Some(0));
        // Refused: the next form, if that one is kept (seed-23 set 7) ...
        assert_eq!(choose(&[Some(false), Some(true)], 2), Some(1));
        // ... else the first stays (the selection refuses the effect).
        assert_eq!(choose(&[Some(false), Some(false)], 2), Some(0));
        // A leading effect tries one form only.
        assert_eq!(choose(&[Some(false), Some(true)], 1), Some(0));
        // A form that could not be judged is passed over.
        assert_eq!(choose(&[None, Some(false)], 2), Some(1));
        assert_eq!(choose(&[None], 2), None);
    }

    #[test]
    fn the_effect_the_response_needs_most_leads() {
        let w = |moved, moved_sd, heldout_rise| Some(ResponseWeight { moved, moved_sd, heldout_rise });
        // Seed 11 set 16: harmonics first by the key gap; without the
        // hysteresis the fitting units' response moves by 2 359 (sd 11),
        // without the harmonics by 74 (sd 2): the hysteresis leads.
        assert_eq!(response_leader(&[w(74.4, 2.0, Some((23.7, 0.5))), w(2359.2, 11.4, Some((112.0, 0.5)))]), 1);
        // Within one sd of the difference the first added keeps the lead.
        assert_eq!(response_leader(&[w(20.0, 1.0, None), w(21.2, 1.0, None)]), 0);
        // Seed 26 set 15: the coloured noise first by the key gap, its
        // removal 34.1 ± 1.4, the load dependence's 47.9 ± 1.6; at the
        // held-out interior load the load dependence's removal costs
        // little (3.3 ± 6.3) but does not help: the load leads.
        assert_eq!(response_leader(&[w(34.1, 1.4, Some((228.8, 4.4))), w(47.9, 1.6, Some((3.3, 6.3)))]), 1);
        // Seed 29 set 2: a spurious coloured noise moves the response more
        // than the true non-Gaussian noise, but by less than a spread, and
        // the held-out response is better without it: the first keeps it.
        assert_eq!(response_leader(&[w(0.46, 0.1, Some((2.94, 0.97))), w(0.85, 0.1, Some((-1.58, 0.68)))]), 0);
        assert_eq!(response_leader(&[w(0.46, 0.1, Some((2.94, 0.97))), w(0.85, 0.1, None)]), 0);
        assert_eq!(response_leader(&[w(0.46, 0.1, None), w(8.5, 0.1, Some((-1.58, 0.68)))]), 0);
        assert_eq!(response_leader(&[w(0.46, 0.1, None), w(8.5, 0.1, Some((-0.5, 0.68)))]), 1);
        // Of two that beat the first, the larger leads.
        assert_eq!(response_leader(&[w(1.0, 0.1, None), w(30.0, 1.0, None), w(50.0, 1.0, None)]), 2);
        // Nothing to weigh (one effect, or the first's weight unknown).
        assert_eq!(response_leader(&[]), 0);
        assert_eq!(response_leader(&[None, w(50.0, 1.0, None)]), 0);
        assert_eq!(response_leader(&[w(1.0, 0.1, None), None]), 0);
    }

    #[test]
    fn an_effect_weighs_what_its_removal_moves_the_fitted_response_at_the_fitting_units() {
        use crate::diagnose::score::test_score;
        let at = |unit, observable, heldout, simulated| Score {
            simulated,
            scale: 2.0,
            simulated_share: 0.1,
            ..test_score(unit, observable, 0.0, heldout)
        };
        let fitted = [
            at(0, Observable::PeakMeanM, false, 1.0),
            at(1, Observable::PhaseMeanDeg, false, 1.0),
            at(2, Observable::PeakMeanM, true, 1.0),
            at(0, Observable::FrictionMuMean, false, 1.0),
        ];
        // The peak mean moves by two spreads, the phase not at all; the
        // held-out unit and the friction feature are not counted.
        let without = [
            at(0, Observable::PeakMeanM, false, 5.0),
            at(1, Observable::PhaseMeanDeg, false, 1.0),
            at(2, Observable::PeakMeanM, true, 100.0),
            at(0, Observable::FrictionMuMean, false, 100.0),
        ];
        let (weight, sd) = response_move(&fitted, &without);
        assert!((weight - 2.0).abs() < 1e-12, "{weight}");
        // sqrt(8·0.1·4 + 8·0.01 + 8·0.01) / 2.
        assert!((sd - 3.36f64.sqrt() / 2.0).abs() < 1e-12, "{sd}");
        // Nothing moved, nothing weighed; nothing scored, nothing either.
        // A phase moves on the circle: from 179° to −179° is 2°, one spread.
        let (near, across) =
            ([at(1, Observable::PhaseMeanDeg, false, 179.0)], [at(1, Observable::PhaseMeanDeg, false, -179.0)]);
        assert!((response_move(&near, &across).0 - 1.0).abs() < 1e-9, "{:?}", response_move(&near, &across));
        assert_eq!(response_move(&fitted, &fitted).0, 0.0);
        assert_eq!(response_move(&fitted, &[]), (0.0, 0.0));
    }

    #[test]
    fn between_forms_and_effects_a_slightly_better_feature_fit_loses_to_a_better_response() {
        // Three held-out features and one response observable, the baseline
        // with the response 4 of its spreads off.
        let baseline = [
            score(0, Observable::PeakMeanM, 4.0),
            score(0, Observable::FrictionMuMean, 3.0),
            score(1, Observable::FrictionMuMean, 3.0),
            score(2, Observable::FrictionMuMean, 3.0),
        ];
        let ruler = yardstick(&baseline);
        // Form A fits the features better but leaves the response; form B
        // fits them worse and predicts the response.
        let form_a = [
            score(0, Observable::PeakMeanM, 4.0),
            score(0, Observable::FrictionMuMean, 0.5),
            score(1, Observable::FrictionMuMean, 0.5),
            score(2, Observable::FrictionMuMean, 0.5),
        ];
        let form_b = [
            score(0, Observable::PeakMeanM, 1.0),
            score(0, Observable::FrictionMuMean, 2.5),
            score(1, Observable::FrictionMuMean, 2.5),
            score(2, Observable::FrictionMuMean, 2.5),
        ];
        assert!(gap_of(&form_a, true) < gap_of(&form_b, true), "the premise: A has the lower held-out gap");
        let (rank_a, rank_b) = (form_rank(&form_a, 0.0, true, &ruler), form_rank(&form_b, 0.0, true, &ruler));
        assert!(rank_b < rank_a, "form B, which predicts the response, must rank first: {rank_b} vs {rank_a}");
        // With the response equally predicted the lower gap wins.
        let form_c = [form_a[0].clone(), form_b[1].clone(), form_b[2].clone(), form_b[3].clone()];
        assert!(form_rank(&form_a, 0.0, true, &ruler) < form_rank(&form_c, 0.0, true, &ruler));
        // Between effects of one round the same where their key gaps tie:
        // form B' fits the features nearly as well as A (its key gap within
        // a tenth of A's fall from the baseline's) and predicts the
        // response, so it leads; form D predicts the response best but
        // closes far less of the gap, so it stays behind both.
        let feature = |z: f64| [1, 2, 3].map(|u| score(u, Observable::FrictionMuMean, z));
        let form_b_tied = [&[score(0, Observable::PeakMeanM, 1.0)][..], &feature(2.3)].concat();
        let form_d = [&[score(0, Observable::PeakMeanM, 0.0)][..], &feature(3.0)].concat();
        let candidate = |effect: Effect, scores: &[Score]| test_candidate(effect, 0.0, scores);
        let mut round = vec![
            candidate(Effect::FrictionHysteresis, &form_a),
            candidate(Effect::Stiction, &form_b_tied),
            candidate(Effect::NonGaussianFriction, &form_d),
        ];
        let key_before = gap_of(&baseline, true);
        rank_effects(&mut round, (0.0, key_before), true, &ruler);
        let order: Vec<Effect> = round.iter().map(|c| c.effect).collect();
        assert_eq!(order, [Effect::Stiction, Effect::FrictionHysteresis, Effect::NonGaussianFriction]);
        // Without the tie (B's features as far off as before) the key gap decides.
        round[0] = candidate(Effect::Stiction, &form_b);
        rank_effects(&mut round, (0.0, key_before), true, &ruler);
        assert_eq!(round[0].effect, Effect::FrictionHysteresis);
    }

    #[test]
    fn an_effect_that_fits_far_better_ties_with_one_a_little_better_held_out() {
        // The 18-run seed-22 set 8 in miniature: from gaps (fitting 889,
        // held-out 245), A leaves (389, 148) and B (135, 164). B is 16
        // behind on the held-out gap (beyond a tenth of A's fall, 9.7) but
        // closes 29% more of the fitting gap against 6% less of the held-out
        // one: they tie, and B, which predicts the held-out response, leads.
        let held_out = |response: f64, feature: f64| {
            [score(0, Observable::PeakMeanM, response), score(1, Observable::FrictionMuMean, feature)]
        };
        let baseline = held_out(30.0, 30.0);
        let ruler = yardstick(&baseline);
        let (a, b) = (held_out(27.0, 22.7), held_out(20.0, 34.0));
        let before = (889.0, gap_of(&baseline, true));
        let (key_a, key_b) = (gap_of(&a, true), gap_of(&b, true));
        assert!(key_b - key_a > RANK_TIE_SHARE * (before.1 - key_a), "the premise: no tie on the held-out gap alone");
        let mut round = vec![
            test_candidate(Effect::FrictionHysteresis, 389.0, &a),
            test_candidate(Effect::LoadDependentFriction, 135.0, &b),
        ];
        rank_effects(&mut round, before, true, &ruler);
        assert_eq!(round[0].effect, Effect::LoadDependentFriction);
        // Fitting no better than A, B stays behind it.
        let mut round = vec![
            test_candidate(Effect::FrictionHysteresis, 389.0, &a),
            test_candidate(Effect::LoadDependentFriction, 389.0, &b),
        ];
        rank_effects(&mut round, before, true, &ruler);
        assert_eq!(round[0].effect, Effect::FrictionHysteresis);
    }
}
