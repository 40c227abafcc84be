//! The f64 reference integrator of one realisation.
//!
//! Each realisation is integrated on a fixed grid of `steps_per_period` steps
//! per excitation period. Noise-interval boundaries and output samples split
//! steps, so every random value holds exactly over its interval. Slip phases
//! use classical RK4 with the slip direction frozen (the ODE is smooth there);
//! a velocity zero inside a step is located by root finding on the RK4 map
//! itself (Illinois method), and the stick→slip breakaway is solved in closed
//! form because the block is at rest and only the base moves. No `sgn` is
//! smoothed.
//!
//! `shaders/oscillator.wgsl` is the same algorithm in f32; the functions
//! below carry the kernel's names and come in its order. The two differ on
//! purpose in these places, and nowhere else:
//!
//! | what | CPU (f64) | GPU (f32) | why |
//! | --- | --- | --- | --- |
//! | arithmetic | f64 | f32 | WGSL has no portable f64; the CPU is the judge |
//! | events per segment before forcing progress | 64 | 16 | a chattering guard only; the GPU's loops must stay short (lavapipe's loop limiter, SIMD divergence) |
//! | Illinois iterations / tolerance on the step | 100 / 1e-15 · max(h, 10⁻⁶ T) | 40 / 2e-7 · h | each converges to its own precision: 1e-15 is f64's, 2e-7 is f32's (2⁻²³ ≈ 1.2e-7) |
//! | halvings probing for motion after a start from rest | 60 | 30 | 2⁻⁶⁰ and 2⁻³⁰ of the step are below each type's resolution |
//! | time inside a period | `step · dt` in f64 | integer step counter, boundary position `frac · steps / 2³²` by `mulhilo` | f32 cannot hold 32.32 fixed point; both switch noise at the same instants |
//! | noise interval index | u64 | u32 (runs are refused past 2³² intervals) | WGSL has no u64 |
//!
//! Output samples (records) split steps on the CPU only.

use crate::engine::cpu::effects;
use crate::engine::effects::{ColourForm, STICTION_DECAY_M, StictionForm};
use crate::engine::oscillator::{InitialState, Oscillator, PathResult, RunPlan, Sample};
use crate::engine::rng;

/// Whether the block sticks or slips, and in which direction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    Stick,
    /// Slipping with velocity sign +1 or −1.
    Slip(i8),
}

/// Fixed-point `2^32`.
const FIXED_ONE: f64 = 4_294_967_296.0;
/// Events handled within one segment before the integrator forces progress
/// (guards against chattering at exactly balanced forces).
const MAX_EVENTS_PER_SEGMENT: u32 = 64;

/// The state of one realisation.
#[derive(Clone, Debug)]
struct Path<'a> {
    osc: &'a Oscillator,
    key: [u32; 2],
    realisation: u32,
    /// Displacement x, m.
    x_m: f64,
    /// Velocity v, m/s.
    v_m_per_s: f64,
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
    /// x where the current slip began, m (hysteresis, decaying stiction).
    slip_start_x_m: f64,
    /// Coloured noise state: the previous ξ (ar1) or the slow part (two_scale), –.
    colour_state: f64,
    /// Start of the current noise interval within its period, in periods.
    interval_phase: f64,
    /// Static-friction excess in the current interval, –.
    stiction_excess: f64,
    /// Largest x so far in the current period, m.
    period_max_x_m: f64,
    /// Time stuck so far in the current period, s.
    period_stick_s: f64,
    /// `∫ x cos(Ωt) dt` and `∫ x sin(Ωt) dt` over the current period so far,
    /// m·s (the response's fundamental; see [`phase_of`]).
    period_cos_integral: f64,
    period_sin_integral: f64,
}

/// One RK4 step of the slip ODE, with what the phase quadrature needs: the
/// four stage displacements (m) and `cos(Ωt)` at the step's start, middle
/// and end.
#[derive(Clone, Copy, Debug)]
struct SlipStep {
    x_m: f64,
    v_m_per_s: f64,
    stage_x_m: [f64; 4],
    cos: [f64; 3],
}

