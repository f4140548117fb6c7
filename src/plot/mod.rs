//! Sweep plots: SVG figures drawn from a sweep's records (the lines of `results.jsonl`).
//!
//! Each record is one sweep point:
//! `{"index", "key", "scene", "params": {"path", "k", "arch.segmenter.count", ...}, "report"}`,
//! where `report` is a `report.json` object ([`crate::report::Report`]). For every scene,
//! [`write_plots`] draws whichever of these the records support:
//!
//! | file | x | y | series |
//! |---|---|---|---|
//! | `tradeoff_<scene>.svg` | frame time \[cycles\], log | RMS colour error [0-255], log | one per path, and the Pareto front (with an area budget: each path's front within it, larger units grey) |
//! | `error_vs_energy_<scene>.svg` | energy of the frame \[pJ\], log | RMS colour error [0-255], log | as `tradeoff` |
//! | `flip_tradeoff_<scene>.svg`, `flip_vs_energy_<scene>.svg` | as `tradeoff`, `error_vs_energy` | mean FLIP [0-1], log | as `tradeoff` (records that carry `accuracy.flip_mean`) |
//! | `cycles_vs_k_<scene>.svg` | k \[px\], log | frame time \[cycles\] | one per combination of the other varying parameters run at two k or more (lembo path) |
//! | `cycles_vs_units_<scene>.svg` | unit instances | frame time \[cycles\] | one per varying `arch.*.count`, the other parameters at their most common value (a parameter a point leaves at its default counts as the value its run used) |
//! | `cycles_vs_fifo_depth_<scene>.svg` | FIFO depth \[entries\], log | frame time \[cycles\] | one per varying `arch.links.*.fifo_depth`, as above |
//! | `utilisation_<scene>.svg` | share of the frame time [%] | unit | busy / starved / blocked bars at the most and the fewest cycles |
//!
//! A record whose report has no cycles (functional mode) takes part in no plot, and one
//! without accuracy (no reference) in no trade-off plot; neither is an error.
//!
//! Legends go below the chart, where they cannot hide a point. The SVG backend writes text
//! as `<text>` elements that the viewer lays out, so plotters places captions and tick
//! labels by its built-in size estimate instead of a font library: the spacing is
//! approximate, the text itself exact.
//!
//! Layout: this file the entry ([`plot_files`], [`write_plots`]) and plots 2 to 4 (cycles
//! against k, unit counts and FIFO depths; utilisation); `error.rs` plot 1; `point.rs` what
//! the plots read from a record; `chart.rs` how they draw. The children import each other
//! downwards (error.rs imports point.rs and chart.rs, point.rs imports chart.rs) and never
//! this file.

mod chart;
mod error;
mod field;
pub mod loglog;
mod point;
pub mod speedup;

use crate::error::{Error, Result};
pub use chart::fmt_num;
use chart::{
    draw_legend, draw_lines, draw_mark, fmt_int, fmt_value, framed, log_axis, log_range, mesh,
    min_max, plot_size, svg, Area, DrawResult, Entry, Mark, Plot, CHART_HEIGHT, FONT, LEMBO, MARKS,
    PALETTE, WIDTH,
};
use error::{error_against, Against, ErrorAxis};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
pub(crate) use point::used;
use point::{assignment, most_common, varying, Point};
pub use point::{pareto_front, scene_label};
use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Writes the sweep's plots into `dir` and returns the file names written (only the plots the
/// records support), scene by scene in name order. All files appear together or none
/// ([`crate::output::write_files`]); with nothing to plot, nothing is written and `dir` is not
/// created. Records that are not sweep points (no `report.settings.path`) are skipped.
pub fn write_plots(dir: &Path, records: &[Value], budget: Option<f64>) -> Result<Vec<String>> {
    let files = plot_files(records, budget)?;
    if !files.is_empty() {
        let named: Vec<(&str, Vec<u8>)> = files
            .iter()
            .map(|(name, svg)| (name.as_str(), svg.clone()))
            .collect();
        crate::output::write_files(dir, &named)?;
    }
    Ok(files.into_iter().map(|(name, _)| name).collect())
}

