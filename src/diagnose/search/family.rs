//! A round's families: every form of each effect fitted on top of the
//! current model, coarsely for every family and in full for the closest
//! ones, each trial kept in its family's pool for cross-validation.

use std::collections::BTreeMap;

use crate::diagnose::DiagnoseSettings;
use crate::diagnose::candidates::{Context, SearchedForm, Variant, bent, variants};
use crate::diagnose::data::{Data, Folds};
use crate::diagnose::search::cv::{UnitLosses, fold_picks, pair_losses};
use crate::diagnose::search::fit::{Fitted, Trial, coordinate_search, evaluate, law_can_stay};
use crate::diagnose::simulate::fits_per_task;
use crate::engine::{Effect, Engine, Model};
use crate::error::Result;
use rayon::prelude::*;

/// Families searched in full in a round, after every family's coarse fit:
/// those whose coarse fit came closest to the data.
const REFINED_FAMILIES: usize = 2;

/// One member of a family's pool: a form at some parameter values, its
/// losses at every unit and the current model's in the same yardstick
/// ([`pair_losses`]).
#[derive(Clone, Debug)]
pub(super) struct Member {
    pub(super) form: SearchedForm,
    pub(super) values: Vec<f64>,
    /// The trial's objective on the full data (comparable across forms).
    pub(super) objective: f64,
    pub(super) losses: UnitLosses,
    pub(super) reference: UnitLosses,
}

impl Member {
    /// A member made of a trial of `form` on top of `current`.
    fn of(form: SearchedForm, trial: &Trial, current: &Fitted, data: &Data<'_>) -> Member {
        let (reference, losses) = pair_losses(&current.scores, &trial.scores, data);
        Member { form, values: trial.values.clone(), objective: trial.objective, losses, reference }
    }
}

/// What one effect's fits gave in a round.
pub(super) struct Family {
    pub(super) effect: Effect,
    /// The best full-data trial and its form.
    pub(super) best: Trial,
    pub(super) form: SearchedForm,
    pub(super) parameters: BTreeMap<String, f64>,
    /// Every trial, any form.
    pub(super) pool: Vec<Member>,
    /// Whether it was searched in full (else only its coarse fit).
    pub(super) refined: bool,
}

impl Family {
    /// Each member's losses and the current model's in the same yardstick.
    pub(super) fn pool_losses(&self) -> Vec<(UnitLosses, UnitLosses)> {
        self.pool.iter().map(|m| (m.losses.clone(), m.reference.clone())).collect()
    }

    /// Where each fold's refit starts: the member of the family's named
    /// form (its best full-data fit's) that fits the fold's other units
    /// best ([`fold_picks`]); of any form where that one has no member.
    pub(super) fn fold_starts(&self, folds: &Folds) -> Vec<usize> {
        let pool = self.pool_losses();
        let named = fold_picks(&pool, folds, |i| self.pool[i].form == self.form);
        if named.is_empty() { fold_picks(&pool, folds, |_| true) } else { named }
    }

    /// The member a fold that cannot build the named form (`buildable`:
    /// the forms it can) is refitted from: the best full-data fit among
    /// those forms. A fold that withholds one of three loads keeps two,
    /// through which every one-parameter load dependence passes alike, so
    /// the fold's own units cannot choose among them; what they predict at
    /// the withheld load differs with their curvature, and the form whose
    /// curvature the full data favour is the named form's closest stand-in
    /// (a straight line through 4 and 16 N misses a convex load dependence
    /// at 8 N by its chord's error, a power law far less).
    pub(super) fn stand_in(&self, buildable: &[SearchedForm]) -> Option<usize> {
        (0..self.pool.len())
            .filter(|&i| buildable.contains(&self.pool[i].form))
            .min_by(|&a, &b| self.pool[a].objective.total_cmp(&self.pool[b].objective))
    }
}

