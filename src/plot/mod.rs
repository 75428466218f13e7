//! Plots and pages for the tools built on runs (`report`, `stress`): one kind of figure,
//! drawn by plotters into a PNG (bitmap backend) and an SVG (svg backend) from the same
//! code: a chart with log or linear axes labelled in engineering units at every decade
//! ([`axis`]), every series and level in a legend to the right of the chart (never over
//! the data), and a caption under it saying what was swept and what the error is
//! measured against; [`svg_check`] reads a figure's SVG back by its text, [`page`]
//! holds what the tools' self-contained HTML pages share. Knows no scene and no run
//! (layer 1: tests/layers.rs), so both tools can use it.
//!
//! Text is DejaVu Sans Mono embedded in the binary (assets/fonts), registered as the
//! `monospace` family: every machine lays out the PNG's text the same way, and the SVG
//! asks the browser for a monospace font, whose advance (0.60 em) is within the
//! layout's (0.64 of the SVG's em), so text that does not overlap in the PNG does not
//! overlap in a browser either ([`svg_check`] checks the SVG against 0.65 em).

use std::path::Path;

use std::ops::Range;

use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};
use plotters::coord::Shift;
use plotters::prelude::*;

pub mod axis;
pub mod page;
pub mod svg_check;

use axis::{engineering, linear_ticks, log_ticks, Scale, Ticks, Unit};

/// Why a figure could not be drawn or written.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// No point of the figure can be drawn (none finite, or none positive on a log
    /// axis): the figure's title and that.
    #[error("{0}: no run to plot")]
    NoData(String),
    /// plotters failed to draw (its errors are not `Send`, so only their text is kept).
    #[error("{0}")]
    Draw(String),
    #[error(transparent)]
    Png(#[from] png::EncodingError),
    /// The file could not be written.
    #[error("cannot write {path}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
}

/// An I/O error naming the file.
fn io(path: &Path) -> impl FnOnce(std::io::Error) -> PlotError {
    let path = path.display().to_string();
    move |source| PlotError::Io { path, source }
}

/// How a series is drawn (and shown in the legend).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Style {
    /// A line through filled markers (a sweep); `bold`: thicker and larger (the
    /// default solver).
    Line { bold: bool },
    /// A line without markers (a time series).
    Plain,
    /// A dashed line without markers (a theory, a bound).
    Dashed,
    /// Hollow circles (a resolution sweep).
    HollowCircle,
    /// Hollow squares (a tolerance sweep).
    HollowSquare,
    /// A wide translucent staircase through the points (the Pareto front).
    Front,
}

/// One series: its legend entry, colour, points (x, y) and style.
pub(crate) struct Series {
    pub label: String,
    pub color: RGBColor,
    pub points: Vec<(f64, f64)>,
    pub style: Style,
}

/// A horizontal level across the chart: a dashed grey line at `y`, and with `band`
/// a shaded band from the bottom of the chart up to it (values there are not resolved).
pub(crate) struct Level {
    pub y: f64,
    pub label: String,
    pub band: bool,
}

/// An axis: its description, the unit its ticks are labelled in and its scale.
pub(crate) struct Axis {
    pub desc: String,
    pub unit: Unit,
    pub scale: Scale,
}

/// What [`write_figure`] draws.
pub(crate) struct Figure {
    pub title: String,
    pub x: Axis,
    pub y: Axis,
    pub series: Vec<Series>,
    pub levels: Vec<Level>,
    /// One sentence under the chart (wrapped to the figure's width).
    pub caption: String,
}

/// Figure width, px.
const WIDTH: u32 = 1000;
/// Chart height (title, plot area, tick labels, axis descriptions), px, unless the
/// legend needs more; the caption adds [`LINE`] per line below it.
const CHART_HEIGHT: u32 = 560;
/// The legend starts this far below the top, px.
const LEGEND_TOP: u32 = 40;
/// Width of a legend entry's sample and the gap after it, px.
const SAMPLE: (i32, i32) = (34, 8);
/// Width of the chart's area; the legend takes the rest, px.
const CHART_WIDTH: u32 = 670;
/// Font sizes (plotters' size: the layout height of a line, px).
const TITLE_FONT: u32 = 20;
const FONT: u32 = 14;
/// Line pitch of the legend and the caption, px (more than [`FONT`]: no two lines'
/// layout boxes touch).
const LINE: u32 = 18;
/// Advance of a character of the embedded font, in units of the font size (DejaVu
/// Sans Mono: 1233 / 2048 em, em = size / 1.164), for wrapping before drawing.
const ADVANCE: f64 = 0.52;
const FAMILY: &str = "monospace";

