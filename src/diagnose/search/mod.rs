//! Attribution: which effects the data need beyond the calibrated
//! baseline, named by cross-validated share of the gap explained.
//!
//! Round by round (at most [`MAX_EFFECTS`] effects), on top of the model
//! named so far:
//!
//! 1. **Every family is fitted** ([`family::round`]): each form of every effect the
//!    data have a channel for is tried at the parameters the data's
//!    signature implies (a coarse fit, the friction law recalibrated), and
//!    the families that fit best are then searched in full
//!    ([`fit::coordinate_search`]). Screening orders the search; it never
//!    drops a family unfitted.
//! 2. **Cross-validated**: each fold of the set ([`crate::diagnose::data::Folds`]:
//!    every load level in turn, the outer ones included) is predicted by the
//!    family member (form and parameters) that fits the other folds best
//!    ([`cv::pool_predictions`]).
//! 3. **The contest** ([`cv::contest`]) leads with the family that closes
//!    the largest share of the current model's out-of-sample gap, beyond
//!    the noise. The leading contender is then refitted fold by fold from
//!    scratch on each fold's own units, friction law included, in the form
//!    it is named by ([`refit_folds`]), and must close a share beyond the
//!    noise that way too, and predict no withheld fold worse than the
//!    model before it (beyond what its form leaves of that fold when it is
//!    fitted to it: [`verdict`]).
//!    Where no family predicts a withheld level beyond the noise in the
//!    first round, an effect seen at one load alone may be why (fitted
//!    without that load, it was never seen): the contest is held again on
//!    folds crossed over loads and frequencies
//!    ([`crate::diagnose::data::Data::crossed`]), each fall judged
//!    against the noise of the scores the family moved, and a leader named
//!    there must still predict every withheld level no worse.
//!    [`verdict::judge`] says which leaders are named and how sure that is.
//! 4. The named family's best fit on the full data is polished on every
//!    replicate ([`fit::polish`]) and becomes the model the next round
//!    builds on; its fold refits become the next round's fold models.
//!
//! What a named form still leaves of the gap it was asked to explain is
//! reported as its form misfit: real rigs never match a candidate's shape
//! exactly, and an effect is named for the family, not the shape.
//!
//! Where nothing is named, [`power`] measures how surely these records
//! would have shown each family at its smallest size of interest, and the
//! `none` is no surer than the least of those.

pub(crate) mod cv;
mod family;
pub(crate) mod fit;
pub mod power;
mod refit;
#[cfg(test)]
mod tests;
pub(crate) mod verdict;

use crate::diagnose::calibrate::{calibrate_and_score, converge_law};
use crate::diagnose::data::Data;
use crate::diagnose::observable::Observable;
use crate::diagnose::score::{Scope, Score, score};
use crate::diagnose::simulate::fits_per_task;
use crate::diagnose::tracing;
use crate::diagnose::{Candidate, DiagnoseSettings, Refusal, RefusalReason, Unexplained};
use crate::engine::{Effect, Engine, Model};
use crate::error::Result;
use cv::{
    Contest, Entrant, NullLoss, UnitLosses, contest, fold_predictions, held_units, mean_loss, own_losses,
    own_losses_of, pair_losses, pair_losses_of, pool_predictions, unpaired,
};
use family::{Family, round};
pub(crate) use fit::Fitted;
use fit::polish;
use rayon::prelude::*;
use refit::refit_folds;

/// At most this many effects are named. What two named effects leave
/// beyond the noise is reported (a note, and `verdict.misfit`'s hints:
/// [`Selection::left_after_most`]), not pinned on a third family: with the
/// few loads a set holds, a third round's leader is judged on folds that
/// two fitted effects and a recalibrated law have already bent to, and it
/// closes what the first two forms leave (their form misfit, or a property
/// of one of them, such as a telegraph noise's two-valued marginal beside
/// its correlation) as readily as a third effect's signal. A set that does
/// hold three strong effects loses the third name to the note. A third
/// round also took as long as the two before it.
pub(crate) const MAX_EFFECTS: usize = 2;

