//! Running a sweep: the rayon pool of `--jobs` workers, one reference per scene and sample
//! count, each
//! finished run appended to `results.jsonl` at once, resumption by key, the progress bar.

use super::{
    bracket::{next_round, Knob, Limits, Measured, Refine},
    lock::FolderLock,
    plan::{Plan, SweepReference},
    results::{
        check_all_placed, check_same_spec, joined, place, read_partial, write_final, Unplaced,
        RESULTS_JSONL, SPEC_JSON,
    },
    spec::{Run, Shard},
};
use crate::camera::Samples;
use crate::error::{Error, Result, COMMAND_LINE};
use crate::job::{check_count, render_reference, PrimitivePath, MAX_HOST_THREADS};
use crate::output::write_files;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::collections::BTreeMap;
use std::fmt;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

// ---- The request and its outcome -----------------------------------------------------

/// The most threads `--jobs` accepts; each run is one host thread (or `--host-threads`).
pub const MAX_JOBS: usize = 256;

/// A sweep request, from the command line.
#[derive(Clone, Debug)]
pub struct SweepJob {
    /// The spec file.
    pub spec: PathBuf,
    /// Output directory; None for `out/sweeps/<spec name>/`.
    pub out: Option<PathBuf>,
    /// Worker threads; None for the host's available parallelism.
    pub jobs: Option<usize>,
    /// Which runs this process does (`--shard`).
    pub shard: Shard,
    /// Test hook: stop once this many records were appended (see [`SweepOutcome`]).
    pub stop_after: Option<usize>,
    /// Draw a progress bar on stderr (hidden anyway when stderr is not a terminal).
    pub progress: bool,
    /// Host threads of each timed run (`--host-threads`; results do not depend on it).
    pub host_threads: u32,
    /// Run even when the runs at once are estimated to need more memory than is available
    /// (`--no-memory-check`).
    pub no_memory_check: bool,
    /// The swept field to give the answer by value for (`--by`); None for the spec's `by`.
    pub by: Option<String>,
}

/// What a sweep did.
#[derive(Debug)]
pub enum SweepOutcome {
    /// Every run of the shard has a record; the final files are written.
    Done(SweepOutput),
    /// Stopped by `stop_after` with `appended` records added to `results.jsonl`; the
    /// final files are not written.
    Stopped {
        /// The sweep folder.
        dir: PathBuf,
        /// Records appended by this process.
        appended: usize,
    },
}

/// A finished sweep, for its summary.
#[derive(Debug)]
pub struct SweepOutput {
    /// The sweep folder.
    pub dir: PathBuf,
    /// The spec's name.
    pub name: String,
    /// Runs of this shard.
    pub runs: usize,
    /// Runs found done in `results.jsonl` and skipped.
    pub skipped: usize,
    /// Worker threads used.
    pub jobs: usize,
    /// Files written, in the directory.
    pub files: Vec<String>,
    /// The answer's rows, one line a scene, for the summary (empty without an area budget).
    pub answer: Vec<String>,
    /// Wall time of the whole sweep \[s\].
    pub wall_seconds: f64,
}

/// A sweep that failed: the error, and the run it happened in when it was a run's.
#[derive(Debug)]
pub struct SweepError {
    /// Boxed so that results carrying a SweepError stay small.
    pub error: Box<Error>,
    /// `run 7 (key)` when a run failed; None for a refused spec or flag.
    pub run: Option<String>,
}

impl SweepError {
    /// The process's exit status for this failure (2 for bad input).
    pub fn exit_code(&self) -> u8 {
        self.error.exit_code()
    }
}

impl fmt::Display for SweepError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.run {
            Some(run) => write!(f, "{run}: {}", self.error),
            None => write!(f, "{}", self.error),
        }
    }
}

impl From<Error> for SweepError {
    fn from(error: Error) -> SweepError {
        SweepError {
            error: Box::new(error),
            run: None,
        }
    }
}

impl SweepJob {
    /// Checks the flags; errors name the flag and the value.
    pub fn validate(&self) -> Result<()> {
        if let Some(n) = self.jobs {
            check_count("--jobs", n, MAX_JOBS, "threads")?;
        }
        Shard::new(self.shard.index, self.shard.count)?;
        if let Some(dir) = &self.out {
            crate::output::check_out_dir("--out", dir)?;
        }
        check_count(
            "--host-threads",
            self.host_threads,
            MAX_HOST_THREADS,
            "host threads",
        )?;
        Ok(())
    }
}

