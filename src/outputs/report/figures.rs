//! The report's figures as inline SVG (plotters' SVG backend into a
//! string), scaled to the page's width by their view box: readable on a
//! phone's 390 px and in print.

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// The drawing size in SVG units; the page scales it to its width.
const SIZE: (u32, u32) = (600, 380);
const FONT: u32 = 20;
const GREY: RGBColor = RGBColor(150, 150, 150);
const HIGHLIGHT: RGBColor = RGBColor(20, 80, 200);
const ALARM: RGBColor = RGBColor(200, 30, 30);
const SHADE: RGBColor = RGBColor(255, 215, 215);

/// A point of a scatter figure: x, y, an optional ±bar (lower, upper) and
/// how it is drawn.
pub struct Marked {
    pub x: f64,
    pub y: f64,
    pub bar: Option<(f64, f64)>,
    pub mark: Mark,
}

#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Mark {
    /// An earlier or later event: grey dot.
    Other,
    /// An alarmed event: red dot.
    Alarmed,
    /// The event the report is of: large blue dot (red when alarmed).
    This { alarmed: bool },
    /// The band the earlier events predict at this event's amplitude: a
    /// bar with a diamond at the prediction.
    Band,
    /// The updated model's value: open square.
    Model,
}

/// A value against amplitude (log axis), optionally on a log y axis.
pub fn scatter(points: &[Marked], x_label: &str, y_label: &str, log_y: bool) -> String {
    let finite: Vec<&Marked> = points.iter().filter(|p| p.x > 0.0 && p.y.is_finite()).collect();
    let (mut x0, mut x1) = finite
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.x), b.max(p.x)));
    let (mut y0, mut y1) = finite.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
        let (lo, hi) = p.bar.unwrap_or((p.y, p.y));
        (a.min(lo.min(p.y)), b.max(hi.max(p.y)))
    });
    if finite.is_empty() {
        (x0, x1, y0, y1) = (0.1, 1.0, 0.0, 1.0);
    }
    let (x0, x1) = (x0 / 1.6, x1 * 1.6);
    canvas(|root| {
        if log_y && y0 > 0.0 {
            let (y0, y1) = (y0 / 1.3, y1 * 1.3);
            let chart = axes(root, (x0..x1).log_scale(), (y0..y1).log_scale(), x_label, y_label);
            chart.and_then(|mut c| draw_marks(&mut c, &finite))
        } else {
            let pad = ((y1 - y0) * 0.15).max(y1.abs() * 0.02).max(1e-12);
            let chart = axes(root, (x0..x1).log_scale(), (y0 - pad)..(y1 + pad), x_label, y_label);
            chart.and_then(|mut c| draw_marks(&mut c, &finite))
        }
    })
}

/// A figure drawn by `draw` on a white canvas of [`SIZE`], as SVG scaled
/// to its container; a note in its place when `draw` could not draw it.
fn canvas(draw: impl FnOnce(&Root<'_>) -> Option<()>) -> String {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        let _ = root.fill(&WHITE);
        if draw(&root).is_none() {
            let _ = root.draw(&Text::new(
                "(figure could not be drawn)",
                (20, 20),
                ("sans-serif", FONT),
            ));
        }
        let _ = root.present();
    }
    responsive(svg)
}

type Root<'s> = DrawingArea<SVGBackend<'s>, plotters::coord::Shift>;

type Chart<'r, 's, X, Y> = ChartContext<'r, SVGBackend<'s>, Cartesian2d<X, Y>>;

fn axes<'r, 's, X, Y>(
    root: &'r Root<'s>,
    x: X,
    y: Y,
    x_label: &str,
    y_label: &str,
) -> Option<Chart<'r, 's, X::CoordDescType, Y::CoordDescType>>
where
    X: plotters::coord::ranged1d::AsRangedCoord<Value = f64>,
    Y: plotters::coord::ranged1d::AsRangedCoord<Value = f64>,
    X::CoordDescType: plotters::coord::ranged1d::ValueFormatter<f64>,
    Y::CoordDescType: plotters::coord::ranged1d::ValueFormatter<f64>,
{
    let mut chart = ChartBuilder::on(root)
        .margin(14)
        .x_label_area_size(48)
        .y_label_area_size(78)
        .build_cartesian_2d(x, y)
        .ok()?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .label_style(("sans-serif", FONT))
        .axis_desc_style(("sans-serif", FONT))
        .x_labels(5)
        .y_labels(5)
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .light_line_style(WHITE)
        .draw()
        .ok()?;
    Some(chart)
}

