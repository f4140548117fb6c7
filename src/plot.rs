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
/// Points over a sweep's area budget.
const OVER_BUDGET: RGBColor = RGBColor(190, 190, 190);
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

/// What an error plot puts on its x axis.
#[derive(Clone, Copy)]
enum Against {
    /// Simulated frame time.
    Cycles,
    /// The frame's energy (report.json `cost`).
    Energy,
}

impl Against {
    fn x(self, p: &Point) -> Option<f64> {
        match self {
            Against::Cycles => p.cycles.map(|c| c as f64),
            Against::Energy => p.energy_pj.filter(|e| *e > 0.0),
        }
    }
}

/// Plot 1: image error against cycles (`Against::Cycles`, `tradeoff_*`) or energy
/// (`error_vs_energy_*`), one series per path. Without an area budget, the Pareto front over
/// both paths is circled; with one, points whose unit is larger are drawn grey and left
/// out, and each path gets its own front among the configurations within the budget.
fn error_against(scene: &str, points: &[Point], against: Against, budget: Option<f64>) -> Plot {
    let pts: Vec<(&Point, (f64, f64))> = points
        .iter()
        .filter_map(|p| Some((p, (against.x(p)?, p.rms_error?))))
        .collect();
    if pts.is_empty() {
        return None;
    }
    let xy: Vec<(f64, f64)> = pts.iter().map(|&(_, xy)| xy).collect();
    let within = |p: &Point| match (budget, p.area_mm2) {
        (None, _) => true,
        (Some(b), Some(a)) => a <= b,
        (Some(_), None) => false,
    };
    let mut by_path: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
    for (i, (p, _)) in pts.iter().enumerate() {
        by_path.entry(p.path.as_str()).or_default().push(i);
    }
    // The fronts: one over both paths, or one per path within the budget.
    let front_of = |members: &[usize]| -> Vec<usize> {
        let kept: Vec<usize> = members
            .iter()
            .copied()
            .filter(|&i| within(pts[i].0))
            .collect();
        let sub: Vec<(f64, f64)> = kept.iter().map(|&i| xy[i]).collect();
        pareto_front(&sub).into_iter().map(|j| kept[j]).collect()
    };
    let fronts: Vec<(RGBColor, Vec<usize>)> = match budget {
        None => vec![(BLACK, front_of(&(0..pts.len()).collect::<Vec<_>>()))],
        Some(_) => by_path
            .iter()
            .enumerate()
            .map(|(s, (path, members))| (path_style(path, s).0, front_of(members)))
            .collect(),
    };
    // Series: a path, split by the datapath and blend mode where they vary, so points that
    // differ only in those (and often coincide) keep apart by their marker.
    let all: Vec<&Point> = pts.iter().map(|(p, _)| *p).collect();
    let variant_keys: Vec<String> = varying(&all)
        .into_iter()
        .filter(|k| k == "datapath" || k == "blend")
        .collect();
    let mut series: BTreeMap<(String, String), Vec<usize>> = BTreeMap::new();
    for (i, (p, _)) in pts.iter().enumerate() {
        let variant = assignment(p, &variant_keys);
        series.entry((p.path.clone(), variant)).or_default().push(i);
    }
    let paths: Vec<&str> = by_path.keys().copied().collect();
    let style_of = |path: &str, variant_rank: usize| {
        let s = paths.iter().position(|p| *p == path).unwrap_or(0);
        let (color, mark) = path_style(path, s);
        let marks: Vec<Mark> = std::iter::once(mark)
            .chain(MARKS.iter().copied().filter(|m| *m != mark))
            .collect();
        (color, marks[variant_rank % marks.len()])
    };
    let mut styles: Vec<(RGBColor, Mark)> = Vec::new();
    let mut entries: Vec<Entry> = Vec::new();
    let mut rank: BTreeMap<&str, usize> = BTreeMap::new();
    for (path, variant) in series.keys() {
        let r = rank.entry(path.as_str()).or_default();
        let (color, mark) = style_of(path, *r);
        *r += 1;
        styles.push((color, mark));
        let what = match path.as_str() {
            "lembo" => "lembo path".to_string(),
            "triangle" => "triangle path".to_string(),
            other => format!("{other} path"),
        };
        let levels = match path.as_str() {
            "lembo" => ", labelled with k, the chord error [px]",
            "triangle" => ", labelled with n (n² triangles per lembo)",
            _ => "",
        };
        entries.push(Entry {
            mark: Some(mark),
            line: false,
            color,
            label: if variant.is_empty() {
                format!("{what}{levels}")
            } else {
                format!("{what}, {variant}{levels}")
            },
            note: None,
        });
    }
    let measure = match against {
        Against::Cycles => "cycles",
        Against::Energy => "energy",
    };
    match budget {
        None => entries.push(Entry {
            mark: Some(Mark::Ring),
            line: true,
            color: BLACK,
            label: format!("Pareto front over both paths (circled): no other point has both less {measure} and less error"),
            note: None,
        }),
        Some(b) => {
            entries.push(Entry {
                mark: Some(Mark::Ring),
                line: true,
                color: BLACK,
                label: format!("each path's Pareto front (circled) among configurations of at most {} mm²", fmt_num(b)),
                note: None,
            });
            entries.push(Entry {
                mark: Some(Mark::Dot),
                line: false,
                color: OVER_BUDGET,
                label: format!("over the area budget of {} mm² (report.json cost.area_mm2)", fmt_num(b)),
                note: None,
            });
        }
    }
    let title = match budget {
        None => format!("{scene}: image error against {measure}"),
        Some(b) => format!(
            "{scene}: image error against {measure}, units within {} mm²",
            fmt_num(b)
        ),
    };
    let x_desc = match against {
        Against::Cycles => "simulated frame time [cycles], log scale",
        Against::Energy => "energy of the frame [pJ] (report.json cost), log scale",
    };
    svg(plot_size(&entries), |root| {
        let (plot, legend) = root.split_vertically(CHART_HEIGHT);
        let mut chart = ChartBuilder::on(&plot)
            .caption(&title, (FONT, 20))
            .margin(20)
            .x_label_area_size(50)
            .y_label_area_size(80)
            .build_cartesian_2d(
                log_axis(log_range(xy.iter().map(|p| p.0))),
                log_axis(log_range(xy.iter().map(|p| p.1))),
            )?;
        mesh(
            &mut chart,
            x_desc,
            "RMS colour error 255*10^(-PSNR/20) [0-255], log scale",
        )?;

        // The fronts first, so the series' points are drawn over them.
        for (color, front) in &fronts {
            let mut step = Vec::new();
            for (j, &i) in front.iter().enumerate() {
                step.push(xy[i]);
                if let Some(&next) = front.get(j + 1) {
                    step.push((xy[next].0, xy[i].1));
                }
            }
            chart.draw_series(LineSeries::new(step, color.stroke_width(1)))?;
            for &i in front {
                root.draw(&Circle::new(
                    chart.backend_coord(&xy[i]),
                    9,
                    color.stroke_width(2),
                ))?;
            }
        }
        // A label once per text and place: a level repeated at nearly the same point (the
        // same k on two datapaths) would only smear.
        // Marks first, then labels placed where they cover no other label.
        let mut labels = Labels::default();
        let mut pending = Vec::new();
        for (members, &(color, mark)) in series.values().zip(&styles) {
            for &i in members {
                let at = chart.backend_coord(&xy[i]);
                let color = if within(pts[i].0) { color } else { OVER_BUDGET };
                draw_mark(root, at, mark, color)?;
                pending.push((pts[i].0.level(), at, color));
            }
        }
        for (label, at, color) in pending {
            if let Some(pos) = labels.place(&label, at) {
                root.draw(&Text::new(label, pos, (FONT, 12).into_font().color(&color)))?;
            }
        }
        draw_legend(&legend, &entries)
    })
}

