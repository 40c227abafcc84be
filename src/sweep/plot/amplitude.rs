//! Figure 9(a): the mean peak against frequency, one curve per normal force,
//! with the 5–95% range, a zoom on the measured conditions, and its caption.

use plotters::coord::Shift;
use plotters::prelude::*;

use super::measured::pair;
use super::panel::{
    Axis, Layout, MeasuredMark, SimPoint, SimSeries, Spread, draw_measured, draw_minor, draw_simulated, frequency_axis,
    frequency_span, labels_fit, pairing_note,
};
use super::{AmplitudeAxis, PlotOptions, curves, loads};
use crate::engine::{Condition, PointAccumulator};
use crate::error::Result;
use crate::figure::{FONT, Look, caption_below, caption_px, colour, decade_range, legend_box, plot_error, tick};
use crate::sweep::SweepResult;

/// The simulated mean peak (m) of a curve at `frequency_hz`: the grid point's
/// when the grid has that frequency, else interpolated linearly between the
/// neighbouring grid frequencies; `None` outside the grid.
fn mean_at(points: &[(Condition, &PointAccumulator)], frequency_hz: f64) -> Option<f64> {
    let at = |k: usize| (points[k].0.excitation_frequency_hz, points[k].1.moments().0);
    let tol = 1e-6 * frequency_hz.abs();
    if let Some(k) = points.iter().position(|(c, _)| (c.excitation_frequency_hz - frequency_hz).abs() <= tol) {
        return Some(at(k).1);
    }
    let k = points.iter().position(|(c, _)| c.excitation_frequency_hz > frequency_hz)?;
    if k == 0 {
        return None;
    }
    let ((f0, m0), (f1, m1)) = (at(k - 1), at(k));
    Some(m0 + (m1 - m0) * (frequency_hz - f0) / (f1 - f0))
}

/// The measured points of Figure 9(a) in the panel's coordinates, labelled
/// with their load and how far the simulation misses them (same load), or
/// with the nearest simulated load they are set against.
fn figure9a_measured(
    result: &SweepResult,
    opts: &PlotOptions,
    layout: Layout,
    y: &dyn Fn(f64) -> f64,
    labels: bool,
) -> Vec<MeasuredMark> {
    let curves = curves(result);
    let forces: Vec<f64> = curves.iter().map(|(n, _)| *n).collect();
    opts.measured
        .iter()
        .map(|m| {
            let se = m.mean_standard_error_m();
            let paired = pair(&forces, m);
            let colour = paired.map_or(BLACK, |p| colour(p.curve));
            let label = match paired {
                _ if !labels => String::new(),
                Some(p) if p.same_load => match mean_at(&curves[p.curve].1, m.excitation_frequency_hz) {
                    Some(sim) => format!("{} N: simulated {}", tick(m.normal_force_n), relative(sim, m.peak_mean_m)),
                    None => format!("{} N", tick(m.normal_force_n)),
                },
                Some(p) => format!("{} N (nearest simulated load {} N)", tick(m.normal_force_n), tick(p.force_n)),
                None => format!("{} N", tick(m.normal_force_n)),
            };
            (
                layout.measured(paired.map(|p| p.curve), m.excitation_frequency_hz),
                y(m.peak_mean_m),
                y(m.peak_mean_m - se),
                y(m.peak_mean_m + se),
                colour,
                label,
            )
        })
        .collect()
}

/// The simulated mean `sim` against the measured one (both m): a signed
/// percentage with one decimal, two below 0.1% (`−2.9%`, `+0.04%`); a
/// factor where the simulated is a thousandfold or more (`×2.0e197`), so
/// that a label stays one line; `n/a` where the measured mean is 0.
fn relative(sim: f64, measured: f64) -> String {
    let p = 100.0 * (sim / measured - 1.0);
    if !p.is_finite() {
        return "n/a (measured mean 0)".into();
    }
    if p >= 1e5 {
        return format!("×{:.1e}", sim / measured);
    }
    let text = if p.abs() < 0.1 { format!("{:.2}", p.abs()) } else { format!("{:.1}", p.abs()) };
    format!("{}{text}%", if p < 0.0 { "−" } else { "+" })
}