static REGISTERED: std::sync::Once = std::sync::Once::new();

fn register_font() {
    REGISTERED.call_once(|| {
        let bytes: &'static [u8] = include_bytes!("../../assets/fonts/DejaVuSansMono.ttf");
        // a font that does not parse leaves text undrawn; the plot itself still renders
        let _ = plotters::style::register_font(FAMILY, FontStyle::Normal, bytes);
    });
}

/// `text` broken at spaces into lines of at most `chars` characters (a longer word
/// gets a line of its own).
pub(crate) fn wrap(text: &str, chars: usize) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for word in text.split_whitespace() {
        match lines.last_mut() {
            Some(l) if l.chars().count() + 1 + word.chars().count() <= chars => {
                l.push(' ');
                l.push_str(word);
            }
            _ => lines.push(word.to_string()),
        }
    }
    lines
}

/// Characters of [`FONT`]-sized text that fit in `px`.
fn fits(px: u32) -> usize {
    (px as f64 / (ADVANCE * FONT as f64)).floor() as usize
}

impl Figure {
    /// The caption's lines at the figure's width.
    fn caption_lines(&self) -> Vec<String> {
        wrap(&self.caption, fits(WIDTH - 24))
    }

    /// The legend's entries: (the series, or None for a level; its label's lines).
    fn legend(&self) -> Vec<(Option<&Series>, Option<&Level>, Vec<String>)> {
        let chars = fits(WIDTH - CHART_WIDTH - (SAMPLE.0 + SAMPLE.1) as u32 - 10);
        self.series
            .iter()
            .filter(|s| !s.points.is_empty())
            .map(|s| (Some(s), None, wrap(&s.label, chars)))
            .chain(
                self.levels
                    .iter()
                    .map(|l| (None, Some(l), wrap(&l.label, chars))),
            )
            .collect()
    }

    /// The chart's height: [`CHART_HEIGHT`], or more for a long legend.
    fn chart_height(&self) -> u32 {
        let legend: u32 = self
            .legend()
            .iter()
            .map(|e| LINE * e.2.len() as u32 + 6)
            .sum();
        CHART_HEIGHT.max(LEGEND_TOP + legend + 12)
    }

    fn size(&self) -> (u32, u32) {
        (
            WIDTH,
            self.chart_height() + LINE * self.caption_lines().len() as u32 + 12,
        )
    }

    /// The ticks of both axes over every point that can be drawn (finite, positive on
    /// a log axis) and, on y, the levels.
    fn ticks(&self) -> Result<(Ticks, Ticks), PlotError> {
        let usable =
            |axis: &Axis, v: f64| v.is_finite() && (axis.scale == Scale::Linear || v > 0.0);
        let none = || PlotError::NoData(self.title.clone());
        let pts: Vec<(f64, f64)> = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().copied())
            .filter(|p| usable(&self.x, p.0) && usable(&self.y, p.1))
            .collect();
        if pts.is_empty() {
            return Err(none());
        }
        let x = axis_ticks(&self.x, pts.iter().map(|p| p.0)).ok_or_else(none)?;
        let ys = pts
            .iter()
            .map(|p| p.1)
            .chain(self.levels.iter().map(|l| l.y));
        let y = axis_ticks(&self.y, ys).ok_or_else(none)?;
        Ok((x, y))
    }
}

fn axis_ticks(axis: &Axis, values: impl Iterator<Item = f64>) -> Option<Ticks> {
    match axis.scale {
        Scale::Log => log_ticks(values),
        Scale::Linear => linear_ticks(values, true),
    }
}

/// Every how many ticks to label so that labels `extent` px long (along the axis,
/// gap included) fit `ticks` over `axis_px`.
fn label_stride(ticks: &Ticks, axis_px: f64, extent: f64) -> usize {
    let span = ticks.range.1 - ticks.range.0;
    let step = match ticks.major.as_slice() {
        [a, b, ..] => b - a,
        _ => return 1,
    };
    let px = axis_px * step / span;
    ((extent / px).ceil() as usize).max(1)
}