/// The form `form` of `effect` at `values` as the context `ctx` of a fold
/// builds it (the bent load dependence from the linear one), with the
/// values it takes, if it can build it: a fold that withholds one of three
/// loads cannot bend a line through the other two
/// ([`Family::stand_in`] is refitted there instead).
pub(super) fn fold_variant(
    effect: Effect,
    form: SearchedForm,
    values: &[f64],
    ctx: &Context<'_>,
) -> Option<(Variant, Vec<f64>)> {
    variants(effect, ctx)
        .into_iter()
        .find(|v| v.form == form)
        .or_else(|| bent(effect, SearchedForm::Linear, values, ctx).filter(|v| v.form == form))
        .map(|v| (v, values.to_vec()))
}

/// Every family's coarse fit on the full data (each form at the start the
/// data point to), then a full search of every form of the
/// [`REFINED_FAMILIES`] whose coarse fits came closest; every trial joins
/// its family's pool.
#[allow(clippy::too_many_arguments)]
pub(super) fn round(
    current: &Fitted,
    named: &[Effect],
    slope: f64,
    data: &Data<'_>,
    search: &DiagnoseSettings,
    engine: &Engine,
    progress: &mut dyn FnMut(&str),
) -> Result<Vec<Family>> {
    let unnamed: Vec<Effect> = Effect::ALL.into_iter().filter(|e| !named.contains(e)).collect();
    let ctx = Context::new(data, &current.model, &current.scores, search.warmup_cycles)
        .with_position_start(&unnamed, engine, search)?;
    let searched: Vec<(Effect, Vec<Variant>)> =
        unnamed.into_iter().map(|e| (e, variants(e, &ctx))).filter(|(_, forms)| !forms.is_empty()).collect();
    let every_form: Vec<&Variant> = searched.iter().flat_map(|(_, forms)| forms).collect();
    progress(&format!(
        "trying every family: a coarse fit of each of {} forms of {} effects",
        every_form.len(),
        searched.len()
    ));
    // The coarse fits are independent of each other (each starts from the
    // current model, and a trial's records depend only on its model), so
    // they run side by side ([`fits_per_task`]): on a machine with many
    // cores a round is not a queue of small jobs. (Trace lines of
    // side-by-side trials interleave.)
    let coarse: Vec<Vec<Trial>> = every_form
        .par_iter()
        .with_min_len(fits_per_task(engine))
        .map(|v| coarse_fit(v, current, slope, data, search, engine))
        .collect::<Result<_>>()?;
    let mut coarse = coarse.into_iter();
    let mut families: Vec<(Family, Vec<Option<Trial>>)> = Vec::new();
    for (effect, forms) in &searched {
        let mut starts: Vec<Option<Trial>> = Vec::new();
        let mut pool = Vec::new();
        for v in forms {
            let trials = coarse.next().expect("a coarse fit per form");
            pool.extend(trials.iter().map(|t| Member::of(v.form, t, current, data)));
            starts.push(trials.into_iter().min_by(|a, b| a.objective.total_cmp(&b.objective)));
        }
        let objective = |i: usize| starts[i].as_ref().map_or(f64::INFINITY, |t| t.objective);
        let best = (0..forms.len()).min_by(|&a, &b| objective(a).total_cmp(&objective(b)));
        let Some((best, Some(trial))) = best.map(|i| (i, starts[i].clone())) else { continue };
        let (form, parameters) = (forms[best].form, forms[best].describe(&trial.values));
        families.push((Family { effect: *effect, best: trial, form, parameters, pool, refined: false }, starts));
    }
    families.sort_by(|a, b| a.0.best.objective.total_cmp(&b.0.best.objective));
    // Every round searches every form of the closest family and the best
    // form of the next: a further effect is judged as the first is, so it
    // is fitted as closely. The searches are independent: side by side too.
    let refined = families.len().min(REFINED_FAMILIES);
    for (rank, (family, starts)) in families.iter_mut().take(refined).enumerate() {
        progress(&format!("searching {} in full", family.effect));
        if rank > 0 {
            // Only the form whose coarse fit came closest.
            let o = |s: &Option<Trial>| s.as_ref().map_or(f64::INFINITY, |t| t.objective);
            let best = (0..starts.len()).min_by(|&a, &b| o(&starts[a]).total_cmp(&o(&starts[b]))).unwrap_or(0);
            for (i, s) in starts.iter_mut().enumerate() {
                if i != best {
                    *s = None;
                }
            }
        }
    }
    families[..refined]
        .par_iter_mut()
        .with_min_len(fits_per_task(engine))
        .enumerate()
        .map(|(rank, (family, starts))| {
            let starts = std::mem::take(starts);
            refine(family, starts, rank > 0, current, slope, &ctx, data, search, engine)
        })
        .collect::<Result<Vec<()>>>()?;
    Ok(families.into_iter().map(|(f, _)| f).collect())
}

