//! `answer.md` and its figures: the lembo path against the triangle path on each scene of a
//! sweep with an area budget (DESIGN.md §7, "The answer"), every run named by its
//! parameters and the unit that bounds it:
//!
//! - **bracketing**: each series' knob levels (k on the lembo path, n on the triangle path),
//!   the best PSNR at each, and why it went no finer and no coarser ([`super::bracket`]);
//! - **speed-up against target error**, on PSNR, mean FLIP and the silhouette error: at each
//!   target, each path's fewest cycles and least energy within the budget (the monotone
//!   envelope, [`super::curves`]), and `speedup_<metric>_<scene>.svg` over every level;
//! - **equal area**: each path's most accurate run (highest PSNR) within the budget, the
//!   fastest of equally accurate ones;
//! - **equal time** and **equal energy**: the cap is the least cycles (energy) a frame at
//!   which both paths have a run within the budget (the higher of their least); each path's
//!   most accurate run within it;
//! - **what flips it** ([`super::flips`]) and **the runs named**, each with its `lembo-sim
//!   render` command ([`super::reproduce`]).
//!
//! A deciding run is flagged where the answer would be the grid's, not the hardware's: at
//! the fine end of a series that was not bracketed (and then the equal-cost rows name no
//! winner), at the coarse end of its architecture's runs where the series' coarse side was
//! not bracketed (a coarser knob might reach the target for less), or bound by a unit whose
//! count the sweep held at one value. Remaining ties go to the run listed first in the
//! sweep. Only runs with both a cost and an accuracy count (timed runs measured against the
//! reference).

use super::bracket::{
    series, Knob, Limits, Measured, Refine, Series, DEFAULT_COST_MARGIN, DEFAULT_MARGIN_DB,
};
use super::curves::{curve, default_targets, reach, Metric, Targets, METRICS};
use super::flips;
use super::names::{file_stem, Figure};
use super::reproduce::render_command;
use super::sensitivity::Sensitivity;
use crate::config::ArchConfig;
use crate::error::Result;
use crate::graph::KINDS;
use crate::job::MAX_TRIANGLES;
use crate::plot::speedup::{speedup_svg, SpeedupFigure};
use serde_json::Value;
use std::cell::RefCell;
use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;

/// What the answer is made from, besides the records.
pub(super) struct Ask<'a> {
    /// The spec's area budget \[mm²\].
    pub(super) budget_mm2: f64,
    /// The spec's refinement; None for the grid alone.
    pub(super) refine: Option<Refine>,
    /// The spec's targets.
    pub(super) targets: &'a Targets,
    /// The spec's sensitivity study.
    pub(super) sensitivity: Option<Sensitivity>,
    /// The field whose values are series apart (`by`); None for none.
    pub(super) by: Option<&'a str>,
}

/// The answer: its files and each scene's figures.
pub(super) struct Answer {
    /// `answer.md` and its figures, as (file name, bytes).
    pub(super) files: Vec<Figure>,
    /// Each scene's answer in figures, in the order answer.md lists the scenes.
    pub(super) headlines: Vec<Headline>,
}

/// One scene's answer in figures: what the sweep's summary and the table of an answer by
/// value (`super::by`) show.
#[derive(Clone, Debug)]
pub(super) struct Headline {
    /// The scene, with its viewport where the sweep varies it.
    pub(super) scene: String,
    /// At equal area, each path's most accurate run within the budget: (run, cycles,
    /// PSNR), the lembo path's first; None when either path has none.
    pub(super) area: Option<[(usize, u64, f64); 2]>,
    /// The equal-area verdict in words (no winner where a deciding run is unbracketed).
    pub(super) verdict: String,
    /// At each PSNR target \[dB\]: the triangle path's fewest cycles over the lembo
    /// path's, None where either path does not reach it.
    pub(super) psnr: Vec<(f64, Option<f64>)>,
}

