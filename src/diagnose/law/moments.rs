//! What the within-record fit of eq. 7 reads from slipping samples, as sums
//! that add over records ([`LawMoments`]), and the law and its residual σ_μ
//! (–) read from them: the curve from every slipping sample alike, σ_μ
//! weighted by the noise each record's sensors put into μ.

use super::{FrictionLaw, MAX_D_S2_PER_M2, Reading, slipping_samples};
use crate::diagnose::features::solve_normal;
use crate::measure::Run;

/// The cross products of a record's columns s², g(s) and μ, each centred on
/// the record's mean (d, q and y below), summed over some of its samples.
#[derive(Clone, Copy, Debug, Default)]
struct Products {
    /// Σd², m⁴/s⁴.
    dd: f64,
    /// Σd q, m²/s².
    dg: f64,
    /// Σq², –.
    gg: f64,
    /// Σd y, m²/s².
    dy: f64,
    /// Σq y, –.
    gy: f64,
    /// Σy², –.
    yy: f64,
}

impl Products {
    /// Adds one sample's centred s² (`d`, m²/s²), g (`q`) and μ (`y`).
    fn add_sample(&mut self, d: f64, q: f64, y: f64) {
        self.dd += d * d;
        self.dg += d * q;
        self.gg += q * q;
        self.dy += d * y;
        self.gy += q * y;
        self.yy += y * y;
    }

    /// Adds another record's (or records') products.
    fn add(&mut self, other: &Products) {
        self.dd += other.dd;
        self.dg += other.dg;
        self.gg += other.gg;
        self.dy += other.dy;
        self.gy += other.gy;
        self.yy += other.yy;
    }

    /// The sum over the samples of the squared residual about the law with
    /// Stribeck term `b` and v² term `d` (s²/m²; the rate the products were
    /// taken at), y − b q − d (the centred s²), –: each record about its own
    /// mean.
    fn residual_sum_of_squares(&self, b: f64, d: f64) -> f64 {
        let fitted = b * b * self.gg + 2.0 * b * d * self.dg + d * d * self.dd;
        (self.yy - 2.0 * b * self.gy - 2.0 * d * self.dy + fitted).max(0.0)
    }
}

/// What the within-record fit of eq. 7 at one Stribeck rate `c` reads from
/// slipping samples ([`super::SlipSamples::fit_at`]), as sums that add over
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
    /// The columns' cross products, each centred on its record's mean.
    products: Products,
}

impl LawMoments {
    /// The moments of one record's slipping samples (`speed`, m/s; `mu`, –)
    /// at Stribeck rate `c` (s/m).
    pub(super) fn of_record(speed: &[f64], mu: &[f64], c: f64) -> LawMoments {
        let n = speed.len();
        if n == 0 {
            return LawMoments::default();
        }
        let g = |s: f64| 1.0 / (1.0 + c * s);
        let (sum_mu, sum_s2, sum_g) =
            speed.iter().zip(mu).fold((0.0, 0.0, 0.0), |(m, d, q), (&s, &y)| (m + y, d + s * s, q + g(s)));
        let (mean_mu, mean_s2, mean_g) = (sum_mu / n as f64, sum_s2 / n as f64, sum_g / n as f64);
        let mut m = LawMoments { count: n, records: 1, sum_mu, sum_s2, sum_g, ..LawMoments::default() };
        for (&s, &y) in speed.iter().zip(mu) {
            m.products.add_sample(s * s - mean_s2, g(s) - mean_g, y - mean_mu);
        }
        m
    }

    /// The moments of one run's slipping samples ([`slipping_samples`]) at
    /// Stribeck rate `c` (s/m), read as `reading` says.
    pub(crate) fn of_run(run: &Run, reading: &Reading<'_>, c: f64) -> LawMoments {
        let (speed, mu) = slipping_samples(run, reading);
        LawMoments::of_record(&speed, &mu, c).with_sensor_variance(reading.sensor_variance(run))
    }

