//! How a run's cost grows (`examples/scaling.rs`): render time and peak memory against the
//! scene's lembos or the viewport's pixels, on log-log axes, each series with the slope of
//! the straight line fitted to it (a slope of 1: twice the lembos, twice the cost).

use super::chart::{
    draw_legend, draw_mark, fmt_num, log_axis, log_range, mesh, plot_size, svg, Entry, Mark,
    CHART_HEIGHT, FONT, PALETTE,
};
use crate::error::{Error, Result};
use plotters::prelude::*;

/// One series of a scaling plot: its label and its (x, y) points, both positive.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// What it is, as the legend says it (`functional`, `timed`).
    pub label: String,
    /// The measured points.
    pub points: Vec<(f64, f64)>,
}

/// The slope of the least-squares line through the points in log-log space (the exponent
/// b of y = a x^b), over the points with positive coordinates; None for fewer than two
/// such points or a single x.
pub fn loglog_slope(points: &[(f64, f64)]) -> Option<f64> {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite())
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    let n = logs.len() as f64;
    if logs.len() < 2 {
        return None;
    }
    let (mx, my) = logs
        .iter()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x / n, b + y / n));
    let sxx: f64 = logs.iter().map(|(x, _)| (x - mx) * (x - mx)).sum();
    let sxy: f64 = logs.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// A log-log plot of `series` against `x_desc` and `y_desc`, each series' legend entry
/// with its fitted slope ([`loglog_slope`]) over all its points and over those from
/// `tail_from` on (where a fixed cost no longer hides the growth).
pub fn loglog_svg(x_desc: &str, y_desc: &str, series: &[Series], tail_from: f64) -> Result<String> {
    let slope = |points: &[(f64, f64)]| {
        loglog_slope(points)
            .map(|s| format!("{s:.2}"))
            .unwrap_or_else(|| "-".into())
    };
    let entries: Vec<Entry> = series
        .iter()
        .enumerate()
        .map(|(k, s)| {
            let tail: Vec<(f64, f64)> = s
                .points
                .iter()
                .copied()
                .filter(|p| p.0 >= tail_from)
                .collect();
            Entry {
                mark: Some([Mark::Dot, Mark::Square, Mark::Triangle][k % 3]),
                line: true,
                color: PALETTE[k % PALETTE.len()],
                label: format!(
                    "{}: slope {} over all points, {} from {} on",
                    s.label,
                    slope(&s.points),
                    slope(&tail),
                    fmt_num(tail_from)
                ),
                note: None,
            }
        })
        .collect();
    let xs = log_range(series.iter().flat_map(|s| s.points.iter().map(|p| p.0)));
    let ys = log_range(series.iter().flat_map(|s| s.points.iter().map(|p| p.1)));
    let lines: Vec<Vec<(f64, f64)>> = series.iter().map(|s| s.points.clone()).collect();
    let plot = svg(plot_size(&entries), |root| {
        let (top, legend) = root.split_vertically(CHART_HEIGHT);
        let mut chart = ChartBuilder::on(&top)
            .margin(15)
            .caption(format!("{y_desc} against {x_desc}"), (FONT, 18))
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(log_axis(xs.clone()), log_axis(ys.clone()))?;
        mesh(&mut chart, x_desc, y_desc)?;
        for (entry, line) in entries.iter().zip(&lines) {
            chart.draw_series(LineSeries::new(
                line.iter().copied(),
                entry.color.stroke_width(2),
            ))?;
        }
        for (entry, line) in entries.iter().zip(&lines) {
            for p in line {
                let at = chart.backend_coord(p);
                draw_mark(&top, at, entry.mark.unwrap_or(Mark::Dot), entry.color)?;
            }
        }
        draw_legend(&legend, &entries)
    });
    match plot {
        Some(Ok(text)) => Ok(text),
        Some(Err(e)) => Err(Error::Internal(format!("the scaling plot: {e}"))),
        None => Err(Error::Internal("the scaling plot drew nothing".into())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_slope_is_the_exponent_of_a_power_law() {
        let cube: Vec<(f64, f64)> = [1.0, 2.0, 10.0, 300.0]
            .map(|x| (x, 5.0 * x * x * x))
            .to_vec();
        assert!((loglog_slope(&cube).unwrap() - 3.0).abs() < 1e-12);
        let flat = [(1.0, 7.0), (1e6, 7.0)];
        assert!(loglog_slope(&flat).unwrap().abs() < 1e-12);
        assert_eq!(loglog_slope(&[(1.0, 2.0)]), None);
        assert_eq!(loglog_slope(&[(3.0, 2.0), (3.0, 5.0)]), None);
        assert_eq!(loglog_slope(&[(0.0, 2.0), (-1.0, 5.0), (4.0, 1.0)]), None);
    }

    #[test]
    fn a_plot_names_each_series_with_its_slopes() {
        let series = [
            Series {
                label: "functional".into(),
                points: vec![(1e3, 0.01), (1e4, 0.1), (1e5, 1.0)],
            },
            Series {
                label: "timed".into(),
                points: vec![(1e3, 0.02), (1e4, 0.2), (1e5, 4.0)],
            },
        ];
        let svg = loglog_svg("lembos", "render time [s]", &series, 1e4).unwrap();
        assert!(svg.starts_with("<svg"), "{}", &svg[..40]);
        assert!(svg.contains("functional: slope 1.00 over all points, 1.00 from 10k on"));
        assert!(svg.contains("timed: slope 1.15 over all points, 1.30 from 10k on"));
    }
}
