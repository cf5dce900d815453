//! Line and scatter charts as SVG (plotters), for reports.

use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mark {
    /// A solid line.
    Line,
    /// Circles at the points.
    Points,
    /// Both.
    LinePoints,
    /// Open rings, larger than `Points`: shows a second series that lies on
    /// top of a first.
    Rings,
}

/// One labelled series.
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend text.
    pub label: String,
    /// `(x, y)` points.
    pub points: Vec<(f64, f64)>,
    /// How to draw it.
    pub mark: Mark,
}

impl Series {
    /// A series from labels and points.
    pub fn new(label: impl Into<String>, points: Vec<(f64, f64)>, mark: Mark) -> Self {
        Self {
            label: label.into(),
            points,
            mark,
        }
    }
}

/// One panel: axes, title and series.
#[derive(Clone, Debug, Default)]
pub struct Panel {
    /// Title.
    pub title: String,
    /// x-axis label.
    pub x_label: String,
    /// y-axis label.
    pub y_label: String,
    /// Logarithmic x axis.
    pub log_x: bool,
    /// Logarithmic y axis (non-positive values are dropped).
    pub log_y: bool,
    /// The series.
    pub series: Vec<Series>,
}

/// A plotting failure.
#[derive(Debug, thiserror::Error)]
#[error("plotting {path}: {message}")]
pub struct PlotError {
    path: String,
    message: String,
}

impl PlotError {
    /// A failure writing `path`.
    pub fn new(path: &Path, message: impl Into<String>) -> Self {
        Self {
            path: path.display().to_string(),
            message: message.into(),
        }
    }
}

const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
];

fn range(values: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && (!log || *v > 0.0))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return if log { (1e-16, 1.0) } else { (0.0, 1.0) };
    }
    if log {
        (lo / 2.0, hi * 2.0)
    } else {
        let pad = if hi > lo {
            0.05 * (hi - lo)
        } else {
            lo.abs().max(1.0) * 0.05
        };
        (lo - pad, hi + pad)
    }
}

/// Tick labels: `1.2e-3` on logarithmic axes (whole numbers such as box
/// sides stay plain), else up to three decimals without trailing zeros.
fn tick_label(log: bool) -> impl Fn(&f64) -> String {
    move |v: &f64| {
        if log && !(v.fract() == 0.0 && v.abs() < 1e5) {
            format!("{v:.1e}")
        } else {
            format!("{v:.3}")
                .trim_end_matches('0')
                .trim_end_matches('.')
                .to_string()
        }
    }
}

fn draw_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, p: &Panel) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let xs = range(
        p.series.iter().flat_map(|s| s.points.iter().map(|q| q.0)),
        p.log_x,
    );
    let ys = range(
        p.series.iter().flat_map(|s| s.points.iter().map(|q| q.1)),
        p.log_y,
    );
    let mut builder = ChartBuilder::on(area);
    builder
        .caption(&p.title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70);
    macro_rules! finish {
        ($chart:expr) => {{
            let mut chart = $chart;
            let x_fmt = tick_label(p.log_x);
            let y_fmt = tick_label(p.log_y);
            chart
                .configure_mesh()
                .x_desc(p.x_label.as_str())
                .y_desc(p.y_label.as_str())
                .x_label_formatter(&x_fmt)
                .y_label_formatter(&y_fmt)
                .y_labels(8)
                .light_line_style(WHITE.mix(0.0))
                .draw()
                .map_err(|e| e.to_string())?;
            let mut labelled = false;
            for (k, s) in p.series.iter().enumerate() {
                let colour = PALETTE[k % PALETTE.len()];
                let pts: Vec<(f64, f64)> = s
                    .points
                    .iter()
                    .copied()
                    .filter(|q| q.0.is_finite() && q.1.is_finite())
                    .filter(|q| (!p.log_x || q.0 > 0.0) && (!p.log_y || q.1 > 0.0))
                    .collect();
                // Nothing to draw, nothing to label; colours stay with the
                // series' position, so a run keeps its colour in every panel.
                if pts.is_empty() {
                    continue;
                }
                labelled = true;
                let legend_colour = colour;
                if matches!(s.mark, Mark::Line | Mark::LinePoints) {
                    chart
                        .draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))
                        .map_err(|e| e.to_string())?
                        .label(s.label.as_str())
                        .legend(move |(x, y)| {
                            PathElement::new(
                                vec![(x, y), (x + 16, y)],
                                legend_colour.stroke_width(2),
                            )
                        });
                }
                if s.mark == Mark::Rings {
                    chart
                        .draw_series(
                            pts.iter()
                                .map(|&q| Circle::new(q, 7, colour.stroke_width(2))),
                        )
                        .map_err(|e| e.to_string())?
                        .label(s.label.as_str())
                        .legend(move |(x, y)| {
                            Circle::new((x + 8, y), 6, legend_colour.stroke_width(2))
                        });
                }
                if matches!(s.mark, Mark::Points | Mark::LinePoints) {
                    let series = chart
                        .draw_series(pts.iter().map(|&q| Circle::new(q, 4, colour.filled())))
                        .map_err(|e| e.to_string())?;
                    if s.mark == Mark::Points {
                        series.label(s.label.as_str()).legend(move |(x, y)| {
                            Circle::new((x + 8, y), 4, legend_colour.filled())
                        });
                    }
                }
            }
            // A panel with nothing drawn gets no empty legend box.
            if labelled {
                chart
                    .configure_series_labels()
                    .background_style(WHITE.mix(0.8))
                    .border_style(BLACK)
                    .draw()
                    .map_err(|e| e.to_string())?;
            }
        }};
    }
    match (p.log_x, p.log_y) {
        (false, false) => finish!(builder
            .build_cartesian_2d(xs.0..xs.1, ys.0..ys.1)
            .map_err(|e| e.to_string())?),
        (false, true) => finish!(builder
            .build_cartesian_2d(xs.0..xs.1, (ys.0..ys.1).log_scale().base(2.0))
            .map_err(|e| e.to_string())?),
        (true, false) => finish!(builder
            .build_cartesian_2d((xs.0..xs.1).log_scale().base(2.0), ys.0..ys.1)
            .map_err(|e| e.to_string())?),
        (true, true) => finish!(builder
            .build_cartesian_2d(
                (xs.0..xs.1).log_scale().base(2.0),
                (ys.0..ys.1).log_scale().base(2.0)
            )
            .map_err(|e| e.to_string())?),
    }
    Ok(())
}

/// Writes `panels` side by side as one SVG file.
pub fn write_svg(path: &Path, panels: &[Panel]) -> Result<(), PlotError> {
    write_svg_rows(path, panels, panels.len())
}

/// [`write_svg`] with `columns` panels per row, filled row by row.
pub fn write_svg_rows(path: &Path, panels: &[Panel], columns: usize) -> Result<(), PlotError> {
    let err = |message: String| PlotError {
        path: path.display().to_string(),
        message,
    };
    let columns = columns.clamp(1, panels.len().max(1));
    let rows = panels.len().div_ceil(columns).max(1);
    // Drawn in memory, then written whole: a failure leaves no half plot.
    let mut svg = String::new();
    {
        let size = (560 * columns as u32, 420 * rows as u32);
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(e.to_string()))?;
        let areas = root.split_evenly((rows, columns));
        for (area, panel) in areas.iter().zip(panels) {
            draw_panel(area, panel).map_err(err)?;
        }
        root.present().map_err(|e| err(e.to_string()))?;
    }
    crate::whole_file::write_whole(path, svg.as_bytes()).map_err(|e| err(e.cause.to_string()))
}