/// The plots [`write_plots`] writes, as (file name, SVG bytes), without writing them;
/// `budget` is the sweep's `area_budget_mm2`.
pub fn plot_files(records: &[Value], budget: Option<f64>) -> Result<Vec<(String, Vec<u8>)>> {
    let mut scenes: BTreeMap<String, Vec<Point>> = BTreeMap::new();
    for p in records.iter().filter_map(Point::from_record) {
        scenes.entry(p.scene.clone()).or_default().push(p);
    }
    let mut files = Vec::new();
    let mut stems = BTreeSet::new();
    for (scene, points) in &scenes {
        let stem = unique_stem(scene, &mut stems);
        let plots = [
            (
                "tradeoff",
                error_against(scene, points, Against::Cycles, ErrorAxis::Rms, budget),
            ),
            (
                "error_vs_energy",
                error_against(scene, points, Against::Energy, ErrorAxis::Rms, budget),
            ),
            (
                "flip_tradeoff",
                error_against(scene, points, Against::Cycles, ErrorAxis::Flip, budget),
            ),
            (
                "flip_vs_energy",
                error_against(scene, points, Against::Energy, ErrorAxis::Flip, budget),
            ),
            ("cycles_vs_k", cycles_vs_k(scene, points)),
            (
                "cycles_vs_units",
                cycles_vs_arch(scene, points, ArchAxis::Counts),
            ),
            (
                "cycles_vs_fifo_depth",
                cycles_vs_arch(scene, points, ArchAxis::FifoDepths),
            ),
            ("utilisation", utilisation(scene, points)),
        ];
        let fields = field::field_plots(scene, points)
            .into_iter()
            .map(|(f, plot)| (format!("vs_{}", field_stem(&f)), plot));
        let plots = plots
            .into_iter()
            .map(|(k, p)| (k.to_string(), p))
            .chain(fields);
        for (kind, plot) in plots {
            let name = format!("{kind}_{stem}.svg");
            match plot {
                None => {}
                Some(Ok(svg)) => files.push((name, svg.into_bytes())),
                Some(Err(e)) => return Err(Error::Internal(format!("drawing {name}: {e}"))),
            }
        }
    }
    Ok(files)
}

const BUSY: RGBColor = RGBColor(44, 160, 44);
const STARVED: RGBColor = RGBColor(199, 199, 199);
const BLOCKED: RGBColor = RGBColor(214, 39, 40);

/// Plot 2: cycles against k on the lembo path, one series per combination of the other
/// parameters that vary. A combination run at a single k says nothing about k: its points
/// are counted in the legend, not drawn.
fn cycles_vs_k(scene: &str, points: &[Point]) -> Plot {
    let (series, left_out) = k_series(points)?;
    let style = |s: usize| k_style(s, series.len());
    let entries = k_entries(&series, left_out);
    let drawn = || series.iter().flat_map(|(_, line)| line.iter());
    let y_max = drawn().map(|p| p.1).fold(1.0, f64::max);
    let title = format!("{scene}: cycles against k (lembo path)");
    svg(plot_size(&entries), |root| {
        let (plot, legend) = root.split_vertically(CHART_HEIGHT);
        let mut chart = framed(&plot, &title, 22)
            .build_cartesian_2d(log_axis(log_range(drawn().map(|p| p.0))), 0.0..y_max * 1.1)?;
        chart
            .configure_mesh()
            .x_desc("k, chord error of the extreme method [px], log scale")
            .y_desc("simulated frame time [cycles]")
            .x_label_formatter(&|v| fmt_num(*v))
            .y_label_formatter(&|v| fmt_num(*v))
            .label_style((FONT, 13))
            .axis_desc_style((FONT, 15))
            .draw()?;
        for (s, (_, line)) in series.iter().enumerate() {
            let (color, mark) = style(s);
            chart.draw_series(LineSeries::new(line.iter().copied(), color.stroke_width(2)))?;
            for p in line {
                draw_mark(root, chart.backend_coord(p), mark, color)?;
            }
        }
        draw_legend(&legend, &entries)
    })
}

/// A series of plot 2: its name and its points (k, cycles) in ascending k.
type KSeries = (String, Vec<(f64, f64)>);

