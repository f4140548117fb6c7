//! A sweep directory's files: `spec.json` and a partial `results.jsonl` read back to
//! resume (each record checked against the spec and shard), and the finished set written
//! at once: `results.jsonl` in index order, `results.csv` and the plots.

use super::spec::{Shard, Spec};
use crate::error::{Error, Result};
use crate::graph::KINDS;
use crate::output::write_files;
use crate::plot::{plot_files, used};
use crate::report::html::{self, REPORT_HTML};
use serde::Deserialize;
use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The records file of a sweep directory.
pub const RESULTS_JSONL: &str = "results.jsonl";

/// The table of a sweep directory.
pub const RESULTS_CSV: &str = "results.csv";

/// The copy of the spec in a sweep directory.
pub const SPEC_JSON: &str = "spec.json";
/// The lembo path against the triangle path within the spec's area budget
/// (DESIGN.md §7, "The answer"); written when the spec has an `area_budget_mm2`.
pub const ANSWER_MD: &str = "answer.md";

/// A directory that holds results must hold this spec's.
pub(super) fn check_same_spec(dir: &Path, spec: &Spec) -> Result<()> {
    let path = dir.join(SPEC_JSON);
    let text = match std::fs::read_to_string(&path) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            if dir.join(RESULTS_JSONL).exists() {
                return Err(Error::invalid(
                    dir.display().to_string(),
                    SPEC_JSON,
                    "missing",
                    "the directory holds results.jsonl but no spec.json, so its runs cannot be matched to this spec; use another --out",
                ));
            }
            return Ok(());
        }
        Err(source) => return Err(Error::Read { path, source }),
    };
    let file = path.display().to_string();
    let theirs: Value = serde_json::from_str(&text).map_err(|e| Error::Parse {
        file: file.clone(),
        field: String::new(),
        message: e.to_string(),
    })?;
    if theirs != spec.value {
        return Err(spec_difference(&file, &theirs, &spec.value, &spec.file));
    }
    Ok(())
}

/// Names the first top-level field where two specs differ.
pub(super) fn spec_difference(file: &str, theirs: &Value, ours: &Value, our_file: &str) -> Error {
    let empty = serde_json::Map::new();
    let (a, b) = (
        theirs.as_object().unwrap_or(&empty),
        ours.as_object().unwrap_or(&empty),
    );
    let field = a
        .keys()
        .chain(b.keys())
        .find(|k| a.get(*k) != b.get(*k))
        .cloned()
        .unwrap_or_default();
    Error::invalid(
        file,
        &field,
        a.get(&field).unwrap_or(&Value::Null),
        format!(
            "differs from {our_file}'s ({}): these are results of another spec; use another --out",
            b.get(&field).unwrap_or(&Value::Null)
        ),
    )
}

/// Records of refinement runs read back before their round expanded them: by index,
/// their key and line.
pub(super) type Unplaced = BTreeMap<usize, (String, String)>;

/// The records already in `results.jsonl`, by index, and whether a truncated or
/// unreadable last line was dropped. Each must be a run of this spec and shard; with a
/// `refine` spec, the records beyond the spec's own runs are refinement runs, returned
/// apart until their round adds them ([`place`]).
pub(super) fn read_partial(
    path: &Path,
    spec: &Spec,
    shard: Shard,
) -> Result<(BTreeMap<usize, String>, bool, Unplaced)> {
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Ok((BTreeMap::new(), false, Unplaced::new()))
        }
        Err(source) => {
            return Err(Error::Read {
                path: path.to_path_buf(),
                source,
            })
        }
    };
    let file = path.display().to_string();
    let mut lines = BTreeMap::new();
    let mut unplaced = Unplaced::new();
    let mut dropped = false;
    let all: Vec<&str> = text.split_inclusive('\n').collect();
    for (n, raw) in all.iter().enumerate() {
        let last = n + 1 == all.len();
        let line = raw.strip_suffix('\n');
        let parsed = line.and_then(|l| record_id(l).ok());
        let Some((index, key)) = parsed else {
            if last {
                // A kill mid-write leaves a partial last line: the run is redone.
                dropped = true;
                continue;
            }
            let message = match line {
                Some(l) => record_id(l).err().unwrap_or_default(),
                None => "no newline".into(),
            };
            return Err(Error::Parse {
                file,
                field: format!("line {}", n + 1),
                message,
            });
        };
        let line = line.expect("parsed");
        if spec.refine.is_some() && index >= spec.runs.len() {
            if unplaced
                .insert(index, (key.clone(), line.to_string()))
                .is_some()
            {
                return Err(Error::invalid(
                    file,
                    format!("line {}", n + 1),
                    index,
                    "a second record of the same run",
                ));
            }
            continue;
        }
        check_record(&file, n, index, &key, spec, shard)?;
        if lines.insert(index, line.to_string()).is_some() {
            return Err(Error::invalid(
                file,
                format!("line {}", n + 1),
                index,
                "a second record of the same run",
            ));
        }
    }
    Ok((lines, dropped, unplaced))
}

