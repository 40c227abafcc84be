//! The load: friction that depends on the normal force, and a normal force that drifts.

use super::*;
use crate::diagnose::law;
use crate::measure::Run;

impl Context<'_> {
    /// The slope of μ against N0 (1/N) that the fitting units' phase means
    /// imply, for data that carry phases but neither friction channels nor
    /// peaks (phase-only summary tables); `None` where no frequency's phase
    /// gradient is known well enough.
    ///
    /// In the model the friction force is μ(v)·N, so adding δμ to the law
    /// moves the response as raising N0 by δμ·N0/μ̄ does (μ̄: the law at the
    /// base's velocity amplitude). The simulated phases of one frequency at
    /// its loads give ∂φ/∂N0 there, so a unit's phase misfit r reads as
    /// r ≈ ∂φ/∂N0 · N0/μ̄ · (δ0 + k (N0 − `reference_n`)), solved for
    /// (δ0, k) by least squares weighted by the misfits' spreads (δ0 is
    /// what the level's calibration left). A frequency enters only where
    /// the standard error of its gradient is under a quarter of the
    /// gradient: a load at which the simulation's phase is erratic (a
    /// response that sticks, its phase spread over the circle) says nothing
    /// about the slope.
    ///
    /// Starting from the data's own slope, of either sign, keeps the search
    /// away from degenerate laws that a fixed start's first step can meet,
    /// and reaches a rig whose friction falls with load.
    pub(super) fn slope_from_phase(&self, reference_n: f64) -> Option<f64> {
        let units: Vec<PhaseUnit> = self
            .scores
            .iter()
            .filter(|s| !s.heldout && s.observable == Observable::PhaseMeanDeg)
            .map(|s| PhaseUnit {
                excitation_frequency_hz: s.excitation_frequency_hz,
                normal_force_n: self.data.simulated_condition(&self.data.units[s.unit], self.model).normal_force_n,
                simulated_deg: s.simulated,
                measured_deg: s.measured,
                spread_deg: s.scale,
            })
            .collect();
        let law = FrictionLaw::of(self.model);
        let amplitude_m = self.model.excitation.amplitude_m;
        phase_implied_slope(units, reference_n, |hz| law.mu(std::f64::consts::TAU * hz * amplitude_m))
    }

    /// The slope of the sliding friction level against N0 (1/N) that the
    /// force channels give: each fitting unit's mean of μ − the model's law
    /// over its slipping samples, fitted against its N0 by least squares
    /// weighted by how many samples slip. Read from the records alone, not
    /// from simulated features: a load at which the block sticks for most
    /// of each cycle has a mean |F|/N set by the spring, not by the law, in
    /// the data and in the simulation alike, and says nothing about how
    /// friction changes with load, while a weighting by slipping samples
    /// lets it count only for what it slips. `None` without force channels
    /// or with fewer than two loads that slip.
    fn slope_from_law(&self) -> Option<f64> {
        let law = FrictionLaw::of(self.model);
        let points: Vec<(f64, f64, f64)> = self
            .data
            .units
            .iter()
            .filter(|u| !u.heldout && !u.runs.is_empty())
            .filter_map(|u| {
                let runs: Vec<&Run> = u.runs.iter().map(|&r| &self.data.set.runs[r]).collect();
                let (level, count) = law::level_against(&runs, &self.data.reading(), &law)?;
                let n0 = self.data.simulated_condition(u, self.model).normal_force_n;
                Some((n0, level, count as f64))
            })
            .collect();
        if levels(points.iter().map(|p| p.0)).len() < 2 {
            return None;
        }
        weighted_slope(&points)
    }
}

/// Least-squares slope of y against x; `None` without spread in x.
fn slope(points: &[(f64, f64)]) -> Option<f64> {
    weighted_slope(&points.iter().map(|&(x, y)| (x, y, 1.0)).collect::<Vec<_>>())
}

