//! The independent generator's integrator: semi-implicit Euler at a fixed step with explicit stick/slip switching, its noise and its plant.

use super::*;

/// A stream of standard Gaussian (Box–Muller) and uniform values.
pub(super) struct Gauss {
    pub(super) rng: StdRng,
    pub(super) spare: Option<f64>,
}

impl Gauss {
    pub(super) fn new(seed: u64, path: u64, stream: u64) -> Gauss {
        Gauss { rng: stream_rng(seed, path, stream), spare: None }
    }

    pub(super) fn uniform(&mut self) -> f64 {
        self.rng.random::<f64>()
    }

    pub(super) fn normal(&mut self) -> f64 {
        if let Some(s) = self.spare.take() {
            return s;
        }
        let u1 = 1.0 - self.rng.random::<f64>(); // (0, 1]
        let u2 = self.rng.random::<f64>();
        let r = (-2.0 * u1.ln()).sqrt();
        let (s, c) = (TAU * u2).sin_cos();
        self.spare = Some(r * s);
        r * c
    }
}

/// The per-path state of the random parts that change once per noise
/// interval.
pub(super) struct Noise {
    pub(super) friction: Gauss,
    pub(super) normal: Gauss,
    pub(super) shape: Gauss,
    pub(super) colour: Gauss,
    pub(super) harmonic: Gauss,
    pub(super) drift: Gauss,
    /// Pink: (ρ, innovation scale, value) per AR(1).
    pub(super) pink: Vec<(f64, f64, f64)>,
    pub(super) telegraph: f64,
    pub(super) telegraph_switch: f64,
    pub(super) phase: f64,
    pub(super) wear: f64,
}

/// What is held over one noise interval.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Held {
    /// `σ_μ ξ_μ`.
    pub(super) mu_noise: f64,
    /// The mean normal force with its drift, N.
    pub(super) n_mean: f64,
    /// `σ_N ξ_N`, N.
    pub(super) n_noise: f64,
    /// cos and sin of the wandering harmonic's phase.
    pub(super) phase_cos: f64,
    pub(super) phase_sin: f64,
}

impl Noise {
    pub(super) fn new(plant: &Plant, seed: u64, path: u64) -> Noise {
        let mut colour = Gauss::new(seed, path, streams::COLOUR);
        let tau = plant.noise_interval_s;
        let mut pink = Vec::new();
        let mut telegraph = 1.0;
        let mut telegraph_switch = 0.0;
        match plant.colour {
            Some(ColourForm::Pink { shortest_s, longest_s, components, .. }) => {
                let count = components.max(1);
                for i in 0..count {
                    let frac = if count > 1 { f64::from(i) / f64::from(count - 1) } else { 0.0 };
                    let time = shortest_s * (longest_s / shortest_s).powf(frac);
                    let rho = (-tau / time.max(1e-12)).exp();
                    // Each component starts in its stationary law: no warm-up of the noise.
                    pink.push((rho, (1.0 - rho * rho).sqrt(), colour.normal()));
                }
            }
            Some(ColourForm::Telegraph { mean_dwell_s, .. }) => {
                telegraph = if colour.uniform() < 0.5 { -1.0 } else { 1.0 };
                telegraph_switch = 1.0 - (-tau / mean_dwell_s.max(1e-12)).exp();
            }
            None => {}
        }
        let phase = match plant.harmonic {
            Some(HarmonicForm::WanderingHarmonic { initial_phase_rad, .. }) => initial_phase_rad,
            _ => 0.0,
        };
        Noise {
            friction: Gauss::new(seed, path, streams::FRICTION),
            normal: Gauss::new(seed, path, streams::NORMAL),
            shape: Gauss::new(seed, path, streams::SHAPE),
            colour,
            harmonic: Gauss::new(seed, path, streams::HARMONIC),
            drift: Gauss::new(seed, path, streams::DRIFT),
            pink,
            telegraph,
            telegraph_switch,
            phase,
            wear: 0.0,
        }
    }

