//! The search that matches the two paths' accuracy (`compare --tess auto`, `--match`,
//! `--match-path`): one path's knob is searched, each level drawn by the functional model
//! and measured against the reference, for the level whose metric ([`MatchMetric`]) is at
//! least as good as the other path's run. The triangle path's n: the smallest level, n
//! doubled from 1 and then bisected ([`smallest_level`]) up to [`MAX_AUTO_TESS`] or the
//! triangle budget. The lembo path's k: the largest k in [`K_RANGE`], halved from the given
//! k until one matches (or doubled while it does) and then bisected to within
//! [`K_MATCH_WITHIN`] ([`largest_k`]). Both assume the metric improves with the knob
//! between the levels they bisect. A target the knob's cap cannot reach is refused (exit
//! status 2, DESIGN.md §8) naming the closest run, rather than compared at unequal
//! accuracy; [`MatchReport`] is what compare.json says of a match found.

use crate::camera::{Samples, View};
use crate::datapath::Datapath;
use crate::error::{Error, Result, COMMAND_LINE};
use crate::frame;
use crate::job::{self, PathRun, PrimitivePath, RenderJob, MAX_TRIANGLES};
use crate::lembo::tessellate::Tessellation;
use crate::reference::metrics::Accuracy;
use crate::reference::oracle::ReferenceImage;
use crate::reference::PixelsPerDegree;
use crate::report::Report;
use crate::scene::Scene;
use crate::tolerance::K_RANGE;
use serde::Serialize;
use std::fmt::Write as _;

/// The largest level `--tess auto` tries.
pub const MAX_AUTO_TESS: u32 = 64;
/// `--match-path lembo` bisects k until the k that matches and the k above it that did not
/// are within this fraction of the former.
pub const K_MATCH_WITHIN: f64 = 0.05;

/// The accuracy metric a compare's search matches the two paths on (`--match`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum MatchMetric {
    /// `silhouette_max_px`, no larger than the target's.
    #[default]
    Silhouette,
    /// `psnr_db`, no smaller than the target's.
    Psnr,
    /// `flip_mean`, no larger than the target's.
    Flip,
}

impl MatchMetric {
    /// The flag's value: `silhouette`, `psnr`, `flip`.
    pub fn name(self) -> &'static str {
        match self {
            MatchMetric::Silhouette => "silhouette",
            MatchMetric::Psnr => "psnr",
            MatchMetric::Flip => "flip",
        }
    }

    /// The accuracy field it reads, as report.json names it.
    pub fn field(self) -> &'static str {
        match self {
            MatchMetric::Silhouette => "silhouette_max_px",
            MatchMetric::Psnr => "psnr_db",
            MatchMetric::Flip => "flip_mean",
        }
    }

    /// Its value in `a`.
    pub fn of(self, a: &Accuracy) -> f64 {
        match self {
            MatchMetric::Silhouette => a.silhouette_max_px,
            MatchMetric::Psnr => a.psnr_db,
            MatchMetric::Flip => a.flip_mean,
        }
    }

    /// Whether `value` is at least as accurate as `target`.
    pub fn meets(self, value: f64, target: f64) -> bool {
        match self {
            MatchMetric::Psnr => value >= target,
            MatchMetric::Silhouette | MatchMetric::Flip => value <= target,
        }
    }

    /// How a value must compare with the target to meet it: `>=` or `<=`.
    pub fn relation(self) -> &'static str {
        match self {
            MatchMetric::Psnr => ">=",
            MatchMetric::Silhouette | MatchMetric::Flip => "<=",
        }
    }

    /// A value in its unit: `41.30 dB`, `0.0026`, `0.205 px`.
    pub fn value(self, v: f64) -> String {
        match self {
            MatchMetric::Silhouette => format!("{v:.3} px"),
            MatchMetric::Psnr => format!("{v:.2} dB"),
            MatchMetric::Flip => format!("{v:.4}"),
        }
    }

    /// A value named: `PSNR 41.30 dB`, `mean FLIP 0.0026`, `silhouette_max_px 0.205 px`.
    fn show(self, v: f64) -> String {
        let name = match self {
            MatchMetric::Silhouette => "silhouette_max_px",
            MatchMetric::Psnr => "PSNR",
            MatchMetric::Flip => "mean FLIP",
        };
        format!("{name} {}", self.value(v))
    }
}