/// `answer.md` and its figures, and each scene's headline, for `records`; None when no
/// scene has measured runs of both paths within the budget.
pub(super) fn answer_files(records: &[Value], ask: &Ask) -> Result<Option<Answer>> {
    let measured: Vec<Measured> = records
        .iter()
        .filter_map(Measured::of)
        .filter(|m| m.cycles.is_some() && m.energy_uj.is_some() && m.psnr_db.is_some())
        .collect();
    // The grid's runs; a sensitivity study's variants only answer what flips it.
    let (variants, runs): (Vec<Measured>, Vec<Measured>) =
        measured.into_iter().partition(Measured::is_variant);
    let triangle_ok = |scene: &str, n: u32| {
        runs.iter()
            .filter(|m| m.scene == scene)
            .filter_map(|m| m.lembos)
            .next()
            .is_some_and(|l| l.saturating_mul(n as u64 * n as u64) <= MAX_TRIANGLES)
    };
    let limits = Limits {
        refine: ask.refine,
        budget: Some(ask.budget_mm2),
        triangle_ok: &triangle_ok,
        by: ask.by,
    };
    let all_series = series(&runs, &limits);
    let (constant, shared) = shared_params(&runs);
    let margin = ask.refine.map_or(DEFAULT_MARGIN_DB, |r| r.margin_db);
    let commands: BTreeMap<usize, String> = records
        .iter()
        .filter_map(|r| Some((r["index"].as_u64()? as usize, render_command(r)?)))
        .collect();
    let names = Names {
        runs: &runs,
        commands: &commands,
        named: RefCell::new(BTreeSet::new()),
        series: &all_series,
        constant: &constant,
        margin,
        cost_margin: ask.refine.map_or(DEFAULT_COST_MARGIN, |r| r.cost_margin),
        by: ask.by,
    };

    let mut scenes: Vec<&str> = Vec::new();
    for m in &runs {
        if !scenes.contains(&m.scene.as_str()) {
            scenes.push(&m.scene);
        }
    }
    let mut sections = Sections {
        curves: vec![String::new(); METRICS.len()],
        ..Sections::default()
    };
    let mut any = false;
    for scene in scenes {
        let within = |path: &str| -> Vec<&Measured> {
            runs.iter()
                .filter(|m| m.scene == scene && m.path == path && m.within(limits.budget))
                .collect()
        };
        let (lembo, triangle) = (within("lembo"), within("triangle"));
        let of_scene = Scene {
            name: scene,
            lembo: &lembo,
            triangle: &triangle,
            variants: &variants,
        };
        any |= of_scene.write(ask, &names, &limits, &mut sections)?;
    }
    if !any {
        return Ok(None);
    }
    let page = sections.page(ask, margin, &shared, &names);
    let mut files = vec![("answer.md".to_string(), page.into_bytes())];
    files.extend(sections.figures);
    Ok(Some(Answer {
        files,
        headlines: sections.headlines,
    }))
}

/// answer.md's sections as the scenes fill them, and the figures.
#[derive(Default)]
struct Sections {
    bracket: String,
    /// One a metric, in [`METRICS`]' order.
    curves: Vec<String>,
    area: String,
    time: String,
    energy: String,
    flips: String,
    figures: Vec<Figure>,
    headlines: Vec<Headline>,
}

/// One scene's runs within the budget, and the sensitivity variants of every scene.
struct Scene<'a> {
    name: &'a str,
    lembo: &'a [&'a Measured],
    triangle: &'a [&'a Measured],
    variants: &'a [Measured],
}

