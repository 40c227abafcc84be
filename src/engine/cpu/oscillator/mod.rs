//! The f64 reference integrator of one realisation.
//!
//! Each realisation is integrated in steps of at most `T / steps_per_period`.
//! Noise-interval boundaries, output samples and period ends are step
//! boundaries (each span between them is divided into equal steps), so
//! every random value holds exactly over its interval. Slip phases
//! use classical RK4 with the slip direction frozen (the ODE is smooth there);
//! a velocity zero inside a step is located by root finding on the RK4 map
//! itself (Newton's method in a bracket), and the stick→slip breakaway is solved in closed
//! form because the block is at rest and only the base moves (on the elastic
//! stick of hysteresis `bristle` the block follows the base by a fixed share,
//! so the contact force is still a cosine of the base's phase). No `sgn` is
//! smoothed. The base's `cos Ωt` and `sin Ωt` are exact at the start of each
//! span and carried through its steps by rotation (by `Ωh/2` for each half
//! step), so a step evaluates no trigonometric function.
//!
//! The realisation being integrated is one type, `Path`:
//! - this file: its state, its noise and its friction law;
//! - `step.rs`: the slip ODE's RK4 step, velocity zeros, breakaway from
//!   stick, and a segment between two grid times;
//! - `interval.rs`: a group's noise at the start of each interval;
//! - `period.rs`: a period of up to `LANES` paths stepped together, and the
//!   output samples of records;
//! - `simd/`: the slip step of all lanes as vector code, and probes of
//!   their velocity zeros (the lanes' state and the law in files of their
//!   own);
//! - `zeros.rs`: the velocity zeros of several lanes located side by side.
//!
//! `shaders/oscillator.wgsl` is the same algorithm in f32; the functions
//! carry the kernel's names and come in its order, file after file. The two
//! differ on purpose in these places, and nowhere else:
//!
//! | what | CPU (f64) | GPU (f32) | why |
//! | --- | --- | --- | --- |
//! | arithmetic | f64 | f32 | WGSL has no portable f64; the CPU is the judge |
//! | events per segment before forcing progress | 64 | 16 | a chattering guard only; the GPU's loops must stay short (lavapipe's loop limiter, SIMD divergence) |
//! | velocity zero: method, iterations / tolerance on the step | Newton in the bracket, 100 / 1e-15 · max(h, 10⁻⁶ T) | Illinois, 40 / 2e-7 · h | each converges to its own precision: 1e-15 is f64's, 2e-7 is f32's (2⁻²³ ≈ 1.2e-7); Newton needs the acceleration at each probe's end, a fifth evaluation per probe, and under half the probes |
//! | halvings probing for motion after a start from rest | 60, from a guess of the first under way, walked to it | 30, one by one from h/2 | 2⁻⁶⁰ and 2⁻³⁰ of the step are below each type's resolution; both find the same probe (the first under way) where the motion's sign changes once, the CPU in about two steps |
//! | time inside a period | span start + `k · h` in f64 | the same in f32, boundary position `frac · S / 2³²` by `mulhilo` | f32 cannot hold 32.32 fixed point; both switch noise at the same instants |
//! | `cos Ωt`, `sin Ωt` | exact at the period start and after events, rotated otherwise | also exact at every noise boundary and every 16 steps | f32 rotations drift by about 1e-7 each, f64 ones by 1e-16 |
//! | a `bristle` stick's slider anchor w | kept in the path | recomputed from x at each dispatch's start (a period start), as the path states keep no anchor | the same w within f32 rounding; the states' layout is shared with the host |
//! | noise interval index | u64 | u32 (runs are refused past 2³² intervals) | WGSL has no u64 |
//! | normal-force harmonics' `cos((k+1)θ + φ)` per interval | one `sin_cos` of θ, rotated to (k+1)θ, turned by φ's stored (cos, sin) | a `cos` per harmonic | libm's `cos` was 13% of a diagnosis of harmonics in the CPU reference; the CPU's sum is within 1e-14 N of the direct one (`harmonics_by_angle_addition_match_a_cos_per_harmonic`) |
//! | realisations per thread | up to `LANES` of one point, or of several loads at one frequency (`steps_beside`), stepped together: each grid step's slip step for all as vector code (`simd`), then events one lane at a time (`run_period`), velocity zeros met in the same step located side by side (`zeros`); their noise drawn side by side, or read from tables their realisations' other paths share (`noise`) | one per invocation | the GPU's SIMD already runs invocations side by side; on the CPU one realisation alone waits out each stage's latency. The answers are those of one at a time, bit for bit |
//!
//! Output samples (records) between noise boundaries split steps on the CPU
//! only; records sampled at the noise boundaries split none, and the GPU
//! kernel writes those itself.

mod interval;
mod period;
mod simd;
mod step;
#[cfg(test)]
mod tests;
mod zeros;

