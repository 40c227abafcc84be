//! Figure 9(c): the circular mean phase lag of the response's fundamental
//! against frequency, with ± one circular standard deviation.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::measured::pair;
use super::panel::{
    Layout, MeasuredMark, SimPoint, SimSeries, Spread, draw_measured, draw_simulated, frequency_axis, frequency_span,
    labels_fit, pairing_note,
};
use super::{PlotOptions, curves, loads};
use crate::engine::PointAccumulator;
use crate::error::Result;
use crate::figure::{FONT, Look, caption_below, colour, legend_box, plot_error, tick};
use crate::sweep::SweepResult;

/// Figure 9(c)'s caption.
pub(super) fn figure9c_caption(result: &SweepResult, opts: &PlotOptions) -> String {
    let layout = Layout::new(result);
    format!(
        "Figure 9(c). Phase lag of the response's fundamental behind the base motion {}, one colour per normal \
         force N0 (circular mean over every measured period of every realisation); the {} is ± one circular \
         standard deviation of the per-period lag.{}",
        match layout.single {
            Some(f) => format!("at {} Hz, the normal forces side by side", tick(f)),
            None => "against excitation frequency".to_string(),
        },
        if layout.single.is_some() { "box" } else { "band" },
        pairing_note(result, opts.measured, &format!("{}: mean ± standard error", opts.measured_label))
    )
}

/// Figure 9's phase panel: the circular mean phase lag of the response's
/// fundamental (degrees) against frequency, one curve per normal force, with
/// a band of ± one circular standard deviation. The caption is set below.
pub(super) fn figure9c<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    result: &SweepResult,
    opts: &PlotOptions,
    look: Look,
    caption: &str,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| plot_error("fig9c", e);
    let layout = Layout::new(result);
    let (f_lo, f_hi) = frequency_span(result, opts.measured);
    let plot = caption_below(&root, caption, look, "fig9c")?;
    let mut chart = ChartBuilder::on(&plot)
        .margin(look.px(14))
        .x_label_area_size(look.px(52))
        .y_label_area_size(look.px(72))
        .build_cartesian_2d(f_lo..f_hi, -10.0..190.0)
        .map_err(e)?;
    let (x_desc, x_fmt) = frequency_axis(layout);
    let y_fmt = |v: &f64| tick(*v);
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(x_desc)
        .y_desc("phase lag behind the base (°)")
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .y_labels(11)
        .x_labels(11)
        .label_style((FONT, look.px(15)))
        .axis_desc_style((FONT, look.px(17)));
    if layout.single.is_some() {
        mesh.disable_x_mesh().x_labels(0);
    }
    mesh.draw().map_err(e)?;
    // Lags are drawn in [0°, 360°) so curves above resonance do not jump.
    let lag = |a: &PointAccumulator| {
        let (mean, var) = a.phase_moments();
        (mean.to_degrees().rem_euclid(360.0), var.max(0.0).sqrt().to_degrees())
    };
    let series: Vec<SimSeries> = curves(result)
        .iter()
        .enumerate()
        .map(|(i, (n, pts))| SimSeries {
            force_n: *n,
            colour: colour(i),
            points: pts
                .iter()
                .map(|(c, a)| {
                    let (m, sd) = lag(a);
                    SimPoint { x: layout.simulated(i, c.excitation_frequency_hz), y: m, lo: m - sd, hi: m + sd }
                })
                .collect(),
        })
        .collect();
    draw_simulated(&mut chart, &series, Spread::Band, layout, look, "fig9c")?;
    let forces = loads(result);
    let labels = labels_fit(layout, opts.measured);
    let measured: Vec<MeasuredMark> = opts
        .measured
        .iter()
        .filter_map(|m| {
            let (mean, var) = m.phase_deg?;
            let mean = mean.rem_euclid(360.0);
            let se = match (var, m.n_peaks) {
                (Some(v), Some(n)) if n > 0 => (v.max(0.0) / n as f64).sqrt(),
                _ => 0.0,
            };
            let paired = pair(&forces, m);
            let label = match paired {
                _ if !labels => String::new(),
                Some(p) if !p.same_load => {
                    format!("{} N (nearest simulated load {} N)", tick(m.normal_force_n), tick(p.force_n))
                }
                _ => format!("{} N", tick(m.normal_force_n)),
            };
            Some((
                layout.measured(paired.map(|p| p.curve), m.excitation_frequency_hz),
                mean,
                mean - se,
                mean + se,
                paired.map_or(BLACK, |p| colour(p.curve)),
                label,
            ))
        })
        .collect();
    draw_measured(&mut chart, &measured, &format!("{}: mean ± s.e.", opts.measured_label), look, "fig9c")?;
    legend_box(&mut chart, look.px(15), SeriesLabelPosition::LowerRight, "fig9c")
}
