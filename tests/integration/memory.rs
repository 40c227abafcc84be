//! Friction with a memory: the hysteresis forms that carry state through a
//! slip (a lag in time, the rate-and-state slip and ageing laws, Dahl's
//! friction through a reversal), each against what its law says, and the
//! integrator's steps resolving a short memory.

use stickslip::engine::{Condition, Model, Oscillator, Sample};

use super::effects::{COND, law, mean, model, noiseless_record, record, sticks};

/// Hysteresis `lag` with a memory time far shorter than a step (0.1 ms
/// against 2.2 ms at 7 Hz): the steps are raised to resolve it, so the
/// lagged coefficient follows the law within its lag instead of growing
/// without bound (classical RK4 on the lag is unstable beyond 2.8 τ per
/// step). Noise off, so the law is known exactly at every sample.
#[test]
fn a_lag_shorter_than_a_step_follows_the_law() {
    let m = model(&[
        "friction_hysteresis.form=\"lag\"",
        "friction_hysteresis.time_constant_s=1e-4",
        "friction.sigma=0",
        "normal_force.sigma=0",
    ]);
    let f = &m.friction;
    let law = |v: f64| f.a + f.b / (1.0 + f.c * v.abs()) + f.d * v * v;
    let slipping: Vec<Sample> = record(&m, 5.0).into_iter().filter(|s| s.v_m_per_s.abs() > 1e-3).collect();
    assert!(slipping.len() > 500, "only {} slipping samples", slipping.len());
    let worst = slipping
        .iter()
        .map(|s| (s.friction_force_n.abs() / s.normal_force_n - law(s.v_m_per_s)).abs())
        .fold(0.0f64, f64::max);
    println!("lag 0.1 ms: largest |μ − μ(v)| while slipping {worst:.2e}");
    assert!(worst < 0.01, "the lagged coefficient left the law by {worst}");
}

/// A memory time that no allowed step count resolves is refused by name
/// (it would need 1.4e11 steps per period at 7 Hz), not run for days.
#[test]
fn a_lag_too_short_to_integrate_is_refused_by_name() {
    let m = model(&["friction_hysteresis.form=\"lag\"", "friction_hysteresis.time_constant_s=1e-12"]);
    let err = Oscillator::new(&m, COND).expect_err("refused").to_string();
    assert!(err.contains("friction_hysteresis.time_constant_s") && err.contains("steps per period"), "{err}");
}

/// Per slip that starts from a stick in `r` (a record of a law that does
/// not depend on speed, `a`, with a static excess `excess` that the slip's
/// memory starts from): the slip distance (m) and the time (s, from the
/// stick's last sample) at which the friction coefficient's excess over `a`
/// has fallen to `excess / e`, interpolated in its logarithm between samples.
fn e_folds(r: &[Sample], a: f64, excess: f64) -> Vec<(f64, f64)> {
    /// Where a slip began (the stick's last sample) and its last sample so far.
    struct Slip {
        x0_m: f64,
        t0_s: f64,
        /// Slip distance (m), excess (–) and time since t0 (s) at the last sample.
        last: (f64, f64, f64),
    }
    let target = excess / std::f64::consts::E;
    let mut out = Vec::new();
    let mut slip: Option<Slip> = None;
    for s in r {
        if s.v_m_per_s == 0.0 {
            slip = Some(Slip { x0_m: s.x_m, t0_s: s.t_s, last: (0.0, excess, 0.0) });
            continue;
        }
        let Some(current) = slip.as_mut() else { continue };
        let (d0, e0, t0) = current.last;
        let d = (s.x_m - current.x0_m).abs();
        let (e, t) = (s.friction_force_n.abs() / s.normal_force_n - a, s.t_s - current.t0_s);
        if e <= target {
            let f = (target.ln() - e0.ln()) / (e.ln() - e0.ln());
            out.push((d0 + f * (d - d0), t0 + f * (t - t0)));
            slip = None;
        } else {
            current.last = (d, e, t);
        }
    }
    out
}

