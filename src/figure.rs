//! Drawing helpers shared by every figure: the embedded font, the palette,
//! legends, tick labels ([`tick`], [`decade_tick`]), and [`render`], which
//! writes a figure as PNG and SVG under temporary names and renames each
//! into place when it is complete.

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::{Error, Result};

pub const FONT: &str = "sans-serif";
static FONT_BYTES: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");

fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        plotters::style::register_font(FONT, FontStyle::Normal, FONT_BYTES)
            .unwrap_or_else(|_| panic!("the embedded DejaVu Sans is a valid font"));
    });
}

pub fn plot_error(what: &str, e: impl std::fmt::Display) -> Error {
    Error::Io { path: PathBuf::from(what), source: std::io::Error::other(e.to_string()) }
}

/// Draws with `draw` into `dir/stem.png` and `dir/stem.svg` (temporary
/// names first, renamed when complete). Returns the two paths.
pub fn render(
    dir: &Path,
    stem: &str,
    size: (u32, u32),
    draw: &dyn Fn(DrawingArea<BitMapBackend, Shift>) -> Result<()>,
    draw_svg: &dyn Fn(DrawingArea<SVGBackend, Shift>) -> Result<()>,
) -> Result<Vec<PathBuf>> {
    register_font();
    let mut written = Vec::new();
    for ext in ["png", "svg"] {
        let path = dir.join(format!("{stem}.{ext}"));
        let tmp = dir.join(format!(".{stem}.{}.tmp.{ext}", std::process::id()));
        let outcome = if ext == "png" {
            let root = BitMapBackend::new(&tmp, size).into_drawing_area();
            root.fill(&WHITE).map_err(|e| plot_error(stem, e))?;
            draw(root.clone()).and_then(|_| root.present().map_err(|e| plot_error(stem, e)))
        } else {
            let root = SVGBackend::new(&tmp, size).into_drawing_area();
            root.fill(&WHITE).map_err(|e| plot_error(stem, e))?;
            draw_svg(root.clone()).and_then(|_| root.present().map_err(|e| plot_error(stem, e)))
        };
        if let Err(e) = outcome.and_then(|_| std::fs::rename(&tmp, &path).map_err(|e| Error::io(&path, e))) {
            let _ = std::fs::remove_file(&tmp);
            return Err(e);
        }
        written.push(path);
    }
    Ok(written)
}

pub fn colour(i: usize) -> RGBColor {
    const COLOURS: [RGBColor; 8] = [
        RGBColor(31, 119, 180),
        RGBColor(214, 39, 40),
        RGBColor(44, 160, 44),
        RGBColor(148, 103, 189),
        RGBColor(255, 127, 14),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(23, 190, 207),
    ];
    COLOURS[i % COLOURS.len()]
}

/// The legend: white box, black border, font of `size` px.
pub fn legend_box<'a, DB: DrawingBackend + 'a, CT: plotters::coord::CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    size: u32,
    position: SeriesLabelPosition,
    what: &str,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    chart
        .configure_series_labels()
        .label_font((FONT, size))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(position)
        .draw()
        .map_err(|e| plot_error(what, e))
}

/// A tick label without trailing zeros: 200, 2.5, 0.01 (not "200.0").
pub fn tick(v: f64) -> String {
    if !v.is_finite() {
        return String::new();
    }
    let mut s = format!("{v:.6}");
    if s.contains('.') {
        s = s.trim_end_matches('0').trim_end_matches('.').to_string();
    }
    if s == "-0" { "0".into() } else { s }
}

/// A log axis's tick label: 10ⁿ at the decades, nothing between them.
pub fn decade_tick(v: f64) -> String {
    if !(v.is_finite() && v > 0.0) {
        return String::new();
    }
    let e = v.log10();
    if (e - e.round()).abs() > 1e-6 {
        return String::new();
    }
    let digits: String = (e.round() as i64)
        .to_string()
        .chars()
        .map(|c| match c {
            '-' => '⁻',
            '0' => '⁰',
            '1' => '¹',
            '2' => '²',
            '3' => '³',
            '4' => '⁴',
            '5' => '⁵',
            '6' => '⁶',
            '7' => '⁷',
            '8' => '⁸',
            _ => '⁹',
        })
        .collect();
    format!("10{digits}")
}

/// The decades around `[lo, hi]` (both > 0): the lowest and highest decade
/// of the axis both carry a label.
pub fn decade_range(lo: f64, hi: f64) -> (f64, f64) {
    let lo = 10f64.powf(lo.log10().floor());
    let mut hi = 10f64.powf(hi.log10().ceil());
    if hi <= lo {
        hi = lo * 10.0;
    }
    (lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_have_no_trailing_zeros() {
        assert_eq!(tick(200.0), "200");
        assert_eq!(tick(2.5), "2.5");
        assert_eq!(tick(0.1 + 0.2), "0.3");
        assert_eq!(tick(-0.0), "0");
        assert_eq!(decade_tick(1e-3), "10⁻³");
        assert_eq!(decade_tick(100.0), "10²");
        assert_eq!(decade_tick(2e-3), "");
    }
}