    /// The values of the interval that starts at record time `t` (negative
    /// during the warm-up).
    pub(super) fn interval(&mut self, plant: &Plant, t: f64) -> Held {
        let tau = plant.noise_interval_s;
        let mut xi = self.friction.normal();
        if let Some(shape) = plant.shape {
            let (s, q) = match shape {
                ShapeForm::StudentT { strength, degrees_of_freedom } => {
                    let nu = degrees_of_freedom.max(3);
                    let z = self.shape.normal();
                    let chi2: f64 = (0..nu).map(|_| self.shape.normal().powi(2)).sum::<f64>().max(1e-300);
                    let nu = f64::from(nu);
                    (strength, z / (chi2 / nu).sqrt() / (nu / (nu - 2.0)).sqrt())
                }
                ShapeForm::Bimodal { strength, high_probability } => {
                    let p = high_probability.clamp(1e-6, 1.0 - 1e-6);
                    let bit = if self.shape.uniform() < p { 1.0 } else { 0.0 };
                    (strength, (bit - p) / (p * (1.0 - p)).sqrt())
                }
            };
            let s = s.clamp(0.0, 1.0);
            xi = (1.0 - s).sqrt() * xi + s.sqrt() * q;
        }
        if let Some(colour) = plant.colour {
            let (s, c) = match colour {
                ColourForm::Pink { strength, .. } => {
                    let mut sum = 0.0;
                    for (rho, scale, value) in &mut self.pink {
                        *value = *rho * *value + *scale * self.colour.normal();
                        sum += *value;
                    }
                    (strength, sum / (self.pink.len().max(1) as f64).sqrt())
                }
                ColourForm::Telegraph { strength, .. } => {
                    if self.colour.uniform() < self.telegraph_switch {
                        self.telegraph = -self.telegraph;
                    }
                    (strength, self.telegraph)
                }
            };
            let s = s.clamp(0.0, 1.0);
            xi = (1.0 - s).sqrt() * xi + s.sqrt() * c;
        }
        let n_noise = plant.sigma_n * self.normal.normal();
        let since_start = t.max(0.0);
        let drift = match plant.drift {
            None => 1.0,
            Some(DriftForm::ThermalRelaxation { strength, time_constant_s }) => {
                1.0 + strength * (1.0 - (-since_start / time_constant_s.max(1e-12)).exp())
            }
            Some(DriftForm::BrownianWear { strength }) => {
                let z = self.drift.normal();
                if t > 0.0 {
                    self.wear += strength * tau.sqrt() * z;
                }
                1.0 + self.wear
            }
        };
        let (mut phase_cos, mut phase_sin) = (1.0, 0.0);
        if let Some(HarmonicForm::WanderingHarmonic { phase_diffusion_rad2_per_s, .. }) = plant.harmonic {
            self.phase += (phase_diffusion_rad2_per_s * tau).sqrt() * self.harmonic.normal();
            (phase_sin, phase_cos) = self.phase.sin_cos();
        }
        Held { mu_noise: plant.sigma_mu * xi, n_mean: plant.n0 * drift, n_noise, phase_cos, phase_sin }
    }
}

// ---------------------------------------------------------------------------
// The integrator
// ---------------------------------------------------------------------------

/// The constants of one condition.
#[derive(Clone, Debug)]
pub(super) struct Plant {
    pub(super) m: f64,
    pub(super) k: f64,
    pub(super) c: f64,
    pub(super) u0: f64,
    pub(super) omega: f64,
    pub(super) n0: f64,
    pub(super) a: f64,
    pub(super) b: f64,
    pub(super) cs: f64,
    pub(super) d: f64,
    pub(super) sigma_mu: f64,
    pub(super) sigma_n: f64,
    pub(super) noise_interval_s: f64,
    pub(super) rest_speed: f64,
    pub(super) load: Option<LoadForm>,
    pub(super) memory: Option<MemoryForm>,
    pub(super) harmonic: Option<HarmonicForm>,
    pub(super) colour: Option<ColourForm>,
    pub(super) shape: Option<ShapeForm>,
    pub(super) stiction: Option<StaticForm>,
    pub(super) drift: Option<DriftForm>,
    /// LuGre: (L, σ1, v_d), when LuGre is on with a positive strength.
    pub(super) lugre: Option<(f64, f64, f64)>,
}