/// Moves the set-aside records of `new` refinement runs into `lines`; a record whose key is
/// not its run's is refused (the folder holds another sweep's refinement).
pub(super) fn place(
    path: &Path,
    spec: &Spec,
    new: &[usize],
    unplaced: &mut Unplaced,
    lines: &mut BTreeMap<usize, String>,
) -> Result<()> {
    for &index in new {
        let Some((key, line)) = unplaced.remove(&index) else {
            continue;
        };
        let expected = &spec.runs[index].key;
        if *expected != key {
            return Err(Error::invalid(
                path.display().to_string(),
                format!("run {index}"),
                key,
                format!(
                    "is not refinement run {index} of {} (whose key is {expected}): the records are another sweep's; use another --out",
                    spec.file
                ),
            ));
        }
        lines.insert(index, line);
    }
    Ok(())
}

/// Refuses records of refinement runs that no round asked for.
pub(super) fn check_all_placed(path: &Path, unplaced: &Unplaced) -> Result<()> {
    match unplaced.iter().next() {
        None => Ok(()),
        Some((index, (key, _))) => Err(Error::invalid(
            path.display().to_string(),
            format!("run {index}"),
            key,
            "a refinement run this spec's rounds do not ask for: the records are another sweep's; use another --out",
        )),
    }
}

/// A record's index and key.
pub(super) fn record_id(line: &str) -> std::result::Result<(usize, String), String> {
    #[derive(Deserialize)]
    struct Id {
        index: usize,
        key: String,
    }
    serde_json::from_str::<Id>(line)
        .map(|id| (id.index, id.key))
        .map_err(|e| e.to_string())
}

/// A record read back must be run `index` of this spec, in this shard.
pub(super) fn check_record(
    file: &str,
    n: usize,
    index: usize,
    key: &str,
    spec: &Spec,
    shard: Shard,
) -> Result<()> {
    let expected = spec.runs.get(index).map(|r| r.key.as_str());
    let reason = if expected != Some(key) {
        format!(
            "is not run {index} of {} (whose key is {}): the records are another spec's",
            spec.file,
            expected.unwrap_or("absent")
        )
    } else if !shard.keeps(index) {
        format!(
            "run {index} is not in shard {}/{}: the records are another shard's; use another --out",
            shard.index, shard.count
        )
    } else {
        return Ok(());
    };
    Err(Error::invalid(file, format!("line {}", n + 1), key, reason))
}

/// What the final write wrote: the files, and the answer's lines for the summary a sweep
/// prints.
pub struct Final {
    /// The files written, by name (relative to the folder).
    pub files: Vec<String>,
    /// The answer's rows in one line a scene (at equal area, and the speed-up at each PSNR
    /// target), and where the answer by value is; empty without an area budget.
    pub answer: Vec<String>,
}