/// The curves of Figure 9(a): mean peak (mm) with its 5–95% range, only those
/// `keep` lets through.
fn figure9a_series(
    result: &SweepResult,
    layout: Layout,
    y: &dyn Fn(f64) -> f64,
    keep: &dyn Fn(usize) -> bool,
) -> Vec<SimSeries> {
    curves(result)
        .iter()
        .enumerate()
        .filter(|(i, _)| keep(*i))
        .map(|(i, (n, pts))| SimSeries {
            force_n: *n,
            colour: colour(i),
            points: pts
                .iter()
                .map(|(c, a)| SimPoint {
                    x: layout.simulated(i, c.excitation_frequency_hz),
                    y: y(a.moments().0),
                    lo: y(a.quantile(0.05)),
                    hi: y(a.quantile(0.95)),
                })
                .collect(),
        })
        .collect()
}

/// The ranges one panel of Figure 9(a) shows.
#[derive(Clone, Copy, Debug)]
struct PanelRange {
    /// Excitation frequencies, Hz.
    x: (f64, f64),
    /// Peak amplitudes, mm.
    y: (f64, f64),
}

/// One panel of Figure 9(a) over `range`. `zoom` draws only the curves the
/// measured points are set against, on a linear axis fitted to them.
#[allow(clippy::too_many_arguments)]
fn figure9a_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    result: &SweepResult,
    opts: &PlotOptions,
    look: Look,
    heading: &str,
    range: PanelRange,
    zoom: bool,
    legend: bool,
) -> Result<Axis>
where
    DB::ErrorType: 'static,
{
    let PanelRange { x, y } = range;
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| plot_error("fig9a", e);
    let log = match opts.amplitude_axis {
        _ if zoom => false,
        AmplitudeAxis::Auto => y.0 > 0.0 && y.1 / y.0 > 30.0,
        AmplitudeAxis::Log => y.0 > 0.0,
        AmplitudeAxis::Linear => false,
    };
    let (y_lo, y_hi, axis) = if log {
        let (lo, hi) = decade_range(y.0, y.1);
        let (lo, hi) = (lo.log10().round(), hi.log10().round());
        (lo, hi, Axis::Log { lo, hi, powers: false })
    } else if zoom {
        let pad = 0.08 * (y.1 - y.0).max(1e-6);
        (y.0 - pad, y.1 + pad, Axis::Linear)
    } else {
        (0.0, if y.1 > 0.0 { y.1 * 1.1 } else { 1.0 }, Axis::Linear)
    };
    let layout = Layout::new(result);
    let mut builder = ChartBuilder::on(area);
    if !heading.is_empty() {
        builder.caption(heading, (FONT, caption_px(look, heading, 16, area.dim_in_pixel().0)));
    }
    let mut chart = builder
        .margin(look.px(12))
        .x_label_area_size(look.px(52))
        .y_label_area_size(look.px(64))
        .build_cartesian_2d(x.0..x.1, y_lo..y_hi)
        .map_err(e)?;
    let (x_desc, x_fmt) = frequency_axis(layout);
    let y_fmt = |v: &f64| axis.label(*v);
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(x_desc)
        .y_desc("peak amplitude (mm)")
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .label_style((FONT, look.px(15)))
        .axis_desc_style((FONT, look.px(16)))
        .x_labels(if zoom { 5 } else { 11 });
    if layout.single.is_some() {
        mesh.disable_x_mesh().x_labels(0);
    }
    if let Axis::Log { lo, hi, .. } = axis {
        mesh.y_labels((hi - lo) as usize + 1).light_line_style(TRANSPARENT);
    }
    mesh.draw().map_err(e)?;
    draw_minor(&mut chart, axis, x, look, "fig9a")?;
    let ymap = |v_m: f64| axis.map(v_m * 1e3);
    let forces = loads(result);
    let paired: Vec<usize> = opts.measured.iter().filter_map(|m| pair(&forces, m)).map(|p| p.curve).collect();
    let keep = |i: usize| !zoom || paired.contains(&i);
    let series = figure9a_series(result, layout, &ymap, &keep);
    draw_simulated(&mut chart, &series, Spread::Band, layout, look, "fig9a")?;
    let labels = zoom || labels_fit(layout, opts.measured);
    let measured = figure9a_measured(result, opts, layout, &ymap, labels);
    draw_measured(&mut chart, &measured, &format!("{}: mean ± s.e.", opts.measured_label), look, "fig9a")?;
    if legend {
        legend_box(&mut chart, look.px(14), SeriesLabelPosition::UpperRight, "fig9a")?;
    }
    Ok(axis)
}