/// Plot 2's series: the lembo points grouped by the other varying parameters, each
/// group run at more than one k a series, named by what tells the series apart (a lone
/// series by all it holds fixed); with the count of points left out, whose group was run
/// at a single k. None when no group was.
fn k_series(points: &[Point]) -> Option<(Vec<KSeries>, usize)> {
    let pts: Vec<&Point> = points
        .iter()
        .filter(|p| p.path == "lembo" && p.cycles.is_some() && p.k_px.is_some_and(|k| k > 0.0))
        .collect();
    let others: Vec<String> = varying(&pts)
        .into_iter()
        .filter(|key| key != "k" && key != "path")
        .collect();
    let mut groups: BTreeMap<String, Vec<&Point>> = BTreeMap::new();
    for p in &pts {
        groups.entry(assignment(p, &others)).or_default().push(p);
    }
    let (drawn, single): (Vec<Vec<&Point>>, Vec<Vec<&Point>>) =
        groups.into_values().partition(|group| {
            let ks: BTreeSet<u64> = group
                .iter()
                .filter_map(|p| p.k_px)
                .map(f64::to_bits)
                .collect();
            ks.len() > 1
        });
    if drawn.is_empty() {
        return None;
    }
    let left_out: usize = single.iter().map(Vec::len).sum();
    // Named by what tells the drawn series apart; a lone series by all it holds fixed.
    let all_drawn: Vec<&Point> = drawn.iter().flatten().copied().collect();
    let mut names: Vec<String> = varying(&all_drawn)
        .into_iter()
        .filter(|key| others.contains(key))
        .collect();
    if names.is_empty() {
        names = others.clone();
    }
    let series: Vec<KSeries> = drawn
        .iter()
        .map(|group| {
            let mut line: Vec<(f64, f64)> = group
                .iter()
                .filter_map(|p| Some((p.k_px?, p.cycles? as f64)))
                .collect();
            line.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
            let name = if names.is_empty() {
                "all points".to_string()
            } else {
                assignment(group[0], &names)
            };
            (name, line)
        })
        .collect();
    Some((series, left_out))
}

/// The colour and marker of plot 2's series `s` of `n`: a lone series in the lembo
/// path's colour.
fn k_style(s: usize, n: usize) -> (RGBColor, Mark) {
    let color = if n == 1 {
        LEMBO
    } else {
        PALETTE[s % PALETTE.len()]
    };
    (color, MARKS[s % MARKS.len()])
}

/// Plot 2's legend: one entry per series, and a line counting the points not drawn.
fn k_entries(series: &[KSeries], left_out: usize) -> Vec<Entry> {
    let mut entries: Vec<Entry> = series
        .iter()
        .enumerate()
        .map(|(s, (name, _))| {
            let (color, mark) = k_style(s, series.len());
            Entry {
                mark: Some(mark),
                line: true,
                color,
                label: name.clone(),
                note: None,
            }
        })
        .collect();
    if left_out > 0 {
        entries.push(Entry {
            mark: None,
            line: false,
            color: BLACK,
            label: format!(
                "not drawn: {left_out} point(s) whose other parameters were run at a single k"
            ),
            note: None,
        });
    }
    entries
}

/// An architecture field a plot puts on its x axis: unit counts or FIFO depths.
#[derive(Clone, Copy)]
enum ArchAxis {
    /// `arch.*.count`.
    Counts,
    /// `arch.links.*.fifo_depth`.
    FifoDepths,
}

impl ArchAxis {
    fn matches(self, key: &str) -> bool {
        key.starts_with("arch.")
            && match self {
                ArchAxis::Counts => key.ends_with(".count"),
                ArchAxis::FifoDepths => key.ends_with(".fifo_depth"),
            }
    }
}

/// One series per varying field of `axis`, the other parameters held at their most common
/// value: (legend entry, points (field value, cycles) in ascending value). A field that
/// takes one value where the others are held says nothing and gets no series.
fn held_series(points: &[Point], axis: ArchAxis) -> Vec<(Entry, Vec<(f64, f64)>)> {
    let pts: Vec<&Point> = points.iter().filter(|p| p.cycles.is_some()).collect();
    let keys = varying(&pts);
    let fields: Vec<&String> = keys
        .iter()
        .filter(|k| axis.matches(k))
        .filter(|k| pts.iter().any(|p| p.param(k).as_i64().is_some()))
        .collect();
    let mut series = Vec::new();
    for (s, &key) in fields.iter().enumerate() {
        let mut held = pts.clone();
        // The path first: k and tess are null on the other path, so they are fixed after it.
        let mut others: Vec<&String> = keys.iter().filter(|k| *k != key).collect();
        others.sort_by_key(|k| (k.as_str() != "path", k.as_str()));
        let mut fixed = Vec::new();
        for other in others {
            let (value, tied) = most_common(&held, other);
            held.retain(|p| p.param(other) == &value);
            // Null is a parameter that does not apply (tess on the lembo path).
            if !value.is_null() {
                let mut said = format!("{other}={}", fmt_value(&value));
                if !tied.is_empty() {
                    let tied: Vec<String> = tied.iter().map(fmt_value).collect();
                    said += &format!(" (tied with {})", tied.join(", "));
                }
                fixed.push(said);
            }
        }
        let mut line: Vec<(f64, f64)> = held
            .iter()
            .filter_map(|p| Some((p.param(key).as_i64()? as f64, p.cycles? as f64)))
            .collect();
        line.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
        if line.windows(2).all(|w| w[0].0 == w[1].0) {
            continue;
        }
        let entry = Entry {
            mark: Some(MARKS[s % MARKS.len()]),
            line: true,
            color: PALETTE[s % PALETTE.len()],
            label: key.clone(),
            note: Some(if fixed.is_empty() {
                "no other parameter varies".into()
            } else {
                format!(
                    "the others at their most common value: {}",
                    fixed.join(", ")
                )
            }),
        };
        series.push((entry, line));
    }
    series
}

