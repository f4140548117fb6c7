//! Output files that appear whole or not at all (DESIGN.md §8: a failed run "leaves no partial
//! output file").
//!
//! A write ([`write_files`], [`write_paths`]) has three steps:
//!
//! 1. the missing directories are created, and the temporaries that dead processes left in
//!    them are removed (a temporary is stale when `/proc/<pid>` is gone; on a system without
//!    `/proc` none is judged stale and they are kept);
//! 2. every file is written to a hidden temporary beside its target, `.{name}.{pid}.tmp`;
//! 3. the temporaries are renamed onto their targets, in the order given, holding this
//!    process's commit lock and an advisory lock (`flock`) on each target directory.
//!
//! What an interruption leaves:
//!
//! - **An error in step 1 or 2** (a directory that cannot be created, a full disk): the
//!   temporaries and the directories this write created are removed; earlier outputs are
//!   untouched.
//! - **SIGINT, SIGTERM, SIGHUP** (once [`remove_temporaries_on_signals`] is installed): the
//!   handler takes the commit lock, so it runs before step 3 or after it, never during; it
//!   removes this process's temporaries and the (empty) directories its writes created, and
//!   exits with status 128 + the signal's number (130 for Ctrl-C, 143 for SIGTERM).
//! - **SIGKILL or a crash in step 1 or 2**: the dead process's hidden temporaries remain
//!   until the next write into that directory removes them; no target is touched.
//! - **SIGKILL or power loss in step 3**, a window of a few `rename` calls after all the
//!   data is written: the targets renamed so far hold the new files and the rest the
//!   previous run's. Each file is whole. The window is not closed: that would need the
//!   directory itself swapped, and an output directory may hold other files (a sweep's
//!   `results.jsonl`, the user's own). An I/O error in a rename leaves the same mix and is
//!   reported.
//! - **Two processes writing one directory**: their temporaries have different names and
//!   their commits are serialised by the directory lock, so the later commit's files win
//!   together (a name only the earlier one wrote stays beside them).
//!
//! Nothing is fsynced: a killed process loses nothing the kernel already has, and
//! durability across a power loss is not attempted.
//!
//! Test hook, in builds with the `testkit` feature only (the tests' builds, not the shipped
//! binary: Cargo.toml): with the environment variable `LEMBO_HOLD_BEFORE_RENAME_SECS=S`
//! every write waits S seconds between steps 2 and 3, so a test can interrupt a run whose
//! temporaries are all written (`tests/integration/atomic.rs`).

use crate::error::{parent_dir, Error, Result, COMMAND_LINE};
use std::fs::File;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

/// The test hook's environment variable: seconds to wait before the renames.
#[cfg(feature = "testkit")]
pub const HOLD_ENV: &str = "LEMBO_HOLD_BEFORE_RENAME_SECS";

/// What this process's writes in progress have put on disk: what a signal must remove.
struct Live {
    temps: Vec<PathBuf>,
    /// Directories created by writes not yet committed, outermost first.
    dirs: Vec<PathBuf>,
    /// Folder locks this process holds (`sweep::FolderLock`), released by a signal too.
    locks: Vec<PathBuf>,
}

/// The commit lock: held while a temporary is created and registered, while the renames
/// run, and by the signal handler until the process exits.
static LIVE: Mutex<Live> = Mutex::new(Live {
    temps: Vec::new(),
    dirs: Vec::new(),
    locks: Vec::new(),
});

/// One write at a time in this process, so two writes of the same name into one directory
/// cannot share a temporary.
static WRITE: Mutex<()> = Mutex::new(());

fn live() -> MutexGuard<'static, Live> {
    // The lists stay consistent whatever panicked while holding the lock.
    LIVE.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// The hidden temporary name of output `name` written by this process.
pub fn temp_name(name: &str) -> String {
    format!(".{name}.{}.tmp", std::process::id())
}

