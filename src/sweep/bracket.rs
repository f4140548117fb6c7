//! Bracketing each path's accuracy knob (DESIGN.md §7, "Bracketing"): a spec's `refine`
//! settings, what a run's record says of its knob and error ([`Measured`]), the knob
//! series of a scene and path ([`series`]) with the reason each one ended ([`Stop`]), and
//! the next round of refinement runs ([`next_round`]).
//!
//! A *series* is the runs of one scene and path that differ only in the accuracy knob (k on
//! the lembo path, n on the triangle path) and in architecture fields: their images, so
//! their errors, do not depend on the architecture (timing never changes pixels). A
//! *group* is a series' runs that share every parameter but the knob (one architecture).
//!
//! Refinement rounds: after the spec's own runs, each series whose error still improved by
//! `margin_db` or more at one of its two finest levels (a gain is a level's best PSNR over
//! the best of the coarser levels; one step under the margin can be a plateau, so two in a
//! row end a series), and whose knob has not reached `k_floor` or
//! `tess_cap` (or whose runs have not passed `cycle_cap` cycles, or the next n the triangle
//! budget), goes one level finer: k halved (down to the floor) or n doubled (up to the
//! cap). The finer level is run on the series' fastest and most frugal architectures at
//! its finest level within the area budget (the ones an equal-error answer there would
//! name), not on every architecture: the other architectures' cost at the finer level is
//! not measured. Rounds repeat until no series goes further. Everything depends only on the
//! records, so a sweep started again recomputes the same rounds.

use crate::error::{Error, Result};
use crate::tolerance::{check_k, K_RANGE};
use serde::Deserialize;
use serde_json::Value;
use std::collections::BTreeMap;

// ---- The spec's settings ---------------------------------------------------------------

/// Default `refine.margin_db`: a refinement that gains less PSNR than this ends its series.
pub const DEFAULT_MARGIN_DB: f64 = 0.5;
/// Default `refine.k_floor` \[px\].
pub const DEFAULT_K_FLOOR: f64 = 0.01;
/// Default `refine.tess_cap`.
pub const DEFAULT_TESS_CAP: u32 = 64;
/// The widest margin accepted \[dB\].
pub const MAX_MARGIN_DB: f64 = 60.0;
/// Default `refine.k_ceiling` \[px\]: the coarsest k refinement runs.
pub const DEFAULT_K_CEILING: f64 = 16.0;
/// Default `refine.cost_margin`: a coarser level that saves less than this fraction of the
/// fewest cycles and of the least energy of the level finer than it ends the coarse side.
pub const DEFAULT_COST_MARGIN: f64 = 0.02;

/// `refine` as the spec file writes it.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RefineFile {
    margin_db: Option<f64>,
    k_floor: Option<f64>,
    tess_cap: Option<u32>,
    cycle_cap: Option<u64>,
    k_ceiling: Option<f64>,
    cost_margin: Option<f64>,
}

/// How far refinement goes (`refine` in a spec).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Refine {
    /// A series stops when its finest level gained less than this over its best coarser
    /// one \[dB of PSNR\].
    pub margin_db: f64,
    /// The finest k refinement runs \[px\].
    pub k_floor: f64,
    /// The largest n refinement runs.
    pub tess_cap: u32,
    /// A series stops once a run of it took more cycles than this; None for no cap.
    pub cycle_cap: Option<u64>,
    /// The coarsest k refinement runs \[px\].
    pub k_ceiling: f64,
    /// A coarser level saving less than this fraction of the cost of the level finer than
    /// it ends a series' coarse side.
    pub cost_margin: f64,
}

impl Default for Refine {
    fn default() -> Refine {
        Refine {
            margin_db: DEFAULT_MARGIN_DB,
            k_floor: DEFAULT_K_FLOOR,
            tess_cap: DEFAULT_TESS_CAP,
            cycle_cap: None,
            k_ceiling: DEFAULT_K_CEILING,
            cost_margin: DEFAULT_COST_MARGIN,
        }
    }
}

impl Refine {
    /// Checks the file's values; errors name `refine.<field>` of `file`.
    pub(super) fn from_file(file: &str, f: &RefineFile) -> Result<Refine> {
        let d = Refine::default();
        let margin_db = f.margin_db.unwrap_or(d.margin_db);
        if !(margin_db.is_finite() && (0.0..=MAX_MARGIN_DB).contains(&margin_db)) {
            return Err(Error::invalid(
                file,
                "refine.margin_db",
                margin_db,
                format!("must be a PSNR gain in [0, {MAX_MARGIN_DB}] dB"),
            ));
        }
        let k_floor = f.k_floor.unwrap_or(d.k_floor);
        check_k(k_floor).map_err(|why| Error::invalid(file, "refine.k_floor", k_floor, why))?;
        let tess_cap = f.tess_cap.unwrap_or(d.tess_cap);
        crate::job::check_tess_range(tess_cap)
            .map_err(|e| super::names::reword(e, file, "refine.tess_cap"))?;
        if f.cycle_cap == Some(0) {
            return Err(Error::invalid(
                file,
                "refine.cycle_cap",
                0,
                "must be a number of cycles above 0 (leave it out for no cap)",
            ));
        }
        let k_ceiling = f.k_ceiling.unwrap_or(d.k_ceiling.max(k_floor));
        check_k(k_ceiling)
            .map_err(|why| Error::invalid(file, "refine.k_ceiling", k_ceiling, why))?;
        if k_ceiling < k_floor {
            return Err(Error::invalid(
                file,
                "refine.k_ceiling",
                k_ceiling,
                format!("must be at least refine.k_floor ({k_floor})"),
            ));
        }
        let cost_margin = f.cost_margin.unwrap_or(d.cost_margin);
        if !(cost_margin.is_finite() && (0.0..1.0).contains(&cost_margin)) {
            return Err(Error::invalid(
                file,
                "refine.cost_margin",
                cost_margin,
                "must be a fraction of a cost in [0, 1)",
            ));
        }
        Ok(Refine {
            margin_db,
            k_floor,
            tess_cap,
            cycle_cap: f.cycle_cap,
            k_ceiling,
            cost_margin,
        })
    }

