//! The slopes of how a run's cost grows: the exponent of the power law fitted to a series on
//! log-log axes (a slope of 1: twice the lembos, twice the cost), and the legend label that
//! states it.

use lembo_sim::plot::fmt_num;

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

/// A series' legend label: its name and its fitted slope ([`loglog_slope`]) over all its
/// points and over those from `tail_from` on (where a fixed cost no longer hides the growth).
pub fn slope_label(name: &str, points: &[(f64, f64)], tail_from: f64) -> String {
    let slope = |points: &[(f64, f64)]| {
        loglog_slope(points)
            .map(|s| format!("{s:.2}"))
            .unwrap_or_else(|| "-".into())
    };
    let tail: Vec<(f64, f64)> = points
        .iter()
        .copied()
        .filter(|p| p.0 >= tail_from)
        .collect();
    format!(
        "{name}: slope {} over all points, {} from {} on",
        slope(points),
        slope(&tail),
        fmt_num(tail_from)
    )
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
    fn a_label_names_the_series_with_its_slopes() {
        let functional = [(1e3, 0.01), (1e4, 0.1), (1e5, 1.0)];
        let timed = [(1e3, 0.02), (1e4, 0.2), (1e5, 4.0)];
        assert_eq!(
            slope_label("functional", &functional, 1e4),
            "functional: slope 1.00 over all points, 1.00 from 10k on"
        );
        assert_eq!(
            slope_label("timed", &timed, 1e4),
            "timed: slope 1.15 over all points, 1.30 from 10k on"
        );
    }
}
