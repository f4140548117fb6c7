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

use crate::error::{Error, Result};
use plotters::coord::combinators::WithKeyPoints;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};
use std::ops::Range;
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
                error_against(scene, points, Against::Cycles, budget),
            ),
            (
                "error_vs_energy",
                error_against(scene, points, Against::Energy, budget),
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

/// Indices of the points that no other point dominates, minimising both coordinates (q
/// dominates p when q is no larger in both and smaller in one). Equal points do not dominate
/// each other, so duplicates on the front are all returned. The indices come in ascending x
/// (ties by ascending y, then index), the order a step line through the front takes. Points
/// with a NaN coordinate are never on the front.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..points.len())
        .filter(|&i| !points[i].0.is_nan() && !points[i].1.is_nan())
        .collect();
    order.sort_by(|&a, &b| {
        let (pa, pb) = (points[a], points[b]);
        pa.0.total_cmp(&pb.0)
            .then(pa.1.total_cmp(&pb.1))
            .then(a.cmp(&b))
    });
    let mut front: Vec<usize> = Vec::new();
    for i in order {
        // Every earlier point has x no larger; it dominates this one unless this one has a
        // smaller y than all of them, or it is the last front point again.
        let keep = match front.last() {
            None => true,
            Some(&last) => points[i].1 < points[last].1 || points[i] == points[last],
        };
        if keep {
            front.push(i);
        }
    }
    front
}

/// One sweep point, as far as the plots use it.
struct Point {
    index: u64,
    scene: String,
    /// `lembo` or `triangle` (`report.settings.path`).
    path: String,
    /// Tolerance k \[px\]; lembo path only.
    k_px: Option<f64>,
    /// Tessellation level n; triangle path only.
    tess: Option<u64>,
    /// The sweep's parameters of this point; a parameter another point has and this one
    /// lacks counts as null.
    params: BTreeMap<String, Value>,
    /// Frame time \[cycles\]; `None` in functional mode.
    cycles: Option<u64>,
    units: Vec<UnitTime>,
    /// RMS colour error 255·10^(−PSNR/20) [0-255]; `None` without a reference.
    rms_error: Option<f64>,
    /// The run's report, for the value of a parameter its point left at the default.
    report: Value,
    /// The frame's energy \[pJ\]; `None` without a cost section.
    energy_pj: Option<f64>,
    /// The unit's area \[mm²\]; `None` without a cost section.
    area_mm2: Option<f64>,
}

/// One unit's cycle accounting; busy + starved + blocked = the frame's cycles.
struct UnitTime {
    name: String,
    busy: u64,
    starved: u64,
    blocked: u64,
}

impl Point {
    fn from_record(record: &Value) -> Option<Point> {
        let report = record.get("report")?;
        let settings = report.get("settings")?;
        let path = settings.get("path")?.as_str()?.to_string();
        let scene = record
            .get("scene")
            .and_then(Value::as_str)
            .or_else(|| report.pointer("/scene/name").and_then(Value::as_str))?
            .to_string();
        let params = record
            .get("params")
            .and_then(Value::as_object)
            .map(|m| m.iter().map(|(k, v)| (k.clone(), v.clone())).collect())
            .unwrap_or_default();
        let cycles = report.pointer("/cycles/total").and_then(Value::as_u64);
        let units = report
            .pointer("/cycles/units")
            .and_then(Value::as_array)
            .map(|units| {
                units
                    .iter()
                    .filter_map(|u| {
                        Some(UnitTime {
                            name: u.get("name")?.as_str()?.to_string(),
                            busy: u.get("busy")?.as_u64()?,
                            starved: u.get("starved")?.as_u64()?,
                            blocked: u.get("blocked")?.as_u64()?,
                        })
                    })
                    .collect()
            })
            .unwrap_or_default();
        let rms_error = report
            .pointer("/accuracy/psnr_db")
            .and_then(Value::as_f64)
            .map(|psnr| 255.0 * 10f64.powf(-psnr / 20.0))
            .filter(|e| e.is_finite() && *e > 0.0);
        Some(Point {
            index: record.get("index").and_then(Value::as_u64).unwrap_or(0),
            scene,
            path,
            k_px: settings.get("k_px").and_then(Value::as_f64),
            tess: settings.get("tess").and_then(Value::as_u64),
            params,
            cycles: cycles.filter(|&c| c > 0),
            units,
            rms_error,
            report: report.clone(),
            energy_pj: report.pointer("/cost/energy_pj").and_then(Value::as_f64),
            area_mm2: report.pointer("/cost/area_mm2").and_then(Value::as_f64),
        })
    }