/// A chart axis in plot coordinates (log10 of the value on a log axis) whose labelled
/// and grid positions are [`Ticks`]' (plotters' own numeric axes choose their own).
#[derive(Clone)]
struct TickAxis {
    range: (f64, f64),
    bold: Vec<f64>,
    light: Vec<f64>,
}

impl Ranged for TickAxis {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, v: &f64, limit: (i32, i32)) -> i32 {
        let t = (v - self.range.0) / (self.range.1 - self.range.0);
        limit.0 + ((limit.1 - limit.0) as f64 * t).round() as i32
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            self.light.clone()
        } else {
            self.bold.clone()
        }
    }

    fn range(&self) -> Range<f64> {
        self.range.0..self.range.1
    }
}

/// The drawing error of plotters as the report's.
fn plot_err<E: std::fmt::Debug>(e: E) -> PlotError {
    PlotError::Draw(format!("{e:?}"))
}

fn text_style(size: u32) -> TextStyle<'static> {
    (FAMILY, size).into_font().color(&BLACK)
}

/// Draw `fig` on `root`.
fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, fig: &Figure) -> Result<(), PlotError> {
    root.fill(&WHITE).map_err(plot_err)?;
    let (w, _) = fig.size();
    let (xt, yt) = fig.ticks()?;
    let chart_h = fig.chart_height();
    let chart_area = root.clone().shrink((0, 0), (CHART_WIDTH, chart_h));
    let legend_area = root.clone().shrink(
        (CHART_WIDTH, LEGEND_TOP),
        (w - CHART_WIDTH, chart_h - LEGEND_TOP),
    );
    draw_chart(&chart_area, fig, &xt, &yt)?;
    draw_legend(&legend_area, fig)?;
    let caption = text_style(FONT);
    for (i, line) in fig.caption_lines().iter().enumerate() {
        root.draw_text(line, &caption, (12, (chart_h + 4 + LINE * i as u32) as i32))
            .map_err(plot_err)?;
    }
    Ok(())
}

/// The title, axes, grid, tick labels and series.
fn draw_chart<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    fig: &Figure,
    xt: &Ticks,
    yt: &Ticks,
) -> Result<(), PlotError> {
    const MARGIN: u32 = 14;
    let (x_label_area, y_label_area) = (56u32, 86u32);
    let area = area
        .titled(&fig.title, text_style(TITLE_FONT))
        .map_err(plot_err)?;
    // the plotting area ChartBuilder leaves: the margins and label areas taken off
    let (w, h) = area.dim_in_pixel();
    let px_w = w.saturating_sub(2 * MARGIN + y_label_area).max(1);
    let px_h = h.saturating_sub(2 * MARGIN + x_label_area).max(1);
    // labels: the widest label plus 2 characters of gap along x; a line and a half
    // along y
    let label = |t: &Ticks, unit: Unit, p: f64| engineering(t.value(p), unit);
    let widest = xt
        .major
        .iter()
        .map(|p| label(xt, fig.x.unit, *p).chars().count())
        .max()
        .unwrap_or(1);
    let x_major = xt.thinned(label_stride(
        xt,
        px_w as f64,
        (widest + 2) as f64 * ADVANCE * FONT as f64,
    ));
    let y_major = yt.thinned(label_stride(yt, px_h as f64, 1.5 * FONT as f64));
    let (xu, yu) = (fig.x.unit, fig.y.unit);
    let (xs, ys) = (xt.clone(), yt.clone());
    let x_fmt = move |p: &f64| label(&xs, xu, *p);
    let y_fmt = move |p: &f64| label(&ys, yu, *p);
    let mut chart = ChartBuilder::on(&area)
        .margin(MARGIN)
        .x_label_area_size(x_label_area)
        .y_label_area_size(y_label_area)
        .build_cartesian_2d(
            TickAxis {
                range: xt.range,
                bold: x_major,
                light: xt.minor.clone(),
            },
            TickAxis {
                range: yt.range,
                bold: y_major,
                light: yt.minor.clone(),
            },
        )
        .map_err(plot_err)?;
    chart
        .configure_mesh()
        .x_desc(fig.x.desc.as_str())
        .y_desc(fig.y.desc.as_str())
        .label_style(text_style(FONT))
        .axis_desc_style(text_style(FONT))
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .bold_line_style(BLACK.mix(0.25))
        .light_line_style(BLACK.mix(0.07))
        .max_light_lines(10)
        .draw()
        .map_err(plot_err)?;
    let to = |p: &(f64, f64)| Some((xt.coord(p.0)?, yt.coord(p.1)?));
    for level in fig.levels.iter().filter(|l| l.band) {
        if let Some(y) = yt.coord(level.y) {
            let band = Rectangle::new(
                [(xt.range.0, yt.range.0), (xt.range.1, y)],
                BLACK.mix(0.08).filled(),
            );
            chart.draw_series(std::iter::once(band)).map_err(plot_err)?;
        }
    }
    // the Pareto front under every marker; the default solver (bold: a wider line and
    // larger markers) under the others, so a series that shares its errors (L-BFGS-B
    // on the heavy cantilever) shows on top of it with the default's edges in sight
    let rank = |s: &Series| match s.style {
        Style::Front => 0,
        Style::Line { bold: true } => 1,
        _ => 2,
    };
    let mut order: Vec<&Series> = fig.series.iter().collect();
    order.sort_by_key(|s| rank(s));
    for s in order {
        let pts: Vec<(f64, f64)> = s.points.iter().filter_map(to).collect();
        draw_series(&mut chart, s, pts)?;
    }
    for level in &fig.levels {
        if let Some(y) = yt.coord(level.y) {
            let dash = DashedLineSeries::new(
                vec![(xt.range.0, y), (xt.range.1, y)],
                8,
                6,
                RGBColor(90, 90, 90).stroke_width(2),
            );
            chart.draw_series(dash).map_err(plot_err)?;
        }
    }
    Ok(())
}

