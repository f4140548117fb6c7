//! The answer as curves (DESIGN.md §7, "The answer"): for a target error on one of three
//! metrics, the fewest cycles and the least energy with which each path reaches it within
//! the area budget, and the speed-up of the lembo path over the triangle path as the target
//! tightens.
//!
//! A path *reaches* a target at cost C when one of its runs costing at most C reaches it
//! (the monotone envelope): its cost at a target is the least over every run that reaches
//! it, so a tighter target never costs less, whatever the grid's order.

use super::bracket::Measured;
use crate::error::{Error, Result};
use serde::Deserialize;
use serde_json::Value;

/// An error metric a target is set on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Metric {
    /// PSNR against the exact reference \[dB\]: higher is better.
    Psnr,
    /// Mean FLIP, the perceived difference \[0-1\]: lower is better.
    Flip,
    /// The largest distance of a misplaced pixel from the true outline \[px\]: lower is
    /// better.
    Silhouette,
}

/// The metrics, in the order the answer lists them.
pub const METRICS: [Metric; 3] = [Metric::Psnr, Metric::Flip, Metric::Silhouette];

impl Metric {
    /// The accuracy field's name (`acc.<name>` in results.csv, `targets.<name>` in a spec).
    pub fn name(self) -> &'static str {
        match self {
            Metric::Psnr => "psnr_db",
            Metric::Flip => "flip_mean",
            Metric::Silhouette => "silhouette_max_px",
        }
    }

    /// The metric in words, with its unit.
    pub fn title(self) -> &'static str {
        match self {
            Metric::Psnr => "PSNR [dB]",
            Metric::Flip => "mean FLIP",
            Metric::Silhouette => "silhouette error, max [px]",
        }
    }

    /// Whether a larger value is the better image.
    pub fn higher_is_better(self) -> bool {
        self == Metric::Psnr
    }

    /// The run's value of the metric.
    pub fn of(self, m: &Measured) -> Option<f64> {
        match self {
            Metric::Psnr => m.psnr_db,
            Metric::Flip => m.flip_mean,
            Metric::Silhouette => m.silhouette_max_px,
        }
        .filter(|v| v.is_finite())
    }

    /// Whether `value` meets `target`.
    pub fn reaches(self, value: f64, target: f64) -> bool {
        if self.higher_is_better() {
            value >= target
        } else {
            value <= target
        }
    }

    /// `a` strictly better than `b`.
    fn better(self, a: f64, b: f64) -> bool {
        if self.higher_is_better() {
            a > b
        } else {
            a < b
        }
    }

    /// A value as the answer prints it: `50.0 dB`, `0.0123`, `0.25 px`.
    pub fn show(self, v: f64) -> String {
        match self {
            Metric::Psnr => format!("{v:.1} dB"),
            Metric::Flip => format!("{v:.4}"),
            Metric::Silhouette => format!("{v:.3} px"),
        }
    }

    /// A spec's target `v` at `field`, checked: a number in the metric's range.
    pub(super) fn parse_target(self, file: &str, field: &str, v: &Value) -> Result<f64> {
        let x = super::names::number(file, field, v)?;
        self.check_target(x)
            .map_err(|why| Error::invalid(file, field, v, why))?;
        Ok(x)
    }

    /// The valid range of a target, for the spec's check.
    fn check_target(self, v: f64) -> std::result::Result<(), &'static str> {
        let ok = v.is_finite()
            && match self {
                Metric::Psnr => true,
                Metric::Flip => v > 0.0 && v <= 1.0,
                Metric::Silhouette => v >= 0.0,
            };
        if ok {
            Ok(())
        } else {
            Err(match self {
                Metric::Psnr => "must be a finite PSNR in dB",
                Metric::Flip => "must be a mean FLIP in (0, 1]",
                Metric::Silhouette => "must be a finite distance of 0 px or more",
            })
        }
    }
}

// ---- A spec's targets ------------------------------------------------------------------

/// `targets` as the spec file writes it: a list of target levels per metric.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct TargetsFile {
    psnr_db: Option<Vec<Value>>,
    flip_mean: Option<Vec<Value>>,
    silhouette_max_px: Option<Vec<Value>>,
}

/// The target levels the answer tabulates, per metric; a metric without a list gets
/// three levels from the runs ([`default_targets`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Targets {
    /// In [`METRICS`]' order.
    pub lists: [Option<Vec<f64>>; 3],
}

impl Targets {
    /// Checks the file's lists; errors name `targets.<metric>[i]` of `file`.
    pub(super) fn from_file(file: &str, f: &TargetsFile) -> Result<Targets> {
        let mut out = Targets::default();
        for (i, (metric, list)) in METRICS
            .iter()
            .zip([&f.psnr_db, &f.flip_mean, &f.silhouette_max_px])
            .enumerate()
        {
            let Some(list) = list else { continue };
            let field = format!("targets.{}", metric.name());
            if list.is_empty() {
                return Err(super::names::empty_list(file, &field));
            }
            let mut values = Vec::with_capacity(list.len());
            for (j, v) in list.iter().enumerate() {
                let field = format!("{field}[{j}]");
                values.push(metric.parse_target(file, &field, v)?);
            }
            out.lists[i] = Some(values);
        }
        Ok(out)
    }