    /// The swept level of detail: `k=0.5` or `n=4`.
    fn level(&self) -> String {
        match (self.k_px, self.tess) {
            (Some(k), _) => format!("k={}", fmt_num(k)),
            (None, Some(n)) => format!("n={n}"),
            (None, None) => format!("#{}", self.index),
        }
    }

    /// The point's value of parameter `key`, or the value its run used by default (as its
    /// report echoes it); null where the parameter does not apply.
    fn param(&self, key: &str) -> &Value {
        static NULL: Value = Value::Null;
        self.params
            .get(key)
            .or_else(|| crate::sweep::results::used(&self.report, key))
            .unwrap_or(&NULL)
    }
}

mod error;
use error::{error_against, Against};

type DrawResult = std::result::Result<(), Box<dyn std::error::Error>>;
type Plot = Option<std::result::Result<String, Box<dyn std::error::Error>>>;
type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;

/// Draws one SVG of `size` pixels.
fn svg(size: (u32, u32), draw: impl FnOnce(&Area) -> DrawResult) -> Plot {
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

const FONT: &str = "sans-serif";
/// Width of every plot and height of the chart above its legend \[px\].
const WIDTH: u32 = 900;
const CHART_HEIGHT: u32 = 600;
const LEMBO: RGBColor = RGBColor(31, 119, 180);
const TRIANGLE: RGBColor = RGBColor(214, 39, 40);
/// Series colours other than the two paths' (the tab10 palette, less its blue and red).
const PALETTE: [RGBColor; 8] = [
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];
const BUSY: RGBColor = RGBColor(44, 160, 44);
const STARVED: RGBColor = RGBColor(199, 199, 199);
const BLOCKED: RGBColor = RGBColor(214, 39, 40);

/// A series' point marker. Series differ in shape as well as colour, so one drawn over
/// another (equal cycles in f32 and f64, say) still shows.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Mark {
    Dot,
    Ring,
    Cross,
    Triangle,
    Square,
}

const MARKS: [Mark; 5] = [
    Mark::Dot,
    Mark::Ring,
    Mark::Cross,
    Mark::Triangle,
    Mark::Square,
];

/// One line of a legend: a marker (none for a plain note), a line through it or not, the
/// label and an optional second line.
struct Entry {
    mark: Option<Mark>,
    line: bool,
    color: RGBColor,
    label: String,
    note: Option<String>,
}

impl Entry {
    fn height(&self) -> u32 {
        if self.note.is_some() {
            38
        } else {
            20
        }
    }
}