type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<TickAxis, TickAxis>>;

/// One series in plot coordinates `pts`.
fn draw_series<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    s: &Series,
    mut pts: Vec<(f64, f64)>,
) -> Result<(), PlotError> {
    let c = s.color;
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    match s.style {
        Style::Line { bold } => {
            let (width, radius) = if bold { (3, 5) } else { (2, 4) };
            chart
                .draw_series(LineSeries::new(pts.clone(), c.stroke_width(width)))
                .map_err(plot_err)?;
            chart
                .draw_series(pts.iter().map(|p| Circle::new(*p, radius, c.filled())))
                .map_err(plot_err)?;
        }
        Style::Plain => {
            chart
                .draw_series(LineSeries::new(pts, c.stroke_width(2)))
                .map_err(plot_err)?;
        }
        Style::Dashed => {
            chart
                .draw_series(DashedLineSeries::new(pts, 10, 6, c.stroke_width(2)))
                .map_err(plot_err)?;
        }
        Style::HollowCircle => {
            chart
                .draw_series(pts.iter().map(|p| Circle::new(*p, 6, c.stroke_width(2))))
                .map_err(plot_err)?;
        }
        Style::HollowSquare => {
            chart
                .draw_series(pts.iter().map(|p| {
                    EmptyElement::at(*p) + Rectangle::new([(-5, -5), (5, 5)], c.stroke_width(2))
                }))
                .map_err(plot_err)?;
        }
        Style::Front => {
            let mut stairs = Vec::new();
            for (i, p) in pts.iter().enumerate() {
                if i > 0 {
                    stairs.push((p.0, pts[i - 1].1));
                }
                stairs.push(*p);
            }
            chart
                .draw_series(std::iter::once(PathElement::new(
                    stairs,
                    c.mix(0.3).stroke_width(9),
                )))
                .map_err(plot_err)?;
            // a halo on each run of the front: a front of one run is seen too
            chart
                .draw_series(pts.iter().map(|p| Circle::new(*p, 10, c.mix(0.3).filled())))
                .map_err(plot_err)?;
        }
    }
    Ok(())
}

/// The legend: one entry per series with points and per level, its sample drawn as in
/// the chart, its label wrapped to the legend's width.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    fig: &Figure,
) -> Result<(), PlotError> {
    let text = text_style(FONT);
    let (sample_w, gap) = SAMPLE;
    let mut y = 6i32;
    for (series, level, lines) in fig.legend() {
        let mid = y + (LINE as i32) / 2;
        let x0 = 2;
        match (series, level) {
            (Some(s), _) => legend_sample(area, s, (x0, mid), sample_w)?,
            (_, Some(l)) => {
                if l.band {
                    area.draw(&Rectangle::new(
                        [(x0, mid - 7), (x0 + sample_w, mid + 7)],
                        BLACK.mix(0.08).filled(),
                    ))
                    .map_err(plot_err)?;
                }
                for k in [0, 13, 26] {
                    area.draw(&PathElement::new(
                        vec![(x0 + k, mid), (x0 + k + 8, mid)],
                        RGBColor(90, 90, 90).stroke_width(2),
                    ))
                    .map_err(plot_err)?;
                }
            }
            _ => {}
        }
        for line in lines {
            area.draw_text(&line, &text, (x0 + sample_w + gap, y + 1))
                .map_err(plot_err)?;
            y += LINE as i32;
        }
        y += 6;
    }
    Ok(())
}

