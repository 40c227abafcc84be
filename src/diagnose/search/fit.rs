//! Fitting one form of an effect: trials (a model with the form's
//! parameters, its friction law recalibrated), the coordinate search over
//! the parameters, and the polish of the best trial on every replicate.

use crate::diagnose::calibrate::{calibrate_and_score, converge_law, law_step};
use crate::diagnose::candidates::{Param, Variant};
use crate::diagnose::data::Data;
use crate::diagnose::score::{Scope, Score, add_heldout, count_of, gap_noise, gap_of, score};
use crate::diagnose::search::cv::{mean_loss, pair_losses};
use crate::diagnose::{DiagnoseSettings, tracing};
use crate::engine::{Engine, Model};
use crate::error::Result;

/// One trial: a form's parameter values on top of a model, the friction
/// law recalibrated, scored on the units of the view it was fitted on.
#[derive(Clone, Debug)]
pub(crate) struct Trial {
    pub(crate) values: Vec<f64>,
    pub(crate) model: Model,
    pub(crate) scores: Vec<Score>,
    /// Mean Huber loss over the view's fitting units (its own z-scores), –.
    pub(crate) gap_fit: f64,
    /// What the search minimises: its loss over the view's fitting units
    /// as a share of the loss there of the model it is added to, both in its
    /// yardstick ([`crate::diagnose::search::cv::pair_losses`]), –: 1 is no
    /// change. A trial cannot lower it by widening its simulated spreads.
    pub(crate) objective: f64,
    /// The model with its friction law moved one more step from this
    /// trial's own records: where the next trials of a search start, so the
    /// law follows the search without a simulation of its own per trial.
    pub(crate) carry: Model,
}

/// A model with its scores.
#[derive(Clone, Debug)]
pub(crate) struct Fitted {
    pub(crate) model: Model,
    pub(crate) scores: Vec<Score>,
}

impl From<Trial> for Fitted {
    fn from(t: Trial) -> Fitted {
        Fitted { model: t.model, scores: t.scores }
    }
}

/// Whether a trial on `data` can be scored at the law it starts from
/// (`law_steps` 0 in [`evaluate`]): only where the records carry force
/// channels. Without them the friction level is solved at every trial, so
/// the unstepped start is the stepped one evaluated again.
pub(crate) fn law_can_stay(data: &Data<'_>) -> bool {
    data.measured_law.is_some()
}

/// Evaluates one set of parameter values on top of `base` on the view
/// `data`, its friction law first calibrated with `law_steps` steps (the
/// indirect inference, or the level's solve without force channels; 0:
/// scored at `base`'s law, as a search's trials are,
/// each starting from the [`Trial::carry`] of the point it moves from), its
/// objective measured against `reference` (the scores of the model the
/// effect is added to); `None` when the values give no valid model, or a
/// model the oscillator cannot run (friction turned negative, say): such a
/// trial is passed over like an invalid one instead of ending the diagnosis.
#[allow(clippy::too_many_arguments)]
pub(crate) fn evaluate(
    variant: &Variant,
    values: &[f64],
    base: &Model,
    reference: &[Score],
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
    // Without force channels the friction level is solved on the response
    // at every trial: a summary table's mean peaks are known to a few
    // hundred periods' precision, and a level carried from the last trial
    // by one Newton step leaves them tens of spreads off.
    let outcome = if law_steps == 0 && law_can_stay(data) {
        score(engine, &trial, data, settings, Scope::Fitting).map(|scores| (trial, scores))
    } else {
        calibrate_and_score(&trial, data, settings, engine, Some(slope), law_steps.max(1), Scope::Fitting)
            .map(|(m, s, _)| (m, s))
    };
    let (model, scores) = match outcome {
        Err(e) if e.cannot_run() => {
            if tracing() {
                eprintln!("{} [{}] {values:?}: {e}", variant.effect, variant.form);
            }
            return Ok(None);
        }
        other => other?,
    };
    let carry = law_step(&model, &scores, slope, data, settings, engine)?;
    let gap_fit = gap_of(&scores, false);
    let objective = fitting_ratio(reference, &scores, data);
    if tracing() {
        let f = &model.friction;
        eprintln!(
            "{} [{}] {values:?}: a {:.4} b {:.4} c {:.2} d {:.4} sigma {:.4} gap {gap_fit:.2} ratio {objective:.4} | {}",
            variant.effect,
            variant.form,
            f.a,
            f.b,
            f.c,
            f.d,
            f.sigma,
            observable_changes(reference, &scores)
        );
    }
    Ok(Some(Trial { values: values.to_vec(), model, scores, gap_fit, objective, carry }))
}

/// The loss of `after` over the fitting units of the view `data` as a share
/// of that of `before`, both in `after`'s yardstick ([`pair_losses`]), –.
pub(crate) fn fitting_ratio(before: &[Score], after: &[Score], data: &Data<'_>) -> f64 {
    let (b, a) = pair_losses(before, after, data);
    let fitting = || (0..data.units.len()).filter(|&u| !data.units[u].heldout);
    mean_loss(&a, fitting()) / mean_loss(&b, fitting()).max(1e-12)
}

/// Moves per parameter in one direction in the coordinate search (of 1, 2,
/// 4, … steps: up to 7 steps away), besides the first probe of the other
/// direction and one move back from an overshoot.
const STEPS_PER_PARAM: usize = 3;