/// Labels placed beside their points so that no two overlap: each tries the four corners
/// around its point and is left out when all four are taken or the same text is already
/// near (the same level on two datapaths).
#[derive(Default)]
struct Labels {
    /// Placed labels: text, point, and box (x0, y0, x1, y1) in pixels.
    placed: Vec<(String, (i32, i32), [i32; 4])>,
}

impl Labels {
    /// Where to draw `text` for the point at `at`, if anywhere.
    fn place(&mut self, text: &str, at: (i32, i32)) -> Option<(i32, i32)> {
        if self
            .placed
            .iter()
            .any(|(t, (x, y), _)| t == text && (x - at.0).abs() < 12 && (y - at.1).abs() < 12)
        {
            return None;
        }
        // 12-point text: about 7 px a character, 12 px high.
        let (w, h) = (7 * text.chars().count() as i32, 12);
        for (dx, dy) in [(7, -16), (7, 4), (-7 - w, -16), (-7 - w, 4)] {
            let (x, y) = (at.0 + dx, at.1 + dy);
            let rect = [x, y, x + w, y + h];
            let free = self.placed.iter().all(|(_, _, r)| {
                rect[2] <= r[0] || r[2] <= rect[0] || rect[3] <= r[1] || r[3] <= rect[1]
            });
            if free {
                self.placed.push((text.to_string(), at, rect));
                return Some((x, y));
            }
        }
        None
    }
}

