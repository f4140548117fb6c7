//! The module import graph of `src/` has no cycle and points down the layers that
//! ARCHITECTURE.md lists: nothing lower imports anything higher.
//!
//! A file is a module. An edge A -> B means file A names an item of file B: in a `use`
//! tree, in an inline `crate::`/`super::`/`self::` path, or in a path through one of A's
//! own child modules (`child::item` in the file that declares `mod child;`); the path goes
//! to the longest of its prefixes that is a file. So a child that imports `super::Counts` and a parent that
//! uses (or re-exports) the child are a cycle. `main.rs` is the binary: its paths through
//! the library's name count as edges into `src/`.
//!
//! Not counted: comments (doc comments too), string and character literals and `$crate`
//! in macros. Test code (every item under `#[cfg(test)]`, the `mod tests { .. }` blocks, and
//! every file declared under one, `#[cfg(test)] mod tests;`: `tests.rs`, `tests/**`) counts
//! for the layers: no top-level module imports another in a ring, and no file imports a
//! higher layer, test code included (a test that reaches higher lives with the higher
//! module's tests or in `tests/integration/`). The file-level ring check leaves test code
//! out: a test file importing its parent closes no ring that matters.
//!
//! A small tokenizer is enough for this (no parser dependency): the crate's own paths are
//! written as `use` trees and `crate::`/`super::`/`self::`/`child::` paths, never built by
//! macros. A failure prints every cycle with each edge's first line, or every import against
//! the layer order, or every ring of top-level modules with each edge's first line; a new
//! top-level module fails until it is placed in [`LAYERS`]. Planted crates check the
//! checker: a ring through test code only is found, exactly, and a crate without one has
//! none.
//!
//! The same tokens also measure every function of `src/`: none is longer than
//! [`MAX_FN_LINES`] (a function that needs a scroll bar is several).

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::Path;

/// The layers from the bottom up, each with its top-level modules (`main` is `src/main.rs`).
/// A file may import files of its own layer and of lower ones; within a layer the file-level
/// graph has no cycle either. A new module of `src/lib.rs` must be placed here.
const LAYERS: &[(&str, &[&str])] = &[
    (
        "leaf types and errors",
        &[
            "error",
            "graph",
            "datapath",
            "isa",
            "json",
            "tolerance",
            "progress",
            "testkit",
            "memory",
        ],
    ),
    ("the architecture file", &["config"]),
    (
        "the model",
        &[
            "camera",
            "lembo",
            "discoid",
            "scene",
            "raster",
            "rop",
            "frame",
            "reference",
        ],
    ),
    ("the timed pipeline", &["pipeline"]),
    ("cost", &["cost"]),
    (
        "jobs and reports",
        &["report", "output", "job", "compare", "sweep", "plot"],
    ),
    ("the command", &["main"]),
];

/// The binary's file, named by its module in [`LAYERS`].
const MAIN: &str = "main";
/// The binary's file, relative to `src/`.
const MAIN_FILE: &str = "main.rs";

#[test]
fn src_has_no_import_cycle() {
    let graph = Graph::of_src();
    let cycles = graph.cycles();
    assert!(
        cycles.is_empty(),
        "{} import cycles among src/ files (each file's first line that makes an edge):\n{}",
        cycles.len(),
        graph.describe_cycles(&cycles)
    );
}

/// This crate's `src/`, test code included.
fn src_with_tests() -> Graph {
    Graph::of_src_with_tests()
}

/// Top-level modules import one another in no ring, test code included: a test that
/// reaches a higher module lives in that module's tests or in `tests/integration/`.
#[test]
fn no_cycle_among_top_level_modules_test_code_included() {
    let graph = src_with_tests();
    let cycles = graph.module_cycles();
    assert!(
        cycles.is_empty(),
        "{} cycles among src/'s top-level modules, test code included (each edge's first line):\n{}",
        cycles.len(),
        graph.describe_module_cycles(&cycles)
    );
}

/// Test code counts: a test that names a higher module lives in that module's tests or in
/// `tests/integration/`.
#[test]
fn no_file_imports_a_higher_layer_test_code_included() {
    let graph = src_with_tests();
    let back = graph.back_edges(LAYERS);
    assert!(
        back.is_empty(),
        "{} imports against the layer order, test code included (ARCHITECTURE.md; LAYERS in tests/layers.rs):\n{}",
        back.len(),
        back.join("\n")
    );
}

#[test]
fn every_module_has_a_layer() {
    let graph = Graph::of_src();
    let unplaced = graph.unplaced(LAYERS);
    assert!(unplaced.is_empty(), "{}", unplaced.join("\n"));
}

/// The graph is read whole: a tokenizer that lost the `use` trees would find no cycle.
#[test]
fn the_graph_has_the_crates_files_and_imports() {
    let graph = Graph::of_src();
    let edges: usize = graph.edges.values().map(BTreeMap::len).sum();
    assert!(graph.edges.len() >= 60, "{} files", graph.edges.len());
    assert!(edges >= 300, "{edges} edges");
    assert!(
        graph.edges[MAIN_FILE].len() >= 5,
        "main.rs imports too little"
    );
}

/// The most lines a function of `src/` may take, from its `fn` line to its closing brace
/// (ARCHITECTURE.md's invariant; test code included).
const MAX_FN_LINES: usize = 150;

