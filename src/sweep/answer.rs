//! `answer.md` and its figures: the lembo path against the triangle path on each scene of a
//! sweep with an area budget (DESIGN.md §7, "The answer"), every run named by its
//! parameters and the unit that bounds it:
//!
//! - **bracketing**: each series' knob levels (k on the lembo path, n on the triangle path),
//!   the best PSNR at each, and why it went no further ([`super::bracket`]);
//! - **speed-up against target error**, on PSNR, mean FLIP and the silhouette error: at each
//!   target, each path's fewest cycles and least energy within the budget (the monotone
//!   envelope, [`super::curves`]), and `speedup_<metric>_<scene>.svg` over every level;
//! - **equal area**: each path's most accurate run (highest PSNR) within the budget, the
//!   fastest of equally accurate ones;
//! - **equal energy**: the cap is the least energy a frame at which both paths have a run
//!   within the budget (the higher of their least energies); each path's most accurate run
//!   within it.
//!
//! A deciding run is flagged where the answer would be the grid's, not the hardware's: at
//! the fine end of a series that was not bracketed, at the coarse end of its grid (a
//! coarser knob might reach the target for less), or bound by a unit whose count the
//! sweep held at one value. Remaining ties go to the run listed first in the sweep. Only
//! runs with both a cost and an accuracy count (timed runs measured against the reference).

use super::bracket::{series, Knob, Limits, Measured, Refine, Series, DEFAULT_MARGIN_DB};
use super::curves::{curve, default_targets, reach, Metric, Targets, METRICS};
use super::sensitivity::Sensitivity;
use crate::config::ArchConfig;
use crate::error::Result;
use crate::graph::KINDS;
use crate::job::PrimitivePath;
use crate::job::MAX_TRIANGLES;
use crate::plot::speedup::{speedup_svg, tornado_svg, SpeedupFigure, TornadoBar};
use crate::tolerance::K_RANGE;
use serde_json::Value;
use std::collections::BTreeSet;
use std::fmt::Write as _;

/// A file the answer writes: its name and bytes.
pub(super) type Figure = (String, Vec<u8>);

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
}