/// Writes the finished directory as one atomic set: results.jsonl in index order,
/// results.csv, spec.json, the plots, the answer (with an area budget; by value of `by`,
/// or the spec's `by`, where given) and report.html.
pub(super) fn write_final(
    dir: &Path,
    spec_text: &[u8],
    lines: &BTreeMap<usize, String>,
    by: Option<&str>,
) -> Result<Final> {
    let records: Vec<Value> = lines
        .values()
        .map(|l| serde_json::from_str(l).expect("every line was parsed or written as JSON"))
        .collect();
    // The plots are drawn first so that the records, the table and the plots are one
    // atomic set.
    // The budget as the spec states it (parsed and checked before any run; sweep-merge
    // reads the shards' spec).
    let spec: Value = serde_json::from_slice(spec_text).unwrap_or(Value::Null);
    let budget = spec.get("area_budget_mm2").and_then(Value::as_f64);
    let by = by.or_else(|| spec.get("by").and_then(Value::as_str));
    let plots = plot_files(&records, budget)?;
    let mut files: Vec<(String, Vec<u8>)> = vec![
        (RESULTS_JSONL.into(), joined(lines)),
        (RESULTS_CSV.into(), csv_bytes(&records)?),
        (SPEC_JSON.into(), spec_text.to_vec()),
    ];
    files.extend(plots);
    let targets = super::curves::Targets::of_spec_text(spec_text);
    let mut answer_lines = Vec::new();
    let mut by_table = None;
    if let Some(budget_mm2) = budget {
        let ask = super::answer::Ask {
            budget_mm2,
            refine: super::bracket::Refine::of_spec_text(spec_text),
            targets: &targets,
            sensitivity: super::sensitivity::Sensitivity::of_spec_text(spec_text),
            by,
        };
        match super::answer::answer_files(&records, &ask)? {
            Some(answer) => {
                answer_lines = answer.headlines.iter().map(summary_line).collect();
                files.extend(answer.files);
            }
            None => answer_lines.push(format!(
                "answer: no scene has runs of both paths within {budget_mm2} mm²"
            )),
        }
        if let Some(field) = by {
            let by = super::by::by_files(&records, &ask, field)?;
            answer_lines.push(format!(
                "answer by {field}: {} (one answer.md per value under by_{}/)",
                by.table_file,
                super::names::file_stem(field)
            ));
            files.extend(by.files);
            by_table = Some((by.table_file, by.table));
        }
    }
    let named: Vec<(&str, Vec<u8>)> = files
        .iter()
        .map(|(name, bytes)| (name.as_str(), bytes.clone()))
        .collect();
    let page = page(spec_text, records.len(), &named, by_table.as_ref())?;
    files.push((REPORT_HTML.into(), page.into_bytes()));
    let named: Vec<(&str, Vec<u8>)> = files
        .iter()
        .map(|(name, bytes)| (name.as_str(), bytes.clone()))
        .collect();
    write_files(dir, &named)?;
    Ok(Final {
        files: files.into_iter().map(|(name, _)| name).collect(),
        answer: answer_lines,
    })
}

/// One scene's answer on one line: at equal area, and the speed-up at each PSNR target.
fn summary_line(h: &super::answer::Headline) -> String {
    let area = match h.area {
        Some([l, t]) => format!(
            "at equal area lembo run {} ({} cycles, {:.1} dB), triangle run {} ({} cycles, {:.1} dB), triangle/lembo cycles {:.2}; {}",
            l.0,
            l.1,
            l.2,
            t.0,
            t.1,
            t.2,
            t.1 as f64 / l.1.max(1) as f64,
            h.verdict
        ),
        None => h.verdict.clone(),
    };
    let targets: Vec<String> = h
        .psnr
        .iter()
        .map(|(target, x)| match x {
            Some(x) => format!("{target:.1} dB {x:.2}x"),
            None => format!("{target:.1} dB -"),
        })
        .collect();
    if targets.is_empty() {
        format!("{}: {area}", h.scene)
    } else {
        format!(
            "{}: {area}; speed-up at equal PSNR: {}",
            h.scene,
            targets.join(", ")
        )
    }
}