/// The phase lag (rad) of a period's fundamental behind the base, from
/// `∫ x cos(Ωt) dt` and `∫ x sin(Ωt) dt` over the period: the fundamental is
/// `sqrt(a² + b²) cos(Ωt − φ)` with `φ = atan2(b, a)` (`interfaces.md`).
pub fn phase_of(cos_integral: f64, sin_integral: f64) -> f64 {
    sin_integral.atan2(cos_integral)
}

impl<'a> Path<'a> {
    fn new(osc: &'a Oscillator, seed: u64, realisation: u32, initial: InitialState) -> Self {
        let mut path = Path {
            osc,
            key: rng::seed_key(seed),
            realisation,
            x_m: initial.x_m,
            v_m_per_s: initial.v_m_per_s,
            mode: Mode::Stick,
            period: 0,
            interval: 0,
            next_boundary: osc.noise_interval_fixed,
            friction_noise: 0.0,
            normal_force_n: 0.0,
            slip_start_x_m: initial.x_m,
            colour_state: 0.0,
            interval_phase: 0.0,
            stiction_excess: 0.0,
            period_max_x_m: initial.x_m,
            period_stick_s: 0.0,
            period_cos_integral: 0.0,
            period_sin_integral: 0.0,
        };
        path.draw_noise();
        path.mode = if initial.v_m_per_s > 0.0 {
            Mode::Slip(1)
        } else if initial.v_m_per_s < 0.0 {
            Mode::Slip(-1)
        } else {
            path.stick_or_slip(0.0)
        };
        path
    }

    /// Noise values (and everything else held per interval) of the current interval.
    fn draw_noise(&mut self) {
        let o = self.osc;
        let e = &o.effects;
        let friction_interval = if e.colour_form == ColourForm::Hold {
            self.interval / u64::from(e.colour_hold_intervals)
        } else {
            self.interval
        };
        let (z, z2) = rng::gaussian_pair(self.key, self.realisation, rng::STREAM_FRICTION, friction_interval);
        let innovation = (1.0 - e.colour_rho * e.colour_rho).sqrt();
        let g = if e.colour_form == ColourForm::TwoScale && e.colour_rho > 0.0 {
            let (slow, _) = rng::gaussian_pair(self.key, self.realisation, rng::STREAM_COLOUR, self.interval);
            self.colour_state =
                if self.interval == 0 { slow } else { e.colour_rho * self.colour_state + innovation * slow };
            std::f64::consts::FRAC_1_SQRT_2 * (z + self.colour_state)
        } else if e.colour_form == ColourForm::Ar1 {
            self.colour_state = if self.interval == 0 { z } else { e.colour_rho * self.colour_state + innovation * z };
            self.colour_state
        } else {
            z
        };
        let xi_mu = effects::non_gaussian(e.non_gaussian_form, e.non_gaussian_strength, g, z2);
        self.friction_noise = o.friction_sigma * xi_mu;
        let (xi_n, _) = rng::gaussian_pair(self.key, self.realisation, rng::STREAM_NORMAL_FORCE, self.interval);
        let t_s = self.interval as f64 * o.noise_interval_s;
        let mean_n = o.normal_force_mean_n * effects::drift_factor(e.drift_form, e.drift_rate_per_s, t_s);
        let theta = std::f64::consts::TAU * self.interval_phase;
        let mut harmonics_n = 0.0;
        for k in 0..4 {
            if e.harmonic_amplitudes_n[k] != 0.0 {
                let c = ((k + 1) as f64 * theta + e.harmonic_phases_rad[k]).cos();
                harmonics_n += e.harmonic_amplitudes_n[k]
                    * effects::harmonic_wave(e.harmonic_form, c, e.harmonic_shape, e.harmonic_shape_mean);
            }
        }
        self.normal_force_n = (mean_n + o.normal_force_sigma_n * xi_n + harmonics_n).max(0.0);
        self.stiction_excess = if e.stiction_form == StictionForm::Noisy {
            let (zs, _) = rng::gaussian_pair(self.key, self.realisation, rng::STREAM_STICTION, self.interval);
            e.stiction_excess * (1.0 + 0.5 * zs).max(0.0)
        } else {
            e.stiction_excess
        };
    }

    /// Force of springs and damper on the block at rest, `k (u(t) − x)`, N.
    fn spring_force(&self, t_local_s: f64, x_m: f64) -> f64 {
        let o = self.osc;
        o.stiffness_n_per_m * (o.base_amplitude_m * (o.omega_rad_per_s * t_local_s).cos() - x_m)
    }

