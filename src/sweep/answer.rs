//! `answer.md`: the lembo path against the triangle path on each scene of a sweep with an
//! area budget, three ways (DESIGN.md §7, "The answer"), each run named by its parameters
//! and its bottleneck:
//!
//! - **equal area**: each path's most accurate run (highest PSNR) whose unit is within the
//!   budget, the fastest of equally accurate ones;
//! - **equal error**: the target is the lower of the two paths' best PSNR within the budget;
//!   each path's fastest run (fewest cycles) within the budget that reaches it, and, apart,
//!   its most frugal one (least energy a frame) that reaches it;
//! - **equal energy**: the cap is the least energy a frame at which both paths have a run
//!   within the area budget (the higher of their least energies); each path's most accurate
//!   run within the area budget that spends at most that.
//!
//! Remaining ties go to the run listed first in the sweep. A scene where a path has no measured run
//! within the budget gets a line saying so. Only runs with both a cost and an accuracy count
//! (timed runs measured against the reference).

use serde_json::Value;
use std::fmt::Write as _;

/// One measured run: what the answer reads of its record.
#[derive(Clone, Debug)]
struct Run {
    /// `lembo` or `triangle`.
    path: String,
    /// Its parameters, as `name=value` joined by `, ` (the path aside).
    label: String,
    cycles: u64,
    energy_uj: f64,
    area_mm2: f64,
    psnr_db: f64,
    bottleneck: String,
}

impl Run {
    /// The run of `record`, its label without the parameters in `constant`.
    fn of(record: &Value, constant: &[(String, Value)]) -> Option<Run> {
        let report = &record["report"];
        let params = record["params"].as_object()?;
        let path = params
            .get("path")
            .and_then(Value::as_str)
            .unwrap_or("lembo")
            .to_string();
        let label = params
            .iter()
            .filter(|(name, value)| {
                name.as_str() != "path" && !constant.iter().any(|(n, v)| n == *name && v == *value)
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
        Some(Run {
            path,
            label,
            cycles: report["cycles"]["total"].as_u64()?,
            energy_uj: report["cost"]["energy_pj"].as_f64()? * 1e-6,
            area_mm2: report["cost"]["area_mm2"].as_f64()?,
            psnr_db: report["accuracy"]["psnr_db"].as_f64()?,
            bottleneck: report["cycles"]["bottleneck"]
                .as_str()
                .unwrap_or("none")
                .to_string(),
        })
    }

    /// The run in a table cell.
    fn cell(&self) -> String {
        format!(
            "{}: {} cycles, {:.0} µJ, {:.1} dB, {:.2} mm², bound by {}",
            if self.label.is_empty() {
                "defaults"
            } else {
                &self.label
            },
            self.cycles,
            self.energy_uj,
            self.psnr_db,
            self.area_mm2,
            self.bottleneck
        )
    }
}

/// The first of `runs` with the largest `key`, compared in order (ties: the earliest).
fn best_by<'a>(runs: &[&'a Run], key: impl Fn(&Run) -> (f64, f64)) -> Option<&'a Run> {
    runs.iter()
        .copied()
        .fold(None, |best: Option<&Run>, r| match best {
            Some(b) if key(b) >= key(r) => Some(b),
            _ => Some(r),
        })
}

/// Most accurate, then fastest.
fn accurate(r: &Run) -> (f64, f64) {
    (r.psnr_db, -(r.cycles as f64))
}

/// Fastest, then least energy.
fn fast(r: &Run) -> (f64, f64) {
    (-(r.cycles as f64), -r.energy_uj)
}

/// Least energy, then fastest.
fn frugal(r: &Run) -> (f64, f64) {
    (-r.energy_uj, -(r.cycles as f64))
}

/// The runs of `runs` that `keep`.
fn filtered<'a>(runs: &[&'a Run], keep: impl Fn(&Run) -> bool) -> Vec<&'a Run> {
    runs.iter().copied().filter(|r| keep(r)).collect()
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
fn more_accurate(lembo: &Run, triangle: &Run) -> String {
    let winner = if lembo.psnr_db >= triangle.psnr_db {
        "lembos"
    } else {
        "triangles"
    };
    format!(
        "{winner} more accurate by {:.1} dB",
        (lembo.psnr_db - triangle.psnr_db).abs()
    )
}