#[test]
fn no_function_is_longer_than_150_lines() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    read_tree(&src, &src, &mut files);
    let mut measured = 0;
    let mut long = Vec::new();
    for (path, text) in &files {
        for (name, line, lines) in fn_lengths(text) {
            measured += 1;
            if lines > MAX_FN_LINES {
                long.push(format!("src/{path}:{line} fn {name}: {lines} lines"));
            }
        }
    }
    assert!(measured >= 1000, "only {measured} functions measured");
    assert!(
        long.is_empty(),
        "functions over {MAX_FN_LINES} lines (split them by the steps their comments name):\n{}",
        long.join("\n")
    );
}

/// The most lines a product function may take (test code apart): longer ones are the
/// flat checklists ARCHITECTURE.md names under "Functions over 100 lines", by their path
/// in backticks (`job::RenderJob::validate`), whose last part is the function's name.
const MAX_PRODUCT_FN_LINES: usize = 100;

#[test]
fn no_product_function_is_longer_than_100_lines_but_the_named_checklists() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let map = std::fs::read_to_string(root.join("ARCHITECTURE.md")).unwrap();
    let allowed = named_long_functions(&map);
    let src = root.join("src");
    let mut files = Vec::new();
    read_tree(&src, &src, &mut files);
    let mut long = Vec::new();
    let mut measured = 0;
    for (path, text) in &files {
        if path.ends_with("tests.rs") || path.contains("/tests/") {
            continue;
        }
        let tests = test_lines(text);
        for (name, line, lines) in fn_lengths(text) {
            if tests.iter().any(|&(a, b)| (a..=b).contains(&line)) {
                continue;
            }
            measured += 1;
            if lines > MAX_PRODUCT_FN_LINES && !allowed.contains(&name) {
                long.push(format!("src/{path}:{line} fn {name}: {lines} lines"));
            }
        }
    }
    assert!(
        measured >= 1000,
        "only {measured} product functions measured"
    );
    assert!(
        long.is_empty(),
        "product functions over {MAX_PRODUCT_FN_LINES} lines that ARCHITECTURE.md does not \
         name as a flat checklist (split them by their steps):\n{}",
        long.join("\n")
    );
}

/// The control: a long function in test code is not a product function, and a named
/// checklist is read from the map's section.
#[test]
fn the_product_measure_skips_test_code_and_reads_the_named_checklists() {
    let body: String = (0..120).map(|i| format!("    let x{i} = {i};\n")).collect();
    let text = format!("fn product() {{\n{body}}}\n#[cfg(test)]\nmod tests {{\n    fn long() {{\n{body}    }}\n}}\n");
    let tests = test_lines(&text);
    let product: Vec<String> = fn_lengths(&text)
        .into_iter()
        .filter(|(_, line, _)| !tests.iter().any(|&(a, b)| (a..=b).contains(line)))
        .map(|(name, _, _)| name)
        .collect();
    assert_eq!(product, ["product"]);
    let map = "## Code map\n\n### Functions over 100 lines\n\n- `job::RenderJob::validate` (102 lines): why.\n\n## Layers\n- `not::this` (x).\n";
    assert_eq!(named_long_functions(map), ["validate"]);
}

/// The function names ARCHITECTURE.md allows over the limit: the last part of each
/// backticked path that starts an item of its "Functions over 100 lines" section.
fn named_long_functions(map: &str) -> Vec<String> {
    let Some(start) = map.find("### Functions over 100 lines") else {
        return Vec::new();
    };
    let section = &map[start..];
    let end = section[4..].find("\n#").map_or(section.len(), |e| e + 4);
    section[..end]
        .lines()
        .filter_map(|l| l.strip_prefix("- `"))
        .filter_map(|l| l.split('`').next())
        .filter_map(|path| path.rsplit("::").next())
        .map(str::to_string)
        .collect()
}

/// The lines (first, last) of `text`'s items under `#[cfg(test)]`; the whole file when it
/// says `#![cfg(test)]`.
fn test_lines(text: &str) -> Vec<(usize, usize)> {
    let tokens = tokenize(text);
    let mut out = Vec::new();
    let mut i = 0;
    while i < tokens.len() {
        match cfg_test_at(&tokens, i) {
            Some((_, true)) => return vec![(0, usize::MAX)],
            Some((after, false)) => {
                let end = skip_item(&tokens, after).min(tokens.len()) - 1;
                out.push((tokens[i].line, tokens[end.max(i)].line));
                i = end + 1;
            }
            None => i += 1,
        }
    }
    out
}

/// No product code outside `graph.rs` and the units' own files tests a unit kind by name:
/// what a kind is (shared, priced as DRAM, its rates, its design-point variant, a discoid
/// kind) is declared in the graph and read from there.
#[test]
fn no_product_code_tests_a_unit_kind_by_name_outside_the_graph() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    read_tree(&src, &src, &mut files);
    let mut found = Vec::new();
    for (path, text) in &files {
        let own = path == "graph.rs" || path.starts_with("pipeline/units/");
        if own || path.ends_with("tests.rs") || path.contains("/tests/") {
            continue;
        }
        let tests = test_lines(text);
        for (n, line) in text.lines().enumerate() {
            let in_test = tests.iter().any(|&(a, b)| (a..=b).contains(&(n + 1)));
            if !in_test && tests_a_kind(line) {
                found.push(format!("src/{path}:{}: {}", n + 1, line.trim()));
            }
        }
    }
    assert!(
        found.is_empty(),
        "unit kinds tested by name outside graph.rs (declare the fact in the graph):\n{}",
        found.join("\n")
    );
}