#[cfg(test)]
pub(crate) use period::QUARTER_LANES;
pub(crate) use period::{LANE_WIDTHS, Sampler, run_period};
pub(crate) use simd::LANES;

use crate::engine::cpu::{effects, noise};
use crate::engine::effects::{
    AGEING_CUTOFF_SPEED_M_PER_S, AGEING_FLOOR_SPEED_M_PER_S, ColourForm, DriftForm, EffectParams, HarmonicForm,
    HysteresisForm, Memory, STICTION_DECAY_M, StictionForm, drift_factor,
};
use crate::engine::oscillator::{InitialState, Oscillator, Sample};
use crate::engine::rng;
use crate::engine::schedule::FIXED_ONE;
use zeros::PastZero;

/// Whether paths of oscillators `a` and `b` may step in one lane group
/// ([`run_period`]): the same model at the same frequency, apart from the
/// load. A group shares its step grid (period, noise boundaries, steps per
/// period where those are shorter than the noise interval), its noise key
/// and the law's forms; what depends on the load is
/// each lane's own: the mean normal force (with the drift's nominal
/// scale), and the effects' terms at that load (the harmonics'
/// amplitudes, the non-Gaussian noise's strength, the friction offset and
/// scale), which the vector step reads lane by lane
/// ([`Path::slip_law`]) and the noise draws oscillator by oscillator.
/// The noise's terms (harmonics, non-Gaussian) must be zero at one load
/// where they are zero at the other, since the group decides on its first
/// lane's whether its noise is plain. Anything else that differs keeps
/// them apart.
pub(crate) fn steps_beside(a: &Oscillator, b: &Oscillator) -> bool {
    if std::ptr::eq(a, b) {
        return true;
    }
    let (ea, eb) = (&a.effects, &b.effects);
    let zero_alike = |x: f64, y: f64| (x == 0.0) == (y == 0.0);
    let per_load_alike = zero_alike(ea.non_gaussian_strength, eb.non_gaussian_strength)
        && zero_alike(ea.non_gaussian_cubic, eb.non_gaussian_cubic)
        && ea.harmonic_amplitudes_n.iter().zip(&eb.harmonic_amplitudes_n).all(|(&x, &y)| zero_alike(x, y));
    if !per_load_alike {
        return false;
    }
    let mut as_a = b.clone();
    as_a.normal_force_mean_n = a.normal_force_mean_n;
    // A step longer than the noise interval is never taken whole: every
    // span between noise boundaries (at most one interval) is one step at
    // either count, so two such counts (the law's rule raises them with
    // the load) make the same grid. The margin covers the boundaries'
    // fixed-point rounding.
    let noise_sets_the_steps =
        |o: &Oscillator| o.period_s / f64::from(o.steps_per_period) > o.noise_interval_s * 1.000_001;
    if noise_sets_the_steps(a) && noise_sets_the_steps(b) {
        as_a.steps_per_period = a.steps_per_period;
    }
    let (e, from) = (&mut as_a.effects, &a.effects);
    e.harmonic_amplitudes_n = from.harmonic_amplitudes_n;
    e.non_gaussian_strength = from.non_gaussian_strength;
    e.non_gaussian_cubic = from.non_gaussian_cubic;
    e.friction_offset = from.friction_offset;
    e.friction_scale = from.friction_scale;
    as_a == *a
}

/// Whether the block sticks or slips, and in which direction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    Stick,
    /// Slipping with velocity sign +1 or −1.
    Slip(i8),
}

/// Halvings of a step probing for motion after a start from rest: 2⁻⁶⁰ of
/// a step is below f64's resolution of it.
const MAX_PROBE_HALVINGS: i32 = 60;

/// Events handled within one segment before the integrator forces progress
/// (guards against chattering at exactly balanced forces).
const MAX_EVENTS_PER_SEGMENT: u32 = 64;

/// `cos Ωt` and `sin Ωt` of the base at one time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Trig {
    pub(crate) cos: f64,
    pub(crate) sin: f64,
}

impl Trig {
    /// At phase `theta` (rad).
    fn at(theta: f64) -> Trig {
        let (sin, cos) = theta.sin_cos();
        Trig { cos, sin }
    }

    /// A rotation by a half step's angle `theta` (rad): Taylor series up to
    /// 0.1 rad (terms through θ¹⁰: the first omitted, θ¹¹/11!, is under
    /// 3e-19, below f64's resolution), `sin_cos` above. A noise interval of
    /// 1/600 s at 10–20 Hz is a half turn of 0.05–0.1 rad.
    fn turn(theta: f64) -> Trig {
        if theta.abs() > 0.1 {
            return Trig::at(theta);
        }
        let t2 = theta * theta;
        let sin = theta * (1.0 - t2 / 6.0 * (1.0 - t2 / 20.0 * (1.0 - t2 / 42.0 * (1.0 - t2 / 72.0))));
        let cos = 1.0 - t2 / 2.0 * (1.0 - t2 / 12.0 * (1.0 - t2 / 30.0 * (1.0 - t2 / 56.0 * (1.0 - t2 / 90.0))));
        Trig { cos, sin }
    }