/// Hysteresis `slip`, the rate-and-state slip law: after a breakaway the
/// friction relaxes to the steady law over a slip *distance* L, whatever the
/// speed. With a law that does not depend on speed (b = 0, no noise) and a
/// static excess Δ = 0.2 the memory starts from, μ_f − a = Δ e^(−|Δx|/L):
/// the excess falls by e after L of slip. Doubling both the base amplitude
/// and the normal force doubles the slip speeds (the equations scale), so
/// that distance is covered sooner; it stays L. Hysteresis `lag` on the same
/// runs relaxes over a *time* instead: e-fold after τ_m whatever the speed,
/// over twice the distance at twice the speed.
#[test]
fn the_slip_law_relaxes_friction_over_a_slip_distance_whatever_the_speed() {
    let (length_m, lag_s, excess) = (2e-4, 5e-3, 0.2);
    let e_fold = |form: &str, amplitude_m: f64, normal_force_n: f64| -> (f64, f64) {
        let sets = [
            format!("friction_hysteresis.form=\"{form}\""),
            format!("friction_hysteresis.length_m={length_m}"),
            format!("friction_hysteresis.time_constant_s={lag_s}"),
            "friction.b=0".into(),
            format!("stiction.excess={excess}"),
            format!("excitation.amplitude_m={amplitude_m}"),
        ];
        let sets: Vec<&str> = sets.iter().map(String::as_str).collect();
        let condition = Condition { excitation_frequency_hz: 7.0, normal_force_n };
        let (m, r) = noiseless_record(&sets, condition, 3.0, 20_000.0);
        let folds = e_folds(&r, m.friction.a, excess);
        assert!(folds.len() >= 20, "{form} at {amplitude_m} m, {normal_force_n} N: {} slips from a stick", folds.len());
        (mean(folds.iter().map(|f| f.0)), mean(folds.iter().map(|f| f.1)))
    };
    let (slow, fast) = (e_fold("slip", 2.5e-3, 16.39), e_fold("slip", 5e-3, 32.78));
    println!(
        "slip law: e-fold after {:.4e} m in {:.4e} s, and at twice the speed {:.4e} m in {:.4e} s",
        slow.0, slow.1, fast.0, fast.1
    );
    for (distance, _) in [slow, fast] {
        assert!((distance / length_m - 1.0).abs() < 0.02, "slip law: e-fold distance {distance} m, L = {length_m} m");
    }
    assert!(fast.1 < 0.9 * slow.1, "slip law: at twice the speed L took {} s against {} s", fast.1, slow.1);
    let (slow, fast) = (e_fold("lag", 2.5e-3, 16.39), e_fold("lag", 5e-3, 32.78));
    println!(
        "lag: e-fold after {:.4e} m in {:.4e} s, and at twice the speed {:.4e} m in {:.4e} s",
        slow.0, slow.1, fast.0, fast.1
    );
    for (_, time) in [slow, fast] {
        assert!((time / lag_s - 1.0).abs() < 0.02, "lag: e-fold time {time} s, τ_m = {lag_s} s");
    }
    assert!(fast.0 > 1.5 * slow.0, "lag: at twice the speed τ_m took {} m against {} m", fast.0, slow.0);
}

