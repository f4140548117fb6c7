//! The answer grouped by one swept parameter (`by` in the spec, `--by` on `sweep` and
//! `sweep-merge`; DESIGN.md §7, "The answer by value"): for each value the field takes,
//! `answer.md` and its figures made from only the runs at that value, under
//! `by_<field>/<value>/`, and `answer_by_<field>.md`, one screen of how the answer moves
//! with the value. A run whose point leaves the field at its default is grouped by the value
//! it used, as its report echoes it.

use super::answer::{answer_files, Answer, Ask, Headline};
use super::names::{file_stem, Figure};
use crate::error::{Error, Result};
use serde_json::Value;
use std::fmt::Write as _;

/// The parameters an answer cannot be grouped by: the path and the knobs are what each
/// answer compares.
pub(super) const NOT_BY: [&str; 3] = ["path", "k", "tess"];

/// The answers by value: every value's files, and the table.
pub(super) struct ByAnswer {
    /// Each value's answer files under `by_<field>/<value>/`, then `answer_by_<field>.md`.
    pub(super) files: Vec<Figure>,
    /// The name of the table's file.
    pub(super) table_file: String,
    /// The table, as the file holds it.
    pub(super) table: String,
}

/// The table's file name for `field`.
pub(super) fn table_file(field: &str) -> String {
    format!("answer_by_{}.md", file_stem(field))
}

/// Refuses a `by` field (`--by` or the spec's `by`, named `flag` in `file`) that the spec
/// does not sweep (one value over every point, a point that leaves it unset counting as one
/// value), that is a knob or the path, or where the spec has no area budget.
pub(super) fn check_by(spec: &super::spec::Spec, file: &str, flag: &str, by: &str) -> Result<()> {
    let why = if NOT_BY.contains(&by) {
        Some("each answer compares the paths across their knobs (path, k, tess); group by another field".to_string())
    } else if spec.area_budget_mm2.is_none() {
        Some("an answer needs the spec's `area_budget_mm2`".to_string())
    } else if spec
        .points
        .iter()
        .map(|p| p.params.get(by).map(Value::to_string))
        .collect::<std::collections::BTreeSet<_>>()
        .len()
        < 2
    {
        let mut swept: Vec<&str> = spec
            .points
            .iter()
            .flat_map(|p| p.params.keys().map(String::as_str))
            .filter(|n| !NOT_BY.contains(n) && *n != super::names::SENSITIVITY)
            .collect();
        swept.sort_unstable();
        swept.dedup();
        Some(format!(
            "the spec does not sweep it (it takes one value in every run); the spec sweeps {}",
            if swept.is_empty() {
                "nothing but the path and the knobs".to_string()
            } else {
                swept.join(", ")
            }
        ))
    } else {
        None
    };
    match why {
        Some(why) => Err(Error::invalid(file, flag, by, why)),
        None => Ok(()),
    }
}

