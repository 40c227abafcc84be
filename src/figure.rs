//! Drawing helpers shared by every figure: the embedded font, the palette,
//! legends, tick labels ([`tick`], [`decade_tick`]), a figure's size and
//! text scale for a page ([`SizePreset`], [`Look`]), captions set below the
//! plot ([`with_caption`], [`caption_below`]), and [`render`], which writes a
//! figure as PNG and SVG under temporary names and renames each into place
//! when it is complete.

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

/// How large a figure is drawn, and how large its text is relative to it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum SizePreset {
    /// 1000 px wide, for a screen (the default).
    #[default]
    Screen,
    /// One journal column (3.5 in) at 300 dpi, text about 8 pt when printed at that width.
    Single,
    /// Two columns (7.2 in) at 300 dpi, text about 8 pt.
    Double,
    /// A 16:9 slide, 1920 × 1080, text large enough for the back of the room.
    Slide,
}

impl SizePreset {
    /// Width of a figure (px) and the factor applied to the screen layout's
    /// text, lines and margins.
    fn width_and_scale(self) -> (f64, f64) {
        match self {
            SizePreset::Screen => (1000.0, 1.0),
            SizePreset::Single => (1050.0, 2.1),
            SizePreset::Double => (2160.0, 2.2),
            SizePreset::Slide => (1920.0, 1.9),
        }
    }

    /// The look of a figure designed at `design` px on the screen.
    pub fn look(self, design: (u32, u32)) -> Look {
        let (w, scale) = self.width_and_scale();
        let aspect = match self {
            SizePreset::Slide => 1080.0 / 1920.0,
            _ => f64::from(design.1) / f64::from(design.0),
        };
        Look { size: (w.round() as u32, (w * aspect).round() as u32), scale }
    }
}

/// A figure's pixel size and the scale of its text, lines and margins.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Look {
    pub size: (u32, u32),
    pub scale: f64,
}

impl Look {
    /// `base` (px on the screen layout) scaled.
    pub fn px(&self, base: u32) -> u32 {
        (f64::from(base) * self.scale).round().max(1.0) as u32
    }
    pub fn signed(&self, base: i32) -> i32 {
        (f64::from(base) * self.scale).round() as i32
    }
}

/// Width of a legend's icons, px: plotters sets the labels a fixed distance
/// from the icon's start, so the icon does not scale with the text.
pub const LEGEND_ICON: i32 = 20;

/// A title's font size: `base` scaled, but no wider than `width` px.
pub fn caption_px(look: Look, text: &str, base: u32, width: u32) -> u32 {
    let fit = (f64::from(width) * 0.95 / (text.chars().count().max(1) as f64 * 0.56)).floor() as u32;
    look.px(base).min(fit.max(8))
}

/// Wraps `text` into lines no wider than `width` px in `style`.
pub fn wrap<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    text: &str,
    style: &TextStyle,
    width: u32,
) -> Vec<String> {
    let fits = |s: &str| area.estimate_text_size(s, style).map_or(s.chars().count() < 60, |(w, _)| w <= width);
    let mut lines = Vec::new();
    let mut line = String::new();
    for word in text.split_whitespace() {
        let candidate = if line.is_empty() { word.to_string() } else { format!("{line} {word}") };
        if fits(&candidate) || line.is_empty() {
            line = candidate;
        } else {
            lines.push(std::mem::replace(&mut line, word.to_string()));
        }
    }
    if !line.is_empty() {
        lines.push(line);
    }
    lines
}

/// A caption's font size, line height and margin, px on the screen layout.
pub const CAPTION_FONT: u32 = 14;
pub const CAPTION_LINE: u32 = 19;
pub const CAPTION_PAD: u32 = 12;

/// The look of a figure designed at `design` px on the screen with `caption`
/// set below it: the canvas grows by the caption's height, so a long caption
/// never squeezes the plot (a slide keeps its 16:9 and gives the plot less).
/// The height is estimated generously (0.62 em a character); what the
/// wrapped caption does not use goes to the plot.
pub fn with_caption(size: SizePreset, design: (u32, u32), caption: &str) -> Look {
    let look = size.look(design);
    if size == SizePreset::Slide {
        return look;
    }
    let width = f64::from(look.size.0.saturating_sub(2 * look.px(CAPTION_PAD)));
    let per_line = (width / (0.62 * f64::from(look.px(CAPTION_FONT)))).floor().max(10.0) as usize;
    let mut lines = 1;
    let mut used = 0;
    for word in caption.split_whitespace() {
        let n = word.chars().count();
        if used > 0 && used + 1 + n > per_line {
            lines += 1;
            used = n;
        } else {
            used += n + usize::from(used > 0);
        }
    }
    let strip = 2 * look.px(CAPTION_PAD) + look.px(CAPTION_LINE) * lines;
    Look { size: (look.size.0, look.size.1 + strip), scale: look.scale }
}

/// Writes `caption` below the figure, as a journal sets it, and returns the
/// area above it for the plot: the figure's number in bold-face words, then
/// what is drawn. The caption is outside every plot area.
pub fn caption_below<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    caption: &str,
    look: Look,
    what: &'static str,
) -> Result<DrawingArea<DB, Shift>>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| plot_error(what, e);
    let (w, h) = root.dim_in_pixel();
    let ink = RGBColor(40, 40, 40);
    let style = TextStyle::from((FONT, look.px(CAPTION_FONT)).into_font()).color(&ink);
    let pad = look.px(CAPTION_PAD);
    let lines = wrap(root, caption, &style, w.saturating_sub(2 * pad));
    let line_h = look.px(CAPTION_LINE);
    let strip = (2 * pad + line_h * lines.len() as u32).min(h / 2);
    let (plot, below) = root.split_vertically(h - strip);
    for (i, line) in lines.iter().enumerate() {
        below
            .draw(&Text::new(line.clone(), (pad as i32, (pad / 2 + line_h * i as u32) as i32), style.clone()))
            .map_err(e)?;
    }
    Ok(plot)
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