impl Plant {
    pub(super) fn new(truth: &IndependentTruth, condition: Condition) -> Plant {
        let r = &truth.rig;
        let f = &truth.friction;
        let mut p = Plant {
            m: r.mass_kg,
            k: r.stiffness_n_per_m(),
            c: r.damping_n_s_per_m(),
            u0: r.excitation_amplitude_m,
            omega: TAU * condition.excitation_frequency_hz,
            n0: condition.normal_force_n,
            a: f.a,
            b: f.b,
            cs: f.c_s_per_m,
            d: f.d_s2_per_m2,
            sigma_mu: f.sigma_mu,
            sigma_n: f.sigma_n_n,
            noise_interval_s: f.noise_interval_s,
            rest_speed: truth.integration.rest_speed_m_per_s,
            load: None,
            memory: None,
            harmonic: None,
            colour: None,
            shape: None,
            stiction: None,
            drift: None,
            lugre: None,
        };
        for e in &truth.effects {
            match *e {
                IndependentEffect::LoadDependentFriction(form) => p.load = Some(form),
                IndependentEffect::FrictionHysteresis(form) => {
                    p.memory = Some(form);
                    if let MemoryForm::Lugre {
                        strength,
                        bristle_damping_ratio,
                        damping_decay_speed_m_per_s,
                        reference_load_n,
                    } = form
                        && strength > 0.0
                    {
                        let sigma1 =
                            2.0 * bristle_damping_ratio * (p.m / (reference_load_n.max(1e-9) * strength)).sqrt();
                        p.lugre = Some((strength, sigma1, damping_decay_speed_m_per_s.max(1e-12)));
                    }
                }
                IndependentEffect::NormalForceHarmonics(form) => p.harmonic = Some(form),
                IndependentEffect::ColouredFrictionNoise(form) => p.colour = Some(form),
                IndependentEffect::NonGaussianFriction(form) => p.shape = Some(form),
                IndependentEffect::Stiction(form) => p.stiction = Some(form),
                IndependentEffect::NormalForceDrift(form) => p.drift = Some(form),
            }
        }
        p
    }

    /// The load factor of the friction law at normal force `n`.
    pub(super) fn load_factor(&self, n: f64) -> f64 {
        match self.load {
            None => 1.0,
            Some(LoadForm::Hertzian { strength, reference_load_n }) => {
                ((1.0 + strength) / (1.0 + strength * n / reference_load_n)).cbrt()
            }
            Some(LoadForm::Logistic { strength, transition_load_n, width_n, reference_load_n }) => {
                let l = |n: f64| 1.0 / (1.0 + (-(n - transition_load_n) / width_n).exp());
                (1.0 + strength * (l(n) - l(reference_load_n))).max(0.0)
            }
            Some(LoadForm::JkrAdhesion { strength, exponent, reference_load_n }) => {
                ((1.0 + strength / n.max(1e-9)) / (1.0 + strength / reference_load_n)).powf(exponent)
            }
        }
    }

