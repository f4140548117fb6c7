//! The answer's figures (DESIGN.md §7): the lembo path's speed-up over the triangle path
//! against a target error ([`speedup_svg`]), and a one-at-a-time sensitivity as a tornado
//! chart ([`tornado_svg`]). Both take plain numbers: the sweep works them out.

use super::chart::{
    draw_legend, draw_mark, fmt_num, framed, log_axis, log_range, min_max, plot_size, svg, Entry,
    Mark, Plot, CHART_HEIGHT, FONT, LEMBO, PALETTE, TRIANGLE, WIDTH,
};
use crate::error::{Error, Result};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// What a speed-up figure shows.
pub struct SpeedupFigure<'a> {
    /// The scene's name.
    pub scene: &'a str,
    /// The metric in words, with its unit (`PSNR [dB]`).
    pub metric: &'a str,
    /// Whether a higher value of the metric is the stricter target.
    pub higher_is_stricter: bool,
    /// (target, triangle cycles over lembo cycles), loosest target first.
    pub cycles: &'a [(f64, f64)],
    /// (target, triangle energy over lembo energy).
    pub energy: &'a [(f64, f64)],
}

/// The speed-up of the lembo path (the triangle path's cost over the lembo path's) in
/// cycles and in energy against the target, on a log axis with 1 (a tie) marked, drawn as
/// steps: a value holds from the looser level before it up to its own. The x
/// axis is linear in dB for PSNR and logarithmic for the others; which side is stricter is
/// said on it.
pub fn speedup_svg(f: &SpeedupFigure) -> Result<String> {
    let entries = speedup_entries();
    let all = || f.cycles.iter().chain(f.energy);
    let ys = log_range(all().map(|p| p.1).chain([1.0]));
    let title = format!("{}: lembo speed-up against target {}", f.scene, f.metric);
    let stricter = if f.higher_is_stricter {
        "stricter to the right"
    } else {
        "stricter to the left"
    };
    let x_desc = format!("target {} ({stricter})", f.metric);
    let log_x = !f.higher_is_stricter;
    let xs: Vec<f64> = all().map(|p| p.0).filter(|x| !log_x || *x > 0.0).collect();
    if xs.is_empty() {
        return Err(Error::Internal(format!("{title}: no point to draw")));
    }
    let drawn = svg(plot_size(&entries), |root| {
        let (plot, legend) = root.split_vertically(CHART_HEIGHT);
        let mut builder = framed(&plot, &title, 22);
        let lines = [
            (f.cycles, LEMBO, Mark::Dot),
            (f.energy, PALETTE[0], Mark::Ring),
        ];
        macro_rules! draw {
            ($chart:expr) => {{
                let mut chart = $chart;
                chart
                    .configure_mesh()
                    .x_desc(x_desc.as_str())
                    .y_desc("lembo speed-up (triangle cost / lembo cost), log scale")
                    .x_label_formatter(&|v| fmt_num(*v))
                    .y_label_formatter(&|v| fmt_num(*v))
                    .label_style((FONT, 13))
                    .axis_desc_style((FONT, 15))
                    .draw()?;
                let (x0, x1) = min_max(xs.iter().copied());
                chart.draw_series(LineSeries::new(
                    [(x0, 1.0), (x1, 1.0)],
                    RGBColor(150, 150, 150).stroke_width(1),
                ))?;
                for (line, color, mark) in lines {
                    let pts: Vec<(f64, f64)> = line
                        .iter()
                        .copied()
                        .filter(|p| !log_x || p.0 > 0.0)
                        .collect();
                    chart.draw_series(LineSeries::new(step_points(&pts), color.stroke_width(2)))?;
                    for p in &pts {
                        draw_mark(root, chart.backend_coord(p), mark, color)?;
                    }
                }
            }};
        }
        if log_x {
            let range = log_range(xs.iter().copied());
            draw!(builder.build_cartesian_2d(log_axis(range), log_axis(ys.clone()))?);
        } else {
            let (lo, hi) = min_max(xs.iter().copied());
            let pad = ((hi - lo) * 0.05).max(0.5);
            draw!(builder.build_cartesian_2d((lo - pad)..(hi + pad), log_axis(ys.clone()))?);
        }
        draw_legend(&legend, &entries)
    });
    drawn_or_error(drawn, &title)
}