/// Least-squares slope of y against x with each point (x, y, w) weighted
/// by w; `None` without spread in x.
fn weighted_slope(points: &[(f64, f64, f64)]) -> Option<f64> {
    let total: f64 = points.iter().map(|p| p.2).sum();
    if points.len() < 2 || total <= 0.0 {
        return None;
    }
    let mx = points.iter().map(|p| p.2 * p.0).sum::<f64>() / total;
    let my = points.iter().map(|p| p.2 * p.1).sum::<f64>() / total;
    let sxx: f64 = points.iter().map(|p| p.2 * (p.0 - mx).powi(2)).sum();
    let sxy: f64 = points.iter().map(|p| p.2 * (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 1e-12 * total * mx.abs().max(1.0)).then(|| sxy / sxx)
}

/// A fitting unit's phase mean, as [`phase_implied_slope`] reads it.
#[derive(Clone, Copy, Debug)]
struct PhaseUnit {
    /// Hz
    excitation_frequency_hz: f64,
    /// N0 as simulated, N.
    normal_force_n: f64,
    /// The current model's phase mean, degrees.
    simulated_deg: f64,
    /// The data's, degrees.
    measured_deg: f64,
    /// The spread of their difference (the score's scale), degrees.
    spread_deg: f64,
}

/// The slope k of μ against N0 (1/N) that the phase misfits of `units`
/// imply (see [`Context::slope_from_phase`]), with `mu_at(f)` the law's μ̄
/// at the mean frequency `f` (Hz) of the frequencies that enter. ∂φ/∂N0 at
/// a unit is the chord through its frequency's loads where it has two, the
/// derivative of their least-squares parabola where it has more.
fn phase_implied_slope(mut units: Vec<PhaseUnit>, reference_n: f64, mu_at: impl Fn(f64) -> f64) -> Option<f64> {
    let degrees = |d: f64| wrap_angle(d.to_radians()).to_degrees();
    units.retain(|u| u.spread_deg > 0.0 && u.spread_deg.is_finite());
    units.sort_by(|a, b| {
        a.excitation_frequency_hz
            .total_cmp(&b.excitation_frequency_hz)
            .then(a.normal_force_n.total_cmp(&b.normal_force_n))
    });
    // Rows (∂φ/∂N0 · N0 in degrees, N0 − reference in N, misfit in degrees,
    // its spread in degrees) and the frequencies they come from, Hz.
    let mut rows: Vec<(f64, f64, f64, f64)> = Vec::new();
    let mut frequencies: Vec<f64> = Vec::new();
    for group in units.chunk_by(|a, b| a.excitation_frequency_hz == b.excitation_frequency_hz) {
        // Loads about their mean, N, and the simulated phases unwrapped
        // around the group's first, degrees.
        let mx = mean(&group.iter().map(|u| u.normal_force_n).collect::<Vec<_>>());
        let x: Vec<f64> = group.iter().map(|u| u.normal_force_n - mx).collect();
        let y: Vec<f64> =
            group.iter().map(|u| group[0].simulated_deg + degrees(u.simulated_deg - group[0].simulated_deg)).collect();
        let sxx: f64 = x.iter().map(|x| x * x).sum();
        if group.len() < 2 || sxx <= 1e-12 * mx.abs().max(1.0) {
            continue;
        }
        let chord = x.iter().zip(&y).map(|(x, y)| x * y).sum::<f64>() / sxx;
        let standard_error = x.iter().zip(group).map(|(x, u)| (x * u.spread_deg).powi(2)).sum::<f64>().sqrt() / sxx;
        if standard_error >= 0.25 * chord.abs() {
            continue;
        }
        // The gradient at the loads' mean and its rate of change, °/N and °/N².
        let (at_mean, curvature) = (group.len() >= 3)
            .then(|| least_squares(x.len(), 3, |i, row| row.copy_from_slice(&[1.0, x[i], x[i] * x[i]]), |i| y[i]))
            .flatten()
            .map_or((chord, 0.0), |(p, _)| (p[1], p[2]));
        frequencies.push(group[0].excitation_frequency_hz);
        rows.extend(group.iter().zip(&x).map(|(u, x)| {
            let gradient = at_mean + 2.0 * curvature * x;
            (
                gradient * u.normal_force_n,
                u.normal_force_n - reference_n,
                degrees(u.measured_deg - u.simulated_deg),
                u.spread_deg,
            )
        }));
    }
    if frequencies.is_empty() {
        return None;
    }
    let mu = mu_at(mean(&frequencies));
    if mu.is_nan() || mu <= 1e-3 {
        return None;
    }
    // misfit = s/μ̄ · (δ0 + k x), each row weighted by 1/spread.
    let (coefficients, _) = least_squares(
        rows.len(),
        2,
        |i, row| {
            let (s, x, _, spread) = rows[i];
            row.copy_from_slice(&[s / mu / spread, s / mu * x / spread]);
        },
        |i| rows[i].2 / rows[i].3,
    )?;
    Some(coefficients[1]).filter(|k| k.is_finite())
}

/// The form that bends `form` of `effect` once it fitted with `values`, if
/// there is one: for the `linear` load dependence, where three or more
/// loads were fitted, a friction whose change with load steepens or
/// flattens (wear-in at high loads, a contact area that saturates), the
/// fitted slope k bent by c, k (N0 − Nref) (1 + c (N0 − Nref)/Nref), so the
/// bend is searched in steps of the slope's own scale (q = k c / Nref in the
/// model file). A straight line through such loads misses the middle ones
/// by the chord's error. Searched only from a slope that fitted (see the
/// search's round), starting there: it costs no trials where there is no
/// load dependence to bend.
pub(crate) fn bent(effect: Effect, form: SearchedForm, values: &[f64], ctx: &Context<'_>) -> Option<Variant> {
    if effect != Effect::LoadDependentFriction || form != SearchedForm::Linear {
        return None;
    }
    if levels(ctx.by_load(Observable::FrictionMuMean).iter().map(|p| p.0)).len() < 3 {
        return None;
    }
    let reference = ctx.mean_load();
    Some(Variant {
        effect,
        form: SearchedForm::Quadratic,
        params: vec![
            Param::log("strength_per_n", *values.first()?, 1.2, -1.0, 1.0),
            Param::linear("bend", 0.0, 0.25, -3.0, 3.0),
        ],
        apply: Box::new(move |m, p| {
            let mut m = m.clone();
            m.effects.load_dependent_friction = Some(LoadDependentFriction {
                form: LoadForm::Quadratic,
                strength: p[0],
                curvature_per_n2: p[0] * p[1] / reference,
                reference_force_n: reference,
            });
            m
        }),
    })
}

/// The forms of a load-dependent friction searched, started where the data point.
pub(super) fn load_dependent_friction(effect: Effect, ctx: &Context<'_>) -> Vec<Variant> {
    // At one load every form is a shift of the friction level, which the
    // calibration owns: nothing tells a load dependence apart there.
    if ctx.data.loads().len() < 2 {
        return Vec::new();
    }
    let mean_n0 = ctx.mean_load();
    // The slope of the sliding friction level against N0 (1/N) from the
    // force channels; where too few samples slip for that, the slope of
    // measured minus simulated mean μ; without friction channels, from
    // the relative misfit of the mean peaks against N0 (more friction
    // lowers the peaks).
    let from_mu: Vec<(f64, f64)> =
        ctx.by_load(Observable::FrictionMuMean).iter().map(|&(n, m, s)| (n, m - s)).collect();
    let from_peaks: Vec<(f64, f64)> =
        ctx.by_load(Observable::PeakMeanM).iter().map(|&(n, m, s)| (n, (s - m) / m.abs().max(1e-12))).collect();
    let mu_at_rest = (ctx.model.friction.a + ctx.model.friction.b).max(0.02);
    let start = ctx
        .slope_from_law()
        .or_else(|| slope(&from_mu))
        .or_else(|| slope(&from_peaks).map(|s| s * mu_at_rest))
        .or_else(|| ctx.slope_from_phase(mean_n0))
        .filter(|s| s.is_finite() && s.abs() > 1e-5)
        .unwrap_or(0.005);
    let reference = mean_n0;
    vec![
        Variant {
            effect,
            form: SearchedForm::Linear,
            params: vec![Param::log("strength_per_n", start, 1.5, -1.0, 1.0)],
            apply: Box::new(move |m, p| {
                let mut m = m.clone();
                m.effects.load_dependent_friction = Some(LoadDependentFriction {
                    form: LoadForm::Linear,
                    strength: p[0],
                    curvature_per_n2: 0.0,
                    reference_force_n: reference,
                });
                m
            }),
        },
        Variant {
            effect,
            form: SearchedForm::Power,
            // Slope μ₀·k/Nref at the reference (μ₀ = a + b, the level at
            // rest that the form scales): k from the same slope.
            params: vec![Param::log("exponent", (start * reference / mu_at_rest).clamp(-3.0, 3.0), 1.5, -5.0, 5.0)],
            apply: Box::new(move |m, p| {
                let mut m = m.clone();
                m.effects.load_dependent_friction = Some(LoadDependentFriction {
                    form: LoadForm::Power,
                    strength: p[0],
                    curvature_per_n2: 0.0,
                    reference_force_n: reference,
                });
                m
            }),
        },
        // The two-term law F = μN + A (Derjaguin; Bowden & Tabor):
        // |F|/N = μ + A/N falls with the load by −A/N² at the
        // reference.
        Variant {
            effect,
            form: SearchedForm::Adhesion,
            params: vec![Param::log("adhesion_n", (-start * reference * reference).clamp(-50.0, 50.0), 1.5, -1e3, 1e3)],
            apply: Box::new(move |m, p| {
                let mut m = m.clone();
                m.effects.load_dependent_friction = Some(LoadDependentFriction {
                    form: LoadForm::Adhesion,
                    strength: p[0],
                    curvature_per_n2: 0.0,
                    reference_force_n: reference,
                });
                m
            }),
        },
        // The whole law scaled by (N0/Nref)^k: its slope at the
        // reference is k times the law's mean level over Nref.
        Variant {
            effect,
            form: SearchedForm::Scaled,
            params: vec![Param::log("exponent", (start * reference / mu_at_rest).clamp(-3.0, 3.0), 1.5, -5.0, 5.0)],
            apply: Box::new(move |m, p| {
                let mut m = m.clone();
                m.effects.load_dependent_friction = Some(LoadDependentFriction {
                    form: LoadForm::Scaled,
                    strength: p[0],
                    curvature_per_n2: 0.0,
                    reference_force_n: reference,
                });
                m
            }),
        },
    ]
}

/// The forms of a normal-force drift searched, started where the data point.
pub(super) fn normal_force_drift(effect: Effect, ctx: &Context<'_>) -> Vec<Variant> {
    // A drift shows only over time: in a record's normal force, its
    // friction's trend or its peaks' trend, never in a summary row's
    // statistics.
    let over_time = [Observable::NormalForceDriftPerS, Observable::FrictionTrendPerS, Observable::PeakTrendPerS];
    if !over_time.iter().any(|&o| ctx.has(o)) {
        return Vec::new();
    }
    // The drift's rate read one for one: from the normal force where it is
    // recorded; else from the friction's trend (μ read against the nominal
    // load moves as the load does); else from the peaks' (which move
    // against the load, by less).
    let rate = ctx
        .excess(Observable::NormalForceDriftPerS)
        .or_else(|| ctx.excess(Observable::FrictionTrendPerS))
        .or_else(|| ctx.excess(Observable::PeakTrendPerS).map(|t| -t))
        .filter(|r| r.abs() > 1e-6)
        .unwrap_or(0.002);
    // A quadratic's t² term shows in the record as the curvature
    // (relative to the record's mean) and tilts the record's slope
    // by 2 q × the record's middle (time from the run's start).
    let curvature = ctx
        .excess(Observable::NormalForceCurvaturePerS2)
        .filter(|q| q.is_finite() && q.abs() > 1e-9)
        .unwrap_or(0.0)
        .clamp(-1e-2, 1e-2);
    let initial_rate = (rate - 2.0 * curvature * ctx.mean_record_middle_s()).clamp(-0.5, 0.5);
    let drift = |form: DriftForm, rate: f64, curvature: f64| NormalForceDrift {
        form,
        rate_per_s: rate,
        curvature_per_s2: curvature,
        mean_over_s: None,
    };
    // A random walk's record slope b has variance 1.2 r / T over a record
    // of T seconds (r the walk's variance per second), whenever the record
    // starts: r ≈ (5/6) mean(T b²) over the fitting records (a unit's
    // mean slope over n records has 1/n of one's variance).
    let diffusion = ctx.mean_over_fitting_runs(|duration_s, runs, m| {
        m.get(&Observable::NormalForceDriftPerS).map(|b| 5.0 / 6.0 * duration_s * runs as f64 * b * b)
    });
    let diffusion = diffusion.filter(|r| r.is_finite() && *r > 0.0).unwrap_or(1e-5).clamp(1e-8, 0.05);
    // Linear, quadratic and random-walk forms: the saturating and wandering
    // drifts are the benchmark's withheld forms (the quadratic bends as
    // both do, without either's shape); a random walk is a drift whose
    // course no deterministic form predicts from run to run.
    vec![
        Variant {
            effect,
            form: SearchedForm::DriftLinear,
            params: vec![Param::log("rate_per_s", rate, 1.4, -0.5, 0.5)],
            apply: Box::new(move |m, p| {
                let mut m = m.clone();
                m.effects.normal_force_drift = Some(drift(DriftForm::Linear, p[0], 0.0));
                m
            }),
        },
        Variant {
            effect,
            form: SearchedForm::DriftQuadratic,
            params: vec![
                Param::linear("rate_per_s", initial_rate, 0.2 * initial_rate.abs().max(1e-4), -0.5, 0.5),
                Param::linear("curvature_per_s2", curvature, 0.2 * curvature.abs().max(1e-6), -1e-2, 1e-2),
            ],
            apply: Box::new(move |m, p| {
                let mut m = m.clone();
                m.effects.normal_force_drift = Some(drift(DriftForm::Quadratic, p[0], p[1]));
                m
            }),
        },
        Variant {
            effect,
            form: SearchedForm::DriftRandomWalk,
            params: vec![Param::log("rate_per_s", diffusion, 2.0, 1e-8, 0.05)],
            apply: Box::new(move |m, p| {
                let mut m = m.clone();
                m.effects.normal_force_drift = Some(drift(DriftForm::RandomWalk, p[0], 0.0));
                m
            }),
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A load weighted by how little it slips barely moves the slope: two
    /// loads that slip give a friction level rising by 0.0255 per newton
    /// (a transition between 4 and 8 N), and a third at which the block
    /// sticks, whose mean |F|/N the spring sets far below, counts for its
    /// few slipping samples alone.
    #[test]
    fn a_load_that_barely_slips_barely_moves_the_weighted_slope() {
        let points = [(4.0, -0.07, 30_000.0), (8.0, 0.032, 30_000.0), (16.0, -0.2, 60.0)];
        let k = weighted_slope(&points).unwrap();
        assert!((k / 0.0255 - 1.0).abs() < 0.1, "slope {k}");
        let unweighted = slope(&points.map(|(x, y, _)| (x, y))).unwrap();
        assert!(unweighted < 0.0, "unweighted, the stuck load turns the slope over: {unweighted}");
        assert_eq!(weighted_slope(&[(4.0, 0.1, 1.0), (4.0, 0.2, 1.0)]), None);
    }

    /// Phase tables of a rig whose phase depends on the friction force μN
    /// through `phase_of(f, μN)`, measured where μ = μ̄ + δ0 + k (N0 − 50 N)
    /// and simulated at μ̄ = 0.2, at loads that differ between frequencies;
    /// at 11 Hz the simulation's phase is erratic (spread 100°).
    fn tables(k: f64, phase_of: impl Fn(f64, f64) -> f64) -> Vec<PhaseUnit> {
        let (mu, offset, reference) = (0.2, 0.01, 50.0);
        let mut units = Vec::new();
        for (hz, loads) in [(7.0, [25.0, 45.0, 65.0]), (9.0, [35.0, 60.0, 85.0]), (11.0, [30.0, 55.0, 80.0])] {
            for n in loads {
                let erratic = hz == 11.0;
                units.push(PhaseUnit {
                    excitation_frequency_hz: hz,
                    normal_force_n: n,
                    simulated_deg: if erratic {
                        [-170.0, 120.0, 10.0][(n as usize / 25) % 3]
                    } else {
                        phase_of(hz, mu * n)
                    },
                    measured_deg: phase_of(hz, (mu + offset + k * (n - reference)) * n),
                    spread_deg: if erratic { 100.0 } else { 0.05 },
                });
            }
        }
        units
    }

    #[test]
    fn the_phase_misfit_across_loads_gives_the_slope_of_friction_with_load_and_its_sign() {
        let mu_bar = |_: f64| 0.2;
        // A phase linear in μN: the linearisation is exact up to the wrap.
        let linear = |hz: f64, force: f64| 5.0 * hz + 1.5 * force;
        for k in [0.0015, -0.0015] {
            let found = phase_implied_slope(tables(k, linear), 50.0, mu_bar).unwrap();
            assert!((found - k).abs() < 0.02 * k.abs(), "k {k}: found {found}");
        }
        // A saturating phase (its gradient across a frequency's loads is a
        // chord): within one step of the strength search (× 1.5).
        let saturating = |hz: f64, force: f64| 3.0 * hz + 70.0 * (force / 15.0).tanh();
        for k in [0.0015, -0.0015] {
            let found = phase_implied_slope(tables(k, saturating), 50.0, mu_bar).unwrap();
            assert!(found / k > 1.0 / 1.5 && found / k < 1.5, "k {k}: found {found}");
        }
        // A frequency's middle load held out: two loads each, the chord.
        // Phase tables that bend this little (about 0.8 and 0.9°/N either
        // side of the middle load) are what phase-only sets give.
        let gentle = |hz: f64, force: f64| 3.0 * hz + 70.0 * (force / 40.0).tanh();
        for k in [0.0015, -0.0015] {
            let two_loads: Vec<PhaseUnit> =
                tables(k, gentle).into_iter().enumerate().filter(|(i, _)| i % 3 != 1).map(|(_, u)| u).collect();
            let found = phase_implied_slope(two_loads, 50.0, mu_bar).unwrap();
            assert!(found / k > 1.0 / 1.5 && found / k < 1.5, "k {k}: found {found}");
        }
        // Phases near ±180° are unwrapped, not read as a 360° jump.
        let near_half_turn = |hz: f64, force: f64| wrap_angle((160.0 + hz + 1.5 * force).to_radians()).to_degrees();
        let found = phase_implied_slope(tables(0.0015, near_half_turn), 50.0, mu_bar).unwrap();
        assert!((found - 0.0015).abs() < 0.02 * 0.0015, "found {found}");
        // Only the erratic frequency: nothing to read.
        let erratic: Vec<PhaseUnit> =
            tables(0.0015, linear).into_iter().filter(|u| u.excitation_frequency_hz == 11.0).collect();
        assert_eq!(phase_implied_slope(erratic, 50.0, mu_bar), None);
    }
}