/// `answer.md` and its figures, as (file name, bytes), for `records`; None when no scene
/// has measured runs of both paths within the budget.
pub(super) fn answer_files(records: &[Value], ask: &Ask) -> Result<Option<Vec<Figure>>> {
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
    };
    let all_series = series(&runs, &limits);
    let (constant, shared) = shared_params(&runs);
    let margin = ask.refine.map_or(DEFAULT_MARGIN_DB, |r| r.margin_db);
    let names = Names {
        runs: &runs,
        series: &all_series,
        constant: &constant,
        margin,
    };

    let mut scenes: Vec<&str> = Vec::new();
    for m in &runs {
        if !scenes.contains(&m.scene.as_str()) {
            scenes.push(&m.scene);
        }
    }
    let mut figures: Vec<Figure> = Vec::new();
    let (mut area, mut energy, mut bracket) = (String::new(), String::new(), String::new());
    let mut flips = String::new();
    let mut curves: Vec<String> = vec![String::new(); METRICS.len()];
    let mut any = false;
    for scene in scenes {
        let within = |path: &str| -> Vec<&Measured> {
            runs.iter()
                .filter(|m| m.scene == scene && m.path == path && m.within(limits.budget))
                .collect()
        };
        let (lembo, triangle) = (within("lembo"), within("triangle"));
        for s in all_series.iter().filter(|s| s.scene == scene) {
            let _ = writeln!(bracket, "{}", names.series_row(s));
        }
        let (Some(bl), Some(bt)) = (most_accurate(&lembo), most_accurate(&triangle)) else {
            let _ = writeln!(
                area,
                "| {scene} | no run of both paths within {} mm² | | |",
                ask.budget_mm2
            );
            continue;
        };
        any = true;
        let _ = writeln!(
            area,
            "| {scene} | {} | {} | {}; {}, {} |",
            names.cell_fine(bl),
            names.cell_fine(bt),
            more_accurate(bl, bt),
            ratio("cycles", bl.cycles_f(), bt.cycles_f()),
            ratio("µJ", bl.uj(), bt.uj()),
        );
        energy += &equal_energy_row(scene, &lembo, &triangle, &names);
        if let Some(study) = &ask.sensitivity {
            let (section, figs) = tornado(scene, study, &lembo, &triangle, &variants, &limits)?;
            flips += &section;
            figures.extend(figs);
        }
        for (i, &metric) in METRICS.iter().enumerate() {
            let stated = ask.targets.of(metric).map(<[f64]>::to_vec);
            let targets = stated.unwrap_or_else(|| default_targets(&lembo, &triangle, metric));
            for t in targets {
                curves[i] += &names.target_row(scene, metric, t, &lembo, &triangle);
            }
            let points = curve(&lembo, &triangle, metric);
            if points.is_empty() {
                continue;
            }
            let cycles: Vec<(f64, f64)> = points.iter().map(|p| (p.target, p.cycles)).collect();
            let energy: Vec<(f64, f64)> = points.iter().map(|p| (p.target, p.energy)).collect();
            let svg = speedup_svg(&SpeedupFigure {
                scene,
                metric: metric.title(),
                higher_is_stricter: metric.higher_is_better(),
                cycles: &cycles,
                energy: &energy,
            })?;
            figures.push((
                format!("speedup_{}_{}.svg", metric.name(), file_stem(scene)),
                svg.into_bytes(),
            ));
        }
    }
    if !any {
        return Ok(None);
    }
    let mut page = preamble(ask, margin, &shared);
    page += &bracket;
    page += "\n## Speed-up against target error\n\nFor each target, each path's fewest cycles \
             and least energy with which a run within the budget reaches it (a path reaches a \
             target at cost C if any of its runs costing at most C reaches it). The figures \
             (`speedup_<metric>_<scene>.svg`) draw the speed-up at every level a run measured \
             that both paths reach.\n";
    for (i, &metric) in METRICS.iter().enumerate() {
        let how = match ask.targets.of(metric) {
            Some(_) => "the spec's targets".to_string(),
            None => "three levels from the runs: the stricter of the two paths' worst, the \
                     looser of their best, and their middle"
                .to_string(),
        };
        let _ = write!(
            page,
            "\n### {} ({})\n\n| scene | target | lembo, fastest | triangle, fastest | cycles | \
             lembo, least energy | triangle, least energy | energy |\n|---|---|---|---|---|---|---|---|\n",
            metric.title(),
            how
        );
        page += &curves[i];
    }
    page += "\n## At equal area\n\nEach path's most accurate run (PSNR) within the budget (ties: \
             the fastest).\n\n| scene | lembo | triangle | comparison |\n|---|---|---|---|\n";
    page += &area;
    page += "\n## At equal energy\n\nThe energy cap is the least at which both paths have a \
             run within the budget (the higher of their least energies a frame); each path's \
             most accurate run within the area budget spending at most that (ties: the \
             fastest).\n\n| scene | cap | lembo | triangle | comparison |\n|---|---|---|---|---|\n";
    page += &energy;
    if let Some(study) = &ask.sensitivity {
        let (metric, target) = study.target;
        let _ = write!(
            page,
            "\n## What flips it\n\nOne parameter at a time, scaled down and up (or set low and \
             high) with every other setting at the grid's: the lembo path's advantage at a {} \
             target of {} (the triangle path's fewest cycles over the lembo path's, and its \
             least energy over the lembo path's), against the same runs on the spec's \
             architecture as it is (the grid's points that set no `arch.` field). A variant that \
             turns the advantage to the other side of 1 is marked **flips**; one whose runs \
             exceed the area budget is said to.\n",
            metric.title(),
            metric.show(target)
        );
        page += &flips;
    }
    if !figures.is_empty() {
        page += "\n## Figures\n\n";
        for (name, _) in &figures {
            let _ = writeln!(page, "- [{name}]({name})");
        }
    }
    let mut files = vec![("answer.md".to_string(), page.into_bytes())];
    files.extend(figures);
    Ok(Some(files))
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
         finer knob was not run), **coarse end** where a coarser knob was not \
         tried and might reach the target for less, and **fixed count** where the unit that \
         bounds it had one count in every run of its path.\n\n"
    );
    if !shared.is_empty() {
        page += shared;
        page += "\n";
    }
    page += &format!(
        "## Bracketing\n\nEach series is a scene's runs of one path that differ only in the \
         knob and the architecture (their images do not depend on the architecture). \
         {}\n\n| scene | path | series | levels (best PSNR) | how it ended |\n|---|---|---|---|---|\n",
        match ask.refine {
            Some(r) => format!(
                "Refined beyond the grid (k halved down to {}, n doubled up to {}{}) until the \
                 last two levels each gained under {} dB over the best coarser one; each finer level \
                 runs on the series' fastest and most frugal architectures at the level before.",
                r.k_floor,
                r.tess_cap,
                r.cycle_cap
                    .map_or(String::new(), |c| format!(", until a run took over {c} cycles")),
                r.margin_db
            ),
            None => format!(
                "The spec asks for no refinement (`refine`): a series whose last two steps \
                 did not each gain under {margin} dB stops at the edge of its grid."
            ),
        }
    );
    page
}