    /// Advanced by the rotation `by` (the cos and sin of an angle).
    fn rotated(self, by: Trig) -> Trig {
        Trig { cos: self.cos * by.cos - self.sin * by.sin, sin: self.sin * by.cos + self.cos * by.sin }
    }
}

/// The normal force's harmonics (N) at `interval_phase` (of the excitation
/// period, –): Σ A_k w(cos((k+1)θ + φ_k)), θ = 2π · `interval_phase`, each
/// cosine by angle addition from one `sin_cos` of θ ((k+1)θ by repeated
/// rotation, then φ_k's stored cos and sin) instead of a `cos` per harmonic.
/// The `position` form instead follows `x_per_u0`, the displacement at the
/// interval's start over the base amplitude (–): αN0 r + βN0 r².
fn harmonics_n(e: &EffectParams, interval_phase: f64, x_per_u0: f64) -> f64 {
    if e.harmonic_amplitudes_n.iter().all(|&a| a == 0.0) {
        return 0.0;
    }
    if e.harmonic_form == HarmonicForm::Position {
        return effects::position_load(e.harmonic_amplitudes_n[0], e.harmonic_amplitudes_n[1], x_per_u0);
    }
    let base = Trig::at(std::f64::consts::TAU * interval_phase);
    let mut multiple = base;
    let mut sum_n = 0.0;
    for k in 0..4 {
        if k > 0 {
            multiple = multiple.rotated(base);
        }
        if e.harmonic_amplitudes_n[k] != 0.0 {
            let (cos_phase, sin_phase) = e.harmonic_phase_cos_sin[k];
            let c = multiple.cos * cos_phase - multiple.sin * sin_phase;
            sum_n += e.harmonic_amplitudes_n[k]
                * effects::harmonic_wave(e.harmonic_form, c, e.harmonic_shape, e.harmonic_shape_mean);
        }
    }
    sum_n
}

/// One RK4 step of the slip ODE, with what the phase quadrature needs: the
/// four stage displacements (m) and the base's trig at the step's start,
/// middle and end.
#[derive(Clone, Copy, Debug)]
struct SlipStep {
    x_m: f64,
    v_m_per_s: f64,
    /// The friction memory at the end (μ_f, –, or θ, s; see [`Memory`]).
    memory: f64,
    stage_x_m: [f64; 4],
    trig: [Trig; 3],
}

/// The phase lag (rad) of a period's fundamental behind the base, from
/// `∫ x cos(Ωt) dt` and `∫ x sin(Ωt) dt` over the period: the fundamental is
/// `sqrt(a² + b²) cos(Ωt − φ)` with `φ = atan2(b, a)` (`interfaces.md`).
pub fn phase_of(cos_integral: f64, sin_integral: f64) -> f64 {
    sin_integral.atan2(cos_integral)
}