    /// The spec's `refine` read back from its text (checked when the spec was parsed);
    /// None when it has none.
    pub(super) fn of_spec_text(spec_text: &[u8]) -> Option<Refine> {
        let v: Value = serde_json::from_slice(spec_text).ok()?;
        let f: RefineFile = serde_json::from_value(v.get("refine")?.clone()).ok()?;
        Refine::from_file("spec", &f).ok()
    }
}

// ---- What a record says ----------------------------------------------------------------

/// The accuracy knob of a run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Knob {
    /// The lembo path's k \[px\].
    K(f64),
    /// The triangle path's tessellation level n.
    Tess(u32),
}

impl Knob {
    /// Finer first: k ascending, n descending.
    fn fineness(self) -> f64 {
        match self {
            Knob::K(k) => -k,
            Knob::Tess(n) => n as f64,
        }
    }
    /// `k = 0.25` or `n = 16`.
    pub fn label(self) -> String {
        match self {
            Knob::K(k) => format!("k = {k}"),
            Knob::Tess(n) => format!("n = {n}"),
        }
    }
    /// The parameter's name in a spec.
    pub fn param(self) -> &'static str {
        match self {
            Knob::K(_) => "k",
            Knob::Tess(_) => "tess",
        }
    }
    /// The parameter's canonical value.
    pub fn value(self) -> Value {
        match self {
            Knob::K(k) => Value::from(k),
            Knob::Tess(n) => Value::from(n),
        }
    }
}

/// What the answer and the refinement read of one record.
#[derive(Clone, Debug)]
pub struct Measured {
    /// The run's index in the sweep.
    pub index: usize,
    /// The scene's name, with the viewport where the point sets one
    /// ([`crate::plot::scene_label`]).
    pub scene: String,
    /// `lembo` or `triangle`.
    pub path: &'static str,
    /// Its knob, as the run used it.
    pub knob: Knob,
    /// Its parameters, as the record holds them.
    pub params: BTreeMap<String, Value>,
    /// Frame time \[cycles\]; None in functional mode.
    pub cycles: Option<u64>,
    /// Energy of the frame \[µJ\].
    pub energy_uj: Option<f64>,
    /// The unit's area \[mm²\].
    pub area_mm2: Option<f64>,
    /// The unit that bounds the frame.
    pub bottleneck: Option<String>,
    /// PSNR against the exact reference \[dB\].
    pub psnr_db: Option<f64>,
    /// Mean FLIP \[0-1\].
    pub flip_mean: Option<f64>,
    /// The largest distance of a misplaced pixel from the true outline \[px\].
    pub silhouette_max_px: Option<f64>,
    /// The architecture the run used, as its report echoes it (null in functional mode).
    pub arch: Value,
    /// The scene's lembos (a triangle run's triangles over n²).
    pub lembos: Option<u64>,
}

impl Measured {
    /// The record's figures; None for a record of a discoid scene or without settings.
    pub fn of(record: &Value) -> Option<Measured> {
        let report = &record["report"];
        let settings = &report["settings"];
        if !report["blend"].is_null() {
            return None;
        }
        let (path, knob) = match settings["path"].as_str()? {
            "triangle" => (
                "triangle",
                Knob::Tess(u32::try_from(settings["tess"].as_u64()?).ok()?),
            ),
            _ => ("lembo", Knob::K(settings["k_px"].as_f64()?)),
        };
        let params = record["params"]
            .as_object()
            .map(|m| m.iter().map(|(k, v)| (k.clone(), v.clone())).collect())
            .unwrap_or_default();
        let acc = &report["accuracy"];
        Some(Measured {
            index: record["index"].as_u64()? as usize,
            scene: crate::plot::scene_label(record)?,
            path,
            knob,
            params,
            cycles: report["cycles"]["total"].as_u64(),
            energy_uj: report["cost"]["energy_pj"].as_f64().map(|e| e * 1e-6),
            area_mm2: report["cost"]["area_mm2"].as_f64(),
            bottleneck: report["cycles"]["bottleneck"].as_str().map(str::to_string),
            psnr_db: acc["psnr_db"].as_f64(),
            flip_mean: acc["flip_mean"].as_f64(),
            silhouette_max_px: acc["silhouette_max_px"].as_f64(),
            arch: report["arch"].clone(),
            lembos: report["primitives"]["count"].as_u64().map(|c| match knob {
                Knob::Tess(n) => c / (n as u64 * n as u64).max(1),
                Knob::K(_) => c,
            }),
        })
    }

