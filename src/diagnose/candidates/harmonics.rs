//! Normal-force harmonics: Fourier forms started at the measured N's harmonics, and a load that follows the block's position started at the regression of N on x.

use super::*;

/// The normal force's harmonics in excess of the model's noise floor, per
/// fitting unit: (N0, [amplitude excess (N), phase (rad)] per harmonic).
fn harmonic_estimates(ctx: &Context<'_>) -> Vec<(f64, [(f64, f64); 4])> {
    let data = ctx.data;
    let interval = data.sample_interval_s;
    let mut out = Vec::new();
    for (i, u) in data.units.iter().enumerate() {
        if u.heldout || data.features[i].is_empty() {
            continue;
        }
        let mut per = [(0.0, 0.0); 4];
        for (k, slot) in per.iter_mut().enumerate() {
            let o = Observable::normal_force_harmonic(k + 1);
            let Some(floor) = ctx.scores.iter().find(|s| {
                !s.heldout
                    && s.observable == o
                    && s.excitation_frequency_hz == u.condition.excitation_frequency_hz
                    && s.normal_force_n == u.condition.normal_force_n
            }) else {
                continue;
            };
            // A record with a free time origin gives each harmonic's phase
            // relative to its own response's fundamental, turned into the
            // model's frame with the response lag of a linear oscillator
            // there (friction shifts it; the search then turns every
            // harmonic by a common phase shift).
            let omega_ratio = u.condition.excitation_frequency_hz / ctx.model.rig.natural_frequency_hz;
            let linear_lag = (2.0 * ctx.model.rig.damping_ratio * omega_ratio).atan2(1.0 - omega_ratio * omega_ratio);
            let phases: Vec<f64> = data.features[i]
                .iter()
                .filter_map(|f| {
                    let phase = f.normal_force.as_ref().and_then(|n| n.harmonic_phase_rad[k])?;
                    if f.absolute_phase {
                        return Some(phase);
                    }
                    let lag = f.peaks.as_ref()?.phase_mean_deg.to_radians();
                    Some(phase + (k + 1) as f64 * (lag - linear_lag))
                })
                .collect();
            let amplitude = data.measured[i].get(&o).copied().unwrap_or(0.0);
            if phases.is_empty() {
                continue;
            }
            // Values held per noise interval lag their continuous wave by
            // half an interval: the model's phase leads by kΩτ/2.
            let omega = std::f64::consts::TAU * u.condition.excitation_frequency_hz;
            let phase = circular_mean_var(&phases).0 + (k + 1) as f64 * omega * interval / 2.0;
            *slot = ((amplitude * amplitude - floor.simulated * floor.simulated).max(0.0).sqrt(), phase);
        }
        out.push((data.simulated_condition(u, ctx.model, 0).normal_force_n, per));
    }
    out
}

/// The `position` form's α and β (–, shares of N0 per U0 and per U0² of
/// displacement) that the fitting units' records suggest: per record with
/// a normal-force channel, the least-squares fit N ≈ c0 + c1 r + c2 r²
/// with r = x/U0, so that c0 is the load at x = 0 (N0), α = c1/c0 and
/// β = c2/c0; averaged over records weighted by how much of r (for α) and
/// r² (for β) each spans. The normal force's noise and the sensor's are
/// independent of x, so the fit is unbiased whatever their size. `None`
/// without such records.
fn position_estimate(ctx: &Context<'_>) -> Option<(f64, f64)> {
    let data = ctx.data;
    let (mut alpha, mut beta) = ((0.0, 0.0), (0.0, 0.0));
    for u in data.units.iter().filter(|u| !u.heldout) {
        for &r in &u.runs {
            let run = &data.set.runs[r];
            let (Some(n), u0) = (&run.normal_force, run.excitation_amplitude_m) else { continue };
            if u0 <= 0.0 {
                continue;
            }
            let len = n.len().min(run.x_m.len());
            let fill = |i: usize, row: &mut [f64]| {
                let r = run.x_m[i] / u0;
                row.copy_from_slice(&[1.0, r, r * r]);
            };
            let Some((c, _)) = least_squares(len, 3, fill, |i| n[i]) else { continue };
            if c[0] <= 0.0 {
                continue;
            }
            let spread = |p: i32| mean(&run.x_m[..len].iter().map(|x| (x / u0).powi(p)).collect::<Vec<_>>());
            let mean_r2 = spread(2);
            let (w1, w2) = (mean_r2, (spread(4) - mean_r2 * mean_r2).max(0.0));
            alpha = (alpha.0 + w1 * c[1] / c[0], alpha.1 + w1);
            beta = (beta.0 + w2 * c[2] / c[0], beta.1 + w2);
        }
    }
    if alpha.1 <= 0.0 || beta.1 <= 0.0 {
        return None;
    }
    let (a, b) = (alpha.0 / alpha.1, beta.0 / beta.1);
    (a.is_finite() && b.is_finite()).then_some((a, b))
}

