//! The report's one log-log plot (work-precision and convergence plots): lines with
//! filled markers, hollow markers, an optional dashed level, a legend at the upper
//! right, written as a 900 x 600 px PNG.

use std::path::Path;

use plotters::prelude::*;

use super::report_error::{io, ReportError};

/// One series: drawn as a line through filled markers (`line`) or as hollow markers.
pub(super) struct Series {
    /// Legend entry (None: no entry).
    pub label: Option<String>,
    pub color: RGBColor,
    pub points: Vec<(f64, f64)>,
    pub line: bool,
}

/// What [`write_log_log`] draws.
pub(super) struct LogLogPlot<'a> {
    pub title: &'a str,
    pub x_desc: &'a str,
    pub y_desc: &'a str,
    pub series: Vec<Series>,
    /// A grey dashed horizontal line at this y, with its legend entry.
    pub level: Option<(f64, &'a str)>,
}

static FONT: std::sync::Once = std::sync::Once::new();

/// Plot labels use DejaVu Sans Mono embedded in the binary (assets/fonts): no
/// dependence on the machine's fonts, so every machine draws the same text.
fn register_font() {
    FONT.call_once(|| {
        let bytes: &'static [u8] = include_bytes!("../../assets/fonts/DejaVuSansMono.ttf");
        // a font that does not parse leaves text undrawn; the plot itself still renders
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, bytes);
    });
}

fn positive(p: &(f64, f64)) -> bool {
    p.0 > 0.0 && p.1 > 0.0
}

/// The axes' ranges: every positive finite point and the level, widened by 1.5 on
/// each side; then headroom for the legend (upper right, up to six entries of ~20 px
/// on a 540 px plot): the data keep the lower 70 % of the log y range, so the
/// expensive, inaccurate runs (top right) stay visible below it.
fn ranges(plot: &LogLogPlot) -> Result<(f64, f64, f64, f64), ReportError> {
    let all: Vec<(f64, f64)> = plot
        .series
        .iter()
        .flat_map(|s| s.points.iter().copied())
        .filter(|p| positive(p) && p.0.is_finite() && p.1.is_finite())
        .collect();
    if all.is_empty() {
        return Err(ReportError::Invalid(format!(
            "{}: no run to plot",
            plot.title
        )));
    }
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for (x, y) in &all {
        x0 = x0.min(*x);
        x1 = x1.max(*x);
        y0 = y0.min(*y);
        y1 = y1.max(*y);
    }
    if let Some((e, _)) = plot.level {
        y0 = y0.min(e);
        y1 = y1.max(e);
    }
    let (x0, x1, y0, y1) = (x0 / 1.5, x1 * 1.5, y0 / 1.5, y1 * 1.5);
    Ok((x0, x1, y0, y1 * (y1 / y0).powf(0.43)))
}

/// Draw `plot` into an RGB buffer of `w` x `h` px.
fn draw(plot: &LogLogPlot, buf: &mut [u8], (w, h): (u32, u32)) -> Result<(), ReportError> {
    let (x0, x1, y0, y1) = ranges(plot)?;
    let err = |e: DrawingAreaErrorKind<_>| ReportError::Plot(format!("{e:?}"));
    let root = BitMapBackend::with_buffer(buf, (w, h)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(plot.title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(80)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(plot.x_desc)
        .y_desc(plot.y_desc)
        // 8 labels: at the default 10 the log axis labels every 100 from 600 to 1000 and they overlap
        .x_labels(8)
        .x_label_formatter(&|v| format!("{v:.2e}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()
        .map_err(err)?;
    for s in &plot.series {
        let c = s.color;
        let mut pts: Vec<(f64, f64)> = s.points.iter().copied().filter(positive).collect();
        if !s.line {
            chart
                .draw_series(pts.iter().map(|p| Circle::new(*p, 6, c.stroke_width(2))))
                .map_err(err)?;
            continue;
        }
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        let line = chart
            .draw_series(LineSeries::new(pts.clone(), c.stroke_width(2)))
            .map_err(err)?;
        if let Some(label) = &s.label {
            line.label(label.as_str()).legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
            });
        }
        chart
            .draw_series(pts.iter().map(|p| Circle::new(*p, 4, c.filled())))
            .map_err(err)?;
    }
    if let Some((e, label)) = plot.level {
        let grey = RGBColor(120, 120, 120);
        // dashed: segments over every other twentieth of the log x range
        let (lx0, lx1) = (x0.ln(), x1.ln());
        let dashes = (0..20).step_by(2).map(move |k| {
            let a = (lx0 + (lx1 - lx0) * k as f64 / 20.0).exp();
            let b = (lx0 + (lx1 - lx0) * (k + 1) as f64 / 20.0).exp();
            PathElement::new(vec![(a, e), (b, e)], grey.stroke_width(1))
        });
        chart
            .draw_series(dashes)
            .map_err(err)?
            .label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], grey));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(err)?;
    root.present().map_err(err)
}