/// One bar of a tornado chart: a parameter, its low and high values and the speed-up at
/// each (None where the path did not reach the target there).
pub struct TornadoBar {
    /// The parameter (`arch.framebuffer.bytes_per_cycle`).
    pub param: String,
    /// Its low value, as written (`32`).
    pub low: String,
    /// Its high value.
    pub high: String,
    /// The speed-up with the low value.
    pub at_low: Option<f64>,
    /// The speed-up with the high value.
    pub at_high: Option<f64>,
}

/// A tornado chart: for each parameter a bar from the speed-up at its low value to the
/// speed-up at its high value, around the base's speed-up, widest first, on a log axis with
/// 1 (a tie) marked.
/// `measure` names the x axis's ratio (`triangle cycles / lembo cycles`).
pub fn tornado_svg(title: &str, measure: &str, base: f64, bars: &[TornadoBar]) -> Result<String> {
    let order = widest_first(bars, base);
    let entries = tornado_entries(base);
    let xs = log_range(
        bars.iter()
            .flat_map(|b| [b.at_low, b.at_high])
            .flatten()
            .chain([base, 1.0]),
    );
    let rows = order.len().max(1);
    let row_px = 34u32;
    let chart_h = (rows as u32 * row_px + 140).max(300);
    let (w, h) = plot_size(&entries);
    let size = (w.max(WIDTH), h - CHART_HEIGHT + chart_h);
    let drawn = svg(size, |root| {
        let (plot, legend) = root.split_vertically(chart_h);
        let mut chart = ChartBuilder::on(&plot)
            .caption(title, (FONT, 20))
            .margin(20)
            .x_label_area_size(50)
            .y_label_area_size(330)
            .build_cartesian_2d(log_axis(xs.clone()), 0.0..rows as f64)?;
        chart
            .configure_mesh()
            .disable_y_mesh()
            .y_labels(0)
            .x_desc(format!(
                "lembo advantage at the target ({measure}), log scale"
            ))
            .x_label_formatter(&|v| fmt_num(*v))
            .label_style((FONT, 13))
            .axis_desc_style((FONT, 15))
            .draw()?;
        let text = |s: &str, at: (i32, i32), pos: Pos| {
            Text::new(
                s.to_string(),
                at,
                (FONT, 13).into_font().color(&BLACK).pos(pos),
            )
        };
        for (i, b) in order.iter().enumerate() {
            let y = rows as f64 - i as f64 - 0.5;
            for (v, color, label) in [
                (b.at_low, PALETTE[1], &b.low),
                (b.at_high, TRIANGLE, &b.high),
            ] {
                let Some(v) = v else { continue };
                chart.draw_series(std::iter::once(Rectangle::new(
                    [(base.min(v), y - 0.3), (base.max(v), y + 0.3)],
                    color.mix(0.7).filled(),
                )))?;
                let at = chart.backend_coord(&(v, y));
                let (hpos, dx) = if v >= base {
                    (HPos::Left, 4)
                } else {
                    (HPos::Right, -4)
                };
                root.draw(&text(
                    &format!("{label}: {}", fmt_num(v)),
                    (at.0 + dx, at.1),
                    Pos::new(hpos, VPos::Center),
                ))?;
            }
            let at = chart.backend_coord(&(xs.start, y));
            root.draw(&text(
                &bar_name(b),
                (at.0 - 8, at.1),
                Pos::new(HPos::Right, VPos::Center),
            ))?;
        }
        chart.draw_series(LineSeries::new(
            [(base, 0.0), (base, rows as f64)],
            BLACK.stroke_width(2),
        ))?;
        chart.draw_series(LineSeries::new(
            [(1.0, 0.0), (1.0, rows as f64)],
            RGBColor(150, 150, 150).stroke_width(1),
        ))?;
        draw_legend(&legend, &entries)
    });
    drawn_or_error(drawn, title)
}