/// The path whose knob a compare's search sets (`--match-path`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MatchPath {
    /// The triangle path's n (`--tess auto`), against the lembo run at the given k.
    #[default]
    Triangle,
    /// The lembo path's k, against the triangle run at the given n.
    Lembo,
}

/// A level of one path's accuracy knob: a tessellation n, or a tolerance k.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Level {
    /// Tessellation level n of the triangle path.
    Tess(u32),
    /// Tolerance k of the lembo path \[pixels\].
    K(f64),
}

impl std::fmt::Display for Level {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Level::Tess(n) => write!(f, "n = {n}"),
            Level::K(k) => write!(f, "k = {k} px"),
        }
    }
}

/// One level tried by `--tess auto`.
#[derive(Clone, Debug, Serialize)]
pub struct AutoStep {
    /// The level n tried.
    pub tess: u32,
    /// Triangles of the scene at that level.
    pub triangles: u64,
    /// Its largest silhouette error against the reference \[pixels\].
    pub silhouette_max_px: f64,
    /// Its mean silhouette error against the reference \[pixels\].
    pub silhouette_mean_px: f64,
    /// Its PSNR against the reference \[dB\].
    pub psnr_db: f64,
    /// Its mean FLIP against the reference (0 to 1).
    pub flip_mean: f64,
}

impl AutoStep {
    /// Level `n` of `scene` measured as `a`.
    fn new(scene: &Scene, n: u32, a: &Accuracy) -> Self {
        AutoStep {
            tess: n,
            triangles: scene.lembo_count() as u64 * (n as u64).pow(2),
            silhouette_max_px: a.silhouette_max_px,
            silhouette_mean_px: a.silhouette_mean_px,
            psnr_db: a.psnr_db,
            flip_mean: a.flip_mean,
        }
    }
}

/// How the tessellation level was chosen.
#[derive(Clone, Debug, Serialize)]
pub struct TessChoice {
    /// The level used.
    pub level: u32,
    /// Whether it was chosen by `--tess auto`.
    pub auto: bool,
    /// The lembo path's silhouette_max_px when `auto` matched the silhouette (its target),
    /// else null \[pixels\].
    pub target_silhouette_px: Option<f64>,
    /// Whether the level used meets the target: always true (a target no level reaches is
    /// refused).
    pub reached: bool,
    /// Every level `auto` tried, in the order tried.
    pub tried: Vec<AutoStep>,
}

impl TessChoice {
    /// A level given (`--tess N`).
    pub(super) fn given(n: u32) -> Self {
        TessChoice {
            level: n,
            auto: false,
            target_silhouette_px: None,
            reached: true,
            tried: Vec::new(),
        }
    }
}

/// A level a match search tried.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MatchStep {
    /// The level: n (a whole number) or k \[pixels\].
    pub level: Level,
    /// Its metric against the reference, by the functional model, in the metric's unit.
    pub value: f64,
    /// Whether it met the target.
    pub meets: bool,
}

impl MatchStep {
    /// Level `level`, its accuracy `a` read on `metric` and checked against `target`.
    fn measured(level: Level, metric: MatchMetric, a: &Accuracy, target: f64) -> MatchStep {
        let value = metric.of(a);
        MatchStep {
            level,
            value,
            meets: metric.meets(value, target),
        }
    }
}

/// How a compare matched its two paths' accuracy (`compare.json`'s `match`).
#[derive(Clone, Debug, Serialize)]
pub struct MatchReport {
    /// The metric matched: `silhouette`, `psnr` or `flip` (`--match`).
    pub metric: MatchMetric,
    /// The accuracy field it is: `silhouette_max_px`, `psnr_db` or `flip_mean`.
    pub field: &'static str,
    /// How a level's value had to compare with the target: `<=` or `>=`.
    pub relation: &'static str,
    /// The path whose knob was searched: `triangle` (n) or `lembo` (k).
    pub searched_path: &'static str,
    /// The other path, whose run set the target.
    pub target_path: &'static str,
    /// The other path's run's value: the target, in the metric's unit.
    pub target: f64,
    /// The level the search started from: n = 1, or the given k.
    pub start: Level,
    /// The level it could not go past: n's cap (64, or less under the triangle budget),
    /// or k's floor.
    pub cap: Level,
    /// Every level tried, in the order tried.
    pub tried: Vec<MatchStep>,
    /// The level chosen: the smallest n, or the largest k, that met the target.
    pub level: Level,
    /// The chosen run's value, as its report measured it, in the metric's unit.
    pub value: f64,
    /// `value` less `target`, in the metric's unit.
    pub difference: f64,
    /// The level tried nearest the chosen one that missed the target (the largest n below
    /// it, the smallest k above it); null when the first level tried met it.
    pub nearest_miss: Option<MatchStep>,
    /// What was matched and how close it came, as compare.txt says it.
    pub summary: String,
}