/// One step of the selection: a named effect.
#[derive(Clone, Debug)]
pub(crate) struct Step {
    /// Its full-data fit, polished on every replicate.
    pub(crate) candidate: Candidate,
    /// The share of resamples that name it, discounted for the form misfit
    /// of the verdict that names it ([`verdict::judge`]); the leading
    /// step's is the verdict's own, –.
    pub(crate) confidence: f64,
    /// The share of what the model before it left of the out-of-sample gap
    /// that it closed, from its fold refits, –.
    pub(crate) share: f64,
    /// Per fold: the model before it and with it, refitted without the
    /// fold, and their gaps at the fold's units.
    pub(crate) folds: Vec<FoldResult>,
}

/// A model and the one before it, both fitted without a fold, at that fold.
#[derive(Clone, Debug)]
pub(crate) struct FoldResult {
    /// The model with the effect (fitted without the fold).
    pub(crate) after: Fitted,
    /// Their mean Huber loss at the fold's units.
    pub(crate) gap_before: f64,
    pub(crate) gap_after: f64,
}

/// The model with every named effect: its full-data fit and its refits
/// without each fold. Each round adds its effect to the model before it, so
/// this is the last named round's model, whatever order the effects are
/// reported in.
#[derive(Clone, Debug)]
pub(crate) struct NamedModel {
    pub(crate) full: Fitted,
    pub(crate) folds: Vec<Fitted>,
}

impl NamedModel {
    /// The model of the last of `steps`, in the order they were named.
    fn of_rounds(steps: &[Step]) -> Option<NamedModel> {
        steps.last().map(|s| NamedModel {
            full: Fitted { model: s.candidate.model.clone(), scores: s.candidate.scores.clone() },
            folds: s.folds.iter().map(|f| f.after.clone()).collect(),
        })
    }
}

/// What the selection found.
pub(crate) struct Selection {
    /// The named effects, the one that shapes the response most first
    /// ([`in_report_order`]): not the order they were named in.
    pub(crate) steps: Vec<Step>,
    /// The model with every named effect; `None` where none was named.
    pub(crate) named_model: Option<NamedModel>,
    /// The first leader not named, where one led.
    pub(crate) refused: Option<Refusal>,
    /// The withheld folds the model with the named effects predicts worse
    /// than the baseline, but as closely as its form fits them
    /// ([`verdict::Rise::within_form_misfit`]).
    pub(crate) misfit_folds: Vec<verdict::FoldCheck>,
    /// Every family of the first round, best (most wins) first.
    pub(crate) first_round: Vec<Candidate>,
    /// How sure "the baseline explains the data" is where nothing was
    /// named: the share of resamples in which its out-of-sample gap stood
    /// within its noise of the floor, –. (Where it misfits and no family
    /// explains any of the misfit beyond the noise the verdict is still
    /// `none`, but not a confident one.)
    pub(crate) none_confidence: f64,
    /// Where nothing was named: each family's power to show itself in
    /// these records at its smallest size of interest ([`power`]); a
    /// `none`'s confidence is at most the least of them.
    pub(crate) powers: Vec<power::Power>,
    /// The baseline refitted without each fold.
    pub(crate) baseline_folds: Vec<Fitted>,
    /// The out-of-sample noise threshold of the gap, –.
    pub(crate) noise: f64,
    /// Where [`MAX_EFFECTS`] were named and the model with them still
    /// leaves a gap beyond the noise: how far that gap (mean loss over the
    /// held-out units, –) stands above the floor of a right model, and its
    /// noise threshold, –.
    pub(crate) left_after_most: Option<(f64, f64)>,
    /// The loss of a model that is right, on the replicates models are
    /// compared on.
    pub(crate) null: NullLoss,
    /// The folds the first effect's family was judged on: the set's own,
    /// or folds crossed over loads and frequencies where no family predicts
    /// a withheld level beyond the noise ([`crate::diagnose::data::Data::crossed`]).
    pub(crate) attribution_folds: crate::diagnose::data::Folds,
}

