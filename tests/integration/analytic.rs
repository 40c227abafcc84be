//! The integrators against closed-form results: the linear response and
//! Den Hartog's exact Coulomb solution, amplitude and phase, on the CPU (1e-4)
//! and the GPU (1e-3).

use stickslip::engine::analytic::{DenHartog, linear_amplitude_ratio, linear_phase_rad};
use stickslip::engine::{Condition, InitialState, Model, PathResult, RunPlan};

use crate::common;

/// One realisation on the reference.
fn cpu_path(m: &Model, cond: Condition, seed: u64, plan: RunPlan, initial: InitialState) -> PathResult {
    common::paths(common::cpu(), m, cond, initial, seed, 1, plan).remove(0)
}

const NO_NOISE: [&str; 2] = ["friction.sigma=0", "normal_force.sigma=0"];

fn model(extra: &[&str]) -> Model {
    let sets: Vec<String> = NO_NOISE.iter().chain(extra).map(|s| s.to_string()).collect();
    Model::paper_rig(&sets).unwrap()
}

/// Largest relative deviation of every peak from `exact`.
fn worst_error(peaks: &[f64], exact: f64) -> f64 {
    peaks.iter().map(|p| (p / exact - 1.0).abs()).fold(0.0, f64::max)
}

/// Largest deviation (rad) of every period's phase from `exact`, modulo 2π.
fn worst_phase_error(paths: &[PathResult], exact: f64) -> f64 {
    paths
        .iter()
        .flat_map(|p| &p.phases_rad)
        .map(|phase| stickslip::engine::reduce::wrap_angle(phase - exact).abs())
        .fold(0.0, f64::max)
}

#[test]
fn linear_response_cpu_and_gpu() {
    let zeta = 0.02;
    let m = model(&["friction.a=0", "friction.b=0", "rig.damping_ratio=0.02"]);
    let plan = RunPlan { warmup_cycles: 5, measured_cycles: 20 };
    for eta in [0.5, 0.8, 1.2, 2.0] {
        let f = eta * m.rig.natural_frequency_hz;
        let cond = Condition { excitation_frequency_hz: f, normal_force_n: 10.0 };
        let (x, v) = m.linear_steady_state_at_zero(f);
        let initial = InitialState { x_m: x, v_m_per_s: v };
        let exact = m.excitation.amplitude_m * linear_amplitude_ratio(eta, zeta);
        let cpu = cpu_path(&m, cond, 1, plan, initial);
        let cpu_err = worst_error(&cpu.peaks_m, exact);
        let gpu = common::paths(common::gpu(), &m, cond, initial, 1, 64, plan);
        let gpu_err = gpu.iter().map(|p| worst_error(&p.peaks_m, exact)).fold(0.0, f64::max);
        println!("linear eta {eta}: cpu {cpu_err:.2e}, gpu {gpu_err:.2e}");
        assert!(cpu_err < 1e-4, "CPU linear response at eta {eta}: relative error {cpu_err:e}");
        assert!(gpu_err < 1e-3, "GPU linear response at eta {eta}: relative error {gpu_err:e}");
    }
}

/// The per-period phase of the fundamental against `atan2(2ζη, 1 − η²)`
/// (friction and noise off, ζ = 0.02) at ten frequency ratios, on the CPU
/// (1e-4 rad) and the GPU (1e-3 rad).
#[test]
fn linear_phase_cpu_and_gpu() {
    let zeta = 0.02;
    let m = model(&["friction.a=0", "friction.b=0", "rig.damping_ratio=0.02"]);
    let plan = RunPlan { warmup_cycles: 5, measured_cycles: 20 };
    for eta in [0.3, 0.5, 0.7, 0.8, 0.9, 1.1, 1.2, 1.5, 2.0, 3.0] {
        let cond = Condition { excitation_frequency_hz: eta * m.rig.natural_frequency_hz, normal_force_n: 10.0 };
        let initial = InitialState::steady(&m, cond);
        let exact = linear_phase_rad(eta, zeta);
        let cpu_err = worst_phase_error(&[cpu_path(&m, cond, 1, plan, initial)], exact);
        let gpu_err = worst_phase_error(&common::paths(common::gpu(), &m, cond, initial, 1, 64, plan), exact);
        println!("linear phase eta {eta}: exact {:.4} rad; cpu error {cpu_err:.2e}, gpu {gpu_err:.2e} rad", exact);
        assert!(cpu_err < 1e-4, "CPU linear phase at eta {eta}: error {cpu_err:e} rad");
        assert!(gpu_err < 1e-3, "GPU linear phase at eta {eta}: error {gpu_err:e} rad");
    }
}

