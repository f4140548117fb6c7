//! Plot 5: cycles, energy and PSNR against any numeric swept field (`vs_<field>_<scene>.svg`;
//! the bandwidth of the frame-buffer port, the clock, a unit count, a technology figure, the
//! samples a pixel): one series per path, each path's other varying parameters held at
//! their most common value among its runs, said in the title and in the legend (a tie
//! says which values tied).

use super::chart::{
    draw_legend, draw_lines, fmt_value, log_axis, mesh, min_max, svg, Area, Entry, Plot, FONT,
    LEMBO, MARKS, PALETTE, TRIANGLE, WIDTH,
};
use super::point::{most_common, varying, Point};
use plotters::prelude::*;
use serde_json::Value;

/// The parameters a field plot does not put on its x axis: the knobs have their own plots
/// (`cycles_vs_k`, and the trade-off plots over both), the sensitivity marker is a label.
const NOT_AXES: [&str; 4] = ["k", "tess", "path", "sensitivity"];

/// The numeric fields that vary among `points` with cycles, each with its plot.
pub(super) fn field_plots(scene: &str, points: &[Point]) -> Vec<(String, Plot)> {
    let pts: Vec<&Point> = points.iter().filter(|p| p.cycles.is_some()).collect();
    varying(&pts)
        .into_iter()
        .filter(|f| !NOT_AXES.contains(&f.as_str()))
        .filter(|f| {
            pts.iter()
                .all(|p| p.param(f).is_null() || p.param(f).is_number())
        })
        .filter_map(|f| {
            let plot = against(scene, &pts, &f)?;
            Some((f, Some(plot)))
        })
        .collect()
}

/// One run on a line: (field value, cycles, energy \[µJ\], PSNR \[dB\]).
type Sample = (f64, f64, Option<f64>, Option<f64>);

/// What a panel's y axis reads from a sample.
type Pick = fn(&Sample) -> Option<f64>;

/// One path's runs at one knob level along `field`, the other varying parameters held.
struct Line {
    path: &'static str,
    /// The knob level (`k=0.5`, `n=4`) where the path's runs vary it.
    knob: Option<String>,
    /// The held values, `name=value`, a tie said as `(tied with ...)`.
    held: Vec<String>,
    /// (field value, cycles, energy \[µJ\], PSNR \[dB\]) in ascending field value.
    points: Vec<Sample>,
}

/// Each path's lines along `field`, one a knob level (the trade the plot is read for); a
/// level whose held runs take one value of the field has none.
fn lines(pts: &[&Point], field: &str) -> Vec<Line> {
    let keys = varying(pts);
    let mut lines = Vec::new();
    for (path, knob) in [("lembo", "k"), ("triangle", "tess")] {
        let mut held: Vec<&Point> = pts.iter().copied().filter(|p| p.path == path).collect();
        let mut said = Vec::new();
        for other in keys
            .iter()
            .filter(|k| *k != field && !["path", knob].contains(&k.as_str()))
        {
            let (value, tied) = most_common(&held, other);
            held.retain(|p| p.param(other) == &value);
            if value.is_null() {
                continue;
            }
            let mut s = format!("{other}={}", fmt_value(&value));
            if !tied.is_empty() {
                let tied: Vec<String> = tied.iter().map(fmt_value).collect();
                s += &format!(" (tied with {})", tied.join(", "));
            }
            said.push(s);
        }
        let mut levels: Vec<(Value, Vec<&Point>)> = Vec::new();
        for p in held {
            let level = p.param(knob).clone();
            match levels.iter_mut().find(|(l, _)| *l == level) {
                Some((_, group)) => group.push(p),
                None => levels.push((level, vec![p])),
            }
        }
        levels.sort_by(|a, b| {
            let (x, y) = (a.0.as_f64().unwrap_or(0.0), b.0.as_f64().unwrap_or(0.0));
            // Coarse to fine: k falling, n rising.
            if knob == "k" {
                y.total_cmp(&x)
            } else {
                x.total_cmp(&y)
            }
        });
        let several = levels.len() > 1;
        for (level, group) in levels {
            let mut points: Vec<Sample> = group
                .iter()
                .filter_map(|p| {
                    let psnr = p
                        .report
                        .pointer("/accuracy/psnr_db")
                        .and_then(Value::as_f64)
                        .filter(|v| v.is_finite());
                    Some((
                        p.param(field).as_f64()?,
                        p.cycles? as f64,
                        p.energy_pj.map(|e| e * 1e-6),
                        psnr,
                    ))
                })
                .collect();
            points.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
            if points.windows(2).any(|w| w[0].0 != w[1].0) {
                lines.push(Line {
                    path,
                    knob: several.then(|| {
                        format!(
                            "{}={}",
                            if knob == "k" { "k" } else { "n" },
                            fmt_value(&level)
                        )
                    }),
                    held: said.clone(),
                    points,
                });
            }
        }
    }
    lines
}