/// The process id in a temporary's file name `.{name}.{pid}.tmp`, if it is one.
fn temp_owner(file_name: &str) -> Option<u32> {
    let rest = file_name.strip_prefix('.')?.strip_suffix(".tmp")?;
    let (name, pid) = rest.rsplit_once('.')?;
    if name.is_empty() || pid.is_empty() || !pid.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    pid.parse().ok()
}

/// Registers a lock file this process holds, so that a signal's exit removes it.
pub fn register_lock(path: &Path) {
    live().locks.push(path.to_path_buf());
}

/// Forgets a lock file this process released.
pub fn unregister_lock(path: &Path) {
    live().locks.retain(|l| l != path);
}

/// Whether process `pid` is alive; None where this cannot be told (no `/proc`).
pub fn pid_alive(pid: u32) -> Option<bool> {
    let proc = Path::new("/proc");
    if !proc.join("self").exists() {
        return None;
    }
    Some(pid == std::process::id() || proc.join(pid.to_string()).exists())
}

/// Removes from `dir` the temporaries of processes that no longer run. Best effort: a
/// temporary that cannot be removed is left for the next write.
fn remove_stale_temporaries(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let is_file = entry.file_type().map(|t| t.is_file()).unwrap_or(false);
        let owner = entry.file_name().to_str().and_then(temp_owner);
        if let (true, Some(pid)) = (is_file, owner) {
            if pid_alive(pid) == Some(false) {
                let _ = std::fs::remove_file(entry.path());
            }
        }
    }
}

/// The file in an output folder that lists the set of files the last run wrote there.
pub const MANIFEST: &str = "manifest.json";

/// Writes a run's set of outputs: `files` into `dir` with [`MANIFEST`] listing them, and
/// `elsewhere` (a trace written where `--trace-out` says), as one atomic set; then removes
/// from `dir` the files of the set this one replaces (the previous manifest's names that
/// this set does not have), so that a folder holds exactly one run's files. Files the
/// manifest never listed (the user's own) are left alone.
pub fn write_set(
    dir: &Path,
    command: &str,
    files: &[(&str, Vec<u8>)],
    elsewhere: &[(PathBuf, &[u8])],
) -> Result<()> {
    let previous = previous_set(dir);
    let names: Vec<&str> = files.iter().map(|(n, _)| *n).chain([MANIFEST]).collect();
    let manifest = serde_json::to_vec_pretty(&serde_json::json!({
        "command": command,
        "files": names,
    }))
    .expect("the manifest serialises");
    let mut paths: Vec<(PathBuf, &[u8])> = files
        .iter()
        .map(|(name, bytes)| (dir.join(name), bytes.as_slice()))
        .collect();
    paths.push((dir.join(MANIFEST), manifest.as_slice()));
    paths.extend(elsewhere.iter().map(|(p, b)| (p.clone(), *b)));
    write_paths(&paths)?;
    // What this set wrote elsewhere may land in `dir` under an old name: never removed.
    let written_here = |name: &str| {
        elsewhere
            .iter()
            .any(|(p, _)| parent_dir(p) == dir && p.file_name() == Some(name.as_ref()))
    };
    for old in previous
        .iter()
        .filter(|o| !names.contains(&o.as_str()) && !written_here(o))
    {
        // Best effort: a file that cannot be removed stays, and the manifest no longer
        // claims it.
        let _ = std::fs::remove_file(dir.join(old));
    }
    Ok(())
}

/// The names the previous run's manifest in `dir` lists: plain file names only (a
/// manifest is not trusted to name anything outside its folder).
fn previous_set(dir: &Path) -> Vec<String> {
    let Ok(text) = std::fs::read_to_string(dir.join(MANIFEST)) else {
        return Vec::new();
    };
    let Ok(value) = serde_json::from_str::<serde_json::Value>(&text) else {
        return Vec::new();
    };
    value["files"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|v| v.as_str())
        .filter(|n| {
            !n.is_empty()
                && *n != "."
                && *n != ".."
                && !n.contains(['/', '\\'])
                && Path::new(n).file_name().is_some()
        })
        .map(str::to_string)
        .collect()
}