/// A form's coarse fit: its start (the parameters the data point to) at the
/// current model's friction law and with the law stepped once with it (a
/// law step reads the measured law against the simulated one as if the
/// form were the data's, and a form of another shape can move the law the
/// wrong way: both are tried), then from the better of the two its first
/// parameter two steps either way (a start that overshoots or falls short
/// by a factor of a few is not taken for the form's best). Every trial.
fn coarse_fit(
    v: &Variant,
    current: &Fitted,
    slope: f64,
    data: &Data<'_>,
    search: &DiagnoseSettings,
    engine: &Engine,
) -> Result<Vec<Trial>> {
    let start = v.start();
    let mut out = Vec::new();
    let mut best: Option<(Model, f64)> = None;
    for steps in [0, 1] {
        if steps == 0 && !law_can_stay(data) {
            continue;
        }
        if let Some(t) = evaluate(v, &start, &current.model, &current.scores, steps, slope, data, search, engine)? {
            // The base the moves below start from: the unstepped law, or
            // the stepped one carried on.
            let base = if steps == 0 { current.model.clone() } else { t.carry.clone() };
            if best.as_ref().is_none_or(|b| t.objective < b.1) {
                best = Some((base, t.objective));
            }
            out.push(t);
        }
    }
    let (Some((base, _)), Some(p)) = (best, v.params.first()) else { return Ok(out) };
    for k in [-2.0, 2.0] {
        let mut values = start.clone();
        values[0] = p.moved(values[0], k);
        if values[0] == start[0] {
            continue;
        }
        if let Some(t) = evaluate(v, &values, &base, &current.scores, 0, slope, data, search, engine)? {
            out.push(t);
        }
    }
    Ok(out)
}

/// The full search of every form of a family from its coarse fit
/// (`starts`, one trial per form in the order of its variants; with
/// `given_only`, only the forms that have one; a linear load dependence
/// that fitted is then bent), every trial joining the pool.
///
/// The forms' searches are independent of each other (each from its own
/// start on the current model), so they run side by side
/// ([`fits_per_task`]): a trial's ensembles are too small to keep every
/// core busy alone. Their outcomes are merged in the forms' order, and the
/// bent forms searched after all the others, so the pool and the best are
/// those of the forms searched one after another.
#[allow(clippy::too_many_arguments)]
fn refine(
    family: &mut Family,
    starts: Vec<Option<Trial>>,
    given_only: bool,
    current: &Fitted,
    slope: f64,
    ctx: &Context<'_>,
    data: &Data<'_>,
    search: &DiagnoseSettings,
    engine: &Engine,
) -> Result<()> {
    let mut batch: Vec<(Variant, Option<Trial>)> = variants(family.effect, ctx).into_iter().zip(starts).collect();
    // Where only the given starts are searched, a form without one is
    // passed over (a bent form, searched below, has none and is searched
    // from its own start).
    if given_only {
        batch.retain(|(_, start)| start.is_some());
    }
    while !batch.is_empty() {
        let (forms, starts): (Vec<Variant>, Vec<Option<Trial>>) = batch.into_iter().unzip();
        let searched: Vec<Option<(Vec<Member>, Trial)>> = forms
            .par_iter()
            .zip(starts)
            .with_min_len(fits_per_task(engine))
            .map(|(variant, start)| search_form(variant, start, current, slope, data, search, engine))
            .collect::<Result<_>>()?;
        let mut bends = Vec::new();
        for (variant, outcome) in forms.iter().zip(searched) {
            let Some((seen, best)) = outcome else { continue };
            family.pool.extend(seen);
            let bend = (best.objective < 1.0).then(|| bent(family.effect, variant.form, &best.values, ctx)).flatten();
            if best.objective < family.best.objective {
                family.parameters = variant.describe(&best.values);
                family.form = variant.form;
                family.best = best;
            }
            bends.extend(bend.map(|b| (b, None)));
        }
        batch = bends;
    }
    family.refined = true;
    Ok(())
}