/// The answer of each value of `field` over `records`, and how it moves; an internal error
/// when no record carries the field ([`check_by`] refuses such a field before any run).
pub(super) fn by_files(records: &[Value], ask: &Ask, field: &str) -> Result<ByAnswer> {
    let mut groups: Vec<(Value, Vec<Value>)> = Vec::new();
    for r in records {
        let value = r["params"]
            .get(field)
            .or_else(|| crate::plot::used(&r["report"], field))
            .cloned()
            .unwrap_or(Value::Null);
        match groups.iter_mut().find(|(v, _)| *v == value) {
            Some((_, group)) => group.push(r.clone()),
            None => groups.push((value, vec![r.clone()])),
        }
    }
    if groups.iter().all(|(v, _)| v.is_null()) {
        return Err(Error::Internal(format!(
            "no run of the sweep sets `{field}`"
        )));
    }
    groups.sort_by(|(a, _), (b, _)| match (a.as_f64(), b.as_f64()) {
        (Some(x), Some(y)) => x.total_cmp(&y),
        _ => show(a).cmp(&show(b)),
    });
    let stem = file_stem(field);
    let mut files = Vec::new();
    let mut answers: Vec<(String, Option<Vec<Headline>>)> = Vec::new();
    for (value, group) in &groups {
        let shown = show(value);
        let answer = answer_files(group, ask)?;
        let folder = format!("by_{stem}/{}", file_stem(&shown));
        if let Some(Answer {
            files: theirs,
            headlines,
        }) = answer
        {
            files.extend(
                theirs
                    .into_iter()
                    .map(|(name, bytes)| (format!("{folder}/{name}"), bytes)),
            );
            answers.push((shown, Some(headlines)));
        } else {
            answers.push((shown, None));
        }
    }
    let table = table(field, &stem, ask.budget_mm2, &answers);
    let table_file = table_file(field);
    files.push((table_file.clone(), table.clone().into_bytes()));
    Ok(ByAnswer {
        files,
        table_file,
        table,
    })
}

/// A value as a cell and a folder name: a string bare, null as `default`.
fn show(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        Value::Null => "default".to_string(),
        other => other.to_string(),
    }
}

/// `answer_by_<field>.md`: at equal area and at each PSNR target, a row a value and scene.
fn table(
    field: &str,
    stem: &str,
    budget: f64,
    answers: &[(String, Option<Vec<Headline>>)],
) -> String {
    let mut page = format!(
        "# How the answer moves with {field}\n\n\
         One answer for each value of `{field}`, made from only the runs at that value \
         (within the area budget of {budget} mm², as answer.md): each is \
         `by_{stem}/<value>/answer.md`, with its figures beside it. A ratio is the \
         triangle path's cycles over the lembo path's (above 1: lembos faster).\n\n\
         ## At equal area\n\nEach path's most accurate run within the budget (PSNR; ties: \
         the fastest). The two runs' accuracy differs: where the verdict names no winner, \
         their cycle ratio is not a speed-up (the equal-PSNR table below is).\n\n\
         | {field} | scene | lembo | triangle | triangle/lembo cycles | verdict |\n\
         |---|---|---|---|---|---|\n"
    );
    let run = |(index, cycles, psnr): (usize, u64, f64)| {
        format!("run {index}: {cycles} cycles, {psnr:.1} dB")
    };
    for (value, headlines) in answers {
        let Some(headlines) = headlines else {
            let _ = writeln!(
                page,
                "| {value} | every scene | no run of both paths within the budget | | | |"
            );
            continue;
        };
        for h in headlines {
            match h.area {
                Some([l, t]) => {
                    let _ = writeln!(
                        page,
                        "| {value} | {} | {} | {} | {:.2}x | {} |",
                        h.scene,
                        run(l),
                        run(t),
                        t.1 as f64 / l.1.max(1) as f64,
                        h.verdict
                    );
                }
                None => {
                    let _ = writeln!(page, "| {value} | {} | {} | | | |", h.scene, h.verdict);
                }
            }
        }
    }
    page += &format!(
        "\n## At equal PSNR\n\nAt each target, the triangle path's fewest cycles over the \
             lembo path's, each path's cheapest run within the budget that reaches it (`-`: \
             one path reaches no run there). The targets are the spec's, or three levels from \
             each value's own runs.\n\n\
             | {field} | scene | speed-up at each PSNR target |\n|---|---|---|\n"
    );
    for (value, headlines) in answers {
        for h in headlines.iter().flatten() {
            let cells: Vec<String> = h
                .psnr
                .iter()
                .map(|(target, speedup)| match speedup {
                    Some(x) => format!("{target:.1} dB: {x:.2}x"),
                    None => format!("{target:.1} dB: -"),
                })
                .collect();
            let _ = writeln!(page, "| {value} | {} | {} |", h.scene, cells.join(", "));
        }
    }
    page
}