fn draw_marks<X, Y>(chart: &mut Chart<'_, '_, X, Y>, points: &[&Marked]) -> Option<()>
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    // Others first, then the band, then this event on top.
    let order = |m: Mark| match m {
        Mark::Other => 0,
        Mark::Alarmed => 1,
        Mark::Model => 2,
        Mark::Band => 3,
        Mark::This { .. } => 4,
    };
    let mut sorted: Vec<&&Marked> = points.iter().collect();
    sorted.sort_by_key(|p| order(p.mark));
    for p in sorted {
        let colour = match p.mark {
            Mark::Other => GREY,
            Mark::Alarmed | Mark::This { alarmed: true } => ALARM,
            Mark::This { alarmed: false } | Mark::Model => HIGHLIGHT,
            Mark::Band => BLACK,
        };
        if let Some((lo, hi)) = p.bar {
            let width = if p.mark == Mark::Band { 3 } else { 1 };
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(p.x, lo), (p.x, hi)],
                    colour.stroke_width(width),
                )))
                .ok()?;
        }
        match p.mark {
            Mark::Other | Mark::Alarmed => {
                chart
                    .draw_series(std::iter::once(Circle::new((p.x, p.y), 4, colour.filled())))
                    .ok()?;
            }
            Mark::This { .. } => {
                chart
                    .draw_series(std::iter::once(Circle::new((p.x, p.y), 7, colour.filled())))
                    .ok()?;
            }
            Mark::Model => {
                let square = EmptyElement::at((p.x, p.y)) + Rectangle::new([(-5, -5), (5, 5)], colour.stroke_width(2));
                chart.draw_series(std::iter::once(square)).ok()?;
            }
            Mark::Band => {
                let diamond = EmptyElement::at((p.x, p.y))
                    + Polygon::new(vec![(0, -6), (6, 0), (0, 6), (-6, 0)], colour.stroke_width(2));
                chart.draw_series(std::iter::once(diamond)).ok()?;
            }
        }
    }
    Some(())
}

/// A series over time: x in hours from the period's start, the value with
/// an optional ±2σ band, horizontal limit lines, and spans (x from, x to)
/// shaded as alarmed.
pub struct Series<'a> {
    pub points: &'a [(f64, f64)],
    /// The lower and upper edges of a band around the points (same x).
    pub band: Option<&'a [(f64, f64, f64)]>,
    /// Second series drawn dashed (a limit that changes with time).
    pub limit: Option<&'a [(f64, f64)]>,
    pub alarmed: &'a [(f64, f64)],
    pub log_y: bool,
}

pub fn over_time(s: &Series, x_label: &str, y_label: &str) -> String {
    let x1 = s.points.iter().map(|p| p.0).fold(1e-9, f64::max);
    let ys = s
        .points
        .iter()
        .map(|p| p.1)
        .chain(s.band.into_iter().flatten().flat_map(|b| [b.1, b.2]))
        .chain(s.limit.into_iter().flatten().map(|p| p.1))
        .filter(|y| y.is_finite() && (!s.log_y || *y > 0.0));
    let (mut y0, mut y1) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| (a.min(y), b.max(y)));
    if y0 > y1 {
        (y0, y1) = (0.1, 1.0);
    }
    canvas(|root| {
        if s.log_y {
            axes(root, 0.0..x1, (y0 / 1.5..y1 * 1.5).log_scale(), x_label, y_label)
                .and_then(|mut c| draw_series(&mut c, s, y0 / 1.5, y1 * 1.5))
        } else {
            let pad = ((y1 - y0) * 0.1).max(y1.abs() * 0.01).max(1e-12);
            axes(root, 0.0..x1, (y0 - pad)..(y1 + pad), x_label, y_label)
                .and_then(|mut c| draw_series(&mut c, s, y0 - pad, y1 + pad))
        }
    })
}

