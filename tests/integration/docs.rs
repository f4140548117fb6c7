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
//!
//! ARCHITECTURE.md, the map, is held closer: every item it names is declared, every file
//! its code map names lies under the module whose entry names it, its "The unit graph" is
//! what `lembo-sim graph` prints, and it stays within a ten-minute read.

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

/// The names a Rust file declares: items (`fn`, `struct`, `enum`, `trait`, `type`,
/// `const`, `static`, `mod`, `macro_rules!`), enum variants and struct fields (an
/// identifier that starts a line and is followed by `,`, `(`, `{` or `:`).
fn declared(text: &str) -> impl Iterator<Item = String> + '_ {
    const KEYWORDS: &[&str] = &[
        "fn",
        "struct",
        "enum",
        "trait",
        "type",
        "const",
        "static",
        "mod",
        "macro_rules!",
    ];
    text.lines().flat_map(|line| {
        let words: Vec<&str> = line.split_whitespace().collect();
        let mut names: Vec<String> = words
            .windows(2)
            .filter(|w| KEYWORDS.contains(&w[0]))
            .filter_map(|w| identifiers(w[1]).next())
            .collect();
        let mut bare = line.trim_start();
        if let Some(rest) = bare.strip_prefix("pub(") {
            bare = rest.split_once(')').map_or(rest, |(_, r)| r).trim_start();
        }
        let bare = bare.trim_start_matches("pub ");
        if let Some(name) = identifiers(bare)
            .next()
            .filter(|n| bare.starts_with(n.as_str()))
        {
            let rest = bare[name.len()..].trim_start();
            if rest.starts_with([',', '(', '{', ':']) {
                names.push(name);
            }
        }
        names
    })
}

/// Items of other crates and tools that ARCHITECTURE.md names, each with where it lives.
const FOREIGN_ITEMS: &[(&str, &str)] = &[
    ("Arc", "std::sync"),
    ("Option", "std::option"),
    ("Pending", "std::task::Poll"),
    (
        "ProgramBuilder",
        "DAM-RS, the simulator the builder follows",
    ),
    ("look_at_rh", "glam::Mat4"),
    ("perspective_rh_gl", "glam::Mat4"),
    ("orthographic_rh_gl", "glam::Mat4"),
    ("deny_unknown_fields", "serde's container attribute"),
];

/// Every name the repository declares: the Rust code's items ([`declared`]), the names
/// its string literals give (a boundary's name, a JSON field), the stems of its files (a
/// shipped scene), and [`FOREIGN_ITEMS`].
fn declarations(root: &Path, tree: &Tree) -> BTreeSet<String> {
    let mut names: BTreeSet<String> = FOREIGN_ITEMS.iter().map(|(n, _)| n.to_string()).collect();
    for p in &tree.paths {
        let stem = p.rsplit('/').next().unwrap_or(p);
        names.insert(stem.split('.').next().unwrap_or(stem).to_string());
        if p.ends_with(".rs") {
            let text = std::fs::read_to_string(root.join(p)).unwrap_or_default();
            names.extend(declared(&text));
            names.extend(text.split('"').skip(1).step_by(2).filter_map(|q| {
                let q = q.trim_end_matches("\\");
                identifiers(q).next().filter(|i| i == q)
            }));
        }
    }
    names
}

/// What ARCHITECTURE.md names as an item, bare in backticks (`Netlist`, `run_path`,
/// `cost_of()`), that nothing declares: a code map names only what the code holds. A bare
/// span is an item when it is an identifier with an upper-case first letter and a
/// lower-case letter (a type, trait or variant), or a snake_case identifier with `_` or a
/// call's `()` (a function, field, module or constant); other words (`auto`, `k`) are
/// prose.
fn undeclared(text: &str, declared: &BTreeSet<String>) -> Vec<String> {
    let is_ident = |s: &str| {
        s.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_')
            && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
    };
    let mut out = Vec::new();
    for span in text.split('`').skip(1).step_by(2) {
        let called = span.ends_with("()");
        let s = span.trim_end_matches("()");
        if !is_ident(s) {
            continue;
        }
        let typed = s.starts_with(|c: char| c.is_ascii_uppercase())
            && s.contains(|c: char| c.is_ascii_lowercase());
        let snake = s.contains('_') && s.chars().all(|c| !c.is_ascii_uppercase());
        if (typed || snake || called) && !declared.contains(s) {
            out.push(format!("ARCHITECTURE.md: `{span}` (nothing declares it)"));
        }
    }
    out.sort();
    out.dedup();
    out
}