/// Whether a line compares or matches a `UnitKind` variant by name.
fn tests_a_kind(line: &str) -> bool {
    let code = line.split("//").next().unwrap_or_default();
    code.match_indices("UnitKind::").any(|(i, _)| {
        let before = code[..i].trim_end();
        let after = &code[i + "UnitKind::".len()..];
        let variant: String = after.chars().take_while(|c| c.is_alphanumeric()).collect();
        let rest = after[variant.len()..].trim_start();
        variant.starts_with(char::is_uppercase)
            && (before.ends_with("==")
                || before.ends_with("!=")
                || rest.starts_with("=>")
                || rest.starts_with('|')
                || (before.ends_with('(') && rest.starts_with(',') && code.contains("=>")))
    })
}

#[test]
fn tests_a_kind_finds_comparisons_and_match_arms_only() {
    for yes in [
        "if u.kind == UnitKind::Rop {",
        "UnitKind::Rop => 1,",
        "UnitKind::GeometryFetch | UnitKind::FrameBuffer => (vec![], vec![]),",
        "(UnitKind::Rop, _) => x,",
    ] {
        assert!(tests_a_kind(yes), "{yes}");
    }
    for no in [
        "const KIND: UnitKind = UnitKind::Rop;",
        "ops.add(UnitKind::Rop, Op::Mul, 1);",
        "// u.kind == UnitKind::Rop",
        "kinds: vec![UnitKind::Setup],",
    ] {
        assert!(!tests_a_kind(no), "{no}");
    }
}

/// The measure itself, on functions of known length: a body's lines counted from `fn` to
/// its closing brace, braces in strings and comments ignored, declarations without a body
/// and `fn` pointer types skipped.
#[test]
fn fn_lengths_counts_from_fn_to_the_closing_brace() {
    let body: String = (0..150)
        .map(|i| format!("    let x{i} = \"{{\"; // }}\n"))
        .collect();
    let text = format!(
        "trait T {{\n    fn declared(&self) -> u32;\n}}\n\
         fn long(f: fn(u32) -> u32) -> u32 {{\n{body}    f(1)\n}}\n\
         impl T for () {{\n    fn declared(&self) -> u32 {{\n        1\n    }}\n}}\n"
    );
    assert_eq!(
        fn_lengths(&text),
        [
            ("long".to_string(), 4, 153),
            ("declared".to_string(), 158, 3)
        ]
    );
}

/// Each function with a body in `text`: its name, the line of its `fn` and its length in
/// lines through its closing brace.
fn fn_lengths(text: &str) -> Vec<(String, usize, usize)> {
    let tokens = tokenize(text);
    let mut out = Vec::new();
    for i in 0..tokens.len().saturating_sub(1) {
        if tokens[i].text != "fn" || !is_ident(&tokens[i + 1].text) {
            continue;
        }
        // The body's brace, or the `;` of a declaration, outside the parameters.
        let mut depth = 0i32;
        let mut j = i + 2;
        while j < tokens.len() {
            match tokens[j].text.as_str() {
                "(" | "[" => depth += 1,
                ")" | "]" => depth -= 1,
                ";" | "{" if depth == 0 => break,
                _ => {}
            }
            j += 1;
        }
        if j == tokens.len() || tokens[j].text == ";" {
            continue;
        }
        let mut braces = 0i32;
        for t in &tokens[j..] {
            match t.text.as_str() {
                "{" => braces += 1,
                "}" => braces -= 1,
                _ => {}
            }
            if braces == 0 {
                let lines = t.line - tokens[i].line + 1;
                out.push((tokens[i + 1].text.clone(), tokens[i].line, lines));
                break;
            }
        }
    }
    out
}

/// The checker itself on a crate made up for it: one cycle (a child importing its parent,
/// which re-exports it), one back-edge, and imports it must not count (a comment, a string,
/// a raw string, a test module, a test-only file, `$crate`).
#[test]
fn the_checker_finds_a_planted_cycle_and_back_edge_and_nothing_else() {
    let files = [
        ("lib.rs", "pub mod a;\npub mod high;\npub mod low;\n"),
        (
            "a/mod.rs",
            "mod b;\npub use b::B;\npub struct A;\n#[cfg(test)]\nmod tests;\n",
        ),
        ("a/b.rs", "use super::A;\npub struct B(A);\n"),
        ("a/tests.rs", "use crate::high::Thing;\n"),
        (
            "low.rs",
            "/* crate::a::A, /* nested */ crate::a::A */\n\
             pub fn f<'a>(x: &'a str) -> char {\n\
             \x20   let _ = (\"crate::a::A\", r#\"self::a\"#, b'\\'');\n\
             \x20   crate::high::Thing::new(x)\n\
             }\n\
             macro_rules! m { () => { $crate::a::A } }\n",
        ),
        (
            "high.rs",
            "//! Uses crate::low in a doc comment only.\n\
             pub struct Thing;\n\
             #[cfg(test)]\n\
             mod tests {\n    use crate::low::f;\n}\n",
        ),
        ("main.rs", "use demo::high::Thing;\nfn main() {}\n"),
    ];
    let graph = Graph::new(
        "demo",
        files.iter().map(|&(p, t)| (p.to_string(), t.to_string())),
    );
    let edges: Vec<String> = graph
        .edges
        .iter()
        .flat_map(|(f, ts)| ts.keys().map(move |t| format!("{f} -> {t}")))
        .collect();
    assert_eq!(
        edges,
        [
            "a/b.rs -> a/mod.rs",
            "a/mod.rs -> a/b.rs",
            "low.rs -> high.rs",
            "main.rs -> high.rs",
        ]
    );
    let cycles = graph.cycles();
    assert_eq!(cycles, [vec!["a/b.rs".to_string(), "a/mod.rs".to_string()]]);
    assert!(graph
        .describe_cycles(&cycles)
        .contains("a/b.rs -> a/mod.rs   (src/a/b.rs:1: use super::A;)"));
    let layers: &[(&str, &[&str])] = &[
        ("bottom", &["low"]),
        ("middle", &["a"]),
        ("top", &["high", "main"]),
    ];
    assert_eq!(
        graph.back_edges(layers),
        ["src/low.rs (bottom) imports src/high.rs (top): line 4: crate::high::Thing::new(x)"]
    );
    assert!(graph.unplaced(layers).is_empty());
    let short: &[(&str, &[&str])] = &[("all", &["a", "low", "gone"])];
    assert_eq!(
        graph.unplaced(short),
        [
            "module `high` of src/lib.rs has no layer in LAYERS (tests/layers.rs)",
            "src/main.rs (`main`) has no layer in LAYERS (tests/layers.rs)",
            "LAYERS names `gone`, which src/lib.rs does not declare",
        ]
    );
}

