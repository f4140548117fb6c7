//! The documents point at real things: every repository path and every Rust path
//! (`a::b::c`) that README, DESIGN, ARCHITECTURE, OUTPUTS, RESULTS and the READMEs under
//! `sim/` and `traces/` name, in backticks or as a link, exists.
//!
//! What counts as a name, read from a backticked span or a link's target (an anchor `#..`
//! and a line suffix `:12` or `:12-30` dropped, trailing punctuation too):
//! - a path with a `/` whose first part is a top-level entry of the repository, or that
//!   resolves from the document's own folder: the file or folder must exist (from the root
//!   or from the document's folder);
//! - a bare file name with a file extension (`metrics.rs`, `bunny.json`): some file of the
//!   repository must have that name, unless it is one of the files a run writes
//!   ([`OUTPUTS`], OUTPUTS.md);
//! - a Rust path (`sweep::bracket::Refine`, `Scene::load()`): each of its parts must be an
//!   identifier of the repository's Rust code (a renamed item fails; external crates are
//!   skipped).
//!
//! Not names: spans with spaces or shell syntax, URLs, command lines, placeholders
//! (`<scene>`, `NAME`), criterion benchmark ids (`stages_more/...`: no top-level entry).

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// Files a run or a sweep writes (OUTPUTS.md): named bare, they are outputs, not sources.
const OUTPUTS: &[&str] = &[
    "answer.md",
    "compare.json",
    "compare.txt",
    "cycles.json",
    "error.png",
    "flip.png",
    "image.png",
    "lembo.png",
    "lembo_error.png",
    "lembo_flip.png",
    "manifest.json",
    "montage.png",
    "reference.png",
    "report.html",
    "report.json",
    "report.txt",
    "results.csv",
    "results.jsonl",
    "scaling.csv",
    "spec.json",
    "trace.json",
    "triangle.png",
    "triangle_error.png",
    "triangle_flip.png",
];

/// External crates: a Rust path through one is not checked.
const EXTERNAL: &[&str] = &[
    "std",
    "core",
    "alloc",
    "serde",
    "serde_json",
    "glam",
    "crossbeam_channel",
    "image",
    "criterion",
    "clap",
    "rayon",
    "plotters",
    "libc",
    "tobj",
    "half",
    "csv",
    "indicatif",
    "nv_flip",
    "proptest",
];

/// The repository as the check sees it: every file and folder (relative, `/`-separated),
/// and every identifier of its Rust code.
struct Tree {
    paths: BTreeSet<String>,
    names: BTreeSet<String>,
    top: BTreeSet<String>,
    words: BTreeSet<String>,
}

impl Tree {
    fn read(root: &Path) -> Tree {
        let mut tree = Tree {
            paths: BTreeSet::new(),
            names: BTreeSet::new(),
            top: BTreeSet::new(),
            words: BTreeSet::new(),
        };
        let mut stack = vec![PathBuf::new()];
        while let Some(rel) = stack.pop() {
            for entry in std::fs::read_dir(root.join(&rel)).unwrap() {
                let entry = entry.unwrap();
                let name = entry.file_name().to_string_lossy().to_string();
                if rel.as_os_str().is_empty() && ["target", ".git", "out"].contains(&&*name) {
                    continue;
                }
                let path = rel.join(&name);
                let shown = path.to_string_lossy().replace('\\', "/");
                if rel.as_os_str().is_empty() {
                    tree.top.insert(name.clone());
                }
                tree.paths.insert(shown);
                if entry.file_type().unwrap().is_dir() {
                    stack.push(path);
                } else {
                    if name.ends_with(".rs") {
                        let text = std::fs::read_to_string(root.join(&path)).unwrap_or_default();
                        tree.words.extend(identifiers(&text));
                    }
                    tree.names.insert(name);
                }
            }
        }
        tree
    }

    fn exists(&self, doc_dir: &str, path: &str) -> bool {
        let path = path.trim_end_matches('/');
        [normalize(path), normalize(&format!("{doc_dir}/{path}"))]
            .iter()
            .flatten()
            .any(|p| self.paths.contains(p))
    }
}

/// The identifiers of a text.
fn identifiers(text: &str) -> impl Iterator<Item = String> + '_ {
    text.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .filter(|w| w.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_'))
        .map(str::to_string)
}

/// `a/./b/../c` as `a/c`; None when it climbs out of the root.
fn normalize(path: &str) -> Option<String> {
    let mut parts: Vec<&str> = Vec::new();
    for part in path.split('/') {
        match part {
            "" | "." => {}
            ".." => {
                parts.pop()?;
            }
            p => parts.push(p),
        }
    }
    Some(parts.join("/"))
}

/// Whether `s` is a Rust path: identifiers joined by `::`, maybe called.
fn rust_path(s: &str) -> Option<Vec<&str>> {
    let s = s.strip_suffix("()").unwrap_or(s);
    let parts: Vec<&str> = s.split("::").collect();
    let ident = |p: &&str| {
        p.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_')
            && p.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
    };
    (parts.len() >= 2 && parts.iter().all(ident)).then_some(parts)
}

