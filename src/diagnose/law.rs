//! The friction law as the force channels give it: the paper's
//! μ(v) = a + b / (1 + c |v|) + d v² fitted by least squares to the slipping
//! samples of records, with the residual spread σ_μ (–), and the moments a
//! simulated record's law is read from so that simulated and measured
//! records are read alike.

use rayon::prelude::*;

use crate::diagnose::features::{MotionReading, solve_normal};
use crate::engine::Model;
use crate::measure::{RigInfo, Run};

/// The paper's law `μ(v) = a + b / (1 + c |v|) + d v²` fitted to slipping
/// samples, with the residual standard deviation around it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct FrictionLaw {
    /// Mean level over the samples (records' levels may differ), –.
    pub(crate) a: f64,
    /// –
    pub(crate) b: f64,
    /// s/m
    pub(crate) c: f64,
    /// s²/m²
    pub(crate) d: f64,
    /// Residual standard deviation of μ within records (around the fit,
    /// whose levels are per record, so a friction level that differs
    /// between records — with the load, over a drift — is not counted as
    /// noise), –. The fit over `c` minimises it; σ_μ is matched by it.
    pub(crate) sigma: f64,
    /// The slipping speeds' 5%, 15%, …, 95% quantiles, m/s: where the law
    /// is known.
    pub(crate) anchors_m_per_s: [f64; 10],
}

/// The largest |d| a fitted law may have, s²/m²: d v² then reaches 0.3 at
/// 0.3 m/s, beyond any steel-on-steel law we know of (the paper's 0.105).
const MAX_D_S2_PER_M2: f64 = 3.0;

impl FrictionLaw {
    /// This law moved at the `measured` law's anchor speeds by what the
    /// measured law and the `simulated` one (the same fit on simulated
    /// records) differ by there, refitted at this law's Stribeck rate;
    /// `None` where the refit is singular or implausible.
    pub(crate) fn moved(&self, measured: &FrictionLaw, simulated: &FrictionLaw) -> Option<FrictionLaw> {
        let anchors = SlipSamples {
            speed: measured.anchors_m_per_s.to_vec(),
            mu: measured.anchors_m_per_s.iter().map(|&v| self.mu(v) + measured.mu(v) - simulated.mu(v)).collect(),
            record: vec![0; measured.anchors_m_per_s.len()],
            clear: None,
            sensor_variance: vec![0.0],
            anchors_m_per_s: speed_deciles(&measured.anchors_m_per_s),
        };
        anchors.fit_at(self.c).filter(|l| l.plausible())
    }

    /// The model's law (no anchors).
    pub(crate) fn of(model: &Model) -> FrictionLaw {
        let f = &model.friction;
        FrictionLaw { a: f.a, b: f.b, c: f.c, d: f.d, sigma: f.sigma, anchors_m_per_s: [0.0; 10] }
    }

    /// μ at speed `v`, m/s.
    pub(crate) fn mu(&self, v: f64) -> f64 {
        self.a + self.b / (1.0 + self.c * v.abs()) + self.d * v * v
    }

    /// A law a rig could have: friction non-negative at rest, a Stribeck
    /// drop and a v² term within an order of magnitude of any published
    /// steel-on-steel law. Beyond these the four terms only trade off
    /// against each other within the noise.
    fn plausible(&self) -> bool {
        let top = self.anchors_m_per_s[9].max(0.05);
        self.a >= 0.0
            && self.a + self.b >= 0.0
            && self.b.abs() <= 1.0
            && self.d.abs() <= MAX_D_S2_PER_M2
            && (1..=8).all(|k| self.mu(0.25 * top * f64::from(k)) >= 0.0)
    }
}

/// Stribeck rates `c` (s/m) the fit starts from before refining: 0 and a
/// log grid from 1 to 316 s/m.
fn law_c_grid() -> impl Iterator<Item = f64> {
    std::iter::once(0.0).chain((0..11).map(|i| 10f64.powf(0.25 * f64::from(i))))
}

/// The slipping samples of some records: speed |v| (m/s) and μ = |F|/N,
/// where |v| is above 5% of its record's largest, the friction opposes the
/// motion and N > 0, and which record each came from.
struct SlipSamples {
    speed: Vec<f64>,
    mu: Vec<f64>,
    record: Vec<usize>,
    /// For a derived force, whether each sample is clear of the filter's
    /// blur ([`RecordSlips::clear`]).
    clear: Option<Vec<bool>>,
    /// The variance each record's sensors put into its μ ([`Reading`]), –².
    sensor_variance: Vec<f64>,
    /// The speeds' 5%, 15%, …, 95% quantiles, m/s (sorted once: every law
    /// fitted to these samples carries them).
    anchors_m_per_s: [f64; 10],
}

/// The 5%, 15%, …, 95% quantiles of some speeds (m/s), each the sample
/// at or below its rank.
/// Found by successive selection (each rank's sample put in place, the
/// next searched only above it), the same samples a full sort gives.
fn speed_deciles(speed: &[f64]) -> [f64; 10] {
    let mut values = speed.to_vec();
    let n = values.len();
    let ranks: [usize; 10] = std::array::from_fn(|k| ((0.05 + 0.1 * k as f64) * (n - 1) as f64) as usize);
    let mut below = 0;
    for &rank in &ranks {
        if rank >= below {
            values[below..].select_nth_unstable_by(rank - below, f64::total_cmp);
            below = rank + 1;
        }
    }
    ranks.map(|rank| values[rank])
}

/// No friction law is fitted to fewer slipping samples than this.
pub(crate) const MIN_SLIP_SAMPLES: usize = 50;

/// How the records a law (and their friction features) are read from were
/// measured: the velocity channel's white noise, which a slipping sample's
/// speed must stand above
/// ([`crate::diagnose::features::SLIP_SPEED_NOISE_SDS`]), and, for a
/// friction force derived from the displacement, the rig it was derived
/// with, which sets how much of the displacement sensor's noise each
/// record's μ carries ([`crate::diagnose::derived::mu_noise_variance`])
/// and how far its filter blurs ([`Reading::motion`]). The measured
/// records and the model's replicates are read with the same one.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Reading<'a> {
    /// m/s
    pub(crate) v_noise_m_per_s: f64,
    /// `None` where the friction force is recorded: its sensor's share of
    /// μ's spread is then taken as nil, and every record weighs alike.
    pub(crate) derived_with: Option<&'a RigInfo>,
}