/// The state of one realisation.
#[derive(Clone, Debug)]
pub(crate) struct Path<'a> {
    osc: &'a Oscillator,
    key: [u32; 2],
    realisation: u32,
    /// The main stream's pair A of this realisation's intervals, drawn
    /// once for every path of it ([`noise`]); where it ends (or with
    /// none), [`Path::draw_noise`] draws them itself.
    pub(crate) pair_a_table: noise::PathPairs,
    /// Displacement x, m.
    pub(crate) x_m: f64,
    /// Velocity v, m/s.
    pub(crate) v_m_per_s: f64,
    mode: Mode,
    /// Index of the current excitation period.
    period: u64,
    /// Index of the current noise interval.
    interval: u64,
    /// Start of the next noise interval, in periods, 32.32 fixed point.
    next_boundary: u64,
    /// Friction coefficient's random part `σ_μ ξ_μ` in the current interval, –.
    friction_noise: f64,
    /// Normal force in the current interval, N.
    normal_force_n: f64,
    /// x where the current slip began, m (displacement hysteresis, stiction release).
    slip_start_x_m: f64,
    /// Coloured noise states: the AR(1) parts of `ar1`, `two_scale`,
    /// `multi_scale` and `fast_slow`, –.
    colour_state: [f64; 3],
    /// Start of the current noise interval within its period, in periods.
    interval_phase: f64,
    /// Static-friction excess in the current interval, –.
    stiction_excess: f64,
    /// The friction memory: μ_f of hysteresis `lag` and `slip` (–), the
    /// contact age θ of `ageing` (s; while stuck, θ when the stick began),
    /// the factor φ₀ the current slip's friction turned from under `dahl`
    /// (–; held through the slip, as no memory rate moves it).
    memory: f64,
    /// The static coefficient's contact-age term B ln((θ + θ_0)/(θ_c + θ_0)) of
    /// hysteresis `ageing`, with θ at the current interval's start while
    /// stuck (or at the stick's start), and at the last velocity zero, –.
    ageing_excess: f64,
    /// When the current stick began, s from the run's start (stiction
    /// `dwell`, hysteresis `ageing`).
    stick_since_s: f64,
    /// The `random_walk` drift's walk W at the current interval (N0 is
    /// times 1 + W), –; 0 for every other form.
    drift_walk: f64,
    /// Whether sliding friction depends on more than the current velocity
    /// and interval (hysteresis, or a stiction excess carried into the
    /// slip): whether its coefficient takes more than the baseline's
    /// arithmetic. An adhesion force does not set it: it is one more term
    /// on top of μN, which the baseline's step adds too.
    history: bool,
    /// Which friction memory is on ([`Memory::form`] of the effects).
    memory_form: Memory,
    /// The law's a, b (–) and d (s²/m²) at this point's load: times
    /// (N0/Nref)^k under load dependence `scaled`, themselves otherwise.
    law_a: f64,
    law_b: f64,
    law_d: f64,
    /// 1 / m, 1/kg.
    inv_mass: f64,
    /// κ = k / (k + k_t) of hysteresis `bristle`: the share of the base's
    /// motion a stuck block follows on the contact's elasticity, –; 0 for
    /// a rigid stick (every other form).
    stick_compliance: f64,
    /// The anchored slider's position w while stuck, m: the block is at
    /// x = κ u + (1 − κ) w (w = x for a rigid stick).
    stick_anchor_m: f64,
    /// Largest x so far in the current period, m.
    pub(crate) period_max_x_m: f64,
    /// Time stuck so far in the current period, s.
    pub(crate) period_stick_s: f64,
    /// `∫ x cos(Ωt) dt` and `∫ x sin(Ωt) dt` over the current period so far,
    /// m·s (the response's fundamental; see [`phase_of`]).
    pub(crate) period_cos_integral: f64,
    pub(crate) period_sin_integral: f64,
    /// The last `acos` of each breakaway direction's level, by the level's
    /// bits (a stuck block's are the same over an interval; [`Path::breakaway_time`]).
    entry_acos: std::cell::Cell<[(u64, f64); 2]>,
}

impl<'a> Path<'a> {
    pub(crate) fn new(osc: &'a Oscillator, seed: u64, realisation: u32, initial: InitialState) -> Self {
        let e = &osc.effects;
        let memory_form = Memory::form(e);
        let build_up = matches!(
            e.hysteresis_form,
            HysteresisForm::Exponential
                | HysteresisForm::Tanh
                | HysteresisForm::Rational
                | HysteresisForm::Dahl
                | HysteresisForm::Bristle
        );
        let (law_a, law_b) = (osc.friction_a * e.friction_scale, osc.friction_b * e.friction_scale);
        let stick_compliance = if e.hysteresis_form == HysteresisForm::Bristle && e.hysteresis_length_m > 0.0 {
            effects::bristle_compliance(
                osc.stiffness_n_per_m,
                (law_a + e.friction_offset + law_b) * osc.normal_force_mean_n,
                e.hysteresis_length_m,
            )
        } else {
            0.0
        };
        let history = memory_form != Memory::None
            || (e.hysteresis_length_m != 0.0 && build_up)
            || e.stiction_form == StictionForm::Decaying
            || (e.stiction_form == StictionForm::Constant && e.stiction_release_m > 0.0);
        let mut path = Path {
            osc,
            key: rng::seed_key(seed),
            realisation,
            pair_a_table: noise::PathPairs::default(),
            x_m: initial.x_m,
            v_m_per_s: initial.v_m_per_s,
            mode: Mode::Stick,
            period: 0,
            interval: 0,
            next_boundary: osc.noise_interval_fixed,
            friction_noise: 0.0,
            normal_force_n: 0.0,
            slip_start_x_m: initial.x_m,
            colour_state: [0.0; 3],
            interval_phase: 0.0,
            stiction_excess: 0.0,
            memory: 0.0,
            ageing_excess: 0.0,
            stick_since_s: 0.0,
            drift_walk: 0.0,
            history,
            memory_form,
            law_a,
            law_b,
            law_d: osc.friction_d_s2_per_m2 * e.friction_scale,
            inv_mass: 1.0 / osc.mass_kg,
            stick_compliance,
            stick_anchor_m: initial.x_m,
            period_max_x_m: initial.x_m,
            period_stick_s: 0.0,
            period_cos_integral: 0.0,
            period_sin_integral: 0.0,
            entry_acos: std::cell::Cell::new([(f64::NAN.to_bits(), f64::NAN); 2]),
        };
        path.draw_noise();
        path.mode = if initial.v_m_per_s > 0.0 {
            Mode::Slip(1)
        } else if initial.v_m_per_s < 0.0 {
            Mode::Slip(-1)
        } else {
            path.stick_or_slip(Trig { cos: 1.0, sin: 0.0 })
        };
        if path.mode == Mode::Stick {
            path.start_stick(0.0, Trig { cos: 1.0, sin: 0.0 });
        } else if path.memory_form != Memory::Ageing {
            // The contact age starts at 0 whether the block sticks or slips.
            path.memory = path.breakaway_memory();
        }
        path
    }