/// The accuracy of the triangle path at level `n` with `samples` per pixel against
/// `reference`, FLIP for the observer `ppd`, from the functional model (what the search of
/// n compares).
fn triangle_accuracy(
    scene: &Scene,
    view: &View,
    reference: &ReferenceImage,
    n: u32,
    datapath: Datapath,
    samples: Samples,
    ppd: PixelsPerDegree,
) -> Accuracy {
    let t = Tessellation::new(scene.lembo_sets(), n);
    let frame = frame::render_functional_triangles(scene, &view.grid(samples), &t, datapath, true)
        .resolve(samples);
    job::measure_frame_and_flip(
        scene,
        view,
        &frame,
        reference,
        PrimitivePath::Triangle,
        t.triangles_per_lembo(),
        ppd,
        samples,
    )
    .0
}

/// The accuracy of the lembo path as `job` draws it (its k, perspective tolerance, samples
/// and datapath) against `reference`, from the functional model (what the search of k
/// compares).
fn lembo_accuracy(
    scene: &Scene,
    view: &View,
    reference: &ReferenceImage,
    job: &RenderJob,
) -> Result<Accuracy> {
    let frame = frame::render_functional(
        scene,
        &view.grid(job.samples),
        job.grid_tolerance(),
        job.datapath,
        true,
    )?
    .resolve(job.samples);
    Ok(job::measure_frame_and_flip(
        scene,
        view,
        &frame,
        reference,
        PrimitivePath::Lembo,
        1,
        job.flip_ppd,
        job.samples,
    )
    .0)
}

/// The smallest level in 1..=`cap` that `meets`: levels doubled from 1 (the last step
/// clamped to `cap`) until one meets, then bisected between the last that missed and the
/// first that met (which assumes the levels in between meet from some level on). None when
/// `cap` misses too, or is 0.
pub fn smallest_level(cap: u32, mut meets: impl FnMut(u32) -> Result<bool>) -> Result<Option<u32>> {
    if cap == 0 {
        return Ok(None);
    }
    let (mut missed, mut n) = (0, 1);
    while !meets(n)? {
        if n >= cap {
            return Ok(None);
        }
        missed = n;
        n = (2 * n).min(cap);
    }
    while n - missed > 1 {
        let mid = missed + (n - missed) / 2;
        if meets(mid)? {
            n = mid;
        } else {
            missed = mid;
        }
    }
    Ok(Some(n))
}

/// The largest k in `floor..=ceiling` that `meets`, searched from `start`: k halved from
/// `start` until one meets (the last step clamped to `floor`), or, when `start` meets,
/// doubled until one misses (clamped to `ceiling`); then bisected between the largest k
/// that met and the smallest that missed until the two are within [`K_MATCH_WITHIN`] of
/// the former (which assumes the ks meet up to some k). `ceiling` when it meets; None when
/// `floor` misses.
pub fn largest_k(
    start: f64,
    (floor, ceiling): (f64, f64),
    mut meets: impl FnMut(f64) -> Result<bool>,
) -> Result<Option<f64>> {
    // The bracket: k met, `missed` (above it) did not.
    let (mut k, mut missed) = (start, start);
    if meets(start)? {
        loop {
            if k >= ceiling {
                return Ok(Some(k));
            }
            missed = (2.0 * k).min(ceiling);
            if !meets(missed)? {
                break;
            }
            k = missed;
        }
    } else {
        loop {
            if k <= floor {
                return Ok(None);
            }
            k = (k / 2.0).max(floor);
            if meets(k)? {
                break;
            }
            missed = k;
        }
    }
    while missed - k > K_MATCH_WITHIN * k {
        let mid = 0.5 * (k + missed);
        if meets(mid)? {
            k = mid;
        } else {
            missed = mid;
        }
    }
    Ok(Some(k))
}

