//! A lock on a sweep folder: one writer at a time.
//!
//! Two `sweep` processes on one `--out` would both run every pending point and append to
//! one `results.jsonl` (a requeued Slurm task racing its predecessor does exactly this).
//! So `sweep` and `sweep-merge` hold [`LOCK_FILE`] in the folder they write while they run:
//!
//! - **Taking it** is one atomic step: the holder's description (command, process id,
//!   host) is written to a temporary and hard-linked to the lock's name, which fails if the
//!   name exists, so a lock file is never seen half written.
//! - **A live holder** refuses the second process at once, naming the holder (exit 2).
//! - **A dead holder** (its host is this one and its process id is gone from `/proc`) left
//!   a stale lock, which is taken over, as stale temporaries are (`crate::output`).
//! - **A holder on another host** (a folder on a shared file system) cannot be checked from
//!   here: the second process is refused and told which file to remove if that process no
//!   longer runs. So is a lock whose holder cannot be read.
//! - **Releasing it**: when the command ends, normally or by an error, and on SIGINT,
//!   SIGTERM or SIGHUP (the signal handler of `crate::output` removes it). SIGKILL leaves it
//!   for the next run to take over.
//!
//! Shards of one sweep write different folders, so they never contend. A process id reused
//! by an unrelated process after the holder died keeps the lock held until the user
//! removes it; the message says how.

use crate::error::{Error, Result, COMMAND_LINE};
use crate::output::{pid_alive, register_lock, temp_name, unregister_lock};
use serde::{Deserialize, Serialize};
use std::io::ErrorKind;
use std::path::{Path, PathBuf};

/// The lock's file name in a sweep folder (hidden, like the output temporaries).
pub const LOCK_FILE: &str = ".lembo-sim.lock";

/// Who holds a lock: the lock file's contents.
#[derive(Serialize, Deserialize, PartialEq, Debug)]
struct Holder {
    /// `sweep` or `sweep-merge`.
    command: String,
    /// The holding process.
    pid: u32,
    /// The host it runs on.
    host: String,
}

impl Holder {
    /// This process, running `command`.
    fn me(command: &str) -> Holder {
        Holder {
            command: command.to_string(),
            pid: std::process::id(),
            host: host_name(),
        }
    }
}

/// This machine's name (`/proc/sys/kernel/hostname`, else `$HOSTNAME`, else `unknown`).
fn host_name() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .or_else(|| std::env::var("HOSTNAME").ok())
        .map(|h| h.trim().to_string())
        .filter(|h| !h.is_empty())
        .unwrap_or_else(|| "unknown".into())
}

/// What a lock file found in place says.
enum Found {
    /// Its holder is alive, or cannot be checked: the reason to refuse.
    Held(String),
    /// Its holder died on this host: the lock may be taken over.
    Stale,
    /// It vanished meanwhile: try again.
    Gone,
}

/// Reads the lock at `path` and judges its holder.
fn judge(path: &Path) -> Found {
    let text = match std::fs::read_to_string(path) {
        Ok(text) => text,
        Err(e) if e.kind() == ErrorKind::NotFound => return Found::Gone,
        Err(e) => {
            return Found::Held(format!(
            "is locked by {} that cannot be read ({e}); if no sweep writes it, remove that file",
            path.display()
        ))
        }
    };
    let Ok(holder) = serde_json::from_str::<Holder>(&text) else {
        return Found::Held(format!(
            "is locked by {}, whose holder cannot be told; if no sweep writes it, remove that file",
            path.display()
        ));
    };
    let Holder { command, pid, host } = &holder;
    if *host != host_name() {
        return Found::Held(format!(
            "is being written by `{command}` (process {pid} on host {host}), which cannot be \
             checked from this host; wait for it to end, or if it no longer runs remove {}",
            path.display()
        ));
    }
    match pid_alive(*pid) {
        Some(false) => Found::Stale,
        Some(true) => Found::Held(format!(
            "is being written by `{command}` (process {pid} on this host); wait for it to end \
             or use another folder"
        )),
        None => Found::Held(format!(
            "is locked by `{command}` (process {pid}), and this system cannot tell whether it \
             runs; if it does not, remove {}",
            path.display()
        )),
    }
}

/// The lock on a sweep folder, held until dropped.
#[derive(Debug)]
pub struct FolderLock {
    path: PathBuf,
    /// What the lock file holds: removed on release only while it still does.
    mine: String,
}

impl FolderLock {
    /// Takes the lock on `dir` (created if missing) for `command`; a folder another live
    /// process holds is refused naming `flag`, the folder and that process (exit 2).
    pub fn acquire(dir: &Path, command: &str, flag: &str) -> Result<FolderLock> {
        std::fs::create_dir_all(dir).map_err(|source| Error::Write {
            path: dir.to_path_buf(),
            source,
        })?;
        let path = dir.join(LOCK_FILE);
        let mine = serde_json::to_string(&Holder::me(command)).expect("a holder serialises");
        let tmp = dir.join(temp_name(LOCK_FILE));
        std::fs::write(&tmp, &mine).map_err(|source| Error::Write {
            path: tmp.clone(),
            source,
        })?;
        let taken = take(&tmp, &path, &mine);
        let _ = std::fs::remove_file(&tmp);
        match taken {
            Ok(()) => {
                register_lock(&path);
                Ok(FolderLock { path, mine })
            }
            Err(Refused::Held(why)) => Err(Error::invalid(COMMAND_LINE, flag, dir.display(), why)),
            Err(Refused::Io(source)) => Err(Error::Write { path, source }),
        }
    }