// ---- Running -------------------------------------------------------------------------

/// Runs a sweep: validates everything, then runs what `results.jsonl` does not hold yet.
pub fn run_sweep(job: &SweepJob) -> std::result::Result<SweepOutcome, SweepError> {
    let t0 = Instant::now();
    job.validate()?;
    let mut plan = Plan::load(&job.spec)?;
    clamp_host_threads(&mut plan, job.host_threads);
    let dir = job
        .out
        .clone()
        .unwrap_or_else(|| Path::new("out").join("sweeps").join(&plan.spec.name));
    let jobs = job.jobs.unwrap_or_else(default_jobs);
    check_request(&plan, job)?;
    let runs = plan.shard_runs(job.shard);
    plan.check_memory(&runs, jobs, job.no_memory_check)?;
    let mut round: Vec<usize> = runs.iter().map(|r| r.index).collect();

    let (_lock, results_path, mut lines, mut unplaced) = open_folder(&dir, &plan, job.shard)?;

    let pool = thread_pool(jobs)?;
    let bar = progress_bar(job.progress, 0);
    let mut references: Vec<SweepReference> = Vec::new();
    let (mut total, mut skipped, mut appended) = (0, 0, 0);
    // Each record as refinement reads it, by run index.
    let mut parsed: BTreeMap<usize, Option<Measured>> = BTreeMap::new();
    // The spec's runs, then each refinement round's (DESIGN.md §7, "Bracketing").
    loop {
        total += round.len();
        let pending: Vec<&Run> = round
            .iter()
            .map(|&i| &plan.spec.runs[i])
            .filter(|r| !lines.contains_key(&r.index))
            .collect();
        skipped += round.len() - pending.len();
        let left = job.stop_after.map(|n| n.saturating_sub(appended));
        if left == Some(0) && !pending.is_empty() {
            return Ok(SweepOutcome::Stopped { dir, appended });
        }
        bar.inc_length(pending.len() as u64);
        add_references(&plan, &pending, &pool, &bar, &mut references);
        let st = run_pending(
            &plan,
            &pending,
            &references,
            &results_path,
            left,
            &pool,
            jobs,
            &bar,
            &mut lines,
        )?;
        appended += st.appended;
        if let Some(failure) = st.failure {
            bar.finish_and_clear();
            return Err(failure);
        }
        if st.stopped && st.appended < pending.len() {
            bar.finish_and_clear();
            return Ok(SweepOutcome::Stopped { dir, appended });
        }
        let Some(refine) = plan.spec.refine else {
            break;
        };
        let additions = refinement_round(&plan, refine, &lines, &mut parsed);
        round = plan.extend(&additions)?;
        if round.is_empty() {
            break;
        }
        clamp_host_threads(&mut plan, job.host_threads);
        place(&results_path, &plan.spec, &round, &mut unplaced, &mut lines)?;
        let new: Vec<&Run> = round.iter().map(|&i| &plan.spec.runs[i]).collect();
        plan.check_memory(&new, jobs, job.no_memory_check)?;
    }
    bar.finish_and_clear();
    check_all_placed(&results_path, &unplaced)?;
    let spec = &plan.spec;

    let written = write_final(&dir, spec.text.as_bytes(), &lines, job.by.as_deref())?;
    Ok(SweepOutcome::Done(SweepOutput {
        dir,
        name: spec.name.clone(),
        runs: total,
        skipped,
        jobs,
        files: written.files,
        answer: written.answer,
        wall_seconds: t0.elapsed().as_secs_f64(),
    }))
}

/// The runs at once when `--jobs` is not given: the host's parallelism, at most
/// [`MAX_JOBS`].
fn default_jobs() -> usize {
    std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1)
        .min(MAX_JOBS)
}

/// Takes the output folder `dir` for this sweep and reads what it holds: the folder's lock
/// (one writer per folder: a second sweep on it is refused before it reads anything),
/// the path of `results.jsonl`, its records by run index and those refinement rounds have
/// not placed yet. The spec is written beside them, and `results.jsonl` rewritten when a
/// torn last line was dropped or it did not exist.
fn open_folder(
    dir: &Path,
    plan: &Plan,
    shard: Shard,
) -> Result<(FolderLock, PathBuf, BTreeMap<usize, String>, Unplaced)> {
    let lock = FolderLock::acquire(dir, "sweep", "--out")?;
    let results_path = dir.join(RESULTS_JSONL);
    check_same_spec(dir, &plan.spec)?;
    let (lines, dropped, unplaced) = read_partial(&results_path, &plan.spec, shard)?;
    write_files(dir, &[(SPEC_JSON, plan.spec.text.clone().into_bytes())])?;
    if dropped || !results_path.exists() {
        write_files(dir, &[(RESULTS_JSONL, joined(&lines))])?;
    }
    Ok((lock, results_path, lines, unplaced))
}

