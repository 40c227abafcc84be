//! The friction noise's shape and colour: non-Gaussian and coloured friction noise.

use super::*;

/// The forms of a non-Gaussian friction noise searched, started where the data point.
pub(super) fn non_gaussian_friction(effect: Effect, ctx: &Context<'_>) -> Vec<Variant> {
    let friction = ctx.has(Observable::FrictionMuMean);
    let mean_n0 = ctx.mean_load();
    if !friction {
        return Vec::new();
    }
    let skew = ctx.excess(Observable::FrictionResidualSkewness).unwrap_or(0.0);
    let sign = if skew < 0.0 { -1.0 } else { 1.0 };
    let non_gaussian = move |form: NonGaussianForm, p: &[f64]| NonGaussianFriction {
        form,
        strength: p[0],
        load_exponent: p[1],
        reference_force_n: mean_n0,
    };
    vec![
        Variant {
            effect,
            form: SearchedForm::Skew,
            params: vec![
                Param::log("strength", sign * 0.4, 1.8, -30.0, 30.0),
                Param::linear("load_exponent", 0.0, 1.0, -3.0, 3.0),
            ],
            apply: Box::new(move |m, p| {
                let mut m = m.clone();
                m.effects.non_gaussian_friction = Some(non_gaussian(NonGaussianForm::Skew, p));
                m
            }),
        },
        Variant {
            effect,
            form: SearchedForm::TukeyH,
            params: vec![
                Param::log("strength", 0.08, 1.6, 0.005, 0.2),
                Param::linear("load_exponent", 0.0, 1.0, -3.0, 3.0),
            ],
            apply: Box::new(move |m, p| {
                let mut m = m.clone();
                m.effects.non_gaussian_friction = Some(non_gaussian(NonGaussianForm::TukeyH, p));
                m
            }),
        },
    ]
}

/// The forms of a coloured friction noise searched, started where the data point.
pub(super) fn coloured_friction_noise(effect: Effect, ctx: &Context<'_>) -> Vec<Variant> {
    let friction = ctx.has(Observable::FrictionMuMean);
    let interval = ctx.data.sample_interval_s;
    if !friction {
        return Vec::new();
    }
    // An AR(1) part with correlation ρ per sample shows as ρ at lag 1
    // and ρ^10 at lag 10 (times its share): their ratio gives ρ.
    let lag1 = ctx.measured(Observable::FrictionResidualAutocorrLag1).unwrap_or(0.0);
    let lag10 = ctx.measured(Observable::FrictionResidualAutocorrLag10).unwrap_or(0.0);
    let rho = if lag1 > 0.05 && lag10 > 0.0 { (lag10 / lag1).powf(1.0 / 9.0).clamp(0.3, 0.995) } else { 0.8 };
    let tau = (-interval / rho.ln()).clamp(2.0 * interval, 200.0 * interval);
    let share = if lag1 > 0.0 { (lag1 / rho).clamp(0.2, 1.0) } else { 1.0 };
    let coloured = |form: SearchedForm, colour: ColourForm, params: Vec<Param>| Variant {
        effect,
        form,
        params,
        apply: Box::new(move |m, p| {
            let mut m = m.clone();
            m.effects.coloured_friction_noise =
                Some(ColouredFrictionNoise { form: colour, correlation_time_s: p[0], coloured_share: p[1] });
            m
        }),
    };
    vec![
        coloured(
            SearchedForm::Ar1,
            ColourForm::Ar1,
            vec![
                Param::log("correlation_time_s", tau, 2.0, interval, 500.0 * interval),
                Param::linear("coloured_share", share, 0.25, 0.05, 1.0),
            ],
        ),
        // A spectrum with two corners (τc and 10 τc, no white part): a
        // noise correlated over several time scales, which one AR(1)
        // can only mimic by running to its longest time, widening the
        // response where the data do not.
        coloured(
            SearchedForm::FastSlow,
            ColourForm::FastSlow,
            vec![
                Param::log("correlation_time_s", (tau / 3.0).max(interval), 2.0, interval, 50.0 * interval),
                Param::linear("slow_share", 0.5, 0.2, 0.05, 0.95),
            ],
        ),
    ]
}