/// The sweep's `report.html`: what was swept, every plot, and results.csv as a table.
fn page(
    spec_text: &[u8],
    runs: usize,
    files: &[(&str, Vec<u8>)],
    by: Option<&(String, String)>,
) -> Result<String> {
    let spec: Value = serde_json::from_slice(spec_text).unwrap_or(Value::Null);
    let name = spec["name"].as_str().unwrap_or("sweep");
    // The folder's own plots; each value's answer figures stay with its answer.md.
    let plots: String = files
        .iter()
        .filter(|(file, _)| file.ends_with(".svg") && !file.contains('/'))
        .map(|(file, _)| html::figure(file, file, true))
        .collect();
    let csv = files
        .iter()
        .find(|(file, _)| *file == RESULTS_CSV)
        .map(|(_, bytes)| bytes.as_slice())
        .unwrap_or_default();
    let mut reader = csv::ReaderBuilder::new().from_reader(csv);
    let csv_err = |e: csv::Error| Error::Internal(format!("results.csv: {e}"));
    let head: Vec<String> = reader
        .headers()
        .map_err(csv_err)?
        .iter()
        .map(str::to_string)
        .collect();
    let rows = reader
        .records()
        .map(|r| r.map(|r| r.iter().map(str::to_string).collect::<Vec<_>>()))
        .collect::<std::result::Result<Vec<_>, _>>()
        .map_err(csv_err)?;
    let head: Vec<&str> = head.iter().map(String::as_str).collect();
    // The answer first, where the spec has an area budget: its text as written, and its
    // figures among the plots below.
    let answer = files
        .iter()
        .find(|(file, _)| *file == ANSWER_MD)
        .map(|(_, bytes)| {
            html::section(
                "Answer",
                &(format!(
                    "<p><a href=\"{}\">{ANSWER_MD}</a> as written (its figures, speedup_*.svg \
                     and tornado_*.svg, are among the plots below).</p>\n",
                    html::href(ANSWER_MD)
                ) + &format!(
                    "<pre>{}</pre>\n",
                    html::escape(&String::from_utf8_lossy(bytes))
                )),
            )
        })
        .unwrap_or_default();
    let by = by
        .map(|(file, table)| {
            html::section(
                "Answer by value",
                &(format!(
                    "<p><a href=\"{}\">{}</a> as written: how the answer moves with the field \
                     (each value's answer.md is in the folder it names).</p>\n",
                    html::href(file),
                    html::escape(file)
                ) + &format!("<pre>{}</pre>\n", html::escape(table))),
            )
        })
        .unwrap_or_default();
    let body = answer
        + &by
        + &html::section(
        "Plots",
        &if plots.is_empty() {
            html::para("No parameter varied over more than one value, so there is nothing to plot.")
        } else {
            plots
        },
    ) + &html::section(
        "Results",
        &(html::para(&format!(
            "One row per run, as {RESULTS_CSV} holds it (results.jsonl has each run's whole report; \
             the columns are explained in sim/sweeps/README.md)."
        )) + &html::table(&head, &rows)),
    ) + &html::section(
        "Spec",
        &format!(
            "<pre>{}</pre>\n",
            html::escape(&String::from_utf8_lossy(spec_text))
        ),
    );
    Ok(html::page(
        &format!("lembo-sim sweep: {name}"),
        &format!("{runs} runs"),
        &body,
    ))
}

// ---- results.csv ---------------------------------------------------------------------

/// Sort key of a unit name: its kind in dataflow order, then its instance number
/// (`Segmenter[10]` after `Segmenter[9]`).
pub(super) fn unit_order(name: &str) -> (usize, u64, String) {
    let (kind, instance) = match name.split_once('[') {
        Some((k, rest)) => (k, rest.trim_end_matches(']').parse().unwrap_or(0)),
        None => (name, 0),
    };
    let rank = KINDS
        .iter()
        .position(|k| k.name() == kind)
        .unwrap_or(KINDS.len());
    (rank, instance, name.to_string())
}

/// A CSV cell: strings bare, null and absent empty, numbers and booleans as JSON.
pub(super) fn cell(v: Option<&Value>) -> String {
    match v {
        None | Some(Value::Null) => String::new(),
        Some(Value::String(s)) => s.clone(),
        Some(other) => other.to_string(),
    }
}

/// The `memory_system` fields `results.csv` gives as `mem.<field>` when a run used the
/// DRAM memory model.
const MEMORY_COLUMNS: [&str; 11] = [
    "atoms_read",
    "geometry_atoms_read",
    "atoms_written",
    "activations",
    "row_hit_rate",
    "rop_read_latency_mean",
    "colour_cache_hit_rate",
    "depth_cache_hit_rate",
    "colour_compression_ratio",
    "depth_compression_ratio",
    "cleared_tiles",
];