/// The forms of the normal force's harmonics searched, started where the data point.
pub(super) fn normal_force_harmonics(effect: Effect, ctx: &Context<'_>) -> Vec<Variant> {
    let normal_force = ctx.has(Observable::NormalForceHarmonic1N);
    if !normal_force {
        return Vec::new();
    }
    let mut out = Vec::new();
    if let Some((alpha, beta)) = position_estimate(ctx) {
        // The load that follows the block's position: started at
        // the regression of the measured N on x/U0 and its square,
        // both terms scaled together.
        out.push(Variant {
            effect,
            form: SearchedForm::Position,
            params: vec![Param::log("scale", 1.0, 1.25, 0.2, 5.0)],
            apply: Box::new(move |m, p| {
                let mut m = m.clone();
                m.effects.normal_force_harmonics = Some(NormalForceHarmonics {
                    form: HarmonicForm::Position,
                    amplitudes_n: [0.0; 4],
                    amplitudes_per_n0: [alpha * p[0], beta * p[0], 0.0, 0.0],
                    phases_rad: [0.0; 4],
                    shape: 2.0,
                });
                m
            }),
        });
    }
    let estimates = harmonic_estimates(ctx);
    if estimates.is_empty() {
        return out;
    }
    let phases: [f64; 4] = std::array::from_fn(|k| {
        let p: Vec<f64> = estimates.iter().filter(|e| e.1[k].0 > 0.0).map(|e| e.1[k].1).collect();
        if p.is_empty() { 0.0 } else { circular_mean_var(&p).0 }
    });
    let shares: [f64; 4] =
        std::array::from_fn(|k| mean(&estimates.iter().map(|e| e.1[k].0 / e.0.max(1e-3)).collect::<Vec<_>>()));
    let newtons: [f64; 4] = std::array::from_fn(|k| mean(&estimates.iter().map(|e| e.1[k].0).collect::<Vec<_>>()));
    // Each harmonic k turned by k × `shift` (rad): the common phase
    // that records with a free time origin leave unknown.
    let harmonics = move |amplitudes_n: [f64; 4], per_n0: [f64; 4], shift: f64| NormalForceHarmonics {
        form: HarmonicForm::Fourier,
        amplitudes_n,
        amplitudes_per_n0: per_n0,
        phases_rad: std::array::from_fn(|k| phases[k] + (k + 1) as f64 * shift),
        shape: 2.0,
    };
    let free = ctx.data.features.iter().flatten().any(|f| !f.absolute_phase);
    let params = || {
        let mut p = vec![Param::log("scale", 1.0, 1.25, 0.2, 5.0)];
        if free {
            p.push(Param::linear("phase_shift_rad", 0.0, std::f64::consts::PI / 8.0, -3.2, 3.2));
        }
        p
    };
    let shift = |p: &[f64]| p.get(1).copied().unwrap_or(0.0);
    out.extend([
        Variant {
            effect,
            form: SearchedForm::FourierShareOfN0,
            params: params(),
            apply: Box::new(move |m, p| {
                let mut m = m.clone();
                let per = shares.map(|a| a * p[0]);
                m.effects.normal_force_harmonics = Some(harmonics([0.0; 4], per, shift(p)));
                m
            }),
        },
        Variant {
            effect,
            form: SearchedForm::FourierNewtons,
            params: params(),
            apply: Box::new(move |m, p| {
                let mut m = m.clone();
                let n = newtons.map(|a| a * p[0]);
                m.effects.normal_force_harmonics = Some(harmonics(n, [0.0; 4], shift(p)));
                m
            }),
        },
    ]);
    out
}
