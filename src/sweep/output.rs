//! A sweep's output set: `sweep.csv` (the columns of `docs/formats.md`),
//! `histograms.csv`, `accumulators.json` (what `merge` combines), the
//! figures and the `sweep.json` sidecar. The set is built in a temporary
//! sibling directory and swapped in whole ([`OutputSet`]): the output
//! directory holds one run's complete set or the previous one, never a mix.
//! Nothing non-finite is written: a statistic that is not finite is refused.

use std::path::Path;

use crate::engine::{Model, PeakRange, PointStats};
use crate::error::Error;
use crate::error::Result;
use crate::io::{OutputSet, owned, write_atomically};
use crate::sweep::plot;
use crate::sweep::shard::{AccumulatorFile, RunIdentity, Shard};
use crate::sweep::{Refinement, SweepResult};

/// The columns of `sweep.csv` (`docs/formats.md`).
pub const SWEEP_COLUMNS: [&str; 12] = [
    "excitation_frequency_hz",
    "normal_force_n",
    "realisations",
    "peaks",
    "peak_mean_m",
    "peak_var_m2",
    "peak_p05_m",
    "peak_p50_m",
    "peak_p95_m",
    "stick_fraction",
    "phase_mean_deg",
    "phase_var_deg2",
];

/// Writes `sweep.csv` atomically.
pub fn write_sweep_csv(path: &Path, rows: &[PointStats]) -> Result<()> {
    write_atomically(path, |w| {
        writeln!(w, "{}", SWEEP_COLUMNS.join(","))?;
        for r in rows {
            writeln!(
                w,
                "{},{},{},{},{:e},{:e},{:e},{:e},{:e},{},{},{}",
                r.excitation_frequency_hz,
                r.normal_force_n,
                r.realisations,
                r.peaks,
                r.peak_mean_m,
                r.peak_var_m2,
                r.peak_p05_m,
                r.peak_p50_m,
                r.peak_p95_m,
                r.stick_fraction,
                blank_if_nan(r.phase_mean_deg, |v| v.to_string()),
                blank_if_nan(r.phase_var_deg2, |v| format!("{v:e}"))
            )?;
        }
        Ok(())
    })
}

/// A cell: `value` as `show` writes it, or blank where it is NaN (a phase
/// of a block that never moved).
fn blank_if_nan(value: f64, show: impl Fn(f64) -> String) -> String {
    if value.is_nan() { String::new() } else { show(value) }
}

/// Writes `histograms.csv`: every non-empty bin of every point, in metres,
/// with its probability density (1/m). The first and last bins of a point
/// (below and above its range) have infinite outer edges.
pub fn write_histograms_csv(path: &Path, result: &SweepResult) -> Result<()> {
    write_atomically(path, |w| {
        writeln!(w, "excitation_frequency_hz,normal_force_n,bin_lo_m,bin_hi_m,count,density_per_m")?;
        for (c, a) in result.conditions.iter().zip(&result.accumulators) {
            let last = a.histogram.len() as u32 - 1;
            for (b, &count) in a.histogram.iter().enumerate() {
                if count == 0 {
                    continue;
                }
                let b = b as u32;
                let (lo, hi) = if b == 0 {
                    (f64::NEG_INFINITY, a.range.lo_m)
                } else if b == last {
                    (a.range.hi_m, f64::INFINITY)
                } else {
                    a.range.bin_edges(b)
                };
                let density =
                    if lo.is_finite() && hi.is_finite() { count as f64 / (a.peaks as f64 * (hi - lo)) } else { 0.0 };
                writeln!(
                    w,
                    "{},{},{:e},{:e},{count},{density:e}",
                    c.excitation_frequency_hz, c.normal_force_n, lo, hi
                )?;
            }
        }
        Ok(())
    })
}

/// Writes `accumulators.json`.
pub fn write_accumulators(path: &Path, file: &AccumulatorFile) -> Result<()> {
    write_atomically(path, |w| {
        serde_json::to_writer(&mut *w, file)?;
        writeln!(w)
    })
}