    /// Noise values (and everything else held per interval) of the current
    /// interval. The main stream's pair A gives the friction's white value
    /// and the normal force's; pair B and the colour stream are drawn only
    /// by the effects that use them.
    fn draw_noise(&mut self) {
        self.draw_noise_with(None);
    }

    /// Whether [`Path::draw_noise`] draws the current interval's pair A
    /// itself (no table holds it).
    fn draws_pair_a(&self) -> bool {
        self.pair_a_table.get(self.interval).is_none()
    }

    /// The current interval's pair A of the main stream, `(ξ_μ, ξ_N)` (–):
    /// from the table where it holds the interval, else drawn.
    fn pair_a(&self) -> (f64, f64) {
        self.pair_a_table.get(self.interval).unwrap_or_else(|| {
            rng::pair_a(rng::noise_block(self.key, self.realisation, rng::STREAM_MAIN, self.interval))
        })
    }

    /// [`Path::draw_noise`] with the current interval's pair A drawn
    /// already (`Some`: the same values as its own draw).
    fn draw_noise_with(&mut self, pair_a: Option<(f64, f64)>) {
        let o = self.osc;
        let e = &o.effects;
        let block = |interval: u64| rng::noise_block(self.key, self.realisation, rng::STREAM_MAIN, interval);
        let main = || block(self.interval);
        let (white, xi_n) = pair_a.unwrap_or_else(|| self.pair_a());
        // The block the friction's value comes from (its interval's, or
        // the first of its hold): Philox is one-to-one on counters, so
        // the blocks are the same exactly when their intervals are.
        let friction_interval = if e.colour_form == ColourForm::Hold && e.colour_hold_intervals > 1 {
            self.interval / u64::from(e.colour_hold_intervals)
        } else {
            self.interval
        };
        let friction_block = || block(friction_interval);
        let z = if friction_interval == self.interval { white } else { rng::pair_a(friction_block()).0 };
        let colour = || rng::noise_block(self.key, self.realisation, rng::STREAM_COLOUR, self.interval);
        let first = self.interval == 0;
        let ar1 = |state: f64, rho: f64, innovation: f64| {
            if first { innovation } else { rho * state + (1.0 - rho * rho).sqrt() * innovation }
        };
        let g = match e.colour_form {
            _ if e.colour_rho == 0.0 => z,
            ColourForm::Ar1 if e.colour_share >= 1.0 => {
                self.colour_state[0] = ar1(self.colour_state[0], e.colour_rho, z);
                self.colour_state[0]
            }
            ColourForm::Ar1 => {
                self.colour_state[0] = ar1(self.colour_state[0], e.colour_rho, rng::pair_a(colour()).0);
                (1.0 - e.colour_share).sqrt() * z + e.colour_share.sqrt() * self.colour_state[0]
            }
            ColourForm::Hold => z,
            ColourForm::TwoScale => {
                self.colour_state[0] = ar1(self.colour_state[0], e.colour_rho, rng::pair_a(colour()).0);
                std::f64::consts::FRAC_1_SQRT_2 * (z + self.colour_state[0])
            }
            ColourForm::MultiScale => {
                let words = colour();
                let ((c0, c1), (c2, _)) = (rng::pair_a(words), rng::pair_b(words));
                for (k, innovation) in [c0, c1, c2].into_iter().enumerate() {
                    self.colour_state[k] = ar1(self.colour_state[k], e.colour_rhos[k], innovation);
                }
                self.colour_state.iter().sum::<f64>() * (1.0 / 3f64.sqrt())
            }
            ColourForm::FastSlow => {
                let (fast, slow) = rng::pair_a(colour());
                self.colour_state[0] = ar1(self.colour_state[0], e.colour_rhos[0], fast);
                self.colour_state[1] = ar1(self.colour_state[1], e.colour_rhos[1], slow);
                (1.0 - e.colour_share).sqrt() * self.colour_state[0] + e.colour_share.sqrt() * self.colour_state[1]
            }
        };
        let xi_mu = if e.non_gaussian_strength == 0.0 && e.non_gaussian_cubic == 0.0 {
            g
        } else {
            let g2 = rng::pair_b(friction_block()).0;
            effects::non_gaussian(e.non_gaussian_form, e.non_gaussian_strength, e.non_gaussian_cubic, g, g2)
        };
        self.friction_noise = o.friction_sigma * xi_mu;
        let t_s = self.interval as f64 * o.noise_interval_s;
        let drift_t_s = o.drift_time_s(t_s);
        if e.drift_form == DriftForm::RandomWalk && !first && t_s > o.drift_start_s {
            let step = rng::pair_a(rng::noise_block(self.key, self.realisation, rng::STREAM_DRIFT, self.interval)).0;
            self.drift_walk += (e.drift_rate_per_s * o.noise_interval_s).sqrt() * step;
        }
        let mean_n = o.normal_force_mean_n
            * (drift_factor(e.drift_form, e.drift_rate_per_s, e.drift_curvature_per_s2, drift_t_s) + self.drift_walk);
        let harmonics_n = harmonics_n(e, self.interval_phase, self.x_m / o.base_amplitude_m);
        self.normal_force_n = (mean_n + o.normal_force_sigma_n * xi_n + harmonics_n).max(0.0);
        self.stiction_excess = match e.stiction_form {
            StictionForm::Noisy if e.stiction_excess != 0.0 => {
                e.stiction_excess * (1.0 + 0.5 * rng::pair_b(main()).1).max(0.0)
            }
            StictionForm::Dwell if self.mode == Mode::Stick => {
                effects::dwell_excess(e.stiction_excess, t_s - self.stick_since_s, e.stiction_dwell_s)
            }
            StictionForm::Dwell => 0.0,
            _ => e.stiction_excess,
        };
        if self.memory_form == Memory::Ageing && self.mode == Mode::Stick {
            self.ageing_excess = self.contact_age_excess(self.contact_age_at(t_s));
        }
    }

