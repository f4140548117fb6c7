//! The measurements summarised: per family, datapath and k, and by screen extent.

use super::*;
use lembo_sim::datapath::Datapath;
use serde::Serialize;
use std::fmt::Write as _;

/// The aggregate of one family, datapath and k.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// The family summarised.
    pub family: Family,
    /// The datapath.
    pub datapath: Datapath,
    /// The tolerance k \[pixels\].
    pub k_px: f64,
    /// Cases measured.
    pub cases: u64,
    /// Cases whose render gave an error or panicked.
    pub failures: u64,
    /// Cases with at least one fragment: the slack statistics are over these.
    pub drawn: u64,
    /// Median and largest `max_scanline_deviation_px − k` \[pixels\]; None when nothing
    /// was drawn.
    pub slack_median_px: Option<f64>,
    /// Largest `slack_px` over the cases \[pixels\]; None without fragments.
    pub slack_max_px: Option<f64>,
    /// Fraction of the drawn cases whose slack is at most [`HOLD_TOLERANCE_PX`].
    pub holds_frac: f64,
    /// Over the cases rendered without failure.
    pub false_positive_frac_mean: f64,
    /// Largest `false_positive_frac`.
    pub false_positive_frac_max: f64,
    /// Mean `false_negative_frac`.
    pub false_negative_frac_mean: f64,
    /// Largest `false_negative_frac`.
    pub false_negative_frac_max: f64,
    /// Largest and mean pixels whose winning lembo differs from f64's (0 for f64).
    pub winner_diff_vs_f64_px_max: u64,
    /// Mean `winner_diff_vs_f64_px` \[pixels\].
    pub winner_diff_vs_f64_px_mean: f64,
    /// Largest colour channel difference from f64 over pixels with the same winner [0-255]
    /// (0 for f64).
    pub shade_diff_vs_f64_max: u64,
    /// Unpaired roots over the cases.
    pub unpaired_roots: u64,
    /// Cases with at least one unpaired root.
    pub cases_with_unpaired_roots: u64,
    /// Crack pixels over the cases \[pixels\].
    pub crack_pixels: u64,
    /// Double hits over the cases \[pixels\].
    pub double_hit_pixels: u64,
    /// Sum of the renders' wall times \[seconds\] (host-dependent).
    pub render_seconds: f64,
}

fn median(sorted: &[f64]) -> Option<f64> {
    let n = sorted.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(sorted[n / 2]),
        _ => Some(0.5 * (sorted[n / 2 - 1] + sorted[n / 2])),
    }
}

/// Aggregates the measurements per family, datapath and k, in the settings' order (family,
/// then k, then f32 before f64).
pub fn summarise(settings: &StudySettings, results: &[CaseResult]) -> Vec<Summary> {
    let mut out = Vec::new();
    for &family in &settings.families {
        for &k in &settings.ks {
            for datapath in [Datapath::F32, Datapath::F64] {
                let ms: Vec<&Measurement> = results
                    .iter()
                    .filter(|r| r.family == family)
                    .flat_map(|r| &r.measurements)
                    .filter(|m| m.datapath == datapath && m.k_px == k)
                    .collect();
                let ok: Vec<&&Measurement> = ms.iter().filter(|m| m.status == "ok").collect();
                let mut slack: Vec<f64> = ok.iter().filter_map(|m| m.slack_px).collect();
                slack.sort_by(f64::total_cmp);
                let n_ok = ok.len().max(1) as f64;
                let mean = |f: fn(&Measurement) -> f64| ok.iter().map(|m| f(m)).sum::<f64>() / n_ok;
                let max = |f: fn(&Measurement) -> f64| ok.iter().map(|m| f(m)).fold(0.0, f64::max);
                let sum = |f: fn(&Measurement) -> u64| ok.iter().map(|m| f(m)).sum::<u64>();
                out.push(Summary {
                    family,
                    datapath,
                    k_px: k,
                    cases: ms.len() as u64,
                    failures: (ms.len() - ok.len()) as u64,
                    drawn: slack.len() as u64,
                    slack_median_px: median(&slack),
                    slack_max_px: slack.last().copied(),
                    holds_frac: if slack.is_empty() {
                        1.0
                    } else {
                        slack.iter().filter(|&&s| s <= HOLD_TOLERANCE_PX).count() as f64
                            / slack.len() as f64
                    },
                    false_positive_frac_mean: mean(|m| m.false_positive_frac),
                    false_positive_frac_max: max(|m| m.false_positive_frac),
                    false_negative_frac_mean: mean(|m| m.false_negative_frac),
                    false_negative_frac_max: max(|m| m.false_negative_frac),
                    winner_diff_vs_f64_px_max: ok
                        .iter()
                        .map(|m| m.winner_diff_vs_f64_px)
                        .max()
                        .unwrap_or(0),
                    winner_diff_vs_f64_px_mean: mean(|m| m.winner_diff_vs_f64_px as f64),
                    shade_diff_vs_f64_max: ok
                        .iter()
                        .map(|m| m.shade_diff_vs_f64_max)
                        .max()
                        .unwrap_or(0),
                    unpaired_roots: sum(|m| m.unpaired_roots),
                    cases_with_unpaired_roots: ok.iter().filter(|m| m.unpaired_roots > 0).count()
                        as u64,
                    crack_pixels: sum(|m| m.crack_pixels),
                    double_hit_pixels: sum(|m| m.double_hit_pixels),
                    render_seconds: ms.iter().map(|m| m.render_seconds).sum(),
                });
            }
        }
    }
    out
}

