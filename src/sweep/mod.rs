//! Frequency × normal-force sweeps: grids, their adaptive refinement
//! ([`refine`]), running them on the engine, shards and their merge
//! ([`shard`]), the output set (`sweep.csv`, `histograms.csv`,
//! `accumulators.json`, `sweep.json`: [`output`]) and the figures ([`plot`]).

pub mod output;
pub mod plot;
pub mod refine;
pub mod shard;

use crate::engine::{Condition, Engine, Job, Model, Point, PointAccumulator, PointStats, Record, RunPlan};
use crate::error::{Error, Result};
use crate::text::excerpt;

pub use output::{SWEEP_COLUMNS, write_accumulators, write_histograms_csv, write_output_set, write_sweep_csv};
pub use refine::{RefineSettings, Refinement, not_refinable, refine_frequencies};
pub use shard::{ACCUMULATOR_FORMAT, AccumulatorFile, RunIdentity, Shard, merge_shards, read_accumulators};

/// A count written as a whole number, in integer or float notation
/// (`1e9`), capped at `u64::MAX`; `None` for anything else.
fn whole_count(text: &str) -> Option<u64> {
    let text = text.trim();
    text.parse::<u64>().ok().or_else(|| {
        let c: f64 = text.parse().ok()?;
        (c.fract() == 0.0 && c >= 0.0).then_some(c.min(u64::MAX as f64) as u64)
    })
}

/// Parses a grid flag: a comma list (`6,7,8`) or `START:STOP:COUNT`, of
/// at most [`Job::MAX_POINTS`] values.
pub fn parse_list(flag: &str, text: &str) -> Result<Vec<f64>> {
    let bad = |message: String| Error::setting(flag, format!("`{}`: {message}", excerpt(text, 60)));
    // Checked before the values are made: a range is a few characters
    // whatever its count.
    let too_many = |count: u64| -> Result<()> {
        if count > Job::MAX_POINTS as u64 {
            return Err(bad(format!("gives {count} values; a grid may have at most {} points", Job::MAX_POINTS)));
        }
        Ok(())
    };
    let number = |s: &str| -> Result<f64> {
        let shown = excerpt(s.trim(), 30);
        let v: f64 = s.trim().parse().map_err(|_| bad(format!("`{shown}` is not a number")))?;
        if v.is_finite() { Ok(v) } else { Err(bad(format!("`{shown}` is not finite"))) }
    };
    let values = if text.contains(':') {
        let parts: Vec<&str> = text.split(':').collect();
        if parts.len() != 3 {
            return Err(bad("expected START:STOP:COUNT".into()));
        }
        let (start, stop) = (number(parts[0])?, number(parts[1])?);
        let count = whole_count(parts[2])
            .ok_or_else(|| bad(format!("COUNT `{}` is not a whole number", excerpt(parts[2].trim(), 30))))?;
        too_many(count)?;
        let count = count as usize;
        match count {
            0 => return Err(bad("COUNT must be at least 1".into())),
            1 if start != stop => return Err(bad("COUNT 1 needs START = STOP".into())),
            1 => vec![start],
            _ => (0..count).map(|i| start + (stop - start) * i as f64 / (count - 1) as f64).collect(),
        }
    } else {
        too_many(text.split(',').count() as u64)?;
        text.split(',').map(number).collect::<Result<Vec<f64>>>()?
    };
    if values.is_empty() {
        return Err(bad("no values".into()));
    }
    Ok(values)
}

/// A frequency × normal-force grid; points run frequency-major.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    /// Excitation frequencies, Hz.
    pub frequencies_hz: Vec<f64>,
    /// Nominal normal forces, N.
    pub normal_forces_n: Vec<f64>,
}

impl Grid {
    /// All grid points, frequency-major.
    pub fn conditions(&self) -> Vec<Condition> {
        self.frequencies_hz
            .iter()
            .flat_map(|&f| {
                self.normal_forces_n.iter().map(move |&n| Condition { excitation_frequency_hz: f, normal_force_n: n })
            })
            .collect()
    }
}