/// The pool of `jobs` threads the sweep's runs share (`sweep-0`, `sweep-1`, ...).
fn thread_pool(jobs: usize) -> Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .thread_name(|i| format!("sweep-{i}"))
        .build()
        .map_err(|e| Error::Internal(format!("cannot start the sweep's threads: {e}")))
}

/// The flags checked against the spec: `--shard` of a spec with `refine`, a `--by` field
/// it does not sweep.
fn check_request(plan: &Plan, job: &SweepJob) -> Result<()> {
    if plan.spec.refine.is_some() && job.shard != Shard::ALL {
        return Err(Error::invalid(
            COMMAND_LINE,
            "--shard",
            format!("{}/{}", job.shard.index, job.shard.count),
            format!(
                "{} has `refine`: its refinement rounds follow the results of every earlier run, so it runs in one process",
                plan.spec.file
            ),
        )
        );
    }
    if let Some(by) = &job.by {
        super::by::check_by(&plan.spec, COMMAND_LINE, "--by", by)?;
    }
    Ok(())
}

/// The next refinement round's additions (DESIGN.md §7, "Bracketing") from the records
/// so far; `parsed` keeps each record as refinement reads it, by run index, so that each
/// is parsed once over the rounds (a round adds a few runs to thousands).
fn refinement_round(
    plan: &Plan,
    refine: Refine,
    lines: &BTreeMap<usize, String>,
    parsed: &mut BTreeMap<usize, Option<Measured>>,
) -> Vec<(usize, Knob)> {
    for (index, l) in lines {
        parsed.entry(*index).or_insert_with(|| {
            serde_json::from_str::<serde_json::Value>(l)
                .ok()
                .and_then(|r| Measured::of(&r))
        });
    }
    let measured: Vec<Measured> = parsed.values().flatten().cloned().collect();
    let triangle_ok = |scene: &str, n: u32| plan.triangle_ok(scene, n);
    next_round(
        &measured,
        &Limits {
            refine: Some(refine),
            budget: plan.spec.area_budget_mm2,
            triangle_ok: &triangle_ok,
            by: plan.spec.by.as_deref(),
        },
    )
}

/// At most as many host threads per run as the run has units (points may differ in unit
/// counts).
fn clamp_host_threads(plan: &mut Plan, host_threads: u32) {
    for (run, rj) in plan.spec.runs.iter().zip(plan.jobs.iter_mut()) {
        if let Some(arch) = &plan.archs[run.point] {
            // Its primitives, which no viewport changes.
            let scene = &plan.scenes[run.scene];
            let path = if rj.path == PrimitivePath::Triangle
                || (scene.discoid_count() > 0 && scene.lembo_count() == 0)
            {
                PrimitivePath::Triangle
            } else {
                PrimitivePath::Lembo
            };
            let units = arch.instances(path).len().max(1);
            rj.host_threads = host_threads.min(units as u32);
        }
    }
}

/// Adds to `references` the exact reference of each scene and sample count that a
/// pending run measures against and that is not there yet, each computed before the runs
/// that need it (each is itself parallel over rows on the pool).
fn add_references(
    plan: &Plan,
    pending: &[&Run],
    pool: &rayon::ThreadPool,
    bar: &ProgressBar,
    references: &mut Vec<SweepReference>,
) {
    for f in 0..plan.frames.len() {
        let scene = plan.frame_scene(f);
        // Each sample count's reference, as its runs' jobs ask for it.
        let samples: BTreeMap<Samples, u32> = pending
            .iter()
            .filter(|r| plan.frame_of[r.index] == f)
            .map(|r| &plan.jobs[r.index])
            .filter(|j| j.reference)
            .map(|j| (j.samples, j.reference_supersample()))
            .collect();
        for (n, supersample) in samples {
            if references.iter().any(|r| (r.frame, r.samples) == (f, n)) {
                continue;
            }
            let v = scene.viewport;
            bar.set_message(format!(
                "reference of {} at {}x{}",
                scene.name, v.width, v.height
            ));
            // The plan measures a discoid scene only where it says what surface it stands for.
            let surface = crate::job::reference_scene(scene).expect("checked by the plan");
            let (mut image, wall) = pool.install(|| {
                render_reference(surface.as_ref(), &plan.frames[f].view, supersample, n)
            });
            if SweepReference::area_averaged(n, supersample) {
                image = image.with_area_colours();
            }
            references.push(SweepReference {
                frame: f,
                samples: n,
                image,
                wall,
            });
        }
    }
    bar.set_message("");
}