fn draw_series<X, Y>(chart: &mut Chart<'_, '_, X, Y>, s: &Series, y0: f64, y1: f64) -> Option<()>
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    chart
        .draw_series(
            s.alarmed
                .iter()
                .map(|&(a, b)| Rectangle::new([(a, y0), (b, y1)], SHADE.filled())),
        )
        .ok()?;
    if let Some(band) = s.band {
        let mut outline: Vec<(f64, f64)> = band.iter().map(|b| (b.0, b.2)).collect();
        outline.extend(band.iter().rev().map(|b| (b.0, b.1)));
        chart
            .draw_series(std::iter::once(Polygon::new(outline, HIGHLIGHT.mix(0.2).filled())))
            .ok()?;
    }
    if let Some(limit) = s.limit {
        chart
            .draw_series(DashedLineSeries::new(
                limit.iter().copied(),
                6,
                4,
                ALARM.stroke_width(2),
            ))
            .ok()?;
    }
    let finite = s
        .points
        .iter()
        .copied()
        .filter(|p| p.1.is_finite() && (p.1 > 0.0 || !s.log_y));
    chart
        .draw_series(LineSeries::new(finite, HIGHLIGHT.stroke_width(2)))
        .ok()?;
    Some(())
}

/// Two bars per category (the forecast's and the baseline's), categories
/// along x.
pub fn paired_bars(categories: &[String], first: &[f64], second: &[f64], y_label: &str) -> String {
    let top = first
        .iter()
        .chain(second)
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max)
        .max(1e-9)
        * 1.15;
    let n = categories.len().max(1);
    canvas(|root| {
        let mut chart = ChartBuilder::on(root)
            .margin(14)
            .x_label_area_size(48)
            .y_label_area_size(78)
            .build_cartesian_2d(0.0..n as f64, 0.0..top)
            .ok()?;
        chart
            .configure_mesh()
            .disable_x_mesh()
            .light_line_style(WHITE)
            .x_labels(0)
            .y_label_formatter(&|v| tick(*v))
            .y_desc(y_label)
            .label_style(("sans-serif", FONT))
            .axis_desc_style(("sans-serif", FONT))
            .draw()
            .ok()?;
        let under = ("sans-serif", FONT)
            .into_font()
            .color(&BLACK)
            .pos(Pos::new(HPos::Center, VPos::Top));
        chart
            .draw_series(categories.iter().enumerate().map(|(k, name)| {
                EmptyElement::at((k as f64 + 0.5, 0.0)) + Text::new(name.clone(), (0, 8), under.clone())
            }))
            .ok()?;
        for (k, (&a, &b)) in first.iter().zip(second).enumerate() {
            let x = k as f64;
            // The first value's bar on the left half of its slot, the second's on the right.
            for (value, from, colour) in [(a, 0.12, HIGHLIGHT), (b, 0.52, GREY)] {
                if value.is_finite() {
                    chart
                        .draw_series(std::iter::once(Rectangle::new(
                            [(x + from, 0.0), (x + from + 0.36, value)],
                            colour.filled(),
                        )))
                        .ok()?;
                }
            }
        }
        Some(())
    })
}

/// An axis tick: short, whatever the magnitude.
fn tick(v: f64) -> String {
    super::html::number(Some(v), 3)
}

/// The SVG scaled to its container's width (its view box kept).
fn responsive(svg: String) -> String {
    let (w, h) = SIZE;
    svg.replacen(
        &format!("width=\"{w}\" height=\"{h}\""),
        "width=\"100%\" preserveAspectRatio=\"xMidYMid meet\" role=\"img\"",
        1,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_figure_scales_to_its_container() {
        let svg = scatter(
            &[Marked {
                x: 0.5,
                y: 3.4,
                bar: Some((3.3, 3.5)),
                mark: Mark::This { alarmed: false },
            }],
            "ground peak (m/s²)",
            "frequency (Hz)",
            false,
        );
        assert!(svg.starts_with("<svg"), "{}", &svg[..80.min(svg.len())]);
        assert!(
            svg.contains("viewBox=\"0 0 600 380\""),
            "{}",
            &svg[..200.min(svg.len())]
        );
        assert!(svg.contains("width=\"100%\""));
        assert!(svg.contains("<circle"));
    }
}