/// The module checker on crates made up for it: a cycle between two top-level modules
/// through test code only (a test-only file of `low` names `high`, which imports `low`) is
/// found with test code counted, exactly, and not without; an inline test module's import
/// counts too; the same crate whose test names only its own module has no cycle.
#[test]
fn the_module_checker_finds_a_cycle_through_test_code_only() {
    let crate_with = |low_test: &str| {
        let files = [
            (
                "lib.rs",
                "pub mod high;\npub mod low;\npub mod mid;\n".to_string(),
            ),
            (
                "low/mod.rs",
                "pub struct L;\n#[cfg(test)]\nmod tests;\n".to_string(),
            ),
            ("low/tests.rs", low_test.to_string()),
            (
                "high.rs",
                "use crate::low::L;\npub struct H(L);\n".to_string(),
            ),
            (
                "mid.rs",
                "pub struct M;\n#[cfg(test)]\nmod tests {\n    use crate::high::H;\n}\n"
                    .to_string(),
            ),
        ];
        files.map(|(p, t)| (p.to_string(), t))
    };
    let planted = crate_with("use super::L;\nuse crate::high::H;\n");
    let graph = Graph::with_tests("demo", planted.clone());
    let cycles = graph.module_cycles();
    assert_eq!(cycles, [vec!["high".to_string(), "low".to_string()]]);
    let described = graph.describe_module_cycles(&cycles);
    assert!(
        described.contains("low -> high   (src/low/tests.rs:2: use crate::high::H;)"),
        "{described}"
    );
    assert!(described.contains("high -> low   (src/high.rs:1: use crate::low::L;)"));
    assert!(
        graph.modules()["mid"].contains_key("high"),
        "inline test module"
    );
    let layers: &[(&str, &[&str])] = &[("bottom", &["low", "mid"]), ("top", &["high"])];
    assert_eq!(
        graph.back_edges(layers),
        [
            "src/low/tests.rs (bottom) imports src/high.rs (top): line 2: use crate::high::H;",
            "src/mid.rs (bottom) imports src/high.rs (top): line 4: use crate::high::H;",
        ]
    );
    let shipped = Graph::new("demo", planted);
    assert!(shipped.module_cycles().is_empty());
    assert!(shipped.back_edges(layers).is_empty());
    let clean = Graph::with_tests("demo", crate_with("use super::L;\n"));
    assert!(
        clean.module_cycles().is_empty(),
        "{:?}",
        clean.module_cycles()
    );
    assert_eq!(
        clean.without(&["mid"]).back_edges(layers),
        Vec::<String>::new()
    );
}

/// The file-level import graph of a crate's `src/`, test code left out.
struct Graph {
    /// Every non-test file (relative to `src/`) and the files it imports, each with the
    /// first line that does.
    edges: BTreeMap<String, BTreeMap<String, Line>>,
    /// The top-level modules `lib.rs` declares.
    top_level: Vec<String>,
}

/// A line of a file: its number and text.
#[derive(Clone, Debug)]
struct Line {
    number: usize,
    text: String,
}

impl Graph {
    /// This crate's `src/`.
    fn of_src() -> Graph {
        Graph::new(&lib_name(), src_files())
    }

    /// This crate's `src/`, test code included.
    fn of_src_with_tests() -> Graph {
        Graph::with_tests(&lib_name(), src_files())
    }

    /// The graph of the files (path relative to `src/`, text), test code left out;
    /// `lib_name` is how `main.rs` names the library.
    fn new(lib_name: &str, files: impl IntoIterator<Item = (String, String)>) -> Graph {
        Graph::build(lib_name, files, false)
    }

    /// The same graph with test code in: the items under `#[cfg(test)]` and the files
    /// declared under it are read as any other.
    fn with_tests(lib_name: &str, files: impl IntoIterator<Item = (String, String)>) -> Graph {
        Graph::build(lib_name, files, true)
    }

