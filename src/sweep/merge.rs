//! `sweep-merge`: the shards' records unioned into what one unsharded sweep writes.

use super::{
    lock::FolderLock,
    results::{check_record, record_id, spec_difference, write_final, RESULTS_JSONL, SPEC_JSON},
    spec::{Shard, Spec},
};
use crate::error::{read_text_file, Error, Result, COMMAND_LINE};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::PathBuf;

// ---- sweep-merge ---------------------------------------------------------------------

/// A merge request: the shards' directories and where the union goes.
#[derive(Clone, Debug)]
pub struct MergeJob {
    /// Where the union is written (`--out`).
    pub out: PathBuf,
    /// The shards' folders, in the order given (the first holding a run wins).
    pub shards: Vec<PathBuf>,
    /// The swept field to give the answer by value for (`--by`); None for the spec's `by`.
    pub by: Option<String>,
}

/// A finished merge, for its summary.
#[derive(Debug)]
pub struct MergeOutput {
    /// The folder written.
    pub dir: PathBuf,
    /// The spec's name.
    pub name: String,
    /// Runs of the spec, all merged.
    pub runs: usize,
    /// The files written, by name.
    pub files: Vec<String>,
    /// The answer's rows, one line a scene (empty without an area budget).
    pub answer: Vec<String>,
}

/// Unions the shards' records into what an unsharded sweep writes. The shards must hold
/// the same spec; a run found in two shards must have the same record but for host timing
/// (`report.host`); every run of the spec must be found.
pub fn run_merge(job: &MergeJob) -> Result<MergeOutput> {
    if job.shards.is_empty() {
        return Err(Error::invalid(
            COMMAND_LINE,
            "SHARD_DIR",
            "none",
            "name at least one shard directory",
        ));
    }
    crate::output::check_out_dir("--out", &job.out)?;
    let mut spec: Option<(Spec, Vec<u8>)> = None;
    let mut lines: BTreeMap<usize, (String, Value, String)> = BTreeMap::new();
    for shard in &job.shards {
        FolderLock::check_free(shard, "SHARD_DIR")?;
        let spec_path = shard.join(SPEC_JSON);
        let text = read_text_file(&spec_path)?;
        let this = Spec::parse(&text, &spec_path.display().to_string())?;
        match &spec {
            None => spec = Some((this, text.into_bytes())),
            Some((first, _)) if first.value != this.value => {
                return Err(spec_difference(
                    &this.file,
                    &this.value,
                    &first.value,
                    &first.file,
                ))
            }
            Some(_) => {}
        }
        let (spec, _) = spec.as_ref().expect("set above");

        let path = shard.join(RESULTS_JSONL);
        let file = path.display().to_string();
        let text = std::fs::read_to_string(&path).map_err(|source| Error::Read {
            path: path.clone(),
            source,
        })?;
        for (n, raw) in text.split_inclusive('\n').enumerate() {
            let field = format!("line {}", n + 1);
            let Some(line) = raw.strip_suffix('\n') else {
                return Err(Error::Parse {
                    file,
                    field,
                    message: "no newline: the shard did not finish; run it again".into(),
                });
            };
            let (index, key) = record_id(line).map_err(|message| Error::Parse {
                file: file.clone(),
                field: field.clone(),
                message,
            })?;
            check_record(&file, n, index, &key, spec, Shard::ALL)?;
            let mut masked: Value = serde_json::from_str(line).expect("parsed above");
            if let Some(report) = masked.get_mut("report").and_then(Value::as_object_mut) {
                report.remove("host");
            }
            match lines.get(&index) {
                Some((_, other, from)) if *other != masked => {
                    return Err(Error::invalid(
                        file,
                        field,
                        key,
                        format!(
                            "differs from the record of the same run in {from} beyond host timing"
                        ),
                    ))
                }
                Some(_) => {}
                None => {
                    lines.insert(index, (line.to_string(), masked, file.clone()));
                }
            }
        }
    }
    let (spec, spec_bytes) = spec.expect("at least one shard");
    if let Some(by) = &job.by {
        super::by::check_by(&spec, COMMAND_LINE, "--by", by)?;
    }
    check_every_run(&spec, |i| lines.contains_key(&i))?;
    let lines: BTreeMap<usize, String> = lines.into_iter().map(|(i, (l, _, _))| (i, l)).collect();
    let _lock = FolderLock::acquire(&job.out, "sweep-merge", "--out")?;
    let written = write_final(&job.out, &spec_bytes, &lines, job.by.as_deref())?;
    Ok(MergeOutput {
        dir: job.out.clone(),
        name: spec.name,
        runs: spec.runs.len(),
        files: written.files,
        answer: written.answer,
    })
}

/// Refuses a merge that misses a run of `spec`, naming the first missing ones.
fn check_every_run(spec: &Spec, merged: impl Fn(usize) -> bool) -> Result<()> {
    let missing: Vec<usize> = (0..spec.runs.len()).filter(|&i| !merged(i)).collect();
    if !missing.is_empty() {
        let shown: Vec<String> = missing.iter().take(8).map(|i| i.to_string()).collect();
        return Err(Error::invalid(
            COMMAND_LINE,
            "SHARD_DIR",
            format!(
                "runs {}{}",
                shown.join(", "),
                if missing.len() > 8 { ", ..." } else { "" }
            ),
            format!(
                "{} of the spec's {} runs are in no shard: did every shard finish?",
                missing.len(),
                spec.runs.len()
            ),
        ));
    }
    Ok(())
}