    /// The contact age θ (s) of hysteresis `ageing` while stuck, held over
    /// the noise interval that starts at `interval_start_s` (s from the
    /// run's start): θ at the stick's start plus the time stuck up to the
    /// interval's start (none in the interval the stick began).
    fn contact_age_at(&self, interval_start_s: f64) -> f64 {
        self.memory + (interval_start_s - self.stick_since_s).max(0.0)
    }

    /// The static coefficient's contact-age term at age `age_s` (s):
    /// `B ln((θ + θ_0)/(θ_c + θ_0))`, the sliding friction's term at v = 0, –.
    fn contact_age_excess(&self, age_s: f64) -> f64 {
        let e = &self.osc.effects;
        let cutoff_age_s = e.hysteresis_length_m / AGEING_CUTOFF_SPEED_M_PER_S;
        let floor_age_s = e.hysteresis_length_m / AGEING_FLOOR_SPEED_M_PER_S;
        effects::contact_age_term(e.hysteresis_strength, age_s, cutoff_age_s, floor_age_s)
    }

    /// Marks the start of a stick at `t_s` (from the run's start, with the
    /// base at `trig`): the `dwell` stiction's ageing starts again, and the
    /// slider is anchored where the block rests on it.
    fn start_stick(&mut self, t_s: f64, trig: Trig) {
        self.stick_since_s = t_s;
        self.stick_anchor_m = self.anchor_of(trig);
        if self.osc.effects.stiction_form == StictionForm::Dwell {
            let e = &self.osc.effects;
            self.stiction_excess = effects::dwell_excess(e.stiction_excess, 0.0, e.stiction_dwell_s);
        }
    }

    /// Where the slider is anchored for a block at x with the base at
    /// `trig`: `w = (x − κ u) / (1 − κ)`, m (x itself for a rigid stick).
    fn anchor_of(&self, trig: Trig) -> f64 {
        let kappa = self.stick_compliance;
        if kappa == 0.0 {
            return self.x_m;
        }
        (self.x_m - kappa * self.osc.base_amplitude_m * trig.cos) / (1.0 - kappa)
    }

    /// A stuck block's displacement (m) and velocity (m/s) with the base at
    /// `trig`: `κ u + (1 − κ) w` and `κ du/dt`.
    fn stuck_state(&self, trig: Trig) -> (f64, f64) {
        let (kappa, o) = (self.stick_compliance, self.osc);
        let x = kappa * o.base_amplitude_m * trig.cos + (1.0 - kappa) * self.stick_anchor_m;
        (x, -kappa * o.base_amplitude_m * o.omega_rad_per_s * trig.sin)
    }

    /// Force of springs and damper on the block at rest, `k (u − x)` with
    /// the base at `cos_omega_t` of its amplitude, N.
    #[inline(always)]
    fn spring_force(&self, cos_omega_t: f64, x_m: f64) -> f64 {
        let o = self.osc;
        o.stiffness_n_per_m * (o.base_amplitude_m * cos_omega_t - x_m)
    }

    /// The steady friction law while slipping with speed `speed` (m/s) at
    /// velocity `v` (m/s), before effects of history:
    /// `a + Δa + b S(c, s) + d v² + σ ξ` with `S` = [`stribeck_factor`]
    /// (a, b and d at this point's load), –.
    #[inline(always)]
    fn steady_law(&self, speed_m_per_s: f64, v_m_per_s: f64) -> f64 {
        self.mean_law(speed_m_per_s, v_m_per_s) + self.friction_noise
    }

