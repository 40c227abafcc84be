//! The selection's bookkeeping: which model the verdict reports.

use super::{FoldResult, Step, in_report_order};
use crate::diagnose::Candidate;
use crate::diagnose::candidates::SearchedForm;
use crate::diagnose::search::fit::Fitted;
use crate::engine::effects::{ColourForm, ColouredFrictionNoise, LoadDependentFriction, LoadForm};
use crate::engine::{Effect, Model};

/// A named step whose full-data model is `model` and whose one fold
/// refit is `model` too.
fn step(effect: Effect, model: Model) -> Step {
    let candidate = Candidate {
        effect,
        form: SearchedForm::Linear,
        gap_fit: 1.0,
        shrink: 0.5,
        in_sample_share: 0.5,
        cv_share: 0.5,
        heldout_shrink: 0.5,
        wins: 1.0,
        refined: true,
        parameters: Default::default(),
        unexplained: Vec::new(),
        model: model.clone(),
        scores: Vec::new(),
    };
    let after = Fitted { model, scores: Vec::new() };
    Step { candidate, confidence: 0.5, share: 0.5, folds: vec![FoldResult { after, gap_before: 2.0, gap_after: 1.0 }] }
}

/// Each round adds its effect to the model before it, and the verdict
/// reports the effect that shapes the response most first. Where that is
/// the second one named, the model reported (the model file, the gap after
/// it, the fold models a withheld level is predicted by) must still be the
/// one with both: the first round's lacks the second effect.
#[test]
fn the_reported_model_carries_every_named_effect_whichever_leads() {
    let mut first = Model::default();
    first.effects.coloured_friction_noise =
        Some(ColouredFrictionNoise { form: ColourForm::Ar1, correlation_time_s: 0.03, coloured_share: 0.5 });
    let mut second = first.clone();
    second.effects.load_dependent_friction = Some(LoadDependentFriction {
        form: LoadForm::Power,
        strength: -0.25,
        curvature_per_n2: 0.0,
        reference_force_n: 8.0,
    });
    let both = |m: &Model| m.effects.has(Effect::ColouredFrictionNoise) && m.effects.has(Effect::LoadDependentFriction);
    for weights in [[0.2, 3.0], [3.0, 0.2]] {
        let mut steps = vec![
            step(Effect::ColouredFrictionNoise, first.clone()),
            step(Effect::LoadDependentFriction, second.clone()),
        ];
        let named = in_report_order(&mut steps, &weights).expect("two effects were named");
        let leader =
            if weights[1] > weights[0] { Effect::LoadDependentFriction } else { Effect::ColouredFrictionNoise };
        assert_eq!(steps[0].candidate.effect, leader, "the heavier response weight leads");
        assert!(both(&named.full.model), "the full-data model lacks an effect: {:?}", named.full.model.effects);
        assert!(named.folds.iter().all(|f| both(&f.model)), "a fold model lacks an effect");
    }
    assert!(in_report_order(&mut [], &[]).is_none(), "nothing named, no model");
}