    /// Whether the run is a sensitivity variant (`super::sensitivity`), not one of the
    /// grid's.
    pub fn is_variant(&self) -> bool {
        self.params.contains_key(super::names::SENSITIVITY)
    }

    /// Whether the unit fits `budget` (every run fits no budget).
    pub fn within(&self, budget: Option<f64>) -> bool {
        match (budget, self.area_mm2) {
            (None, _) => true,
            (Some(b), Some(a)) => a <= b,
            (Some(_), None) => false,
        }
    }

    /// The parameters without the knob and the path, as `name=value` joined by `|`: one
    /// architecture of a series.
    pub fn group(&self) -> String {
        self.params_without(|name| name == "path" || name == self.knob.param())
    }

    /// The parameters that can change the image (not `arch.*`), without the knob, and
    /// the value of `by` (the spec's `by`: each value's runs are series of their own, so
    /// that each is refined and bracketed apart): the series.
    pub fn series_key(&self, by: Option<&str>) -> String {
        let key = self.params_without(|name| {
            name == "path" || name == self.knob.param() || name.starts_with(super::names::ARCH)
        });
        match by.and_then(|b| Some((b, b.strip_prefix(super::names::ARCH)?))) {
            Some((name, path)) => {
                let value = self.params.get(name).cloned().unwrap_or_else(|| {
                    path.split('.')
                        .try_fold(&self.arch, |at, part| at.get(part))
                        .cloned()
                        .unwrap_or(Value::Null)
                });
                let by = format!("{name}={value}");
                if key.is_empty() {
                    by
                } else {
                    format!("{key}|{by}")
                }
            }
            None => key,
        }
    }

    fn params_without(&self, drop: impl Fn(&str) -> bool) -> String {
        self.params
            .iter()
            .filter(|(name, _)| !drop(name))
            .map(|(name, value)| format!("{name}={value}"))
            .collect::<Vec<_>>()
            .join("|")
    }
}

// ---- Series and why each ended ---------------------------------------------------------

/// Why a series' knob went no further.
#[derive(Clone, Debug, PartialEq)]
pub enum Stop {
    /// Its last two levels each gained less than the margin over the best level coarser
    /// than it: bracketed.
    Converged {
        /// The two gains, the finer last \[dB\] (negative: it lost).
        gains_db: [f64; 2],
    },
    /// k reached the floor while the error still improved.
    Floor,
    /// n reached the cap while the error still improved.
    Cap,
    /// A run of the series took more than the cycle cap.
    CycleCap {
        /// The cycles of that run.
        cycles: u64,
    },
    /// The next n would exceed the triangle budget of the scene.
    TriangleBudget {
        /// The n refused.
        next: u32,
    },
    /// No run of the series at its finest level carries a PSNR.
    Unmeasured,
    /// The spec asks for no refinement and the grid ends here.
    GridEnd {
        /// The last (at most two) steps' gains, the finer last \[dB\]; empty with one level.
        gains_db: Vec<f64>,
    },
    /// Not ended: the next round runs this knob.
    Next(Knob),
}

impl Stop {
    /// Whether going further would not have gained more than `margin_db`: the series'
    /// finest level is an answer, not the edge of a grid. A grid without refinement
    /// brackets a series whose last two steps each gained less than the margin.
    pub fn bracketed(&self, margin_db: f64) -> bool {
        match self {
            Stop::Converged { .. } => true,
            Stop::GridEnd { gains_db } => settled(gains_db, margin_db),
            _ => false,
        }
    }

    /// The reason in words, for `answer.md`.
    pub fn describe(&self, margin_db: f64, finest: Knob) -> String {
        let further = match finest {
            Knob::K(_) => "k would have to go lower",
            Knob::Tess(_) => "n would have to go higher",
        };
        match self {
            Stop::Converged { gains_db: [a, b] } => format!(
                "bracketed: the last two refinements gained {a:.2} and {b:.2} dB, each under the {margin_db} dB margin"
            ),
            Stop::Floor => format!("unbracketed: stopped at the floor {}; {further}", finest.label()),
            Stop::Cap => format!("unbracketed: stopped at the cap {}; {further}", finest.label()),
            Stop::CycleCap { cycles } => format!(
                "unbracketed: stopped by the cycle cap ({cycles} cycles at {}); {further}",
                finest.label()
            ),
            Stop::TriangleBudget { next } => format!(
                "unbracketed: n = {next} exceeds the triangle budget; {further}"
            ),
            Stop::Unmeasured => "unbracketed: no PSNR at the finest level".to_string(),
            Stop::GridEnd { gains_db } if settled(gains_db, margin_db) => format!(
                "bracketed by the grid: its last two steps gained {:.2} and {:.2} dB, each under {margin_db} dB",
                gains_db[0], gains_db[1]
            ),
            Stop::GridEnd { gains_db } => match gains_db.last() {
                Some(g) => format!(
                    "unbracketed: the grid stops at {} where the last step gained {g:.2} dB (two steps under {margin_db} dB bracket it); {further}",
                    finest.label()
                ),
                None => format!(
                    "unbracketed: the grid has one level, {}; {further}",
                    finest.label()
                ),
            },
            Stop::Next(k) => format!("refining: next {}", k.label()),
        }
    }
}