impl Selection {
    /// The fold models with every named effect (the baseline's where none).
    pub(crate) fn fitted_folds(&self) -> Vec<Fitted> {
        match &self.named_model {
            Some(m) => m.folds.clone(),
            None => self.baseline_folds.clone(),
        }
    }
}

/// One cut of the data into folds, with each fold's view and the current
/// model fitted without it (at first the baseline).
struct FoldSet<'a> {
    data: Data<'a>,
    views: Vec<Data<'a>>,
    current: Vec<Fitted>,
}

impl<'a> FoldSet<'a> {
    /// The folds of `data`, with the baseline refitted without each as the
    /// current model: its
    /// law carried to each fold's measured law from the full-data
    /// baseline's, on search replicates, scored on every unit.
    fn new(
        data: Data<'a>,
        baseline: &Model,
        slope: f64,
        search: &DiagnoseSettings,
        engine: &Engine,
    ) -> Result<FoldSet<'a>> {
        let views = data.fold_views();
        let fitted = views
            .par_iter()
            .with_min_len(fits_per_task(engine))
            .map(|view| {
                let (m, s, _) = calibrate_and_score(baseline, view, search, engine, Some(slope), 2, Scope::Fitting)?;
                let (model, scores) = converge_law(m, s, view, search, engine)?;
                Ok(Fitted { model, scores })
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(FoldSet { data, views, current: fitted })
    }
}

/// A round as the contest judges it: its families, the current model's
/// own losses, the held-out units and the null loss.
struct Judged<'r> {
    families: &'r [Family],
    current: &'r UnitLosses,
    units: &'r [usize],
    null: NullLoss,
    seed: u64,
    round: usize,
}

/// A round's contest on one cut of the data into folds, and its leader
/// refitted without each of them.
struct Attribution {
    /// Per family: its out-of-sample losses, the current model's in the
    /// same yardsticks, and the member each fold was predicted by.
    predictions: Vec<(UnitLosses, UnitLosses, Vec<usize>)>,
    pooled: Contest,
    led: Option<Led>,
}

/// The leader of a contest, refitted without each fold.
struct Led {
    /// Its index among the round's families.
    top: usize,
    refits: Vec<Fitted>,
    /// The models before and after it, refitted without each fold, at the
    /// folds' units.
    refitted: (UnitLosses, UnitLosses),
    /// The share of what the model before it left that the refits close,
    /// and whether that is beyond the noise.
    share: f64,
    beyond: bool,
}