    fn build(
        lib_name: &str,
        files: impl IntoIterator<Item = (String, String)>,
        tests: bool,
    ) -> Graph {
        let scans: BTreeMap<String, (String, Scan)> = files
            .into_iter()
            .map(|(path, text)| {
                let scan = Scan::of(&text, &module_of(&path), tests);
                (path, (text, scan))
            })
            .collect();
        let mut test_roots = BTreeSet::new();
        for (path, (_, scan)) in &scans {
            let module = module_of(path);
            if scan.test_only {
                test_roots.insert(module.clone());
            }
            for child in &scan.test_children {
                test_roots.insert([module.clone(), vec![child.clone()]].concat());
            }
        }
        let is_test = |m: &[String]| !tests && test_roots.iter().any(|r| m.starts_with(r));
        let modules: BTreeMap<Vec<String>, &str> = scans
            .keys()
            .filter(|p| *p != MAIN_FILE && !is_test(&module_of(p)))
            .map(|p| (module_of(p), p.as_str()))
            .collect();
        let mut edges = BTreeMap::new();
        for (path, (text, scan)) in &scans {
            if !(path == MAIN_FILE || modules.values().any(|p| p == path)) {
                continue;
            }
            let lines: Vec<&str> = text.lines().collect();
            let own = module_of(path);
            let mut targets = BTreeMap::new();
            for r in &scan.refs {
                let full = if path == MAIN_FILE {
                    match r.segments.split_first() {
                        Some((first, rest)) if first == lib_name => Some(rest.to_vec()),
                        _ => None,
                    }
                } else {
                    resolve(&r.segments, &r.scope, &modules)
                };
                let Some(full) = full else { continue };
                let Some(target) = (0..=full.len()).rev().find_map(|k| modules.get(&full[..k]))
                else {
                    continue;
                };
                if module_of(target) != own {
                    targets.entry(target.to_string()).or_insert_with(|| Line {
                        number: r.line,
                        text: lines[r.line - 1].trim().to_string(),
                    });
                }
            }
            edges.insert(path.clone(), targets);
        }
        let top_level = scans.get("lib.rs").map_or(Vec::new(), |(_, scan)| {
            scan.children
                .iter()
                .filter(|c| tests || !scan.test_children.contains(c))
                .cloned()
                .collect()
        });
        Graph { edges, top_level }
    }

    /// The strongly connected components of more than one file, each sorted, in order.
    fn cycles(&self) -> Vec<Vec<String>> {
        cycles_of(&self.edges)
    }

    /// Each cycle's files, then its edges with the line that makes each.
    fn describe_cycles(&self, cycles: &[Vec<String>]) -> String {
        let mut out = String::new();
        for cycle in cycles {
            writeln!(out, "cycle of {} files: {}", cycle.len(), cycle.join(", ")).unwrap();
            for from in cycle {
                for (to, line) in &self.edges[from] {
                    if cycle.contains(to) {
                        writeln!(
                            out,
                            "    {from} -> {to}   (src/{from}:{}: {})",
                            line.number, line.text
                        )
                        .unwrap();
                    }
                }
            }
        }
        out
    }

    /// This graph without the files of the top-level modules `modules` and the edges into
    /// them.
    fn without(mut self, modules: &[&str]) -> Graph {
        let out = |f: &str| top_level_of(f).is_some_and(|m| modules.contains(&m.as_str()));
        self.edges.retain(|f, _| !out(f));
        for targets in self.edges.values_mut() {
            targets.retain(|t, _| !out(t));
        }
        self
    }

    /// The graph of the top-level modules (`main` for the binary): A -> B when a file of A
    /// imports a file of B, with the first such file and line.
    fn modules(&self) -> BTreeMap<String, BTreeMap<String, String>> {
        let mut modules: BTreeMap<String, BTreeMap<String, String>> = BTreeMap::new();
        for (from, targets) in &self.edges {
            let Some(a) = top_level_of(from) else {
                continue;
            };
            let out = modules.entry(a.clone()).or_default();
            for (to, line) in targets {
                match top_level_of(to) {
                    Some(b) if b != a => {
                        out.entry(b).or_insert_with(|| {
                            format!("src/{from}:{}: {}", line.number, line.text)
                        });
                    }
                    _ => {}
                }
            }
        }
        modules
    }

    /// The cycles among the top-level modules, each sorted, in order.
    fn module_cycles(&self) -> Vec<Vec<String>> {
        cycles_of(&self.modules())
    }

    /// Each module cycle, then its edges with the first line that makes each.
    fn describe_module_cycles(&self, cycles: &[Vec<String>]) -> String {
        let modules = self.modules();
        let mut out = String::new();
        for cycle in cycles {
            writeln!(
                out,
                "cycle of {} modules: {}",
                cycle.len(),
                cycle.join(", ")
            )
            .unwrap();
            for from in cycle {
                for (to, line) in &modules[from] {
                    if cycle.contains(to) {
                        writeln!(out, "    {from} -> {to}   ({line})").unwrap();
                    }
                }
            }
        }
        out
    }

    /// Every edge from a file into a higher layer than its own, with its line.
    fn back_edges(&self, layers: &[(&str, &[&str])]) -> Vec<String> {
        let layer = |file: &str| {
            let top = top_level_of(file)?;
            layers
                .iter()
                .enumerate()
                .find(|(_, (_, modules))| modules.contains(&top.as_str()))
                .map(|(i, (name, _))| (i, *name))
        };
        let mut back = Vec::new();
        for (from, targets) in &self.edges {
            for (to, line) in targets {
                if let (Some((lf, from_name)), Some((lt, to_name))) = (layer(from), layer(to)) {
                    if lt > lf {
                        back.push(format!(
                            "src/{from} ({from_name}) imports src/{to} ({to_name}): line {}: {}",
                            line.number, line.text
                        ));
                    }
                }
            }
        }
        back
    }

