//! Golden files of named cases (a JSON map from case to its text), compared exactly, and the
//! one guarded way to bless them.
//!
//! Blessing rewrites a golden only with `LEMBO_BLESS=1` exactly: any other value blesses
//! nothing (and says so). A bless prints, per golden file, how many cases changed and the
//! first few differences, and refuses what would hide a regression: a case whose run failed
//! (its text `error: ...`) unless the golden declares it as an expected error, a case that
//! fails its golden's non-triviality check, or fewer cases than the golden's minimum. Those
//! checks hold when comparing too, so a golden that was blessed blank fails.

use std::collections::BTreeMap;
use std::ffi::OsStr;
use std::path::Path;

/// The environment variable that blesses goldens.
pub const BLESS: &str = "LEMBO_BLESS";

/// Whether `value` (the variable's value, if set) asks to bless: only `1` does.
pub fn bless_requested(value: Option<&OsStr>) -> bool {
    value.is_some_and(|v| v == "1")
}

/// Whether this run blesses goldens; a set value other than `1` is reported on stderr and
/// blesses nothing.
pub fn blessing() -> bool {
    let value = std::env::var_os(BLESS);
    let bless = bless_requested(value.as_deref());
    if let (Some(v), false) = (&value, bless) {
        eprintln!("{BLESS}={v:?} blesses nothing: set {BLESS}=1 to rewrite goldens");
    }
    bless
}

/// What every golden must hold, checked when comparing and when blessing.
pub struct Expect<'a> {
    /// The fewest cases the golden may have.
    pub min_cases: usize,
    /// Cases whose run is expected to fail (their text starts with `error: `).
    pub expected_errors: &'a [&'a str],
    /// A case's non-triviality check: Err says why its text cannot be a golden.
    pub valid: &'a dyn Fn(&str) -> Result<(), String>,
}

/// The prefix of a failed run's text.
const ERROR: &str = "error: ";

/// Why `got` cannot be blessed or compared as a golden: too few cases, an undeclared
/// failed run, or a case failing the non-triviality check.
fn refusals(got: &BTreeMap<String, String>, expect: &Expect) -> Vec<String> {
    let mut why = Vec::new();
    if got.len() < expect.min_cases {
        why.push(format!(
            "{} cases, fewer than the {} expected",
            got.len(),
            expect.min_cases
        ));
    }
    for (case, text) in got {
        if text.starts_with(ERROR) {
            if !expect.expected_errors.contains(&case.as_str()) {
                why.push(format!("{case}: the run failed ({text})"));
            }
        } else if let Err(e) = (expect.valid)(text) {
            why.push(format!("{case}: {e}"));
        }
    }
    why
}

/// Each case of `want` and `got` that differs, with its first differing line; cases only
/// in one of them are named as added or removed.
pub fn differences(want: &BTreeMap<String, String>, got: &BTreeMap<String, String>) -> Vec<String> {
    let mut out = Vec::new();
    for (case, g) in got {
        match want.get(case) {
            None => out.push(format!("{case}: added")),
            Some(w) if w != g => {
                let line = w
                    .lines()
                    .zip(g.lines())
                    .find(|(a, b)| a != b)
                    .map(|(a, b)| format!("\n  want {a}\n  got  {b}"))
                    .unwrap_or_else(|| "\n  (one text is a prefix of the other)".into());
                out.push(format!("{case}:{line}"));
            }
            Some(_) => {}
        }
    }
    for case in want.keys().filter(|c| !got.contains_key(*c)) {
        out.push(format!("{case}: removed"));
    }
    out
}

/// Compares `got` with the golden file at `path`, case by case, naming the first differing
/// line of each case that differs (`what` names the cases in the message); when
/// [`blessing`], writes `got` there instead, after printing what changed. Either way `got`
/// must meet `expect`.
pub fn check(path: &Path, got: BTreeMap<String, String>, what: &str, expect: &Expect) {
    check_with(path, got, what, expect, blessing());
}

/// [`check`], blessing when `bless`.
pub fn check_with(
    path: &Path,
    got: BTreeMap<String, String>,
    what: &str,
    expect: &Expect,
    bless: bool,
) {
    let refused = refusals(&got, expect);
    assert!(
        refused.is_empty(),
        "{} {what} cannot be {} {}:\n{}",
        refused.len(),
        if bless {
            "blessed into"
        } else {
            "compared with"
        },
        path.display(),
        refused.join("\n")
    );
    let want: BTreeMap<String, String> = std::fs::read_to_string(path)
        .ok()
        .and_then(|text| serde_json::from_str(&text).ok())
        .unwrap_or_default();
    let differ = differences(&want, &got);
    if bless {
        eprintln!(
            "{BLESS}: {} of {} {what} changed in {}",
            differ.len(),
            got.len(),
            path.display()
        );
        for d in differ.iter().take(5) {
            eprintln!("  {d}");
        }
        std::fs::create_dir_all(path.parent().expect("a golden is in a folder")).unwrap();
        std::fs::write(path, serde_json::to_string_pretty(&got).unwrap() + "\n").unwrap();
        return;
    }
    assert!(
        path.exists() && !want.is_empty(),
        "{} is missing or unreadable",
        path.display()
    );
    let mut failing = refusals(&want, expect);
    failing.iter_mut().for_each(|f| f.insert_str(0, "golden "));
    assert!(
        failing.is_empty(),
        "{} holds what no golden may: \n{}",
        path.display(),
        failing.join("\n")
    );
    assert!(
        differ.is_empty(),
        "{} of {} {what} differ from {}:\n{}",
        differ.len(),
        want.len(),
        path.display(),
        differ.join("\n")
    );
}