impl Scene<'_> {
    /// Adds the scene's rows and figures to `out`; false when it has no run of both paths
    /// within the budget (its bracketing and equal-area rows say so).
    fn write(&self, ask: &Ask, names: &Names, limits: &Limits, out: &mut Sections) -> Result<bool> {
        let (scene, lembo, triangle) = (self.name, self.lembo, self.triangle);
        for s in names.series.iter().filter(|s| s.scene == scene) {
            let _ = writeln!(out.bracket, "{}", names.series_row(s));
        }
        let (Some(bl), Some(bt)) = (most_accurate(lembo), most_accurate(triangle)) else {
            let _ = writeln!(
                out.area,
                "| {scene} | no run of both paths within {} mm² | | |",
                ask.budget_mm2
            );
            out.headlines.push(Headline {
                scene: scene.to_string(),
                area: None,
                verdict: format!("no run of both paths within {} mm²", ask.budget_mm2),
                psnr: Vec::new(),
            });
            return Ok(false);
        };
        let mut headline = Headline {
            scene: scene.to_string(),
            area: Some([bl, bt].map(|m| (m.index, m.cycles.unwrap_or(0), m.psnr()))),
            verdict: names.verdict(bl, bt),
            psnr: Vec::new(),
        };
        let _ = writeln!(
            out.area,
            "| {scene} | {} | {} | {}; {}, {} |",
            names.cell_fine(bl),
            names.cell_fine(bt),
            names.verdict(bl, bt),
            ratio("cycles", bl.cycles_f(), bt.cycles_f()),
            ratio("µJ", bl.uj(), bt.uj()),
        );
        out.time += &equal_cap_row(scene, lembo, triangle, names, Cost::Cycles);
        out.energy += &equal_cap_row(scene, lembo, triangle, names, Cost::Energy);
        if let Some(study) = &ask.sensitivity {
            let (section, figs) =
                flips::section(scene, study, lembo, triangle, self.variants, limits)?;
            out.flips += &section;
            out.figures.extend(figs);
        }
        for (i, &metric) in METRICS.iter().enumerate() {
            let stated = ask.targets.of(metric).map(<[f64]>::to_vec);
            let targets = stated.unwrap_or_else(|| default_targets(lembo, triangle, metric));
            for t in targets {
                out.curves[i] += &names.target_row(scene, metric, t, lembo, triangle);
                if metric == Metric::Psnr {
                    let speedup = reach(lembo, metric, t)
                        .zip(reach(triangle, metric, t))
                        .map(|(l, t)| t.fastest.cycles_f() / l.fastest.cycles_f().max(1.0));
                    headline.psnr.push((t, speedup));
                }
            }
            out.figures.extend(self.speedup_figure(metric)?);
        }
        out.headlines.push(headline);
        Ok(true)
    }

    /// `speedup_<metric>_<scene>.svg`; None when no level is reached by both paths.
    fn speedup_figure(&self, metric: Metric) -> Result<Option<Figure>> {
        let points = curve(self.lembo, self.triangle, metric);
        if points.is_empty() {
            return Ok(None);
        }
        let cycles: Vec<(f64, f64)> = points.iter().map(|p| (p.target, p.cycles)).collect();
        let energy: Vec<(f64, f64)> = points.iter().map(|p| (p.target, p.energy)).collect();
        let svg = speedup_svg(&SpeedupFigure {
            scene: self.name,
            metric: metric.title(),
            higher_is_stricter: metric.higher_is_better(),
            cycles: &cycles,
            energy: &energy,
        })?;
        Ok(Some((
            format!("speedup_{}_{}.svg", metric.name(), file_stem(self.name)),
            svg.into_bytes(),
        )))
    }
}

impl Sections {
    /// answer.md: the preamble, then each section with its head.
    fn page(&self, ask: &Ask, margin: f64, shared: &str, names: &Names) -> String {
        let mut page = preamble(ask, margin, shared);
        page += &self.bracket;
        page += "\n## Speed-up against target error\n\nFor each target, each path's fewest \
                 cycles and least energy with which a run within the budget reaches it (a path \
                 reaches a target at cost C if any of its runs costing at most C reaches it). The \
                 figures (`speedup_<metric>_<scene>.svg`) draw the speed-up at every level a run \
                 measured that both paths reach.\n";
        for (i, &metric) in METRICS.iter().enumerate() {
            let how = match ask.targets.of(metric) {
                Some(_) => "the spec's targets",
                None => {
                    "three levels from the runs: the stricter of the two paths' worst, the \
                     looser of their best, and their middle"
                }
            };
            let _ = write!(
                page,
                "\n### {} ({how})\n\n| scene | target | lembo, fastest | triangle, fastest | \
                 cycles | lembo, least energy | triangle, least energy | energy |\n\
                 |---|---|---|---|---|---|---|---|\n",
                metric.title(),
            );
            page += &self.curves[i];
        }
        page += "\n## At equal area\n\nEach path's most accurate run (PSNR) within the budget \
                 (ties: the fastest). Where either sits at the fine end of a series that was not \
                 bracketed, no winner is named: a finer knob might change the answer.\n\n\
                 | scene | lembo | triangle | comparison |\n|---|---|---|---|\n";
        page += &self.area;
        page += "\n## At equal time\n\nThe cycle cap is the least at which both paths have a \
                 run within the budget (the higher of their fewest cycles a frame); each path's \
                 most accurate run within the area budget taking at most that (ties: the \
                 fastest).\n\n| scene | cap | lembo | triangle | comparison |\n\
                 |---|---|---|---|---|\n";
        page += &self.time;
        page += "\n## At equal energy\n\nThe energy cap is the least at which both paths have \
                 a run within the budget (the higher of their least energies a frame); each \
                 path's most accurate run within the area budget spending at most that (ties: \
                 the fastest).\n\n| scene | cap | lembo | triangle | comparison |\n\
                 |---|---|---|---|---|\n";
        page += &self.energy;
        if let Some(study) = &ask.sensitivity {
            let (metric, target) = study.target;
            let _ = write!(
                page,
                "\n## What flips it\n\nOne parameter at a time, scaled down and up (or set low \
                 and high) with every other setting at the grid's: the lembo path's advantage at \
                 a {} target of {} (the triangle path's fewest cycles over the lembo path's, and \
                 its least energy over the lembo path's), against the same runs on the spec's \
                 architecture as it is (the grid's points that set no `arch.` field). A variant \
                 that turns the advantage to the other side of 1 is marked **flips**; one whose \
                 runs exceed the area budget is said to.\n",
                metric.title(),
                metric.show(target)
            );
            page += &self.flips;
        }
        page += &names.reproduce();
        if !self.figures.is_empty() {
            page += "\n## Figures\n\n";
            for (name, _) in &self.figures {
                let _ = writeln!(page, "- [{name}]({name})");
            }
        }
        page
    }
}