/// f32's slack against the magnitude of the screen coordinates, half a decade per row.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ExtentSummary {
    /// The bin: largest screen coordinate in [lo_px, hi_px) \[pixels\], hi_px = √10 lo_px.
    pub lo_px: f64,
    /// Upper end of the screen-extent bucket \[pixels\].
    pub hi_px: f64,
    /// The tolerance k \[pixels\].
    pub k_px: f64,
    /// Drawn f32 cases in the bin.
    pub drawn: u64,
    /// Largest f32 slack \[pixels\].
    pub f32_slack_max_px: f64,
    /// Drawn f32 cases whose slack is at most [`HOLD_TOLERANCE_PX`].
    pub f32_holds: u64,
    /// Largest f64 slack over the same cases \[pixels\].
    pub f64_slack_max_px: f64,
}

/// f32's slack by half decade of the largest screen coordinate, over the orthographic families
/// (the perspective one is left out: its violations are the segmenter's, not f32's).
pub fn by_extent(settings: &StudySettings, results: &[CaseResult]) -> Vec<ExtentSummary> {
    let ortho = |m: &&Measurement| m.family != Family::SteepPerspective && m.status == "ok";
    let bin = |m: &Measurement| (2.0 * m.max_screen_coordinate_px.max(1.0).log10()).floor() as i32;
    let all: Vec<&Measurement> = results
        .iter()
        .flat_map(|r| &r.measurements)
        .filter(ortho)
        .filter(|m| m.slack_px.is_some())
        .collect();
    let (lo, hi) = all.iter().fold((i32::MAX, i32::MIN), |(lo, hi), m| {
        (lo.min(bin(m)), hi.max(bin(m)))
    });
    let mut out = Vec::new();
    for d in lo..=hi {
        for &k in &settings.ks {
            let of = |dp: Datapath| {
                all.iter()
                    .filter(move |m| bin(m) == d && m.k_px == k && m.datapath == dp)
                    .filter_map(|m| m.slack_px)
            };
            let f32s: Vec<f64> = of(Datapath::F32).collect();
            if f32s.is_empty() {
                continue;
            }
            out.push(ExtentSummary {
                lo_px: 10f64.powf(0.5 * d as f64),
                hi_px: 10f64.powf(0.5 * (d + 1) as f64),
                k_px: k,
                drawn: f32s.len() as u64,
                f32_slack_max_px: f32s.iter().copied().fold(f64::MIN, f64::max),
                f32_holds: f32s.iter().filter(|&&s| s <= HOLD_TOLERANCE_PX).count() as u64,
                f64_slack_max_px: of(Datapath::F64).fold(f64::MIN, f64::max),
            });
        }
    }
    out
}

/// [`by_extent`] as a markdown table.
pub fn extent_markdown(rows: &[ExtentSummary]) -> String {
    let mut t = String::from(
        "| largest screen coordinate (px) | k (px) | cases | f32 slack max (px) | f32 holds | f64 slack max (px) |\n\
         |---|---|---|---|---|---|\n",
    );
    for r in rows {
        let _ = writeln!(
            t,
            "| {:.0} - {:.0} | {} | {} | {} | {}/{} | {} |",
            r.lo_px,
            r.hi_px,
            r.k_px,
            r.drawn,
            slack(Some(r.f32_slack_max_px)),
            r.f32_holds,
            r.drawn,
            slack(Some(r.f64_slack_max_px)),
        );
    }
    t
}