/// Hysteresis `dahl`: friction is continuous through a reversal. With a
/// law that does not depend on speed (b = d = 0, no noise) and a light load
/// (2 N: the block slides through its reversals without sticking), the
/// friction it slid against points along the new motion at first and turns
/// over the displacement δ: its component against the motion is
/// a (1 − 2 e^(−d/δ)) after a slide much longer than δ, −a at the reversal
/// and 0 after δ ln 2 (within 1%). Hysteresis `exponential` over the same
/// δ starts from 0 and never points along the motion.
#[test]
fn dahls_friction_turns_over_a_displacement_through_a_reversal() {
    let length_m = 2e-4;
    // Per reversal: the friction coefficient against the motion at the
    // first sample after it, and the distance from the reversal at which
    // that coefficient crosses 0 (interpolated; None where it never is
    // below 0).
    let turns = |form: &str| -> Vec<(f64, Option<f64>)> {
        let sets = [
            format!("friction_hysteresis.form=\"{form}\""),
            format!("friction_hysteresis.length_m={length_m}"),
            "friction.b=0".into(),
            "friction.d=0".into(),
        ];
        let sets: Vec<&str> = sets.iter().map(String::as_str).collect();
        let condition = Condition { excitation_frequency_hz: 7.0, normal_force_n: 2.0 };
        let (_, r) = noiseless_record(&sets, condition, 2.0, 50_000.0);
        let against = |s: &Sample| -s.friction_force_n * s.v_m_per_s.signum() / s.normal_force_n;
        let mut out = Vec::new();
        let mut i = 1;
        while i < r.len() {
            if r[i - 1].v_m_per_s * r[i].v_m_per_s < 0.0 {
                let x0 = if r[i].v_m_per_s > 0.0 { r[i - 1].x_m.min(r[i].x_m) } else { r[i - 1].x_m.max(r[i].x_m) };
                let first = against(&r[i]);
                let mut crossing = None;
                let mut j = i + 1;
                while j < r.len() && r[j].v_m_per_s * r[i].v_m_per_s > 0.0 {
                    let (m0, m1) = (against(&r[j - 1]), against(&r[j]));
                    if m0 < 0.0 && m1 >= 0.0 {
                        let (d0, d1) = ((r[j - 1].x_m - x0).abs(), (r[j].x_m - x0).abs());
                        crossing = Some(d0 + (d1 - d0) * (-m0) / (m1 - m0));
                        break;
                    }
                    j += 1;
                }
                out.push((first, crossing));
                i = j;
            } else {
                i += 1;
            }
        }
        out
    };
    let a = Model::default().friction.a;
    let dahl = turns("dahl");
    assert!(dahl.len() >= 20, "{} reversals without a stick", dahl.len());
    let crossings: Vec<f64> = dahl.iter().filter_map(|t| t.1).collect();
    assert_eq!(crossings.len(), dahl.len(), "every reversal's friction turns over");
    let (first, crossing) = (mean(dahl.iter().map(|t| t.0)), mean(crossings.iter().copied()));
    let expected = length_m * 2f64.ln();
    println!(
        "dahl: friction against the motion just after a reversal {first:.4} (−a = {:.4}), 0 after {crossing:.4e} m \
         (δ ln 2 = {expected:.4e} m), over {} reversals",
        -a,
        dahl.len()
    );
    assert!(first < -0.9 * a, "dahl: {first} against the motion just after a reversal, a = {a}");
    assert!((crossing / expected - 1.0).abs() < 0.01, "dahl: turned over after {crossing} m, δ ln 2 = {expected} m");
    let build_up = turns("exponential");
    assert!(build_up.len() >= 20 && build_up.iter().all(|t| t.0 >= 0.0 && t.1.is_none()), "exponential: {build_up:?}");
}

/// Hysteresis `bristle`: a stick held by the contact's elasticity. Noise
/// off, at 7 Hz and 16.39 N where the block sticks at every reversal: while
/// stuck the block creeps with the base, x = κ u + (1 − κ) w with w fixed
/// and κ = k δ / (k δ + μ₀ N0), so x − κ u holds to rounding while x itself
/// moves by tens of micrometres, and v = κ du/dt; the contact force k (u − x)
/// stays within μ₀ N0 and reaches it at the breakaway (within the spring's
/// rise over one 20 µs sample). Under `dahl` the same δ leaves the stick
/// rigid: x holds and v is 0.
#[test]
fn a_bristle_stick_creeps_with_the_base_until_the_contact_lets_go() {
    let length_m = 2e-4;
    let condition = COND;
    let sets = [format!("friction_hysteresis.length_m={length_m}"), "friction_hysteresis.form=\"bristle\"".into()];
    let sets: Vec<&str> = sets.iter().map(String::as_str).collect();
    let (m, r) = noiseless_record(&sets, condition, 2.0, 50_000.0);
    let k = m.stiffness_n_per_m();
    let (u0, w) = (m.excitation.amplitude_m, std::f64::consts::TAU * condition.excitation_frequency_hz);
    let held_n = (m.friction.a + m.friction.b) * condition.normal_force_n;
    let kappa = k * length_m / (k * length_m + held_n);
    let u = |s: &Sample| u0 * (w * s.t_s).cos();
    let anchor = |s: &Sample| s.x_m - kappa * u(s);
    // Runs of samples over which x − κ u holds: the sticks, less their
    // first and last samples (the stick may begin or the slip have begun
    // between a sample and its neighbour).
    let mut stretches: Vec<&[Sample]> = Vec::new();
    let mut start = 0;
    for i in 1..=r.len() {
        if i == r.len() || (anchor(&r[i]) - anchor(&r[i - 1])).abs() > 1e-12 {
            if i - start >= 20 {
                stretches.push(&r[start + 1..i - 1]);
            }
            start = i;
        }
    }
    assert!(stretches.len() >= 20, "only {} sticks in 2 s at 7 Hz", stretches.len());
    let mut largest_force: f64 = 0.0;
    for stick in &stretches {
        let (first, last) = (&stick[0], &stick[stick.len() - 1]);
        assert!((last.x_m - first.x_m).abs() > 1e-6, "the block held still over a stick: {} m", last.x_m - first.x_m);
        for s in *stick {
            let creep = -kappa * u0 * w * (w * s.t_s).sin();
            assert!(
                (s.v_m_per_s - creep).abs() <= 1e-9 * creep.abs().max(1e-9),
                "v {} against κ du/dt {creep}",
                s.v_m_per_s
            );
            let force = k * (u(s) - s.x_m);
            assert!(force.abs() <= held_n * (1.0 + 1e-9), "contact force {force} N beyond μ₀ N0 = {held_n} N");
        }
        largest_force = largest_force.max((k * (u(last) - last.x_m)).abs());
    }
    // The contact force's rise over the two samples between the last one
    // read and the breakaway, at most.
    let rise_n = 2.0 * k * (1.0 - kappa) * u0 * w / 50_000.0;
    println!(
        "bristle: κ = {kappa:.4}, {} sticks, largest contact force {largest_force:.4} N of μ₀ N0 = {held_n:.4} N",
        stretches.len()
    );
    assert!(largest_force >= held_n - rise_n, "the contact let go at {largest_force} N, μ₀ N0 = {held_n} N");
    let dahl = [format!("friction_hysteresis.length_m={length_m}"), "friction_hysteresis.form=\"dahl\"".into()];
    let dahl: Vec<&str> = dahl.iter().map(String::as_str).collect();
    let (_, rigid) = noiseless_record(&dahl, condition, 2.0, 50_000.0);
    assert!(sticks(&rigid).len() >= 20, "dahl: {} sticks", sticks(&rigid).len());
}