impl Reading<'_> {
    /// The variance the sensors put into `run`'s μ, –².
    fn sensor_variance(&self, run: &Run) -> f64 {
        self.derived_with.map_or(0.0, |rig| crate::diagnose::derived::mu_noise_variance(run, rig))
    }

    /// How `run`'s friction features tell its slipping samples apart. A
    /// force derived from the displacement is read only where it resolves
    /// a slip: above the derived velocity's noise, and clear of the
    /// filter's blur. Otherwise a block that the noise frees for a few
    /// samples at a time (a load that holds it) shows a "friction" that is
    /// the filter's blend of the spring's force at rest, and the velocity's
    /// noise alone passes a twentieth of a largest speed that is itself
    /// noise. A recorded force is read at every sample above a twentieth of
    /// the largest speed, as it always was.
    pub(crate) fn motion(&self, run: &Run) -> MotionReading {
        match self.derived_with {
            Some(_) => MotionReading {
                v_noise_m_per_s: self.v_noise_m_per_s,
                blur_samples: crate::diagnose::derived::blur_samples(run),
            },
            None => MotionReading::default(),
        }
    }
}

/// The samples of one run that count as slipping: speed |v| (m/s) and
/// μ = |F|/N, where |v| is above 5% of the run's largest and above
/// [`crate::diagnose::features::SLIP_SPEED_NOISE_SDS`] standard deviations
/// of the velocity's white noise (m/s; the data's estimate, which the
/// simulated records carry too, so both sides pick alike;
/// [`MotionReading::slipping`]), the friction opposes the motion and N is
/// at least a tenth of its median
/// ([`crate::diagnose::features::normal_force_floor`]; the nominal load
/// without a normal-force channel, [`crate::diagnose::features::load_of`]).
/// Every such sample, a derived force's blurred ones too: the slowest
/// slips, at a stick's ends, are what pin μ(0) = a + b, and read clear of
/// the blur a few records leave the law's curve free to wander, while the
/// indirect inference reads the replicates' blur alike. For a derived
/// force, which of them are also clear of the blur
/// ([`Reading::motion`]): the friction's spread is read there
/// ([`LawMoments::law_of_records`]). Empty without velocity and friction
/// channels.
fn slipping_samples(run: &Run, reading: &Reading<'_>) -> RecordSlips {
    let mut slips = RecordSlips::default();
    let (Some(v), Some(f)) = (&run.v_m_per_s, &run.friction_force) else {
        return slips;
    };
    let n = &crate::diagnose::features::load_of(run);
    let moving = MotionReading { v_noise_m_per_s: reading.v_noise_m_per_s, blur_samples: 0 }.slipping(v);
    let clear = reading.derived_with.map(|_| reading.motion(run).slipping(v));
    let floor = crate::diagnose::features::normal_force_floor(n);
    let mut clear_of_blur = Vec::new();
    for i in 0..v.len().min(f.len()).min(n.len()) {
        if moving[i] && f[i] * v[i] < 0.0 && n[i] >= floor {
            slips.speed.push(v[i].abs());
            slips.mu.push(f[i].abs() / n[i]);
            clear_of_blur.extend(clear.as_ref().map(|c| c[i]));
        }
    }
    slips.clear = clear.map(|_| clear_of_blur);
    slips
}

/// One record's slipping samples ([`slipping_samples`]).
#[derive(Debug, Default)]
struct RecordSlips {
    /// |v|, m/s.
    speed: Vec<f64>,
    /// |F|/N, –.
    mu: Vec<f64>,
    /// For a derived force, whether each sample is clear of the filter's
    /// blur; `None` for a recorded force (every sample is).
    clear: Option<Vec<bool>>,
}

/// What the residual about a law reads from the slipping samples of one
/// record that are clear of a derived force's blur: their count and the
/// sums and cross products of the columns s², g(s) and μ, each centred on
/// the whole record's mean ([`LawMoments`]), so the residual about any
/// (b, d) and its spread about its own mean can be read
/// ([`ClearMoments::residual_sum_of_squares`]).
#[derive(Clone, Copy, Debug, Default)]
struct ClearMoments {
    /// Samples.
    count: usize,
    /// Σ of the centred s², m²/s².
    d: f64,
    /// Σ of the centred g, –.
    g: f64,
    /// Σ of the centred μ, –.
    y: f64,
    /// m⁴/s⁴
    dd: f64,
    /// m²/s²
    dg: f64,
    /// –
    gg: f64,
    /// m²/s²
    dy: f64,
    /// –
    gy: f64,
    /// –
    yy: f64,
}

impl ClearMoments {
    /// The sum of squares of the residual μ − b g − d s² about its own
    /// mean over these samples, –.
    fn residual_sum_of_squares(&self, b: f64, d: f64) -> f64 {
        if self.count == 0 {
            return 0.0;
        }
        let sum = self.y - b * self.g - d * self.d;
        let fitted = b * b * self.gg + 2.0 * b * d * self.dg + d * d * self.dd;
        let squares = self.yy - 2.0 * b * self.gy - 2.0 * d * self.dy + fitted;
        (squares - sum * sum / self.count as f64).max(0.0)
    }
}

/// What the within-record fit of eq. 7 at one Stribeck rate `c` reads from
/// slipping samples ([`SlipSamples::fit_at`]), as sums that add over
/// records: the samples' count and sums of μ, s² and g(s) = 1/(1 + c s)
/// (for the mean level `a`), and the cross products of the columns s², g
/// and μ, each centred on its own record's mean (so a friction level that
/// differs between records is not read as a curve). Records summed
/// separately (in parallel, say) give the fit all of them give at once.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct LawMoments {
    /// Samples.
    count: usize,
    /// Records with at least one sample.
    records: usize,
    /// Σ over the samples of the variance their record's sensors put into
    /// μ (0 for a recorded force, [`Reading`]), –².
    sensor_variance_sum: f64,
    /// Σμ, –.
    sum_mu: f64,
    /// Σs², m²/s².
    sum_s2: f64,
    /// Σg, –.
    sum_g: f64,
    /// Σ(s² − its record's mean)², m⁴/s⁴.
    dd: f64,
    /// Σ(s² − mean)(g − mean), m²/s².
    dg: f64,
    /// Σ(g − mean)², –.
    gg: f64,
    /// Σ(s² − mean)(μ − mean), m²/s².
    dy: f64,
    /// Σ(g − mean)(μ − mean), –.
    gy: f64,
    /// Σ(μ − mean)², –.
    yy: f64,
    /// For one record of a derived force, the same read at its samples
    /// clear of the filter's blur; `None` for a recorded force, and once
    /// records are added together.
    clear: Option<ClearMoments>,
}