    /// The steady law without its random part, `a + Δa + b S(c, s) + d v²`:
    /// what a friction memory that relaxes (`lag`, `slip`) follows, the
    /// random part added on top. The random part of friction comes from
    /// asperity contacts faster than any memory of the contact's state (the
    /// rate-and-state and bristle laws carry no noise): a memory that
    /// filtered it would lower and colour the record's friction noise, –.
    #[inline(always)]
    fn mean_law(&self, speed_m_per_s: f64, v_m_per_s: f64) -> f64 {
        let o = self.osc;
        self.law_a
            + o.effects.friction_offset
            + self.law_b * stribeck_factor(o.friction_c_s_per_m, speed_m_per_s)
            + self.law_d * v_m_per_s * v_m_per_s
    }

    /// Friction coefficient while slipping with speed `speed` (m/s) at
    /// displacement `x_m`, with the friction memory `memory` (μ_f of
    /// hysteresis `lag` and `slip`, θ of `ageing`; unused otherwise),
    /// clipped at 0.
    #[inline(always)]
    fn friction_coefficient(&self, speed_m_per_s: f64, v_m_per_s: f64, x_m: f64, memory: f64) -> f64 {
        if !self.history {
            return self.steady_law(speed_m_per_s, v_m_per_s).max(0.0);
        }
        let e = &self.osc.effects;
        let slipped_m = (x_m - self.slip_start_x_m).abs();
        let mut mu = match self.memory_form {
            Memory::Lag | Memory::Slip => memory + self.friction_noise,
            Memory::Ageing => self.ageing_coefficient(speed_m_per_s, v_m_per_s, memory),
            Memory::None if self.dahl() => {
                self.steady_law(speed_m_per_s, v_m_per_s).max(0.0)
                    * effects::hysteresis_factor(e.hysteresis_form, slipped_m, e.hysteresis_length_m, memory)
            }
            Memory::None => {
                self.steady_law(speed_m_per_s, v_m_per_s)
                    * effects::hysteresis_factor(e.hysteresis_form, slipped_m, e.hysteresis_length_m, memory)
            }
        };
        if e.stiction_form == StictionForm::Decaying {
            mu += self.stiction_excess * effects::exp_neg(slipped_m / STICTION_DECAY_M);
        } else if e.stiction_form == StictionForm::Constant && e.stiction_release_m > 0.0 {
            mu += self.stiction_excess * (1.0 - slipped_m / e.stiction_release_m).max(0.0);
        }
        // Dahl's friction may point along the motion just after a reversal.
        if self.dahl() { mu } else { mu.max(0.0) }
    }

    /// The magnitude of the friction force while slipping, the arguments
    /// those of [`Path::friction_coefficient`]: μN, plus the adhesion force
    /// under load dependence `adhesion` (the sum clipped at 0), N. Without
    /// an adhesion force μN is left as it is (negative for a while under
    /// hysteresis `dahl`), as in the kernel.
    #[inline(always)]
    fn friction_force_n(&self, speed_m_per_s: f64, v_m_per_s: f64, x_m: f64, memory: f64) -> f64 {
        let friction_n = self.friction_coefficient(speed_m_per_s, v_m_per_s, x_m, memory) * self.normal_force_n;
        let adhesion_n = self.osc.effects.adhesion_force_n;
        if adhesion_n == 0.0 { friction_n } else { friction_n + effects::adhesion(friction_n, adhesion_n) }
    }

    /// The sliding coefficient of hysteresis `ageing` with contact age
    /// `age_s` (s), before stiction: `μ_ss(v) + B ln((θ + θ_0)/(θ_ss(v) + θ_0))`,
    /// θ_ss(v) = L/(|v| + v_c), θ_0 = L/v_0, –. Not inlined: it calls `ln` anyway.
    #[inline(never)]
    fn ageing_coefficient(&self, speed_m_per_s: f64, v_m_per_s: f64, age_s: f64) -> f64 {
        let e = &self.osc.effects;
        let length_m = e.hysteresis_length_m;
        let steady_age_s = length_m / (v_m_per_s.abs() + AGEING_CUTOFF_SPEED_M_PER_S);
        let floor_age_s = length_m / AGEING_FLOOR_SPEED_M_PER_S;
        self.steady_law(speed_m_per_s, v_m_per_s)
            + effects::contact_age_term(e.hysteresis_strength, age_s, steady_age_s, floor_age_s)
    }

    /// The static coefficient `μ(0) + stiction excess + contact-age term`,
    /// clipped at 0, –.
    fn static_coefficient(&self) -> f64 {
        let o = self.osc;
        (self.law_a
            + o.effects.friction_offset
            + self.law_b
            + self.friction_noise
            + self.stiction_excess
            + self.ageing_excess)
            .max(0.0)
    }

    /// Whether hysteresis `dahl` or `bristle` is on (δ > 0): friction
    /// continuous through a reversal, so its coefficient may be negative
    /// for a while.
    #[inline(always)]
    fn dahl(&self) -> bool {
        let e = &self.osc.effects;
        matches!(e.hysteresis_form, HysteresisForm::Dahl | HysteresisForm::Bristle) && e.hysteresis_length_m != 0.0
    }

