//! Bracketing each path's accuracy knob (DESIGN.md §7, "Bracketing"): the knob series of
//! a scene and path ([`series`]) with the reason each one ended ([`Stop`]), and the next
//! round of refinement runs ([`next_round`]), from a spec's `refine` settings ([`Refine`],
//! `bracket/refine.rs`) and what each run's record says of its knob and error
//! ([`Measured`], `bracket/record.rs`).
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

use crate::tolerance::K_RANGE;

mod record;
mod refine;
#[cfg(test)]
mod tests;

pub use record::{Knob, Measured};
pub(super) use refine::RefineFile;
pub use refine::{
    Refine, DEFAULT_COST_MARGIN, DEFAULT_K_CEILING, DEFAULT_K_FLOOR, DEFAULT_MARGIN_DB,
    DEFAULT_TESS_CAP, MAX_MARGIN_DB,
};

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
