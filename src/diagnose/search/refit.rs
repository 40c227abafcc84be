//! A leading family refitted from scratch without each fold: what its
//! out-of-sample share and the verdict's fold checks are measured on.

use rayon::prelude::*;

use super::FoldSet;
use super::family::{Family, fold_variant};
use super::fit::{Fitted, Trial, coordinate_search, evaluate, law_can_stay};
use crate::diagnose::DiagnoseSettings;
use crate::diagnose::calibrate::converge_law;
use crate::diagnose::candidates::{Context, SearchedForm, variants};
use crate::diagnose::data::Data;
use crate::diagnose::score::gap_of;
use crate::diagnose::simulate::fits_per_task;
use crate::diagnose::tracing;
use crate::engine::Engine;
use crate::error::Result;

/// The family refitted without each fold in the form it is named by (its
/// best full-data fit's), from the member of that form its pool chose for
/// the fold ([`Family::fold_starts`], chosen on the fold's other units
/// alone): what the folds test is the model reported. A fold too small to
/// build that form is refitted in its closest stand-in
/// ([`Family::stand_in`]). With a few levels
/// every form fits the other levels about alike, and the one that happens
/// to fit them best need not extrapolate as the named one does (a two-term
/// adhesion law through two loads rises far more steeply below them than a
/// power law does). Scored on every unit. `None` where a fold's model
/// cannot be built or run.
pub(super) fn refit_folds(
    family: &Family,
    folds: &FoldSet<'_>,
    slope: f64,
    search: &DiagnoseSettings,
    engine: &Engine,
) -> Result<Option<Vec<Fitted>>> {
    let starts = family.fold_starts(&folds.data.folds);
    // Each fold's refit is independent of the others': side by side, then
    // read in order, so the first fold without a model decides as a loop
    // would have.
    let each: Vec<Result<Option<Fitted>>> = starts
        .par_iter()
        .with_min_len(fits_per_task(engine))
        .enumerate()
        .map(|(k, &member)| refit_fold(family, member, k, folds, slope, search, engine))
        .collect();
    let mut out = Vec::new();
    for fitted in each {
        match fitted? {
            Some(f) => out.push(f),
            None => return Ok(None),
        }
    }
    Ok(Some(out))
}

/// Fold `k` refitted from pool member `member`: its form at its parameters
/// put on the current model's fold refit, with the friction law
/// recalibrated to the fold's own measured law and carried until it stops
/// lowering the fold's fitting gap. `None` where the model cannot be
/// built or run.
fn refit_fold(
    family: &Family,
    member: usize,
    k: usize,
    folds: &FoldSet<'_>,
    slope: f64,
    search: &DiagnoseSettings,
    engine: &Engine,
) -> Result<Option<Fitted>> {
    let member = &family.pool[member];
    let (view, base): (&Data<'_>, &Fitted) = (&folds.views[k], &folds.current[k]);
    let ctx = Context::new(view, &base.model, &base.scores, search.warmup_cycles).with_position_start(
        &[family.effect],
        engine,
        search,
    )?;
    let built = fold_variant(family.effect, member.form, &member.values, &ctx).or_else(|| {
        let forms: Vec<SearchedForm> = variants(family.effect, &ctx).iter().map(|v| v.form).collect();
        let stand_in = &family.pool[family.stand_in(&forms)?];
        fold_variant(family.effect, stand_in.form, &stand_in.values, &ctx)
    });
    let Some((variant, values)) = built else {
        return Ok(None);
    };
    let Some(mut start) = evaluate(&variant, &values, &base.model, &base.scores, 1, slope, view, search, engine)?
    else {
        return Ok(None);
    };
    // Where the pool's parameters with the fold's own law fit the fold's
    // units no better than the model before the effect, they are searched
    // again there, from the best of three starts: the law recalibrated at
    // those parameters, the law the fold's model already has (as a coarse
    // fit tries both), and the law the family's full-data fit calibrated
    // with the effect on, recalibrated to the fold's records. One
    // calibration step can hand part of an effect's signature to the law
    // (a friction spread cut by half where a harmonic of the normal force
    // adds its own), a basin the search, which keeps the law it starts
    // from, never leaves. And the fold's law can hold part of the effect in
    // its own terms (a Stribeck peak standing in for a stiction): the
    // effect put on it counts that part twice, the block barely slips, and
    // its records' law is then no guide for a step back.
    if start.objective >= 1.0 {
        if law_can_stay(view)
            && let Some(kept) = evaluate(&variant, &values, &base.model, &base.scores, 0, slope, view, search, engine)?
            && kept.objective < start.objective
        {
            start = kept;
        }
        let mut with_law = base.model.clone();
        with_law.friction = family.best.model.friction.clone();
        if with_law.friction != base.model.friction
            && let Some(t) = evaluate(&variant, &values, &with_law, &base.scores, 1, slope, view, search, engine)?
            && t.objective < start.objective
        {
            start = t;
        }
        start = coordinate_search(
            &variant.params,
            start,
            |b: &Trial, v: &[f64]| evaluate(&variant, v, &b.carry, &base.scores, 0, slope, view, search, engine),
            &mut |_| {},
        )?;
    }
    let (model, scores) = match converge_law(start.model, start.scores, view, search, engine) {
        Err(e) if e.cannot_run() => return Ok(None),
        other => other?,
    };
    if tracing() {
        eprintln!(
            "fold {k} ({}): {} [{}] {:?}: fit {:.2} held out {:.2}",
            view.folds.folds[k].label,
            family.effect,
            variant.form,
            values,
            gap_of(&scores, false),
            gap_of(&scores, true)
        );
    }
    Ok(Some(Fitted { model, scores }))
}