impl LawMoments {
    /// The moments of one record's slipping samples (`speed`, m/s; `mu`, –)
    /// at Stribeck rate `c` (s/m), with those of the samples `clear` of a
    /// derived force's blur.
    fn of_record(speed: &[f64], mu: &[f64], clear: Option<&[bool]>, c: f64) -> LawMoments {
        let n = speed.len();
        if n == 0 {
            return LawMoments { clear: clear.map(|_| ClearMoments::default()), ..LawMoments::default() };
        }
        let g = |s: f64| 1.0 / (1.0 + c * s);
        let (sum_mu, sum_s2, sum_g) =
            speed.iter().zip(mu).fold((0.0, 0.0, 0.0), |(m, d, q), (&s, &y)| (m + y, d + s * s, q + g(s)));
        let (mean_mu, mean_s2, mean_g) = (sum_mu / n as f64, sum_s2 / n as f64, sum_g / n as f64);
        let mut m = LawMoments { count: n, records: 1, sum_mu, sum_s2, sum_g, ..LawMoments::default() };
        let mut cm = ClearMoments::default();
        for (i, (&s, &y)) in speed.iter().zip(mu).enumerate() {
            let (d, q, y) = (s * s - mean_s2, g(s) - mean_g, y - mean_mu);
            m.dd += d * d;
            m.dg += d * q;
            m.gg += q * q;
            m.dy += d * y;
            m.gy += q * y;
            m.yy += y * y;
            if clear.is_some_and(|c| c[i]) {
                cm.count += 1;
                (cm.d, cm.g, cm.y) = (cm.d + d, cm.g + q, cm.y + y);
                cm.dd += d * d;
                cm.dg += d * q;
                cm.gg += q * q;
                cm.dy += d * y;
                cm.gy += q * y;
                cm.yy += y * y;
            }
        }
        m.clear = clear.map(|_| cm);
        m
    }

    /// The moments of one run's slipping samples ([`slipping_samples`]) at
    /// Stribeck rate `c` (s/m), read as `reading` says.
    pub(crate) fn of_run(run: &Run, reading: &Reading<'_>, c: f64) -> LawMoments {
        let slips = slipping_samples(run, reading);
        LawMoments::of_record(&slips.speed, &slips.mu, slips.clear.as_deref(), c)
            .with_sensor_variance(reading.sensor_variance(run))
    }

    /// These moments of one record whose sensors put `variance` (–²) into
    /// each sample's μ.
    fn with_sensor_variance(mut self, variance: f64) -> LawMoments {
        self.sensor_variance_sum = variance * self.count as f64;
        self
    }

    /// How many samples the moments are of.
    pub(crate) fn count(&self) -> usize {
        self.count
    }

    /// Adds another record's (or records') moments.
    pub(crate) fn add(&mut self, other: &LawMoments) {
        self.count += other.count;
        self.records += other.records;
        self.clear = None;
        for (a, b) in [
            (&mut self.sensor_variance_sum, other.sensor_variance_sum),
            (&mut self.sum_mu, other.sum_mu),
            (&mut self.sum_s2, other.sum_s2),
            (&mut self.sum_g, other.sum_g),
            (&mut self.dd, other.dd),
            (&mut self.dg, other.dg),
            (&mut self.gg, other.gg),
            (&mut self.dy, other.dy),
            (&mut self.gy, other.gy),
            (&mut self.yy, other.yy),
        ] {
            *a += b;
        }
    }

    /// The least-squares law at Stribeck rate `c` (s/m, the rate the
    /// moments were taken at) with `anchors_m_per_s`: linear in (b, d)
    /// with basis (1/(1 + c s), s²) within records; `a` is the samples'
    /// mean level, μ's mean less the curve's. At `c = 0` the Stribeck term
    /// is part of `a` (reported as b = 0). Where |d| comes out beyond
    /// [`MAX_D_S2_PER_M2`] (b and d trading off along a direction the
    /// speeds cannot resolve) d is held at that bound and b refitted.
    /// Otherwise not constrained: as a statistic of simulated records it
    /// must be the same function as on the measured ones. `None` where the
    /// fit is singular.
    pub(crate) fn law(&self, c: f64, anchors_m_per_s: [f64; 10]) -> Option<FrictionLaw> {
        let stribeck = c != 0.0;
        // (b, d, residual sum of squares, fitted columns) with d free or
        // held at `fixed_d` (μ less d s² fitted then).
        let solve = |fixed_d: Option<f64>| -> Option<(f64, f64, f64, usize)> {
            let fd = fixed_d.unwrap_or(0.0);
            let (gy, yy) = (self.gy - fd * self.dg, self.yy - 2.0 * fd * self.dy + fd * fd * self.dd);
            match (fixed_d, stribeck) {
                (None, true) => {
                    let (coef, rss) =
                        solve_normal(&[[self.dd, 0.0], [self.dg, self.gg]], &[self.dy, self.gy], self.yy)?;
                    Some((coef[1], coef[0], rss, 2))
                }
                (None, false) => {
                    let (coef, rss) = solve_normal(&[[self.dd]], &[self.dy], self.yy)?;
                    Some((0.0, coef[0], rss, 1))
                }
                (Some(_), true) => {
                    let (coef, rss) = solve_normal(&[[self.gg]], &[gy], yy)?;
                    Some((coef[0], fd, rss, 1))
                }
                (Some(_), false) => Some((0.0, fd, yy.max(0.0), 0)),
            }
        };
        let (mut b, mut d, mut rss, mut p) = solve(None)?;
        if d.abs() > MAX_D_S2_PER_M2 {
            (b, d, rss, p) = solve(Some(d.clamp(-MAX_D_S2_PER_M2, MAX_D_S2_PER_M2)))?;
        }
        let n = self.count as f64;
        let a = self.sum_mu / n - d * self.sum_s2 / n - b * self.sum_g / n;
        let sigma = (rss.max(0.0) / (self.count.saturating_sub(p + self.records)).max(1) as f64).sqrt();
        Some(FrictionLaw { a, b, c, d, sigma, anchors_m_per_s })
    }