/// What the workers share, under one lock.
struct Progress<'a> {
    file: std::fs::File,
    lines: &'a mut BTreeMap<usize, String>,
    appended: usize,
    failure: Option<SweepError>,
    stopped: bool,
}

/// Runs `pending` on `jobs` workers of `pool`, appending each finished run's record to
/// `results_path` and to `lines`; stops at the first failure or after `stop_after` records.
#[allow(clippy::too_many_arguments)]
fn run_pending<'a>(
    plan: &Plan,
    pending: &[&Run],
    references: &[SweepReference],
    results_path: &Path,
    stop_after: Option<usize>,
    pool: &rayon::ThreadPool,
    jobs: usize,
    bar: &ProgressBar,
    lines: &'a mut BTreeMap<usize, String>,
) -> Result<Progress<'a>> {
    let file = std::fs::OpenOptions::new()
        .append(true)
        .open(results_path)
        .map_err(|source| Error::Write {
            path: results_path.to_path_buf(),
            source,
        })?;
    let state = Mutex::new(Progress {
        file,
        lines,
        appended: 0,
        failure: None,
        stopped: false,
    });
    let stop = AtomicBool::new(false);
    let next = AtomicUsize::new(0);
    // Workers take runs in index order; a finished run is appended under the lock, so
    // records are whole lines and a stop leaves exactly `stop_after` of them.
    let worker = || loop {
        if stop.load(Ordering::Relaxed) {
            return;
        }
        let Some(&run) = pending.get(next.fetch_add(1, Ordering::Relaxed)) else {
            return;
        };
        let result = plan.run(run, references);
        let mut guard = state.lock().expect("no worker panics holding the lock");
        let st = &mut *guard;
        // After a stop no record is added (the hook promises exactly `stop_after`); after
        // a failure the runs in flight are still recorded, so a rerun need not redo them.
        if st.stopped {
            return;
        }
        let line = match result {
            Ok(line) => line,
            Err(_) if st.failure.is_some() => return,
            Err(error) => {
                st.failure = Some(SweepError {
                    error: Box::new(error),
                    run: Some(format!("run {} ({})", run.index, run.key)),
                });
                stop.store(true, Ordering::Relaxed);
                return;
            }
        };
        let written = st
            .file
            .write_all(format!("{line}\n").as_bytes())
            .and_then(|()| st.file.flush());
        if let Err(source) = written {
            st.failure.get_or_insert_with(|| {
                Error::Write {
                    path: results_path.to_path_buf(),
                    source,
                }
                .into()
            });
            stop.store(true, Ordering::Relaxed);
            return;
        }
        st.lines.insert(run.index, line);
        st.appended += 1;
        bar.inc(1);
        if stop_after == Some(st.appended) {
            st.stopped = true;
            stop.store(true, Ordering::Relaxed);
        }
    };
    pool.scope(|s| {
        for _ in 0..jobs {
            s.spawn(|_| worker());
        }
    });
    pool.scope(|s| {
        for _ in 0..jobs {
            s.spawn(|_| worker());
        }
    });
    Ok(state.into_inner().expect("no worker panicked"))
}

pub(super) fn progress_bar(show: bool, len: usize) -> ProgressBar {
    let target = if show {
        ProgressDrawTarget::stderr()
    } else {
        ProgressDrawTarget::hidden()
    };
    let bar = ProgressBar::with_draw_target(Some(len as u64), target);
    bar.set_style(
        ProgressStyle::with_template(
            "{elapsed_precise} [{wide_bar}] {pos}/{len} runs, ETA {eta_precise} {msg}",
        )
        .expect("the template is valid")
        .progress_chars("=> "),
    );
    if show {
        // The clock and ETA move while a long run or a reference is computed.
        bar.enable_steady_tick(std::time::Duration::from_millis(500));
    }
    bar
}