/// A scene's name as a file name's part.
fn file_stem(scene: &str) -> String {
    scene
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
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

/// The equal-energy row of `scene`.
fn equal_energy_row(
    scene: &str,
    lembo: &[&Measured],
    triangle: &[&Measured],
    names: &Names,
) -> String {
    let least = |runs: &[&Measured]| runs.iter().map(|r| r.uj()).fold(f64::MAX, f64::min);
    let cap = least(lembo).max(least(triangle));
    let (kl, kt): (Vec<&Measured>, Vec<&Measured>) = (
        lembo.iter().copied().filter(|r| r.uj() <= cap).collect(),
        triangle.iter().copied().filter(|r| r.uj() <= cap).collect(),
    );
    let (l, t) = (most_accurate(&kl), most_accurate(&kt));
    let cell = |r: Option<&Measured>| r.map_or("no run within it".to_string(), |r| names.cell(r));
    let comparison = match (l, t) {
        (Some(l), Some(t)) => more_accurate(l, t),
        _ => String::new(),
    };
    format!(
        "| {scene} | {cap:.0} µJ | {} | {} | {comparison} |\n",
        cell(l),
        cell(t)
    )
}

/// How runs are named and flagged.
struct Names<'a> {
    runs: &'a [Measured],
    series: &'a [Series],
    constant: &'a [(String, Value)],
    margin: f64,
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
        let mut cell = format!(
            "{}: {} cycles, {:.0} µJ, {:.1} dB, {:.2} mm², bound by {}",
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

    /// The cell of a run chosen for its accuracy: flagged when it sits at the fine end of a
    /// series that was not bracketed.
    fn cell_fine(&self, m: &Measured) -> String {
        let mut cell = self.cell(m);
        if let Some(s) = self.series_of(m) {
            if m.knob == s.finest() && !s.stop.bracketed(self.margin) {
                let why = s.stop.describe(self.margin, s.finest());
                let why = why.strip_prefix("unbracketed: ").unwrap_or(&why);
                let _ = write!(cell, "; **unbracketed**: {why}");
            }
        }
        cell
    }

    /// The cell of a run chosen as the cheapest to reach a target: flagged when it sits at
    /// the coarse end of its grid and a coarser knob exists.
    fn cell_coarse(&self, m: &Measured) -> String {
        let mut cell = self.cell(m);
        let coarser = self
            .runs
            .iter()
            .filter(|r| r.scene == m.scene && r.path == m.path && r.group() == m.group())
            .any(|r| coarser_than(r.knob, m.knob));
        let natural = match m.knob {
            Knob::Tess(n) => n <= 1,
            Knob::K(k) => k >= K_RANGE.1,
        };
        if !coarser && !natural {
            let _ = write!(
                cell,
                "; **coarse end**: no coarser {} was run on its architecture",
                m.knob.param()
            );
        }
        cell
    }

    fn series_of(&self, m: &Measured) -> Option<&Series> {
        let key = m.series_key();
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
            "| {} | {} | {key} | {levels} | {} |",
            s.scene,
            s.path,
            s.stop.describe(self.margin, s.finest())
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

/// A scene's part of "What flips it" and its two tornado charts (cycles, energy).
fn tornado<'a>(
    scene: &str,
    study: &Sensitivity,
    lembo: &[&'a Measured],
    triangle: &[&'a Measured],
    variants: &'a [Measured],
    limits: &Limits,
) -> Result<(String, Vec<Figure>)> {
    let (metric, target) = study.target;
    // The grid's runs on the spec's architecture as it is: the points the variants vary.
    let as_is = |runs: &[&'a Measured]| -> Vec<&'a Measured> {
        runs.iter()
            .copied()
            .filter(|m| {
                !m.params
                    .keys()
                    .any(|k| k.starts_with(super::spec::ARCH) || k.starts_with(super::spec::TECH))
            })
            .collect()
    };
    let (lembo, triangle) = (&as_is(lembo)[..], &as_is(triangle)[..]);
    // (cycles, energy) advantage of the lembo path at the target; None where a path does
    // not reach it.
    let advantage = |l: &[&Measured], t: &[&Measured]| -> Option<(f64, f64)> {
        let (rl, rt) = (reach(l, metric, target)?, reach(t, metric, target)?);
        Some((
            rt.fastest.cycles_f() / rl.fastest.cycles_f(),
            rt.frugal.uj() / rl.frugal.uj(),
        ))
    };
    let show = |a: Option<f64>| a.map_or("not reached".to_string(), |a| format!("{a:.2}x"));
    let Some(base) = advantage(lembo, triangle) else {
        return Ok((
            format!(
                "\n**{scene}**: one of the paths does not reach {} on the grid's runs; no sensitivity.\n",
                metric.show(target)
            ),
            Vec::new(),
        ));
    };
    let mut text = format!(
        "\n**{scene}** (on the spec's architecture as it is: {:.2}x cycles, {:.2}x energy)\n\n| parameter | low | high | cycles at low | cycles at high | energy at low | energy at high |\n|---|---|---|---|---|---|---|\n",
        base.0, base.1
    );
    let (mut cycles_bars, mut energy_bars) = (Vec::new(), Vec::new());
    for p in &study.params {
        let ends = p.ends();
        let mut at = [None, None];
        let mut over_budget = [false, false];
        for (i, tag) in p.tags().iter().enumerate() {
            let pick = |path: PrimitivePath| -> Vec<&'a Measured> {
                variants
                    .iter()
                    .filter(|m| m.scene == scene && m.path == path.name())
                    .filter(|m| {
                        m.params.get(super::sensitivity::PARAM) == Some(&Value::from(tag.as_str()))
                    })
                    .filter(|m| m.within(limits.budget))
                    .collect()
            };
            let l = match p.applies(PrimitivePath::Lembo) {
                true => pick(PrimitivePath::Lembo),
                false => lembo.to_vec(),
            };
            let t = match p.applies(PrimitivePath::Triangle) {
                true => pick(PrimitivePath::Triangle),
                false => triangle.to_vec(),
            };
            at[i] = advantage(&l, &t);
            let over = |path: PrimitivePath, kept: &[&Measured]| {
                p.applies(path)
                    && kept.is_empty()
                    && variants.iter().any(|m| {
                        m.scene == scene
                            && m.path == path.name()
                            && m.params.get(super::sensitivity::PARAM)
                                == Some(&Value::from(tag.as_str()))
                    })
            };
            over_budget[i] = over(PrimitivePath::Lembo, &l) || over(PrimitivePath::Triangle, &t);
        }
        let flips = |base: f64, v: Option<f64>| {
            v.is_some_and(|v| (v - 1.0).signum() != (base - 1.0).signum())
        };
        let cell = |base: f64, v: Option<f64>, over: bool| {
            if over {
                "over the area budget".to_string()
            } else if flips(base, v) {
                format!("{} **flips**", show(v))
            } else {
                show(v)
            }
        };
        let _ = writeln!(
            text,
            "| {} | {} | {} | {} | {} | {} | {} |",
            p.name,
            ends[0],
            ends[1],
            cell(base.0, at[0].map(|a| a.0), over_budget[0]),
            cell(base.0, at[1].map(|a| a.0), over_budget[1]),
            cell(base.1, at[0].map(|a| a.1), over_budget[0]),
            cell(base.1, at[1].map(|a| a.1), over_budget[1]),
        );
        for (bars, pick) in [(&mut cycles_bars, 0usize), (&mut energy_bars, 1)] {
            let get = |a: Option<(f64, f64)>| a.map(|a| if pick == 0 { a.0 } else { a.1 });
            bars.push(TornadoBar {
                param: p.name.trim_start_matches("arch.").to_string(),
                low: ends[0].clone(),
                high: ends[1].clone(),
                at_low: get(at[0]),
                at_high: get(at[1]),
            });
        }
    }
    let stem = file_stem(scene);
    let title = |what: &str| {
        format!(
            "{scene}: what moves the lembo advantage in {what} at {}",
            metric.show(target)
        )
    };
    let figures = vec![
        (
            format!("tornado_cycles_{stem}.svg"),
            tornado_svg(
                &title("cycles"),
                "triangle cycles / lembo cycles",
                base.0,
                &cycles_bars,
            )?
            .into_bytes(),
        ),
        (
            format!("tornado_energy_{stem}.svg"),
            tornado_svg(
                &title("energy"),
                "triangle energy / lembo energy",
                base.1,
                &energy_bars,
            )?
            .into_bytes(),
        ),
    ];
    Ok((text, figures))
}
