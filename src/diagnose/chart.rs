//! The report's chart: the worst observables' |z| under the calibrated
//! baseline and under the fitted model.

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::diagnose::Diagnosis;
use crate::diagnose::score::Score;
use crate::error::Result;
use crate::figure::{FONT, colour, legend_box, plot_error, render};

fn gap_chart<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, d: &Diagnosis) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| plot_error("gap", e);
    let mut worst: Vec<&Score> = d.baseline_scores.iter().collect();
    worst.sort_by(|a, b| b.z.abs().total_cmp(&a.z.abs()));
    worst.truncate(12);
    let fitted_z = |s: &Score| {
        d.fitted_scores
            .iter()
            .find(|f| {
                f.observable == s.observable
                    && f.excitation_frequency_hz == s.excitation_frequency_hz
                    && f.normal_force_n == s.normal_force_n
                    && f.heldout == s.heldout
            })
            .map_or(0.0, |f| f.z.abs())
    };
    let top = worst.iter().map(|s| s.z.abs()).fold(3.5, f64::max) * 1.1;
    let n = worst.len().max(1);
    let mut chart = ChartBuilder::on(&root)
        .caption(format!("|z| of the worst observables: baseline vs fitted ({})", d.verdict_name()), (FONT, 20))
        .margin(12)
        .x_label_area_size(150)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..n as f64, (0.1..top).log_scale())
        .map_err(e)?;
    let labels: Vec<String> = worst
        .iter()
        .map(|s| format!("{} @ {:.2} Hz, {:.2} N", s.observable, s.excitation_frequency_hz, s.normal_force_n))
        .collect();
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(n)
        .x_label_formatter(&|x| labels.get(x.floor() as usize).cloned().unwrap_or_default())
        .x_label_style((FONT, 11).into_font().transform(FontTransform::Rotate90))
        .y_desc("|z| (simulator's replicate spreads)")
        .label_style((FONT, 12))
        .draw()
        .map_err(e)?;
    chart
        .draw_series(worst.iter().enumerate().map(|(i, s)| {
            Rectangle::new([(i as f64 + 0.1, 0.1), (i as f64 + 0.48, s.z.abs().max(0.1))], colour(1).filled())
        }))
        .map_err(e)?
        .label("baseline")
        .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 14, y + 5)], colour(1).filled()));
    chart
        .draw_series(worst.iter().enumerate().map(|(i, s)| {
            Rectangle::new([(i as f64 + 0.52, 0.1), (i as f64 + 0.9, fitted_z(s).max(0.1))], colour(0).filled())
        }))
        .map_err(e)?
        .label("fitted")
        .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 14, y + 5)], colour(0).filled()));
    chart.draw_series(LineSeries::new(vec![(0.0, 3.0), (n as f64, 3.0)], BLACK.stroke_width(1))).map_err(e)?;
    legend_box(&mut chart, 13, SeriesLabelPosition::UpperRight, "gap")
}

/// Writes `gap.png` and `gap.svg`: the worst observables' |z| before and after.
pub(crate) fn write_gap_chart(dir: &Path, d: &Diagnosis) -> Result<Vec<PathBuf>> {
    render(dir, "gap", (1000, 700), &|r| gap_chart(r, d), &|r| gap_chart(r, d))
}