/// Draw `plot` and write it to `path` as a PNG.
pub(super) fn write_log_log(path: &Path, plot: &LogLogPlot) -> Result<(), ReportError> {
    register_font();
    let (w, h) = (900u32, 600u32);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    draw(plot, &mut buf, (w, h))?;
    let file = std::fs::File::create(path).map_err(io("cannot write", path))?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header()?;
    writer.write_image_data(&buf)?;
    writer.finish()?;
    Ok(())
}

/// A log-log plot of named series, each a line through filled markers, as a 900 x 600
/// px PNG: for measurements outside the report, such as the step time against n of
/// `cargo bench --bench ribbon -- step_vs_n` (examples/step_vs_n_plot.rs).
pub fn write_lines(
    path: &Path,
    title: &str,
    (x_desc, y_desc): (&str, &str),
    series: &[(String, Vec<(f64, f64)>)],
) -> Result<(), ReportError> {
    const PALETTE: [RGBColor; 5] = [
        RGBColor(31, 119, 180),
        RGBColor(214, 39, 40),
        RGBColor(44, 160, 44),
        RGBColor(148, 103, 189),
        RGBColor(127, 127, 127),
    ];
    let series = series
        .iter()
        .enumerate()
        .map(|(i, (label, points))| Series {
            label: Some(label.clone()),
            color: PALETTE[i % PALETTE.len()],
            points: points.clone(),
            line: true,
        })
        .collect();
    let plot = LogLogPlot {
        title,
        x_desc,
        y_desc,
        series,
        level: None,
    };
    write_log_log(path, &plot)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plot(points: Vec<(f64, f64)>, level: Option<(f64, &str)>) -> LogLogPlot<'_> {
        LogLogPlot {
            title: "t",
            x_desc: "x",
            y_desc: "y",
            series: vec![Series {
                label: Some("a".into()),
                color: RGBColor(0, 0, 0),
                points,
                line: true,
            }],
            level,
        }
    }

    #[test]
    fn ranges_widen_the_data_and_the_level_and_leave_legend_room() {
        let (x0, x1, y0, y1) =
            ranges(&plot(vec![(1.0, 1e-3), (10.0, 1e-2)], Some((1e-4, "l")))).unwrap();
        assert_eq!((x0, x1, y0), (1.0 / 1.5, 15.0, 1e-4 / 1.5));
        let top = 1e-2 * 1.5;
        assert_eq!(y1, top * (top / y0).powf(0.43));
    }

    #[test]
    fn a_plot_without_a_positive_finite_point_is_refused_and_one_with_is_written() {
        let bad = plot(vec![(0.0, 1.0), (1.0, f64::NAN), (-1.0, 2.0)], None);
        let dir = std::env::temp_dir().join(format!("plot_test_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("p.png");
        let err = write_log_log(&path, &bad).unwrap_err();
        assert_eq!(err.to_string(), "t: no run to plot");
        assert!(!path.exists());
        write_log_log(&path, &plot(vec![(1.0, 1e-3), (2.0, 5e-4)], None)).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    }

    #[test]
    fn write_lines_draws_every_series_and_refuses_an_empty_plot() {
        let dir = std::env::temp_dir().join(format!("plot_lines_test_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("lines.png");
        let axes = ("n", "ms");
        let err = write_lines(&path, "empty", axes, &[]).unwrap_err();
        assert_eq!(err.to_string(), "empty: no run to plot");
        let series = [
            ("a".to_string(), vec![(50.0, 0.8), (100.0, 1.6)]),
            ("b".to_string(), vec![(50.0, 0.9), (100.0, 4.0)]),
        ];
        write_lines(&path, "t", axes, &series).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    }
}