impl Judged<'_> {
    /// The contest on `folds` ([`cv::contest`]) and its leader, if any,
    /// refitted without each of them ([`refit_folds`]); no leader where a
    /// fold's model cannot be built or run. With `local`, a fall is judged
    /// against the noise of the scores the family moved
    /// ([`cv::NullLoss::fall_noise`]: the question is whether an effect
    /// seen at a few conditions is there); else against that of every
    /// score ([`cv::unpaired`]): an effect that matters across the set must
    /// stand out at its scale, and with long records a family that
    /// compensates some of the named forms' misfit moves a few scores far
    /// beyond their own noise.
    #[allow(clippy::too_many_arguments)]
    fn attribute(
        &self,
        folds: &FoldSet<'_>,
        local: bool,
        slope: f64,
        search: &DiagnoseSettings,
        engine: &Engine,
        progress: &mut dyn FnMut(&str),
    ) -> Result<Attribution> {
        let pair = |p: (UnitLosses, UnitLosses)| if local { p } else { (unpaired(&p.0), unpaired(&p.1)) };
        let predictions: Vec<(UnitLosses, UnitLosses, Vec<usize>)> = self
            .families
            .iter()
            .map(|f| {
                let (losses, reference, picks) = pool_predictions(&f.pool_losses(), &folds.data.folds);
                let (losses, reference) = pair((losses, reference));
                (losses, reference, picks)
            })
            .collect();
        let entrants: Vec<Entrant<'_>> =
            predictions.iter().map(|(losses, reference, _)| Entrant { losses, reference }).collect();
        let pooled = contest(self.current, &entrants, self.units, self.null, self.seed);
        if tracing() {
            eprintln!("round {}: judged on {}", self.round, folds.data.folds.describe());
            trace_round(self.round, self.families, &predictions, &pooled, self.units);
        }
        let led = match pooled.leader {
            None => None,
            Some(top) => {
                let family = &self.families[top];
                progress(&format!("refitting {} without each fold", family.effect));
                refit_folds(family, folds, slope, search, engine)?.map(|refits| {
                    let refitted = pair(fold_pair_losses(&folds.current, &refits, &folds.data));
                    let ones = vec![1.0; self.units.len()];
                    let point = cv::Weights { units: self.units, w: &ones, null: self.null };
                    let (share, beyond) = point.share(&refitted.1, &refitted.0);
                    if tracing() {
                        let (moved, n) = point.moved(&refitted.1);
                        eprintln!(
                            "round {}: {} refitted without each fold closes {share:.3} of what was left (beyond noise {beyond}; moved {moved:.1} of {n} scores)",
                            self.round, family.effect,
                        );
                    }
                    Led { top, refits, refitted, share, beyond }
                })
            }
        };
        Ok(Attribution { predictions, pooled, led })
    }
}