/// A series' legend sample: a short line, marker or band centred at `(x, y)`.
fn legend_sample<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    s: &Series,
    (x, y): (i32, i32),
    width: i32,
) -> Result<(), PlotError> {
    let c = s.color;
    let mid = (x + width / 2, y);
    let line = |style: ShapeStyle| PathElement::new(vec![(x, y), (x + width, y)], style);
    match s.style {
        Style::Line { bold } => {
            let (sw, r) = if bold { (3, 5) } else { (2, 4) };
            area.draw(&line(c.stroke_width(sw))).map_err(plot_err)?;
            area.draw(&Circle::new(mid, r, c.filled()))
                .map_err(plot_err)?;
        }
        Style::Plain => area.draw(&line(c.stroke_width(2))).map_err(plot_err)?,
        Style::Dashed => {
            for k in [0, 16] {
                area.draw(&PathElement::new(
                    vec![(x + k, y), (x + k + 10, y)],
                    c.stroke_width(2),
                ))
                .map_err(plot_err)?;
            }
        }
        Style::HollowCircle => area
            .draw(&Circle::new(mid, 6, c.stroke_width(2)))
            .map_err(plot_err)?,
        Style::HollowSquare => area
            .draw(&Rectangle::new(
                [(mid.0 - 5, y - 5), (mid.0 + 5, y + 5)],
                c.stroke_width(2),
            ))
            .map_err(plot_err)?,
        Style::Front => area
            .draw(&line(c.mix(0.3).stroke_width(9)))
            .map_err(plot_err)?,
    }
    Ok(())
}

/// `fig` as an SVG document.
pub(crate) fn svg(fig: &Figure) -> Result<String, PlotError> {
    register_font();
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, fig.size()).into_drawing_area();
        draw(&root, fig)?;
        root.present().map_err(plot_err)?;
    }
    Ok(out)
}

/// `fig` as a PNG file at `path`.
pub(crate) fn write_png(path: &Path, fig: &Figure) -> Result<(), PlotError> {
    register_font();
    let (w, h) = fig.size();
    let mut buf = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        draw(&root, fig)?;
        root.present().map_err(plot_err)?;
    }
    let file = std::fs::File::create(path).map_err(io(path))?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header()?;
    writer.write_image_data(&buf)?;
    writer.finish()?;
    Ok(())
}

/// Write `fig` as `<dir>/<stem>.png` and `<dir>/<stem>.svg`; returns the SVG (for
/// index.html, which inlines it).
pub(crate) fn write_figure(dir: &Path, stem: &str, fig: &Figure) -> Result<String, PlotError> {
    let svg = svg(fig)?;
    write_png(&dir.join(format!("{stem}.png")), fig)?;
    let path = dir.join(format!("{stem}.svg"));
    std::fs::write(&path, &svg).map_err(io(&path))?;
    Ok(svg)
}

/// A log-log plot of named series, each a line through filled markers, as a PNG (and
/// an SVG beside it): for measurements outside the report, such as the step time
/// against n of `cargo bench --bench ribbon -- step_vs_n` (examples/step_vs_n_plot.rs).
/// The axes' units are in their descriptions; ticks are plain numbers.
pub fn write_lines(
    path: &Path,
    title: &str,
    (x_desc, y_desc): (&str, &str),
    series: &[(String, Vec<(f64, f64)>)],
) -> Result<(), PlotError> {
    const PALETTE: [RGBColor; 5] = [
        RGBColor(31, 119, 180),
        RGBColor(214, 39, 40),
        RGBColor(44, 160, 44),
        RGBColor(148, 103, 189),
        RGBColor(127, 127, 127),
    ];
    let axis = |desc: &str| Axis {
        desc: desc.to_string(),
        unit: Unit::Count,
        scale: Scale::Log,
    };
    let fig = Figure {
        title: title.to_string(),
        x: axis(x_desc),
        y: axis(y_desc),
        series: series
            .iter()
            .enumerate()
            .map(|(i, (label, points))| Series {
                label: label.clone(),
                color: PALETTE[i % PALETTE.len()],
                points: points.clone(),
                style: Style::Line { bold: false },
            })
            .collect(),
        levels: Vec::new(),
        caption: String::new(),
    };
    write_png(path, &fig)?;
    let svg_path = path.with_extension("svg");
    std::fs::write(&svg_path, svg(&fig)?).map_err(io(&svg_path))
}