    /// The spec's `targets` read back from its text (checked when the spec was parsed).
    pub(super) fn of_spec_text(spec_text: &[u8]) -> Targets {
        let parsed = || -> Option<Targets> {
            let v: Value = serde_json::from_slice(spec_text).ok()?;
            let f: TargetsFile = serde_json::from_value(v.get("targets")?.clone()).ok()?;
            Targets::from_file("spec", &f).ok()
        };
        parsed().unwrap_or_default()
    }

    /// The stated list of `metric`, if the spec gives one.
    pub fn of(&self, metric: Metric) -> Option<&[f64]> {
        let i = METRICS.iter().position(|&m| m == metric)?;
        self.lists[i].as_deref()
    }
}

// ---- Reaching a target -----------------------------------------------------------------

/// How a path reaches a target: its fastest run doing so and its most frugal one.
#[derive(Clone, Copy, Debug)]
pub struct Reach<'a> {
    /// The fewest cycles (ties: the less energy, then the first).
    pub fastest: &'a Measured,
    /// The least energy (ties: the fewer cycles, then the first).
    pub frugal: &'a Measured,
}

/// Where `runs` (one path's, within the budget) reach `target` on `metric`; None when no
/// run does.
pub fn reach<'a>(runs: &[&'a Measured], metric: Metric, target: f64) -> Option<Reach<'a>> {
    let reaching: Vec<&Measured> = runs
        .iter()
        .copied()
        .filter(|m| metric.of(m).is_some_and(|v| metric.reaches(v, target)))
        .filter(|m| m.cycles.is_some() && m.energy_uj.is_some())
        .collect();
    let cycles = |m: &Measured| m.cycles.unwrap_or(u64::MAX) as f64;
    let energy = |m: &Measured| m.energy_uj.unwrap_or(f64::INFINITY);
    let first = |key: &dyn Fn(&Measured) -> (f64, f64)| {
        reaching
            .iter()
            .copied()
            .fold(None, |best: Option<&Measured>, m| match best {
                Some(b) if key(b) <= key(m) => Some(b),
                _ => Some(m),
            })
    };
    Some(Reach {
        fastest: first(&|m| (cycles(m), energy(m)))?,
        frugal: first(&|m| (energy(m), cycles(m)))?,
    })
}

/// One point of a speed-up curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurvePoint {
    /// The target level.
    pub target: f64,
    /// The triangle path's fewest cycles over the lembo path's, at the target.
    pub cycles: f64,
    /// The triangle path's least energy over the lembo path's.
    pub energy: f64,
}

/// The speed-up of the lembo path over the triangle path at every level either path's runs
/// measured on `metric` that both reach, from the loosest to the strictest: the envelope
/// only changes at those levels, so these points are the whole curve.
pub fn curve(lembo: &[&Measured], triangle: &[&Measured], metric: Metric) -> Vec<CurvePoint> {
    let mut levels: Vec<f64> = lembo
        .iter()
        .chain(triangle)
        .filter_map(|m| metric.of(m))
        .collect();
    levels.sort_by(|a, b| {
        if metric.higher_is_better() {
            a.total_cmp(b)
        } else {
            b.total_cmp(a)
        }
    });
    levels.dedup();
    levels
        .into_iter()
        .filter_map(|t| {
            let (l, tr) = (reach(lembo, metric, t)?, reach(triangle, metric, t)?);
            Some(CurvePoint {
                target: t,
                cycles: ratio(tr.fastest.cycles? as f64, l.fastest.cycles? as f64),
                energy: ratio(tr.frugal.energy_uj?, l.frugal.energy_uj?),
            })
        })
        .collect()
}

fn ratio(triangle: f64, lembo: f64) -> f64 {
    triangle / lembo.max(f64::MIN_POSITIVE)
}