/// Figure 9(a): the mean peak against frequency, one curve per normal force,
/// a marker at every grid point, with the 5–95% range of the peaks (a band;
/// a box on a one-frequency grid). With measured data over a grid of several
/// frequencies, a second panel zooms on the measured conditions and the
/// curves they are set against. The caption is set below the plot.
/// The amplitudes (mm) Figure 9(a)'s full panel spans: every simulated 5–95%
/// range and mean, and the measured means with their error bars, down to a
/// decade below the lowest mean (a block that sticks can have a 5% quantile
/// far below it).
fn figure9a_extent(result: &SweepResult, opts: &PlotOptions) -> (f64, f64) {
    let means: Vec<f64> =
        result.accumulators.iter().map(|a| a.moments().0 * 1e3).filter(|v| v.is_finite() && *v > 0.0).collect();
    let values: Vec<f64> = result
        .accumulators
        .iter()
        .flat_map(|a| [a.quantile(0.05), a.quantile(0.95)])
        .chain(opts.measured.iter().flat_map(|m| {
            let se = m.mean_standard_error_m();
            [m.peak_mean_m - se, m.peak_mean_m + se]
        }))
        .map(|v| v * 1e3)
        .filter(|v| v.is_finite() && *v > 0.0)
        .chain(means.iter().copied())
        .collect();
    let mean_lo = means.iter().copied().fold(f64::INFINITY, f64::min);
    let lo = values.iter().copied().fold(f64::INFINITY, f64::min).max(mean_lo / 10.0);
    let hi = values.iter().copied().fold(0.0, f64::max);
    (lo, hi)
}

/// Figure 9(a)'s caption: what is drawn, on which axis, and how the measured
/// points meet the curves.
pub(super) fn figure9a_caption(result: &SweepResult, opts: &PlotOptions) -> String {
    let (lo, hi) = figure9a_extent(result, opts);
    let layout = Layout::new(result);
    let zoom = !opts.measured.is_empty() && layout.single.is_none();
    let single_zoomed = !opts.measured.is_empty() && layout.single.is_some();
    // The axis by the full panel's own rule, on the same range.
    let log = match opts.amplitude_axis {
        _ if single_zoomed => false,
        AmplitudeAxis::Auto => lo > 0.0 && hi / lo > 30.0,
        AmplitudeAxis::Log => lo > 0.0,
        AmplitudeAxis::Linear => false,
    };
    let mut caption = match layout.single {
        Some(f) => format!(
            "Figure 9(a) at one frequency. Mean peak amplitude at {} Hz, one colour per normal force N0, the normal \
             forces side by side: a dot marks the simulated mean, the box the 5–95% range of the simulated peaks.",
            tick(f)
        ),
        None => "Figure 9(a). Mean peak amplitude against excitation frequency, one colour per normal force N0: a \
                 dot marks every simulated grid point, the shaded band (edges drawn) the 5–95% range of the \
                 simulated peaks."
            .to_string(),
    };
    caption.push_str(if log {
        " Logarithmic amplitude axis (`stickslip plot --amplitude-axis linear` draws the paper's linear view)."
    } else {
        " Linear amplitude axis."
    });
    caption.push_str(&pairing_note(result, opts.measured, &format!("{}: mean ± standard error", opts.measured_label)));
    if zoom {
        caption.push_str(" Right: zoom on the measured conditions, with only the curves they are set against.");
    }
    caption
}