/// What the document `doc` (its path, for its folder) names that does not exist.
fn missing(doc: &str, text: &str, tree: &Tree) -> Vec<String> {
    let doc_dir = doc.rsplit_once('/').map_or("", |(d, _)| d);
    let mut spans: Vec<&str> = text.split('`').skip(1).step_by(2).collect();
    spans.extend(text.split("](").skip(1).filter_map(|r| r.split(')').next()));
    let mut out = Vec::new();
    for span in spans {
        if span.contains('\n') {
            continue;
        }
        let mut s = span.trim().trim_end_matches(['.', ',', ';', ':']);
        s = s.split('#').next().unwrap_or_default();
        if let Some((head, tail)) = s.rsplit_once(':') {
            if !tail.is_empty() && tail.chars().all(|c| c.is_ascii_digit() || c == '-') {
                s = head;
            }
        }
        let skip = s.is_empty()
            || s.contains(char::is_whitespace)
            || ["http", "git:", "/", "~", "-", "$"]
                .iter()
                .any(|p| s.starts_with(p));
        if skip {
            continue;
        }
        if let Some(parts) = rust_path(s) {
            if EXTERNAL.contains(&parts[0]) {
                continue;
            }
            let unknown: Vec<&&str> = parts
                .iter()
                .filter(|p| !["crate", "super", "self", "lembo_sim"].contains(p))
                .filter(|p| !tree.words.contains(**p))
                .collect();
            if !unknown.is_empty() {
                out.push(format!("{doc}: `{s}` (no Rust item {unknown:?})"));
            }
            continue;
        }
        if s.contains("...") || s.contains("::") || s.contains(|c| "<>*{}[]()|=?'\"".contains(c)) {
            continue;
        }
        if s.contains('/') {
            let first = s.split('/').next().unwrap_or_default();
            let local = [".", ".."].contains(&first) || tree.exists(doc_dir, first);
            if (tree.top.contains(first) || local) && !tree.exists(doc_dir, s) {
                out.push(format!("{doc}: `{s}` (no such file or folder)"));
            }
            continue;
        }
        let extension = s.rsplit_once('.').map(|(_, e)| e);
        let file_like = [
            "rs", "json", "md", "svg", "png", "csv", "toml", "obj", "ply", "txt",
        ]
        .iter()
        .any(|e| extension == Some(e));
        if file_like && !OUTPUTS.contains(&s) && !tree.names.contains(s) {
            out.push(format!("{doc}: `{s}` (no file of that name)"));
        }
    }
    out
}

/// The documents checked, relative to the root.
fn documents(tree: &Tree) -> Vec<String> {
    let mut docs: Vec<String> = ["README.md", "DESIGN.md", "ARCHITECTURE.md", "OUTPUTS.md"]
        .iter()
        .chain(&["RESULTS.md"])
        .map(|s| s.to_string())
        .collect();
    docs.extend(
        tree.paths
            .iter()
            .filter(|p| {
                (p.starts_with("sim/") || p.starts_with("traces/")) && p.ends_with("/README.md")
            })
            .cloned(),
    );
    docs
}

#[test]
fn documents_name_only_what_exists() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let tree = Tree::read(root);
    let docs = documents(&tree);
    assert!(docs.len() >= 8, "{docs:?}");
    let missing: Vec<String> = docs
        .iter()
        .flat_map(|d| missing(d, &std::fs::read_to_string(root.join(d)).unwrap(), &tree))
        .collect();
    assert!(
        missing.is_empty(),
        "documents name what does not exist:\n{}",
        missing.join("\n")
    );
}

/// The control: a planted bad path, bad file name and renamed item are each found, and
/// what exists, outputs, commands and benchmark ids are not.
#[test]
fn documents_a_planted_bad_name_is_found() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let tree = Tree::read(root);
    // The renamed item's name is built here, so that this file does not hold it whole.
    let item = format!("NoSuch{}", "Item");
    let text = format!(
        "See `src/sweep/bracket.rs`, `src/sweep/no_such_file.rs:12`, [the spec](fair.json), \
         [gone](results/none/answer.md), `bracket.rs`, `gone_file.rs`, \
         `sweep::bracket::Refine`, `sweep::bracket::{item}`, `answer.md`, \
         `cargo run --release`, `stages_more/triangle_rasterizer/x`, `<scene>.json`."
    );
    let found = missing("sim/sweeps/README.md", &text, &tree);
    assert_eq!(found.len(), 4, "{found:#?}");
    for bad in [
        "src/sweep/no_such_file.rs",
        "results/none/answer.md",
        "gone_file.rs",
        item.as_str(),
    ] {
        assert!(found.iter().any(|f| f.contains(bad)), "{bad}: {found:#?}");
    }
}

/// ARCHITECTURE.md's "The unit graph" is what `lembo-sim graph` prints for each graph, so
/// the diagram cannot go stale.
#[test]
fn architecture_unit_graph_is_generated() {
    use lembo_sim::graph::{diagram, Path as UnitPath, TessSource};
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join("ARCHITECTURE.md")).unwrap();
    let graphs = [
        (UnitPath::Lembo, TessSource::Memory),
        (UnitPath::Triangle, TessSource::Memory),
        (UnitPath::Triangle, TessSource::OnChip),
    ];
    let want: Vec<String> = graphs.iter().map(|&(p, s)| diagram(p, s)).collect();
    let block = format!("```text\n{}```\n", want.join("\n"));
    assert!(
        text.contains(&block),
        "ARCHITECTURE.md's section \"The unit graph\" is stale: replace its text block with \
         the output of\n  for a in lembo triangle 'triangle --source onchip'; do \
         cargo run -q --release -- graph --path $a; echo; done\n(without the last empty \
         line), which reads:\n{block}"
    );
}