/// Hysteresis `ageing`, the rate-and-state ageing law: the contact age θ
/// grows while stuck, and the static coefficient is
/// μ(0) + B ln((θ + θ_0)/(θ_c + θ_0)), so a stick twice as long raises it by
/// B ln 2 where sticks are long beside θ_0. L = 1 µm makes θ_c = L / 1 mm/s
/// = 1 ms and θ_0 = L / 1 m/s = 1 µs, against sticks of 31 ms (5 Hz) and
/// 57 ms (4 Hz) at 16.39 N: the static coefficients, read just before each
/// breakaway, differ by B times the difference of the mean ln t within 5%
/// (θ at the stick's start and the hold per noise interval, each under a
/// millisecond, shift ln t by a few percent). Each also lies within 10% of
/// its own prediction's excess over μ(0); without ageing both are μ(0).
#[test]
fn ageing_raises_the_static_friction_with_the_log_of_the_stick_time() {
    use stickslip::engine::effects::{AGEING_CUTOFF_SPEED_M_PER_S, AGEING_FLOOR_SPEED_M_PER_S};
    let (b, cutoff_age_s, floor_age_s) = (0.02, 1e-6 / AGEING_CUTOFF_SPEED_M_PER_S, 1e-6 / AGEING_FLOOR_SPEED_M_PER_S);
    let run = |strength: f64, hz: f64| -> (f64, f64, f64) {
        let strength = format!("friction_hysteresis.strength={strength}");
        let sets = ["friction_hysteresis.form=\"ageing\"", "friction_hysteresis.length_m=1e-6", &strength];
        let condition = Condition { excitation_frequency_hz: hz, normal_force_n: 16.39 };
        let (m, r) = noiseless_record(&sets, condition, 3.0, 50_000.0);
        let sticks = sticks(&r);
        assert!(sticks.len() >= 20, "ageing at {hz} Hz: {} sticks", sticks.len());
        let log_t = mean(sticks.iter().map(|s| s.0.ln()));
        let predicted = mean(sticks.iter().map(|s| ((s.0 + floor_age_s) / (cutoff_age_s + floor_age_s)).ln()));
        (mean(sticks.iter().map(|s| s.1)) - law(&m, 0.0), log_t, predicted)
    };
    let (short, long) = (run(b, 5.0), run(b, 4.0));
    let (rise, expected) = (long.0 - short.0, b * (long.1 - short.1));
    println!(
        "ageing: static excess {:.4} after {:.4} s, {:.4} after {:.4} s: rise {rise:.4}, B ln(t2/t1) {expected:.4}",
        short.0,
        short.1.exp(),
        long.0,
        long.1.exp()
    );
    assert!(long.1 - short.1 > 0.5, "sticks too alike: {} s and {} s", short.1.exp(), long.1.exp());
    assert!((rise / expected - 1.0).abs() < 0.05, "ageing: rise {rise}, B ln(t2/t1) = {expected}");
    for (excess, _, predicted) in [short, long] {
        assert!((excess / (b * predicted) - 1.0).abs() < 0.1, "ageing: excess {excess}, predicted {}", b * predicted);
    }
    let (short, long) = (run(0.0, 5.0), run(0.0, 4.0));
    assert!(short.0.abs() < 1e-3 && long.0.abs() < 1e-3, "without ageing: {} and {}", short.0, long.0);
}