    /// Friction coefficient while slipping with speed `speed` (m/s) at
    /// displacement `x_m`, clipped at 0.
    fn friction_coefficient(&self, speed_m_per_s: f64, v_m_per_s: f64, x_m: f64) -> f64 {
        let o = self.osc;
        let e = &o.effects;
        let slipped_m = (x_m - self.slip_start_x_m).abs();
        let law = o.friction_a
            + e.friction_offset
            + o.friction_b / (1.0 + o.friction_c_s_per_m * speed_m_per_s)
            + o.friction_d_s2_per_m2 * v_m_per_s * v_m_per_s
            + self.friction_noise;
        let mut mu = law * effects::hysteresis_factor(e.hysteresis_form, slipped_m, e.hysteresis_length_m);
        if e.stiction_form == StictionForm::Decaying {
            mu += self.stiction_excess * (-slipped_m / STICTION_DECAY_M).exp();
        } else if e.stiction_form == StictionForm::Constant && e.stiction_release_m > 0.0 {
            mu += self.stiction_excess * (1.0 - slipped_m / e.stiction_release_m).max(0.0);
        }
        mu.max(0.0)
    }

    /// Breakaway force `μ_s N` with `μ_s = μ(0) + stiction excess`, N.
    fn breakaway_force(&self) -> f64 {
        let o = self.osc;
        let mu_static =
            o.friction_a + o.effects.friction_offset + o.friction_b + self.friction_noise + self.stiction_excess;
        mu_static.max(0.0) * self.normal_force_n
    }

    /// Acceleration while slipping in direction `sign`, m/s², with the
    /// base at `cos_omega_t` of its amplitude.
    fn slip_acceleration(&self, cos_omega_t: f64, x_m: f64, v_m_per_s: f64, sign: f64) -> f64 {
        let o = self.osc;
        let friction = sign * self.friction_coefficient(sign * v_m_per_s, v_m_per_s, x_m) * self.normal_force_n;
        let spring = o.stiffness_n_per_m * (o.base_amplitude_m * cos_omega_t - x_m);
        (spring - o.damping_n_s_per_m * v_m_per_s - friction) / o.mass_kg
    }