/// An f64 slack above this is a defect of the method, not rounding \[pixels\]: f64 rounding
/// of screen coordinates up to 10⁶ px stays below 10⁻⁸ px.
pub const F64_DEFECT_PX: f64 = 1e-6;

/// Measurements a user should look at: a failure, an f64 slack above [`F64_DEFECT_PX`],
/// or unpaired roots.
pub fn anomalies(results: &[CaseResult]) -> Vec<&Measurement> {
    results
        .iter()
        .flat_map(|r| &r.measurements)
        .filter(|m| {
            m.status != "ok"
                || m.unpaired_roots > 0
                || (m.datapath == Datapath::F64 && m.slack_px.is_some_and(|s| s > F64_DEFECT_PX))
        })
        .collect()
}

/// A slack in pixels, short: `-0.250`, `1.2e-4`, `-3.0e-12`.
fn slack(s: Option<f64>) -> String {
    match s {
        None => "-".into(),
        Some(0.0) => "0".into(),
        Some(s) if s.abs() >= 0.01 => format!("{s:.3}"),
        Some(s) => format!("{s:.1e}"),
    }
}

/// A fraction, short: `0`, `3.2e-5`.
fn frac(f: f64) -> String {
    if f == 0.0 {
        "0".into()
    } else {
        format!("{f:.1e}")
    }
}

/// The summaries as a markdown table: one row per family and k, f32 and f64 side by side.
/// Coverage errors are fractions of the pixels the reference covers.
pub fn markdown(summaries: &[Summary]) -> String {
    let mut t = String::new();
    t.push_str(
        "| family | k (px) | slack median f32 / f64 (px) | slack max f32 / f64 (px) | holds f32 / f64 | \
         false + mean / max, f32 | false + mean / max, f64 | false − mean / max, f32 | \
         false − mean / max, f64 | f32 vs f64: winner ≠ (px) mean / max; shade max | unpaired, cracks, double hits f32; f64 | \
         failures | ms per render f32 / f64 |\n",
    );
    t.push_str("|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for pair in summaries.chunks(2) {
        let [a, b] = pair else { continue };
        let (s32, s64) = if a.datapath == Datapath::F32 {
            (a, b)
        } else {
            (b, a)
        };
        let holds =
            |s: &Summary| format!("{}/{}", (s.holds_frac * s.drawn as f64).round(), s.drawn);
        let ms = |s: &Summary| 1e3 * s.render_seconds / s.cases.max(1) as f64;
        let _ = writeln!(
            t,
            "| {} | {} | {} / {} | {} / {} | {} / {} | {} / {} | {} / {} | {} / {} | {} / {} | {:.2} / {}; {} | {}, {}, {}; {}, {}, {} | {} | {:.1} / {:.1} |",
            s32.family.name(),
            s32.k_px,
            slack(s32.slack_median_px),
            slack(s64.slack_median_px),
            slack(s32.slack_max_px),
            slack(s64.slack_max_px),
            holds(s32),
            holds(s64),
            frac(s32.false_positive_frac_mean),
            frac(s32.false_positive_frac_max),
            frac(s64.false_positive_frac_mean),
            frac(s64.false_positive_frac_max),
            frac(s32.false_negative_frac_mean),
            frac(s32.false_negative_frac_max),
            frac(s64.false_negative_frac_mean),
            frac(s64.false_negative_frac_max),
            s32.winner_diff_vs_f64_px_mean,
            s32.winner_diff_vs_f64_px_max,
            s32.shade_diff_vs_f64_max,
            s32.unpaired_roots,
            s32.crack_pixels,
            s32.double_hit_pixels,
            s64.unpaired_roots,
            s64.crack_pixels,
            s64.double_hit_pixels,
            s32.failures + s64.failures,
            ms(s32),
            ms(s64),
        );
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(&[]), None);
        assert_eq!(median(&[1.0, 2.0, 9.0]), Some(2.0));
        assert_eq!(median(&[1.0, 2.0, 4.0, 9.0]), Some(3.0));
    }
}
