//! Plot 1: image error against cycles or energy, per path, with Pareto fronts (over both
//! paths, or per path within a sweep's area budget), and the placement of the points'
//! level labels.

use super::chart::{
    draw_legend, draw_mark, fmt_num, framed, log_axis, log_range, mesh, plot_size, svg, Entry,
    Mark, Plot, CHART_HEIGHT, FONT, LEMBO, MARKS, PALETTE, TRIANGLE,
};
use super::point::{assignment, pareto_front, varying, Point};
use plotters::prelude::*;
use std::collections::BTreeMap;

/// Points over a sweep's area budget.
const OVER_BUDGET: RGBColor = RGBColor(190, 190, 190);

/// What an error plot puts on its x axis.
#[derive(Clone, Copy)]
pub(super) enum Against {
    /// Simulated frame time.
    Cycles,
    /// The frame's energy (report.json `cost`).
    Energy,
}

/// What an error plot puts on its y axis.
#[derive(Clone, Copy)]
pub(super) enum ErrorAxis {
    /// RMS colour error from PSNR.
    Rms,
    /// Mean FLIP (Andersson et al. 2020).
    Flip,
}

impl ErrorAxis {
    fn y(self, p: &Point) -> Option<f64> {
        match self {
            ErrorAxis::Rms => p.rms_error,
            ErrorAxis::Flip => p.flip_mean,
        }
    }
}

impl Against {
    fn x(self, p: &Point) -> Option<f64> {
        match self {
            Against::Cycles => p.cycles.map(|c| c as f64),
            Against::Energy => p.energy_pj.filter(|e| *e > 0.0),
        }
    }
}