/// The legend of a speed-up figure: its two series and the line at 1.
fn speedup_entries() -> Vec<Entry> {
    vec![
        Entry {
            mark: Some(Mark::Dot),
            line: true,
            color: LEMBO,
            label: "cycles: the triangle path's fewest over the lembo path's".into(),
            note: None,
        },
        Entry {
            mark: Some(Mark::Ring),
            line: true,
            color: PALETTE[0],
            label: "energy: the triangle path's least over the lembo path's".into(),
            note: None,
        },
        Entry {
            mark: None,
            line: true,
            color: RGBColor(150, 150, 150),
            label: "1: a tie; above it the lembo unit is ahead".into(),
            note: Some(
                "each path's cost at a target is its cheapest run reaching it within the area budget"
                    .into(),
            ),
        },
    ]
}

/// A series drawn as steps: a path's cost is constant between two measured levels and
/// changes at the stricter one, so a step at each point.
fn step_points(pts: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut steps: Vec<(f64, f64)> = Vec::with_capacity(2 * pts.len());
    for (i, p) in pts.iter().enumerate() {
        if i > 0 {
            steps.push((pts[i - 1].0, p.1));
        }
        steps.push(*p);
    }
    steps
}

/// The bars in the order a tornado draws them: the widest swing (in log speed-up, from
/// the base) first; a value not reached counts as the base.
fn widest_first(bars: &[TornadoBar], base: f64) -> Vec<&TornadoBar> {
    let mut order: Vec<&TornadoBar> = bars.iter().collect();
    let width = |b: &TornadoBar| {
        let lo = b.at_low.unwrap_or(base).ln();
        let hi = b.at_high.unwrap_or(base).ln();
        (lo - base.ln()).abs().max((hi - base.ln()).abs())
    };
    order.sort_by(|a, b| width(b).total_cmp(&width(a)));
    order
}

/// The legend of a tornado chart: the low and high values' bars and the base.
fn tornado_entries(base: f64) -> Vec<Entry> {
    vec![
        Entry {
            mark: Some(Mark::Square),
            line: false,
            color: PALETTE[1],
            label: "the parameter at its low value".into(),
            note: None,
        },
        Entry {
            mark: Some(Mark::Square),
            line: false,
            color: TRIANGLE,
            label: "the parameter at its high value".into(),
            note: None,
        },
        Entry {
            mark: None,
            line: true,
            color: BLACK,
            label: format!("the base: {}x", fmt_num(base)),
            note: Some("grey line: 1, a tie; right of it the lembo unit is ahead".into()),
        },
    ]
}

/// A bar's label: its parameter, and the ends at which the path did not reach the target.
fn bar_name(b: &TornadoBar) -> String {
    let missing: Vec<&str> = [(b.at_low, "low"), (b.at_high, "high")]
        .iter()
        .filter(|(v, _)| v.is_none())
        .map(|(_, s)| *s)
        .collect();
    if missing.is_empty() {
        b.param.clone()
    } else {
        format!("{} (not reached at {})", b.param, missing.join(", "))
    }
}

/// A figure's SVG text, or an internal error naming the figure `title`.
fn drawn_or_error(drawn: Plot, title: &str) -> Result<String> {
    match drawn {
        Some(Ok(s)) => Ok(s),
        Some(Err(e)) => Err(Error::Internal(format!("drawing {title}: {e}"))),
        None => Err(Error::Internal(format!("drawing {title}: nothing drawn"))),
    }
}