/// Refuses an output folder flag (`--out`) naming an existing file (exit 2), before any
/// work.
pub fn check_out_dir(flag: &str, dir: &Path) -> Result<()> {
    if dir.exists() && !dir.is_dir() {
        return Err(Error::invalid(
            COMMAND_LINE,
            flag,
            dir.display(),
            "names an existing file; it must name a folder (created when missing)",
        ));
    }
    Ok(())
}

/// Refuses an output file flag (`--trace-out`) naming an existing folder (exit 2), before
/// any work.
pub fn check_out_file(flag: &str, file: &Path) -> Result<()> {
    if file.is_dir() {
        return Err(Error::invalid(
            COMMAND_LINE,
            flag,
            file.display(),
            "names an existing folder; it must name a file",
        ));
    }
    Ok(())
}

/// Writes every `(name, bytes)` into `dir` as one atomic set (see the module doc).
pub fn write_files(dir: &Path, files: &[(&str, Vec<u8>)]) -> Result<()> {
    let paths: Vec<(PathBuf, &[u8])> = files
        .iter()
        .map(|(name, bytes)| (dir.join(name), bytes.as_slice()))
        .collect();
    write_paths(&paths)
}

/// Writes every `(path, bytes)` as one atomic set (see the module doc); the files may be in
/// different directories.
pub fn write_paths(files: &[(PathBuf, &[u8])]) -> Result<()> {
    let _one_at_a_time = WRITE.lock().unwrap_or_else(|p| p.into_inner());
    let mut targets = Vec::with_capacity(files.len());
    for (path, _) in files {
        let name = path.file_name().ok_or_else(|| Error::Write {
            path: path.clone(),
            source: std::io::Error::new(std::io::ErrorKind::InvalidInput, "names no file"),
        })?;
        let dir = parent_dir(path).to_path_buf();
        targets.push((dir, name.to_string_lossy().into_owned(), path.clone()));
    }
    // A target that is a folder would fail its rename after others were renamed: refused
    // before anything is written.
    if let Some((_, _, path)) = targets.iter().find(|(_, _, p)| p.is_dir()) {
        return Err(Error::Write {
            path: path.clone(),
            source: std::io::Error::new(std::io::ErrorKind::IsADirectory, "is a folder"),
        });
    }
    let mut staged = Staged::default();
    let mut dirs: Vec<PathBuf> = Vec::new();
    for (dir, _, _) in &targets {
        if !dirs.contains(dir) {
            staged.create_dir(dir)?;
            remove_stale_temporaries(dir);
            dirs.push(dir.clone());
        }
    }
    let mut seen = Vec::new();
    for (dir, name, path) in &targets {
        // The same file named twice (`--trace-out out/x/report.json`) would share one
        // temporary; its directories exist now, so they compare by their canonical form.
        let canonical = dir
            .canonicalize()
            .unwrap_or_else(|_| dir.clone())
            .join(name);
        if seen.contains(&canonical) {
            return Err(Error::Write {
                path: path.clone(),
                source: std::io::Error::new(
                    std::io::ErrorKind::InvalidInput,
                    "two outputs of one run have this name",
                ),
            });
        }
        seen.push(canonical);
    }
    for ((dir, name, _), (_, bytes)) in targets.iter().zip(files) {
        staged.write_temp(&dir.join(temp_name(name)), bytes)?;
    }
    #[cfg(feature = "testkit")]
    hold_for_tests();
    staged.commit(&dirs, targets.iter().map(|(_, _, path)| path))
}

/// The test hook: waits [`HOLD_ENV`] seconds (at most an hour) when it is set.
#[cfg(feature = "testkit")]
fn hold_for_tests() {
    let secs = std::env::var(HOLD_ENV)
        .ok()
        .and_then(|v| v.trim().parse::<f64>().ok())
        .filter(|s| s.is_finite() && *s > 0.0);
    if let Some(secs) = secs {
        std::thread::sleep(std::time::Duration::from_secs_f64(secs.min(3600.0)));
    }
}