/// answer.md's title, what it is made of, the shared parameters and the bracketing
/// section's head.
fn preamble(ask: &Ask, margin: f64, shared: &str) -> String {
    let budget_mm2 = ask.budget_mm2;
    let mut page = format!(
        "# The answer: lembos against triangles\n\n\
         Made by `lembo-sim sweep` from this directory's runs (DESIGN.md §7): every run whose \
         unit is within the spec's area budget of {budget_mm2} mm², measured against the exact \
         reference. A run is named by its parameters and the unit that bounds it. A deciding \
         run is flagged **unbracketed** where it sits at the fine end of a series that was \
         not bracketed (one of its last two steps still gained {margin} dB or more, and a \
         finer knob was not run), **coarse end** where it sits at the coarse end of its \
         architecture's runs and its series' coarse side was not bracketed (the coarsest level \
         still saved {cost}% or more of the cycles or energy of the level finer than it, and a \
         coarser knob was not run), and **fixed count** where the unit that bounds it had one \
         count in every run of its path.\n\n",
        cost = 100.0 * ask.refine.map_or(DEFAULT_COST_MARGIN, |r| r.cost_margin)
    );
    if !shared.is_empty() {
        page += shared;
        page += "\n";
    }
    page += &format!(
        "## Bracketing\n\nEach series is a scene's runs of one path that differ only in the \
         knob and the architecture (their images do not depend on the architecture). \
         {}\n\n| scene | path | series | levels (best PSNR) | how the fine end ended | how the coarse end ended |\n|---|---|---|---|---|---|\n",
        match ask.refine {
            Some(r) => format!(
                "Refined beyond the grid (k halved down to {}, n doubled up to {}{}) until the \
                 last two levels each gained under {} dB over the best coarser one; each finer level \
                 runs on the series' fastest and most frugal architectures at the level before. \
                 On the coarse side, k doubled up to {} and n halved down to 1 on the fastest \
                 and most frugal architectures at the coarsest level, until a coarser level \
                 saved under {}% of the fewest cycles and of the least energy of the level finer \
                 than it.",
                r.k_floor,
                r.tess_cap,
                r.cycle_cap
                    .map_or(String::new(), |c| format!(", until a run took over {c} cycles")),
                r.margin_db,
                r.k_ceiling,
                100.0 * r.cost_margin
            ),
            None => format!(
                "The spec asks for no refinement (`refine`): a series whose last two steps \
                 did not each gain under {margin} dB stops at the edge of its grid."
            ),
        }
    );
    page
}

impl Measured {
    fn cycles_f(&self) -> f64 {
        self.cycles.unwrap_or(u64::MAX) as f64
    }
    fn uj(&self) -> f64 {
        self.energy_uj.unwrap_or(f64::INFINITY)
    }
    fn psnr(&self) -> f64 {
        self.psnr_db.unwrap_or(f64::NEG_INFINITY)
    }
}

/// The first of `runs` with the largest `key` (ties: the earliest).
fn best_by<'a>(
    runs: &[&'a Measured],
    key: impl Fn(&Measured) -> (f64, f64),
) -> Option<&'a Measured> {
    runs.iter()
        .copied()
        .fold(None, |best: Option<&Measured>, r| match best {
            Some(b) if key(b) >= key(r) => Some(b),
            _ => Some(r),
        })
}

