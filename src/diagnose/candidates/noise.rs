//! The friction noise's shape and colour: non-Gaussian and coloured friction noise.

use super::*;
use crate::engine::effects::{POLYNOMIAL_REACH, polynomial_linear, polynomial_within_reach};

/// The forms of a non-Gaussian friction noise searched, started where the data point.
pub(super) fn non_gaussian_friction(effect: Effect, ctx: &Context<'_>) -> Vec<Variant> {
    let friction = ctx.has(Observable::FrictionMuMean);
    let mean_n0 = ctx.mean_load();
    if !friction {
        return Vec::new();
    }
    let skew = ctx.excess(Observable::FrictionResidualSkewness).unwrap_or(0.0);
    let sign = if skew < 0.0 { -1.0 } else { 1.0 };
    // The polynomial starts where its own quantile shape is the excess
    // the data show over the model (the data's sensor noise dilutes it,
    // so the search moves on from there).
    let tails = ctx.excess(Observable::FrictionResidualTailWeight).unwrap_or(0.0);
    let (c0, d0) = polynomial_with_shape(skew, tails);
    let non_gaussian = move |form: NonGaussianForm, strength: f64, cubic: f64, load_exponent: f64| {
        NonGaussianFriction { form, strength, cubic, load_exponent, reference_force_n: mean_n0 }
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
                m.effects.non_gaussian_friction = Some(non_gaussian(NonGaussianForm::Skew, p[0], 0.0, p[1]));
                m
            }),
        },
        // Skew and tails set apart, so a noise skewed with light tails (two
        // contact states, say) or heavy-tailed without skew is reached by one
        // form; the search keeps the pair inside the form's range by
        // shrinking it along its ray.
        Variant {
            effect,
            form: SearchedForm::Polynomial,
            params: vec![
                Param::linear("strength", c0, 0.03, -0.7, 0.7),
                Param::linear("cubic", d0, 0.015, -0.25, 0.25),
                Param::linear("load_exponent", 0.0, 1.0, -3.0, 3.0),
            ],
            apply: Box::new(move |m, p| {
                let (c, d) = polynomial_within_reach(p[0], p[1]);
                let mut m = m.clone();
                m.effects.non_gaussian_friction = Some(non_gaussian(NonGaussianForm::Polynomial, c, d, p[2]));
                m
            }),
        },
    ]
}

/// The polynomial noise's quantile shape: Kelly's skewness and the excess
/// tail weight (as the features measure them) of the engine's transform,
/// read off the transform of a standard normal's quantiles (it keeps their
/// order where it rises, which [`polynomial_with_shape`] keeps it doing).
fn polynomial_shape(c: f64, d: f64) -> (f64, f64) {
    const Z90: f64 = 1.281_551_565_544_600_4;
    const Z75: f64 = 0.674_489_750_196_081_7;
    const Z975: f64 = 1.959_963_984_540_054;
    let x = |z: f64| crate::engine::cpu::effects::non_gaussian(NonGaussianForm::Polynomial, c, d, z, 0.0);
    let (wide, mid) = (x(Z90) - x(-Z90), x(Z75) - x(-Z75));
    let skewness = (x(Z90) + x(-Z90) - 2.0 * x(0.0)) / wide;
    let tail = (x(Z975) - x(-Z975)) / mid / crate::diagnose::features::GAUSSIAN_TAIL_RATIO - 1.0;
    (skewness, tail)
}

/// The polynomial's (c, d) whose quantile shape is nearest (`skewness`,
/// `tail`), on a grid of steps 0.01 in c and 0.005 in d within the search's
/// range and where the transform rises over z in ±2.5.
fn polynomial_with_shape(skewness: f64, tail: f64) -> (f64, f64) {
    // The slope b + 2cz + 3dz² is least at an end of the range or at its
    // vertex z = −c/(3d).
    let rises = |c: f64, d: f64| {
        let slope = |z: f64| polynomial_linear(c, d) + 2.0 * c * z + 3.0 * d * z * z;
        let vertex = if d == 0.0 { 0.0 } else { (-c / (3.0 * d)).clamp(-2.5, 2.5) };
        [-2.5, vertex, 2.5].into_iter().all(|z| slope(z) > 0.0)
    };
    let mut best = (0.0, 0.0, f64::INFINITY);
    for i in -60..=60 {
        for j in -40..=50 {
            let (c, d) = (f64::from(i) * 0.01, f64::from(j) * 0.005);
            if 2.0 * c * c + 15.0 * d * d > POLYNOMIAL_REACH || !rises(c, d) {
                continue;
            }
            let (s, t) = polynomial_shape(c, d);
            let miss = (s - skewness).powi(2) + (t - tail).powi(2);
            if miss < best.2 {
                best = (c, d, miss);
            }
        }
    }
    (best.0, best.1)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_polynomial_starts_at_the_shape_asked_for() {
        let (s0, t0) = polynomial_shape(0.0, 0.0);
        assert!(s0.abs() < 1e-12 && t0.abs() < 1e-6, "a Gaussian's shape read as ({s0}, {t0})");
        for (c, d) in [(0.0, 0.0), (0.1, -0.03), (-0.1, 0.08), (0.0, 0.15), (0.2, 0.05)] {
            let (skewness, tail) = polynomial_shape(c, d);
            let (c1, d1) = polynomial_with_shape(skewness, tail);
            let (s1, t1) = polynomial_shape(c1, d1);
            assert!(
                (s1 - skewness).abs() < 0.01 && (t1 - tail).abs() < 0.02,
                "({c}, {d}): shape ({skewness}, {tail}); started at ({c1}, {d1}), shape ({s1}, {t1})"
            );
        }
        // A positive c skews to the right, a positive d weighs the tails.
        let (s, t) = polynomial_shape(0.2, 0.1);
        assert!(s > 0.05 && t > 0.2, "skewness {s}, tail {t}");
    }
}