/// The largest n the search of n may try on `scene`: [`MAX_AUTO_TESS`], or less where the
/// triangle budget ([`MAX_TRIANGLES`]) stops it, with what stops it.
fn tess_cap(scene: &Scene) -> (u32, String) {
    let lembos = (scene.lembo_count() as u64).max(1);
    let budget = (MAX_TRIANGLES / lembos).isqrt();
    if budget < MAX_AUTO_TESS as u64 {
        (
            budget as u32,
            format!("the triangle budget of {MAX_TRIANGLES} triangles for {lembos} lembos"),
        )
    } else {
        (MAX_AUTO_TESS, "the cap of --tess auto".to_string())
    }
}

/// A finished search: what it matched, against what, and the levels it tried.
pub(super) struct Found {
    metric: MatchMetric,
    pub(super) searched: PrimitivePath,
    target: f64,
    start: Level,
    cap: Level,
    tried: Vec<MatchStep>,
    level: Level,
}

impl Found {
    /// The match as compare.json reports it, with the value the chosen run's `report`
    /// measured.
    pub(super) fn report(self, report: &Report) -> MatchReport {
        let metric = self.metric;
        let value = report.accuracy.as_ref().map_or(f64::NAN, |a| metric.of(a));
        let order = |s: &MatchStep| match s.level {
            Level::Tess(n) => n as f64,
            // The smallest k above the chosen one is the nearest: order by -k.
            Level::K(k) => -k,
        };
        let chosen = order(&MatchStep {
            level: self.level,
            value,
            meets: true,
        });
        let nearest_miss = self
            .tried
            .iter()
            .filter(|s| !s.meets && order(s) < chosen)
            .max_by(|a, b| order(a).total_cmp(&order(b)))
            .copied();
        let (searched, other) = names(self.searched);
        let difference = value - self.target;
        let side = if difference > 0.0 {
            "above it"
        } else if difference < 0.0 {
            "below it"
        } else {
            "equal to it"
        };
        let mut summary = format!(
            "{} at {} against the {other} run's {}: within {} ({side})",
            metric.show(value),
            self.level,
            metric.value(self.target),
            metric.value(difference.abs()),
        );
        if let Some(m) = &nearest_miss {
            let _ = write!(
                summary,
                "; {} ({}) missed it by {}",
                m.level,
                metric.value(m.value),
                metric.value((m.value - self.target).abs())
            );
        }
        MatchReport {
            metric,
            field: metric.field(),
            relation: metric.relation(),
            searched_path: searched,
            target_path: other,
            target: self.target,
            start: self.start,
            cap: self.cap,
            tried: self.tried,
            level: self.level,
            value,
            difference,
            nearest_miss,
            summary,
        }
    }
}

/// The searched path's name and the other's.
fn names(searched: PrimitivePath) -> (&'static str, &'static str) {
    match searched {
        PrimitivePath::Lembo => ("lembo", "triangle"),
        PrimitivePath::Triangle => ("triangle", "lembo"),
    }
}

/// Refuses a target no level can be matched to: a metric that is not a number.
fn check_target(metric: MatchMetric, target: f64, other: &str) -> Result<()> {
    if target.is_finite() {
        return Ok(());
    }
    Err(Error::invalid(
        COMMAND_LINE,
        "--match",
        metric.name(),
        format!(
            "the {other} run's {} is {target}, not a value a level can be matched to",
            metric.field()
        ),
    ))
}

/// The refusal of a target that no level up to the knob's cap reaches (`what_cap` says
/// what the cap is): names `--match`, the target, the cap and the closest run.
fn not_reached(
    metric: MatchMetric,
    searched: PrimitivePath,
    target: f64,
    tried: &[MatchStep],
    (start, cap, what_cap): (Level, Level, &str),
    instead: &str,
) -> Error {
    let (_, other) = names(searched);
    let closest = tried.iter().min_by(|a, b| {
        (a.value - target)
            .abs()
            .total_cmp(&(b.value - target).abs())
    });
    let closest = closest
        .map(|s| {
            format!(
                "; the closest run, {}, measured {} ({} short)",
                s.level,
                metric.show(s.value),
                metric.value((s.value - target).abs())
            )
        })
        .unwrap_or_else(|| "; no level was affordable to try".to_string());
    Error::invalid(
        COMMAND_LINE,
        "--match",
        metric.name(),
        format!(
            "no level from {start} to {cap} ({what_cap}) reaches the {other} run's {} ({} {} {}){closest}: the two paths cannot be compared at equal {} here; {instead}",
            metric.show(target),
            metric.field(),
            metric.relation(),
            metric.value(target),
            metric.field(),
        ),
    )
}

