//! A log-log line chart of labelled series in the sweep plots' style, for figures drawn
//! from plain numbers (`examples/scaling/` draws how a run's cost grows with it).

use super::chart::{
    draw_legend, draw_mark, log_axis, log_range, mesh, plot_size, svg, Entry, Mark, CHART_HEIGHT,
    FONT, PALETTE,
};
use crate::error::{Error, Result};
use plotters::prelude::*;

/// An SVG of `lines` (each a legend label and its (x, y) points, both positive) on log-log
/// axes described by `x_desc` and `y_desc`, titled "`y_desc` against `x_desc`": each line
/// in the palette's next colour with its points marked, the legend below the chart.
pub fn loglog_svg(
    x_desc: &str,
    y_desc: &str,
    lines: &[(String, Vec<(f64, f64)>)],
) -> Result<String> {
    let entries: Vec<Entry> = lines
        .iter()
        .enumerate()
        .map(|(k, (label, _))| Entry {
            mark: Some([Mark::Dot, Mark::Square, Mark::Triangle][k % 3]),
            line: true,
            color: PALETTE[k % PALETTE.len()],
            label: label.clone(),
            note: None,
        })
        .collect();
    let xs = log_range(lines.iter().flat_map(|(_, p)| p.iter().map(|p| p.0)));
    let ys = log_range(lines.iter().flat_map(|(_, p)| p.iter().map(|p| p.1)));
    let plot = svg(plot_size(&entries), |root| {
        let (top, legend) = root.split_vertically(CHART_HEIGHT);
        let mut chart = ChartBuilder::on(&top)
            .margin(15)
            .caption(format!("{y_desc} against {x_desc}"), (FONT, 18))
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(log_axis(xs.clone()), log_axis(ys.clone()))?;
        mesh(&mut chart, x_desc, y_desc)?;
        for (entry, (_, line)) in entries.iter().zip(lines) {
            chart.draw_series(LineSeries::new(
                line.iter().copied(),
                entry.color.stroke_width(2),
            ))?;
        }
        for (entry, (_, line)) in entries.iter().zip(lines) {
            for p in line {
                let at = chart.backend_coord(p);
                draw_mark(&top, at, entry.mark.unwrap_or(Mark::Dot), entry.color)?;
            }
        }
        draw_legend(&legend, &entries)
    });
    match plot {
        Some(Ok(text)) => Ok(text),
        Some(Err(e)) => Err(Error::Internal(format!("the log-log plot: {e}"))),
        None => Err(Error::Internal("the log-log plot drew nothing".into())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plot_draws_every_line_with_its_label() {
        let lines = [
            (
                "functional".to_string(),
                vec![(1e3, 0.01), (1e4, 0.1), (1e5, 1.0)],
            ),
            (
                "timed".to_string(),
                vec![(1e3, 0.02), (1e4, 0.2), (1e5, 4.0)],
            ),
        ];
        let svg = loglog_svg("lembos", "render time [s]", &lines).unwrap();
        assert!(svg.starts_with("<svg"), "{}", &svg[..40]);
        assert!(svg.contains("render time [s] against lembos"));
        // The labels are drawn as legend text (the title names neither).
        assert!(svg.contains("functional") && svg.contains("timed"), "{svg}");
    }
}