    /// The sum of squares about the law with Stribeck term `b` and `d` (the
    /// rate the moments were taken at), each record about its own mean, –.
    fn residual_sum_of_squares(&self, b: f64, d: f64) -> f64 {
        let fitted = b * b * self.gg + 2.0 * b * d * self.dg + d * d * self.dd;
        (self.yy - 2.0 * b * self.gy - 2.0 * d * self.dy + fitted).max(0.0)
    }

    /// The law at Stribeck rate `c` (s/m) of records whose moments (taken
    /// at `c`) are `records`: its curve from every slipping sample alike,
    /// and its residual σ with each record weighted by the inverse of the
    /// variance its μ is expected to have about the curve: the friction's
    /// own (the unweighted residual variance less the sensors' mean share,
    /// at least [`FRICTION_SHARE_FLOOR`] of it) plus what its sensors put
    /// in. A friction force derived from the displacement carries the
    /// sensor's noise through the filter as a force of fixed size, whose
    /// share of μ grows as 1/N²: at the lightest loads it is nearly all of
    /// μ's spread, and unweighted those records would bury the friction's
    /// own noise under a 1% error in the sensor's. The curve stays
    /// unweighted: the lighter loads slide fastest, and a curve read at the
    /// heavy loads' slow speeds alone would leave theirs to an
    /// extrapolation. The weights come from the sensors alone, never from a
    /// record's own residual, so a record whose friction departs from the
    /// law (an effect) weighs as much as its neighbours. With recorded
    /// forces every record weighs alike: the unweighted fit.
    ///
    /// A derived force's σ is read at the samples clear of the filter's
    /// blur ([`ClearMoments`]), each record's about its own mean, where
    /// there are at least [`MIN_SLIP_SAMPLES`]: near a stop the filter
    /// blends the spring's force at rest into the friction, a spread the
    /// friction does not have, and an ageing memory or a noisier law would
    /// be fitted to stand in for it. The curve still needs those slowest
    /// slips, which pin μ(0) = a + b.
    pub(crate) fn law_of_records(records: &[LawMoments], c: f64, anchors_m_per_s: [f64; 10]) -> Option<FrictionLaw> {
        LawMoments::law_and_curve_sigma(records, c, anchors_m_per_s).map(|(law, _)| law)
    }

    /// [`LawMoments::law_of_records`], and the weighted residual σ of its
    /// curve over every slipping sample (–; the σ of a recorded force),
    /// which a Stribeck rate is chosen by ([`SlipSamples::fit`]).
    fn law_and_curve_sigma(records: &[LawMoments], c: f64, anchors: [f64; 10]) -> Option<(FrictionLaw, f64)> {
        let mut pooled = LawMoments::default();
        records.iter().for_each(|r| pooled.add(r));
        let law = pooled.law(c, anchors)?;
        let every = |r: &LawMoments| Some((r.residual_sum_of_squares(law.b, law.d), r.count));
        let curve_sigma = if pooled.sensor_variance_sum > 0.0 {
            weighted_sigma(records, law.sigma.powi(2), every).unwrap_or(law.sigma)
        } else {
            law.sigma
        };
        let clear = |r: &LawMoments| r.clear.map(|m| (m.residual_sum_of_squares(law.b, law.d), m.count));
        let clear_count: usize = records.iter().filter_map(clear).map(|(_, n)| n).sum();
        if records.iter().any(|r| r.count > 0 && r.clear.is_none()) || clear_count < MIN_SLIP_SAMPLES {
            return Some((FrictionLaw { sigma: curve_sigma, ..law }, curve_sigma));
        }
        let (rss, dof) =
            records.iter().filter_map(clear).fold((0.0, 0usize), |(s, k), (rss, n)| (s + rss, k + n.saturating_sub(1)));
        let sigma = weighted_sigma(records, rss / dof.max(1) as f64, clear).unwrap_or(curve_sigma);
        Some((FrictionLaw { sigma, ..law }, curve_sigma))
    }
}

/// The residual σ (–) of `records` about a law, each record weighted as
/// [`LawMoments::law_of_records`] says, from each record's residual sum of
/// squares and sample count as `read` gives them (each record about its
/// own mean), with `total` (–²) their unweighted residual variance; `None`
/// where it is not finite.
fn weighted_sigma(
    records: &[LawMoments],
    total: f64,
    read: impl Fn(&LawMoments) -> Option<(f64, usize)>,
) -> Option<f64> {
    let read = || records.iter().filter_map(|r| read(r).filter(|&(_, n)| n > 0).map(|x| (r, x)));
    let (mut sensor, mut count) = (0.0, 0usize);
    for (r, (_, n)) in read() {
        sensor += r.sensor_variance_sum / r.count as f64 * n as f64;
        count += n;
    }
    let friction = (total - sensor / count.max(1) as f64).max(FRICTION_SHARE_FLOOR * total);
    let (mut sum_rss, mut sum_dof) = (0.0, 0.0);
    for (r, (rss, n)) in read().filter(|(_, (_, n))| *n > 1) {
        let weight = 1.0 / (friction + r.sensor_variance_sum / r.count as f64);
        sum_rss += weight * rss;
        sum_dof += weight * (n - 1) as f64;
    }
    Some((sum_rss / sum_dof).sqrt()).filter(|s| s.is_finite())
}

/// The least share of the records' residual variance that is taken to be
/// the friction's own when records are weighted
/// ([`LawMoments::law_of_records`]): where the sensors' estimated share
/// comes to all of it, the lightest-loaded records still weigh something.
const FRICTION_SHARE_FLOOR: f64 = 0.05;

impl SlipSamples {
    /// The slipping samples of `runs` ([`slipping_samples`]), read as
    /// `reading` says; `None` with fewer than 50.
    fn of(runs: &[&Run], reading: &Reading<'_>) -> Option<SlipSamples> {
        let (mut speed, mut mu, mut record) = (Vec::new(), Vec::new(), Vec::new());
        let mut clear = reading.derived_with.map(|_| Vec::new());
        let sensor_variance = runs.iter().map(|r| reading.sensor_variance(r)).collect();
        for (k, r) in runs.iter().enumerate() {
            let slips = slipping_samples(r, reading);
            record.extend(std::iter::repeat_n(k, slips.speed.len()));
            speed.extend(slips.speed);
            mu.extend(slips.mu);
            if let (Some(all), Some(of_run)) = (clear.as_mut(), slips.clear) {
                all.extend(of_run);
            }
        }
        if mu.len() < MIN_SLIP_SAMPLES {
            return None;
        }
        let anchors_m_per_s = speed_deciles(&speed);
        Some(SlipSamples { speed, mu, record, clear, sensor_variance, anchors_m_per_s })
    }

