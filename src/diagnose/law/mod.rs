//! The friction law as the force channels give it: the paper's
//! μ(v) = a + b / (1 + c |v|) + d v² fitted by least squares to the slipping
//! samples of records, with the residual spread σ_μ (–), and the moments a
//! simulated record's law is read from so that simulated and measured
//! records are read alike.

use rayon::prelude::*;

mod moments;

pub(crate) use moments::{LawMoments, Spread};

use crate::diagnose::features::MotionReading;
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
    pub(crate) fn plausible(&self) -> bool {
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

/// The indices of `run`'s samples that count as slipping as `motion` reads
/// them ([`MotionReading::slipping`]): |v| above 5% of the run's largest
/// and above [`crate::diagnose::features::SLIP_SPEED_NOISE_SDS`] standard
/// deviations of the velocity's white noise (so at every sample within the
/// blur's reach), the friction opposing the motion, and the normal force
/// `n` (N, the run's [`crate::diagnose::features::load_of`]: the nominal
/// load without a normal-force channel) at least a tenth of its median
/// ([`crate::diagnose::features::normal_force_floor`]). Empty without
/// velocity and friction channels. The one selection of slipping samples
/// that the law's fit and the position estimate of a load
/// ([`crate::diagnose::candidates`]) read μ = |F|/N at.
pub(crate) fn slipping_indices(run: &Run, n: &[f64], motion: MotionReading) -> Vec<usize> {
    let (Some(v), Some(f)) = (&run.v_m_per_s, &run.friction_force) else {
        return Vec::new();
    };
    let moving = motion.slipping(v);
    let floor = crate::diagnose::features::normal_force_floor(n);
    (0..v.len().min(f.len()).min(n.len())).filter(|&i| moving[i] && f[i] * v[i] < 0.0 && n[i] >= floor).collect()
}

/// The slipping samples of one run the law is fitted to
/// ([`slipping_indices`]): speed |v| (m/s) and μ = |F|/N. Every such
/// sample, a derived force's blurred ones too: the slowest slips, at a
/// stick's ends, are what pin μ(0) = a + b, and read clear of the blur a
/// few records leave the law's curve free to wander, while the indirect
/// inference reads the replicates' blur alike. The velocity's noise is the
/// data's estimate, which the simulated records carry too, so both sides
/// pick alike.
fn slipping_samples(run: &Run, reading: &Reading<'_>) -> (Vec<f64>, Vec<f64>) {
    let (Some(v), Some(f)) = (&run.v_m_per_s, &run.friction_force) else {
        return (Vec::new(), Vec::new());
    };
    let n = crate::diagnose::features::load_of(run);
    let motion = MotionReading { v_noise_m_per_s: reading.v_noise_m_per_s, blur_samples: 0 };
    slipping_indices(run, &n, motion).into_iter().map(|i| (v[i].abs(), f[i].abs() / n[i])).unzip()
}

impl SlipSamples {
    /// The slipping samples of `runs` ([`slipping_samples`]), read as
    /// `reading` says; `None` with fewer than 50.
    fn of(runs: &[&Run], reading: &Reading<'_>) -> Option<SlipSamples> {
        let (mut speed, mut mu, mut record) = (Vec::new(), Vec::new(), Vec::new());
        let sensor_variance = runs.iter().map(|r| reading.sensor_variance(r)).collect();
        for (k, r) in runs.iter().enumerate() {
            let (s, m) = slipping_samples(r, reading);
            record.extend(std::iter::repeat_n(k, s.len()));
            speed.extend(s);
            mu.extend(m);
        }
        if mu.len() < MIN_SLIP_SAMPLES {
            return None;
        }
        let anchors_m_per_s = speed_deciles(&speed);
        Some(SlipSamples { speed, mu, record, sensor_variance, anchors_m_per_s })
    }

    /// The within-record least-squares law at a given `c` (s/m; see
    /// [`LawMoments::law`]), with these samples' anchors. With one record
    /// this is the ordinary fit with an intercept.
    fn fit_at(&self, c: f64) -> Option<FrictionLaw> {
        let mut records = Vec::new();
        let mut start = 0;
        // Samples are grouped by record (in the order they were collected).
        while start < self.record.len() {
            let end = start + self.record[start..].iter().take_while(|&&k| k == self.record[start]).count();
            let sensor_variance = self.sensor_variance[self.record[start]];
            records.push(
                LawMoments::of_record(&self.speed[start..end], &self.mu[start..end], c)
                    .with_sensor_variance(sensor_variance),
            );
            start = end;
        }
        LawMoments::law_of_records(&records, c, self.anchors_m_per_s)
    }

    /// The law with the smallest residual: over [`law_c_grid`], then by
    /// golden-section search in log c between the best point's neighbours.
    /// The rate is chosen among laws a rig could have
    /// ([`FrictionLaw::plausible`]). Where there is none at any rate (a
    /// normal force that follows the block's position, read into a friction
    /// derived at the nominal load, gives a curve that falls below zero
    /// within twice the fastest slip), the records' law is still theirs: the
    /// rate is chosen among all the laws. Refused, the force channels would
    /// be lost whole, and the friction level solved from the response alone,
    /// at several times a trial's cost and with the law left at its prior.
    fn fit(&self) -> Option<FrictionLaw> {
        let grid: Vec<f64> = law_c_grid().collect();
        let laws: Vec<Option<FrictionLaw>> = grid.par_iter().map(|&c| self.fit_at(c)).collect();
        let best_of = |keep: fn(&FrictionLaw) -> bool| {
            laws.iter()
                .enumerate()
                .filter_map(|(i, l)| l.map(|l| (i, l)))
                .filter(|(_, l)| keep(l))
                .min_by(|x, y| x.1.sigma.total_cmp(&y.1.sigma))
        };
        let any: fn(&FrictionLaw) -> bool = |l| l.sigma.is_finite();
        let (keep, (best, law)): (fn(&FrictionLaw) -> bool, _) = match best_of(FrictionLaw::plausible) {
            Some(found) => (FrictionLaw::plausible, found),
            None => (any, best_of(any)?),
        };
        if best == 0 {
            return Some(law);
        }
        let lo = if best == 1 { grid[1] / 3.0 } else { grid[best - 1] };
        let hi = grid.get(best + 1).copied().unwrap_or(grid[best] * 3.0);
        let (mut lo, mut hi) = (lo.ln(), hi.ln());
        let golden = 0.5 * (5f64.sqrt() - 1.0);
        let sigma_at = |x: f64| self.fit_at(x.exp()).filter(keep).map_or(f64::INFINITY, |l| l.sigma);
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
        let refined = self.fit_at((0.5 * (lo + hi)).exp()).filter(keep);
        Some(refined.filter(|r| r.sigma <= law.sigma).unwrap_or(law))
    }
}

/// The report's note where the records' law (`measured`) is no law a rig
/// could have at any rate ([`SlipSamples::fit`] keeps it regardless).
pub(crate) fn implausible_law_note(measured: Option<&FrictionLaw>) -> Option<String> {
    let law = measured.filter(|l| !l.plausible())?;
    Some(format!(
        "no friction law a rig could have fits the friction read from the records at any Stribeck rate: the \
         closest, μ = {:.3} + {:.3}/(1 + {:.1}|v|) + {:.3} v², falls below zero at rest or within twice the \
         fastest slip, or has terms beyond any published steel-on-steel law; it is used as the records' \
         curve. A normal force that changes over each cycle (following the block's position through a leaf \
         spring, say) read at the nominal load looks so",
        law.a, law.b, law.c, law.d
    ))
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

/// How much more the friction's residual variance is in the data than in
/// a model's replicates, –²: condition by condition (each unit's records
/// about their own side's law, [`Spread::about`]), the differences averaged
/// with each weighted by its precision, 1 / (v² (1/n_measured + 1/n_simulated))
/// (a variance v read from n samples is known to about v √(2/n)). Pooled
/// over the conditions instead, a model that slides where the data's block
/// is held (a law whose friction at rest is too low) reads thousands of
/// replicate samples at a load where the data give a hundred, and the
/// replicates' pool is weighted by conditions the data hardly have: σ_μ is
/// then stepped by a difference of mixtures, not of noise. A condition's
/// sensors weigh in through v: where they put most of μ's spread (a force
/// derived from the displacement at a light load) its difference is known
/// least. `None` where no condition has a spread on both sides.
pub(crate) fn variance_gap(measured: &[Option<Spread>], simulated: &[Option<Spread>]) -> Option<f64> {
    let (mut sum, mut weights) = (0.0, 0.0);
    for (m, s) in measured.iter().zip(simulated) {
        let (Some(m), Some(s)) = (m, s) else { continue };
        let v = 0.5 * (m.variance + s.variance);
        let weight = 1.0 / (v * v * (1.0 / m.samples as f64 + 1.0 / s.samples as f64));
        if weight.is_finite() && weight > 0.0 {
            sum += weight * (m.variance - s.variance);
            weights += weight;
        }
    }
    (weights > 0.0).then(|| sum / weights)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::derived::{DerivedChannels, derive, velocity_noise};
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

    /// The σ_μ step compares like with like. The data's block slides at a
    /// light load (σ 0.05 about the law) and is nearly held at a heavy one
    /// (σ 0.03, a few hundred samples); a model's replicates have the same
    /// spread at each load but slide a great deal at the heavy one. Pooled,
    /// the replicates read far less spread than the data and σ_μ would be
    /// stepped up; condition by condition the gap is nil. A real gap (the
    /// data 0.01² more at every load) comes back whatever the mixture.
    #[test]
    fn the_variance_gap_compares_each_condition_with_its_own_replicates() {
        let law = |runs: &[&Run]| fit_friction_law(runs, &Reading::default()).unwrap();
        let spread = |runs: &[&Run], l: &FrictionLaw| {
            let moments: Vec<LawMoments> =
                runs.iter().map(|r| LawMoments::of_run(r, &Reading::default(), l.c)).collect();
            Spread::about(&moments, l)
        };
        // Light load: full swings; heavy load: a crawl, 1 sample in 40 kept.
        let crawl = |sigma: f64, seed: u64| {
            let mut run = record_at(0.3, 0.1, 20.0, 0.0, sigma, seed, 0.4);
            let v = run.v_m_per_s.as_mut().unwrap();
            v.iter_mut().enumerate().filter(|(i, _)| i % 40 != 0).for_each(|(_, x)| *x = 0.0);
            run
        };
        for extra in [0.0, 0.01f64] {
            let grow = |s: f64| (s * s + extra * extra).sqrt();
            let (light, heavy) = (record_at(0.3, 0.1, 20.0, 0.0, grow(0.05), 1, 0.4), crawl(grow(0.03), 2));
            let data = law(&[&light, &heavy]);
            let measured = [spread(&[&light], &data), spread(&[&heavy], &data)];
            let (light_sim, heavy_sim) =
                (record_at(0.3, 0.1, 20.0, 0.0, 0.05, 3, 0.4), record_at(0.3, 0.1, 20.0, 0.0, 0.03, 4, 0.4));
            let replicates = law(&[&light_sim, &heavy_sim]);
            let simulated = [spread(&[&light_sim], &replicates), spread(&[&heavy_sim], &replicates)];
            let gap = variance_gap(&measured, &simulated).unwrap();
            let pooled = data.sigma.powi(2) - replicates.sigma.powi(2);
            let truth = extra * extra;
            assert!((gap - truth).abs() < 0.1 * 0.03f64.powi(2), "extra {extra}: gap {gap:.3e}, pooled {pooled:.3e}");
            // The premise: pooled, the mixture alone reads as a gap.
            assert!(pooled - truth > 0.5 * 0.03f64.powi(2), "extra {extra}: pooled {pooled:.3e}");
        }
        // No condition on both sides: no gap.
        let one = Some(Spread { variance: 1e-3, samples: 100 });
        assert_eq!(variance_gap(&[one, None], &[None, one]), None);
    }

    /// A record sliding back and forth at 1 Hz with friction from a known
    /// law of eq. 7 (d = 0) plus Gaussian noise of sd `sigma`.
    fn record(a: f64, b: f64, c: f64, sigma: f64, seed: u64) -> Run {
        record_d(a, b, c, 0.0, sigma, seed)
    }

    pub(super) fn record_d(a: f64, b: f64, c: f64, d: f64, sigma: f64, seed: u64) -> Run {
        record_at(a, b, c, d, sigma, seed, 0.4)
    }

    /// [`record_d`] with a speed amplitude `v0` (m/s).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn record_at(a: f64, b: f64, c: f64, d: f64, sigma: f64, seed: u64, v0: f64) -> Run {
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

    /// Records whose friction falls with speed so steeply that no law a rig
    /// could have fits them at any rate (μ below zero within twice the
    /// fastest slip: a normal force following the position, read at the
    /// nominal load, looks so) still give their law, the curve they follow:
    /// without one a diagnosis would lose its force channels whole.
    #[test]
    fn records_no_rig_s_law_fits_still_give_their_curve() {
        let truth = FrictionLaw { a: 0.4, b: -0.08, c: 10.0, d: -0.8, sigma: 0.02, anchors_m_per_s: [0.0; 10] };
        let run = record_d(truth.a, truth.b, truth.c, truth.d, truth.sigma, 4);
        let samples = SlipSamples::of(&[&run], &Reading::default()).unwrap();
        assert!(
            law_c_grid().filter_map(|c| samples.fit_at(c)).all(|l| !l.plausible()),
            "the premise: no rate gives a law a rig could have"
        );
        let law = fit_friction_law(&[&run], &Reading::default()).expect("the records' own law");
        let worst =
            (1..=20).map(|i| 0.02 * f64::from(i)).map(|v| (mu(&law, v) - mu(&truth, v)).abs()).fold(0.0, f64::max);
        assert!(worst < 0.005 && (law.sigma / truth.sigma - 1.0).abs() < 0.05, "{law:?}: the curve is {worst} off");
        // The report says so; of a rig's law it says nothing.
        assert!(implausible_law_note(Some(&law)).is_some_and(|n| n.contains("no friction law a rig could have")));
        let rig = fit_friction_law(&[&record(0.25, 0.1, 20.0, 0.04, 1)], &Reading::default());
        assert!(rig.is_some() && implausible_law_note(rig.as_ref()).is_none());
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