/// The search of n (`--tess auto`): the smallest level whose `metric` meets the lembo
/// run's `target`, drawn in the datapath and samples of the lembo run's `job` and measured
/// for its observer, with the choice as `tess` reports it; refused when none up to the cap
/// does.
pub(super) fn search_tess(
    job: &RenderJob,
    scene: &Scene,
    view: &View,
    reference: &ReferenceImage,
    metric: MatchMetric,
    target: f64,
) -> Result<(TessChoice, Found)> {
    check_target(metric, target, "lembo")?;
    crate::progress::stage("matching n (functional triangle renders)");
    let (cap, what_cap) = tess_cap(scene);
    let (mut steps, mut tried) = (Vec::new(), Vec::new());
    let found = smallest_level(cap, |n| {
        let a = triangle_accuracy(
            scene,
            view,
            reference,
            n,
            job.datapath,
            job.samples,
            job.flip_ppd,
        );
        steps.push(AutoStep::new(scene, n, &a));
        let step = MatchStep::measured(Level::Tess(n), metric, &a, target);
        tried.push(step);
        Ok(step.meets)
    })?;
    let (start, cap) = (Level::Tess(1), Level::Tess(cap));
    let Some(level) = found else {
        return Err(not_reached(
            metric,
            PrimitivePath::Triangle,
            target,
            &tried,
            (start, cap, &what_cap),
            "give --tess N to compare at a level of your choosing, or a larger --k for a target the triangles can reach",
        ));
    };
    let choice = TessChoice {
        level,
        auto: true,
        target_silhouette_px: (metric == MatchMetric::Silhouette).then_some(target),
        reached: true,
        tried: steps,
    };
    let found = Found {
        metric,
        searched: PrimitivePath::Triangle,
        target,
        start,
        cap,
        tried,
        level: Level::Tess(level),
    };
    Ok((choice, found))
}

/// The search of k (`--match-path lembo`): the largest k in k's range whose `metric` meets
/// the triangle run's `target`, searched from the k of the lembo run's `job` (each k drawn
/// with the rest of its settings); refused when k's floor does not.
pub(super) fn search_k(
    job: &RenderJob,
    scene: &Scene,
    view: &View,
    reference: &ReferenceImage,
    metric: MatchMetric,
    target: f64,
) -> Result<(f64, Found)> {
    check_target(metric, target, "triangle")?;
    crate::progress::stage("matching k (functional lembo renders)");
    let floor = K_RANGE.0;
    let mut tried = Vec::new();
    let found = largest_k(job.k, K_RANGE, |k| {
        let a = lembo_accuracy(scene, view, reference, &RenderJob { k, ..job.clone() })?;
        let step = MatchStep::measured(Level::K(k), metric, &a, target);
        tried.push(step);
        Ok(step.meets)
    })?;
    let (start, cap) = (Level::K(job.k), Level::K(floor));
    let Some(k) = found else {
        return Err(not_reached(
            metric,
            PrimitivePath::Lembo,
            target,
            &tried,
            (start, cap, "the floor of k's range"),
            "give a smaller --tess N for a target the lembos can reach, or leave --match-path to search n instead",
        ));
    };
    let found = Found {
        metric,
        searched: PrimitivePath::Lembo,
        target,
        start,
        cap,
        tried,
        level: Level::K(k),
    };
    Ok((k, found))
}