/// Three target levels from the runs when the spec states none: the loosest level at which
/// neither path can spend less by aiming lower (the worse of the two paths' worst runs),
/// the strictest both reach (the worse of their best), and their middle (in dB for PSNR,
/// geometric for the others). One level when they coincide or cross; none when a path has
/// no measured run.
pub fn default_targets(lembo: &[&Measured], triangle: &[&Measured], metric: Metric) -> Vec<f64> {
    let extremes = |runs: &[&Measured]| -> Option<(f64, f64)> {
        let values: Vec<f64> = runs.iter().filter_map(|m| metric.of(m)).collect();
        let best = values
            .iter()
            .copied()
            .reduce(|a, b| if metric.better(a, b) { a } else { b })?;
        let worst = values
            .iter()
            .copied()
            .reduce(|a, b| if metric.better(a, b) { b } else { a })?;
        Some((worst, best))
    };
    let (Some((wl, bl)), Some((wt, bt))) = (extremes(lembo), extremes(triangle)) else {
        return Vec::new();
    };
    // The looser bound is the stricter of the two worsts; the stricter bound the looser of
    // the two bests.
    let loose = if metric.better(wl, wt) { wl } else { wt };
    let strict = if metric.better(bl, bt) { bt } else { bl };
    if !metric.better(strict, loose) {
        return vec![strict];
    }
    let mid = match metric {
        Metric::Psnr => (loose + strict) / 2.0,
        _ if loose > 0.0 && strict > 0.0 => (loose * strict).sqrt(),
        _ => (loose + strict) / 2.0,
    };
    vec![loose, mid, strict]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sweep::bracket::Knob;
    use std::collections::BTreeMap;

    fn run(path: &'static str, cycles: u64, uj: f64, psnr: f64) -> Measured {
        Measured {
            index: 0,
            scene: "s".into(),
            path,
            knob: Knob::Tess(1),
            params: BTreeMap::new(),
            cycles: Some(cycles),
            energy_uj: Some(uj),
            area_mm2: Some(1.0),
            bottleneck: None,
            psnr_db: Some(psnr),
            flip_mean: Some(1.0 / psnr),
            silhouette_max_px: Some(10.0 / psnr),
            arch: Value::Null,
            lembos: Some(1),
        }
    }

    #[test]
    fn a_target_costs_the_cheapest_run_reaching_it_whatever_the_grid_order() {
        // A slower run that is also less accurate never sets the cost: the envelope.
        let runs = [
            run("lembo", 300, 3.0, 40.0),
            run("lembo", 100, 5.0, 45.0),
            run("lembo", 200, 1.0, 50.0),
        ];
        let refs: Vec<&Measured> = runs.iter().collect();
        let r = reach(&refs, Metric::Psnr, 40.0).unwrap();
        assert_eq!(r.fastest.cycles, Some(100));
        assert_eq!(r.frugal.cycles, Some(200));
        let r = reach(&refs, Metric::Psnr, 46.0).unwrap();
        assert_eq!(r.fastest.cycles, Some(200));
        assert!(reach(&refs, Metric::Psnr, 50.1).is_none());
        // Lower is better on FLIP: 1/45 reaches a target of 0.0225, 1/40 does not.
        let r = reach(&refs, Metric::Flip, 0.0225).unwrap();
        assert_eq!(r.fastest.cycles, Some(100));
    }

    #[test]
    fn the_curve_has_a_point_at_every_level_both_paths_reach() {
        let lembo = [run("lembo", 100, 1.0, 40.0), run("lembo", 400, 2.0, 50.0)];
        let triangle = [
            run("triangle", 50, 1.0, 42.0),
            run("triangle", 800, 8.0, 48.0),
        ];
        let l: Vec<&Measured> = lembo.iter().collect();
        let t: Vec<&Measured> = triangle.iter().collect();
        let c = curve(&l, &t, Metric::Psnr);
        let targets: Vec<f64> = c.iter().map(|p| p.target).collect();
        // 50 dB is the lembo path's alone.
        assert_eq!(targets, [40.0, 42.0, 48.0]);
        // At 40 dB triangles take 50 cycles against 100; at 48 dB 800 against 400.
        assert_eq!(c[0].cycles, 0.5);
        assert_eq!(c[2].cycles, 2.0);
        assert_eq!(c[2].energy, 4.0);
        // Default targets: the worse worst (42), the worse best (48), their middle.
        assert_eq!(default_targets(&l, &t, Metric::Psnr), [42.0, 45.0, 48.0]);
    }

    #[test]
    fn targets_are_checked_by_metric() {
        let parse = |text: &str| -> Result<Targets> {
            let f: TargetsFile = serde_json::from_str(text).unwrap();
            Targets::from_file("s.json", &f)
        };
        let t = parse(r#"{"psnr_db": [40, 50], "flip_mean": [0.05]}"#).unwrap();
        assert_eq!(t.of(Metric::Psnr), Some(&[40.0, 50.0][..]));
        assert_eq!(t.of(Metric::Silhouette), None);
        for (text, field) in [
            (r#"{"psnr_db": []}"#, "targets.psnr_db"),
            (r#"{"flip_mean": [0.1, 0]}"#, "targets.flip_mean[1]"),
            (r#"{"flip_mean": [2]}"#, "targets.flip_mean[0]"),
            (
                r#"{"silhouette_max_px": [-1]}"#,
                "targets.silhouette_max_px[0]",
            ),
            (r#"{"psnr_db": ["x"]}"#, "targets.psnr_db[0]"),
        ] {
            match parse(text).unwrap_err() {
                Error::Invalid { field: f, .. } | Error::Parse { field: f, .. } => {
                    assert_eq!(f, field, "{text}")
                }
                other => panic!("{other}"),
            }
        }
    }
}