/// Hysteresis `slip` and `ageing` raise the steps per period so that a step
/// is no longer than the slip distance's memory time L / (max(Ω, ω0) X) (X
/// the frictionless steady amplitude); `ageing` only where it is on (B ≠ 0);
/// a distance no allowed step count resolves is refused by name.
#[test]
fn a_slip_distance_raises_the_steps_to_resolve_it() {
    let m = Model::default();
    let x = m.linear_amplitude_m(COND.excitation_frequency_hz);
    let fastest_hz = m.rig.natural_frequency_hz.max(COND.excitation_frequency_hz);
    let needed = (std::f64::consts::TAU * fastest_hz * x / (COND.excitation_frequency_hz * 1e-4)).ceil() as u32;
    let steps = |sets: &[&str]| Oscillator::new(&model(sets), COND).expect("an oscillator").steps_per_period;
    let slip = steps(&["friction_hysteresis.form=\"slip\"", "friction_hysteresis.length_m=1e-4"]);
    let ageing = ["friction_hysteresis.form=\"ageing\"", "friction_hysteresis.length_m=1e-4"];
    let ageing_on = steps(&[ageing[0], ageing[1], "friction_hysteresis.strength=0.02"]);
    let ageing_off = steps(&ageing);
    println!("steps at 7 Hz with L = 0.1 mm: slip {slip}, ageing {ageing_on} (off: {ageing_off}), expected {needed}");
    assert!(needed > 400 && slip == needed && ageing_on == needed, "{slip}, {ageing_on}, {needed}");
    assert_eq!(ageing_off, m.solver.steps_per_period);
    let m = model(&["friction_hysteresis.form=\"slip\"", "friction_hysteresis.length_m=1e-12"]);
    let err = Oscillator::new(&m, COND).expect_err("refused").to_string();
    assert!(err.contains("friction_hysteresis.length_m") && err.contains("steps per period"), "{err}");
}

/// A slip distance far below one step's slip (10 µm against up to 0.4 mm
/// per step at the model's 64 steps at 7 Hz) integrated with the raised
/// steps: the friction
/// coefficient stays between the law's kinetic floor a and its static μ(0)
/// = a + b, where the relaxation from μ(0) to the falling law keeps it,
/// instead of running away (RK4 on the relaxation is unstable past 2.8 L of
/// slip per step), and four times as many steps change it by under 1e-3.
/// Noise off, so the law is known exactly at every sample.
#[test]
fn a_short_slip_distance_is_integrated_stably() {
    let sets = ["friction_hysteresis.form=\"slip\"", "friction_hysteresis.length_m=1e-5"];
    let steps = Oscillator::new(&model(&sets), COND).expect("an oscillator").steps_per_period;
    let finer = format!("solver.steps_per_period={}", 4 * steps);
    let (m, r) = noiseless_record(&sets, COND, 3.0, 600.0);
    let (_, fine) = noiseless_record(&[sets[0], sets[1], &finer], COND, 3.0, 600.0);
    let mu = |s: &Sample| s.friction_force_n.abs() / s.normal_force_n;
    let slipping: Vec<(&Sample, &Sample)> = r.iter().zip(&fine).filter(|(s, _)| s.v_m_per_s.abs() > 1e-3).collect();
    assert!(slipping.len() > 500, "only {} slipping samples", slipping.len());
    let (floor, top) = (m.friction.a, law(&m, 0.0));
    assert_eq!(m.friction.d, 0.0, "the paper rig's law falls from a + b to a");
    let outside = slipping.iter().filter(|(s, _)| !(floor - 1e-9..=top + 1e-9).contains(&mu(s))).count();
    let worst = slipping.iter().map(|(s, f)| (mu(s) - mu(f)).abs()).fold(0.0f64, f64::max);
    let lag = slipping.iter().map(|(s, _)| (mu(s) - law(&m, s.v_m_per_s)).abs()).fold(0.0f64, f64::max);
    println!(
        "slip law over 10 µm at {steps} steps: μ within [{floor}, {top}] but for {outside}; |μ − μ(v)| up to \
         {lag:.2e}; against {} steps up to {worst:.2e}",
        4 * steps
    );
    assert!(outside == 0 && worst < 1e-3, "{outside} samples outside the law's range; {worst} from finer steps");
}