    /// The starting state: the harmonic-balance (equivalent viscous
    /// damping) steady state of the baseline at base phase `theta`, or rest
    /// where friction holds the block.
    pub(super) fn initial_state(&self, theta: f64) -> (f64, f64) {
        let eta = self.omega / (self.k / self.m).sqrt();
        let zeta = self.c / (2.0 * (self.k * self.m).sqrt());
        let f0 = (self.a + 0.5 * self.b).max(0.0) * self.n0;
        let r = if self.u0 > 0.0 { 4.0 * f0 / (PI * self.k * self.u0) } else { 1.0 };
        if r >= 1.0 {
            return (0.0, 0.0);
        }
        let big_a = (1.0 - eta * eta).powi(2) + (2.0 * zeta * eta).powi(2);
        let disc = (2.0 * zeta * eta * r).powi(2) - big_a * (r * r - 1.0);
        let y = (-2.0 * zeta * eta * r + disc.max(0.0).sqrt()) / big_a;
        if !(y.is_finite() && y > 0.0) {
            return (0.0, 0.0);
        }
        let lag = (2.0 * zeta * eta + r / y).atan2(1.0 - eta * eta);
        let amplitude = y * self.u0;
        (amplitude * (theta - lag).cos(), -amplitude * self.omega * (theta - lag).sin())
    }
}

/// Where a path starts and how it is stepped.
#[derive(Clone, Copy, Debug)]
pub(super) struct Grid {
    /// Step, s.
    pub(super) dt: f64,
    /// Steps per noise interval.
    pub(super) hold: u64,
    /// Warm-up steps (a whole number of noise intervals, at least whole
    /// excitation periods).
    pub(super) warmup_steps: u64,
    /// Steps from the record's start to its end.
    pub(super) record_steps: u64,
}

impl Grid {
    pub(super) fn new(truth: &IndependentTruth, frequency_hz: f64, duration_s: f64) -> Grid {
        let tau = truth.friction.noise_interval_s;
        let hold = (tau * truth.integration.step_rate_hz.max(MIN_STEP_RATE_HZ)).ceil().max(1.0) as u64;
        let dt = tau / hold as f64;
        let periods = (truth.integration.warmup_s * frequency_hz).ceil();
        let intervals = (periods / frequency_hz / tau).ceil() as u64;
        Grid { dt, hold, warmup_steps: intervals * hold, record_steps: (duration_s / dt).ceil() as u64 }
    }
}

/// What a path reports at each step of its record, before the step: its
/// step index from the record's start, its time, the base phase's cos and
/// sin, the state `x`, `v`, the normal force and the friction force.
pub(super) trait Sink {
    #[allow(clippy::too_many_arguments)]
    fn step(&mut self, n: u64, t: f64, cos: f64, sin: f64, x: f64, v: f64, normal: f64, friction: f64);
}

/// `exp(−x)` for `x ≥ 0`: a 4th-order series below 0.02 (relative error
/// under 3e-11), 0 above 40, the library's `exp` between.
pub(super) fn exp_neg(x: f64) -> f64 {
    if x < 0.02 {
        1.0 - x * (1.0 - 0.5 * x * (1.0 - x / 3.0 * (1.0 - 0.25 * x)))
    } else if x > 40.0 {
        0.0
    } else {
        (-x).exp()
    }
}