    /// The friction memory a slip starts with at a breakaway, from a stick
    /// or from rest: [`Path::lag_start_coefficient`], or φ₀ = 1 under
    /// hysteresis `dahl` (the static friction that held the block acts at
    /// once).
    fn breakaway_memory(&self) -> f64 {
        if self.dahl() { 1.0 } else { self.lag_start_coefficient() }
    }

    /// The friction memory a slip starts with where the block slips on at
    /// a velocity zero without sticking (`reversed`: in the other
    /// direction): as at a breakaway, but under hysteresis `dahl` φ₀ = ±φ
    /// of the slip that just ended, − where it reversed (the friction it
    /// slid against now points along the new motion). Read before the
    /// slip's start moves to the velocity zero.
    fn reversal_memory(&self, reversed: bool) -> f64 {
        if !self.dahl() {
            return self.lag_start_coefficient();
        }
        let e = &self.osc.effects;
        let slipped_m = (self.x_m - self.slip_start_x_m).abs();
        let end = effects::hysteresis_factor(e.hysteresis_form, slipped_m, e.hysteresis_length_m, self.memory);
        if reversed { -end } else { end }
    }

    /// Where the friction memory μ_f of hysteresis `lag` and `slip` starts
    /// when the block breaks away: the static coefficient the breakaway was judged by, less
    /// the stiction excess that [`Path::friction_coefficient`] adds on top
    /// while it is released (`decaying`, or `constant` with a release
    /// length), so that sliding starts at exactly the static coefficient.
    /// Counted twice, friction at the start of a slip exceeded the force
    /// that broke the block away: it stopped at once and re-slipped, up to
    /// the event limit of every segment (a diagnosis's trials of `lag` on
    /// top of a released stiction took 20–45 s instead of under 1 s), –.
    fn lag_start_coefficient(&self) -> f64 {
        let e = &self.osc.effects;
        let released = e.stiction_form == StictionForm::Decaying
            || (e.stiction_form == StictionForm::Constant && e.stiction_release_m > 0.0);
        // The memory holds the mean part: the noise is added on top.
        self.static_coefficient() - if released { self.stiction_excess } else { 0.0 } - self.friction_noise
    }

    /// Breakaway force `μ_s N` (plus the adhesion force under load
    /// dependence `adhesion`, the sum clipped at 0), N.
    fn breakaway_force(&self) -> f64 {
        let friction_n = self.static_coefficient() * self.normal_force_n;
        let adhesion_n = self.osc.effects.adhesion_force_n;
        if adhesion_n != 0.0 { friction_n + effects::adhesion(friction_n, adhesion_n) } else { friction_n }
    }

    /// Rate of the friction memory while slipping at velocity `v` (m/s)
    /// with speed `speed` (m/s, the slip direction's): `lag`
    /// (μ_ss − μ_f)/τ_m and `slip` (|v|/L)(μ_ss − μ_f), 1/s; `ageing`
    /// 1 − |v| θ/L, –.
    #[inline(always)]
    fn memory_rate(&self, speed_m_per_s: f64, v_m_per_s: f64, memory: f64) -> f64 {
        let e = &self.osc.effects;
        match self.memory_form {
            Memory::Lag => (self.mean_law(speed_m_per_s, v_m_per_s) - memory) / e.hysteresis_lag_s,
            Memory::Slip => effects::slip_law_rate(
                self.mean_law(speed_m_per_s, v_m_per_s),
                memory,
                v_m_per_s.abs(),
                e.hysteresis_length_m,
            ),
            Memory::Ageing => effects::ageing_rate(memory, v_m_per_s.abs(), e.hysteresis_length_m),
            Memory::None => 0.0,
        }
    }
}

/// The law's Stribeck factor `1/(1 + c s)` at speed `s` (m/s) with rate `c`
/// (s/m, ≥ 0), –; for `s < 0` its first-order continuation `1 − c s`, equal
/// to it in value and slope at 0. Only an RK4 stage past a velocity zero
/// sees `s < 0` (a slip's sign is held over its steps, so its speed is
/// `sign · v`), and `1/(1 + c s)` has a pole at `s = −1/c`: with a steep law
/// (c ≈ 950 s/m, which a diagnosis's calibration can reach) a stage 1 mm/s
/// past the zero reached it, the friction turned into a huge driving force
/// and the path ran away to x ≈ 1e12 m (`benches/RESULTS.md`, "A friction
/// law's pole"). The kernel's `stribeck_factor` is the same.
#[inline(always)]
pub(crate) fn stribeck_factor(c_s_per_m: f64, speed_m_per_s: f64) -> f64 {
    if speed_m_per_s >= 0.0 { 1.0 / (1.0 + c_s_per_m * speed_m_per_s) } else { 1.0 - c_s_per_m * speed_m_per_s }
}