/// The y axis of the plots of cycles.
const CYCLES: &str = "simulated frame time [cycles]";

/// Plot 3: cycles against unit counts (`ArchAxis::Counts`, linear x) or FIFO depths
/// (`ArchAxis::FifoDepths`, log x), one series per varying field, the other parameters at
/// their most common value. No series, no plot.
fn cycles_vs_arch(scene: &str, points: &[Point], axis: ArchAxis) -> Plot {
    let series = held_series(points, axis);
    if series.is_empty() {
        return None;
    }
    let (entries, lines): (Vec<Entry>, Vec<Vec<(f64, f64)>>) = series.into_iter().unzip();
    let all = || lines.iter().flatten();
    let (x_lo, x_hi) = min_max(all().map(|p| p.0));
    let y_max = all().map(|p| p.1).fold(1.0, f64::max);
    let (what, x_desc) = match axis {
        ArchAxis::Counts => ("unit counts", "unit instances [count]"),
        ArchAxis::FifoDepths => ("FIFO depths", "FIFO depth [entries], log scale"),
    };
    let title = format!("{scene}: cycles against {what}");
    svg(plot_size(&entries), |root| {
        let (plot, legend) = root.split_vertically(CHART_HEIGHT);
        let mut builder = framed(&plot, &title, 22);
        match axis {
            ArchAxis::Counts => {
                let mut chart =
                    builder.build_cartesian_2d(x_lo - 1.0..x_hi + 1.0, 0.0..y_max * 1.1)?;
                mesh(&mut chart, x_desc, CYCLES)?;
                draw_lines(root, &mut chart, &entries, &lines)?;
            }
            ArchAxis::FifoDepths => {
                let mut chart = builder
                    .build_cartesian_2d(log_axis(x_lo * 0.8..x_hi * 1.25), 0.0..y_max * 1.1)?;
                mesh(&mut chart, x_desc, CYCLES)?;
                draw_lines(root, &mut chart, &entries, &lines)?;
            }
        }
        draw_legend(&legend, &entries)
    })
}

/// Plot 4: each unit's busy, starved and blocked share of the frame, for the point with the
/// most cycles and the one with the fewest.
fn utilisation(scene: &str, points: &[Point]) -> Plot {
    let pts: Vec<&Point> = points
        .iter()
        .filter(|p| p.cycles.is_some() && !p.units.is_empty())
        .collect();
    let most = pts
        .iter()
        .max_by_key(|p| (p.cycles, std::cmp::Reverse(p.index)))?;
    let fewest = pts.iter().min_by_key(|p| (p.cycles, p.index))?;
    let mut groups = vec![("most cycles", *most)];
    if !std::ptr::eq(*most, *fewest) {
        groups.push(("fewest cycles", *fewest));
    }
    let varying = varying(&pts);
    let heights: Vec<u32> = groups
        .iter()
        .map(|(_, p)| 110 + 24 * p.units.len() as u32)
        .collect();
    let title = format!("{scene}: unit utilisation at the most and fewest cycles");
    svg((WIDTH, 90 + heights.iter().sum::<u32>()), |root| {
        let root = root.titled(&title, (FONT, 22))?;
        let (legend, mut rest) = root.split_vertically(40);
        utilisation_legend(&legend)?;
        for ((group, p), height) in groups.iter().zip(&heights) {
            let (area, below) = rest.split_vertically(*height);
            rest = below;
            draw_unit_shares(&area, group, p, &pts, &varying)?;
        }
        Ok(())
    })
}

/// Plot 4's legend: the colours of the busy, starved and blocked shares.
fn utilisation_legend(legend: &Area) -> DrawResult {
    for (i, (name, color)) in [
        ("busy", BUSY),
        ("starved (waiting for input)", STARVED),
        ("blocked (a full FIFO downstream)", BLOCKED),
    ]
    .into_iter()
    .enumerate()
    {
        let x = [180, 290, 530][i];
        legend.draw(&Rectangle::new([(x, 12), (x + 16, 28)], color.filled()))?;
        legend.draw(&Text::new(
            name,
            (x + 22, 20),
            (FONT, 14)
                .into_font()
                .color(&BLACK)
                .pos(Pos::new(HPos::Left, VPos::Center)),
        ))?;
    }
    Ok(())
}

