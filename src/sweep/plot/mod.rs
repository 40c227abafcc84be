//! Pictures of a sweep: Figure 9(a) mean peak with its 5–95% band, Figure
//! 9(b) peak variance, a phase panel (fig9c), and Figure 8-style peak
//! densities with the Gaussian of the same mean and variance. Each is written
//! as PNG and SVG, atomically. Measured statistics (a measurement set's
//! summary rows, or the peaks of its records) can be drawn over them
//! ([`MeasuredPoint`]), at a size meant for a page
//! ([`crate::figure::SizePreset`]).
//!
//! - `measured`: a measurement set's statistics per condition, and which
//!   simulated curve each is set against;
//! - `panel`: what the panels share: the frequency axis, the value axes, the
//!   simulated curves and the measured marks;
//! - one file a figure: `amplitude` (Figure 9(a)), `variance` (9(b)),
//!   `phase` (9(c)) and `density` (Figure 8).

mod amplitude;
mod density;
mod measured;
mod panel;
mod phase;
mod variance;

pub use measured::{MeasuredPoint, Pairing, measured_points, pair};

use std::path::{Path, PathBuf};

use crate::engine::{Condition, PointAccumulator};
use crate::error::Result;
use crate::figure::{SizePreset, render, with_caption};
use crate::sweep::SweepResult;
use amplitude::{figure9a, figure9a_caption};
use density::{figure8, figure8_caption, figure8_points};
use phase::{figure9c, figure9c_caption};
use variance::{figure9b, figure9b_caption};

/// How Figure 9(a)'s amplitude axis is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum AmplitudeAxis {
    /// Logarithmic when the values span more than a factor of 30 (a
    /// resonance beside a stuck block), else linear from zero.
    #[default]
    Auto,
    /// Logarithmic, every decade labelled.
    Log,
    /// Linear from zero, as the paper draws its Figure 9(a).
    Linear,
}

/// What [`write_sweep_plots_with`] draws.
#[derive(Clone, Copy, Debug)]
pub struct PlotOptions<'a> {
    /// Figure 8 shows the grid frequency nearest to this, Hz.
    pub fig8_frequency_hz: f64,
    pub size: SizePreset,
    /// Measured statistics drawn over the simulation (empty: none).
    pub measured: &'a [MeasuredPoint],
    /// Where the measured statistics come from, for the legends.
    pub measured_label: &'a str,
    /// Figure 9(a)'s amplitude axis.
    pub amplitude_axis: AmplitudeAxis,
}

/// Normal forces of the grid in order, and per force its points sorted by frequency.
fn curves(result: &SweepResult) -> Vec<(f64, Vec<(Condition, &PointAccumulator)>)> {
    let mut forces: Vec<f64> = result.conditions.iter().map(|c| c.normal_force_n).collect();
    forces.sort_by(f64::total_cmp);
    forces.dedup();
    forces
        .into_iter()
        .map(|n| {
            let mut pts: Vec<(Condition, &PointAccumulator)> = result
                .conditions
                .iter()
                .zip(&result.accumulators)
                .filter(|(c, _)| c.normal_force_n == n)
                .map(|(c, a)| (*c, a))
                .collect();
            pts.sort_by(|a, b| a.0.excitation_frequency_hz.total_cmp(&b.0.excitation_frequency_hz));
            (n, pts)
        })
        .collect()
}

/// The normal forces of the grid, increasing: one curve each.
pub fn loads(result: &SweepResult) -> Vec<f64> {
    curves(result).iter().map(|(n, _)| *n).collect()
}

/// Whether two normal forces are the same load (within 1%).
fn same_load(a: f64, b: f64) -> bool {
    (a - b).abs() <= 0.01 * a.abs().max(b.abs()).max(1e-9)
}

/// Writes fig9a, fig9b, fig9c and fig8 (PNG + SVG) into `dir` at the
/// screen size without measured data; returns the files.
pub fn write_sweep_plots(dir: &Path, result: &SweepResult, figure8_frequency_hz: f64) -> Result<Vec<PathBuf>> {
    let opts = PlotOptions {
        fig8_frequency_hz: figure8_frequency_hz,
        size: SizePreset::Screen,
        measured: &[],
        measured_label: "measured",
        amplitude_axis: AmplitudeAxis::Auto,
    };
    write_sweep_plots_with(dir, result, &opts)
}

/// Writes fig9a, fig9b, fig9c and fig8 (PNG + SVG) into `dir` as `opts`
/// says; returns the files.
pub fn write_sweep_plots_with(dir: &Path, result: &SweepResult, opts: &PlotOptions) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    let caption = figure9a_caption(result, opts);
    let look = with_caption(opts.size, (1000, 650), &caption);
    files.extend(render(dir, "fig9a", look.size, &|r| figure9a(r, result, opts, look, &caption), &|r| {
        figure9a(r, result, opts, look, &caption)
    })?);
    let caption = figure9b_caption(result, opts);
    let look = with_caption(opts.size, (1000, 650), &caption);
    files.extend(render(dir, "fig9b", look.size, &|r| figure9b(r, result, opts, look, &caption), &|r| {
        figure9b(r, result, opts, look, &caption)
    })?);
    let caption = figure9c_caption(result, opts);
    let look = with_caption(opts.size, (1000, 650), &caption);
    files.extend(render(dir, "fig9c", look.size, &|r| figure9c(r, result, opts, look, &caption), &|r| {
        figure9c(r, result, opts, look, &caption)
    })?);
    let pts = figure8_points(result, opts.fig8_frequency_hz);
    let rows = pts.len().div_ceil(2).max(1) as u32;
    let caption = figure8_caption(&pts, opts);
    let look8 = with_caption(opts.size, (1100, 30 + 380 * rows), &caption);
    files.extend(render(dir, "fig8", look8.size, &|r| figure8(r, &pts, opts, look8, &caption), &|r| {
        figure8(r, &pts, opts, look8, &caption)
    })?);
    Ok(files)
}
