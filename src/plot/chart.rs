//! How a sweep plot is drawn: one SVG per plot, the paths' colours and the series' palette
//! and markers, legends below the chart, log axes with ticks at 1, 2 and 5, axis meshes, and
//! numbers as the labels print them. Shared by every plot ([`super::error`] and the plots of
//! cycles in `mod.rs`).

use plotters::coord::combinators::WithKeyPoints;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use serde_json::Value;
use std::ops::Range;

pub(super) type DrawResult = std::result::Result<(), Box<dyn std::error::Error>>;

pub(super) type Plot = Option<std::result::Result<String, Box<dyn std::error::Error>>>;

pub(super) type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;

/// Draws one SVG of `size` pixels.
pub(super) fn svg(size: (u32, u32), draw: impl FnOnce(&Area) -> DrawResult) -> Plot {
    let mut out = String::new();
    let drawn = (|| -> DrawResult {
        let root = SVGBackend::with_string(&mut out, size).into_drawing_area();
        root.fill(&WHITE)?;
        draw(&root)?;
        root.present()?;
        Ok(())
    })();
    Some(drawn.map(|()| out))
}

pub(super) const FONT: &str = "sans-serif";

/// Width of every plot and height of the chart above its legend \[px\].
pub(super) const WIDTH: u32 = 900;

pub(super) const CHART_HEIGHT: u32 = 600;

pub(super) const LEMBO: RGBColor = RGBColor(31, 119, 180);

pub(super) const TRIANGLE: RGBColor = RGBColor(214, 39, 40);

/// Series colours other than the two paths' (the tab10 palette, less its blue and red).
pub(super) const PALETTE: [RGBColor; 8] = [
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// A series' point marker. Series differ in shape as well as colour, so one drawn over
/// another (equal cycles in f32 and f64, say) still shows.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Mark {
    Dot,
    Ring,
    Cross,
    Triangle,
    Square,
}

pub(super) const MARKS: [Mark; 5] = [
    Mark::Dot,
    Mark::Ring,
    Mark::Cross,
    Mark::Triangle,
    Mark::Square,
];

/// One line of a legend: a marker (none for a plain note), a line through it or not, the
/// label and an optional second line.
pub(super) struct Entry {
    pub(super) mark: Option<Mark>,
    pub(super) line: bool,
    pub(super) color: RGBColor,
    pub(super) label: String,
    pub(super) note: Option<String>,
}

impl Entry {
    pub(super) fn height(&self) -> u32 {
        if self.note.is_some() {
            38
        } else {
            20
        }
    }
}

/// Draws a marker centred on `at`, in `area`'s pixel coordinates.
pub(super) fn draw_mark(area: &Area, at: (i32, i32), mark: Mark, color: RGBColor) -> DrawResult {
    let (x, y) = at;
    match mark {
        Mark::Dot => area.draw(&Circle::new(at, 4, color.filled()))?,
        Mark::Ring => area.draw(&Circle::new(at, 5, color.stroke_width(2)))?,
        Mark::Cross => area.draw(&Cross::new(at, 5, color.stroke_width(2)))?,
        Mark::Triangle => area.draw(&TriangleMarker::new(at, 6, color.filled()))?,
        Mark::Square => area.draw(&Rectangle::new(
            [(x - 4, y - 4), (x + 4, y + 4)],
            color.filled(),
        ))?,
    }
    Ok(())
}

/// Draws a legend into `area` (below the chart, so it never hides a point), one entry a line.
pub(super) fn draw_legend(area: &Area, entries: &[Entry]) -> DrawResult {
    let x = 60;
    let mut y = 10;
    for e in entries {
        if e.line {
            area.draw(&PathElement::new(
                vec![(x - 14, y), (x + 14, y)],
                e.color.stroke_width(2),
            ))?;
        }
        if let Some(mark) = e.mark {
            draw_mark(area, (x, y), mark, e.color)?;
        }
        let text = |s: &str, y: i32| {
            Text::new(
                s.to_string(),
                (x + 24, y),
                (FONT, 13)
                    .into_font()
                    .color(&BLACK)
                    .pos(Pos::new(HPos::Left, VPos::Center)),
            )
        };
        area.draw(&text(&e.label, y))?;
        if let Some(note) = &e.note {
            area.draw(&text(note, y + 18))?;
        }
        y += e.height() as i32;
    }
    Ok(())
}

/// The chart and legend areas of a plot whose legend has `entries`.
pub(super) fn plot_size(entries: &[Entry]) -> (u32, u32) {
    let legend: u32 = entries.iter().map(Entry::height).sum();
    (WIDTH, CHART_HEIGHT + legend + 10)
}