/// `results.csv`: one row per record, columns as `sim/sweeps/README.md` lists them.
pub fn csv_bytes(records: &[Value]) -> Result<Vec<u8>> {
    let mut params = BTreeSet::new();
    let mut units = BTreeSet::new();
    let mut metrics = BTreeSet::new();
    for r in records {
        if let Some(p) = r["params"].as_object() {
            params.extend(p.keys().cloned());
        }
        for u in r["report"]["cycles"]["units"]
            .as_array()
            .into_iter()
            .flatten()
        {
            if let Some(name) = u["name"].as_str() {
                units.insert(unit_order(name));
            }
        }
        if let Some(a) = r["report"]["accuracy"].as_object() {
            metrics.extend(a.keys().cloned());
        }
    }
    let mut header: Vec<String> = vec!["index".into(), "scene".into()];
    header.extend(params.iter().cloned());
    header.extend(["cycles_total", "fps", "bottleneck", "area_mm2", "energy_pj"].map(String::from));
    header.extend(units.iter().map(|(_, _, n)| format!("util.{n}")));
    header.extend(metrics.iter().map(|m| format!("acc.{m}")));
    header.extend(
        [
            "primitives",
            "primitive_bytes",
            "geometry_bytes",
            "fragments",
            "lembo_pieces",
            "blend.error_mean",
            "blend.error_max",
            "wall_seconds",
        ]
        .map(String::from),
    );

    // The DRAM memory model's columns, when any run used it.
    let memory = records
        .iter()
        .any(|r| r["report"]["memory_system"].is_object());
    if memory {
        header.extend(MEMORY_COLUMNS.iter().map(|c| format!("mem.{c}")));
    }

    let mut w = csv::Writer::from_writer(Vec::new());
    let csv_err = |e: csv::Error| Error::Internal(format!("results.csv: {e}"));
    w.write_record(&header).map_err(csv_err)?;
    for r in records {
        let report = &r["report"];
        let cycles = &report["cycles"];
        let mut row = vec![cell(r.get("index")), cell(r.get("scene"))];
        row.extend(
            params
                .iter()
                .map(|p| cell(r["params"].get(p).or_else(|| used(report, p)))),
        );
        row.push(cell(cycles.get("total")));
        row.push(cell(cycles.get("fps")));
        row.push(cell(cycles.get("bottleneck")));
        row.push(cell(report["cost"].get("area_mm2")));
        row.push(cell(report["cost"].get("energy_pj")));
        let total = cycles["total"].as_u64();
        let busy: BTreeMap<&str, u64> = cycles["units"]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(|u| Some((u["name"].as_str()?, u["busy"].as_u64()?)))
            .collect();
        for (_, _, name) in &units {
            row.push(match (busy.get(name.as_str()), total) {
                (Some(&b), Some(t)) if t > 0 => (b as f64 / t as f64).to_string(),
                _ => String::new(),
            });
        }
        row.extend(metrics.iter().map(|m| cell(report["accuracy"].get(m))));
        row.push(cell(report["primitives"].get("count")));
        row.push(cell(report["primitives"].get("bytes")));
        row.push(cell(report["cost"].get("geometry_bytes")));
        row.push(cell(report["counts"].get("fragments")));
        row.push(cell(report["counts"].get("lembo_pieces")));
        row.push(cell(report["blend"].get("error_mean")));
        row.push(cell(report["blend"].get("error_max")));
        row.push(cell(report["host"].get("wall_seconds")));
        if memory {
            let m = &report["memory_system"];
            row.extend(MEMORY_COLUMNS.iter().map(|c| match *c {
                "cleared_tiles" => cell(m["rops"].get("cleared_tiles")),
                c => cell(m.get(c)),
            }));
        }
        w.write_record(&row).map_err(csv_err)?;
    }
    w.into_inner()
        .map_err(|e| Error::Internal(format!("results.csv: {e}")))
}

/// Lines, each followed by a newline.
pub(super) fn joined(lines: &BTreeMap<usize, String>) -> Vec<u8> {
    let mut out = String::new();
    for line in lines.values() {
        out.push_str(line);
        out.push('\n');
    }
    out.into_bytes()
}