/// The parameters every run of a path shares (one value, in every run), to leave out of
/// the labels, and the sentences that say them once.
fn shared_params(records: &[Value]) -> (Vec<(String, Value)>, String) {
    let path_of = |r: &Value| r["params"]["path"].as_str().unwrap_or("lembo").to_string();
    let mut constant: Vec<(String, Value)> = Vec::new();
    let mut shared = String::new();
    for path in ["lembo", "triangle"] {
        let of_path: Vec<&Value> = records.iter().filter(|r| path_of(r) == path).collect();
        let Some(first) = of_path.first().and_then(|r| r["params"].as_object()) else {
            continue;
        };
        let mut same: Vec<String> = Vec::new();
        for (name, value) in first {
            if name != "path" && of_path.iter().all(|r| r["params"].get(name) == Some(value)) {
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

/// The measured runs of `records` by scene, scenes in the order they first appear.
fn by_scene(records: &[Value], constant: &[(String, Value)]) -> Vec<(String, Vec<Run>)> {
    let mut scenes: Vec<(String, Vec<Run>)> = Vec::new();
    for record in records {
        let Some(run) = Run::of(record, constant) else {
            continue;
        };
        let scene = record["scene"].as_str().unwrap_or("?");
        match scenes.iter_mut().find(|(s, _)| s == scene) {
            Some((_, runs)) => runs.push(run),
            None => scenes.push((scene.to_string(), vec![run])),
        }
    }
    scenes
}

/// The equal-error row of `scene`: both paths reach `target`; each one's fastest and most
/// frugal run that does. None when a path has no such run (it cannot happen when `target`
/// is the lower of their best).
fn equal_error_row(scene: &str, lembo: &[&Run], triangle: &[&Run], target: f64) -> Option<String> {
    let (rl, rt) = (
        filtered(lembo, |r| r.psnr_db >= target),
        filtered(triangle, |r| r.psnr_db >= target),
    );
    let (fl, ft) = (best_by(&rl, fast)?, best_by(&rt, fast)?);
    let (el, et) = (best_by(&rl, frugal)?, best_by(&rt, frugal)?);
    Some(format!(
        "| {scene} | {target:.1} dB | {} | {} | {} | {} | {}; {} |\n",
        fl.cell(),
        ft.cell(),
        el.cell(),
        et.cell(),
        ratio("cycles", fl.cycles as f64, ft.cycles as f64),
        ratio("µJ", el.energy_uj, et.energy_uj),
    ))
}

/// The equal-energy row of `scene`: the cap is the least energy at which both paths have
/// a run; each one's most accurate run within it.
fn equal_energy_row(scene: &str, lembo: &[&Run], triangle: &[&Run]) -> String {
    let least = |runs: &[&Run]| runs.iter().map(|r| r.energy_uj).fold(f64::MAX, f64::min);
    let cap = least(lembo).max(least(triangle));
    let (sl, st) = (
        filtered(lembo, |r| r.energy_uj <= cap),
        filtered(triangle, |r| r.energy_uj <= cap),
    );
    let (l, t) = (best_by(&sl, accurate), best_by(&st, accurate));
    let cell = |r: Option<&Run>| r.map_or("no run within it".to_string(), Run::cell);
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

/// The answer page for `records` within `budget_mm2`; None when no scene has measured
/// runs of both paths.
pub(super) fn answer_md(records: &[Value], budget_mm2: f64) -> Option<String> {
    let (constant, shared) = shared_params(records);
    let (mut area, mut error, mut energy) = (String::new(), String::new(), String::new());
    let mut any = false;
    for (scene, runs) in by_scene(records, &constant) {
        let within = |path: &str| -> Vec<&Run> {
            runs.iter()
                .filter(|r| r.path == path && r.area_mm2 <= budget_mm2)
                .collect()
        };
        let (lembo, triangle) = (within("lembo"), within("triangle"));
        let (Some(bl), Some(bt)) = (best_by(&lembo, accurate), best_by(&triangle, accurate)) else {
            let _ = writeln!(
                area,
                "| {scene} | no run of both paths within {budget_mm2} mm² | | |"
            );
            continue;
        };
        any = true;
        let _ = writeln!(
            area,
            "| {scene} | {} | {} | {}; {}, {} |",
            bl.cell(),
            bt.cell(),
            more_accurate(bl, bt),
            ratio("cycles", bl.cycles as f64, bt.cycles as f64),
            ratio("µJ", bl.energy_uj, bt.energy_uj),
        );
        let target = bl.psnr_db.min(bt.psnr_db);
        error += &equal_error_row(&scene, &lembo, &triangle, target).unwrap_or_default();
        energy += &equal_energy_row(&scene, &lembo, &triangle);
    }
    if !any {
        return None;
    }
    let mut page = format!(
        "# The answer: lembos against triangles\n\n\
         Made by `lembo-sim sweep` from this directory's runs (DESIGN.md §7): every run whose \
         unit is within the spec's area budget of {budget_mm2} mm², measured against the exact \
         reference (PSNR). A run is named by its parameters and the unit that bounds it.\n\n"
    );
    if !shared.is_empty() {
        page += &shared;
        page += "\n";
    }
    page += "## At equal area\n\nEach path's most accurate run within the budget (ties: the \
             fastest).\n\n";
    page += "| scene | lembo | triangle | comparison |\n|---|---|---|---|\n";
    page += &area;
    page += "\n## At equal error\n\nThe target is the lower of the two paths' best PSNR \
             within the budget; each path's fastest run reaching it (ties: the more frugal), \
             and its most frugal one (ties: the faster).\n\n";
    page += "| scene | target | lembo, fastest | triangle, fastest | lembo, least energy | \
             triangle, least energy | comparison |\n|---|---|---|---|---|---|---|\n";
    page += &error;
    page += "\n## At equal energy\n\nThe energy cap is the least at which both paths have a \
             run within the budget (the higher of their least energies a frame); each path's \
             most accurate run within the area budget spending at most that (ties: the \
             fastest).\n\n";
    page += "| scene | cap | lembo | triangle | comparison |\n|---|---|---|---|---|\n";
    page += &energy;
    Some(page)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn record(scene: &str, params: Value, cycles: u64, uj: f64, mm2: f64, db: f64) -> Value {
        json!({
            "scene": scene,
            "params": params,
            "report": {
                "cycles": {"total": cycles, "bottleneck": "Rop[0]"},
                "cost": {"energy_pj": uj * 1e6, "area_mm2": mm2},
                "accuracy": {"psnr_db": db}
            }
        })
    }

    /// A hand-worked scene: the budget excludes the most accurate triangle run; equal
    /// error picks the fastest and the most frugal runs reaching the lower best; equal
    /// energy caps at the higher of the paths' least energies.
    #[test]
    fn the_three_answers_follow_their_definitions() {
        let records = [
            record("s", json!({"path": "lembo", "k": 1}), 100, 10.0, 1.0, 40.0),
            record(
                "s",
                json!({"path": "lembo", "k": 0.5}),
                150,
                12.0,
                1.0,
                45.0,
            ),
            record(
                "s",
                json!({"path": "triangle", "tess": 4}),
                80,
                8.0,
                1.0,
                42.0,
            ),
            record(
                "s",
                json!({"path": "triangle", "tess": 8}),
                300,
                30.0,
                1.5,
                44.0,
            ),
            record(
                "s",
                json!({"path": "triangle", "tess": 16}),
                900,
                90.0,
                9.0,
                60.0,
            ),
        ];
        let page = answer_md(&records, 2.0).unwrap();
        // Equal area: lembo k = 0.5 (45 dB) against triangle n = 8 (44 dB; n = 16 is 9 mm²).
        assert!(page.contains("| s | k=0.5: 150 cycles"), "{page}");
        assert!(page.contains("tess=8: 300 cycles"), "{page}");
        assert!(page.contains("lembos more accurate by 1.0 dB"), "{page}");
        // Equal error at 44 dB: lembo k = 0.5 (150 cycles) against triangle n = 8 (300).
        assert!(page.contains("| s | 44.0 dB | k=0.5: 150"), "{page}");
        assert!(page.contains("lembos 2.00x fewer cycles"), "{page}");
        // Equal energy, capped at 10 µJ (the lembo path's least; the triangle path's is 8):
        // lembo k = 1 (40 dB) against triangle n = 4 (42 dB).
        assert!(page.contains("| s | 10 µJ | k=1: 100 cycles"), "{page}");
        assert!(
            page.contains("triangles more accurate by 2.0 dB |"),
            "{page}"
        );
        // Without both paths within the budget there is no answer.
        assert!(answer_md(&records[..2], 2.0).is_none());
    }
}