/// Draws a marker centred on `at`, in `area`'s pixel coordinates.
fn draw_mark(area: &Area, at: (i32, i32), mark: Mark, color: RGBColor) -> DrawResult {
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
fn draw_legend(area: &Area, entries: &[Entry]) -> DrawResult {
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
fn plot_size(entries: &[Entry]) -> (u32, u32) {
    let legend: u32 = entries.iter().map(Entry::height).sum();
    (WIDTH, CHART_HEIGHT + legend + 10)
}

/// A log axis over `range` with ticks at 1, 2 and 5 per decade, or at every digit when that
/// gives fewer than four (plotters' own log axis labels only powers of ten).
fn log_axis(range: Range<f64>) -> WithKeyPoints<LogCoord<f64>> {
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

/// Plot 2: cycles against k on the lembo path, one series per combination of the other
/// parameters that vary. A combination run at a single k says nothing about k: its points
/// are counted in the legend, not drawn.
fn cycles_vs_k(scene: &str, points: &[Point]) -> Plot {
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
    // Named by what tells the drawn series apart; a lone series by all it holds fixed.
    let all_drawn: Vec<&Point> = drawn.iter().flatten().copied().collect();
    let mut names: Vec<String> = varying(&all_drawn)
        .into_iter()
        .filter(|key| others.contains(key))
        .collect();
    if names.is_empty() {
        names = others.clone();
    }
    let series: Vec<(String, Vec<(f64, f64)>)> = drawn
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
    let style = |s: usize| {
        let color = if series.len() == 1 {
            LEMBO
        } else {
            PALETTE[s % PALETTE.len()]
        };
        (color, MARKS[s % MARKS.len()])
    };
    let mut entries: Vec<Entry> = series
        .iter()
        .enumerate()
        .map(|(s, (name, _))| {
            let (color, mark) = style(s);
            Entry {
                mark: Some(mark),
                line: true,
                color,
                label: name.clone(),
                note: None,
            }
        })
        .collect();
    let left_out: usize = single.iter().map(Vec::len).sum();
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
    let drawn = || series.iter().flat_map(|(_, line)| line.iter());
    let y_max = drawn().map(|p| p.1).fold(1.0, f64::max);
    let title = format!("{scene}: cycles against k (lembo path)");
    svg(plot_size(&entries), |root| {
        let (plot, legend) = root.split_vertically(CHART_HEIGHT);
        let mut chart = ChartBuilder::on(&plot)
            .caption(&title, (FONT, 22))
            .margin(20)
            .x_label_area_size(50)
            .y_label_area_size(80)
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
            let value = most_common(&held, other);
            held.retain(|p| p.param(other) == &value);
            // Null is a parameter that does not apply (tess on the lembo path).
            if !value.is_null() {
                fixed.push(format!("{other}={}", fmt_value(&value)));
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

/// Draws the mesh of `chart` with its axis descriptions, numbers in [`fmt_num`].
fn mesh<'a, X, Y>(
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
fn draw_lines<'a, X>(
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
    let x_lo = all().map(|p| p.0).fold(f64::INFINITY, f64::min);
    let x_hi = all().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max);
    let y_max = all().map(|p| p.1).fold(1.0, f64::max);
    let (what, x_desc) = match axis {
        ArchAxis::Counts => ("unit counts", "unit instances [count]"),
        ArchAxis::FifoDepths => ("FIFO depths", "FIFO depth [entries], log scale"),
    };
    let title = format!("{scene}: cycles against {what}");
    svg(plot_size(&entries), |root| {
        let (plot, legend) = root.split_vertically(CHART_HEIGHT);
        let mut builder = ChartBuilder::on(&plot);
        builder
            .caption(&title, (FONT, 22))
            .margin(20)
            .x_label_area_size(50)
            .y_label_area_size(80);
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
        for ((group, p), height) in groups.iter().zip(&heights) {
            let (area, below) = rest.split_vertically(*height);
            rest = below;
            let total = p.cycles.unwrap_or(1).max(1) as f64;
            let n = p.units.len() as i32;
            let caption = fit(
                format!(
                    "{group}: {} ({} cycles)",
                    describe_apart(p, &pts, &varying),
                    fmt_int(p.cycles.unwrap_or(0))
                ),
                CAPTION_CHARS,
            );
            let mut chart = ChartBuilder::on(&area)
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
        }
        Ok(())
    })
}

/// The parameters whose value is not the same at every point (a missing one counts as null).
fn varying(points: &[&Point]) -> Vec<String> {
    let keys: BTreeSet<&String> = points.iter().flat_map(|p| p.params.keys()).collect();
    keys.into_iter()
        .filter(|k| {
            let values: BTreeSet<String> = points.iter().map(|p| p.param(k).to_string()).collect();
            values.len() > 1
        })
        .cloned()
        .collect()
}

/// The value of `key` most points have; ties go to the one seen first.
fn most_common(points: &[&Point], key: &str) -> Value {
    let mut tally: Vec<(Value, usize)> = Vec::new();
    for p in points {
        let v = p.param(key);
        match tally.iter_mut().find(|(seen, _)| seen == v) {
            Some((_, n)) => *n += 1,
            None => tally.push((v.clone(), 1)),
        }
    }
    let best = tally.iter().map(|(_, n)| *n).max().unwrap_or(0);
    tally
        .into_iter()
        .find(|(_, n)| *n == best)
        .map(|(v, _)| v)
        .unwrap_or(Value::Null)
}

/// `key=value, ...` for the given parameters of a point.
fn assignment(p: &Point, keys: &[String]) -> String {
    keys.iter()
        .map(|k| format!("{k}={}", fmt_value(p.param(k))))
        .collect::<Vec<_>>()
        .join(", ")
}

/// A point for a caption: its path and level, the other varying parameters and its index.
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
        .filter(|k| p.param(k) != &most_common(pts, k))
        .cloned()
        .collect();
    describe(p, &apart)
}

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

fn fmt_value(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        Value::Null => "-".into(),
        Value::Number(n) => n.as_f64().map(fmt_num).unwrap_or_else(|| n.to_string()),
        other => other.to_string(),
    }
}

/// Three significant digits with k, M or G for thousands: `52.5k`, `0.00255`.
fn fmt_num(v: f64) -> String {
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
fn fmt_int(n: u64) -> String {
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

/// A log axis range around positive values, with a margin of a quarter on either side.
fn log_range(values: impl Iterator<Item = f64>) -> Range<f64> {
    let (lo, hi) = values
        .filter(|v| *v > 0.0 && v.is_finite())
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if hi == 0.0 {
        return 0.1..10.0;
    }
    lo / 1.25..hi * 1.25
}

/// A file-name stem for a scene: ASCII letters, digits, `-`, `_` and `.`, the rest `_`;
/// `_2`, `_3`, ... if another scene already took it.
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