    /// Refuses, naming `flag` and `dir`, a folder that another live process holds (for a
    /// folder that is read, not written: `sweep-merge`'s shards).
    pub fn check_free(dir: &Path, flag: &str) -> Result<()> {
        let path = dir.join(LOCK_FILE);
        if !path.exists() {
            return Ok(());
        }
        match judge(&path) {
            Found::Held(why) => Err(Error::invalid(
                COMMAND_LINE,
                flag,
                dir.display(),
                format!("{why} (a shard still running has not finished)"),
            )),
            Found::Stale | Found::Gone => Ok(()),
        }
    }
}

/// Why a lock could not be taken.
enum Refused {
    /// Another process holds it.
    Held(String),
    /// The file system refused.
    Io(std::io::Error),
}

/// Links the written temporary `tmp` to the lock's name `path`, taking over stale locks;
/// where hard links are not supported the lock is created exclusively and written.
fn take(tmp: &Path, path: &Path, mine: &str) -> std::result::Result<(), Refused> {
    // Bounded: each round either takes the lock, refuses, or removes one stale lock.
    for _ in 0..8 {
        let linked = match std::fs::hard_link(tmp, path) {
            Err(e) if e.kind() != ErrorKind::AlreadyExists => create_exclusive(path, mine),
            other => other,
        };
        match linked {
            Ok(()) => return Ok(()),
            Err(e) if e.kind() == ErrorKind::AlreadyExists => match judge(path) {
                Found::Held(why) => return Err(Refused::Held(why)),
                Found::Gone => continue,
                Found::Stale => match std::fs::remove_file(path) {
                    Ok(()) => continue,
                    Err(e) if e.kind() == ErrorKind::NotFound => continue,
                    Err(e) => return Err(Refused::Io(e)),
                },
            },
            Err(e) => return Err(Refused::Io(e)),
        }
    }
    Err(Refused::Held(
        "is contended by several processes taking its lock at once; try again".into(),
    ))
}

/// Creates `path` only if it does not exist, and writes `mine` into it.
fn create_exclusive(path: &Path, mine: &str) -> std::io::Result<()> {
    use std::io::Write as _;
    let mut file = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(path)?;
    file.write_all(mine.as_bytes())
}

impl Drop for FolderLock {
    fn drop(&mut self) {
        unregister_lock(&self.path);
        // Only a lock that is still this process's is removed.
        if std::fs::read_to_string(&self.path).is_ok_and(|t| t == self.mine) {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn folder(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("lembo-lock-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }

    fn holder(pid: u32, host: &str) -> String {
        serde_json::to_string(&Holder {
            command: "sweep".into(),
            pid,
            host: host.into(),
        })
        .unwrap()
    }

    #[test]
    fn a_held_folder_is_refused_and_released_on_drop() {
        let dir = folder("held");
        let lock = FolderLock::acquire(&dir, "sweep", "--out").unwrap();
        let held = std::fs::read_to_string(dir.join(LOCK_FILE)).unwrap();
        assert_eq!(held, holder(std::process::id(), &host_name()));
        let e = FolderLock::acquire(&dir, "sweep", "--out").unwrap_err();
        assert_eq!(e.exit_code(), 2);
        let message = e.to_string();
        assert!(message.contains("--out"), "{message}");
        assert!(
            message.contains(&format!("process {}", std::process::id())),
            "{message}"
        );
        assert!(FolderLock::check_free(&dir, "SHARD_DIR").is_err());
        drop(lock);
        assert!(!dir.join(LOCK_FILE).exists());
        let names: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
        assert!(names.is_empty(), "no temporary is left: {names:?}");
        FolderLock::check_free(&dir, "SHARD_DIR").unwrap();
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_dead_holders_lock_is_taken_over_and_a_foreign_hosts_is_not() {
        if pid_alive(1).is_none() {
            return; // no /proc: liveness cannot be told
        }
        let dir = folder("stale");
        std::fs::create_dir_all(&dir).unwrap();
        // A process id above the kernel's limit (4194304) has never run.
        std::fs::write(dir.join(LOCK_FILE), holder(4_194_305, &host_name())).unwrap();
        FolderLock::check_free(&dir, "SHARD_DIR").unwrap();
        let lock = FolderLock::acquire(&dir, "sweep", "--out").unwrap();
        drop(lock);
        std::fs::write(dir.join(LOCK_FILE), holder(4_194_305, "elsewhere")).unwrap();
        let message = FolderLock::acquire(&dir, "sweep", "--out")
            .unwrap_err()
            .to_string();
        assert!(message.contains("host elsewhere"), "{message}");
        assert!(message.contains("remove"), "{message}");
        std::fs::write(dir.join(LOCK_FILE), "garbage").unwrap();
        assert!(FolderLock::acquire(&dir, "sweep", "--out").is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