pub(super) fn figure9a<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    result: &SweepResult,
    opts: &PlotOptions,
    look: Look,
    caption: &str,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let (lo, hi) = figure9a_extent(result, opts);
    let x = frequency_span(result, opts.measured);
    let layout = Layout::new(result);
    let zoom = !opts.measured.is_empty() && layout.single.is_none();
    let single_zoomed = !opts.measured.is_empty() && layout.single.is_some();
    let plot = caption_below(&root, caption, look, "fig9a")?;
    if single_zoomed {
        // Zoom on the values: the measured points and the boxes they meet.
        return figure9a_panel(
            &plot,
            result,
            opts,
            look,
            "",
            PanelRange { x, y: zoom_range(result, opts, x) },
            true,
            true,
        )
        .map(|_| ());
    }
    if !zoom {
        return figure9a_panel(&plot, result, opts, look, "", PanelRange { x, y: (lo, hi) }, false, true).map(|_| ());
    }
    let (left, right) = plot.split_horizontally(look.size.0 * 57 / 100);
    figure9a_panel(&left, result, opts, look, "all conditions", PanelRange { x, y: (lo, hi) }, false, true)?;
    // The zoom: the measured frequencies ± 0.6 Hz, every value there.
    let (m_lo, m_hi) = opts.measured.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), m| {
        (l.min(m.excitation_frequency_hz), h.max(m.excitation_frequency_hz))
    });
    let zx = ((m_lo - 0.6).max(x.0), (m_hi + 0.6).min(x.1));
    let zx = if zx.1 > zx.0 { zx } else { (m_lo - 0.6, m_hi + 0.6) };
    let range = PanelRange { x: zx, y: zoom_range(result, opts, zx) };
    figure9a_panel(&right, result, opts, look, "zoom on the measured conditions", range, true, false).map(|_| ())
}

/// The amplitude range (mm) of a zoom over frequencies `x`: the measured
/// points with their error bars and the curves they are set against.
fn zoom_range(result: &SweepResult, opts: &PlotOptions, x: (f64, f64)) -> (f64, f64) {
    let forces = loads(result);
    let paired: Vec<f64> = opts.measured.iter().filter_map(|m| pair(&forces, m)).map(|p| p.force_n).collect();
    let mut zy = (f64::INFINITY, f64::NEG_INFINITY);
    for (c, a) in result.conditions.iter().zip(&result.accumulators) {
        if (x.0..=x.1).contains(&c.excitation_frequency_hz) && paired.contains(&c.normal_force_n) {
            for v in [a.moments().0, a.quantile(0.05), a.quantile(0.95)] {
                if v.is_finite() {
                    zy = (zy.0.min(v * 1e3), zy.1.max(v * 1e3));
                }
            }
        }
    }
    for m in opts.measured {
        let se = m.mean_standard_error_m();
        zy = (zy.0.min((m.peak_mean_m - se) * 1e3), zy.1.max((m.peak_mean_m + se) * 1e3));
    }
    if zy.0.is_finite() { zy } else { (0.0, 1.0) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plot_percentages_are_signed_with_one_decimal() {
        assert_eq!(relative(0.970_6, 1.0), "−2.9%");
        assert_eq!(relative(1.000_44, 1.0), "+0.04%");
        // A measured mean of 0, or one far below the simulated, keeps the
        // label one short line.
        assert_eq!(relative(1e-3, 0.0), "n/a (measured mean 0)");
        assert_eq!(relative(3.85e-3, 3.85e-203), "×1.0e200");
    }
}