/// The three panels of `field`; None when no path has a line.
fn against(scene: &str, pts: &[&Point], field: &str) -> Plot {
    let lines = lines(pts, field);
    if lines.is_empty() {
        return None;
    }
    let entries: Vec<Entry> = lines
        .iter()
        .enumerate()
        .map(|(i, l)| Entry {
            mark: Some(MARKS[i % MARKS.len()]),
            line: true,
            color: match (lines.len() > 2, l.path) {
                (true, _) => PALETTE[i % PALETTE.len()],
                (false, "lembo") => LEMBO,
                (false, _) => TRIANGLE,
            },
            label: match &l.knob {
                Some(knob) => format!("{} path, {knob}", l.path),
                None => format!("{} path", l.path),
            },
            note: Some(if l.held.is_empty() {
                "no other parameter varies".to_string()
            } else {
                format!("held at the most common value: {}", l.held.join(", "))
            }),
        })
        .collect();
    let mut paths: Vec<&Line> = lines.iter().collect();
    paths.dedup_by_key(|l| l.path);
    let held: Vec<String> = paths
        .iter()
        .map(|l| {
            format!(
                "{}: {}",
                l.path,
                if l.held.is_empty() {
                    "nothing held".to_string()
                } else {
                    l.held.join(", ")
                }
            )
        })
        .collect();
    let title = format!("{scene}: cycles, energy and PSNR against {field}");
    let subtitle = format!("held: {}", held.join("; "));
    let (x_lo, x_hi) = min_max(lines.iter().flat_map(|l| l.points.iter().map(|p| p.0)));
    let log = x_lo > 0.0 && x_hi / x_lo >= 8.0;
    let panel = 330u32;
    let legend: u32 = entries.iter().map(Entry::height).sum();
    svg((WIDTH, 80 + 3 * panel + legend + 10), |root| {
        let (head, rest) = root.split_vertically(80);
        head.draw(&Text::new(title.as_str(), (20, 12), (FONT, 20)))?;
        for (i, chunk) in wrap(&subtitle, 110).iter().take(2).enumerate() {
            head.draw(&Text::new(
                chunk.as_str(),
                (20, 42 + 18 * i as i32),
                (FONT, 13),
            ))?;
        }
        let (charts, legend_area) = rest.split_vertically(3 * panel);
        let panels = charts.split_evenly((3, 1));
        let picks: [(&str, Pick); 3] = [
            ("simulated frame time [cycles]", |p| Some(p.1)),
            ("energy of the frame [µJ]", |p| p.2),
            ("PSNR against the reference [dB]", |p| p.3),
        ];
        for (area, (y_desc, pick)) in panels.iter().zip(picks) {
            let series: Vec<Vec<(f64, f64)>> = lines
                .iter()
                .map(|l| {
                    l.points
                        .iter()
                        .filter_map(|p| Some((p.0, pick(p)?)))
                        .collect()
                })
                .collect();
            panel_chart(
                root,
                area,
                field,
                y_desc,
                log,
                (x_lo, x_hi),
                &entries,
                &series,
            )?;
        }
        draw_legend(&legend_area, &entries)
    })
}