/// A coordinate search from `start`: each parameter in turn is stepped up
/// or down while that helps, by moves that double (at most
/// [`STEPS_PER_PARAM`] in one direction), then the first parameter once more
/// at half its step. `evaluate(best, values)` gives the point at `values`
/// starting from the current best (`None`: no valid model there); a move is
/// kept when it lowers the objective. Every point evaluated is passed to
/// `seen` (the cross-validation chooses among them).
pub(crate) fn coordinate_search(
    params: &[Param],
    start: Trial,
    mut evaluate: impl FnMut(&Trial, &[f64]) -> Result<Option<Trial>>,
    seen: &mut dyn FnMut(&Trial),
) -> Result<Trial> {
    let mut best = start;
    // Values already tried from the current best and rejected: a move
    // clamped at a bound can land on one again, and the same values on the
    // same best give the same point (the simulation is deterministic).
    let mut rejected: Vec<Vec<f64>> = Vec::new();
    let mut try_move = |best: &mut Trial, i: usize, k: f64| -> Result<bool> {
        let mut values = best.values.clone();
        values[i] = params[i].moved(values[i], k);
        if values[i] == best.values[i] || rejected.contains(&values) {
            return Ok(false);
        }
        match evaluate(best, &values)? {
            Some(t) => {
                seen(&t);
                if t.objective < best.objective {
                    *best = t;
                    rejected.clear();
                    Ok(true)
                } else {
                    rejected.push(values);
                    Ok(false)
                }
            }
            None => {
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
        // size that overshot: a start several steps off is reached in a few
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
        // is tried.
        if !overshot && size > 1.0 {
            try_move(&mut best, i, -direction * size / 2.0)?;
        }
    }
    if !params.is_empty() && !try_move(&mut best, 0, 0.5)? {
        try_move(&mut best, 0, -0.5)?;
    }
    Ok(best)
}

/// A form's best trial polished on every replicate: one more step of the
/// law (the extra replicates' law differs from the search's by their
/// sampling noise), then the law carried to where this effect's data imply
/// it, so the effect is compared (and the next round searched) from a law
/// that has stopped moving; unless that ends fitting worse, beyond the
/// gap's noise, than the searched law scored on the same replicates (a
/// law step reads the measured law against the simulated one as if the
/// trial's effect had the data's form; where it has another, the effect's
/// structured residual can move the law the wrong way). The scores cover
/// every unit of the view. `None` where the model diverges.
pub(crate) fn polish(
    t: &Trial,
    slope: f64,
    data: &Data<'_>,
    settings: &DiagnoseSettings,
    engine: &Engine,
) -> Result<Option<Trial>> {
    let (model, scores, _) = match calibrate_and_score(&t.model, data, settings, engine, Some(slope), 1, Scope::Fitting)
    {
        Err(e) if e.cannot_run() => return Ok(None),
        other => other?,
    };
    let (model, scores) = converge_law(model, scores, data, settings, engine)?;
    let searched_scores = match score(engine, &t.model, data, settings, Scope::Fitting) {
        Err(e) if e.cannot_run() => None,
        other => Some(other?),
    };
    let (model, scores) = match searched_scores {
        Some(searched) if gap_of(&scores, false) - gap_of(&searched, false) > gap_noise(count_of(&scores, false)) => {
            let searched = add_heldout(engine, &t.model, data, settings, searched)?;
            (t.model.clone(), searched)
        }
        _ => (model, scores),
    };
    Ok(Some(Trial {
        gap_fit: gap_of(&scores, false),
        objective: t.objective,
        values: t.values.clone(),
        carry: model.clone(),
        model,
        scores,
    }))
}

/// The observables whose mean loss changes most from `before` to `after`
/// (each in `after`'s yardstick), for tracing.
fn observable_changes(before: &[Score], after: &[Score]) -> String {
    use std::collections::BTreeMap;
    let key = |s: &Score| (s.unit, s.observable);
    let scale: BTreeMap<_, f64> = after.iter().map(|s| (key(s), s.scale)).collect();
    let mut by: BTreeMap<crate::diagnose::observable::Observable, (f64, f64, usize)> = BTreeMap::new();
    let after_z: BTreeMap<_, f64> = after.iter().map(|s| (key(s), s.z)).collect();
    for b in before {
        let (Some(&r), Some(&za)) = (scale.get(&key(b)), after_z.get(&key(b))) else { continue };
        let zb = if r > 0.0 && b.scale > 0.0 { b.z * b.scale / r.max(0.1 * b.scale) } else { b.z };
        let e = by.entry(b.observable).or_insert((0.0, 0.0, 0));
        e.0 += crate::diagnose::search::cv::loss(zb);
        e.1 += crate::diagnose::search::cv::loss(za);
        e.2 += 1;
    }
    let mut v: Vec<_> = by.into_iter().map(|(o, (b, a, n))| (o, b / n as f64, a / n as f64)).collect();
    v.sort_by(|x, y| (y.2 - y.1).abs().total_cmp(&(x.2 - x.1).abs()));
    v.iter().take(5).map(|(o, b, a)| format!("{o} {b:.2}->{a:.2}")).collect::<Vec<_>>().join(", ")
}