/// One form's full search: the coordinate search from `start` (else from
/// the form's own start, its law stepped once), each trial as a member of
/// the pool and the best; `None` where the form gives no valid model at
/// its start.
fn search_form(
    variant: &Variant,
    start: Option<Trial>,
    current: &Fitted,
    slope: f64,
    data: &Data<'_>,
    search: &DiagnoseSettings,
    engine: &Engine,
) -> Result<Option<(Vec<Member>, Trial)>> {
    let start = match start {
        Some(t) => t,
        None => {
            let own = variant.start();
            match evaluate(variant, &own, &current.model, &current.scores, 1, slope, data, search, engine)? {
                Some(t) => t,
                None => return Ok(None),
            }
        }
    };
    let mut seen: Vec<Member> = Vec::new();
    let mut record = |t: &Trial| seen.push(Member::of(variant.form, t, current, data));
    let best = coordinate_search(
        &variant.params,
        start,
        |b: &Trial, v: &[f64]| evaluate(variant, v, &b.carry, &current.scores, 0, slope, data, search, engine),
        &mut record,
    )?;
    Ok(Some((seen, best)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::search::cv::UnitLoss;
    use crate::diagnose::search::cv::tests::one_unit_folds;

    /// A member of `form` with these losses at units 0, 1, 2 (the current
    /// model's 5 at each).
    fn member(form: SearchedForm, losses: [f64; 3]) -> Member {
        let at = |l: &[f64]| l.iter().enumerate().map(|(u, &l)| (u, UnitLoss::whole(l, 1))).collect();
        Member {
            form,
            values: vec![losses[0]],
            objective: losses.iter().sum(),
            losses: at(&losses),
            reference: at(&[5.0; 3]),
        }
    }

    fn family(form: SearchedForm, pool: Vec<Member>) -> Family {
        let model = Model::paper_rig(&[]).expect("the paper's rig");
        let best =
            Trial { values: Vec::new(), carry: model.clone(), model, scores: Vec::new(), gap_fit: 0.0, objective: 0.5 };
        Family { effect: Effect::LoadDependentFriction, best, form, parameters: BTreeMap::new(), pool, refined: true }
    }

    /// Each fold's refit starts from the named form's member that fits the
    /// other folds best, though another form's member fits them better;
    /// from any form's where the named one has no member.
    #[test]
    fn fold_refits_start_from_the_named_form() {
        let folds = one_unit_folds(3);
        let pool = vec![
            member(SearchedForm::Adhesion, [0.0, 0.0, 0.0]),
            member(SearchedForm::Power, [1.0, 3.0, 4.0]),
            member(SearchedForm::Power, [5.0, 2.0, 1.0]),
        ];
        assert_eq!(family(SearchedForm::Power, pool.clone()).fold_starts(&folds), vec![2, 1, 1]);
        assert_eq!(family(SearchedForm::Linear, pool).fold_starts(&folds), vec![0, 0, 0]);
    }

    /// A fold that cannot build the named (bent) form is refitted from the
    /// best full-data fit among the forms it can build, whatever fits the
    /// fold's own units.
    #[test]
    fn a_fold_without_the_named_form_takes_its_closest_buildable_stand_in() {
        let pool = vec![
            member(SearchedForm::Quadratic, [0.0, 0.0, 0.0]),
            member(SearchedForm::Linear, [1.0, 1.0, 3.0]),
            member(SearchedForm::Power, [1.0, 2.0, 1.0]),
            member(SearchedForm::Adhesion, [4.0, 0.0, 4.0]),
        ];
        let f = family(SearchedForm::Quadratic, pool);
        let one_parameter = [SearchedForm::Linear, SearchedForm::Power, SearchedForm::Adhesion, SearchedForm::Scaled];
        assert_eq!(f.stand_in(&one_parameter), Some(2));
        assert_eq!(f.stand_in(&[SearchedForm::Linear, SearchedForm::Adhesion]), Some(1));
        assert_eq!(f.stand_in(&[SearchedForm::Scaled]), None);
    }
}