/// The grid a sweep runs: `grid` itself, or, with `refine`, its frequencies
/// refined where the response changes fast ([`refine_frequencies`]). The
/// refinement is returned when it was applied (`None` without `refine`, and
/// for a grid it cannot refine: see [`not_refinable`]). Every condition of
/// `grid` must already be valid for `model`; a refined grid of more than
/// [`Job::MAX_POINTS`] points is refused.
pub fn refined_grid(
    model: &Model,
    grid: Grid,
    warmup_cycles: u32,
    refine: Option<RefineSettings>,
) -> Result<(Grid, Option<Refinement>)> {
    match refine {
        Some(settings) if not_refinable(&grid.frequencies_hz).is_none() => {
            let r = refine_frequencies(model, &grid.frequencies_hz, &grid.normal_forces_n, warmup_cycles, settings)?;
            let points = r.frequencies_hz.len() * grid.normal_forces_n.len();
            if points > Job::MAX_POINTS {
                return Err(Error::setting(
                    "--refine-max",
                    format!(
                        "the refined grid has {points} points, over the limit of {} per run; lower it or split the grid",
                        Job::MAX_POINTS
                    ),
                ));
            }
            Ok((Grid { frequencies_hz: r.frequencies_hz.clone(), normal_forces_n: grid.normal_forces_n }, Some(r)))
        }
        _ => Ok((grid, None)),
    }
}

/// How a sweep runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SweepSettings {
    /// Realisations per grid point.
    pub realisations: u32,
    pub plan: RunPlan,
    /// The noise seed.
    pub seed: u64,
}

impl SweepSettings {
    /// Checks the settings that do not depend on the grid.
    pub fn validate(&self) -> Result<()> {
        if self.realisations == 0 {
            return Err(Error::setting("--realisations", "must be at least 1"));
        }
        if self.plan.measured_cycles == 0 {
            return Err(Error::setting("--cycles", "must be at least 1 measured cycle"));
        }
        if u64::from(self.realisations) * u64::from(self.plan.measured_cycles) < 2 {
            return Err(Error::setting(
                "--realisations",
                "1 realisation of 1 measured cycle gives one peak per point, and a variance needs two (raise \
                 --realisations or --cycles)",
            ));
        }
        Ok(())
    }
}

/// Every condition's point, started from its frictionless steady state.
pub fn steady_points(model: &Model, conditions: &[Condition]) -> Vec<Point> {
    conditions.iter().map(|&c| Point::steady(model, c)).collect()
}

/// The job a sweep runs on `points` (sums and histograms, realisations from 0).
pub fn sweep_job<'a>(model: &'a Model, points: &'a [Point], settings: &SweepSettings) -> Job<'a> {
    Job {
        model,
        points,
        realisations: settings.realisations,
        first_realisation: 0,
        seed: settings.seed,
        plan: settings.plan,
        record: Record::Sums,
    }
}

/// Runs every grid point on `engine` and reduces it. `progress(done, total)`
/// reports work. Every point starts from its frictionless steady state.
pub fn run_sweep(
    model: &Model,
    conditions: &[Condition],
    settings: &SweepSettings,
    engine: &Engine,
    progress: &mut dyn FnMut(u64, u64),
) -> Result<SweepResult> {
    settings.validate()?;
    let points = steady_points(model, conditions);
    let accumulators = engine.sums(&sweep_job(model, &points, settings), progress)?;
    Ok(SweepResult { conditions: conditions.to_vec(), accumulators })
}

/// A finished sweep: per point, its condition and exact sums.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepResult {
    pub conditions: Vec<Condition>,
    pub accumulators: Vec<PointAccumulator>,
}

impl SweepResult {
    /// The `sweep.csv` rows.
    pub fn rows(&self) -> Vec<PointStats> {
        self.conditions.iter().zip(&self.accumulators).map(|(&c, a)| a.stats(c)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_and_ranges_parse() {
        assert_eq!(parse_list("--frequencies", "6,7,8").unwrap(), vec![6.0, 7.0, 8.0]);
        assert_eq!(parse_list("--frequencies", "5:15:3").unwrap(), vec![5.0, 10.0, 15.0]);
        assert_eq!(parse_list("--frequencies", "5:15:3.0").unwrap(), vec![5.0, 10.0, 15.0]);
        // A count beyond the grid limit is refused before its values are
        // made, however it is written.
        for huge in ["5:15:1000000000000", "5:15:1e12"] {
            let e = parse_list("--frequencies", huge).unwrap_err().to_string();
            assert!(e.contains("a grid may have at most"), "{e}");
        }
        assert!(parse_list("--frequencies", "5:15:2.5").unwrap_err().to_string().contains("not a whole number"));
        assert!(parse_list("--frequencies", "5:15").unwrap_err().to_string().contains("--frequencies"));
        assert!(parse_list("--normal-forces", "4,x").unwrap_err().to_string().contains("`x`"));
        let escaped = parse_list("--frequencies", "7\u{1b}[2J").unwrap_err().to_string();
        assert!(!escaped.contains('\u{1b}') && escaped.contains("\\u{1b}[2J"), "{escaped}");
    }
}
