//! Golden files of named cases: a JSON map from case to its text.

use std::collections::BTreeMap;
use std::path::Path;

/// Compares `got` with the golden file at `path`, case by case, naming the first differing
/// line of each case that differs (`what` names the cases in the message); with
/// `LEMBO_BLESS` set, writes `got` there instead.
pub fn check(path: &Path, got: BTreeMap<String, String>, what: &str) {
    if std::env::var_os("LEMBO_BLESS").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, serde_json::to_string_pretty(&got).unwrap() + "\n").unwrap();
        return;
    }
    let want: BTreeMap<String, String> =
        serde_json::from_str(&std::fs::read_to_string(path).expect("golden exists")).unwrap();
    assert_eq!(
        want.keys().collect::<Vec<_>>(),
        got.keys().collect::<Vec<_>>(),
        "cases of {}",
        path.display()
    );
    let mut differ = Vec::new();
    for (case, w) in &want {
        let g = &got[case];
        if g != w {
            let line = w
                .lines()
                .zip(g.lines())
                .find(|(a, b)| a != b)
                .map(|(a, b)| format!("\n  want {a}\n  got  {b}"))
                .unwrap_or_default();
            differ.push(format!("{case}:{line}"));
        }
    }
    assert!(
        differ.is_empty(),
        "{} of {} {what} differ:\n{}",
        differ.len(),
        want.len(),
        differ.join("\n")
    );
}