/// Most accurate, then fastest.
fn most_accurate<'a>(runs: &[&'a Measured]) -> Option<&'a Measured> {
    best_by(runs, |r| (r.psnr(), -r.cycles_f()))
}

/// The lembo path's and the triangle path's figures as a ratio in words: "lembos 2.10x
/// fewer cycles" or "triangles 1.30x fewer µJ".
fn ratio(what: &str, lembo: f64, triangle: f64) -> String {
    if lembo <= triangle {
        format!(
            "lembos {:.2}x fewer {what}",
            triangle / lembo.max(f64::MIN_POSITIVE)
        )
    } else {
        format!(
            "triangles {:.2}x fewer {what}",
            lembo / triangle.max(f64::MIN_POSITIVE)
        )
    }
}

/// Which of two runs is the more accurate, and by how much, in words.
fn more_accurate(lembo: &Measured, triangle: &Measured) -> String {
    let winner = if lembo.psnr() >= triangle.psnr() {
        "lembos"
    } else {
        "triangles"
    };
    format!(
        "{winner} more accurate by {:.1} dB",
        (lembo.psnr() - triangle.psnr()).abs()
    )
}

/// The parameters every run of a path shares, to leave out of the labels, and the
/// sentences that say them once.
fn shared_params(runs: &[Measured]) -> (Vec<(String, Value)>, String) {
    let mut constant: Vec<(String, Value)> = Vec::new();
    let mut shared = String::new();
    for path in ["lembo", "triangle"] {
        let of_path: Vec<&Measured> = runs.iter().filter(|m| m.path == path).collect();
        let Some(first) = of_path.first() else {
            continue;
        };
        let mut same: Vec<String> = Vec::new();
        for (name, value) in &first.params {
            if name != "path" && of_path.iter().all(|m| m.params.get(name) == Some(value)) {
                constant.push((name.clone(), value.clone()));
                same.push(format!("{name} = {value}"));
            }
        }
        if !same.is_empty() {
            let _ = writeln!(shared, "Every {path} run: {}.", same.join(", "));
        }
    }
    (constant, shared)
}

/// The cost an equal-cost row caps.
#[derive(Clone, Copy)]
enum Cost {
    Cycles,
    Energy,
}

impl Cost {
    fn of(self, m: &Measured) -> f64 {
        match self {
            Cost::Cycles => m.cycles_f(),
            Cost::Energy => m.uj(),
        }
    }
    fn show(self, cap: f64) -> String {
        match self {
            Cost::Cycles => format!("{cap:.0} cycles"),
            Cost::Energy => format!("{cap:.0} µJ"),
        }
    }
}

/// The row of `scene` at equal `cost`: the cap is the higher of the two paths' least cost
/// within the area budget; each path's most accurate run costing at most that.
fn equal_cap_row(
    scene: &str,
    lembo: &[&Measured],
    triangle: &[&Measured],
    names: &Names,
    cost: Cost,
) -> String {
    let least = |runs: &[&Measured]| runs.iter().map(|r| cost.of(r)).fold(f64::MAX, f64::min);
    let cap = least(lembo).max(least(triangle));
    let (kl, kt): (Vec<&Measured>, Vec<&Measured>) = (
        lembo
            .iter()
            .copied()
            .filter(|r| cost.of(r) <= cap)
            .collect(),
        triangle
            .iter()
            .copied()
            .filter(|r| cost.of(r) <= cap)
            .collect(),
    );
    let (l, t) = (most_accurate(&kl), most_accurate(&kt));
    let cell =
        |r: Option<&Measured>| r.map_or("no run within it".to_string(), |r| names.cell_fine(r));
    let comparison = match (l, t) {
        (Some(l), Some(t)) => names.verdict(l, t),
        _ => String::new(),
    };
    format!(
        "| {scene} | {} | {} | {} | {comparison} |\n",
        cost.show(cap),
        cell(l),
        cell(t)
    )
}

/// How runs are named and flagged.
struct Names<'a> {
    runs: &'a [Measured],
    /// Each run's render command, by run index.
    commands: &'a BTreeMap<usize, String>,
    /// The runs a cell has named.
    named: RefCell<BTreeSet<usize>>,
    series: &'a [Series],
    constant: &'a [(String, Value)],
    margin: f64,
    cost_margin: f64,
    by: Option<&'a str>,
}