/// Forward selection from the calibrated baseline (see the module).
pub(crate) fn select(
    baseline: &Model,
    slope: f64,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    engine: &Engine,
    progress: &mut dyn FnMut(&str),
) -> Result<Selection> {
    let search = settings.for_search();
    let units = held_units(&data.folds);
    progress(&format!("refitting the baseline without each fold ({} folds)", data.folds.folds.len()));
    let mut levels = FoldSet::new(data.clone(), baseline, slope, &search, engine)?;
    let baseline_folds = levels.current.clone();
    let mut attribution_folds = data.folds.clone();
    let mut current = Fitted { model: baseline.clone(), scores: score(engine, baseline, data, &search, Scope::All)? };
    let baseline_scores = current.scores.clone();
    let mut rounds: Vec<verdict::Round> = Vec::new();
    let mut steps: Vec<Step> = Vec::new();
    let mut first_round = Vec::new();
    let mut none_confidence = 1.0;
    let mut noise: f64 = 0.0;
    let mut refused = None;
    let seed = settings.seed ^ 0xC0_47E5;
    let null = NullLoss::for_replicates(search.replicates);
    let ones = vec![1.0; units.len()];
    let point = cv::Weights { units: &units, w: &ones, null };
    if units.is_empty() {
        // Nothing can be held out (one condition, say), so no effect can
        // be tested, and "none" is only as sure as the baseline's fit in
        // sample: the share of resamples of its units within the noise of
        // the floor, divided by √m where its gap stands m noise thresholds
        // above it (as for a `none` beside a gap nothing explains, below).
        let losses = own_losses(&current.scores, data);
        let all: Vec<usize> = losses.keys().copied().collect();
        if !all.is_empty() {
            let idle = contest(&losses, &[], &all, null, seed);
            noise = idle.noise;
            none_confidence = idle.fits / noise_thresholds_above(idle.gap, idle.noise, null).sqrt();
        }
    }
    let mut left = None;
    while !units.is_empty() {
        let current_losses = own_losses(&current.scores, data);
        // Nothing above the noise to explain: no family can lead.
        let idle = contest(&current_losses, &[], &units, null, seed);
        let within = idle.gap - null.mean <= idle.noise;
        if rounds.len() == MAX_EFFECTS {
            // The most effects were added: what they leave is noted, not
            // searched.
            left = (!within).then_some((idle.gap - null.mean, idle.noise));
            break;
        }
        noise = noise.max(idle.noise);
        if rounds.is_empty() {
            none_confidence = idle.fits;
        }
        if within {
            if tracing() {
                eprintln!(
                    "round {}: gap {:.2} within its noise {:.2} of the floor",
                    rounds.len(),
                    idle.gap,
                    idle.noise
                );
            }
            break;
        }
        let named: Vec<Effect> = steps.iter().map(|s| s.candidate.effect).collect();
        let families = round(&current, &named, slope, data, &search, engine, progress)?;
        let on =
            Judged { families: &families, current: &current_losses, units: &units, null, seed, round: rounds.len() };
        let mut attributed = on.attribute(&levels, false, slope, &search, engine, progress)?;
        let mut on_crossed = false;
        // No family predicts a withheld level beyond the noise. An effect
        // seen at one load alone cannot: fitted without that load it was
        // never seen. The weaker question, whether a family predicts
        // conditions it was not fitted to within the loads it was, is then
        // asked on folds crossed over loads and frequencies; a family named
        // on it must still predict every withheld level no worse than the
        // baseline.
        let crossed =
            (rounds.is_empty() && !attributed.led.as_ref().is_some_and(|l| l.beyond)).then(|| data.crossed()).flatten();
        if let Some(crossed) = crossed {
            progress(&format!(
                "refitting the baseline without each crossed fold ({} folds)",
                crossed.folds.folds.len()
            ));
            let folds = FoldSet::new(crossed, baseline, slope, &search, engine)?;
            let other = on.attribute(&folds, true, slope, &search, engine, progress)?;
            if other.led.as_ref().is_some_and(|l| l.beyond) {
                attributed = other;
                on_crossed = true;
                attribution_folds = folds.data.folds;
            }
        }
        let Attribution { predictions, pooled, led } = attributed;
        if rounds.is_empty() {
            first_round = candidates_of(&families, &pooled, &current, data, null);
        }
        // The leader, where it closes a share beyond the noise.
        let Some(Led { top, refits, refitted, share, beyond }) = led else { break };
        let family = &families[top];
        if !beyond {
            refused = Some(Refusal {
                effect: family.effect,
                form: family.form,
                share_of_gap: pooled.shares[top],
                after_named: steps.len(),
                reason: RefusalReason::NotBeyondNoise { refitted_share: share },
            });
            break;
        }
        let level_refits =
            if on_crossed { refit_folds(family, &levels, slope, &search, engine)? } else { Some(refits) };
        let Some(level_refits) = level_refits else { break };
        let refitted_levels = fold_pair_losses(&levels.current, &level_refits, data);
        let joint = fold_pair_losses(&baseline_folds, &level_refits, data);
        let joint_response = fold_pair_losses_of(&baseline_folds, &level_refits, data, Observable::is_response);
        if tracing() {
            eprintln!(
                "round {}: refitted without each level it closes {:.3} of the baseline's gap",
                rounds.len(),
                point.share(&joint.1, &joint.0).0
            );
        }
        let folds: Vec<FoldResult> = (0..levels.views.len())
            .map(|k| {
                let held = data.folds.folds[k].units.iter().copied();
                let (before, after) = pair_gaps(&levels.current[k].scores, &level_refits[k].scores, data, held);
                FoldResult { gap_before: before, gap_after: after, after: level_refits[k].clone() }
            })
            .collect();
        progress(&format!("{} leads; polishing its model on every replicate", family.effect));
        let polished = polish(&family.best, slope, data, settings, engine)?.unwrap_or_else(|| family.best.clone());
        let candidate = candidate_of(
            family,
            Fitted::from(polished.clone()),
            (pooled.gap, pooled.shares[top]),
            pooled.leads[top],
            &current,
            data,
            null,
        );
        steps.push(Step { candidate, confidence: 0.0, share, folds });
        current = Fitted {
            model: polished.model.clone(),
            scores: score(engine, &polished.model, data, &search, Scope::All)?,
        };
        rounds.push(verdict::Round {
            current: current_losses,
            entrants: predictions.iter().map(|(l, r, _)| (l.clone(), r.clone())).collect(),
            effects: families.iter().map(|f| f.effect).collect(),
            leader: top,
            refitted,
            refitted_levels,
            joint,
            joint_response,
            fitted: (own_losses(&current.scores, data), own_losses_of(&current.scores, data, Observable::is_response)),
            local: on_crossed,
        });
        levels.current = level_refits;
    }
    let fold_units: Vec<Vec<usize>> = data.folds.folds.iter().map(|f| f.units.clone()).collect();
    let (count, confidence, each) = verdict::judge(&rounds, &fold_units, &units, null, seed);
    let left_after_most = left.filter(|_| count == MAX_EFFECTS);
    if tracing() {
        for (j, r) in rounds.iter().enumerate() {
            for c in verdict::fold_checks(r, &fold_units, &units, null) {
                eprintln!(
                    "round {j}: fold {} ({}): baseline {:.3}, predicted {:.3}, its own fit {:.3}, noise {:.3}",
                    c.fold,
                    if c.response { "the response" } else { "every observable" },
                    c.rise.other,
                    c.rise.model,
                    c.rise.own_fit.unwrap_or(f64::NAN),
                    c.rise.noise
                );
            }
        }
        eprintln!("verdict: {count} of {} leaders named, confidence {confidence:.3}, each {each:?}", rounds.len());
    }
    if count < rounds.len() {
        let c = &steps[count].candidate;
        let labels = |folds: Vec<usize>| folds.into_iter().map(|k| data.folds.folds[k].label.clone()).collect();
        let reason = match verdict::refusal(&rounds[count], &fold_units, &units, null) {
            verdict::Refused::NotBeyondNoise { share } => RefusalReason::NotBeyondNoise { refitted_share: share },
            verdict::Refused::WorseFolds {
                than_baseline,
                than_before,
                response_than_baseline,
                response_over_every_fold,
            } => RefusalReason::WorseFolds {
                than_baseline: labels(than_baseline),
                than_model_before: labels(than_before),
                response_than_baseline: labels(response_than_baseline),
                response_over_every_fold,
            },
        };
        refused =
            Some(Refusal { effect: c.effect, form: c.form, share_of_gap: c.cv_share, after_named: count, reason });
    }
    let misfit_folds = match count.checked_sub(1) {
        Some(last) => verdict::fold_checks(&rounds[last], &fold_units, &units, null)
            .into_iter()
            .filter(|c| c.rise.within_form_misfit())
            .collect(),
        None => Vec::new(),
    };
    steps.truncate(count);
    for (step, c) in steps.iter_mut().zip(&each) {
        step.confidence = *c;
    }
    let weights = if count > 1 { response_weights(&steps, data, &search, engine)? } else { vec![0.0; count] };
    let named_model = in_report_order(&mut steps, &weights);
    if count > 0 {
        // The verdict's confidence is that of naming exactly these.
        steps[0].confidence = confidence;
    } else if let Some(first) = rounds.first() {
        // "None" is sure only where the baseline fits: where its gap stands
        // m noise thresholds above the floor and nothing explains it, the
        // misfit may be an effect no candidate has, and the share
        // of resamples that name nothing is divided by √m.
        let (gap, n) = point.gap(&first.current);
        none_confidence = confidence / noise_thresholds_above(gap, point.noise(n), null).sqrt();
    }
    let powers = if count == 0 {
        progress("nothing named; measuring what these records could have shown");
        let powers = power::powers(baseline, &baseline_scores, &units, data, &search, engine, null)?;
        if tracing() {
            for p in &powers {
                eprintln!(
                    "power of {}: rise {:.3} against {:.3}, {:.3} ({})",
                    p.effect, p.rise, p.threshold, p.power, p.reference
                );
            }
        }
        none_confidence = none_confidence.min(power::least(&powers));
        powers
    } else {
        Vec::new()
    };
    Ok(Selection {
        steps,
        named_model,
        refused,
        misfit_folds,
        first_round,
        none_confidence,
        powers,
        baseline_folds,
        noise,
        null,
        attribution_folds,
        left_after_most,
    })
}