    /// One classical RK4 step of the slip ODE from `t` over `h` seconds.
    /// Stages 2 and 3 share the excitation's `cos` at the midpoint.
    fn rk4_slip(&self, t_local_s: f64, x_m: f64, v_m_per_s: f64, h_s: f64, sign: f64) -> SlipStep {
        let w = self.osc.omega_rad_per_s;
        let half = 0.5 * h_s;
        let cos = [(w * t_local_s).cos(), (w * (t_local_s + half)).cos(), (w * (t_local_s + h_s)).cos()];
        let k1x = v_m_per_s;
        let k1v = self.slip_acceleration(cos[0], x_m, v_m_per_s, sign);
        let k2x = v_m_per_s + half * k1v;
        let x2 = x_m + half * k1x;
        let k2v = self.slip_acceleration(cos[1], x2, k2x, sign);
        let k3x = v_m_per_s + half * k2v;
        let x3 = x_m + half * k2x;
        let k3v = self.slip_acceleration(cos[1], x3, k3x, sign);
        let k4x = v_m_per_s + h_s * k3v;
        let x4 = x_m + h_s * k3x;
        let k4v = self.slip_acceleration(cos[2], x4, k4x, sign);
        SlipStep {
            x_m: x_m + h_s / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x),
            v_m_per_s: v_m_per_s + h_s / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v),
            stage_x_m: [x_m, x2, x3, x4],
            cos,
        }
    }

    /// Adds an accepted slip step to the period's phase integrals: the RK4
    /// quadrature of `x cos(Ωt)` and `x sin(Ωt)` over the step, with the
    /// step's own stage displacements (the integrals are two more RK4 states).
    fn add_slip_phase(&mut self, t_local_s: f64, h_s: f64, step: &SlipStep) {
        let w = self.osc.omega_rad_per_s;
        let sin = [(w * t_local_s).sin(), (w * (t_local_s + 0.5 * h_s)).sin(), (w * (t_local_s + h_s)).sin()];
        let [x1, x2, x3, x4] = step.stage_x_m;
        self.period_cos_integral += h_s / 6.0 * (x1 * step.cos[0] + 2.0 * (x2 + x3) * step.cos[1] + x4 * step.cos[2]);
        self.period_sin_integral += h_s / 6.0 * (x1 * sin[0] + 2.0 * (x2 + x3) * sin[1] + x4 * sin[2]);
    }

    /// Adds a stuck interval `[t_a, t_b]` to the period's phase integrals,
    /// exactly: x is constant.
    fn add_stick_phase(&mut self, t_a: f64, t_b: f64) {
        let w = self.osc.omega_rad_per_s;
        let (sin_a, cos_a) = (w * t_a).sin_cos();
        let (sin_b, cos_b) = (w * t_b).sin_cos();
        self.period_cos_integral += self.x_m * (sin_b - sin_a) / w;
        self.period_sin_integral += self.x_m * (cos_a - cos_b) / w;
    }

    /// The step length `h* ∈ (0, h]` at which the RK4 map's velocity reaches
    /// zero, given that `sign · v` is ≤ 0 after the full step `h`.
    fn locate_velocity_zero(&self, t_local_s: f64, h_s: f64, sign: f64) -> f64 {
        let g = |h: f64| sign * self.rk4_slip(t_local_s, self.x_m, self.v_m_per_s, h, sign).v_m_per_s;
        let (mut lo, mut g_lo) = (0.0, sign * self.v_m_per_s);
        let (mut hi, mut g_hi) = (h_s, g(h_s));
        if g_lo <= 0.0 {
            // Slip starting from rest: find a point where it is under way.
            let mut probe = 0.5 * h_s;
            let mut found = false;
            for _ in 0..60 {
                let g_probe = g(probe);
                if g_probe > 0.0 {
                    (lo, g_lo) = (probe, g_probe);
                    found = true;
                    break;
                }
                (hi, g_hi) = (probe, g_probe);
                probe *= 0.5;
            }
            if !found {
                return hi;
            }
        }
        // Illinois (modified regula falsi): g_lo > 0 >= g_hi.
        let mut side = 0i8;
        for _ in 0..100 {
            if hi - lo <= 1e-15 * h_s.max(self.osc.period_s * 1e-6) {
                break;
            }
            let mut mid = (lo * g_hi - hi * g_lo) / (g_hi - g_lo);
            if !(mid > lo && mid < hi) {
                mid = 0.5 * (lo + hi);
            }
            let g_mid = g(mid);
            if g_mid > 0.0 {
                (lo, g_lo) = (mid, g_mid);
                if side == 1 {
                    g_hi *= 0.5;
                }
                side = 1;
            } else {
                (hi, g_hi) = (mid, g_mid);
                if side == -1 {
                    g_lo *= 0.5;
                }
                side = -1;
            }
        }
        hi
    }

    /// At rest at `t`: stick if the spring force does not exceed the
    /// breakaway force, otherwise slip in the direction of that force.
    fn stick_or_slip(&self, t_local_s: f64) -> Mode {
        let force = self.spring_force(t_local_s, self.x_m);
        if force.abs() <= self.breakaway_force() {
            Mode::Stick
        } else if force > 0.0 {
            Mode::Slip(1)
        } else {
            Mode::Slip(-1)
        }
    }

    /// Earliest time in `[t_a, t_b]` at which a stuck block breaks away, and
    /// the direction. `k (U0 cos(Ω t) − x) = ±μ_s N` is solved in closed form.
    fn breakaway_time(&self, t_a: f64, t_b: f64) -> Option<(f64, i8)> {
        let o = self.osc;
        let force = self.spring_force(t_a, self.x_m);
        let threshold = self.breakaway_force();
        if force > threshold {
            return Some((t_a, 1));
        }
        if force < -threshold {
            return Some((t_a, -1));
        }
        if o.base_amplitude_m == 0.0 {
            return None;
        }
        let phase_a = o.omega_rad_per_s * t_a;
        let reach = threshold / o.stiffness_n_per_m;
        let best = self.earliest_entry(None, 1, phase_a, reach, t_b);
        self.earliest_entry(best, -1, phase_a, reach, t_b).map(|(t, sign)| (t.max(t_a), sign))
    }

    /// Entering `cos(θ) >= C+` happens at `θ = 2πn − acos(C+)`; entering
    /// `cos(θ) <= C−` at `θ = 2πn + acos(C−)`. Keeps `best` unless this
    /// direction's entry is earlier.
    fn earliest_entry(
        &self,
        best: Option<(f64, i8)>,
        sign: i8,
        phase_a: f64,
        reach: f64,
        t_b: f64,
    ) -> Option<(f64, i8)> {
        let o = self.osc;
        let level = (self.x_m + f64::from(sign) * reach) / o.base_amplitude_m;
        if !(-1.0..=1.0).contains(&level) {
            return best;
        }
        let base = -f64::from(sign) * level.acos();
        let n = ((phase_a - base) / std::f64::consts::TAU).ceil();
        let t = (base + n * std::f64::consts::TAU) / o.omega_rad_per_s;
        if t <= t_b && best.is_none_or(|(tb, _)| t < tb) { Some((t, sign)) } else { best }
    }

    /// Advances from `t_a` to `t_b` (local times in the period) with the
    /// noise held, through any stick/slip events on the way.
    fn advance_segment(&mut self, mut t_a: f64, t_b: f64, measuring: bool) {
        let mut events = 0;
        while t_a < t_b {
            match self.mode {
                Mode::Stick => {
                    let until = if events < MAX_EVENTS_PER_SEGMENT { self.breakaway_time(t_a, t_b) } else { None };
                    let (t_end, next) = match until {
                        None => (t_b, Mode::Stick),
                        Some((t, sign)) => (t, Mode::Slip(sign)),
                    };
                    if measuring {
                        self.period_stick_s += t_end - t_a;
                        self.add_stick_phase(t_a, t_end);
                    }
                    self.mode = next;
                    self.slip_start_x_m = self.x_m;
                    t_a = t_end;
                    events += 1;
                }
                Mode::Slip(s) => {
                    let sign = f64::from(s);
                    let h = t_b - t_a;
                    let step = self.rk4_slip(t_a, self.x_m, self.v_m_per_s, h, sign);
                    if sign * step.v_m_per_s > 0.0 {
                        if measuring {
                            self.add_slip_phase(t_a, h, &step);
                        }
                        self.x_m = step.x_m;
                        self.v_m_per_s = step.v_m_per_s;
                        self.period_max_x_m = self.period_max_x_m.max(step.x_m);
                        t_a = t_b;
                    } else {
                        let h_zero = self.locate_velocity_zero(t_a, h, sign);
                        let to_zero = self.rk4_slip(t_a, self.x_m, self.v_m_per_s, h_zero, sign);
                        if measuring {
                            self.add_slip_phase(t_a, h_zero, &to_zero);
                        }
                        let x_zero = to_zero.x_m;
                        self.x_m = x_zero;
                        self.v_m_per_s = 0.0;
                        self.period_max_x_m = self.period_max_x_m.max(x_zero);
                        t_a += h_zero;
                        self.mode = if events < MAX_EVENTS_PER_SEGMENT { self.stick_or_slip(t_a) } else { Mode::Stick };
                        self.slip_start_x_m = self.x_m;
                        events += 1;
                    }
                }
            }
        }
    }

    /// Friction force on the block at local time `t` (for output samples), N.
    fn friction_force(&self, t_local_s: f64) -> f64 {
        match self.mode {
            Mode::Stick => -self.spring_force(t_local_s, self.x_m),
            Mode::Slip(s) => {
                let sign = f64::from(s);
                -sign * self.friction_coefficient(sign * self.v_m_per_s, self.v_m_per_s, self.x_m) * self.normal_force_n
            }
        }
    }

    /// Integrates one excitation period, splitting steps at noise boundaries
    /// and at output samples.
    fn run_period(&mut self, measuring: bool, mut sampler: Option<&mut Sampler>) {
        let o = self.osc;
        let steps = o.steps_per_period;
        let dt = o.period_s / f64::from(steps);
        let period_start_s = self.period as f64 * o.period_s;
        self.period_max_x_m = self.x_m;
        self.period_stick_s = 0.0;
        self.period_cos_integral = 0.0;
        self.period_sin_integral = 0.0;
        let mut t = 0.0;
        let mut step = 0u32;
        loop {
            let step_end = if step + 1 == steps { o.period_s } else { f64::from(step + 1) * dt };
            let noise_t = if self.next_boundary >> 32 == self.period {
                (self.next_boundary & 0xFFFF_FFFF) as f64 / FIXED_ONE * o.period_s
            } else {
                f64::INFINITY
            };
            let sample_t = sampler.as_ref().map_or(f64::INFINITY, |s| s.next_time_s() - period_start_s);
            let target = step_end.min(noise_t).min(sample_t).max(t);
            self.advance_segment(t, target, measuring);
            t = target;
            if noise_t <= target {
                self.interval_phase = (self.next_boundary & 0xFFFF_FFFF) as f64 / FIXED_ONE;
                self.interval += 1;
                self.next_boundary += o.noise_interval_fixed;
                self.draw_noise();
            }
            if sample_t <= target {
                let sample = Sample {
                    t_s: period_start_s + t,
                    x_m: self.x_m,
                    v_m_per_s: self.v_m_per_s,
                    normal_force_n: self.normal_force_n,
                    friction_force_n: self.friction_force(t),
                };
                sampler.as_mut().expect("sample time implies a sampler").push(sample);
            }
            if step_end <= target {
                step += 1;
                if step == steps {
                    break;
                }
            }
        }
        self.period += 1;
    }
}

