//! Writes the list of the timed pipeline's units from the files of `src/pipeline/units/`, so
//! that adding a unit adds its file and no line to a list (ARCHITECTURE.md, "How to add a
//! unit"). Each file but `mod.rs` is one unit; the script writes a macro that lists each as
//! `module: Type`, the one type the file declares `impl<R: Real> Unit<R> for`, and
//! `pipeline/units/mod.rs` declares each a module and its type an entry of `bodies`. A file
//! that declares no such type, or two, stops the build naming the file.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Where the units live, from the package root.
const UNITS: &str = "src/pipeline/units";
/// What a unit file declares, verbatim, before its type's name.
const UNIT_IMPL: &str = "impl<R: Real> Unit<R> for ";

fn main() {
    println!("cargo::rerun-if-changed=build.rs");
    println!("cargo::rerun-if-changed={UNITS}");
    let root = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let units = unit_files(&root.join(UNITS));
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("set by cargo")).join("units.rs");
    std::fs::write(&out, generated(&units))
        .unwrap_or_else(|e| panic!("cannot write {}: {e}", out.display()));
}

/// Each unit file of `dir` as (module name, unit type), by module name.
fn unit_files(dir: &Path) -> Vec<(String, String)> {
    let entries =
        std::fs::read_dir(dir).unwrap_or_else(|e| panic!("cannot list {}: {e}", dir.display()));
    let mut units: Vec<(String, String)> = entries
        .map(|entry| entry.expect("a readable directory entry").path())
        .filter(|path| path.extension().is_some_and(|e| e == "rs"))
        .filter(|path| path.file_name().is_some_and(|n| n != "mod.rs"))
        .map(|path| {
            let module = path
                .file_stem()
                .expect("a file name")
                .to_string_lossy()
                .into_owned();
            (module, unit_type(&path))
        })
        .collect();
    units.sort();
    units
}

/// The one type `path` declares a unit, or a stop naming the file.
fn unit_type(path: &Path) -> String {
    let text = std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    let names: Vec<String> = text
        .lines()
        .filter_map(|line| line.strip_prefix(UNIT_IMPL))
        .map(|rest| {
            rest.chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect()
        })
        .collect();
    match names.as_slice() {
        [name] if !name.is_empty() => name.clone(),
        _ => panic!(
            "{}: a file of {UNITS} is one unit and declares exactly one `{UNIT_IMPL}Type {{` \
             at the start of a line; found {}",
            path.display(),
            names.len()
        ),
    }
}

/// The macro `pipeline/units/mod.rs` includes and calls with its own `declare!`: each unit
/// as `module: Type`. Names only, no paths: the modules resolve beside `mod.rs` in the
/// checkout being built.
fn generated(units: &[(String, String)]) -> String {
    let mut text = String::from("// Written by build.rs from the files of src/pipeline/units/.\n");
    text.push_str("macro_rules! each_unit {\n    ($declare:ident) => {\n        $declare! {\n");
    for (module, unit) in units {
        writeln!(text, "            {module}: {unit},").expect("writes to a String");
    }
    text.push_str("        }\n    };\n}\n");
    text
}