/// Plot 1: image error (RMS colour error, or mean FLIP: `axis`) against cycles
/// (`Against::Cycles`, `tradeoff_*`, `flip_tradeoff_*`) or energy (`error_vs_energy_*`,
/// `flip_vs_energy_*`), one series per path. Without an area budget, the Pareto front over
/// both paths is circled; with one, points whose unit is larger are drawn grey and left
/// out, and each path gets its own front among the configurations within the budget.
pub(super) fn error_against(
    scene: &str,
    points: &[Point],
    against: Against,
    axis: ErrorAxis,
    budget: Option<f64>,
) -> Plot {
    let pts: Vec<(&Point, (f64, f64))> = points
        .iter()
        .filter_map(|p| Some((p, (against.x(p)?, axis.y(p)?))))
        .collect();
    if pts.is_empty() {
        return None;
    }
    let xy: Vec<(f64, f64)> = pts.iter().map(|&(_, xy)| xy).collect();
    let mut by_path: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
    for (i, (p, _)) in pts.iter().enumerate() {
        by_path.entry(p.path.as_str()).or_default().push(i);
    }
    let fronts = fronts(&pts, &by_path, budget);
    let paths: Vec<&str> = by_path.keys().copied().collect();
    let (series, mut entries) = series(&pts, &paths);
    let measure = match against {
        Against::Cycles => "cycles",
        Against::Energy => "energy",
    };
    entries.extend(front_entries(budget, measure));
    let error = match axis {
        ErrorAxis::Rms => "image error",
        ErrorAxis::Flip => "FLIP",
    };
    let title = match budget {
        None => format!("{scene}: {error} against {measure}"),
        Some(b) => format!(
            "{scene}: {error} against {measure}, units within {} mm²",
            fmt_num(b)
        ),
    };
    let x_desc = match against {
        Against::Cycles => "simulated frame time [cycles], log scale",
        Against::Energy => "energy of the frame [pJ] (report.json cost), log scale",
    };
    svg(plot_size(&entries), |root| {
        let (plot, legend) = root.split_vertically(CHART_HEIGHT);
        let mut chart = framed(&plot, &title, 20).build_cartesian_2d(
            log_axis(log_range(xy.iter().map(|p| p.0))),
            log_axis(log_range(xy.iter().map(|p| p.1))),
        )?;
        mesh(
            &mut chart,
            x_desc,
            match axis {
                ErrorAxis::Rms => "RMS colour error 255*10^(-PSNR/20) [0-255], log scale",
                ErrorAxis::Flip => "mean FLIP [0-1] (report.json accuracy.flip_mean), log scale",
            },
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
        for s in &series {
            for &i in &s.members {
                let at = chart.backend_coord(&xy[i]);
                let color = if within(budget, pts[i].0) {
                    s.color
                } else {
                    OVER_BUDGET
                };
                draw_mark(root, at, s.mark, color)?;
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

/// Whether `p` is within the area budget (every point is, without one).
fn within(budget: Option<f64>, p: &Point) -> bool {
    match (budget, p.area_mm2) {
        (None, _) => true,
        (Some(b), Some(a)) => a <= b,
        (Some(_), None) => false,
    }
}

/// The fronts, each with its colour and its points (indices into `pts`) in order: one over
/// both paths, or one per path (`by_path`) within the budget.
fn fronts(
    pts: &[(&Point, (f64, f64))],
    by_path: &BTreeMap<&str, Vec<usize>>,
    budget: Option<f64>,
) -> Vec<(RGBColor, Vec<usize>)> {
    let front_of = |members: &[usize]| -> Vec<usize> {
        let kept: Vec<usize> = members
            .iter()
            .copied()
            .filter(|&i| within(budget, pts[i].0))
            .collect();
        let sub: Vec<(f64, f64)> = kept.iter().map(|&i| pts[i].1).collect();
        pareto_front(&sub).into_iter().map(|j| kept[j]).collect()
    };
    match budget {
        None => vec![(BLACK, front_of(&(0..pts.len()).collect::<Vec<_>>()))],
        Some(_) => by_path
            .iter()
            .enumerate()
            .map(|(s, (path, members))| (path_style(path, s).0, front_of(members)))
            .collect(),
    }
}

/// One series of an error plot: its points (indices into the plotted points), its colour
/// and its marker.
struct Series {
    members: Vec<usize>,
    color: RGBColor,
    mark: Mark,
}

/// The series of an error plot: a path, split by the samples a pixel, the datapath and the
/// blend mode where they vary, so points that differ only in those keep apart by their
/// marker (with `samples` on an axis, both knobs show: each series one sample count, its
/// points labelled with k or n). A path keeps its colour (`paths` ranks them); its
/// variants take its marker, then the others in turn. Each series comes with its legend
/// entry.
fn series(pts: &[(&Point, (f64, f64))], paths: &[&str]) -> (Vec<Series>, Vec<Entry>) {
    let all: Vec<&Point> = pts.iter().map(|(p, _)| *p).collect();
    let variant_keys: Vec<String> = varying(&all)
        .into_iter()
        .filter(|k| k == "samples" || k == "datapath" || k == "blend")
        .collect();
    let mut members: BTreeMap<(String, String), Vec<usize>> = BTreeMap::new();
    for (i, (p, _)) in pts.iter().enumerate() {
        let variant = assignment(p, &variant_keys);
        members
            .entry((p.path.clone(), variant))
            .or_default()
            .push(i);
    }
    let style_of = |path: &str, variant_rank: usize| {
        let s = paths.iter().position(|p| *p == path).unwrap_or(0);
        let (color, mark) = path_style(path, s);
        let marks: Vec<Mark> = std::iter::once(mark)
            .chain(MARKS.iter().copied().filter(|m| *m != mark))
            .collect();
        (color, marks[variant_rank % marks.len()])
    };
    let mut rank: BTreeMap<String, usize> = BTreeMap::new();
    members
        .into_iter()
        .map(|((path, variant), members)| {
            let r = rank.entry(path.clone()).or_default();
            let (color, mark) = style_of(&path, *r);
            *r += 1;
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
            let entry = Entry {
                mark: Some(mark),
                line: false,
                color,
                label: if variant.is_empty() {
                    format!("{what}{levels}")
                } else {
                    format!("{what}, {variant}{levels}")
                },
                note: None,
            };
            (
                Series {
                    members,
                    color,
                    mark,
                },
                entry,
            )
        })
        .unzip()
}

/// The legend's entries for the fronts and, with an area budget, for the points over it;
/// `measure` is what the x axis shows (`cycles`, `energy`).
fn front_entries(budget: Option<f64>, measure: &str) -> Vec<Entry> {
    match budget {
        None => vec![Entry {
            mark: Some(Mark::Ring),
            line: true,
            color: BLACK,
            label: format!("Pareto front over both paths (circled): no other point has both less {measure} and less error"),
            note: None,
        }],
        Some(b) => vec![
            Entry {
                mark: Some(Mark::Ring),
                line: true,
                color: BLACK,
                label: format!("each path's Pareto front (circled) among configurations of at most {} mm²", fmt_num(b)),
                note: None,
            },
            Entry {
                mark: Some(Mark::Dot),
                line: false,
                color: OVER_BUDGET,
                label: format!("over the area budget of {} mm² (report.json cost.area_mm2)", fmt_num(b)),
                note: None,
            },
        ],
    }
}

/// Labels placed beside their points so that no two overlap: each tries the four corners
/// around its point and is left out when all four are taken or the same text is already
/// near (the same level on two datapaths).
#[derive(Default)]
pub(super) struct Labels {
    /// Placed labels: text, point, and box (x0, y0, x1, y1) in pixels.
    pub(super) placed: Vec<(String, (i32, i32), [i32; 4])>,
}

impl Labels {
    /// Where to draw `text` for the point at `at`, if anywhere.
    pub(super) fn place(&mut self, text: &str, at: (i32, i32)) -> Option<(i32, i32)> {
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
