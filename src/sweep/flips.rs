//! answer.md's "What flips it" (DESIGN.md §7): at the sensitivity study's target, the
//! lembo path's advantage on the spec's architecture as it is against each variant's, as a
//! table and two tornado charts a scene.

use super::bracket::{Limits, Measured};
use super::curves::{reach, Metric};
use super::names::{file_stem, Figure, ARCH, SENSITIVITY, TECH};
use super::sensitivity::{Param, Sensitivity};
use crate::error::Result;
use crate::job::PrimitivePath;
use crate::plot::speedup::{tornado_svg, TornadoBar};
use serde_json::Value;
use std::fmt::Write as _;

/// The lembo path's advantage: (the triangle path's fewest cycles over the lembo path's,
/// its least energy over the lembo path's).
type Advantage = (f64, f64);

/// One scene's study: its runs on the spec's architecture as it is, and the variants.
struct Study<'a> {
    scene: &'a str,
    metric: Metric,
    target: f64,
    lembo: Vec<&'a Measured>,
    triangle: Vec<&'a Measured>,
    variants: &'a [Measured],
    budget: Option<f64>,
}

impl<'a> Study<'a> {
    /// The advantage at the target of runs `l` and `t`; None where a path does not reach it.
    fn advantage(&self, l: &[&Measured], t: &[&Measured]) -> Option<Advantage> {
        let (rl, rt) = (
            reach(l, self.metric, self.target)?,
            reach(t, self.metric, self.target)?,
        );
        let cycles = |m: &Measured| m.cycles.unwrap_or(u64::MAX) as f64;
        let uj = |m: &Measured| m.energy_uj.unwrap_or(f64::INFINITY);
        Some((
            cycles(rt.fastest) / cycles(rl.fastest),
            uj(rt.frugal) / uj(rl.frugal),
        ))
    }

    /// The variant `tag`'s runs of `path`: within the budget, and whether it had any.
    fn variant(&self, path: PrimitivePath, tag: &str) -> (Vec<&'a Measured>, bool) {
        let tagged: Vec<&'a Measured> = self
            .variants
            .iter()
            .filter(|m| m.scene == self.scene && m.path == path.name())
            .filter(|m| m.params.get(SENSITIVITY) == Some(&Value::from(tag)))
            .collect();
        let any = !tagged.is_empty();
        let within = tagged
            .into_iter()
            .filter(|m| m.within(self.budget))
            .collect();
        (within, any)
    }

    /// At parameter `p`'s end `tag`: the advantage, using the variant's runs of each path
    /// it varies and the unvaried runs of the other, and whether the variant's runs are all
    /// over the area budget.
    fn at_end(&self, p: &Param, tag: &str) -> (Option<Advantage>, bool) {
        let mut over = false;
        let mut runs = |path: PrimitivePath, as_is: &[&'a Measured]| -> Vec<&'a Measured> {
            if !p.applies(path) {
                return as_is.to_vec();
            }
            let (within, any) = self.variant(path, tag);
            over |= any && within.is_empty();
            within
        };
        let l = runs(PrimitivePath::Lembo, &self.lembo);
        let t = runs(PrimitivePath::Triangle, &self.triangle);
        (self.advantage(&l, &t), over)
    }
}

/// A scene's part of "What flips it" and its two tornado charts (cycles, energy).
pub(super) fn section<'a>(
    scene: &'a str,
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
                    .any(|k| k.starts_with(ARCH) || k.starts_with(TECH))
            })
            .collect()
    };
    let s = Study {
        scene,
        metric,
        target,
        lembo: as_is(lembo),
        triangle: as_is(triangle),
        variants,
        budget: limits.budget,
    };
    let Some(base) = s.advantage(&s.lembo, &s.triangle) else {
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
        let [low, high] = p.tags().map(|tag| s.at_end(p, &tag));
        let _ = writeln!(
            text,
            "| {} | {} | {} | {} | {} | {} | {} |",
            p.name,
            ends[0],
            ends[1],
            cell(base.0, low.0.map(|a| a.0), low.1),
            cell(base.0, high.0.map(|a| a.0), high.1),
            cell(base.1, low.0.map(|a| a.1), low.1),
            cell(base.1, high.0.map(|a| a.1), high.1),
        );
        let bar = |get: fn(Advantage) -> f64| TornadoBar {
            param: p.name.trim_start_matches("arch.").to_string(),
            low: ends[0].clone(),
            high: ends[1].clone(),
            at_low: low.0.map(get),
            at_high: high.0.map(get),
        };
        cycles_bars.push(bar(|a| a.0));
        energy_bars.push(bar(|a| a.1));
    }
    let figures = charts(scene, metric.show(target), base, &cycles_bars, &energy_bars)?;
    Ok((text, figures))
}

/// A table cell: the advantage, marked where it turns across 1 from `base`.
fn cell(base: f64, v: Option<f64>, over_budget: bool) -> String {
    let shown = v.map_or("not reached".to_string(), |a| format!("{a:.2}x"));
    if over_budget {
        "over the area budget".to_string()
    } else if v.is_some_and(|v| (v - 1.0).signum() != (base - 1.0).signum()) {
        format!("{shown} **flips**")
    } else {
        shown
    }
}

/// `tornado_cycles_<scene>.svg` and `tornado_energy_<scene>.svg`.
fn charts(
    scene: &str,
    target: String,
    base: Advantage,
    cycles: &[TornadoBar],
    energy: &[TornadoBar],
) -> Result<Vec<Figure>> {
    let stem = file_stem(scene);
    let title =
        |what: &str| format!("{scene}: what moves the lembo advantage in {what} at {target}");
    Ok(vec![
        (
            format!("tornado_cycles_{stem}.svg"),
            tornado_svg(
                &title("cycles"),
                "triangle cycles / lembo cycles",
                base.0,
                cycles,
            )?
            .into_bytes(),
        ),
        (
            format!("tornado_energy_{stem}.svg"),
            tornado_svg(
                &title("energy"),
                "triangle energy / lembo energy",
                base.1,
                energy,
            )?
            .into_bytes(),
        ),
    ])
}