    /// The within-record least-squares law at a given `c` (s/m; see
    /// [`LawMoments::law`]), with these samples' anchors. With one record
    /// this is the ordinary fit with an intercept.
    fn fit_at(&self, c: f64) -> Option<FrictionLaw> {
        self.fit_scored(c).map(|(law, _)| law)
    }

    /// [`SlipSamples::fit_at`], and the weighted residual σ of its curve
    /// over every sample (–; [`LawMoments::law_of_records`]).
    fn fit_scored(&self, c: f64) -> Option<(FrictionLaw, f64)> {
        let mut records = Vec::new();
        let mut start = 0;
        // Samples are grouped by record (in the order they were collected).
        while start < self.record.len() {
            let end = start + self.record[start..].iter().take_while(|&&k| k == self.record[start]).count();
            let sensor_variance = self.sensor_variance[self.record[start]];
            records.push(
                LawMoments::of_record(
                    &self.speed[start..end],
                    &self.mu[start..end],
                    self.clear.as_ref().map(|c| &c[start..end]),
                    c,
                )
                .with_sensor_variance(sensor_variance),
            );
            start = end;
        }
        LawMoments::law_and_curve_sigma(&records, c, self.anchors_m_per_s)
    }

    /// The law with the smallest residual over every slipping sample
    /// ([`SlipSamples::fit_scored`]): over [`law_c_grid`], then by
    /// golden-section search in log c between the best point's neighbours.
    fn fit(&self) -> Option<FrictionLaw> {
        let grid: Vec<f64> = law_c_grid().collect();
        let laws: Vec<Option<(FrictionLaw, f64)>> = grid.par_iter().map(|&c| self.fit_scored(c)).collect();
        let (best, (law, score)) = laws
            .iter()
            .enumerate()
            .filter_map(|(i, l)| l.map(|l| (i, l)))
            .filter(|(_, (l, _))| l.plausible())
            .min_by(|x, y| x.1.1.total_cmp(&y.1.1))?;
        if best == 0 {
            return Some(law);
        }
        let lo = if best == 1 { grid[1] / 3.0 } else { grid[best - 1] };
        let hi = grid.get(best + 1).copied().unwrap_or(grid[best] * 3.0);
        let (mut lo, mut hi) = (lo.ln(), hi.ln());
        let golden = 0.5 * (5f64.sqrt() - 1.0);
        let sigma_at =
            |x: f64| self.fit_scored(x.exp()).filter(|(l, _)| l.plausible()).map_or(f64::INFINITY, |(_, s)| s);
        let (mut x1, mut x2) = (hi - golden * (hi - lo), lo + golden * (hi - lo));
        let (mut f1, mut f2) = (sigma_at(x1), sigma_at(x2));
        for _ in 0..14 {
            if f1 < f2 {
                (hi, x2, f2) = (x2, x1, f1);
                x1 = hi - golden * (hi - lo);
                f1 = sigma_at(x1);
            } else {
                (lo, x1, f1) = (x1, x2, f2);
                x2 = lo + golden * (hi - lo);
                f2 = sigma_at(x2);
            }
        }
        let refined = self.fit_scored((0.5 * (lo + hi)).exp()).filter(|(l, _)| l.plausible());
        Some(refined.filter(|&(_, s)| s <= score).map_or(law, |(l, _)| l))
    }
}

/// How far the friction level of `runs` stands from `law`: the mean of
/// μ − law(|v|) over their slipping samples ([`slipping_samples`], read
/// as `reading` says), –, and how many samples
/// there are; `None` with fewer than [`MIN_SLIP_SAMPLES`] (records of a
/// block that barely slips say nothing about its sliding friction).
pub(crate) fn level_against(runs: &[&Run], reading: &Reading<'_>, law: &FrictionLaw) -> Option<(f64, usize)> {
    let samples = SlipSamples::of(runs, reading)?;
    let sum: f64 = samples.speed.iter().zip(&samples.mu).map(|(&v, &m)| m - law.mu(v)).sum();
    Some((sum / samples.mu.len() as f64, samples.mu.len()))
}

/// The law of eq. 7 with the smallest residual (see [`SlipSamples::fit`])
/// on the slipping samples of `runs`, read as `reading` says; `None`
/// without force channels or with fewer than 50 slipping samples.
pub(crate) fn fit_friction_law(runs: &[&Run], reading: &Reading<'_>) -> Option<FrictionLaw> {
    SlipSamples::of(runs, reading)?.fit()
}