#[test]
fn architecture_names_only_declared_items() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let tree = Tree::read(root);
    let declared = declarations(root, &tree);
    assert!(declared.len() >= 2000, "{} names declared", declared.len());
    let text = std::fs::read_to_string(root.join("ARCHITECTURE.md")).unwrap();
    let missing = undeclared(&text, &declared);
    assert!(
        missing.is_empty(),
        "ARCHITECTURE.md names items the code does not declare:\n{}",
        missing.join("\n")
    );
}

/// The control: a planted renamed type, function and call are found; declared items,
/// variants, fields and prose words are not.
#[test]
fn architecture_a_planted_undeclared_item_is_found() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let declared = declarations(root, &Tree::read(root));
    // The planted names are built here, so that this file does not declare them.
    let (ty, func, call) = (
        format!("Gone{}", "Netlist"),
        format!("gone_{}", "run_path"),
        format!("gone{}()", "Finish"),
    );
    let text = format!(
        "`Netlist`, `run_path`, `UnitKind`, `GeometryFetch`, `bytes_per_cycle`, \
         `auto`, `k`, `{ty}`, `{func}`, `{call}`, `--match`, `sweep::bracket::Refine`."
    );
    let found = undeclared(&text, &declared);
    assert_eq!(found.len(), 3, "{found:#?}");
    for bad in [&ty, &func, &call] {
        assert!(
            found.iter().any(|f| f.contains(bad.as_str())),
            "{bad}: {found:#?}"
        );
    }
}

/// ARCHITECTURE.md's "The unit graph" is what `lembo-sim graph` prints for each graph, so
/// the diagram cannot go stale.
#[test]
fn architecture_unit_graph_is_generated() {
    use lembo_sim::graph::{diagram, PrimitivePath, TessSource};
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join("ARCHITECTURE.md")).unwrap();
    let graphs = [
        (PrimitivePath::Lembo, TessSource::Memory),
        (PrimitivePath::Triangle, TessSource::Memory),
        (PrimitivePath::Triangle, TessSource::OnChip),
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

/// The most words ARCHITECTURE.md may hold, as `wc -w` counts them: about ten minutes'
/// reading of technical prose (some 250 words a minute), the generated unit graph
/// included.
const ARCHITECTURE_WORD_BUDGET: usize = 2600;

/// ARCHITECTURE.md stays a map a newcomer reads in ten minutes: explanation (why, history,
/// numbers) goes to DESIGN.md §13, and the map keeps a sentence and a pointer.
#[test]
fn architecture_stays_a_ten_minute_read() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join("ARCHITECTURE.md")).unwrap();
    let words = text.split_whitespace().count();
    assert!(
        words <= ARCHITECTURE_WORD_BUDGET,
        "ARCHITECTURE.md holds {words} words, over its budget of {ARCHITECTURE_WORD_BUDGET} \
         (a ten-minute read): state each part in a sentence or two and move the explanation \
         (why, history, numbers) to DESIGN.md §13, leaving a pointer"
    );
}

/// What ARCHITECTURE.md names as a file or folder that is not where it says. A name with
/// a `/` resolves from the root or from `src/` (`pipeline/items.rs`). In the code map,
/// each entry's names resolve under the folders the entry names (`src/pipeline/`: its
/// `ctx.rs`, `runtime/`, `units/`), or under its files' folder when it names none; a
/// bare file name elsewhere is left to [`missing`]. Files a run writes ([`OUTPUTS`]) are
/// not sources.
fn misplaced_files(text: &str, tree: &Tree) -> Vec<String> {
    let map_start = text.find("\n## Code map").map_or(text.len(), |i| i + 1);
    let map_end = text[map_start..]
        .find("\n## ")
        .map_or(text.len(), |i| map_start + i + 1);
    let mut chunks: Vec<&str> = vec![&text[..map_start], &text[map_end..]];
    let mut entry_start = map_start;
    for (i, _) in text[map_start..map_end].match_indices("\n- ") {
        chunks.push(&text[entry_start..map_start + i + 1]);
        entry_start = map_start + i + 1;
    }
    chunks.push(&text[entry_start..map_end]);
    let mut out: Vec<String> = chunks
        .iter()
        .flat_map(|chunk| misplaced_in(chunk, tree))
        .collect();
    out.sort();
    out.dedup();
    out
}

