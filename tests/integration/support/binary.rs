//! Helpers shared by the tests that run the `lembo-sim` binary as a user would.

use std::path::Path;
use std::process::{Command, Output};

/// The built binary, with the test hooks a caller's environment may hold removed (a test
/// sets the ones it means).
pub fn bin() -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_lembo-sim"));
    cmd.env_remove("LEMBO_MEMORY_AVAILABLE");
    cmd
}

/// Runs the binary with `args` in `cwd` and waits for it.
pub fn run(args: &[&str], cwd: &Path) -> Output {
    bin()
        .args(args)
        .current_dir(cwd)
        .output()
        .expect("the binary runs")
}

/// The names in `dir`, sorted (none when it does not exist).
pub fn files_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = match std::fs::read_dir(dir) {
        Ok(rd) => rd
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect(),
        Err(_) => vec![],
    };
    v.sort();
    v
}

/// The memory the system can give a new allocation (`MemAvailable` of /proc/meminfo)
/// \[bytes\]; None where it cannot be read.
pub fn memory_available() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024.0)
}