/// The temporaries and directories of one write; removed when dropped uncommitted.
#[derive(Default)]
struct Staged {
    temps: Vec<PathBuf>,
    dirs: Vec<PathBuf>,
}

impl Staged {
    /// Creates `dir` and its missing ancestors, registering each one created.
    fn create_dir(&mut self, dir: &Path) -> Result<()> {
        let mut missing = Vec::new();
        let mut d = Some(dir);
        while let Some(p) = d.filter(|p| !p.as_os_str().is_empty() && !p.exists()) {
            missing.push(p.to_path_buf());
            d = p.parent();
        }
        for d in missing.into_iter().rev() {
            let mut live = live();
            match std::fs::create_dir(&d) {
                Ok(()) => {
                    live.dirs.push(d.clone());
                    self.dirs.push(d);
                }
                // Created meanwhile by another process: not ours to remove.
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && d.is_dir() => {}
                Err(source) => return Err(Error::Write { path: d, source }),
            }
        }
        if dir.as_os_str().is_empty() || dir.is_dir() {
            return Ok(());
        }
        Err(Error::Write {
            path: dir.to_path_buf(),
            source: std::io::Error::new(
                std::io::ErrorKind::NotADirectory,
                "exists and is not a directory",
            ),
        })
    }

    /// Writes `bytes` to the temporary `tmp`, registered before the file exists on disk.
    fn write_temp(&mut self, tmp: &Path, bytes: &[u8]) -> Result<()> {
        let werr = |source| Error::Write {
            path: tmp.to_path_buf(),
            source,
        };
        let mut file = {
            let mut live = live();
            let file = File::create(tmp).map_err(werr)?;
            live.temps.push(tmp.to_path_buf());
            file
        };
        self.temps.push(tmp.to_path_buf());
        file.write_all(bytes).map_err(werr)
    }

    /// Renames the temporaries onto `targets` (in the order written) under the commit lock
    /// and the directories' locks.
    fn commit<'a>(
        mut self,
        dirs: &[PathBuf],
        targets: impl Iterator<Item = &'a PathBuf>,
    ) -> Result<()> {
        let mut live = live();
        let mut sorted: Vec<&PathBuf> = dirs.iter().collect();
        sorted.sort();
        // Best effort: a file system without flock still gets per-process atomicity.
        let _dir_locks: Vec<File> = sorted
            .into_iter()
            .filter_map(|d| File::open(d).ok())
            .filter(|f| f.lock().is_ok())
            .collect();
        for (tmp, target) in self.temps.iter().zip(targets) {
            if let Err(source) = std::fs::rename(tmp, target) {
                drop(live);
                // Dropping `self` removes the temporaries not yet renamed.
                return Err(Error::Write {
                    path: target.clone(),
                    source,
                });
            }
        }
        unregister(&mut live, &self.temps, &self.dirs);
        self.temps.clear();
        self.dirs.clear();
        Ok(())
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if self.temps.is_empty() && self.dirs.is_empty() {
            return;
        }
        let mut live = live();
        for t in &self.temps {
            let _ = std::fs::remove_file(t);
        }
        // Innermost first; a directory that holds anything now is kept.
        for d in self.dirs.iter().rev() {
            let _ = std::fs::remove_dir(d);
        }
        unregister(&mut live, &self.temps, &self.dirs);
    }
}

fn unregister(live: &mut Live, temps: &[PathBuf], dirs: &[PathBuf]) {
    live.temps.retain(|t| !temps.contains(t));
    live.dirs.retain(|d| !dirs.contains(d));
}

/// Installs the handler of SIGINT, SIGTERM and SIGHUP: it waits for a commit in progress,
/// removes this process's temporaries and the empty directories its uncommitted writes
/// created, and exits with status 128 + the signal's number. The binary calls it first
/// thing; without it a signal kills the process with its temporaries left behind (the next
/// write into the directory removes them).
#[cfg(unix)]
pub fn remove_temporaries_on_signals() -> std::io::Result<()> {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP])?;
    std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || {
            if let Some(signal) = signals.forever().next() {
                exit_removing_temporaries(signal);
            }
        })?;
    Ok(())
}