/// One point's chart in plot 4: a bar per unit (unit 0 at the top) split into its busy,
/// starved and blocked shares of the frame, captioned by `group` and what sets the point
/// apart from the others.
fn draw_unit_shares(
    area: &Area,
    group: &str,
    p: &Point,
    pts: &[&Point],
    varying: &[String],
) -> DrawResult {
    let total = p.cycles.unwrap_or(1).max(1) as f64;
    let n = p.units.len() as i32;
    let caption = fit(
        format!(
            "{group}: {} ({} cycles)",
            describe_apart(p, pts, varying),
            fmt_int(p.cycles.unwrap_or(0))
        ),
        CAPTION_CHARS,
    );
    let mut chart = ChartBuilder::on(area)
        .caption(caption, (FONT, 16))
        .margin(10)
        .margin_right(30)
        .x_label_area_size(45)
        .y_label_area_size(170)
        .build_cartesian_2d(0.0..100.0, (0..n).into_segmented())?;
    // Unit 0 at the top.
    let row = |i: usize| n - 1 - i as i32;
    chart
        .configure_mesh()
        .disable_y_mesh()
        .y_labels(p.units.len())
        .y_label_formatter(&|v| match v {
            SegmentValue::CenterOf(r) => p
                .units
                .get((n - 1 - r) as usize)
                .map(|u| u.name.clone())
                .unwrap_or_default(),
            _ => String::new(),
        })
        .x_label_formatter(&|v| fmt_num(*v))
        .x_desc("share of the frame time [%]")
        .y_desc("unit")
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 15))
        .draw()?;
    chart.draw_series(p.units.iter().enumerate().flat_map(|(i, u)| {
        let shares = [(u.busy, BUSY), (u.starved, STARVED), (u.blocked, BLOCKED)];
        let mut x0 = 0.0;
        shares.map(|(cycles, color)| {
            let x1 = x0 + 100.0 * cycles as f64 / total;
            let mut bar = Rectangle::new(
                [
                    (x0, SegmentValue::Exact(row(i))),
                    (x1, SegmentValue::Exact(row(i) + 1)),
                ],
                color.filled(),
            );
            bar.set_margin(3, 3, 0, 0);
            x0 = x1;
            bar
        })
    }))?;
    Ok(())
}

/// The most characters a 16-point caption holds across a plot.
const CAPTION_CHARS: usize = 100;

/// `text`, cut at a comma and ended with ", …" when longer than `chars`.
fn fit(text: String, chars: usize) -> String {
    if text.chars().count() <= chars {
        return text;
    }
    let cut: String = text.chars().take(chars.saturating_sub(3)).collect();
    match cut.rfind(", ") {
        Some(i) => format!("{}, …", &cut[..i]),
        None => format!("{cut}…"),
    }
}

/// `p` by what sets it apart: its path and level, and the varying parameters whose value
/// differs from their most common one among `pts` (the one a one-at-a-time sweep varies).
fn describe_apart(p: &Point, pts: &[&Point], varying: &[String]) -> String {
    let apart: Vec<String> = varying
        .iter()
        .filter(|k| !matches!(k.as_str(), "path" | "k" | "tess"))
        .filter(|k| p.param(k) != &most_common(pts, k).0)
        .cloned()
        .collect();
    describe(p, &apart)
}

/// A point for a caption: its path and level, the other varying parameters and its index.
fn describe(p: &Point, varying: &[String]) -> String {
    let others: Vec<String> = varying
        .iter()
        .filter(|k| !matches!(k.as_str(), "path" | "k" | "tess"))
        .cloned()
        .collect();
    let mut s = format!("{} path, {}", p.path, p.level());
    if !others.is_empty() {
        s += &format!(", {}", assignment(p, &others));
    }
    s + &format!(", point {}", p.index)
}

/// A file-name stem for a scene: ASCII letters, digits, `-`, `_` and `.`, the rest `_`;
/// `_2`, `_3`, ... if another scene already took it.
/// A field's name as a file name's part: `arch.framebuffer.bytes_per_cycle` as
/// `framebuffer_bytes_per_cycle`.
fn field_stem(field: &str) -> String {
    field
        .trim_start_matches("arch.")
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect()
}

fn unique_stem(scene: &str, taken: &mut BTreeSet<String>) -> String {
    let base: String = scene
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.') {
                c
            } else {
                '_'
            }
        })
        .collect();
    let mut stem = base.clone();
    let mut n = 2;
    while !taken.insert(stem.clone()) {
        stem = format!("{base}_{n}");
        n += 1;
    }
    stem
}

#[cfg(test)]
mod tests;