/// How much the fitted model's response (the peak's and the phase's mean
/// and variance, at every unit) needs each named effect (`steps` in the
/// order they were named): the rise of the response observables' mean loss
/// when that effect alone is taken out of the fitted model, in the fitted
/// model's yardstick, –. The effect that shapes the frequency response most
/// leads ([`in_report_order`]); the gap counts every observable, and an
/// effect seen plainly in another channel (a normal-force harmonic in the
/// normal force) can close the largest share of it while a friction memory
/// beside it is what moves the peaks. A removal the model cannot run
/// weighs −∞.
fn response_weights(steps: &[Step], data: &Data<'_>, search: &DiagnoseSettings, engine: &Engine) -> Result<Vec<f64>> {
    let Some(last) = steps.last() else { return Ok(Vec::new()) };
    let fitted = last.candidate.model.clone();
    let fitted_scores = score(engine, &fitted, data, search, Scope::All)?;
    let mut weights = Vec::new();
    for step in steps {
        let mut without = fitted.clone();
        without.effects.remove(step.candidate.effect);
        let weight = match score(engine, &without, data, search, Scope::All) {
            Ok(scores) => {
                let (with, wout) = pair_losses_of(&scores, &fitted_scores, data, Observable::is_response);
                let all = || with.keys().copied();
                // Both in the fitted model's yardstick: `with` is the model
                // without the effect, `wout` the fitted one.
                mean_loss(&with, all()) - mean_loss(&wout, all())
            }
            Err(e) if e.cannot_run() => f64::NEG_INFINITY,
            Err(e) => return Err(e),
        };
        if tracing() {
            eprintln!("response weight of {}: {weight:.3}", step.candidate.effect);
        }
        weights.push(weight);
    }
    Ok(weights)
}