/// Collects output samples at a fixed rate.
#[derive(Clone, Debug)]
pub(crate) struct Sampler {
    /// Sampling interval, s.
    pub interval_s: f64,
    /// Samples so far.
    pub samples: Vec<Sample>,
    /// Time of the first sample, s.
    pub start_s: f64,
}

impl Sampler {
    /// A sampler recording at `start_s + i * interval_s`.
    pub(crate) fn new(interval_s: f64, start_s: f64) -> Self {
        Sampler { interval_s, samples: Vec::new(), start_s }
    }

    fn next_time_s(&self) -> f64 {
        self.start_s + self.samples.len() as f64 * self.interval_s
    }

    fn push(&mut self, sample: Sample) {
        self.samples.push(sample);
    }
}

/// One realisation sampled like a measured record: `seconds` of samples
/// every `sample_interval_s`, starting after `warmup_cycles` periods, with
/// times measured from the record's start.
pub fn sample_record(
    osc: &Oscillator,
    seed: u64,
    realisation: u32,
    warmup_cycles: u32,
    seconds: f64,
    sample_interval_s: f64,
    initial: InitialState,
) -> Vec<Sample> {
    let start_s = f64::from(warmup_cycles) * osc.period_s;
    let cycles = (seconds / osc.period_s).ceil() as u32 + 1;
    let mut sampler = Sampler::new(sample_interval_s, start_s);
    simulate_path(
        osc,
        seed,
        realisation,
        RunPlan { warmup_cycles, measured_cycles: cycles },
        initial,
        Some(&mut sampler),
    );
    let mut samples = sampler.samples;
    samples.truncate((seconds / sample_interval_s).round() as usize);
    for s in &mut samples {
        s.t_s -= start_s;
    }
    samples
}

/// Runs one realisation and returns its per-period peaks.
pub(crate) fn simulate_path(
    osc: &Oscillator,
    seed: u64,
    realisation: u32,
    plan: RunPlan,
    initial: InitialState,
    mut sampler: Option<&mut Sampler>,
) -> PathResult {
    let mut path = Path::new(osc, seed, realisation, initial);
    let mut peaks_m = Vec::with_capacity(plan.measured_cycles as usize);
    let mut phases_rad = Vec::with_capacity(plan.measured_cycles as usize);
    let mut stick_time_s = 0.0;
    for cycle in 0..plan.warmup_cycles + plan.measured_cycles {
        let measuring = cycle >= plan.warmup_cycles;
        path.run_period(measuring, sampler.as_deref_mut());
        if measuring {
            peaks_m.push(path.period_max_x_m);
            phases_rad.push(phase_of(path.period_cos_integral, path.period_sin_integral));
            stick_time_s += path.period_stick_s;
        }
    }
    PathResult { peaks_m, phases_rad, stick_time_s }
}