    /// These moments of one record whose sensors put `variance` (–²) into
    /// each sample's μ.
    pub(super) fn with_sensor_variance(mut self, variance: f64) -> LawMoments {
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
        for (a, b) in [
            (&mut self.sensor_variance_sum, other.sensor_variance_sum),
            (&mut self.sum_mu, other.sum_mu),
            (&mut self.sum_s2, other.sum_s2),
            (&mut self.sum_g, other.sum_g),
        ] {
            *a += b;
        }
        self.products.add(&other.products);
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
        let Products { dd, dg, gg, dy, gy, yy } = self.products;
        // (b, d, residual sum of squares, fitted columns) with d free or
        // held at `fixed_d` (μ less d s² fitted then).
        let solve = |fixed_d: Option<f64>| -> Option<(f64, f64, f64, usize)> {
            let fd = fixed_d.unwrap_or(0.0);
            let (gy_held, yy_held) = (gy - fd * dg, yy - 2.0 * fd * dy + fd * fd * dd);
            match (fixed_d, stribeck) {
                (None, true) => {
                    let (coef, rss) = solve_normal(&[[dd, 0.0], [dg, gg]], &[dy, gy], yy)?;
                    Some((coef[1], coef[0], rss, 2))
                }
                (None, false) => {
                    let (coef, rss) = solve_normal(&[[dd]], &[dy], yy)?;
                    Some((0.0, coef[0], rss, 1))
                }
                (Some(_), true) => {
                    let (coef, rss) = solve_normal(&[[gg]], &[gy_held], yy_held)?;
                    Some((coef[0], fd, rss, 1))
                }
                (Some(_), false) => Some((0.0, fd, yy_held.max(0.0), 0)),
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
    pub(crate) fn law_of_records(records: &[LawMoments], c: f64, anchors_m_per_s: [f64; 10]) -> Option<FrictionLaw> {
        let mut pooled = LawMoments::default();
        records.iter().for_each(|r| pooled.add(r));
        let law = pooled.law(c, anchors_m_per_s)?;
        if pooled.sensor_variance_sum <= 0.0 || pooled.count == 0 {
            return Some(law);
        }
        let total = law.sigma.powi(2);
        let friction = (total - pooled.sensor_variance_sum / pooled.count as f64).max(FRICTION_SHARE_FLOOR * total);
        let (mut sum_rss, mut sum_dof) = (0.0, 0.0);
        for r in records.iter().filter(|r| r.count > 1) {
            let weight = 1.0 / (friction + r.sensor_variance_sum / r.count as f64);
            sum_rss += weight * r.products.residual_sum_of_squares(law.b, law.d);
            sum_dof += weight * (r.count - 1) as f64;
        }
        let sigma = (sum_rss / sum_dof).sqrt();
        Some(if sigma.is_finite() { FrictionLaw { sigma, ..law } } else { law })
    }
}

/// How far one condition's records spread about a law: the residual
/// variance of μ within records (each about its own mean level) around the
/// law's curve, and the slipping samples it was read from. The σ_μ step of
/// the indirect inference compares it condition by condition
/// ([`super::variance_gap`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Spread {
    /// –²
    pub(crate) variance: f64,
    pub(crate) samples: usize,
}

impl Spread {
    /// The spread of the records whose moments are `records` about `law`'s
    /// curve (its `b` and `d`; the moments taken at its `c`); `None` with
    /// fewer than [`super::MIN_SLIP_SAMPLES`] slipping samples.
    pub(crate) fn about(records: &[LawMoments], law: &FrictionLaw) -> Option<Spread> {
        let (mut rss, mut dof, mut samples) = (0.0, 0usize, 0usize);
        for r in records.iter().filter(|r| r.count > 1) {
            rss += r.products.residual_sum_of_squares(law.b, law.d);
            dof += r.count - 1;
            samples += r.count;
        }
        (samples >= super::MIN_SLIP_SAMPLES).then(|| Spread { variance: rss / dof as f64, samples })
    }
}

/// The least share of the records' residual variance that is taken to be
/// the friction's own when records are weighted
/// ([`LawMoments::law_of_records`]): where the sensors' estimated share
/// comes to all of it, the lightest-loaded records still weigh something.
const FRICTION_SHARE_FLOOR: f64 = 0.05;

#[cfg(test)]
mod tests {
    use super::super::tests::{record_at, record_d};
    use super::*;
    use crate::diagnose::features::least_squares;

    /// Records are weighted by the noise their sensors put into μ, not by
    /// their own residual; the curve is read from every sample alike.
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

    /// The law from moments summed record by record (as the diagnosis sums
    /// its replicates' in parallel) is the ordinary least-squares fit of
    /// μ − its record's mean on the centred columns (s², g(s)), solved here
    /// directly on the pooled rows, with and without the Stribeck term.
    #[test]
    fn moments_added_by_record_give_the_pooled_least_squares_fit() {
        let runs = [record_d(0.22, 0.1, 20.0, 0.3, 0.03, 7), record_at(0.30, 0.1, 20.0, 0.3, 0.02, 8, 0.2)];
        for c in [0.0, 20.0] {
            let mut moments = LawMoments::default();
            runs.iter().for_each(|r| moments.add(&LawMoments::of_run(r, &Reading::default(), c)));
            let law = moments.law(c, [0.0; 10]).unwrap();
            let records: Vec<(Vec<f64>, Vec<f64>)> =
                runs.iter().map(|r| slipping_samples(r, &Reading::default())).collect();
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
}