/// Without Unix signals there is nothing to install.
#[cfg(not(unix))]
pub fn remove_temporaries_on_signals() -> std::io::Result<()> {
    Ok(())
}

/// Removes what [`LIVE`] lists and exits, holding the commit lock to the end so that no
/// other thread starts a temporary or a rename meanwhile.
#[cfg(unix)]
fn exit_removing_temporaries(signal: i32) -> ! {
    let mut live = live();
    let removed = live
        .temps
        .drain(..)
        .filter(|t| std::fs::remove_file(t).is_ok())
        .count();
    for d in live.dirs.drain(..).rev() {
        let _ = std::fs::remove_dir(d);
    }
    for lock in live.locks.drain(..) {
        let _ = std::fs::remove_file(lock);
    }
    eprintln!(
        "lembo-sim: interrupted by signal {signal}; removed {removed} temporary output files"
    );
    std::process::exit(128 + signal)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn files_appear_together_and_no_temporaries_remain() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("run");
        write_files(
            &out,
            &[("a.txt", b"one".to_vec()), ("b.txt", b"two".to_vec())],
        )
        .unwrap();
        assert_eq!(std::fs::read(out.join("a.txt")).unwrap(), b"one");
        assert_eq!(names(&out), ["a.txt", "b.txt"]);
    }

    #[test]
    fn a_failed_write_removes_its_temporaries_and_the_directories_it_created() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("blocker"), b"a file").unwrap();
        let err = write_paths(&[
            (dir.path().join("new/deeper/a.txt"), b"one".as_slice()),
            (dir.path().join("blocker/b.txt"), b"two".as_slice()),
        ])
        .unwrap_err();
        assert!(
            matches!(&err, Error::Write { path, .. } if path.ends_with("blocker")),
            "{err}"
        );
        assert_eq!(names(dir.path()), ["blocker"]);
        let live = live();
        let mine = |p: &PathBuf| p.starts_with(dir.path());
        assert!(!live.temps.iter().any(mine) && !live.dirs.iter().any(mine));
    }

    #[test]
    fn one_file_named_twice_is_refused_before_anything_is_renamed() {
        let dir = tempfile::tempdir().unwrap();
        let err = write_paths(&[
            (dir.path().join("a.txt"), b"one".as_slice()),
            (dir.path().join("./a.txt"), b"two".as_slice()),
        ])
        .unwrap_err();
        assert!(err.to_string().contains("two outputs"), "{err}");
        assert!(names(dir.path()).is_empty());
    }

    #[test]
    fn temporaries_name_their_process() {
        assert_eq!(temp_owner(".report.json.4242.tmp"), Some(4242));
        assert_eq!(
            temp_owner(&temp_name("image.png")),
            Some(std::process::id())
        );
        for not_ours in [
            ".report.json.tmp",
            "report.json.42.tmp",
            "..42.tmp",
            ".a.4x2.tmp",
        ] {
            assert_eq!(temp_owner(not_ours), None, "{not_ours}");
        }
    }

    #[test]
    fn stale_temporaries_of_dead_processes_are_removed_and_live_ones_kept() {
        if pid_alive(1).is_none() {
            return; // No /proc: nothing is judged stale (tested by the keep rule below).
        }
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let dead = child.id();
        child.wait().unwrap();
        let dir = tempfile::tempdir().unwrap();
        let stale = format!(".report.json.{dead}.tmp");
        let ours = temp_name("image.png");
        for name in [&stale, &ours, &"notes.txt".to_string()] {
            std::fs::write(dir.path().join(name), b"x").unwrap();
        }
        write_files(dir.path(), &[("report.json", b"{}".to_vec())]).unwrap();
        assert_eq!(
            names(dir.path()),
            [ours.as_str(), "notes.txt", "report.json"]
        );
    }
}