/// Puts the named effects (`steps`, in the order they were named) in the
/// order of their response `weights`, heaviest first (ties keep the order
/// they were named in), and returns the model with them all: the last
/// round's, taken before the order changes. Only the report's order
/// changes.
fn in_report_order(steps: &mut [Step], weights: &[f64]) -> Option<NamedModel> {
    let named = NamedModel::of_rounds(steps);
    let mut order: Vec<usize> = (0..steps.len()).collect();
    order.sort_by(|&a, &b| weights[b].total_cmp(&weights[a]));
    let reordered: Vec<Step> = order.iter().map(|&i| steps[i].clone()).collect();
    steps.clone_from_slice(&reordered);
    named
}

/// How many noise thresholds (`noise`, –) a model's `gap` (–) stands above
/// the floor of a model that is right, at least 1: what a `none`'s
/// confidence is divided by the square root of.
fn noise_thresholds_above(gap: f64, noise: f64, null: NullLoss) -> f64 {
    ((gap - null.mean) / noise).max(1.0)
}

/// Prints a round's families, their picks and shares (`STICKSLIP_DEBUG`).
fn trace_round(
    round: usize,
    families: &[Family],
    predictions: &[(UnitLosses, UnitLosses, Vec<usize>)],
    pooled: &Contest,
    units: &[usize],
) {
    for (f, (losses, reference, picks)) in families.iter().zip(predictions) {
        let per_unit: Vec<String> = units
            .iter()
            .map(|u| {
                let l = losses.get(u).map_or(f64::NAN, |x| x.sum / x.scores as f64);
                let r = reference.get(u).map_or(f64::NAN, |x| x.sum / x.scores as f64);
                format!("{u}: {r:.2}->{l:.2}")
            })
            .collect();
        let picked: Vec<String> = picks.iter().map(|&p| format!("{} {:?}", f.pool[p].form, f.pool[p].values)).collect();
        eprintln!("round {round}: {} picks {picked:?}; by unit {}", f.effect, per_unit.join(", "));
    }
    for (f, (w, s)) in families.iter().zip(pooled.leads.iter().zip(&pooled.shares)) {
        eprintln!(
            "round {round}: {} [{}] fit {:.2} out-of-sample share {s:.3} leads {w:.3}",
            f.effect, f.form, f.best.gap_fit
        );
    }
    eprintln!("round {round}: gap {:.2} noise {:.2} fits {:.3}", pooled.gap, pooled.noise, pooled.fits);
}