/// One panel: `series` against the field, y from zero (PSNR: around its values).
#[allow(clippy::too_many_arguments)]
fn panel_chart(
    root: &Area,
    area: &Area,
    field: &str,
    y_desc: &str,
    log: bool,
    (x_lo, x_hi): (f64, f64),
    entries: &[Entry],
    series: &[Vec<(f64, f64)>],
) -> super::chart::DrawResult {
    let (y_lo, y_hi) = min_max(series.iter().flatten().map(|p| p.1));
    if !y_hi.is_finite() {
        area.draw(&Text::new(
            format!("{y_desc}: no run measured it"),
            (90, 40),
            (FONT, 14),
        ))?;
        return Ok(());
    }
    let y = if y_desc.starts_with("PSNR") {
        (y_lo - 1.0)..(y_hi + 1.0)
    } else {
        0.0..(y_hi * 1.1).max(1e-9)
    };
    let mut builder = ChartBuilder::on(area);
    builder
        .margin(10)
        .margin_right(30)
        .x_label_area_size(45)
        .y_label_area_size(80);
    let x_desc = if log {
        format!("{field}, log scale")
    } else {
        field.to_string()
    };
    if log {
        let mut chart = builder.build_cartesian_2d(log_axis(x_lo / 1.25..x_hi * 1.25), y)?;
        mesh(&mut chart, &x_desc, y_desc)?;
        draw_lines(root, &mut chart, entries, series)
    } else {
        let pad = ((x_hi - x_lo) * 0.05).max(0.5);
        let mut chart = builder.build_cartesian_2d(x_lo - pad..x_hi + pad, y)?;
        mesh(&mut chart, &x_desc, y_desc)?;
        draw_lines(root, &mut chart, entries, series)
    }
}

/// `text` in lines of at most `chars`, broken at spaces.
fn wrap(text: &str, chars: usize) -> Vec<String> {
    let mut lines: Vec<String> = vec![String::new()];
    for word in text.split(' ') {
        let last = lines.last_mut().expect("one line");
        if !last.is_empty() && last.chars().count() + 1 + word.chars().count() > chars {
            lines.push(word.to_string());
        } else {
            if !last.is_empty() {
                last.push(' ');
            }
            last.push_str(word);
        }
    }
    lines
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn point(path: &str, bw: u64, rops: u64, cycles: u64) -> Point {
        Point::from_record(&json!({
            "index": 0, "scene": "s",
            "params": {"path": path, "arch.framebuffer.bytes_per_cycle": bw, "arch.rop.count": rops},
            "report": {"settings": {"path": path}, "cycles": {"total": cycles},
                       "cost": {"energy_pj": 2e6}, "accuracy": {"psnr_db": 40.0}}
        }))
        .unwrap()
    }

    /// A tie between two held values is said, not silently broken, and each path gets its
    /// own line along the field.
    #[test]
    fn a_field_plot_says_what_it_holds_and_which_values_tied() {
        let points = vec![
            point("lembo", 32, 4, 900),
            point("lembo", 64, 4, 500),
            point("lembo", 32, 8, 800),
            point("lembo", 64, 8, 400),
            point("triangle", 32, 4, 1000),
            point("triangle", 64, 4, 700),
        ];
        let pts: Vec<&Point> = points.iter().collect();
        let ls = lines(&pts, "arch.framebuffer.bytes_per_cycle");
        assert_eq!(ls.len(), 2);
        assert_eq!(ls[0].path, "lembo");
        assert_eq!(ls[0].knob, None, "one k: no level in the label");
        assert_eq!(ls[0].held, ["arch.rop.count=4 (tied with 8)"]);
        assert_eq!(
            ls[0].points.iter().map(|p| (p.0, p.1)).collect::<Vec<_>>(),
            [(32.0, 900.0), (64.0, 500.0)]
        );
        assert_eq!(ls[1].held, ["arch.rop.count=4"]);
        let plots = field_plots("s", &points);
        let names: Vec<&str> = plots.iter().map(|(f, _)| f.as_str()).collect();
        assert_eq!(
            names,
            ["arch.framebuffer.bytes_per_cycle", "arch.rop.count"]
        );
        let svg = plots[0].1.as_ref().unwrap().as_ref().unwrap();
        assert!(
            svg.contains("tied with 8"),
            "the title or legend says the tie"
        );
    }
}