/// Den Hartog points: (η, friction as a share of the no-stop threshold).
const DEN_HARTOG_POINTS: [(f64, f64); 10] = [
    (0.6, 0.8),
    (0.7, 0.5),
    (0.8, 0.8),
    (0.95, 0.3),
    (0.95, 0.8),
    (1.2, 0.8),
    (1.5, 0.5),
    (2.0, 0.8),
    (2.5, 0.2),
    (3.0, 0.8),
];

/// Amplitude against `x0 = U0 sqrt(V² − β² U²)`, and the per-period phase
/// of the fundamental against that of Den Hartog's exact solution (its
/// Fourier coefficients; `model.md`'s `sin φ = −βU/V` is the angle of the
/// solution's maximum, which the initial state is built from).
#[test]
fn den_hartog_cpu_and_gpu() {
    let normal_force_n = 10.0;
    let plan = RunPlan { warmup_cycles: 0, measured_cycles: 30 };
    for (eta, share) in DEN_HARTOG_POINTS {
        let beta = share * DenHartog::stop_threshold(eta);
        let dh = DenHartog { eta, beta };
        let base = model(&["friction.b=0", "rig.damping_ratio=0"]);
        let mu = beta * base.stiffness_n_per_m() * base.excitation.amplitude_m / normal_force_n;
        let m = model(&["friction.b=0", "rig.damping_ratio=0", &format!("friction.a={mu}")]);
        let f = eta * m.rig.natural_frequency_hz;
        let cond = Condition { excitation_frequency_hz: f, normal_force_n };
        let w0 = std::f64::consts::TAU * m.rig.natural_frequency_hz;
        let initial = dh.state_at_zero(w0, m.excitation.amplitude_m).expect("a non-stop solution");
        let exact = dh.amplitude_ratio().unwrap() * m.excitation.amplitude_m;
        let cpu = cpu_path(&m, cond, 1, plan, initial);
        let cpu_err = worst_error(&cpu.peaks_m, exact);
        let gpu = common::paths(common::gpu(), &m, cond, initial, 1, 64, plan);
        let gpu_err = gpu.iter().map(|p| worst_error(&p.peaks_m, exact)).fold(0.0, f64::max);
        let exact_phase = dh.phase_rad().unwrap();
        let cpu_phase_err = worst_phase_error(std::slice::from_ref(&cpu), exact_phase);
        let gpu_phase_err = worst_phase_error(&gpu, exact_phase);
        println!(
            "Den Hartog eta {eta} beta {beta:.4}: cpu {cpu_err:.2e}, gpu {gpu_err:.2e}; phase {exact_phase:.4} rad, \
             cpu {cpu_phase_err:.2e}, gpu {gpu_phase_err:.2e} rad"
        );
        assert!(cpu_phase_err < 1e-4, "CPU phase vs Den Hartog at eta {eta}, beta {beta}: {cpu_phase_err:e} rad");
        assert!(gpu_phase_err < 1e-3, "GPU phase vs Den Hartog at eta {eta}, beta {beta}: {gpu_phase_err:e} rad");
        assert_eq!(cpu.stick_time_s, 0.0, "Den Hartog's solution has no stops (eta {eta}, beta {beta})");
        assert!(cpu_err < 1e-4, "CPU vs Den Hartog at eta {eta}, beta {beta}: {cpu_err:e}");
        assert!(gpu_err < 1e-3, "GPU vs Den Hartog at eta {eta}, beta {beta}: {gpu_err:e}");
    }
}

/// Above the no-stop threshold the block must stick: the threshold formula
/// and the integrator's stick logic agree.
#[test]
fn den_hartog_threshold_separates_stops() {
    let normal_force_n = 10.0;
    for eta in [0.7, 1.5] {
        for (share, sticks) in [(0.9, false), (1.15, true)] {
            let beta = share * DenHartog::stop_threshold(eta);
            let base = model(&[]);
            let mu = beta * base.stiffness_n_per_m() * base.excitation.amplitude_m / normal_force_n;
            let m = model(&["friction.b=0", "rig.damping_ratio=0", &format!("friction.a={mu}")]);
            let f = eta * m.rig.natural_frequency_hz;
            let cond = Condition { excitation_frequency_hz: f, normal_force_n };
            let (x, v) = m.linear_steady_state_at_zero(f);
            let r = cpu_path(
                &m,
                cond,
                1,
                RunPlan { warmup_cycles: 200, measured_cycles: 20 },
                InitialState { x_m: x, v_m_per_s: v },
            );
            assert_eq!(
                r.stick_time_s > 0.0,
                sticks,
                "eta {eta}, {share} of the threshold: stick time {}",
                r.stick_time_s
            );
        }
    }
}