/// A path's colour and marker in the error plots (`s`: its rank among the paths drawn).
fn path_style(path: &str, s: usize) -> (RGBColor, Mark) {
    match path {
        "lembo" => (LEMBO, Mark::Dot),
        "triangle" => (TRIANGLE, Mark::Triangle),
        _ => (PALETTE[s % PALETTE.len()], MARKS[(s + 2) % MARKS.len()]),
    }
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
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn pareto_front_of_nothing_is_empty() {
        assert!(pareto_front(&[]).is_empty());
    }

    #[test]
    fn pareto_front_of_one_point_is_that_point() {
        assert_eq!(pareto_front(&[(3.0, 4.0)]), vec![0]);
    }

    #[test]
    fn pareto_front_keeps_the_trade_off_in_ascending_x() {
        let points = [(5.0, 1.0), (1.0, 5.0), (3.0, 3.0), (4.0, 4.0), (6.0, 2.0)];
        assert_eq!(pareto_front(&points), vec![1, 2, 0]);
    }

    #[test]
    fn pareto_front_ties_in_one_coordinate_are_dominated() {
        // (1, 2) beats (1, 3) on y and (2, 2) on x.
        let points = [(1.0, 3.0), (1.0, 2.0), (2.0, 2.0), (3.0, 1.0)];
        assert_eq!(pareto_front(&points), vec![1, 3]);
    }

    #[test]
    fn pareto_front_keeps_every_duplicate_of_a_front_point() {
        let points = [(2.0, 2.0), (1.0, 3.0), (2.0, 2.0), (3.0, 3.0), (3.0, 3.0)];
        assert_eq!(pareto_front(&points), vec![1, 0, 2]);
    }

    #[test]
    fn pareto_front_ignores_nan() {
        let points = [(f64::NAN, 0.0), (1.0, 1.0), (0.5, f64::NAN)];
        assert_eq!(pareto_front(&points), vec![1]);
    }

    #[test]
    fn numbers_are_printed_with_three_significant_digits() {
        assert_eq!(fmt_num(52505.0), "52.5k");
        assert_eq!(fmt_num(2000.0), "2000");
        assert_eq!(fmt_num(0.00255), "0.00255");
        assert_eq!(fmt_num(0.5), "0.5");
        assert_eq!(fmt_num(1.0), "1");
        assert_eq!(fmt_num(1.5e6), "1.5M");
        assert_eq!(fmt_int(103_273), "103 273");
        assert_eq!(fmt_int(999), "999");
        assert_eq!(fmt_int(1_000_000), "1 000 000");
    }

    fn units(cycles: u64, busy: &[u64]) -> Value {
        let units: Vec<Value> = busy
            .iter()
            .enumerate()
            .map(|(i, &b)| {
                json!({"name": format!("Unit[{i}]"), "kind": "Unit", "busy": b,
                       "starved": (cycles - b) / 2, "blocked": cycles - b - (cycles - b) / 2})
            })
            .collect();
        json!({"total": cycles, "clock_mhz": 500.0, "units": units})
    }

    /// A sweep record as the sweep writes it, with only the fields the plots read and a few
    /// they do not.
    fn record(index: u64, params: Value, cycles: Option<u64>, psnr_db: Option<f64>) -> Value {
        let path = params["path"].as_str().unwrap().to_string();
        let k = params.get("k").cloned().unwrap_or(Value::Null);
        let tess = params.get("tess").cloned().unwrap_or(Value::Null);
        json!({
            "index": index,
            "key": format!("point-{index}"),
            "scene": "sphere24",
            "params": params,
            "report": {
                "schema_version": 3,
                "scene": {"name": "sphere24"},
                "settings": {"mode": if cycles.is_some() { "timed" } else { "functional" },
                             "path": path, "k_px": k, "tess": tess, "datapath": "f32"},
                "primitives": {"count": 24},
                "cycles": cycles.map(|c| units(c, &[c / 2, c / 4, c])),
                "accuracy": psnr_db.map(|p| json!({"psnr_db": p, "silhouette_mean_px": 1.0})),
            }
        })
    }

    fn sweep() -> Vec<Value> {
        let mut records = Vec::new();
        let mut i = 0;
        let mut push = |params: Value, cycles, psnr| {
            records.push(record(i, params, Some(cycles), Some(psnr)));
            i += 1;
        };
        for (k, cycles, psnr) in [
            (0.125, 70_000, 48.0),
            (0.5, 52_505, 42.6),
            (2.0, 45_000, 35.0),
        ] {
            for (datapath, extra) in [("f32", 0), ("f64", 1_000)] {
                push(
                    json!({"path": "lembo", "k": k, "datapath": datapath,
                           "arch.segmenter.count": 2, "arch.rasterizer.count": 4}),
                    cycles + extra,
                    psnr,
                );
            }
        }
        for (n, cycles, psnr) in [(1, 39_819, 24.4), (4, 48_282, 38.3), (8, 60_000, 45.0)] {
            push(
                json!({"path": "triangle", "tess": n, "datapath": "f32",
                       "arch.segmenter.count": 2, "arch.rasterizer.count": 4}),
                cycles,
                psnr,
            );
        }
        for (segmenters, cycles) in [(1, 80_000), (4, 50_000)] {
            push(
                json!({"path": "lembo", "k": 0.5, "datapath": "f32",
                       "arch.segmenter.count": segmenters, "arch.rasterizer.count": 4}),
                cycles,
                42.6,
            );
        }
        for (rasterizers, cycles) in [(2, 90_000), (8, 40_000)] {
            push(
                json!({"path": "lembo", "k": 0.5, "datapath": "f32",
                       "arch.segmenter.count": 2, "arch.rasterizer.count": rasterizers}),
                cycles,
                42.6,
            );
        }
        records
    }

    /// Whether the SVG holds `text`, escaped as the SVG backend escapes it.
    fn has(svg: &str, text: &str) -> bool {
        let escaped = text
            .replace('&', "&amp;")
            .replace('<', "&lt;")
            .replace('>', "&gt;")
            .replace('"', "&quot;")
            .replace('\'', "&apos;");
        svg.contains(&escaped)
    }

    fn read_svg(dir: &Path, name: &str) -> String {
        let svg = std::fs::read_to_string(dir.join(name)).unwrap();
        assert!(svg.starts_with("<svg"), "{name}: {}", &svg[..40]);
        assert!(svg.trim_end().ends_with("</svg>"), "{name}");
        assert_eq!(
            svg.matches("<text").count(),
            svg.matches("</text>").count(),
            "{name}"
        );
        svg
    }

    #[test]
    fn no_empty_plot_a_count_changed_only_with_another_gets_none() {
        // The default run, and one point changing two counts at once: neither count has a
        // second value where the other is held, so there is nothing to plot (the smoke
        // spec's case); defaults come from the reports' architecture echo.
        let arch = |seg: u64, rop: u64| json!({"segmenter": {"count": seg}, "rop": {"count": rop}});
        let mut a = record(0, json!({"path": "lembo", "k": 0.5}), Some(1000), None);
        a["report"]["arch"] = arch(2, 4);
        let mut b = record(
            1,
            json!({"path": "lembo", "k": 0.5, "arch.segmenter.count": 4, "arch.rop.count": 8}),
            Some(800),
            None,
        );
        b["report"]["arch"] = arch(4, 8);
        let names: Vec<String> = plot_files(&[a.clone(), b], None)
            .unwrap()
            .into_iter()
            .map(|(n, _)| n)
            .collect();
        assert!(
            !names.iter().any(|n| n.starts_with("cycles_vs_units")),
            "{names:?}"
        );
        // One count changed alone is drawn, its default read from the echo.
        let mut c = record(
            2,
            json!({"path": "lembo", "k": 0.5, "arch.rop.count": 8}),
            Some(900),
            None,
        );
        c["report"]["arch"] = arch(2, 8);
        let files = plot_files(&[a, c], None).unwrap();
        let (_, svg) = files
            .iter()
            .find(|(n, _)| n.starts_with("cycles_vs_units"))
            .expect("a plot of arch.rop.count");
        let svg = String::from_utf8(svg.clone()).unwrap();
        assert!(has(&svg, "arch.rop.count"));
    }

    #[test]
    fn utilisation_captions_name_what_sets_a_point_apart_and_fit() {
        // A one-at-a-time sweep: the base, then one count changed per point.
        let arch = |seg: u64, rop: u64| json!({"segmenter": {"count": seg}, "rop": {"count": rop}});
        let mut base = record(0, json!({"path": "lembo", "k": 0.5}), Some(1000), None);
        base["report"]["arch"] = arch(2, 4);
        let mut slow = record(
            1,
            json!({"path": "lembo", "k": 0.5, "arch.segmenter.count": 1}),
            Some(3000),
            None,
        );
        slow["report"]["arch"] = arch(1, 4);
        let mut fast = record(
            2,
            json!({"path": "lembo", "k": 0.5, "arch.rop.count": 8}),
            Some(500),
            None,
        );
        fast["report"]["arch"] = arch(2, 8);
        let files = plot_files(&[base, slow, fast], None).unwrap();
        let svg = &files
            .iter()
            .find(|(n, _)| n.starts_with("utilisation"))
            .unwrap()
            .1;
        let svg = String::from_utf8(svg.clone()).unwrap();
        assert!(has(
            &svg,
            "most cycles: lembo path, k=0.5, arch.segmenter.count=1, point 1"
        ));
        assert!(has(
            &svg,
            "fewest cycles: lembo path, k=0.5, arch.rop.count=8, point 2"
        ));
        // Long captions are cut at a comma.
        let long = (0..40)
            .map(|i| format!("p{i}=1"))
            .collect::<Vec<_>>()
            .join(", ");
        let cut = fit(long, CAPTION_CHARS);
        assert!(
            cut.chars().count() <= CAPTION_CHARS && cut.ends_with(", …"),
            "{cut}"
        );
        assert_eq!(fit("short".into(), CAPTION_CHARS), "short");
    }

    #[test]
    fn series_differing_in_datapath_have_their_own_marker_and_labels_do_not_overlap() {
        let records: Vec<Value> = [("f32", 0.5), ("f64", 0.5), ("f32", 2.0), ("f64", 2.0)]
            .iter()
            .enumerate()
            .map(|(i, &(dp, k))| {
                let mut r = record(
                    i as u64,
                    json!({"path": "lembo", "k": k, "datapath": dp}),
                    Some(1000),
                    Some(40.0),
                );
                r["report"]["settings"]["datapath"] = json!(dp);
                r
            })
            .collect();
        let files = plot_files(&records, None).unwrap();
        let svg = String::from_utf8(files[0].1.clone()).unwrap();
        assert!(has(&svg, "lembo path, datapath=f32"), "f32 series");
        assert!(has(&svg, "lembo path, datapath=f64"), "f64 series");
        // Labels: nearby points take free corners; the same text on the same spot once.
        let mut labels = Labels::default();
        let a = labels.place("k=2", (100, 100)).unwrap();
        let b = labels.place("k=0.5", (102, 101)).unwrap();
        assert_ne!(a, b);
        assert!(labels.place("k=2", (101, 100)).is_none());
        let boxes: Vec<[i32; 4]> = labels.placed.iter().map(|(_, _, r)| *r).collect();
        let overlap =
            |r: [i32; 4], q: [i32; 4]| r[0] < q[2] && q[0] < r[2] && r[1] < q[3] && q[1] < r[3];
        assert!(!overlap(boxes[0], boxes[1]));
    }

    #[test]
    fn fifo_depths_get_their_own_plot() {
        let key = "arch.links.rasterizer_to_rop.fifo_depth";
        let records: Vec<Value> = [1u64, 4, 16, 64]
            .iter()
            .enumerate()
            .map(|(i, &d)| {
                record(
                    i as u64,
                    json!({"path": "lembo", "k": 0.5, key: d}),
                    Some(2000 - 10 * d),
                    None,
                )
            })
            .collect();
        let files = plot_files(&records, None).unwrap();
        let names: Vec<&str> = files.iter().map(|(n, _)| n.as_str()).collect();
        assert!(
            names.contains(&"cycles_vs_fifo_depth_sphere24.svg"),
            "{names:?}"
        );
        assert!(
            !names.iter().any(|n| n.starts_with("cycles_vs_units")),
            "{names:?}"
        );
        let svg = &files
            .iter()
            .find(|(n, _)| n.starts_with("cycles_vs_fifo"))
            .unwrap()
            .1;
        let svg = String::from_utf8(svg.clone()).unwrap();
        for text in [
            "sphere24: cycles against FIFO depths",
            "FIFO depth [entries], log scale",
            key,
        ] {
            assert!(has(&svg, text), "lacks {text:?}");
        }
    }

    #[test]
    fn an_area_budget_greys_larger_units_and_draws_a_front_per_path() {
        // Error falls with k and n; area grows with the interval managers and rasterizers.
        let mut records = Vec::new();
        for (i, (path, level, area)) in [
            ("lembo", 1.0, 4.0),
            ("lembo", 0.5, 5.0),
            ("lembo", 0.25, 9.0),
            ("triangle", 4.0, 3.0),
            ("triangle", 8.0, 5.5),
            ("triangle", 16.0, 12.0),
        ]
        .into_iter()
        .enumerate()
        {
            let params = if path == "lembo" {
                json!({"path": path, "k": level})
            } else {
                json!({"path": path, "tess": level as u64})
            };
            let mut r = record(
                i as u64,
                params,
                Some(1000 + 100 * i as u64),
                Some(30.0 + 2.0 * i as f64),
            );
            r["report"]["cost"] = json!({"area_mm2": area, "energy_pj": 1e6 * (1.0 + i as f64)});
            records.push(r);
        }
        let files = plot_files(&records, Some(6.0)).unwrap();
        let names: Vec<&str> = files.iter().map(|(n, _)| n.as_str()).collect();
        assert!(names.contains(&"error_vs_energy_sphere24.svg"), "{names:?}");
        for (name, svg) in &files {
            if !(name.starts_with("tradeoff") || name.starts_with("error_vs_energy")) {
                continue;
            }
            let svg = String::from_utf8(svg.clone()).unwrap();
            assert!(has(&svg, "units within 6 mm²"), "{name}");
            assert!(has(&svg, "over the area budget of 6 mm²"), "{name}");
            assert!(
                has(&svg, "each path&apos;s Pareto front") || has(&svg, "each path's Pareto front"),
                "{name}"
            );
            // The two larger units are drawn grey.
            assert!(svg.matches("#BEBEBE").count() >= 2, "{name}");
        }
        // Without a budget no point is grey and the front spans both paths.
        let files = plot_files(&records, None).unwrap();
        let svg = String::from_utf8(files[0].1.clone()).unwrap();
        assert!(has(&svg, "Pareto front over both paths"));
        assert!(!svg.contains("#BEBEBE"));
    }

    #[test]
    fn write_plots_draws_every_plot_a_timed_sweep_with_reference_supports() {
        let dir = tempfile::tempdir().unwrap();
        let names = write_plots(dir.path(), &sweep(), None).unwrap();
        assert_eq!(
            names,
            [
                "tradeoff_sphere24.svg",
                "cycles_vs_k_sphere24.svg",
                "cycles_vs_units_sphere24.svg",
                "utilisation_sphere24.svg"
            ]
        );
        let svg = read_svg(dir.path(), "tradeoff_sphere24.svg");
        for text in [
            "sphere24: image error against cycles",
            "simulated frame time [cycles], log scale",
            "RMS colour error 255*10^(-PSNR/20) [0-255], log scale",
            "lembo path",
            "triangle path",
            "Pareto front over both paths (circled)",
            "k=0.125",
            "n=8",
        ] {
            assert!(has(&svg, text), "tradeoff lacks {text:?}");
        }
        let svg = read_svg(dir.path(), "cycles_vs_k_sphere24.svg");
        for text in [
            "sphere24: cycles against k (lembo path)",
            "k, chord error of the extreme method [px], log scale",
            "simulated frame time [cycles]",
            // The datapath tells the series apart; the points where a count varies are
            // at k = 0.5 only.
            "datapath=f64",
            "not drawn: 4 point(s) whose other parameters were run at a single k",
        ] {
            assert!(has(&svg, text), "cycles_vs_k lacks {text:?}");
        }
        let svg = read_svg(dir.path(), "cycles_vs_units_sphere24.svg");
        for text in [
            "sphere24: cycles against unit counts",
            "unit instances [count]",
            "arch.segmenter.count",
            "arch.rasterizer.count",
            "path=lembo, arch.rasterizer.count=4, datapath=f32, k=0.5",
        ] {
            assert!(has(&svg, text), "cycles_vs_units lacks {text:?}");
        }
        let svg = read_svg(dir.path(), "utilisation_sphere24.svg");
        for text in [
            "sphere24: unit utilisation at the most and fewest cycles",
            "share of the frame time [%]",
            "most cycles: lembo path, k=0.5",
            "fewest cycles: triangle path, n=1",
            "Unit[2]",
            "starved",
        ] {
            assert!(has(&svg, text), "utilisation lacks {text:?}");
        }
    }

    #[test]
    fn functional_records_without_reference_give_no_plot_and_no_error() {
        let records: Vec<Value> = [0.25, 0.5, 1.0]
            .iter()
            .enumerate()
            .map(|(i, k)| record(i as u64, json!({"path": "lembo", "k": k}), None, None))
            .collect();
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("plots");
        assert!(write_plots(&out, &records, None).unwrap().is_empty());
        assert!(!out.exists());
    }

    #[test]
    fn records_without_accuracy_give_no_tradeoff_plot() {
        let records: Vec<Value> = [(0.25, 60_000), (0.5, 52_000), (1.0, 47_000)]
            .iter()
            .enumerate()
            .map(|(i, &(k, c))| record(i as u64, json!({"path": "lembo", "k": k}), Some(c), None))
            .collect();
        let dir = tempfile::tempdir().unwrap();
        let names = write_plots(dir.path(), &records, None).unwrap();
        assert_eq!(
            names,
            ["cycles_vs_k_sphere24.svg", "utilisation_sphere24.svg"]
        );
        let svg = read_svg(dir.path(), "cycles_vs_k_sphere24.svg");
        assert!(has(&svg, "all points"));
    }

    #[test]
    fn records_that_are_not_sweep_points_are_skipped() {
        let records = [
            json!({"index": 0}),
            json!("text"),
            json!({"report": {"settings": {}}}),
        ];
        let dir = tempfile::tempdir().unwrap();
        assert!(write_plots(dir.path(), &records, None).unwrap().is_empty());
    }

    #[test]
    fn scenes_get_their_own_plots_with_safe_file_names() {
        let mut a = record(
            0,
            json!({"path": "lembo", "k": 0.5}),
            Some(50_000),
            Some(40.0),
        );
        a["scene"] = json!("my scene/1");
        let b = record(
            1,
            json!({"path": "lembo", "k": 0.5}),
            Some(50_000),
            Some(40.0),
        );
        let dir = tempfile::tempdir().unwrap();
        let names = write_plots(dir.path(), &[a, b], None).unwrap();
        assert_eq!(
            names,
            [
                "tradeoff_my_scene_1.svg",
                "utilisation_my_scene_1.svg",
                "tradeoff_sphere24.svg",
                "utilisation_sphere24.svg"
            ]
        );
        assert!(has(
            &read_svg(dir.path(), "tradeoff_my_scene_1.svg"),
            "my scene/1: image error"
        ));
    }
}