/// [`misplaced_files`] for one chunk: a code map entry or prose.
fn misplaced_in(chunk: &str, tree: &Tree) -> Vec<String> {
    let names: Vec<&str> = chunk
        .split('`')
        .skip(1)
        .step_by(2)
        .map(|s| s.trim().trim_end_matches(['.', ',', ';', ':']))
        .filter(|s| file_like_name(s) && !OUTPUTS.contains(s))
        .collect();
    let rooted = |s: &&str| tree.exists("", s);
    let mut folders: Vec<String> = names
        .iter()
        .filter(|s| s.ends_with('/') && rooted(s))
        .map(|s| s.to_string())
        .collect();
    if folders.is_empty() {
        folders = names
            .iter()
            .filter(|s| s.contains('/') && rooted(s))
            .filter_map(|s| s.rsplit_once('/').map(|(dir, _)| format!("{dir}/")))
            .collect();
    }
    let mut out = Vec::new();
    for name in names.iter().filter(|s| !rooted(s)) {
        let bare = name.trim_end_matches('/');
        let found = if folders.is_empty() {
            !bare.contains('/') || tree.exists("src", bare)
        } else {
            tree.paths.iter().any(|p| {
                folders
                    .iter()
                    .any(|f| p.starts_with(f.as_str()) && (p.ends_with(&format!("/{bare}"))))
            })
        };
        if !found {
            let place = if folders.is_empty() {
                "the root or src/".to_string()
            } else {
                folders.join(", ")
            };
            out.push(format!("ARCHITECTURE.md: `{name}` (not under {place})"));
        }
    }
    out
}

/// Whether a backticked span names a file or folder: a path with a `/`, or a file name
/// with an extension of the repository's files; not a command, pattern, URL, placeholder
/// or Rust path.
fn file_like_name(s: &str) -> bool {
    let plain = !s.is_empty()
        && !s.contains(char::is_whitespace)
        && !s.contains("::")
        && !s.contains("...")
        && !s.contains(|c| "<>*{}[]()|=?'\"#$~".contains(c))
        && !["http", "-", "/"].iter().any(|p| s.starts_with(p));
    let extension = s.rsplit_once('.').map(|(_, e)| e);
    let file = ["rs", "json", "md", "svg", "png", "csv", "toml", "txt"]
        .iter()
        .any(|e| extension == Some(e));
    plain && (s.contains('/') || file)
}

#[test]
fn architecture_names_only_files_where_they_are() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let tree = Tree::read(root);
    let text = std::fs::read_to_string(root.join("ARCHITECTURE.md")).unwrap();
    let misplaced = misplaced_files(&text, &tree);
    assert!(
        misplaced.is_empty(),
        "ARCHITECTURE.md names files that are not where it says:\n{}",
        misplaced.join("\n")
    );
}

/// The control: a file named under the wrong module, a missing folder and a missing path
/// from `src/` are found; files where their entry says, paths from the root or `src/`,
/// outputs, commands and placeholders are not.
#[test]
fn architecture_a_planted_misplaced_file_is_found() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let tree = Tree::read(root);
    let text = "# Map\n\nSee `raster/driver.rs`, `pipeline/no_such.rs`, `src/graph.rs`, \
                `driver.rs`, `lembo-sim graph`, `src/pipeline/units/<unit>.rs`.\n\n\
                ## Code map\n\n\
                - `src/job/`: `validate.rs`, `ctx.rs`, `answer.md`.\n\
                - `src/pipeline/`: `runtime/` (`ctx.rs`), `units/`, `gone/`, `items.rs`.\n\
                - `src/main.rs`: `report.rs`.\n\
                - Outside: `tests/integration/` (`support/`), `traces/README.md`.\n\n\
                ## Layers\n\n`frame/bands.rs`.\n";
    let found = misplaced_files(text, &tree);
    assert_eq!(found.len(), 3, "{found:#?}");
    for bad in [
        "`pipeline/no_such.rs`",
        "`ctx.rs` (not under src/job/)",
        "`gone/`",
    ] {
        assert!(found.iter().any(|f| f.contains(bad)), "{bad}: {found:#?}");
    }
}