/// The report's candidate for a family: its best full-data fit, what it
/// closes of the current model's gap in sample and out of sample, and how
/// often it won.
fn candidate_of(
    family: &Family,
    fitted: Fitted,
    cv: (f64, f64),
    wins: f64,
    current: &Fitted,
    data: &Data<'_>,
    null: NullLoss,
) -> Candidate {
    let (before, after) = pair_losses(&current.scores, &fitted.scores, data);
    let (g0, g) = (mean_loss(&before, before.keys().copied()), mean_loss(&after, after.keys().copied()));
    let (cv_gap, cv_share) = cv;
    let mut worst: Vec<&Score> = fitted.scores.iter().collect();
    worst.sort_by(|a, b| b.z.abs().total_cmp(&a.z.abs()));
    Candidate {
        effect: family.effect,
        form: family.form,
        gap_fit: g,
        shrink: if g0 > 0.0 { (g0 - g) / g0 } else { 0.0 },
        in_sample_share: (g0 - g) / (g0 - null.mean).max(1e-12),
        cv_share,
        heldout_shrink: if cv_gap > 0.0 { cv_share * (cv_gap - null.mean).max(0.0) / cv_gap } else { 0.0 },
        wins,
        refined: family.refined,
        parameters: family.parameters.clone(),
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
        model: fitted.model,
        scores: fitted.scores,
    }
}

/// Every family of a round as the report lists it, most wins first (then
/// the largest out-of-sample share).
fn candidates_of(
    families: &[Family],
    contest: &Contest,
    current: &Fitted,
    data: &Data<'_>,
    null: NullLoss,
) -> Vec<Candidate> {
    let mut out: Vec<Candidate> = families
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let fitted = Fitted { model: f.best.model.clone(), scores: f.best.scores.clone() };
            candidate_of(f, fitted, (contest.gap, contest.shares[i]), contest.leads[i], current, data, null)
        })
        .collect();
    out.sort_by(|a, b| b.wins.total_cmp(&a.wins).then(b.cv_share.total_cmp(&a.cv_share)));
    out
}

/// Out of sample, the models before an effect and with it, both refitted
/// without each fold (`before[k]`, `after[k]`): the losses at each fold's
/// units, both in one yardstick ([`pair_losses`]).
fn fold_pair_losses(before: &[Fitted], after: &[Fitted], data: &Data<'_>) -> (UnitLosses, UnitLosses) {
    fold_pair_losses_of(before, after, data, |_| true)
}

/// [`fold_pair_losses`] over the observables `keep` selects alone.
fn fold_pair_losses_of(
    before: &[Fitted],
    after: &[Fitted],
    data: &Data<'_>,
    keep: fn(Observable) -> bool,
) -> (UnitLosses, UnitLosses) {
    let (b, a): (Vec<UnitLosses>, Vec<UnitLosses>) =
        before.iter().zip(after).map(|(x, y)| pair_losses_of(&x.scores, &y.scores, data, keep)).unzip();
    (fold_predictions(&b, &data.folds), fold_predictions(&a, &data.folds))
}

/// The mean losses at `units` of a model before an effect and with it
/// (their scores), in one yardstick ([`pair_losses`]).
pub(crate) fn pair_gaps(
    before: &[Score],
    after: &[Score],
    data: &Data<'_>,
    units: impl Iterator<Item = usize> + Clone,
) -> (f64, f64) {
    let (b, a) = pair_losses(before, after, data);
    (mean_loss(&b, units.clone()), mean_loss(&a, units))
}