/// The mean peak of the paper rig at `steps` steps per period, on the CPU
/// reference from the linear steady state: `realisations` paths of seed
/// `seed` under `plan`, m.
fn paper_rig_mean_peak(steps: u32, cond: Condition, plan: RunPlan, seed: u64, realisations: u32) -> f64 {
    let m = Model::paper_rig(&[format!("solver.steps_per_period={steps}")]).unwrap();
    let (x, v) = m.linear_steady_state_at_zero(cond.excitation_frequency_hz);
    let initial = InitialState { x_m: x, v_m_per_s: v };
    let paths = common::paths(common::cpu(), &m, cond, initial, seed, realisations, plan);
    let all: Vec<f64> = paths.iter().flat_map(|p| p.peaks_m.clone()).collect();
    all.iter().sum::<f64>() / all.len() as f64
}

/// Halving the step changes the mean peak of the noisy default model by
/// less than 1e-6 relative.
#[test]
fn cpu_step_convergence() {
    let cond = Condition { excitation_frequency_hz: 7.0, normal_force_n: 16.39 };
    let plan = RunPlan { warmup_cycles: 20, measured_cycles: 50 };
    let mean_peak = |steps: u32| paper_rig_mean_peak(steps, cond, plan, 3, 32);
    let (coarse, fine) = (mean_peak(256), mean_peak(512));
    let change = (fine / coarse - 1.0).abs();
    println!("mean peak 256 steps {coarse:e}, 512 steps {fine:e}: relative change {change:.2e}");
    assert!(change < 1e-6, "halving the step changed the mean peak by {change:e}");
}

/// The default step (`[solver] steps_per_period`, chosen by measurement,
/// not habit) is converged where the main job's grid is hardest, next to
/// resonance (10 Hz, 4 N: the largest and fastest motion): on the same
/// noise, four times as many steps change the mean peak by less than
/// 1e-4 relative, a twenty-fifth of the main job's standard error of a
/// mean peak there (6400 peaks of relative spread ≈ 0.2: ≈ 2.5e-3).
#[test]
fn default_step_is_converged_next_to_resonance() {
    let steps = Model::default().solver.steps_per_period;
    let cond = Condition { excitation_frequency_hz: 10.0, normal_force_n: 4.0 };
    let plan = RunPlan { warmup_cycles: 50, measured_cycles: 50 };
    let mean_peak = |steps: u32| paper_rig_mean_peak(steps, cond, plan, 1, 16);
    let (coarse, fine) = (mean_peak(steps), mean_peak(4 * steps));
    let change = (fine / coarse - 1.0).abs();
    println!(
        "mean peak at 10 Hz, 4 N: {steps} steps {coarse:e}, {} steps {fine:e}: relative change {change:.2e}",
        4 * steps
    );
    assert!(change < 1e-4, "four times the default step count changed the mean peak by {change:e}");
}

/// The embedded default reproduces Figure 8(d)'s measured mean peak,
/// 3.854 mm at 7 Hz and 16.39 N, within 2%.
#[test]
fn default_model_matches_figure_8d_mean() {
    let m = Model::default();
    let cond = Condition { excitation_frequency_hz: 7.0, normal_force_n: 16.39 };
    let (x, v) = m.linear_steady_state_at_zero(7.0);
    let plan = RunPlan { warmup_cycles: 100, measured_cycles: 350 };
    let paths = common::paths(common::cpu(), &m, cond, InitialState { x_m: x, v_m_per_s: v }, 11, 64, plan);
    let all: Vec<f64> = paths.iter().flat_map(|p| p.peaks_m.clone()).collect();
    let mean = all.iter().sum::<f64>() / all.len() as f64;
    let off = mean / 3.854e-3 - 1.0;
    println!("default model mean peak {:.4} mm ({:+.2}% from 3.854 mm)", mean * 1e3, off * 100.0);
    assert!(off.abs() < 0.02, "default mean peak {mean:e} m is {off:+.4} from 3.854 mm");
}