/// The value of `metric` a run's report measured.
pub(super) fn measured(metric: MatchMetric, run: &PathRun) -> f64 {
    run.report
        .accuracy
        .as_ref()
        .map_or(f64::NAN, |a| metric.of(a))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Levels 1..=`cap` searched for the first that is at least `threshold`, with the
    /// levels tried in order.
    fn levels(cap: u32, threshold: u32) -> (Option<u32>, Vec<u32>) {
        let mut tried = Vec::new();
        let found = smallest_level(cap, |n| {
            tried.push(n);
            Ok(n >= threshold)
        })
        .unwrap();
        (found, tried)
    }

    #[test]
    fn smallest_level_doubles_then_bisects_up_to_its_cap() {
        assert_eq!(levels(64, 5), (Some(5), vec![1, 2, 4, 8, 6, 5]));
        assert_eq!(levels(64, 1), (Some(1), vec![1]));
        assert_eq!(
            levels(64, 64),
            (Some(64), vec![1, 2, 4, 8, 16, 32, 64, 48, 56, 60, 62, 63])
        );
        // Nothing meets: every doubling up to the cap, the cap included, and None.
        assert_eq!(levels(64, 65), (None, vec![1, 2, 4, 8, 16, 32, 64]));
        // A cap that is no power of two (the triangle budget's) is tried itself.
        assert_eq!(
            levels(40, 37),
            (Some(37), vec![1, 2, 4, 8, 16, 32, 40, 36, 38, 37])
        );
        assert_eq!(levels(40, 41), (None, vec![1, 2, 4, 8, 16, 32, 40]));
        // No level affordable: nothing tried.
        assert_eq!(levels(0, 1), (None, vec![]));
    }

    /// k searched from `start` in `floor..=64` for the largest at most `threshold`, with
    /// the ks tried in order.
    fn ks(start: f64, floor: f64, threshold: f64) -> (Option<f64>, Vec<f64>) {
        let mut tried = Vec::new();
        let found = largest_k(start, (floor, 64.0), |k| {
            tried.push(k);
            Ok(k <= threshold)
        })
        .unwrap();
        (found, tried)
    }

    #[test]
    fn largest_k_halves_or_doubles_then_bisects_to_within_five_percent() {
        let (k, tried) = ks(0.5, 1e-4, 0.3);
        assert_eq!(k, Some(0.296875));
        assert_eq!(
            tried,
            [0.5, 0.25, 0.375, 0.3125, 0.28125, 0.296875, 0.3046875]
        );
        // The nearest k above it tried missed, within 5 % of it.
        let above = tried
            .iter()
            .copied()
            .filter(|&t| t > 0.296875)
            .fold(f64::MAX, f64::min);
        assert!(above > 0.3 && above - 0.296875 <= K_MATCH_WITHIN * 0.296875);
        // The given k meets: k doubled until one misses, then bisected.
        let (k, tried) = ks(0.5, 1e-4, 2.9);
        assert_eq!(k, Some(2.875));
        assert_eq!(tried, [0.5, 1.0, 2.0, 4.0, 3.0, 2.5, 2.75, 2.875]);
        // Up to the ceiling, which is chosen when it meets.
        let (k, tried) = ks(0.5, 1e-4, 100.0);
        assert_eq!(k, Some(64.0));
        assert_eq!(tried, [0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0]);
        let (k, tried) = ks(48.0, 1e-4, 100.0);
        assert_eq!((k, tried), (Some(64.0), vec![48.0, 64.0]));
        // Only the floor meets: the last halving is clamped to it.
        let (k, tried) = ks(0.5, 1e-4, 1e-4);
        assert_eq!(k, Some(1e-4));
        assert_eq!(tried[12], 0.5 / 4096.0);
        assert_eq!(tried[13], 1e-4);
        // Not even the floor: None, the floor tried last of the halvings.
        let (k, tried) = ks(0.5, 1e-4, 1e-5);
        assert_eq!(k, None);
        assert_eq!(tried.last(), Some(&1e-4));
        assert_eq!(tried.len(), 14);
    }

    #[test]
    fn each_metric_meets_in_its_direction() {
        assert!(MatchMetric::Psnr.meets(41.0, 40.0) && !MatchMetric::Psnr.meets(39.0, 40.0));
        assert!(MatchMetric::Flip.meets(0.01, 0.02) && !MatchMetric::Flip.meets(0.03, 0.02));
        assert!(MatchMetric::Silhouette.meets(0.2, 0.2));
        assert!(!MatchMetric::Silhouette.meets(0.3, 0.2));
    }
}