/// Why a series' knob went no coarser: whether a coarser knob might reach a target for
/// less than its coarsest level does.
#[derive(Clone, Debug, PartialEq)]
pub enum Coarse {
    /// Nothing coarser exists: n = 1, or k at the largest a run accepts.
    Natural,
    /// Its coarsest level saved less than the cost margin over the level finer than it, in
    /// cycles and in energy: bracketed.
    Settled {
        /// The larger of the two savings, a fraction of the finer level's cost (negative:
        /// the coarser level cost more).
        saving: f64,
    },
    /// k reached the ceiling while still saving (n halves on down to 1, which is natural).
    Ceiling,
    /// The spec asks for no refinement and the grid starts here.
    GridEnd,
    /// Not ended: the next round runs this knob.
    Next(Knob),
}

impl Coarse {
    /// Whether a coarser knob would not have saved more than the cost margin: a target its
    /// coarsest level reaches is reached at about the least cost the path can.
    pub fn bracketed(&self) -> bool {
        matches!(self, Coarse::Natural | Coarse::Settled { .. })
    }

    /// The reason in words, for `answer.md`.
    pub fn describe(&self, cost_margin: f64, coarsest: Knob) -> String {
        let pct = |f: f64| format!("{:.1}%", 100.0 * f);
        match self {
            Coarse::Natural => format!("bracketed: nothing coarser than {} exists", coarsest.label()),
            Coarse::Settled { saving } => format!(
                "bracketed: {} saved {} of the cycles or energy of the level finer than it, under the {} margin",
                coarsest.label(),
                pct(saving.max(0.0)),
                pct(cost_margin)
            ),
            Coarse::Ceiling => format!(
                "unbracketed: stopped at the ceiling {} while still saving; k would have to go higher",
                coarsest.label()
            ),
            Coarse::GridEnd => format!(
                "unbracketed: the grid starts at {} and a coarser level saved more than {} or was not run",
                coarsest.label(),
                pct(cost_margin)
            ),
            Coarse::Next(k) => format!("refining: next {}", k.label()),
        }
    }
}

/// Whether the last two gains were each under the margin.
fn settled(gains: &[f64], margin_db: f64) -> bool {
    gains.len() >= 2 && gains[gains.len() - 2..].iter().all(|&g| g < margin_db)
}

/// One scene's runs of one path that differ only in the knob and the architecture.
#[derive(Clone, Debug)]
pub struct Series {
    /// The scene's name, with the viewport where the point sets one
    /// ([`crate::plot::scene_label`]).
    pub scene: String,
    /// `lembo` or `triangle`.
    pub path: &'static str,
    /// The parameters that can change its image (without the knob), `name=value|...`.
    pub key: String,
    /// Each level from coarse to fine: the knob and the best PSNR a run of it measured
    /// (None: none measured).
    pub levels: Vec<(Knob, Option<f64>)>,
    /// Why it went no further.
    pub stop: Stop,
    /// The runs (indices into the measured list) at its finest level within the budget
    /// that the next level is run on: the fastest and the most frugal.
    pub leaders: Vec<usize>,
    /// Why it went no coarser.
    pub coarse: Coarse,
    /// The fastest and the most frugal runs at its coarsest level, that a coarser level is
    /// run on.
    pub coarse_leaders: Vec<usize>,
}

impl Series {
    /// The finest level run.
    pub fn finest(&self) -> Knob {
        self.levels.last().expect("a series has a level").0
    }
    /// The coarsest level run.
    pub fn coarsest(&self) -> Knob {
        self.levels.first().expect("a series has a level").0
    }
    /// The best PSNR any of its levels measured \[dB\].
    pub fn best_psnr(&self) -> Option<f64> {
        self.levels
            .iter()
            .filter_map(|l| l.1)
            .fold(None, |b, p| Some(b.map_or(p, |b: f64| b.max(p))))
    }
}

/// What [`series`] needs to know beyond the records.
pub struct Limits<'a> {
    /// The spec's `refine`; None: the grid alone (its ends are reported, not refined).
    pub refine: Option<Refine>,
    /// The spec's area budget \[mm²\].
    pub budget: Option<f64>,
    /// Whether a scene (by name) can take n triangles a lembo edge.
    pub triangle_ok: &'a dyn Fn(&str, u32) -> bool,
    /// The field whose values are series apart (the spec's `by`); None for none.
    pub by: Option<&'a str>,
}