/// A cycle digest (`total N bottleneck ...`) with a total above zero.
pub fn cycles_above_zero(text: &str) -> Result<(), String> {
    let total = text
        .strip_prefix("total ")
        .and_then(|t| t.split_whitespace().next())
        .and_then(|n| n.parse::<u64>().ok());
    match total {
        Some(n) if n > 0 => Ok(()),
        Some(_) => Err("a frame of 0 cycles".into()),
        None => Err("no cycle total".into()),
    }
}

/// An operation table with at least one operation.
pub fn some_operations(text: &str) -> Result<(), String> {
    if text.contains(|c: char| c.is_ascii_digit() && c != '0') {
        Ok(())
    } else {
        Err("no operation counted".into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cases(pairs: &[(&str, &str)]) -> BTreeMap<String, String> {
        pairs
            .iter()
            .map(|(c, t)| (c.to_string(), t.to_string()))
            .collect()
    }

    const EXPECT: Expect = Expect {
        min_cases: 2,
        expected_errors: &["b declared"],
        valid: &cycles_above_zero,
    };

    fn panic_of(f: impl FnOnce() + std::panic::UnwindSafe) -> String {
        let e = std::panic::catch_unwind(f).expect_err("the check fails");
        e.downcast_ref::<String>().cloned().unwrap_or_default()
    }

    /// CI refuses to run with the variable set, whatever its value, before doing anything.
    #[test]
    fn ci_refuses_to_run_with_bless_set() {
        let script = Path::new(env!("CARGO_MANIFEST_DIR")).join(".ci/run");
        let out = std::process::Command::new("bash")
            .arg(&script)
            .env(BLESS, "0")
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2));
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("LEMBO_BLESS is set (to '0')"), "{err}");
        assert!(out.stdout.is_empty(), "it ran something first");
    }

    /// Only `LEMBO_BLESS=1` blesses.
    #[test]
    fn only_one_blesses() {
        assert!(bless_requested(Some(OsStr::new("1"))));
        for v in ["0", "", "true", "yes", "11", " 1"] {
            assert!(!bless_requested(Some(OsStr::new(v))), "{v:?}");
        }
        assert!(!bless_requested(None));
    }

    /// A corrupted golden fails; an intact one passes; a failed run, a blank case or too
    /// few cases are refused both when comparing and when blessing, and nothing is written
    /// by a refused bless.
    #[test]
    fn a_corrupted_golden_fails_and_a_failing_case_cannot_be_blessed() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("g.json");
        let good = cases(&[("a", "total 5 bottleneck x\nu 1"), ("c", "total 7 b\n")]);
        check_with(&path, good.clone(), "reports", &EXPECT, true);
        check_with(&path, good.clone(), "reports", &EXPECT, false);

        let corrupted = std::fs::read_to_string(&path)
            .unwrap()
            .replace("u 1", "u 2");
        std::fs::write(&path, corrupted).unwrap();
        let msg = panic_of(|| check_with(&path, good.clone(), "reports", &EXPECT, false));
        assert!(
            msg.contains("1 of 2 reports differ") && msg.contains("want u 2"),
            "{msg}"
        );

        let before = std::fs::read_to_string(&path).unwrap();
        let failed = cases(&[("a", "error: boom"), ("c", "total 7 b\n")]);
        let msg = panic_of(|| check_with(&path, failed.clone(), "reports", &EXPECT, true));
        assert!(msg.contains("a: the run failed (error: boom)"), "{msg}");
        assert_eq!(
            std::fs::read_to_string(&path).unwrap(),
            before,
            "nothing written"
        );

        let blank = cases(&[("a", "total 0 bottleneck None\n"), ("c", "total 7 b\n")]);
        let msg = panic_of(|| check_with(&path, blank.clone(), "reports", &EXPECT, true));
        assert!(msg.contains("a: a frame of 0 cycles"), "{msg}");
        let few = cases(&[("a", "total 5 b\n")]);
        let msg = panic_of(|| check_with(&path, few.clone(), "reports", &EXPECT, false));
        assert!(msg.contains("1 cases, fewer than the 2 expected"), "{msg}");

        // A declared expected error may be blessed and compared.
        let declared = cases(&[("a", "total 5 b\n"), ("b declared", "error: expected")]);
        check_with(&path, declared.clone(), "reports", &EXPECT, true);
        check_with(&path, declared, "reports", &EXPECT, false);
    }
}