/// Writes everything a sweep (or a merge) produces into `out`: sweep.csv,
/// histograms.csv, accumulators.json, sweep.json and, with `plots_at_hz`
/// (Figure 8's frequency, Hz), the figures. `description` names the backend
/// and adapter; `timings` goes into sweep.json as it is, and so does
/// `refinement`, the frequencies the grid's refinement added (`null` when
/// the grid was not refined). The set replaces
/// the previous one in `out` whole (see [`OutputSet`]); when `out` is a set
/// the caller prepared, the files go straight into it.
#[allow(clippy::too_many_arguments)]
pub fn write_output_set(
    out: &Path,
    model: &Model,
    identity: &RunIdentity,
    shard: Shard,
    result: &SweepResult,
    description: &str,
    timings: serde_json::Value,
    refinement: Option<&Refinement>,
    plots_at_hz: Option<f64>,
) -> Result<()> {
    let set = OutputSet::prepare(out, "output directory", owned::SWEEP, &[])?;
    write_output_files(set.dir(), model, identity, shard, result, description, timings, refinement, plots_at_hz)?;
    set.commit()
}

/// Refuses a result with a statistic that is not finite, or with a point
/// whose peaks lie outside its range (its quantiles would be the range's
/// edge): nothing of either is written or plotted. The one exception is the
/// phase of a point whose block never moved, which is undefined (NaN,
/// written blank).
pub fn check_finite(result: &SweepResult) -> Result<()> {
    for (c, a) in result.conditions.iter().zip(&result.accumulators) {
        if a.outside_range() > 0 {
            return Err(Error::Diverged {
                point: c.describe(),
                message: format!(
                    "{} of its {} peaks lie outside its histogram range; nothing was written",
                    a.outside_range(),
                    a.peaks
                ),
            });
        }
    }
    for row in result.rows() {
        let values =
            [row.peak_mean_m, row.peak_var_m2, row.peak_p05_m, row.peak_p50_m, row.peak_p95_m, row.stick_fraction];
        let never_moved = row.stick_fraction == 1.0;
        let phase_ok = [row.phase_mean_deg, row.phase_var_deg2].iter().all(|v| v.is_finite() || never_moved);
        if values.iter().any(|v| !v.is_finite()) || !phase_ok || row.peaks == 0 {
            return Err(Error::Diverged {
                point: format!("{} Hz, {} N", row.excitation_frequency_hz, row.normal_force_n),
                message: format!("a statistic is not finite ({} peaks); nothing was written", row.peaks),
            });
        }
    }
    Ok(())
}

/// The points whose peaks left the range their model gives, each with the
/// range that holds them (`sweep.json`'s `widened_ranges`).
pub fn widened_ranges(model: &Model, result: &SweepResult) -> Vec<serde_json::Value> {
    result
        .conditions
        .iter()
        .zip(&result.accumulators)
        .filter(|(c, a)| a.range != PeakRange::for_point(model, **c))
        .map(|(c, a)| {
            serde_json::json!({
                "excitation_frequency_hz": c.excitation_frequency_hz,
                "normal_force_n": c.normal_force_n,
                "lo_m": a.range.lo_m,
                "hi_m": a.range.hi_m,
            })
        })
        .collect()
}

/// Writes the files of a sweep's output set into the directory `dir`.
#[allow(clippy::too_many_arguments)]
pub fn write_output_files(
    out: &Path,
    model: &Model,
    identity: &RunIdentity,
    shard: Shard,
    result: &SweepResult,
    description: &str,
    timings: serde_json::Value,
    refinement: Option<&Refinement>,
    plots_at_hz: Option<f64>,
) -> Result<()> {
    check_finite(result)?;
    write_sweep_csv(&out.join("sweep.csv"), &result.rows())?;
    write_histograms_csv(&out.join("histograms.csv"), result)?;
    write_accumulators(&out.join("accumulators.json"), &result.to_file(identity, shard))?;
    let mut files = vec!["sweep.csv".to_string(), "histograms.csv".into(), "accumulators.json".into()];
    if let Some(f) = plots_at_hz {
        for path in plot::write_sweep_plots(out, result, f)? {
            files.push(path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default());
        }
    }
    let sidecar = serde_json::json!({
        "format": "stickslip-sweep/1",
        "stickslip_version": env!("CARGO_PKG_VERSION"),
        "model": model,
        "model_toml": identity.model_toml,
        "frequencies_hz": identity.frequencies_hz,
        "normal_forces_n": identity.normal_forces_n,
        "realisations": identity.realisations,
        "warmup_cycles": identity.warmup_cycles,
        "measured_cycles": identity.measured_cycles,
        "seed": identity.seed,
        "backend": identity.backend,
        "adapter": description,
        "shard": shard,
        "refinement": refinement.map(|r| serde_json::json!({ "added_frequencies_hz": r.added_hz })),
        "widened_ranges": widened_ranges(model, result),
        "files": files,
        "timings": timings,
    });
    write_atomically(&out.join("sweep.json"), |w| {
        serde_json::to_writer_pretty(&mut *w, &sidecar)?;
        writeln!(w)
    })
}