/// The series of `runs` (measured runs, any order), each with its stop, in order of
/// first appearance. Runs over the area budget take no part.
pub fn series(runs: &[Measured], limits: &Limits) -> Vec<Series> {
    // (scene, path, series key) and the indices of its runs.
    type Keyed = ((String, &'static str, String), Vec<usize>);
    let mut keyed: Vec<Keyed> = Vec::new();
    for (i, m) in runs.iter().enumerate() {
        if !m.within(limits.budget) {
            continue;
        }
        let key = (m.scene.clone(), m.path, m.series_key(limits.by));
        match keyed.iter_mut().find(|(k, _)| *k == key) {
            Some((_, v)) => v.push(i),
            None => keyed.push((key, vec![i])),
        }
    }
    keyed
        .into_iter()
        .map(|((scene, path, key), members)| one_series(runs, scene, path, key, &members, limits))
        .collect()
}

fn one_series(
    runs: &[Measured],
    scene: String,
    path: &'static str,
    key: String,
    members: &[usize],
    limits: &Limits,
) -> Series {
    // Levels from coarse to fine, each with its best PSNR.
    let mut levels: Vec<(Knob, Option<f64>)> = Vec::new();
    for &i in members {
        let m = &runs[i];
        match levels.iter_mut().find(|(k, _)| *k == m.knob) {
            Some((_, best)) => {
                if let Some(p) = m.psnr_db {
                    *best = Some(best.map_or(p, |b: f64| b.max(p)));
                }
            }
            None => levels.push((m.knob, m.psnr_db)),
        }
    }
    levels.sort_by(|a, b| a.0.fineness().total_cmp(&b.0.fineness()));
    let finest = levels.last().expect("a series has a run").0;
    let coarsest = levels[0].0;
    let at = |knob: Knob| -> Vec<usize> {
        members
            .iter()
            .copied()
            .filter(|&i| runs[i].knob == knob)
            .collect()
    };
    let at_finest = at(finest);
    let leaders = leaders_of(runs, &at_finest);
    let at_coarsest = at(coarsest);
    let coarse_leaders = leaders_of(runs, &at_coarsest);
    let next_coarser = levels.get(1).map(|l| at(l.0));
    let coarse = coarse_of(
        runs,
        coarsest,
        &at_coarsest,
        next_coarser.as_deref(),
        limits,
    );
    // Each level's PSNR over the best of the coarser ones; the last two count.
    let mut gains: Vec<f64> = Vec::new();
    let mut best: Option<f64> = None;
    for (_, p) in &levels {
        if let (Some(p), Some(b)) = (p, best) {
            if (p - b).is_finite() {
                gains.push(p - b);
            }
        }
        if let Some(p) = p {
            best = Some(best.map_or(*p, |b| b.max(*p)));
        }
    }
    let gains = gains[gains.len().saturating_sub(2)..].to_vec();
    let stop = stop_of(runs, finest, &levels, gains, &at_finest, &scene, limits);
    Series {
        scene,
        path,
        key,
        levels,
        stop,
        leaders,
        coarse,
        coarse_leaders,
    }
}

/// The fastest and the most frugal of `level`'s runs (ties: the first), once each.
fn leaders_of(runs: &[Measured], level: &[usize]) -> Vec<usize> {
    let pick = |key: &dyn Fn(&Measured) -> f64| {
        level
            .iter()
            .copied()
            .fold(None, |best: Option<usize>, i| match best {
                Some(b) if key(&runs[b]) <= key(&runs[i]) => Some(b),
                _ => Some(i),
            })
    };
    let mut leaders: Vec<usize> = [
        pick(&|m| m.cycles.map_or(f64::INFINITY, |c| c as f64)),
        pick(&|m| m.energy_uj.unwrap_or(f64::INFINITY)),
    ]
    .into_iter()
    .flatten()
    .collect();
    leaders.dedup();
    leaders
}

/// Why a series goes no coarser than `coarsest` (its runs `at_coarsest`), or the knob it
/// goes to; `finer` holds the runs of the level after it, if any.
fn coarse_of(
    runs: &[Measured],
    coarsest: Knob,
    at_coarsest: &[usize],
    finer: Option<&[usize]>,
    limits: &Limits,
) -> Coarse {
    let natural = match coarsest {
        Knob::Tess(n) => n <= 1,
        Knob::K(k) => k >= K_RANGE.1,
    };
    if natural {
        return Coarse::Natural;
    }
    let margin = limits.refine.map_or(DEFAULT_COST_MARGIN, |r| r.cost_margin);
    let least = |level: &[usize], cost: &dyn Fn(&Measured) -> Option<f64>| {
        level
            .iter()
            .filter_map(|&i| cost(&runs[i]))
            .fold(None, |b: Option<f64>, c| Some(b.map_or(c, |b| b.min(c))))
    };
    let saving = |cost: &dyn Fn(&Measured) -> Option<f64>| -> Option<f64> {
        let (c, f) = (least(at_coarsest, cost)?, least(finer?, cost)?);
        (f > 0.0).then(|| 1.0 - c / f)
    };
    let savings = [
        saving(&|m| m.cycles.map(|c| c as f64)),
        saving(&|m| m.energy_uj),
    ];
    if let [Some(a), Some(b)] = savings {
        if a.max(b) < margin {
            return Coarse::Settled { saving: a.max(b) };
        }
    }
    let Some(refine) = limits.refine else {
        return Coarse::GridEnd;
    };
    match coarsest {
        Knob::K(k) if k < refine.k_ceiling => {
            Coarse::Next(Knob::K((k * 2.0).min(refine.k_ceiling)))
        }
        // n halves down to 1, the coarsest n there is (checked above).
        Knob::Tess(n) => Coarse::Next(Knob::Tess(n / 2)),
        Knob::K(_) => Coarse::Ceiling,
    }
}

fn stop_of(
    runs: &[Measured],
    finest: Knob,
    levels: &[(Knob, Option<f64>)],
    gains: Vec<f64>,
    at_finest: &[usize],
    scene: &str,
    limits: &Limits,
) -> Stop {
    let Some(refine) = limits.refine else {
        return Stop::GridEnd { gains_db: gains };
    };
    if levels.last().and_then(|l| l.1).is_none() {
        return Stop::Unmeasured;
    }
    if let [a, b] = gains[..] {
        if settled(&gains, refine.margin_db) {
            return Stop::Converged { gains_db: [a, b] };
        }
    }
    if let Some(cap) = refine.cycle_cap {
        let most = at_finest.iter().filter_map(|&i| runs[i].cycles).max();
        if let Some(c) = most.filter(|&c| c > cap) {
            return Stop::CycleCap { cycles: c };
        }
    }
    match finest {
        Knob::K(k) => {
            if k <= refine.k_floor {
                Stop::Floor
            } else {
                Stop::Next(Knob::K((k / 2.0).max(refine.k_floor)))
            }
        }
        Knob::Tess(n) => {
            if n >= refine.tess_cap {
                Stop::Cap
            } else {
                let next = n.saturating_mul(2).min(refine.tess_cap);
                if (limits.triangle_ok)(scene, next) {
                    Stop::Next(Knob::Tess(next))
                } else {
                    Stop::TriangleBudget { next }
                }
            }
        }
    }
}

/// The runs the next refinement round adds: (the index of the run whose parameters it
/// copies, the knob it runs at), in the order of the series, each series' finer level
/// (on its leaders) before its coarser one (on its coarse leaders). Sensitivity variants
/// are not refined: their runs stay at the grid's levels.
pub fn next_round(runs: &[Measured], limits: &Limits) -> Vec<(usize, Knob)> {
    let base: Vec<Measured> = runs.iter().filter(|m| !m.is_variant()).cloned().collect();
    let runs = &base[..];
    let mut next = Vec::new();
    for s in series(runs, limits) {
        if let Stop::Next(knob) = s.stop {
            next.extend(s.leaders.iter().map(|&i| (runs[i].index, knob)));
        }
        if let Coarse::Next(knob) = s.coarse {
            next.extend(s.coarse_leaders.iter().map(|&i| (runs[i].index, knob)));
        }
    }
    next
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// A measured run of `path` on scene `s` at `knob`, its architecture `arch`.
    fn run(index: usize, knob: Knob, arch: u64, cycles: u64, uj: f64, psnr: f64) -> Measured {
        let path = match knob {
            Knob::K(_) => "lembo",
            Knob::Tess(_) => "triangle",
        };
        let mut params = BTreeMap::new();
        params.insert("path".to_string(), json!(path));
        params.insert(knob.param().to_string(), knob.value());
        params.insert("arch.rop.count".to_string(), json!(arch));
        Measured {
            index,
            scene: "s".into(),
            path,
            knob,
            params,
            cycles: Some(cycles),
            energy_uj: Some(uj),
            area_mm2: Some(arch as f64),
            bottleneck: None,
            psnr_db: Some(psnr),
            flip_mean: None,
            silhouette_max_px: None,
            arch: Value::Null,
            lembos: Some(1000),
        }
    }

    fn limits(refine: Option<Refine>, budget: Option<f64>) -> Limits<'static> {
        Limits {
            refine,
            budget,
            triangle_ok: &|_, n| n <= 64,
            by: None,
        }
    }

    #[test]
    fn a_series_ends_after_two_steps_under_the_margin_not_one() {
        let refine = Some(Refine::default());
        // 40 -> 40.2 (a plateau) -> 45: one small step is not the end.
        let mut runs = vec![
            run(0, Knob::K(1.0), 1, 100, 1.0, 40.0),
            run(1, Knob::K(0.5), 1, 110, 1.0, 40.2),
        ];
        let s = series(&runs, &limits(refine, None));
        assert_eq!(s.len(), 1);
        assert_eq!(s[0].stop, Stop::Next(Knob::K(0.25)));
        runs.push(run(2, Knob::K(0.25), 1, 120, 1.0, 45.0));
        runs.push(run(3, Knob::K(0.125), 1, 130, 1.0, 45.3));
        let s = series(&runs, &limits(refine, None));
        assert_eq!(s[0].stop, Stop::Next(Knob::K(0.0625)));
        // A level that loses counts as a gain under the margin (against the best before).
        runs.push(run(4, Knob::K(0.0625), 1, 140, 1.0, 44.0));
        let s = series(&runs, &limits(refine, None));
        match s[0].stop {
            Stop::Converged { gains_db: [a, b] } => {
                assert!((a - 0.3).abs() < 1e-9 && (b + 1.3).abs() < 1e-9, "{a} {b}")
            }
            ref other => panic!("{other:?}"),
        }
        assert!(s[0].stop.bracketed(0.5));
        assert_eq!(s[0].best_psnr(), Some(45.3));
    }

    #[test]
    fn floors_caps_cycle_caps_and_the_triangle_budget_end_a_series_unbracketed() {
        let r = Refine {
            k_floor: 0.25,
            tess_cap: 16,
            cycle_cap: Some(1_000),
            ..Refine::default()
        };
        let l = limits(Some(r), None);
        // k halves down to the floor, not past it.
        let runs = [
            run(0, Knob::K(1.0), 1, 100, 1.0, 40.0),
            run(1, Knob::K(0.4), 1, 100, 1.0, 45.0),
        ];
        assert_eq!(series(&runs, &l)[0].stop, Stop::Next(Knob::K(0.25)));
        let runs = [
            run(0, Knob::K(0.5), 1, 100, 1.0, 40.0),
            run(1, Knob::K(0.25), 1, 100, 1.0, 45.0),
        ];
        let s = &series(&runs, &l)[0];
        assert_eq!(s.stop, Stop::Floor);
        assert!(!s.stop.bracketed(0.5));
        assert!(s.stop.describe(0.5, s.finest()).contains("unbracketed"));
        // n doubles up to the cap.
        let runs = [
            run(0, Knob::Tess(4), 1, 100, 1.0, 40.0),
            run(1, Knob::Tess(12), 1, 100, 1.0, 45.0),
        ];
        assert_eq!(series(&runs, &l)[0].stop, Stop::Next(Knob::Tess(16)));
        let runs = [
            run(0, Knob::Tess(8), 1, 100, 1.0, 40.0),
            run(1, Knob::Tess(16), 1, 100, 1.0, 45.0),
        ];
        assert_eq!(series(&runs, &l)[0].stop, Stop::Cap);
        // A run over the cycle cap ends it.
        let runs = [
            run(0, Knob::Tess(2), 1, 100, 1.0, 40.0),
            run(1, Knob::Tess(4), 1, 1_001, 1.0, 45.0),
        ];
        assert_eq!(series(&runs, &l)[0].stop, Stop::CycleCap { cycles: 1_001 });
        // The next n beyond the scene's triangle budget (64 here).
        let l = limits(Some(Refine::default()), None);
        let runs = [
            run(0, Knob::Tess(32), 1, 100, 1.0, 40.0),
            run(1, Knob::Tess(48), 1, 100, 1.0, 45.0),
        ];
        assert_eq!(
            series(
                &runs,
                &Limits {
                    triangle_ok: &|_, n| n <= 48,
                    ..l
                }
            )[0]
            .stop,
            Stop::TriangleBudget { next: 64 }
        );
    }

    #[test]
    fn a_grid_without_refinement_is_flagged_where_it_stops_early() {
        let l = limits(None, None);
        let early = [
            run(0, Knob::K(1.0), 1, 100, 1.0, 40.0),
            run(1, Knob::K(0.5), 1, 100, 1.0, 44.0),
            run(2, Knob::K(0.25), 1, 100, 1.0, 47.0),
        ];
        let s = &series(&early, &l)[0];
        assert!(!s.stop.bracketed(0.5));
        let said = s.stop.describe(0.5, s.finest());
        assert!(
            said.contains("unbracketed") && said.contains("k = 0.25"),
            "{said}"
        );
        let settled = [
            run(0, Knob::K(1.0), 1, 100, 1.0, 40.0),
            run(1, Knob::K(0.5), 1, 100, 1.0, 40.1),
            run(2, Knob::K(0.25), 1, 100, 1.0, 40.2),
        ];
        assert!(series(&settled, &l)[0].stop.bracketed(0.5));
    }

    #[test]
    fn the_next_round_runs_the_fastest_and_most_frugal_architecture_within_the_budget() {
        let l = limits(Some(Refine::default()), Some(3.0));
        let runs = [
            run(0, Knob::Tess(1), 1, 500, 1.0, 30.0),
            run(1, Knob::Tess(1), 2, 300, 2.0, 30.0),
            run(2, Knob::Tess(1), 4, 100, 0.5, 30.0),
            run(3, Knob::Tess(2), 1, 900, 1.5, 35.0),
            run(4, Knob::Tess(2), 2, 600, 3.0, 35.0),
            // Over the budget: not a leader, not in the series.
            run(5, Knob::Tess(2), 4, 200, 0.5, 35.0),
        ];
        let next = next_round(&runs, &l);
        // Fastest at n = 2 within 3 mm²: arch 2 (run 4); most frugal: arch 1 (run 3).
        assert_eq!(next, [(4, Knob::Tess(4)), (3, Knob::Tess(4))]);
        // Images do not depend on the architecture: one series, whatever the counts.
        assert_eq!(series(&runs, &l).len(), 1);
    }

    /// A triangle series whose grid starts above n = 1 and whose coarsest level still
    /// saves goes on to half its n, down to n = 1, where nothing coarser exists.
    #[test]
    fn the_coarse_side_halves_n_down_to_one() {
        let l = limits(Some(Refine::default()), None);
        let mut runs = vec![
            run(0, Knob::Tess(4), 1, 500, 1.0, 40.0),
            run(1, Knob::Tess(8), 1, 1000, 2.0, 44.0),
        ];
        assert_eq!(series(&runs, &l)[0].coarse, Coarse::Next(Knob::Tess(2)));
        runs.push(run(2, Knob::Tess(2), 1, 300, 0.6, 35.0));
        assert_eq!(series(&runs, &l)[0].coarse, Coarse::Next(Knob::Tess(1)));
        runs.push(run(3, Knob::Tess(1), 1, 200, 0.5, 30.0));
        let s = &series(&runs, &l)[0];
        assert_eq!(s.coarse, Coarse::Natural);
        assert!(s.coarse.bracketed());
    }

    #[test]
    fn the_coarse_side_doubles_k_until_a_coarser_level_saves_under_the_margin() {
        let l = limits(Some(Refine::default()), None);
        // k = 2 saves 10% of k = 1's cycles: a coarser k might reach a target for less.
        let mut runs = vec![
            run(0, Knob::K(2.0), 1, 900, 1.0, 40.0),
            run(1, Knob::K(2.0), 2, 950, 0.9, 40.0),
            run(2, Knob::K(1.0), 1, 1000, 1.0, 44.0),
        ];
        let s = &series(&runs, &l)[0];
        assert_eq!(s.coarse, Coarse::Next(Knob::K(4.0)));
        assert!(!s.coarse.bracketed());
        // On the coarsest level's fastest (run 0) and most frugal (run 1) architectures,
        // after the finer level's runs.
        let next = next_round(&runs, &l);
        assert_eq!(
            &next[next.len() - 2..],
            [(0, Knob::K(4.0)), (1, Knob::K(4.0))]
        );
        // k = 4 saves 1% of the cycles and 0% of the energy: settled.
        runs.push(run(3, Knob::K(4.0), 1, 891, 1.0, 35.0));
        runs.push(run(4, Knob::K(4.0), 2, 940, 0.9, 35.0));
        let s = &series(&runs, &l)[0];
        match s.coarse {
            Coarse::Settled { saving } => assert!((saving - 0.01).abs() < 1e-9, "{saving}"),
            ref other => panic!("{other:?}"),
        }
        assert!(s.coarse.bracketed());
        assert_eq!(s.coarsest(), Knob::K(4.0));
        // One saving under the margin is not enough: both cycles and energy must be.
        runs[4].energy_uj = Some(0.5);
        assert_eq!(series(&runs, &l)[0].coarse, Coarse::Next(Knob::K(8.0)));
        // The ceiling ends it unbracketed; n = 1 and the largest k are the natural ends.
        let r = Refine {
            k_ceiling: 4.0,
            ..Refine::default()
        };
        let s = &series(&runs, &limits(Some(r), None))[0];
        assert_eq!(s.coarse, Coarse::Ceiling);
        assert!(s
            .coarse
            .describe(0.02, s.coarsest())
            .contains("unbracketed"));
        let ends = [
            run(0, Knob::Tess(1), 1, 10, 1.0, 30.0),
            run(1, Knob::K(K_RANGE.1), 1, 10, 1.0, 30.0),
        ];
        for s in series(&ends, &l) {
            assert_eq!(s.coarse, Coarse::Natural);
        }
        // Without refinement, the grid's coarse end is reported, not extended.
        let grid = [
            run(0, Knob::K(2.0), 1, 500, 1.0, 40.0),
            run(1, Knob::K(1.0), 1, 1000, 1.0, 44.0),
        ];
        assert_eq!(
            series(&grid, &limits(None, None))[0].coarse,
            Coarse::GridEnd
        );
    }

    #[test]
    fn refine_settings_are_checked_naming_their_field() {
        let check = |text: &str| -> std::result::Result<Refine, String> {
            let f: RefineFile = serde_json::from_str(text).unwrap();
            Refine::from_file("s.json", &f).map_err(|e| match e {
                Error::Invalid { field, .. } | Error::Parse { field, .. } => field,
                other => other.to_string(),
            })
        };
        assert_eq!(check("{}"), Ok(Refine::default()));
        for (text, field) in [
            (r#"{"margin_db": -1}"#, "refine.margin_db"),
            (r#"{"margin_db": 100}"#, "refine.margin_db"),
            (r#"{"k_floor": 0}"#, "refine.k_floor"),
            (r#"{"k_floor": 100}"#, "refine.k_floor"),
            (r#"{"tess_cap": 0}"#, "refine.tess_cap"),
            (r#"{"tess_cap": 5000}"#, "refine.tess_cap"),
            (r#"{"cycle_cap": 0}"#, "refine.cycle_cap"),
            (r#"{"k_ceiling": 100}"#, "refine.k_ceiling"),
            (r#"{"k_floor": 1, "k_ceiling": 0.5}"#, "refine.k_ceiling"),
            (r#"{"cost_margin": 1}"#, "refine.cost_margin"),
            (r#"{"cost_margin": -0.1}"#, "refine.cost_margin"),
        ] {
            assert_eq!(check(text), Err(field.to_string()), "{text}");
        }
    }
}