/// The law of eq. 7 at the Stribeck rate `c` (s/m) on the slipping samples
/// of `runs` (see [`fit_friction_law`]); `None` without force channels or
/// with fewer than 50 slipping samples. It is a statistic of the records,
/// read as a simulated record's law is ([`LawMoments::law`]), so it is not
/// held to a law a rig could have: that test chooses `c` on the whole data
/// ([`fit_friction_law`]) and keeps a model's stepped law valid. Part of
/// the data (a fold's other levels) can fit a law just below zero at rest
/// where the whole data fits one just above, friction rising from rest as
/// under a memory. Refused, that fold would lose its force channels: its
/// level would be solved from the response alone, at many times the cost,
/// and the fold judged by another yardstick than its neighbours.
pub(crate) fn fit_friction_law_at(runs: &[&Run], reading: &Reading<'_>, c: f64) -> Option<FrictionLaw> {
    SlipSamples::of(runs, reading)?.fit_at(c).filter(|l| [l.a, l.b, l.d, l.sigma].iter().all(|t| t.is_finite()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::derived::{DerivedChannels, derive, velocity_noise};
    use crate::diagnose::features::least_squares;
    use crate::engine::Sample;
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};

    #[test]
    fn deciles_by_selection_are_those_of_a_sort() {
        let mut rng = StdRng::seed_from_u64(7);
        for n in [1usize, 2, 9, 10, 11, 57, 1000, 4097] {
            // Ties included: a coarse grid of speeds.
            let speed: Vec<f64> = (0..n).map(|_| (rng.random::<f64>() * 50.0).floor() * 0.01).collect();
            let mut sorted = speed.clone();
            sorted.sort_unstable_by(f64::total_cmp);
            let expected: [f64; 10] =
                std::array::from_fn(|k| sorted[((0.05 + 0.1 * k as f64) * (n - 1) as f64) as usize]);
            assert_eq!(speed_deciles(&speed), expected, "n = {n}");
        }
    }

    /// A record sliding back and forth at 1 Hz with friction from a known
    /// law of eq. 7 (d = 0) plus Gaussian noise of sd `sigma`.
    fn record(a: f64, b: f64, c: f64, sigma: f64, seed: u64) -> Run {
        record_d(a, b, c, 0.0, sigma, seed)
    }

    fn record_d(a: f64, b: f64, c: f64, d: f64, sigma: f64, seed: u64) -> Run {
        record_at(a, b, c, d, sigma, seed, 0.4)
    }

    /// [`record_d`] with a speed amplitude `v0` (m/s).
    #[allow(clippy::too_many_arguments)]
    fn record_at(a: f64, b: f64, c: f64, d: f64, sigma: f64, seed: u64, v0: f64) -> Run {
        let mut rng = StdRng::seed_from_u64(seed);
        let samples: Vec<Sample> = (0..12_000)
            .map(|i| {
                let t_s = f64::from(i) / 600.0;
                let v = v0 * (std::f64::consts::TAU * t_s).sin();
                let (u1, u2): (f64, f64) = (rng.random::<f64>().max(1e-300), rng.random());
                let noise = sigma * (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
                let mu = a + b / (1.0 + c * v.abs()) + d * v * v + noise;
                Sample { t_s, x_m: 0.0, v_m_per_s: v, normal_force_n: 10.0, friction_force_n: -v.signum() * mu * 10.0 }
            })
            .collect();
        Run::from_samples(&samples, 1.0, 1e-3, 10.0)
    }

    /// Two records whose friction levels differ (as with load-dependent
    /// friction), the higher level sliding slower (as at a higher load): a
    /// pooled fit would read the level step as friction falling with speed.
    /// The within-record fit recovers the curve, the mean level, and the
    /// noise without the step.
    #[test]
    fn friction_levels_that_differ_between_records_are_not_read_as_a_stribeck_curve() {
        let (fast, slow) =
            (record_at(0.22, 0.1, 20.0, 0.0, 0.03, 5, 0.4), record_at(0.30, 0.1, 20.0, 0.0, 0.03, 6, 0.1));
        let law = fit_friction_law(&[&fast, &slow], &Reading::default()).unwrap();
        let shape = |l: &FrictionLaw, v: f64| mu(l, v) - mu(l, 0.1);
        let truth = FrictionLaw { a: 0.26, b: 0.1, c: 20.0, d: 0.0, sigma: 0.03, anchors_m_per_s: [0.0; 10] };
        let worst = (1..=20)
            .map(|i| 0.02 * f64::from(i))
            .map(|v| (shape(&law, v) - shape(&truth, v)).abs())
            .fold(0.0, f64::max);
        assert!(worst < 0.01, "{law:?}: the curve's shape is {worst} off");
        assert!((law.sigma / 0.03 - 1.0).abs() < 0.03, "{law:?}: sigma should leave out the 0.08 level step");
        // The level is the two records' mean (they hold about as many
        // slipping samples each).
        assert!((mu(&law, 0.1) - mu(&truth, 0.1)).abs() < 0.01, "{law:?}");
    }

    /// The level of records against a law is their friction's mean
    /// distance from it while slipping, whatever the speeds they slip at,
    /// and a record that barely slips gives none: the load dependence's
    /// signature reads each load's level so, and a load at which the block
    /// sticks says nothing about it.
    #[test]
    fn the_level_against_a_law_is_the_mean_offset_of_the_slipping_friction() {
        let law = FrictionLaw { a: 0.22, b: 0.1, c: 20.0, d: 0.0, sigma: 0.03, anchors_m_per_s: [0.0; 10] };
        for (offset, v0, seed) in [(0.0, 0.4, 1), (0.03, 0.1, 2), (-0.02, 0.25, 3)] {
            let run = record_at(0.22 + offset, 0.1, 20.0, 0.0, 0.03, seed, v0);
            let (level, count) = level_against(&[&run], &Reading::default(), &law).unwrap();
            assert!(count > 5_000, "{count} slipping samples");
            assert!((level - offset).abs() < 0.002, "level {level} against an offset of {offset}");
        }
        let stuck = record_at(0.3, 0.1, 20.0, 0.0, 0.03, 4, 0.0);
        assert_eq!(level_against(&[&stuck], &Reading::default(), &law), None);
    }

    /// The law from moments summed record by record (as the diagnosis sums
    /// its replicates' in parallel) is the ordinary least-squares fit of
    /// μ − its record's mean on the centred columns (s², g(s)), solved here
    /// directly on the pooled rows, with and without the Stribeck term.
    #[test]
    fn records_are_weighted_by_the_noise_their_sensors_put_into_mu() {
        // Three records of one law, two read as well as a force channel
        // reads it (σ 0.02) and one whose sensors add noise ten times that
        // (a force derived from the displacement at a light load).
        let (a, b, c, d) = (0.3, 0.1, 20.0, 0.3);
        let runs = [record_d(a, b, c, d, 0.02, 3), record_d(a, b, c, d, 0.02, 4), record_d(a, b, c, d, 0.2, 5)];
        let sensor = [0.0, 0.0, 0.2f64.powi(2) - 0.02f64.powi(2)];
        let moments = |sensor: &[f64]| -> Vec<LawMoments> {
            runs.iter()
                .zip(sensor)
                .map(|(r, &v)| LawMoments::of_run(r, &Reading::default(), c).with_sensor_variance(v))
                .collect()
        };
        let unweighted = LawMoments::law_of_records(&moments(&[0.0; 3]), c, [0.0; 10]).unwrap();
        // Unweighted, the noisy record sets σ near √((2·0.02² + 0.2²)/3) = 0.117.
        assert!(unweighted.sigma > 0.1, "{unweighted:?}");
        // Weighted by the sensors' share, the friction's own σ (0.02)
        // weighs each quiet record a hundred times the noisy one: σ is
        // √(3 / (2/0.02² + 1/0.2²)) = 0.0245. The curve is read from every
        // sample alike, as unweighted.
        let weighted = LawMoments::law_of_records(&moments(&sensor), c, [0.0; 10]).unwrap();
        assert!((weighted.sigma / 0.0245 - 1.0).abs() < 0.05, "{weighted:?}");
        assert_eq!((weighted.a, weighted.b, weighted.d), (unweighted.a, unweighted.b, unweighted.d));
        assert!((weighted.a - a).abs() < 0.02 && (weighted.d - d).abs() < 0.1, "{weighted:?}");
        // A record whose μ departs from the law, its sensors no noisier,
        // weighs as much as the others: the weights come from the sensors.
        let mut pooled = LawMoments::default();
        moments(&[0.0; 3]).iter().for_each(|m| pooled.add(m));
        assert_eq!(pooled.law(c, [0.0; 10]), Some(unweighted));
    }

    /// A derived force's slowest slips carry the filter's blur: a spread
    /// (and a level) the friction does not have. Its law's curve is read
    /// from every slipping sample, the blurred ones too, and its σ from the
    /// samples clear of the blur about their own mean: here σ 0.02 on the
    /// clear samples, and on the slips below 0.12 m/s 0.08 more noise and a
    /// level 0.05 higher.
    #[test]
    fn a_derived_forces_spread_is_read_clear_of_its_blur() {
        let (c, sigma) = (20.0, 0.02);
        let slips = slipping_samples(&record_d(0.3, 0.1, c, 0.3, sigma, 11), &Reading::default());
        let clear: Vec<bool> = slips.speed.iter().map(|&s| s > 0.12).collect();
        let mut rng = StdRng::seed_from_u64(12);
        let mu: Vec<f64> = slips
            .mu
            .iter()
            .zip(&clear)
            .map(|(&m, &clear)| {
                let (u1, u2): (f64, f64) = (rng.random::<f64>().max(1e-300), rng.random());
                let blur = 0.08 * (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
                if clear { m } else { m + 0.05 + blur }
            })
            .collect();
        assert!(clear.iter().filter(|&&c| !c).count() > 1000, "the premise: many blurred samples");
        let read = |clear: Option<&[bool]>| {
            let moments = LawMoments::of_record(&slips.speed, &mu, clear, c).with_sensor_variance(1e-6);
            LawMoments::law_of_records(&[moments], c, [0.0; 10]).unwrap()
        };
        let (split, every) = (read(Some(&clear)), read(None));
        assert_eq!((split.a, split.b, split.d), (every.a, every.b, every.d), "one curve, from every sample");
        assert!(every.sigma > 2.0 * sigma, "the premise: the blur inflates σ, {every:?}");
        assert!((split.sigma / sigma - 1.0).abs() < 0.05, "σ clear of the blur: {split:?}");
        // A record without a sample clear of the blur reads as before.
        let none = LawMoments::of_record(&slips.speed, &mu, Some(&vec![false; mu.len()]), c);
        let none = LawMoments::law_of_records(&[none.with_sensor_variance(1e-6)], c, [0.0; 10]).unwrap();
        assert_eq!(none, every);
    }

    #[test]
    fn moments_added_by_record_give_the_pooled_least_squares_fit() {
        let runs = [record_d(0.22, 0.1, 20.0, 0.3, 0.03, 7), record_at(0.30, 0.1, 20.0, 0.3, 0.02, 8, 0.2)];
        for c in [0.0, 20.0] {
            let mut moments = LawMoments::default();
            runs.iter().for_each(|r| moments.add(&LawMoments::of_run(r, &Reading::default(), c)));
            let law = moments.law(c, [0.0; 10]).unwrap();
            let records: Vec<(Vec<f64>, Vec<f64>)> =
                runs.iter().map(|r| slipping_samples(r, &Reading::default())).map(|s| (s.speed, s.mu)).collect();
            let g = |s: f64| 1.0 / (1.0 + c * s);
            let mean = |x: &[f64]| x.iter().sum::<f64>() / x.len() as f64;
            let mut rows = Vec::new();
            for (speed, mu) in &records {
                let (s2, gs): (Vec<f64>, Vec<f64>) = speed.iter().map(|&s| (s * s, g(s))).unzip();
                let (m_mu, m_s2, m_g) = (mean(mu), mean(&s2), mean(&gs));
                rows.extend((0..mu.len()).map(|i| (s2[i] - m_s2, gs[i] - m_g, mu[i] - m_mu)));
            }
            let p = if c == 0.0 { 1 } else { 2 };
            let (coef, rss) = least_squares(
                rows.len(),
                p,
                |i, row| {
                    row[0] = rows[i].0;
                    if p == 2 {
                        row[1] = rows[i].1;
                    }
                },
                |i| rows[i].2,
            )
            .unwrap();
            let b = if p == 2 { coef[1] } else { 0.0 };
            assert!((law.d - coef[0]).abs() < 1e-9 && (law.b - b).abs() < 1e-9, "c {c}: {law:?} against {coef:?}");
            let sigma = (rss / (rows.len() - p - records.len()) as f64).sqrt();
            assert!((law.sigma / sigma - 1.0).abs() < 1e-9, "c {c}: {law:?} against sigma {sigma}");
            // At the records' own c the fit finds their curve.
            if c == 20.0 {
                assert!((law.d - 0.3).abs() < 0.05, "the fit should find the records' d, {law:?}");
            }
        }
    }

    /// A stuck block's measured speed is the velocity sensor's noise, and
    /// its |F|/N the spring's holding force, not friction. A record that
    /// slides slowly (up to 3 cm/s) for half of each second and sticks for
    /// the other half, its speed read with 2 mm/s of noise: 5% of its
    /// largest speed is below that noise, so without the sensor's noise the
    /// stuck samples (|F|/N = 0.1, half of them with friction's sign) pass
    /// as slipping and pull the low-speed law down; with it they do not.
    #[test]
    fn stuck_samples_read_through_a_noisy_velocity_are_not_friction() {
        let (a, b, c, sigma, v_noise) = (0.2, 0.1, 20.0, 0.01, 0.002);
        let mut rng = StdRng::seed_from_u64(9);
        let mut gauss = move || {
            let (u1, u2): (f64, f64) = (rng.random::<f64>().max(1e-300), rng.random());
            (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
        };
        let samples: Vec<Sample> = (0..12_000)
            .map(|i| {
                let t_s = f64::from(i) / 600.0;
                let phase = t_s.fract();
                let (v, f) = if phase < 0.5 {
                    let v = 0.03 * (std::f64::consts::TAU * phase).sin();
                    (v, -(a + b / (1.0 + c * v) + sigma * gauss()) * 10.0)
                } else {
                    (0.0, -1.0)
                };
                let v_read = v + v_noise * gauss();
                Sample { t_s, x_m: 0.0, v_m_per_s: v_read, normal_force_n: 10.0, friction_force_n: f }
            })
            .collect();
        let run = Run::from_samples(&samples, 1.0, 1e-3, 10.0);
        let truth = FrictionLaw { a, b, c, d: 0.0, sigma, anchors_m_per_s: [0.0; 10] };
        let off = |l: &FrictionLaw| {
            (3..=12).map(|i| 0.0025 * f64::from(i)).map(|v| (mu(l, v) - mu(&truth, v)).abs()).fold(0.0, f64::max)
        };
        let with_noise = fit_friction_law(&[&run], &Reading { v_noise_m_per_s: v_noise, derived_with: None }).unwrap();
        let without = fit_friction_law(&[&run], &Reading::default()).unwrap();
        println!(
            "law off by {:.4} (sigma {:.4}) with the sensor noise, {:.4} (sigma {:.4}) without",
            off(&with_noise),
            with_noise.sigma,
            off(&without),
            without.sigma
        );
        // σ within 30%: of ~6 000 stuck samples about 4 still pass (beyond
        // 3 sd, with friction's sign), each 0.1 off the law.
        assert!(off(&with_noise) < 0.01 && (with_noise.sigma / sigma - 1.0).abs() < 0.3, "{with_noise:?}");
        assert!(
            off(&without) > 0.02 || without.sigma > 2.0 * sigma,
            "the premise: stuck samples pass without it: {without:?}"
        );
    }

    /// The law's value at speed `v` (m/s).
    fn mu(l: &FrictionLaw, v: f64) -> f64 {
        l.a + l.b / (1.0 + l.c * v) + l.d * v * v
    }

    /// The whole of eq. 7 comes back: with d fitted too, c and b trade off
    /// within the noise, so the fitted curve is checked against the true one
    /// over the slipping speeds (here 0.02–0.4 m/s), and σ and d themselves.
    #[test]
    fn friction_law_fit_recovers_a_known_law() {
        let speeds = (1..=20).map(|i| 0.02 * f64::from(i));
        let truth = FrictionLaw { a: 0.25, b: 0.1, c: 20.0, d: 0.0, sigma: 0.04, anchors_m_per_s: [0.0; 10] };
        let law = fit_friction_law(&[&record(0.25, 0.1, 20.0, 0.04, 1)], &Reading::default()).unwrap();
        let worst = speeds.clone().map(|v| (mu(&law, v) - mu(&truth, v)).abs()).fold(0.0, f64::max);
        assert!(worst < 0.005, "{law:?}: the curve is {worst} off");
        assert!((law.sigma / 0.04 - 1.0).abs() < 0.03, "{law:?}");
        let truth = FrictionLaw { a: 0.19, b: 0.075, c: 13.5, d: 0.105, sigma: 0.019, anchors_m_per_s: [0.0; 10] };
        let with_d = fit_friction_law(&[&record_d(0.19, 0.075, 13.5, 0.105, 0.019, 3)], &Reading::default()).unwrap();
        let worst = speeds.map(|v| (mu(&with_d, v) - mu(&truth, v)).abs()).fold(0.0, f64::max);
        assert!(worst < 0.003 && (with_d.d - 0.105).abs() < 0.03, "{with_d:?}: the curve is {worst} off");
        assert!((with_d.sigma / 0.019 - 1.0).abs() < 0.03, "{with_d:?}");
        // At a fixed c the fit is the unconstrained least squares, so a law
        // with friction falling below zero at rest is still reported.
        let samples = SlipSamples::of(&[&record(0.4, -0.3, 80.0, 0.0, 2)], &Reading::default()).unwrap();
        let rising = samples.fit_at(80.0).unwrap();
        assert!((rising.b + 0.3).abs() < 1e-6 && (rising.a - 0.4).abs() < 1e-6, "{rising:?}");
        assert!(
            fit_friction_law(&[&record(0.4, -0.5, 80.0, 0.0, 2)], &Reading::default()).is_none_or(|l| l.a + l.b >= 0.0)
        );
        // A fold's law at the whole data's c is that statistic too: kept
        // where friction at rest comes out just below zero.
        let fold =
            fit_friction_law_at(&[&record(0.4, -0.41, 80.0, 0.0, 2)], &Reading::default(), 80.0).expect("a law at c");
        assert!(fold.a + fold.b < 0.0 && (fold.b + 0.41).abs() < 1e-6, "{fold:?}");
    }

    /// A block its load holds still, recorded as `x` alone: its derived
    /// velocity is the displacement sensor's noise through the filter,
    /// and read against a twentieth of its largest value most samples
    /// "slip", with the spring's force at rest read as friction. Read as
    /// a diagnosis reads a derived force (above the velocity's noise and
    /// clear of the filter's blur), it has no friction features at all.
    #[test]
    fn a_held_block_shows_no_friction_through_a_derived_force() {
        let rig = RigInfo { mass_kg: 1.1, natural_frequency_hz: 9.0, damping_ratio: 0.005 };
        let (f_hz, dt, sigma_x) = (7.0, 1.0 / 600.0, 2e-6);
        let mut rng = StdRng::seed_from_u64(5);
        // Only `t` and `x` are kept: the rest is derived from them.
        let samples: Vec<Sample> = (0..30_000)
            .map(|i| {
                let (u, v): (f64, f64) = (rng.random::<f64>().max(1e-300), rng.random());
                let x_m = sigma_x * (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos();
                Sample { t_s: f64::from(i) * dt, x_m, v_m_per_s: 0.0, normal_force_n: 16.0, friction_force_n: 0.0 }
            })
            .collect();
        let mut run = Run::from_samples(&samples, f_hz, 1.6e-3, 16.0);
        (run.v_m_per_s, run.normal_force, run.friction_force) = (None, None, None);
        let all = DerivedChannels { v: true, friction: true, nominal_load: true, base_from_record: false };
        derive(&mut run, all, &rig);
        let as_recorded = crate::diagnose::features::run_features(&run).friction;
        assert!(as_recorded.as_ref().is_some_and(|f| f.slip_samples > 3000), "{as_recorded:?}");
        let reading = Reading { v_noise_m_per_s: velocity_noise(&run, sigma_x), derived_with: Some(&rig) };
        let read = crate::diagnose::features::run_features_read(&run, reading.motion(&run)).friction;
        assert!(read.is_none(), "{read:?}");
    }
}