pub(super) fn sign(v: f64) -> f64 {
    if v > 0.0 {
        1.0
    } else if v < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// Integrates one path of `truth` at `condition`: the warm-up, then the
/// record's `grid.record_steps` steps, each reported to `sink`. The base is
/// `u = U0 cos(Ω t + phase0)`, `t` from the record's start.
pub(super) fn simulate<S: Sink>(plant: &Plant, grid: Grid, seed: u64, path: u64, phase0: f64, sink: &mut S) {
    let dt = grid.dt;
    let mut noise = Noise::new(plant, seed, path);
    let mut stiction_rng = Gauss::new(seed, path, streams::STICTION);
    let total = grid.warmup_steps + grid.record_steps;
    let t_of = |n: u64| (n as f64 - grid.warmup_steps as f64) * dt;
    let (rot_sin, rot_cos) = (plant.omega * dt).sin_cos();
    let (mut x, mut v) = plant.initial_state(plant.omega * t_of(0) + phase0);
    let mut stuck = v == 0.0;
    let mut held = Held::default();
    let (mut cb, mut sb) = (1.0, 0.0);
    let mut cached_n = f64::NAN;
    let mut cached_factor = 1.0;
    // Stiction: time stuck, and the scatter draw of the current stop.
    let mut t_stick = 0.0;
    let mut scatter = 0.0;
    // Rate-and-state: the state θ.
    let mut theta = match plant.memory {
        Some(MemoryForm::RateState { slip_distance_m, .. }) => slip_distance_m / v.abs().max(1e-3),
        _ => 0.0,
    };
    // LuGre: the bristle deflection z (steady at the start).
    let mut z = 0.0;
    let (k, c, u0) = (plant.k, plant.c, plant.u0);
    let dt_over_m = dt / plant.m;
    let (a, b, cs, d) = (plant.a, plant.b, plant.cs, plant.d);
    let draw_scatter = |rng: &mut Gauss| match plant.stiction {
        Some(StaticForm::Karnopp { .. }) => rng.normal(),
        _ => 0.0,
    };
    let mut countdown = 0;
    for n in 0..total {
        let t = t_of(n);
        if countdown == 0 {
            countdown = grid.hold;
            held = noise.interval(plant, t);
            // Re-anchor the base's rotation on the exact phase.
            (sb, cb) = (plant.omega * t + phase0).sin_cos();
        }
        let u = u0 * cb;
        // The normal force.
        let mut nf = held.n_mean;
        match plant.harmonic {
            None => {}
            Some(HarmonicForm::PositionFollowing { strength, quadratic_per_linear }) => {
                let r = if u0 > 0.0 { x / u0 } else { 0.0 };
                nf *= (1.0 + strength * r + strength * quadratic_per_linear * r * r).max(0.0);
            }
            Some(HarmonicForm::WanderingHarmonic { strength, order, .. }) => {
                let (mut hc, mut hs) = (cb, sb);
                for _ in 1..order.max(1) {
                    (hc, hs) = (hc * cb - hs * sb, hs * cb + hc * sb);
                }
                nf *= 1.0 + strength * (hc * held.phase_cos - hs * held.phase_sin);
            }
        }
        nf = (nf + held.n_noise).max(0.0);
        let lf = if plant.load.is_some() {
            if nf != cached_n {
                cached_n = nf;
                cached_factor = plant.load_factor(nf);
            }
            cached_factor
        } else {
            1.0
        };
        // The eq. 7 law at speed s (noise and load factor included), ≥ 0.
        let law = |s: f64| ((a + b / (1.0 + cs * s) + d * s * s + held.mu_noise) * lf).max(0.0);
        let mu_k0 = ((a + b + held.mu_noise) * lf).max(0.0);
        let breakaway = |t_stick: f64, scatter: f64| match plant.stiction {
            None => mu_k0,
            Some(StaticForm::Karnopp { strength, scatter: r }) => {
                mu_k0 * (1.0 + strength * (1.0 + r * scatter)).max(1.0)
            }
            Some(StaticForm::DwellAgeing { strength, time_constant_s }) => {
                mu_k0 + strength * (t_stick / time_constant_s.max(1e-12)).ln_1p()
            }
        };

        let friction;
        if let Some((length, sigma1, v_d)) = plant.lugre {
            // LuGre: the bristle state carries stick (pre-sliding).
            let s = v.abs();
            let resting = s < 1e-3;
            if resting {
                if t_stick == 0.0 {
                    scatter = draw_scatter(&mut stiction_rng);
                }
                t_stick += dt;
            } else {
                t_stick = 0.0;
            }
            let excess = breakaway(t_stick, scatter) - mu_k0;
            let g = (law(s) + if excess > 0.0 { excess * exp_neg((s / 1e-3).powi(2)) } else { 0.0 }).max(1e-9);
            let zn = if s > 0.0 {
                let z_ss = sign(v) * g * length;
                z_ss + (z - z_ss) * exp_neg(s * dt / (g * length))
            } else {
                z
            };
            let zdot = (zn - z) / dt;
            let mu = zn / length + sigma1 * exp_neg((v / v_d).powi(2)) * zdot;
            friction = -nf * mu;
            let p = k * (u - x) - c * v;
            if n >= grid.warmup_steps {
                sink.step(n - grid.warmup_steps, t, cb, sb, x, v, nf, friction);
            }
            z = zn;
            v += dt_over_m * (p + friction);
            x += dt * v;
        } else if stuck {
            let p = k * (u - x);
            if p.abs() <= breakaway(t_stick, scatter) * nf {
                friction = -p;
                if n >= grid.warmup_steps {
                    sink.step(n - grid.warmup_steps, t, cb, sb, x, 0.0, nf, friction);
                }
                t_stick += dt;
                if let Some(MemoryForm::RateState { .. }) = plant.memory {
                    theta += dt;
                }
            } else {
                // Breakaway in the direction of the spring force, with the
                // kinetic friction just above zero speed.
                let dir = sign(p);
                friction = -dir * mu_k0 * nf;
                if n >= grid.warmup_steps {
                    sink.step(n - grid.warmup_steps, t, cb, sb, x, 0.0, nf, friction);
                }
                let vn = dt_over_m * (p + friction);
                if vn * dir > 0.0 {
                    stuck = false;
                    t_stick = 0.0;
                    v = vn;
                    x += dt * v;
                } else {
                    t_stick += dt;
                }
                if let Some(MemoryForm::RateState { .. }) = plant.memory {
                    theta += dt;
                }
            }
        } else {
            let s = v.abs();
            let mut mu = law(s);
            if let Some(MemoryForm::RateState { strength, slip_distance_m, reference_speed_m_per_s }) = plant.memory {
                // Δμ = 2b [asinh(y) − asinh(z)], y² = v² θ/(4 v_r D_c), z² = |v|/(4 v_r).
                let vr = reference_speed_m_per_s;
                let y2 = s * s * theta / (4.0 * vr * slip_distance_m);
                let z2 = s / (4.0 * vr);
                let delta = if y2.min(z2) > 1e3 {
                    // asinh(w) = ln(2w) + 1/(4w²) − O(1/w⁴): to 1e-7 b.
                    strength * ((y2 / z2).ln() + 0.5 * (1.0 / y2 - 1.0 / z2))
                } else {
                    let (y, zz) = (y2.sqrt(), z2.sqrt());
                    2.0 * strength * ((y + (y2 + 1.0).sqrt()) / (zz + (z2 + 1.0).sqrt())).ln()
                };
                mu = (mu + delta).max(0.0);
                // Aging law, exact for a step at constant speed.
                let theta_ss = slip_distance_m / s.max(1e-300);
                theta = theta_ss + (theta - theta_ss) * exp_neg(s * dt / slip_distance_m);
            }
            friction = -sign(v) * mu * nf;
            if n >= grid.warmup_steps {
                sink.step(n - grid.warmup_steps, t, cb, sb, x, v, nf, friction);
            }
            let p = k * (u - x) - c * v;
            let mut vn = v + dt_over_m * (p + friction);
            let crossing = vn * v <= 0.0;
            if crossing || (vn.abs() < plant.rest_speed && vn.abs() < s) {
                // At rest for an instant: stick, or go on in the direction
                // of the spring force.
                let p0 = k * (u - x);
                t_stick = 0.0;
                scatter = draw_scatter(&mut stiction_rng);
                if p0.abs() <= breakaway(0.0, scatter) * nf {
                    stuck = true;
                    vn = 0.0;
                } else if crossing || p0 * v < 0.0 {
                    let dir = sign(p0);
                    vn = dt_over_m * (p0 - dir * mu_k0 * nf);
                }
            }
            v = vn;
            x += dt * v;
        }
        countdown -= 1;
        // Advance the base's rotation by one step.
        (cb, sb) = (cb * rot_cos - sb * rot_sin, sb * rot_cos + cb * rot_sin);
    }
}

// ---------------------------------------------------------------------------
// Records
// ---------------------------------------------------------------------------