#[cfg(test)]
mod tests {
    use super::svg_check::{axis_labels, label_value, overlapping, text_boxes};
    use super::*;

    fn figure(series: Vec<Series>) -> Figure {
        Figure {
            title: "t".into(),
            x: Axis {
                desc: "run time".into(),
                unit: Unit::Second,
                scale: Scale::Log,
            },
            y: Axis {
                desc: "error".into(),
                unit: Unit::Metre,
                scale: Scale::Log,
            },
            series,
            levels: vec![Level {
                y: 1e-6,
                label: "a level".into(),
                band: true,
            }],
            caption: "Swept: something. ".repeat(30),
        }
    }

    fn line(label: &str, points: Vec<(f64, f64)>) -> Series {
        Series {
            label: label.into(),
            color: RGBColor(0, 0, 0),
            points,
            style: Style::Line { bold: false },
        }
    }

    /// Twelve decades on x and eleven on y: the x labels are thinned to every other
    /// decade, still decades, and no text overlaps, the long caption wrapped.
    #[test]
    fn many_decades_are_thinned_and_nothing_overlaps() {
        let fig = figure(vec![line("wide", vec![(1e-9, 1e-11), (1e3, 1.0)])]);
        let boxes = text_boxes(&svg(&fig).unwrap()).unwrap();
        assert!(overlapping(&boxes).is_empty(), "{:#?}", overlapping(&boxes));
        let (x, y) = axis_labels(&boxes);
        let values: Vec<f64> = x.iter().map(|b| label_value(&b.text).unwrap()).collect();
        assert!(values.len() >= 4, "{x:?}");
        let ratio = values[1] / values[0];
        assert!(ratio == 100.0 || ratio == 10.0, "{values:?}");
        for w in values.windows(2) {
            assert!((w[1] / w[0] / ratio - 1.0).abs() < 1e-9, "{values:?}");
        }
        assert!(y.len() >= 6, "{y:?}");
    }

    /// A legend longer than the chart makes the figure taller, not its text collide.
    #[test]
    fn a_long_legend_grows_the_figure() {
        let series: Vec<Series> = (0..30)
            .map(|i| {
                line(
                    &format!("series {i} with a long label"),
                    vec![(1.0, 1.0 + i as f64)],
                )
            })
            .collect();
        let fig = figure(series);
        assert!(fig.chart_height() > CHART_HEIGHT);
        let boxes = text_boxes(&svg(&fig).unwrap()).unwrap();
        assert!(overlapping(&boxes).is_empty());
        let bottom = boxes.iter().map(|b| b.y1).fold(0.0, f64::max);
        assert!(bottom <= fig.size().1 as f64, "{bottom} > {}", fig.size().1);
    }

    #[test]
    fn a_figure_without_a_drawable_point_is_refused() {
        let fig = figure(vec![line(
            "bad",
            vec![(0.0, 1.0), (1.0, f64::NAN), (-1.0, 2.0)],
        )]);
        let err = svg(&fig).unwrap_err();
        assert_eq!(err.to_string(), "t: no run to plot");
    }

    #[test]
    fn write_lines_writes_a_png_and_an_svg() {
        let dir = std::env::temp_dir().join(format!("plot_lines_test_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("lines.png");
        let series = [
            ("a".to_string(), vec![(50.0, 0.8), (100.0, 1.6)]),
            ("b".to_string(), vec![(50.0, 0.9), (100.0, 4.0)]),
        ];
        write_lines(&path, "t", ("n", "ms"), &series).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let svg = std::fs::read_to_string(dir.join("lines.svg")).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
        let texts: Vec<String> = text_boxes(&svg)
            .unwrap()
            .into_iter()
            .map(|b| b.text)
            .collect();
        assert!(
            texts.iter().any(|t| t == "a") && texts.iter().any(|t| t == "b"),
            "{texts:?}"
        );
    }
}