    /// The top-level modules (and the binary) missing from `layers`, and the names in
    /// `layers` that are neither.
    fn unplaced(&self, layers: &[(&str, &[&str])]) -> Vec<String> {
        let placed: Vec<&str> = layers.iter().flat_map(|(_, m)| m.iter().copied()).collect();
        let mut modules: Vec<&str> = self.top_level.iter().map(String::as_str).collect();
        if self.edges.contains_key(MAIN_FILE) {
            modules.push(MAIN);
        }
        let mut out: Vec<String> = modules
            .iter()
            .filter(|m| !placed.contains(m))
            .map(|&m| match m {
                MAIN => "src/main.rs (`main`) has no layer in LAYERS (tests/layers.rs)".to_string(),
                m => format!("module `{m}` of src/lib.rs has no layer in LAYERS (tests/layers.rs)"),
            })
            .collect();
        out.extend(
            placed
                .iter()
                .filter(|m| !modules.contains(m))
                .map(|m| format!("LAYERS names `{m}`, which src/lib.rs does not declare")),
        );
        out
    }
}

/// The strongly connected components of more than one node of a graph whose every node is
/// a key, each sorted, in order.
fn cycles_of<V>(edges: &BTreeMap<String, BTreeMap<String, V>>) -> Vec<Vec<String>> {
    let adjacent: BTreeMap<&str, Vec<&str>> = edges
        .iter()
        .map(|(v, ws)| (v.as_str(), ws.keys().map(String::as_str).collect()))
        .collect();
    let mut tarjan = Tarjan {
        adjacent: &adjacent,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        components: Vec::new(),
    };
    for &v in adjacent.keys() {
        if !tarjan.index.contains_key(v) {
            tarjan.visit(v);
        }
    }
    let mut cycles: Vec<Vec<String>> = tarjan
        .components
        .into_iter()
        .filter(|c| c.len() > 1)
        .map(|c| {
            let mut c: Vec<String> = c.into_iter().map(str::to_string).collect();
            c.sort();
            c
        })
        .collect();
    cycles.sort();
    cycles
}

/// Tarjan's strongly connected components.
struct Tarjan<'g> {
    adjacent: &'g BTreeMap<&'g str, Vec<&'g str>>,
    index: BTreeMap<&'g str, usize>,
    low: BTreeMap<&'g str, usize>,
    stack: Vec<&'g str>,
    components: Vec<Vec<&'g str>>,
}

impl<'g> Tarjan<'g> {
    fn visit(&mut self, v: &'g str) {
        let adjacent = self.adjacent;
        let n = self.index.len();
        self.index.insert(v, n);
        self.low.insert(v, n);
        self.stack.push(v);
        for &w in adjacent.get(v).into_iter().flatten() {
            if !self.index.contains_key(w) {
                self.visit(w);
                let low = self.low[v].min(self.low[w]);
                self.low.insert(v, low);
            } else if self.stack.contains(&w) {
                let low = self.low[v].min(self.index[w]);
                self.low.insert(v, low);
            }
        }
        if self.low[v] == self.index[v] {
            let at = self
                .stack
                .iter()
                .rposition(|&x| x == v)
                .expect("v is on the stack");
            self.components.push(self.stack.split_off(at));
        }
    }
}

/// How `main.rs` names the library.
fn lib_name() -> String {
    env!("CARGO_PKG_NAME").replace('-', "_")
}

/// Every `.rs` file of this crate's `src/`.
fn src_files() -> Vec<(String, String)> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    read_tree(&src, &src, &mut files);
    files
}