impl Names<'_> {
    /// Its parameters, as `name=value` joined by `, ` (the path and the shared ones aside).
    fn label(&self, m: &Measured) -> String {
        let label = m
            .params
            .iter()
            .filter(|(name, value)| {
                name.as_str() != "path"
                    && !self.constant.iter().any(|(n, v)| n == *name && v == *value)
            })
            .map(|(name, value)| {
                let value = match value {
                    Value::String(s) => s.clone(),
                    v => v.to_string(),
                };
                format!("{}={value}", name.trim_start_matches("arch."))
            })
            .collect::<Vec<_>>()
            .join(", ");
        if label.is_empty() {
            "defaults".to_string()
        } else {
            label
        }
    }

    /// The run in a table cell, with its fixed-count flag.
    fn cell(&self, m: &Measured) -> String {
        self.named.borrow_mut().insert(m.index);
        let mut cell = format!(
            "run {} ({}): {} cycles, {:.0} µJ, {:.1} dB, {:.2} mm², bound by {}",
            m.index,
            self.label(m),
            m.cycles.unwrap_or(0),
            m.uj(),
            m.psnr(),
            m.area_mm2.unwrap_or(f64::NAN),
            m.bottleneck.as_deref().unwrap_or("none")
        );
        if let Some(flag) = self.fixed_count(m) {
            let _ = write!(cell, "; **fixed count**: {flag}");
        }
        cell
    }

    /// Why a run chosen for its accuracy is not an answer, if it is not: it sits at the fine
    /// end of a series that was not bracketed (said without the leading "unbracketed: ").
    fn open_fine(&self, m: &Measured) -> Option<String> {
        let s = self.series_of(m)?;
        if m.knob != s.finest() || s.stop.bracketed(self.margin) {
            return None;
        }
        let why = s.stop.describe(self.margin, s.finest());
        Some(
            why.strip_prefix("unbracketed: ")
                .unwrap_or(&why)
                .to_string(),
        )
    }

    /// The cell of a run chosen for its accuracy, flagged where [`Self::open_fine`] says.
    fn cell_fine(&self, m: &Measured) -> String {
        let mut cell = self.cell(m);
        if let Some(why) = self.open_fine(m) {
            let _ = write!(cell, "; **unbracketed**: {why}");
        }
        cell
    }

    /// Which of the two most accurate runs is the more accurate, in words; no winner where
    /// either is unbracketed (a finer knob might change the answer).
    fn verdict(&self, lembo: &Measured, triangle: &Measured) -> String {
        let open: Vec<&str> = [("lembo", lembo), ("triangle", triangle)]
            .into_iter()
            .filter(|(_, m)| self.open_fine(m).is_some())
            .map(|(path, _)| path)
            .collect();
        if open.is_empty() {
            more_accurate(lembo, triangle)
        } else {
            format!(
                "no winner: the {} path's error still fell at its finest knob",
                open.join(" and the ")
            )
        }
    }

    /// The cell of a run chosen as the cheapest to reach a target: flagged when it sits at
    /// the coarse end of its architecture's runs and its series' coarse side is not
    /// bracketed (a coarser knob might reach the target for less).
    fn cell_coarse(&self, m: &Measured) -> String {
        let mut cell = self.cell(m);
        let coarser = self
            .runs
            .iter()
            .filter(|r| r.scene == m.scene && r.path == m.path && r.group() == m.group())
            .any(|r| coarser_than(r.knob, m.knob));
        let open = match self.series_of(m) {
            Some(s) => {
                (!s.coarse.bracketed()).then(|| s.coarse.describe(self.cost_margin, s.coarsest()))
            }
            None => Some(format!("no coarser {} was run", m.knob.param())),
        };
        if let (false, Some(why)) = (coarser, open) {
            let why = why.strip_prefix("unbracketed: ").unwrap_or(&why);
            let _ = write!(cell, "; **coarse end**: {why}");
        }
        cell
    }

    fn series_of(&self, m: &Measured) -> Option<&Series> {
        let key = m.series_key(self.by);
        self.series
            .iter()
            .find(|s| s.scene == m.scene && s.path == m.path && s.key == key)
    }

    /// Why a run's bounding unit's count was never varied, if it was not: the count field
    /// took one value in every run of the scene's path.
    fn fixed_count(&self, m: &Measured) -> Option<String> {
        let kind_name = m.bottleneck.as_deref()?.split('[').next()?;
        let kind = KINDS.iter().find(|k| k.name() == kind_name)?;
        let field = ArchConfig::count_field(*kind)?;
        let value = |r: &Measured| -> Value {
            field
                .split('.')
                .try_fold(&r.arch, |at, part| at.get(part))
                .cloned()
                .unwrap_or(Value::Null)
        };
        let values: BTreeSet<String> = self
            .runs
            .iter()
            .filter(|r| r.scene == m.scene && r.path == m.path)
            .map(|r| value(r).to_string())
            .collect();
        (values.len() == 1).then(|| format!("{field} = {} in every run", value(m)))
    }

    /// The section that gives each named run's command.
    fn reproduce(&self) -> String {
        let mut section = "\n## Reproducing the runs named above\n\nEach run above is \
                           `lembo-sim render` with these flags, run from the spec's folder \
                           (the paths are the spec's); compare a row's two runs' report.json \
                           files.\n\n"
            .to_string();
        for index in self.named.borrow().iter() {
            if let Some(command) = self.commands.get(index) {
                let _ = writeln!(section, "- run {index}: `{command}`");
            }
        }
        section
    }

    /// A row of the bracketing table.
    fn series_row(&self, s: &Series) -> String {
        let levels = s
            .levels
            .iter()
            .map(|(k, p)| match p {
                Some(p) => format!("{}: {p:.1} dB", k.label()),
                None => format!("{}: -", k.label()),
            })
            .collect::<Vec<_>>()
            .join(", ");
        let key = if s.key.is_empty() {
            "defaults".to_string()
        } else {
            s.key.replace('|', ", ")
        };
        format!(
            "| {} | {} | {key} | {levels} | {} | {} |",
            s.scene,
            s.path,
            s.stop.describe(self.margin, s.finest()),
            s.coarse.describe(self.cost_margin, s.coarsest())
        )
    }

    /// A target's row: each path's fastest and most frugal run reaching it, or why not.
    fn target_row(
        &self,
        scene: &str,
        metric: Metric,
        target: f64,
        lembo: &[&Measured],
        triangle: &[&Measured],
    ) -> String {
        let (rl, rt) = (
            reach(lembo, metric, target),
            reach(triangle, metric, target),
        );
        let missing = |path: &str, runs: &[&Measured]| -> String {
            let open: Vec<String> = self
                .series
                .iter()
                .filter(|s| s.scene == scene && s.path == path)
                .filter(|s| {
                    runs.iter()
                        .any(|m| self.series_of(m).is_some_and(|x| x.key == s.key))
                })
                .filter(|s| !s.stop.bracketed(self.margin))
                .map(|s| s.stop.describe(self.margin, s.finest()))
                .collect();
            if open.is_empty() {
                format!("not reached (every {path} series bracketed)")
            } else {
                let open: Vec<&str> = open
                    .iter()
                    .map(|w| w.strip_prefix("unbracketed: ").unwrap_or(w))
                    .collect();
                format!("not reached; **unbracketed**: {}", open.join("; "))
            }
        };
        let show = metric.show(target);
        match (rl, rt) {
            (Some(l), Some(t)) => format!(
                "| {scene} | {show} | {} | {} | {} | {} | {} | {} |\n",
                self.cell_coarse(l.fastest),
                self.cell_coarse(t.fastest),
                ratio("cycles", l.fastest.cycles_f(), t.fastest.cycles_f()),
                self.cell_coarse(l.frugal),
                self.cell_coarse(t.frugal),
                ratio("µJ", l.frugal.uj(), t.frugal.uj()),
            ),
            (l, t) => format!(
                "| {scene} | {show} | {} | {} | | {} | {} | |\n",
                l.map_or_else(|| missing("lembo", lembo), |l| self.cell_coarse(l.fastest)),
                t.map_or_else(
                    || missing("triangle", triangle),
                    |t| self.cell_coarse(t.fastest)
                ),
                l.map_or(String::new(), |l| self.cell_coarse(l.frugal)),
                t.map_or(String::new(), |t| self.cell_coarse(t.frugal)),
            ),
        }
    }
}

/// Whether knob `a` is coarser than `b`.
fn coarser_than(a: Knob, b: Knob) -> bool {
    match (a, b) {
        (Knob::K(a), Knob::K(b)) => a > b,
        (Knob::Tess(a), Knob::Tess(b)) => a < b,
        _ => false,
    }
}
