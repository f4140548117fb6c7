//! Outputs under interruption (issue 7 item 4, src/output.rs): a failed, interrupted or
//! killed run leaves no partial output file, and the next run removes what a killed one
//! left. The binary runs as a user would start it; signals are sent with `kill`.
//!
//! No test depends on timing: a run to be interrupted is told to wait before its renames
//! (`LEMBO_HOLD_BEFORE_RENAME_SECS`), the tests poll for what they wait on with generous
//! time limits, and a run interrupted earlier or later than expected must leave the same.
#![cfg(target_os = "linux")]

use crate::support::binary::{bin, files_in, run};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

/// Long enough for any poll on a loaded machine; only reached when something is wrong.
const PATIENCE: Duration = Duration::from_secs(120);
/// The wait before the renames: far beyond any test, so a held run is always interrupted.
const HOLD: &str = "600";

/// Starts a render that waits before renaming its outputs.
fn start_held(args: &[&str], cwd: &Path) -> Child {
    bin()
        .args(args)
        .current_dir(cwd)
        .env("LEMBO_HOLD_BEFORE_RENAME_SECS", HOLD)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary starts")
}

/// Polls `done` until it holds; fails the test after [`PATIENCE`].
fn wait_until(what: &str, child: &mut Child, mut done: impl FnMut() -> bool) {
    let t0 = Instant::now();
    while !done() {
        if let Some(status) = child.try_wait().unwrap() {
            panic!("the run ended ({status}) before {what}");
        }
        if t0.elapsed() > PATIENCE {
            let _ = child.kill();
            panic!("timed out waiting for {what}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Waits for the run to end; kills it and fails the test after [`PATIENCE`].
fn wait_exit(child: &mut Child) -> ExitStatus {
    let t0 = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            return status;
        }
        if t0.elapsed() > PATIENCE {
            let _ = child.kill();
            panic!("the run did not end after the signal");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn signal(child: &Child, name: &str) {
    let status = Command::new("kill")
        .args([&format!("-{name}"), &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(status.success(), "kill -{name} failed");
}

/// Whether process `pid` catches SIGINT and SIGTERM (the `SigCgt` mask of /proc).
fn catches_signals(pid: u32) -> bool {
    let Ok(status) = std::fs::read_to_string(format!("/proc/{pid}/status")) else {
        return false;
    };
    let mask = status
        .lines()
        .find_map(|l| l.strip_prefix("SigCgt:"))
        .and_then(|m| u64::from_str_radix(m.trim(), 16).ok())
        .unwrap_or(0);
    let bit = |signal: u32| mask & (1 << (signal - 1)) != 0;
    bit(2) && bit(15)
}

fn temp(dir: &Path, name: &str, pid: u32) -> PathBuf {
    dir.join(format!(".{name}.{pid}.tmp"))
}

const OUTPUTS: [&str; 5] = [
    "image.png",
    "manifest.json",
    "report.html",
    "report.json",
    "report.txt",
];

fn stderr_of(child: Child) -> String {
    String::from_utf8_lossy(&child.wait_with_output().unwrap().stderr).into_owned()
}

#[test]
fn a_run_whose_last_file_cannot_be_written_leaves_no_file_and_no_directory() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("blocker"), b"a file, not a directory").unwrap();
    // The timeline is written with the outputs, last; its directory cannot exist.
    let args = [
        "render",
        "--out",
        "out/run",
        "--trace-out",
        "blocker/trace.json",
    ];
    let out = run(&args, tmp.path());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("cannot write"), "{stderr}");
    assert_eq!(files_in(tmp.path()), ["blocker"]);

    // With an earlier run's outputs there, they stay as they were, and no temporary is left.
    assert!(run(&["render", "--out", "out/run"], tmp.path())
        .status
        .success());
    let dir = tmp.path().join("out/run");
    let before: Vec<Vec<u8>> = OUTPUTS
        .iter()
        .map(|n| std::fs::read(dir.join(n)).unwrap())
        .collect();
    let out = run(&[&args[..], &["--k", "0.25"]].concat(), tmp.path());
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(files_in(&dir), OUTPUTS);
    for (name, bytes) in OUTPUTS.iter().zip(&before) {
        assert_eq!(&std::fs::read(dir.join(name)).unwrap(), bytes, "{name}");
    }
}

#[test]
fn ctrl_c_during_a_render_exits_130_and_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    // A few seconds of work: the signal lands during the render, or, on a machine slow to
    // deliver it, in the wait before the renames; either way nothing may be left.
    let mut child = start_held(
        &["render", "--viewport", "4096x4096", "--out", "out/big"],
        tmp.path(),
    );
    let pid = child.id();
    wait_until("the signal handler is installed", &mut child, || {
        catches_signals(pid)
    });
    signal(&child, "INT");
    let status = wait_exit(&mut child);
    assert_eq!(status.code(), Some(130), "{}", stderr_of(child));
    assert!(
        files_in(tmp.path()).is_empty(),
        "{:?}",
        files_in(tmp.path())
    );
}

#[test]
fn sigint_and_sigterm_after_the_temporaries_are_written_remove_them() {
    for (sig, code, earlier) in [("INT", 130, false), ("TERM", 143, true)] {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("out/run");
        if earlier {
            assert!(
                run(&["render", "--out", "out/run", "--k", "0.25"], tmp.path())
                    .status
                    .success()
            );
        }
        let before: Vec<Option<Vec<u8>>> = OUTPUTS
            .iter()
            .map(|n| std::fs::read(dir.join(n)).ok())
            .collect();
        let mut child = start_held(&["render", "--out", "out/run"], tmp.path());
        let pid = child.id();
        // manifest.json is the last file written before the wait.
        wait_until("every temporary is written", &mut child, || {
            temp(&dir, "manifest.json", pid).exists()
        });
        signal(&child, sig);
        let status = wait_exit(&mut child);
        let stderr = stderr_of(child);
        assert_eq!(status.code(), Some(code), "SIG{sig}: {stderr}");
        assert!(
            stderr.contains("removed 5 temporary output files"),
            "{stderr}"
        );
        if earlier {
            // The earlier outputs, byte for byte, and nothing else.
            assert_eq!(files_in(&dir), OUTPUTS);
            for (name, bytes) in OUTPUTS.iter().zip(&before) {
                assert_eq!(std::fs::read(dir.join(name)).ok(), *bytes, "{name}");
            }
        } else {
            // The directories the run created are gone with its temporaries.
            assert!(
                files_in(tmp.path()).is_empty(),
                "{:?}",
                files_in(tmp.path())
            );
        }
    }
}

#[test]
fn a_stale_temporary_of_a_dead_process_is_removed_by_the_next_run() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("o");
    std::fs::create_dir(&dir).unwrap();
    let mut gone = Command::new("true").spawn().unwrap();
    let dead = gone.id();
    gone.wait().unwrap();
    let stale = temp(&dir, "report.json", dead);
    // A temporary of a live process (this test) is another run's work in progress.
    let live = temp(&dir, "report.json", std::process::id());
    std::fs::write(&stale, b"{\"half\": ").unwrap();
    std::fs::write(&live, b"{\"half\": ").unwrap();

    let out = run(&["render", "--out", "o"], tmp.path());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!stale.exists());
    assert!(live.exists());
    let mut expected: Vec<String> = OUTPUTS.iter().map(|s| s.to_string()).collect();
    expected.insert(0, live.file_name().unwrap().to_string_lossy().into_owned());
    assert_eq!(files_in(&dir), expected);
}

#[test]
fn after_sigkill_a_rerun_removes_the_leftovers_and_writes_complete_outputs() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("o");
    let mut child = start_held(&["render", "--out", "o"], tmp.path());
    let pid = child.id();
    wait_until("every temporary is written", &mut child, || {
        temp(&dir, "manifest.json", pid).exists()
    });
    signal(&child, "KILL");
    assert_eq!(wait_exit(&mut child).code(), None, "killed by a signal");
    // SIGKILL cannot be handled: the hidden temporaries stay, and no output appeared.
    let mut left: Vec<String> = OUTPUTS.iter().map(|n| format!(".{n}.{pid}.tmp")).collect();
    left.sort();
    assert_eq!(files_in(&dir), left);

    let out = run(&["render", "--out", "o"], tmp.path());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(files_in(&dir), OUTPUTS);
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("report.json")).unwrap()).unwrap();
    assert!(report["schema_version"].is_u64(), "{report}");
    let image = image::open(dir.join("image.png")).unwrap();
    assert_eq!(
        (image.width() as u64, image.height() as u64),
        (
            report["scene"]["width"].as_u64().unwrap(),
            report["scene"]["height"].as_u64().unwrap()
        )
    );
    let text = std::fs::read_to_string(dir.join("report.txt")).unwrap();
    assert!(text.starts_with("lembo-sim report"), "{text}");
}

/// SIGTERM to a sweep that holds its folder's lock removes the lock with the temporaries,
/// so the next sweep need not judge a stale one.
#[test]
fn a_signalled_sweep_releases_its_folder_lock() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("out/sweep");
    let spec = Path::new(env!("CARGO_MANIFEST_DIR")).join("sim/sweeps/smoke.json");
    let mut child = start_held(
        &[
            "sweep",
            spec.to_str().unwrap(),
            "--out",
            "out/sweep",
            "--jobs",
            "1",
        ],
        tmp.path(),
    );
    let pid = child.id();
    // spec.json is the sweep's first write, after it took the lock.
    wait_until(
        "the sweep holds its lock and stages spec.json",
        &mut child,
        || dir.join(lembo_sim::sweep::LOCK_FILE).exists() && temp(&dir, "spec.json", pid).exists(),
    );
    signal(&child, "TERM");
    let status = wait_exit(&mut child);
    let stderr = stderr_of(child);
    assert_eq!(status.code(), Some(143), "{stderr}");
    assert!(files_in(&dir).is_empty(), "{:?}", files_in(&dir));
}