/// Every `.rs` file under `dir`, as (path relative to `root` with `/`, text).
fn read_tree(root: &Path, dir: &Path, out: &mut Vec<(String, String)>) {
    for entry in std::fs::read_dir(dir).expect("src/ is readable") {
        let path = entry.expect("src/ is readable").path();
        if path.is_dir() {
            read_tree(root, &path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            let rel = path.strip_prefix(root).expect("under src/");
            let rel: Vec<String> = rel
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            let text = std::fs::read_to_string(&path).expect("a source file is UTF-8");
            out.push((rel.join("/"), text));
        }
    }
}

/// The module path of a file: `raster/triangle/setup.rs` and `raster/triangle/setup/mod.rs`
/// are `raster::triangle::setup`; `lib.rs` (and `main.rs`, its own crate) the root.
fn module_of(path: &str) -> Vec<String> {
    let mut parts: Vec<String> = path
        .trim_end_matches(".rs")
        .split('/')
        .map(str::to_string)
        .collect();
    if parts.last().is_some_and(|p| p == "mod") || parts == ["lib"] || parts == [MAIN] {
        parts.pop();
    }
    parts
}

/// The top-level module a file belongs to (`main` for the binary); None for `lib.rs`.
fn top_level_of(path: &str) -> Option<String> {
    if path == MAIN_FILE {
        return Some(MAIN.to_string());
    }
    module_of(path).into_iter().next()
}

/// The absolute module path `segments` names from `scope`; None for a path that leaves
/// the crate (`std::`, a dependency) or starts at a local name that is not a child module.
fn resolve(
    segments: &[String],
    scope: &[String],
    modules: &BTreeMap<Vec<String>, &str>,
) -> Option<Vec<String>> {
    let (first, rest) = segments.split_first()?;
    match first.as_str() {
        "crate" => Some(rest.to_vec()),
        "self" | "super" => {
            let mut at = scope.to_vec();
            let mut k = 0;
            while k < segments.len() && matches!(segments[k].as_str(), "self" | "super") {
                if segments[k] == "super" {
                    at.pop();
                }
                k += 1;
            }
            Some([at, segments[k..].to_vec()].concat())
        }
        _ => {
            let child = [scope.to_vec(), vec![first.clone()]].concat();
            modules
                .contains_key(&child)
                .then(|| [scope.to_vec(), segments.to_vec()].concat())
        }
    }
}

/// What one file says about modules: the children it declares (`mod x;`), those it
/// declares under `#[cfg(test)]`, whether it is test code as a whole (`#![cfg(test)]`),
/// and every path it names outside test code.
struct Scan {
    children: Vec<String>,
    test_children: Vec<String>,
    test_only: bool,
    refs: Vec<Ref>,
}

/// A path as written, the module it is written in (inline `mod x { .. }` blocks included)
/// and its line.
struct Ref {
    segments: Vec<String>,
    scope: Vec<String>,
    line: usize,
}

impl Scan {
    /// The scan of one file; with `tests`, test code is read as any other (its `mod`
    /// declarations are still listed as test children).
    fn of(text: &str, module: &[String], tests: bool) -> Scan {
        let tokens = tokenize(text);
        let t = |i: usize| tokens.get(i).map_or("", |t: &Token| t.text.as_str());
        let mut scan = Scan {
            children: Vec::new(),
            test_children: Vec::new(),
            test_only: false,
            refs: Vec::new(),
        };
        // Inline modules open: their path and the brace depth outside them.
        let mut scopes: Vec<(Vec<String>, usize)> = vec![(module.to_vec(), usize::MAX)];
        let mut depth = 0usize;
        let mut i = 0;
        while i < tokens.len() {
            if let Some((after, inner)) = cfg_test_at(&tokens, i) {
                if tests {
                    scan.test_only |= inner;
                    if let Some(child) = declared_mod(&tokens, after) {
                        scan.test_children.push(child.to_string());
                    }
                    i = after;
                    continue;
                }
                if inner {
                    scan.test_only = true;
                    scan.refs.clear();
                    return scan;
                }
                if let Some(child) = declared_mod(&tokens, after) {
                    scan.test_children.push(child.to_string());
                    scan.children.push(child.to_string());
                }
                i = skip_item(&tokens, after);
                continue;
            }
            let scope = scopes.last().expect("the file's scope").0.clone();
            let (word, prev, next) = (t(i), if i > 0 { t(i - 1) } else { "" }, t(i + 1));
            match word {
                "{" => depth += 1,
                "}" => {
                    depth = depth.saturating_sub(1);
                    if scopes.last().is_some_and(|s| s.1 == depth) {
                        scopes.pop();
                    }
                }
                "mod" if is_ident(next) && t(i + 2) == "{" => {
                    scopes.push(([scope, vec![next.to_string()]].concat(), depth));
                }
                "mod" if is_ident(next) && t(i + 2) == ";" && scopes.len() == 1 => {
                    scan.children.push(next.to_string());
                }
                "use" if prev != "::" => {
                    let line = tokens[i].line;
                    let mut paths = Vec::new();
                    i = use_tree(&tokens, i + 1, &[], &mut paths);
                    scan.refs.extend(paths.into_iter().map(|segments| Ref {
                        segments,
                        scope: scope.clone(),
                        line,
                    }));
                    continue;
                }
                _ if is_ident(word) && next == "::" && !matches!(prev, "::" | "$" | ".") => {
                    let line = tokens[i].line;
                    let mut segments = vec![word.to_string()];
                    let mut j = i + 2;
                    while is_ident(t(j)) {
                        segments.push(t(j).to_string());
                        j += 1;
                        if t(j) != "::" {
                            break;
                        }
                        j += 1;
                    }
                    scan.refs.push(Ref {
                        segments,
                        scope,
                        line,
                    });
                    i = j;
                    continue;
                }
                _ => {}
            }
            i += 1;
        }
        scan
    }
}

/// If `#[cfg(test)]` or `#![cfg(test)]` starts at `i`: the index after it, and whether it
/// is the inner form (the whole file).
fn cfg_test_at(tokens: &[Token], i: usize) -> Option<(usize, bool)> {
    if tokens[i].text != "#" {
        return None;
    }
    let inner = tokens.get(i + 1).is_some_and(|t| t.text == "!");
    let start = i + 1 + usize::from(inner);
    let words: Vec<&str> = tokens
        .iter()
        .skip(start)
        .take(6)
        .map(|t| t.text.as_str())
        .collect();
    (words == ["[", "cfg", "(", "test", ")", "]"]).then_some((start + 6, inner))
}

/// The module an item starting at `i` declares from its own file (`mod x;`, after any
/// attributes and visibility), if it does.
fn declared_mod(tokens: &[Token], i: usize) -> Option<&str> {
    let end = skip_item(tokens, i);
    let item: Vec<&str> = tokens[i..end].iter().map(|t| t.text.as_str()).collect();
    if item.last() != Some(&";") {
        return None;
    }
    let m = item.iter().position(|&w| w == "mod")?;
    item.get(m + 1).copied()
}

/// The index after the item starting at `i`: after its `;` or its closing brace, or at a
/// bracket that closes what encloses it.
fn skip_item(tokens: &[Token], mut i: usize) -> usize {
    let mut depth = 0usize;
    let mut braced = false;
    while i < tokens.len() {
        match tokens[i].text.as_str() {
            "(" | "[" | "{" => {
                depth += 1;
                braced |= tokens[i].text == "{";
            }
            ")" | "]" | "}" if depth == 0 => return i,
            ")" | "]" | "}" => {
                depth -= 1;
                if depth == 0 && braced && tokens[i].text == "}" {
                    return i + 1;
                }
            }
            ";" if depth == 0 => return i + 1,
            _ => {}
        }
        i += 1;
    }
    i
}

/// Expands the use tree starting at `i` (after `prefix`) into full paths; returns the index
/// after it. A path from the extern prelude (`::std`) is not the crate's.
fn use_tree(
    tokens: &[Token],
    mut i: usize,
    prefix: &[String],
    out: &mut Vec<Vec<String>>,
) -> usize {
    let t = |i: usize| tokens.get(i).map_or("", |t| t.text.as_str());
    if t(i) == "::" {
        return skip_item(tokens, i) - 1;
    }
    let mut segments = prefix.to_vec();
    loop {
        match t(i) {
            "{" => {
                i += 1;
                while !matches!(t(i), "}" | "") {
                    i = use_tree(tokens, i, &segments, out);
                    if t(i) == "," {
                        i += 1;
                    }
                }
                return i + 1;
            }
            "*" => {
                out.push(segments);
                return i + 1;
            }
            word if is_ident(word) => {
                // `a::{self, B}`: `self` names `a` itself.
                if word != "self" || segments.is_empty() {
                    segments.push(word.to_string());
                }
                i += 1;
                if t(i) == "::" {
                    i += 1;
                    continue;
                }
                if t(i) == "as" {
                    i += 2;
                }
                out.push(segments);
                return i;
            }
            _ => return i,
        }
    }
}

/// A token: an identifier or keyword, `::`, one punctuation character, or `"` for any
/// string or character literal (their contents are never paths).
#[derive(Debug)]
struct Token {
    text: String,
    line: usize,
}

fn is_ident(word: &str) -> bool {
    word.starts_with(|c: char| c.is_alphabetic() || c == '_')
}

/// The tokens of Rust source, comments and literal contents dropped.
fn tokenize(text: &str) -> Vec<Token> {
    let s: Vec<char> = text.chars().collect();
    let at = |i: usize| s.get(i).copied().unwrap_or('\0');
    let ident_char = |c: char| c.is_alphanumeric() || c == '_';
    let mut out = Vec::new();
    let (mut i, mut line) = (0, 1);
    let push = |out: &mut Vec<Token>, text: &str, line: usize| {
        out.push(Token {
            text: text.to_string(),
            line,
        })
    };
    while i < s.len() {
        let c = s[i];
        let start_line = line;
        if c == '\n' {
            line += 1;
            i += 1;
        } else if c.is_whitespace() {
            i += 1;
        } else if c == '/' && at(i + 1) == '/' {
            while i < s.len() && s[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && at(i + 1) == '*' {
            let mut depth = 0;
            while i < s.len() {
                if s[i] == '/' && at(i + 1) == '*' {
                    depth += 1;
                    i += 2;
                } else if s[i] == '*' && at(i + 1) == '/' {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    line += usize::from(s[i] == '\n');
                    i += 1;
                }
            }
        } else if let Some(open) = raw_string_at(&s, i) {
            // r"..", r#".."#, br"..": ends at the quote followed by as many hashes.
            let hashes = open - i - 1 - usize::from(c == 'b');
            let mut j = open + 1;
            while j < s.len() && !(s[j] == '"' && (1..=hashes).all(|h| at(j + h) == '#')) {
                line += usize::from(s[j] == '\n');
                j += 1;
            }
            push(&mut out, "\"", start_line);
            i = j + 1 + hashes;
        } else if c == '"' || (c == 'b' && at(i + 1) == '"') {
            let mut j = i + if c == 'b' { 2 } else { 1 };
            while j < s.len() && s[j] != '"' {
                line += usize::from(s[j] == '\n');
                j += if s[j] == '\\' { 2 } else { 1 };
            }
            push(&mut out, "\"", start_line);
            i = j + 1;
        } else if c == '\'' || (c == 'b' && at(i + 1) == '\'') {
            let j = i + if c == 'b' { 2 } else { 1 };
            if at(j) == '\\' {
                let mut k = j + 2;
                while k < s.len() && s[k] != '\'' {
                    k += 1;
                }
                push(&mut out, "\"", line);
                i = k + 1;
            } else if at(j + 1) == '\'' {
                push(&mut out, "\"", line);
                i = j + 2;
            } else {
                // A lifetime: the quote goes, its name is read as an identifier.
                i = j;
            }
        } else if c.is_alphabetic() || c == '_' {
            if c == 'r' && at(i + 1) == '#' && (at(i + 2).is_alphabetic() || at(i + 2) == '_') {
                i += 2;
            }
            let start = i;
            while i < s.len() && ident_char(s[i]) {
                i += 1;
            }
            let word: String = s[start..i].iter().collect();
            push(&mut out, &word, line);
        } else if c.is_ascii_digit() {
            while i < s.len() && ident_char(s[i]) {
                i += 1;
            }
            push(&mut out, "0", line);
        } else if c == ':' && at(i + 1) == ':' {
            push(&mut out, "::", line);
            i += 2;
        } else {
            push(&mut out, &c.to_string(), line);
            i += 1;
        }
    }
    out
}

/// If a raw string (`r"`, `r#"`, `br"`, ...) starts at `i`: the index of its opening quote.
fn raw_string_at(s: &[char], i: usize) -> Option<usize> {
    let mut j = match (s.get(i), s.get(i + 1)) {
        (Some('r'), _) => i + 1,
        (Some('b'), Some('r')) => i + 2,
        _ => return None,
    };
    while s.get(j) == Some(&'#') {
        j += 1;
    }
    (s.get(j) == Some(&'"')).then_some(j)
}