/// A log axis over `range` with ticks at 1, 2 and 5 per decade, or at every digit when that
/// gives fewer than four (plotters' own log axis labels only powers of ten).
pub(super) fn log_axis(range: Range<f64>) -> WithKeyPoints<LogCoord<f64>> {
    let ticks = |mantissas: &[f64]| -> Vec<f64> {
        let first = range.start.log10().floor() as i32;
        let last = range.end.log10().ceil() as i32;
        (first..=last)
            .flat_map(|e| mantissas.iter().map(move |m| m * 10f64.powi(e)))
            .filter(|v| range.contains(v))
            .collect()
    };
    let every = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0];
    let light = ticks(&every);
    let bold = [&[1.0][..], &[1.0, 2.0, 5.0]]
        .iter()
        .map(|m| ticks(m))
        .find(|t| t.len() >= 4)
        .unwrap_or_else(|| light.clone());
    range
        .clone()
        .log_scale()
        .with_key_points(bold)
        .with_light_points(light)
}

/// Draws the mesh of `chart` with its axis descriptions, numbers in [`fmt_num`].
pub(super) fn mesh<'a, X, Y>(
    chart: &mut ChartContext<'a, SVGBackend<'a>, Cartesian2d<X, Y>>,
    x_desc: &str,
    y_desc: &str,
) -> DrawResult
where
    X: Ranged<ValueType = f64> + plotters::coord::ranged1d::ValueFormatter<f64>,
    Y: Ranged<ValueType = f64> + plotters::coord::ranged1d::ValueFormatter<f64>,
{
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .x_label_formatter(&|v| fmt_num(*v))
        .y_label_formatter(&|v| fmt_num(*v))
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 15))
        .draw()?;
    Ok(())
}

/// Draws each entry's line and marks into `chart`.
pub(super) fn draw_lines<'a, X>(
    root: &Area,
    chart: &mut ChartContext<'a, SVGBackend<'a>, Cartesian2d<X, RangedCoordf64>>,
    entries: &[Entry],
    lines: &[Vec<(f64, f64)>],
) -> DrawResult
where
    X: Ranged<ValueType = f64>,
{
    for (entry, line) in entries.iter().zip(lines) {
        chart.draw_series(LineSeries::new(
            line.iter().copied(),
            entry.color.stroke_width(2),
        ))?;
        if let Some(mark) = entry.mark {
            for p in line {
                draw_mark(root, chart.backend_coord(p), mark, entry.color)?;
            }
        }
    }
    Ok(())
}

pub(super) fn fmt_value(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        Value::Null => "-".into(),
        Value::Number(n) => n.as_f64().map(fmt_num).unwrap_or_else(|| n.to_string()),
        other => other.to_string(),
    }
}

/// Three significant digits with k, M or G for thousands: `52.5k`, `0.00255`.
pub fn fmt_num(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let (x, suffix) = match a {
        a if a >= 1e9 => (v / 1e9, "G"),
        a if a >= 1e6 => (v / 1e6, "M"),
        a if a >= 1e4 => (v / 1e3, "k"),
        _ => (v, ""),
    };
    if x.abs() < 1e-4 {
        return format!("{x:.2e}");
    }
    let digits = (2 - x.abs().log10().floor() as i32).clamp(0, 8) as usize;
    let mut s = format!("{x:.digits$}");
    if s.contains('.') {
        s = s.trim_end_matches('0').trim_end_matches('.').to_string();
    }
    s + suffix
}

/// An integer with its thousands apart: `103 273`.
pub(super) fn fmt_int(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(' ');
        }
        out.push(c);
    }
    out
}

/// A chart's builder on `plot` as every plot frames it: its caption at `size` points, a
/// margin of 20, label areas of 50 (x) and 80 (y).
pub(super) fn framed<'a, 'b>(
    plot: &'a Area<'b>,
    title: &str,
    size: u32,
) -> ChartBuilder<'a, 'b, SVGBackend<'b>> {
    let mut builder = ChartBuilder::on(plot);
    builder
        .caption(title, (FONT, size))
        .margin(20)
        .x_label_area_size(50)
        .y_label_area_size(80);
    builder
}

/// The smallest and the largest of `values` (infinities when there are none).
pub(super) fn min_max(values: impl Iterator<Item = f64>) -> (f64, f64) {
    values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    })
}

/// A log axis range around positive values, with a margin of a quarter on either side.
pub(super) fn log_range(values: impl Iterator<Item = f64>) -> Range<f64> {
    let (lo, hi) = min_max(values.filter(|v| *v > 0.0 && v.is_finite()));
    if !hi.is_finite() {
        return 0.1..10.0;
    }
    lo / 1.25..hi * 1.25
}
