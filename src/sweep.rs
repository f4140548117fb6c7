//! `lembo-sim sweep` and `sweep-merge` (DESIGN.md §7, issue 6): many runs of one spec file,
//! each a point of a parameter space on a scene, into one table.
//!
//! ```text
//!  spec.json ─► Spec::parse (shape, parameter values, grid expansion, keys)
//!            ─► Plan::load  (scenes, architectures, every run's RenderJob validated)
//!            ─► references (one per scene, shared) ─► runs on a rayon pool of --jobs threads
//!            ─► results.jsonl (one line per finished run, appended and flushed at once)
//!            ─► when all are done: results.jsonl sorted, results.csv, spec.json, plots
//! ```
//!
//! A spec (`sim/sweeps/README.md` documents the format) names scenes and a list of
//! *points*: a grid block is the cartesian product of its parameters' value lists (the first
//! parameter varies slowest), an explicit point gives one value per parameter, and the
//! points are the union of the blocks and then the explicit points, in that order (a point
//! met again adds its scenes to the first one's). Parameters are the render settings
//! (`path`, `k`, `tess`, `datapath`, `blend`, `threshold`) and any architecture field as
//! `arch.<dotted path>`; a block or point may restrict itself to some of the spec's scenes
//! with `scenes`. Every (point, scene) pair is a *run*; runs are numbered point-major in
//! that order, and each has a *key*: the scene as the spec writes it and the point's
//! parameters, sorted, in canonical form (`../../traces/sphere24.json|k=0.5|path="lembo"`).
//!
//! Everything is validated before the first run starts: the spec's shape, every value,
//! every combination, every scene and every point's architecture; a refused value names
//! the spec file, its field path (`grid[1].arch.rop.count[0]`) and the value.
//!
//! Resumption: a run's record is appended to `results.jsonl` as soon as it finishes, and a
//! sweep started again on the same directory skips the runs whose key is already there (a
//! truncated last line, from a kill mid-write, is dropped). `spec.json` in the directory
//! must then hold the same spec, and every record must belong to this spec and shard.
//! Sharding (`--shard I/N`) keeps the runs whose index is I modulo N; `sweep-merge` unions
//! the shards' records and writes what an unsharded run writes.
//!
//! Paths inside records (`report.scene.source`, `report.settings.arch_file`) are the
//! spec's own strings, so records do not depend on the directory a sweep ran from.

use crate::camera::{View, MAX_VIEWPORT_SIDE};
use crate::config::ArchConfig;
use crate::datapath::Datapath;
use crate::discoid::blend::BlendMode;
use crate::discoid::render::check_scene;
use crate::error::{parent_dir, read_text_file, Error, Result};
use crate::job::{
    check_tess_range, check_triangle_budget, render_reference, run_path, Mode, PrimitivePath,
    RenderJob, COMMAND_LINE, K_RANGE, MAX_HOST_THREADS,
};
use crate::output::write_files;
use crate::pipeline::graph::KINDS;
use crate::raster::PerspectiveTol;
use crate::reference::oracle::ReferenceImage;
use crate::report::Report;
use crate::scene::{parse_strict, Scene};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde::de::{self, MapAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize};
use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};
use std::fmt;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

/// The most runs (points × scenes) a spec may expand to: beyond it a sweep takes days, and
/// a typo in a grid should be refused rather than expanded.
pub const MAX_RUNS: usize = 100_000;
/// The most threads `--jobs` accepts; each run is one host thread (or `--host-threads`).
pub const MAX_JOBS: usize = 256;
/// Tolerance k of a point that sets none \[pixels\]: `render`'s default.
pub const DEFAULT_K_PX: f64 = 0.5;
/// The records file of a sweep directory.
pub const RESULTS_JSONL: &str = "results.jsonl";
/// The table of a sweep directory.
pub const RESULTS_CSV: &str = "results.csv";
/// The copy of the spec in a sweep directory.
pub const SPEC_JSON: &str = "spec.json";

/// The render settings a point can set, besides `arch.<field>`.
const SETTINGS: [&str; 7] = [
    "path",
    "k",
    "perspective_tol",
    "tess",
    "datapath",
    "blend",
    "threshold",
];
/// A block's or point's scene restriction: not a parameter.
const SCENES: &str = "scenes";
/// The prefix of architecture parameters.
const ARCH: &str = "arch.";

// ---- The file's shape ----------------------------------------------------------------

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SpecFile {
    name: String,
    scenes: Vec<String>,
    viewport: Option<[u32; 2]>,
    #[serde(default)]
    mode: ModeSpec,
    reference: Option<bool>,
    arch: Option<String>,
    grid: Option<Vec<Params>>,
    points: Option<Vec<Params>>,
}

#[derive(Deserialize, Default, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
enum ModeSpec {
    #[default]
    Timed,
    Functional,
}

/// A JSON object of parameters in the file's order (the order of a grid's product), with
/// duplicate names refused.
struct Params(Vec<(String, Value)>);

impl<'de> Deserialize<'de> for Params {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Params, D::Error> {
        struct Ordered;
        impl<'de> Visitor<'de> for Ordered {
            type Value = Params;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("an object of parameters")
            }
            fn visit_map<A: MapAccess<'de>>(
                self,
                mut map: A,
            ) -> std::result::Result<Params, A::Error> {
                let mut params: Vec<(String, Value)> = Vec::new();
                while let Some(name) = map.next_key::<String>()? {
                    if params.iter().any(|(n, _)| *n == name) {
                        return Err(de::Error::custom(format!("parameter `{name}` given twice")));
                    }
                    let value = map.next_value::<Value>()?;
                    params.push((name, value));
                }
                Ok(Params(params))
            }
        }
        d.deserialize_map(Ordered)
    }
}

// ---- The expanded spec ---------------------------------------------------------------

/// One parameter value, parsed.
#[derive(Clone, Debug)]
enum Setting {
    Path(PrimitivePath),
    K(f64),
    /// Setup's perspective tolerance: pixels or `"off"`.
    PerspectiveTol(PerspectiveTol),
    Tess(u32),
    Datapath(Datapath),
    Blend(BlendMode),
    Threshold(f64),
    /// An architecture field: its dotted path (without `arch.`) and value.
    Arch(String, Value),
}

/// A point of the parameter space.
#[derive(Clone, Debug)]
pub struct Point {
    /// Every parameter the point sets, by name, in canonical form (`k` and `threshold` as
    /// floats, `tess` as an integer, names as strings, architecture fields as the
    /// architecture serialises them).
    pub params: BTreeMap<String, Value>,
    /// The spec's scenes this point runs on, as indices into [`Spec::scenes`], ascending.
    pub scenes: Vec<usize>,
    /// Where the point was defined (`grid[1]`, `points[0]`), for errors.
    pub origin: String,
    /// Where each parameter's value was given (`grid[1].k[2]`), for errors.
    fields: BTreeMap<String, String>,
    settings: Vec<Setting>,
}

impl Point {
    fn setting<T>(&self, pick: impl Fn(&Setting) -> Option<T>) -> Option<T> {
        self.settings.iter().find_map(pick)
    }
    fn path(&self) -> Option<PrimitivePath> {
        self.setting(|s| match s {
            Setting::Path(p) => Some(*p),
            _ => None,
        })
    }
    fn arch_overrides(&self) -> impl Iterator<Item = (&str, &Value)> {
        self.settings.iter().filter_map(|s| match s {
            Setting::Arch(p, v) => Some((p.as_str(), v)),
            _ => None,
        })
    }
    /// The spec field of parameter `name`, or the point's origin.
    fn field(&self, name: &str) -> String {
        self.fields
            .get(name)
            .cloned()
            .unwrap_or_else(|| self.origin.clone())
    }
}

/// One run: a point on a scene.
#[derive(Clone, Debug)]
pub struct Run {
    /// Position in the sweep's fixed order (point-major, then the spec's scene order).
    pub index: usize,
    pub point: usize,
    pub scene: usize,
    /// The scene as the spec writes it and the sorted parameters:
    /// `../../traces/sphere24.json|k=0.5|path="lembo"`.
    pub key: String,
}

/// A parsed and expanded spec. Needs no file but the spec itself: `sweep-merge` uses it to
/// know every run's index and key.
#[derive(Debug)]
pub struct Spec {
    /// The spec file's name in messages.
    pub file: String,
    /// The spec's text, copied into `spec.json`.
    pub text: String,
    /// The spec as JSON, to compare two specs regardless of layout.
    pub value: Value,
    pub name: String,
    /// The scenes as the spec writes them (relative to its directory).
    pub scenes: Vec<String>,
    pub viewport: Option<(u32, u32)>,
    pub mode: Mode,
    /// Whether runs on scenes without discoids are measured against the exact reference.
    pub reference: bool,
    /// The base architecture as the spec writes it; None for the embedded baseline.
    pub arch: Option<String>,
    pub points: Vec<Point>,
    pub runs: Vec<Run>,
}

impl Spec {
    /// Parses and expands a spec; `file` names it in messages.
    pub fn parse(text: &str, file: &str) -> Result<Spec> {
        let f: SpecFile = parse_strict(text, file)?;
        let value: Value = serde_json::from_str(text).expect("the spec parsed once already");

        check_name(file, &f.name)?;
        if f.scenes.is_empty() {
            return Err(empty_list(file, "scenes"));
        }
        let viewport = match f.viewport {
            Some([w, h]) => {
                for (i, side) in [w, h].into_iter().enumerate() {
                    if !(1..=MAX_VIEWPORT_SIDE).contains(&side) {
                        return Err(Error::invalid(
                            file,
                            format!("viewport[{i}]"),
                            side,
                            format!("must be in 1..={MAX_VIEWPORT_SIDE} pixels"),
                        ));
                    }
                }
                Some((w, h))
            }
            None => None,
        };
        let mode = match f.mode {
            ModeSpec::Timed => Mode::Timed,
            ModeSpec::Functional => Mode::Functional,
        };
        if mode == Mode::Functional && f.arch.is_some() {
            return Err(Error::invalid(
                file,
                "arch",
                f.arch.as_deref().unwrap_or_default(),
                "only meaningful with mode timed",
            ));
        }

        let mut ex = Expander {
            file,
            scenes: &f.scenes,
            mode,
            arch_shape: serde_json::to_value(ArchConfig::default())
                .expect("the architecture serialises"),
            points: Vec::new(),
            by_params: BTreeMap::new(),
        };
        match (&f.grid, &f.points) {
            (None, None) => {
                return Err(Error::invalid(
                    file,
                    "grid",
                    "absent",
                    "a spec needs `grid` or `points` (or both)",
                ))
            }
            (Some(g), _) if g.is_empty() => return Err(empty_list(file, "grid")),
            (_, Some(p)) if p.is_empty() => return Err(empty_list(file, "points")),
            _ => {}
        }
        for (b, block) in f.grid.iter().flatten().enumerate() {
            ex.block(b, block)?;
        }
        for (p, point) in f.points.iter().flatten().enumerate() {
            ex.point(p, point)?;
        }

        let mut runs = Vec::new();
        for (p, point) in ex.points.iter().enumerate() {
            for &s in &point.scenes {
                runs.push(Run {
                    index: runs.len(),
                    point: p,
                    scene: s,
                    key: key(&f.scenes[s], &point.params),
                });
            }
        }
        if runs.len() > MAX_RUNS {
            return Err(too_many(file, "grid", runs.len()));
        }
        Ok(Spec {
            file: file.to_string(),
            text: text.to_string(),
            value,
            name: f.name,
            viewport,
            mode,
            reference: f.reference.unwrap_or(true),
            arch: f.arch,
            points: ex.points,
            runs,
            scenes: f.scenes,
        })
    }
}

/// The canonical key of a run.
fn key(scene: &str, params: &BTreeMap<String, Value>) -> String {
    let mut k = scene.to_string();
    for (name, value) in params {
        k.push('|');
        k.push_str(name);
        k.push('=');
        k.push_str(&value.to_string());
    }
    k
}

fn check_name(file: &str, name: &str) -> Result<()> {
    let ok = (1..=64).contains(&name.chars().count())
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    if ok {
        Ok(())
    } else {
        Err(Error::invalid(
            file,
            "name",
            format!("{name:?}"),
            "must be 1 to 64 of A-Z, a-z, 0-9, `_` and `-`: it names the output directory out/sweeps/<name>/",
        ))
    }
}

fn empty_list(file: &str, field: &str) -> Error {
    Error::invalid(file, field, "[]", "must not be an empty list")
}

fn too_many(file: &str, field: &str, runs: usize) -> Error {
    Error::invalid(
        file,
        field,
        format!("{runs} runs"),
        format!("a sweep may have at most {MAX_RUNS} runs (points x scenes)"),
    )
}

/// A parameter value as given: parsed, canonical, and where in the spec.
#[derive(Clone)]
struct Given {
    setting: Setting,
    canonical: Value,
    field: String,
}

/// Builds the points of a spec, block by block.
struct Expander<'a> {
    file: &'a str,
    scenes: &'a [String],
    mode: Mode,
    /// `ArchConfig::default()` as JSON: the shape every architecture file has, against
    /// which `arch.<field>` names and value types are checked.
    arch_shape: Value,
    points: Vec<Point>,
    by_params: BTreeMap<String, usize>,
}

impl Expander<'_> {
    fn block(&mut self, b: usize, block: &Params) -> Result<()> {
        let origin = format!("grid[{b}]");
        if block.0.is_empty() {
            return Err(Error::invalid(
                self.file,
                &origin,
                "{}",
                "a grid block needs at least one parameter",
            ));
        }
        let mut scenes = None;
        // Each axis: the parameter's name and its values with their fields.
        let mut axes: Vec<(String, Vec<Given>)> = Vec::new();
        let mut size = 1usize;
        for (name, list) in &block.0 {
            let field = format!("{origin}.{name}");
            let items = match list {
                Value::Array(items) if items.is_empty() => {
                    return Err(empty_list(self.file, &field))
                }
                Value::Array(items) => items,
                other => {
                    return Err(Error::Parse {
                        file: self.file.into(),
                        field,
                        message: format!(
                            "expected a list of values in a grid block, found {other}"
                        ),
                    })
                }
            };
            if name == SCENES {
                scenes = Some(self.scene_list(&field, items)?);
                continue;
            }
            let mut values = Vec::new();
            for (j, v) in items.iter().enumerate() {
                let field = format!("{field}[{j}]");
                let (setting, canonical) = self.setting(name, v, &field)?;
                values.push(Given {
                    setting,
                    canonical,
                    field,
                });
            }
            size = size.saturating_mul(values.len());
            if size > MAX_RUNS {
                return Err(too_many(self.file, &origin, size));
            }
            axes.push((name.clone(), values));
        }
        let scenes = scenes.unwrap_or_else(|| (0..self.scenes.len()).collect());
        // The odometer of the product: the last axis turns fastest.
        let mut at = vec![0usize; axes.len()];
        loop {
            let chosen = axes
                .iter()
                .zip(&at)
                .map(|((name, values), &i)| (name.clone(), values[i].clone()))
                .collect();
            self.add(&origin, chosen, &scenes)?;
            let mut axis = axes.len();
            loop {
                if axis == 0 {
                    return Ok(());
                }
                axis -= 1;
                at[axis] += 1;
                if at[axis] < axes[axis].1.len() {
                    break;
                }
                at[axis] = 0;
            }
        }
    }

    fn point(&mut self, p: usize, point: &Params) -> Result<()> {
        let origin = format!("points[{p}]");
        let mut scenes = None;
        let mut chosen = Vec::new();
        for (name, v) in &point.0 {
            let field = format!("{origin}.{name}");
            if name == SCENES {
                let items = match v {
                    Value::Array(items) if items.is_empty() => {
                        return Err(empty_list(self.file, &field))
                    }
                    Value::Array(items) => items,
                    other => {
                        return Err(Error::Parse {
                            file: self.file.into(),
                            field,
                            message: format!("expected a list of the spec's scenes, found {other}"),
                        })
                    }
                };
                scenes = Some(self.scene_list(&field, items)?);
                continue;
            }
            let (setting, canonical) = self.setting(name, v, &field)?;
            chosen.push((
                name.clone(),
                Given {
                    setting,
                    canonical,
                    field,
                },
            ));
        }
        let scenes = scenes.unwrap_or_else(|| (0..self.scenes.len()).collect());
        self.add(&origin, chosen, &scenes)
    }

    /// A `scenes` restriction: each must be one of the spec's scenes, as written there.
    fn scene_list(&self, field: &str, items: &[Value]) -> Result<Vec<usize>> {
        let mut out = BTreeSet::new();
        for (j, item) in items.iter().enumerate() {
            let field = format!("{field}[{j}]");
            let found = item
                .as_str()
                .and_then(|s| self.scenes.iter().position(|t| t == s));
            match found {
                Some(i) => {
                    out.insert(i);
                }
                None => {
                    return Err(Error::invalid(
                        self.file,
                        field,
                        item,
                        format!(
                            "must be one of the spec's scenes, as written there: {}",
                            self.scenes.join(", ")
                        ),
                    ))
                }
            }
        }
        Ok(out.into_iter().collect())
    }

    /// Adds a point, or its scenes to an equal point already added; checks the settings
    /// that do not depend on a scene.
    fn add(&mut self, origin: &str, chosen: Vec<(String, Given)>, scenes: &[usize]) -> Result<()> {
        let mut point = Point {
            params: BTreeMap::new(),
            scenes: scenes.to_vec(),
            origin: origin.to_string(),
            fields: BTreeMap::new(),
            settings: Vec::new(),
        };
        for (name, given) in chosen {
            point.params.insert(name.clone(), given.canonical);
            point.fields.insert(name, given.field);
            point.settings.push(given.setting);
        }
        self.check_combination(&point)?;
        let k = key("", &point.params);
        match self.by_params.get(&k) {
            Some(&i) => {
                let known = &mut self.points[i].scenes;
                known.extend_from_slice(scenes);
                known.sort_unstable();
                known.dedup();
            }
            None => {
                if self.points.len() >= MAX_RUNS {
                    return Err(too_many(self.file, origin, self.points.len() + 1));
                }
                self.by_params.insert(k, self.points.len());
                self.points.push(point);
            }
        }
        Ok(())
    }

    fn check_combination(&self, point: &Point) -> Result<()> {
        let triangle = point.path() == Some(PrimitivePath::Triangle);
        let shown = Value::Object(point.params.clone().into_iter().collect());
        for (name, needs, ok) in [
            ("tess", "path triangle", triangle),
            ("k", "path lembo (and curved discoids)", !triangle),
            (
                "perspective_tol",
                "path lembo (and curved discoids)",
                !triangle,
            ),
        ] {
            if point.params.contains_key(name) && !ok {
                return Err(Error::invalid(
                    self.file,
                    point.field(name),
                    &shown,
                    format!("`{name}` is only meaningful with {needs}"),
                ));
            }
        }
        if self.mode == Mode::Functional {
            if let Some(name) = point.params.keys().find(|n| n.starts_with(ARCH)) {
                return Err(Error::invalid(
                    self.file,
                    point.field(name),
                    &point.params[name],
                    "architecture fields are only meaningful with mode timed",
                ));
            }
        }
        Ok(())
    }

    /// Parses one parameter value; returns it and its canonical JSON.
    fn setting(&self, name: &str, v: &Value, field: &str) -> Result<(Setting, Value)> {
        let file = self.file;
        let parse = |message: String| Error::Parse {
            file: file.into(),
            field: field.into(),
            message,
        };
        let word = |choices: &[&str]| -> Result<String> {
            match v.as_str() {
                Some(s) if choices.contains(&s) => Ok(s.to_string()),
                _ => Err(parse(format!(
                    "expected one of {}, found {v}",
                    choices.join(", ")
                ))),
            }
        };
        let number = || -> Result<f64> {
            v.as_f64()
                .ok_or_else(|| parse(format!("expected a number, found {v}")))
        };
        let setting = match name {
            "path" => Setting::Path(match word(&["lembo", "triangle"])?.as_str() {
                "lembo" => PrimitivePath::Lembo,
                _ => PrimitivePath::Triangle,
            }),
            "k" => {
                let k = number()?;
                let (lo, hi) = K_RANGE;
                if !(k >= lo && k <= hi) {
                    return Err(Error::invalid(
                        file,
                        field,
                        v,
                        format!("k must be a number in [{lo}, {hi}] pixels"),
                    ));
                }
                Setting::K(k)
            }
            "perspective_tol" => {
                let tol = match (v.as_str(), v.as_f64()) {
                    (Some("off"), _) => Ok(PerspectiveTol::Off),
                    (_, Some(px)) => PerspectiveTol::px(px),
                    _ => Err(format!("expected a number of pixels or \"off\", found {v}")),
                };
                Setting::PerspectiveTol(tol.map_err(|why| Error::invalid(file, field, v, why))?)
            }
            "tess" => {
                let n = v
                    .as_u64()
                    .ok_or_else(|| parse(format!("expected a whole number, found {v}")))?;
                let n = u32::try_from(n).unwrap_or(u32::MAX);
                check_tess_range(n).map_err(|e| reword(e, file, field))?;
                Setting::Tess(n)
            }
            "datapath" => Setting::Datapath(match word(&["f32", "f64"])?.as_str() {
                "f32" => Datapath::F32,
                _ => Datapath::F64,
            }),
            "blend" => {
                let names: Vec<&str> = BlendMode::ALL.iter().map(|m| m.name()).collect();
                let w = word(&names)?;
                Setting::Blend(
                    *BlendMode::ALL
                        .iter()
                        .find(|m| m.name() == w)
                        .expect("one of the names"),
                )
            }
            "threshold" => {
                let t = number()?;
                if !(t.is_finite() && t > 0.0) {
                    return Err(Error::invalid(
                        file,
                        field,
                        v,
                        "must be a finite distance above 0 world units",
                    ));
                }
                Setting::Threshold(t)
            }
            _ => match name.strip_prefix(ARCH) {
                Some(path) => {
                    let canonical = self.arch_value(path, v, field)?;
                    return Ok((Setting::Arch(path.to_string(), v.clone()), canonical));
                }
                None => {
                    return Err(parse(format!(
                        "unknown parameter `{name}`; expected {}, `arch.<field>` or `scenes`",
                        SETTINGS.join(", ")
                    )))
                }
            },
        };
        let canonical = match &setting {
            Setting::Path(p) => Value::from(p.name()),
            Setting::K(x) | Setting::Threshold(x) => Value::from(*x),
            Setting::PerspectiveTol(t) => match t {
                PerspectiveTol::Px(px) => Value::from(*px),
                _ => Value::from("off"),
            },
            Setting::Tess(n) => Value::from(*n),
            Setting::Datapath(d) => Value::from(d.name()),
            Setting::Blend(m) => Value::from(m.name()),
            Setting::Arch(..) => unreachable!("returned above"),
        };
        Ok((setting, canonical))
    }

    /// Checks that `arch.<path>` names a field and `v` has its type; returns the value as
    /// the architecture serialises it (400 for a clock becomes 400.0).
    fn arch_value(&self, path: &str, v: &Value, field: &str) -> Result<Value> {
        let mut shape = self.arch_shape.clone();
        set_arch_field(&mut shape, path, v.clone()).map_err(|message| Error::Parse {
            file: self.file.into(),
            field: field.into(),
            message,
        })?;
        let config: ArchConfig =
            serde_path_to_error::deserialize(shape).map_err(|e| Error::Parse {
                file: self.file.into(),
                field: field.into(),
                message: e.into_inner().to_string(),
            })?;
        let back = serde_json::to_value(config).expect("the architecture serialises");
        Ok(arch_field(&back, path).cloned().unwrap_or(Value::Null))
    }
}

/// Sets the field at `path` (dotted) of an architecture's JSON; the field must exist and
/// not be a group of fields. The error says which part is unknown and what is there.
fn set_arch_field(arch: &mut Value, path: &str, v: Value) -> std::result::Result<(), String> {
    let parts: Vec<&str> = path.split('.').collect();
    let mut at = arch;
    for (i, part) in parts.iter().enumerate() {
        let here = parts[..i].join(".");
        let Value::Object(map) = at else {
            return Err(format!(
                "unknown architecture field `{path}`: `{here}` has no fields"
            ));
        };
        if !map.contains_key(*part) {
            let known: Vec<&str> = map.keys().map(String::as_str).collect();
            return Err(format!(
                "unknown architecture field `{path}`; {} has: {}",
                if here.is_empty() {
                    "the architecture".to_string()
                } else {
                    format!("`{here}`")
                },
                known.join(", ")
            ));
        }
        at = map.get_mut(*part).expect("checked");
    }
    if let Value::Object(map) = at {
        let known: Vec<&str> = map.keys().map(String::as_str).collect();
        return Err(format!(
            "`{path}` is a group of fields; name one of them: {}",
            known.join(", ")
        ));
    }
    *at = v;
    Ok(())
}

fn arch_field<'a>(arch: &'a Value, path: &str) -> Option<&'a Value> {
    path.split('.').try_fold(arch, |at, part| at.get(part))
}

/// The same error, said of another file and field (the spec's, for a check written for
/// the command line or an architecture file).
fn reword(e: Error, file: &str, field: &str) -> Error {
    match e {
        Error::Invalid { value, reason, .. } => Error::Invalid {
            file: file.into(),
            field: field.into(),
            value,
            reason,
        },
        Error::Parse { message, .. } => Error::Parse {
            file: file.into(),
            field: field.into(),
            message,
        },
        other => other,
    }
}

// ---- The validated plan --------------------------------------------------------------

/// A spec with its scenes loaded and every run's job built and validated: nothing in it
/// can be refused once a run starts, except what only a run can find (a patch beyond the
/// segment cap).
pub struct Plan {
    pub spec: Spec,
    pub scenes: Vec<Scene>,
    views: Vec<View>,
    /// Each point's architecture; None in functional mode.
    archs: Vec<Option<ArchConfig>>,
    /// Each run's job, by index.
    jobs: Vec<RenderJob>,
}

impl Plan {
    /// Reads, parses, expands and validates a spec file; scenes and the base architecture
    /// are relative to its directory.
    pub fn load(path: &Path) -> Result<Plan> {
        let text = read_text_file(path)?;
        Plan::new(
            Spec::parse(&text, &path.display().to_string())?,
            parent_dir(path),
        )
    }

    /// Validates an expanded spec whose relative paths start at `dir`.
    pub fn new(spec: Spec, dir: &Path) -> Result<Plan> {
        let file = spec.file.as_str();
        let base = match (spec.mode, &spec.arch) {
            (Mode::Functional, _) => None,
            (Mode::Timed, Some(a)) => Some(ArchConfig::load(&dir.join(a))?),
            (Mode::Timed, None) => Some(ArchConfig::baseline()),
        };

        let mut scenes: Vec<Scene> = Vec::new();
        for (i, s) in spec.scenes.iter().enumerate() {
            let mut scene = Scene::load(&dir.join(s))?;
            if let Some(j) = scenes.iter().position(|t| t.name == scene.name) {
                return Err(Error::invalid(
                    file,
                    format!("scenes[{i}]"),
                    s,
                    format!(
                        "its scene name `{}` is also scenes[{j}]'s; results are labelled by scene name",
                        scene.name
                    ),
                ));
            }
            if let Some((w, h)) = spec.viewport {
                scene.set_viewport(w, h)?;
            }
            if scene.discoid_count() > 0 {
                check_scene(&scene)?;
                let planar = scene
                    .objects
                    .iter()
                    .filter_map(|o| o.discoids.as_ref())
                    .any(|d| !d.planar.is_empty());
                if spec.mode == Mode::Timed && planar && scene.lembo_count() > 0 {
                    return Err(Error::invalid(
                        file,
                        format!("scenes[{i}]"),
                        s,
                        "the timed passes draw either curved or planar discoids in one scene; use mode functional for both",
                    ));
                }
            }
            scenes.push(scene);
        }
        let views = scenes
            .iter()
            .map(|s| View::new(&s.camera, s.viewport))
            .collect();

        let mut archs = Vec::with_capacity(spec.points.len());
        for point in &spec.points {
            archs.push(match &base {
                None => None,
                Some(base) => Some(point_arch(file, base, point)?),
            });
        }

        let mut jobs = Vec::with_capacity(spec.runs.len());
        for run in &spec.runs {
            let point = &spec.points[run.point];
            let scene = &scenes[run.scene];
            check_applies(&spec, point, scene, run.scene)?;
            let job = render_job(&spec, point, scene, 1);
            job.validate().map_err(|e| {
                let field = match &e {
                    Error::Invalid { field, .. } => field.trim_start_matches("--").to_string(),
                    _ => String::new(),
                };
                reword(e, file, &point.field(&field))
            })?;
            if job.path == PrimitivePath::Triangle && scene.discoid_count() == 0 {
                check_triangle_budget(scene, job.tess.unwrap_or(1))
                    .map_err(|e| reword(e, file, &point.field("tess")))?;
            }
            jobs.push(job);
        }
        Ok(Plan {
            spec,
            scenes,
            views,
            archs,
            jobs,
        })
    }

    /// The runs of a shard, in index order.
    pub fn shard_runs(&self, shard: Shard) -> Vec<&Run> {
        self.spec
            .runs
            .iter()
            .filter(|r| shard.keeps(r.index))
            .collect()
    }

    /// Runs one run: its record, one JSON line without the newline.
    fn run(&self, run: &Run, references: &[Option<(ReferenceImage, f64)>]) -> Result<String> {
        let job = &self.jobs[run.index];
        let reference = if job.reference {
            references[run.scene].as_ref().map(|(r, w)| (r, *w))
        } else {
            None
        };
        let mut out = run_path(
            job,
            &self.scenes[run.scene],
            &self.views[run.scene],
            crate::job::Model::new(self.archs[run.point].as_ref()),
            reference,
        )?;
        out.report.scene.source = self.spec.scenes[run.scene].clone();
        let record = Record {
            index: run.index,
            key: &run.key,
            scene: &self.scenes[run.scene].name,
            params: &self.spec.points[run.point].params,
            report: &out.report,
        };
        Ok(serde_json::to_string(&record).expect("a record serialises"))
    }
}

/// A point's architecture: the base with the point's `arch.<field>` values, validated; an
/// error names the spec field that set the refused value.
fn point_arch(file: &str, base: &ArchConfig, point: &Point) -> Result<ArchConfig> {
    let mut value = serde_json::to_value(base).expect("the architecture serialises");
    for (path, v) in point.arch_overrides() {
        set_arch_field(&mut value, path, v.clone()).map_err(|message| Error::Parse {
            file: file.into(),
            field: point.field(&format!("{ARCH}{path}")),
            message,
        })?;
    }
    let blame = |arch_field: &str| {
        // The override that set this field, or the point.
        point
            .arch_overrides()
            .map(|(p, _)| p)
            .find(|p| *p == arch_field || arch_field.starts_with(&format!("{p}.")))
            .map(|p| point.field(&format!("{ARCH}{p}")))
            .unwrap_or_else(|| point.origin.clone())
    };
    let arch: ArchConfig = serde_path_to_error::deserialize(value).map_err(|e| {
        let field = blame(&e.path().to_string());
        Error::Parse {
            file: file.into(),
            field,
            message: e.into_inner().to_string(),
        }
    })?;
    arch.validate(file).map_err(|e| {
        let field = match &e {
            Error::Invalid { field, .. } => blame(field),
            _ => point.origin.clone(),
        };
        reword(e, file, &field)
    })?;
    Ok(arch)
}

/// Refuses settings that the scene would ignore, so that no two runs differ only in a
/// parameter that had no effect.
fn check_applies(spec: &Spec, point: &Point, scene: &Scene, s: usize) -> Result<()> {
    let discoids = scene.discoid_count() > 0;
    let curved = scene.lembo_count() > 0;
    let refuse = |name: &str, why: String| {
        Err(Error::invalid(
            &spec.file,
            point.field(name),
            &point.params[name],
            format!(
                "{why}; restrict the {} to other scenes with `scenes`",
                if point.origin.starts_with("grid") {
                    "block"
                } else {
                    "point"
                }
            ),
        ))
    };
    let scene_name = format!("scenes[{s}] ({})", scene.name);
    for name in point.params.keys() {
        let applies = match name.as_str() {
            "path" | "tess" => !discoids,
            "k" | "perspective_tol" => curved,
            "blend" | "threshold" => discoids,
            _ => true,
        };
        if !applies {
            return refuse(
                name,
                if discoids {
                    format!(
                        "does not apply to {scene_name}, a scene of {} discoids",
                        if curved { "curved" } else { "planar" }
                    )
                } else {
                    format!("does not apply to {scene_name}, which has no discoids")
                },
            );
        }
    }
    Ok(())
}

/// The render job of a point on a scene.
fn render_job(spec: &Spec, point: &Point, scene: &Scene, host_threads: u32) -> RenderJob {
    let mut job = RenderJob {
        scene: None,
        out: None,
        k: DEFAULT_K_PX,
        perspective_tol: PerspectiveTol::FollowK,
        datapath: Datapath::F32,
        reference: spec.reference && scene.discoid_count() == 0,
        supersample: 1,
        viewport: spec.viewport,
        mode: spec.mode,
        // Shown in the report's settings only: the architecture itself is the point's.
        arch: match spec.mode {
            Mode::Timed => spec.arch.as_ref().map(PathBuf::from),
            Mode::Functional => None,
        },
        trace_out: None,
        path: PrimitivePath::Lembo,
        tess: None,
        blend: BlendMode::Rgba8,
        threshold: None,
        host_threads,
    };
    for s in &point.settings {
        match s {
            Setting::Path(p) => job.path = *p,
            Setting::K(k) => job.k = *k,
            Setting::PerspectiveTol(t) => job.perspective_tol = *t,
            Setting::Tess(n) => job.tess = Some(*n),
            Setting::Datapath(d) => job.datapath = *d,
            Setting::Blend(m) => job.blend = *m,
            Setting::Threshold(t) => job.threshold = Some(*t),
            Setting::Arch(..) => {}
        }
    }
    job
}

/// One line of `results.jsonl`.
#[derive(Serialize)]
struct Record<'a> {
    index: usize,
    key: &'a str,
    /// The scene's name.
    scene: &'a str,
    /// Every parameter the point sets, canonical.
    params: &'a BTreeMap<String, Value>,
    /// The run's full report.json.
    report: &'a Report,
}

// ---- Running -------------------------------------------------------------------------

/// `--shard I/N`: the runs whose index is I modulo N.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    pub index: u32,
    pub count: u32,
}

impl Shard {
    /// Every run.
    pub const ALL: Shard = Shard { index: 0, count: 1 };

    /// Checks N >= 1 and I < N.
    pub fn new(index: u32, count: u32) -> Result<Shard> {
        if count == 0 || index >= count {
            return Err(Error::invalid(
                COMMAND_LINE,
                "--shard",
                format!("{index}/{count}"),
                "must be I/N with N >= 1 and I in 0..N",
            ));
        }
        Ok(Shard { index, count })
    }

    pub fn keeps(self, index: usize) -> bool {
        index % self.count as usize == self.index as usize
    }
}

/// A sweep request, from the command line.
#[derive(Clone, Debug)]
pub struct SweepJob {
    pub spec: PathBuf,
    /// Output directory; None for `out/sweeps/<spec name>/`.
    pub out: Option<PathBuf>,
    /// Worker threads; None for the host's available parallelism.
    pub jobs: Option<usize>,
    pub shard: Shard,
    /// Test hook: stop once this many records were appended (see [`SweepOutcome`]).
    pub stop_after: Option<usize>,
    /// Draw a progress bar on stderr (hidden anyway when stderr is not a terminal).
    pub progress: bool,
    /// Host threads of each timed run (`--host-threads`; results do not depend on it).
    pub host_threads: u32,
}

/// What a sweep did.
#[derive(Debug)]
pub enum SweepOutcome {
    /// Every run of the shard has a record; the final files are written.
    Done(SweepOutput),
    /// Stopped by `stop_after` with `appended` records added to `results.jsonl`; the
    /// final files are not written.
    Stopped { dir: PathBuf, appended: usize },
}

#[derive(Debug)]
pub struct SweepOutput {
    pub dir: PathBuf,
    pub name: String,
    /// Runs of this shard.
    pub runs: usize,
    /// Runs found done in `results.jsonl` and skipped.
    pub skipped: usize,
    /// Worker threads used.
    pub jobs: usize,
    /// Files written, in the directory.
    pub files: Vec<String>,
    pub wall_seconds: f64,
}

/// A sweep that failed: the error, and the run it happened in when it was a run's.
#[derive(Debug)]
pub struct SweepError {
    /// Boxed so that results carrying a SweepError stay small.
    pub error: Box<Error>,
    /// `run 7 (key)` when a run failed; None for a refused spec or flag.
    pub run: Option<String>,
}

impl SweepError {
    pub fn exit_code(&self) -> u8 {
        self.error.exit_code()
    }
}

impl fmt::Display for SweepError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.run {
            Some(run) => write!(f, "{run}: {}", self.error),
            None => write!(f, "{}", self.error),
        }
    }
}

impl From<Error> for SweepError {
    fn from(error: Error) -> SweepError {
        SweepError {
            error: Box::new(error),
            run: None,
        }
    }
}

impl SweepJob {
    /// Checks the flags; errors name the flag and the value.
    pub fn validate(&self) -> Result<()> {
        if let Some(n) = self.jobs {
            if !(1..=MAX_JOBS).contains(&n) {
                return Err(Error::invalid(
                    COMMAND_LINE,
                    "--jobs",
                    n,
                    format!("must be 1 to {MAX_JOBS} threads"),
                ));
            }
        }
        Shard::new(self.shard.index, self.shard.count)?;
        if !(1..=MAX_HOST_THREADS).contains(&self.host_threads) {
            return Err(Error::invalid(
                COMMAND_LINE,
                "--host-threads",
                self.host_threads,
                format!("must be in 1..={MAX_HOST_THREADS} host threads"),
            ));
        }
        Ok(())
    }
}

/// Runs a sweep: validates everything, then runs what `results.jsonl` does not hold yet.
pub fn run_sweep(job: &SweepJob) -> std::result::Result<SweepOutcome, SweepError> {
    let t0 = Instant::now();
    job.validate()?;
    let mut plan = Plan::load(&job.spec)?;
    // At most as many host threads as a run has units (points may differ in unit counts).
    for (run, rj) in plan.spec.runs.iter().zip(plan.jobs.iter_mut()) {
        if let Some(arch) = &plan.archs[run.point] {
            let scene = &plan.scenes[run.scene];
            let path = if rj.path == PrimitivePath::Triangle
                || (scene.discoid_count() > 0 && scene.lembo_count() == 0)
            {
                crate::pipeline::Path::Triangle
            } else {
                crate::pipeline::Path::Lembo
            };
            let units = crate::pipeline::graph::units(path, arch).len().max(1);
            rj.host_threads = job.host_threads.min(units as u32);
        }
    }
    let spec = &plan.spec;
    let dir = job
        .out
        .clone()
        .unwrap_or_else(|| Path::new("out").join("sweeps").join(&spec.name));
    let jobs = job.jobs.unwrap_or_else(|| {
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
            .min(MAX_JOBS)
    });
    let runs = plan.shard_runs(job.shard);

    let results_path = dir.join(RESULTS_JSONL);
    check_same_spec(&dir, spec)?;
    let (mut lines, dropped) = read_partial(&results_path, spec, job.shard)?;
    write_files(&dir, &[(SPEC_JSON, spec.text.clone().into_bytes())])?;
    if dropped || !results_path.exists() {
        write_files(&dir, &[(RESULTS_JSONL, joined(&lines))])?;
    }
    let skipped = runs.iter().filter(|r| lines.contains_key(&r.index)).count();
    let pending: Vec<&Run> = runs
        .iter()
        .copied()
        .filter(|r| !lines.contains_key(&r.index))
        .collect();
    if job.stop_after == Some(0) && !pending.is_empty() {
        return Ok(SweepOutcome::Stopped { dir, appended: 0 });
    }

    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .thread_name(|i| format!("sweep-{i}"))
        .build()
        .map_err(|e| Error::Internal(format!("cannot start the sweep's threads: {e}")))?;
    let bar = progress_bar(job.progress, pending.len());

    // One exact reference per scene that a pending run measures against, computed before
    // any run (each is itself parallel over rows on the pool).
    let mut references: Vec<Option<(ReferenceImage, f64)>> = Vec::new();
    for (s, scene) in plan.scenes.iter().enumerate() {
        let needed = pending
            .iter()
            .any(|r| r.scene == s && plan.jobs[r.index].reference);
        references.push(needed.then(|| {
            bar.set_message(format!("reference of {}", scene.name));
            pool.install(|| render_reference(scene, &plan.views[s], 1))
        }));
    }
    bar.set_message("");

    let file = std::fs::OpenOptions::new()
        .append(true)
        .open(&results_path)
        .map_err(|source| Error::Write {
            path: results_path.clone(),
            source,
        })?;
    /// What the workers share, under one lock.
    struct Progress<'a> {
        file: std::fs::File,
        lines: &'a mut BTreeMap<usize, String>,
        appended: usize,
        failure: Option<SweepError>,
        stopped: bool,
    }
    let state = Mutex::new(Progress {
        file,
        lines: &mut lines,
        appended: 0,
        failure: None,
        stopped: false,
    });
    let stop = AtomicBool::new(false);
    let next = AtomicUsize::new(0);
    // Workers take runs in index order; a finished run is appended under the lock, so
    // records are whole lines and a stop leaves exactly `stop_after` of them.
    let worker = || loop {
        if stop.load(Ordering::Relaxed) {
            return;
        }
        let Some(&run) = pending.get(next.fetch_add(1, Ordering::Relaxed)) else {
            return;
        };
        let result = plan.run(run, &references);
        let mut guard = state.lock().expect("no worker panics holding the lock");
        let st = &mut *guard;
        // After a stop no record is added (the hook promises exactly `stop_after`); after
        // a failure the runs in flight are still recorded, so a rerun need not redo them.
        if st.stopped {
            return;
        }
        let line = match result {
            Ok(line) => line,
            Err(_) if st.failure.is_some() => return,
            Err(error) => {
                st.failure = Some(SweepError {
                    error: Box::new(error),
                    run: Some(format!("run {} ({})", run.index, run.key)),
                });
                stop.store(true, Ordering::Relaxed);
                return;
            }
        };
        let written = st
            .file
            .write_all(format!("{line}\n").as_bytes())
            .and_then(|()| st.file.flush());
        if let Err(source) = written {
            st.failure.get_or_insert_with(|| {
                Error::Write {
                    path: results_path.clone(),
                    source,
                }
                .into()
            });
            stop.store(true, Ordering::Relaxed);
            return;
        }
        st.lines.insert(run.index, line);
        st.appended += 1;
        bar.inc(1);
        if job.stop_after == Some(st.appended) {
            st.stopped = true;
            stop.store(true, Ordering::Relaxed);
        }
    };
    pool.scope(|s| {
        for _ in 0..jobs {
            s.spawn(|_| worker());
        }
    });
    bar.finish_and_clear();
    let st = state.into_inner().expect("no worker panicked");
    if let Some(failure) = st.failure {
        return Err(failure);
    }
    if st.stopped && st.appended < pending.len() {
        return Ok(SweepOutcome::Stopped {
            dir,
            appended: st.appended,
        });
    }
    drop(st);

    let files = write_final(&dir, spec.text.as_bytes(), &lines)?;
    Ok(SweepOutcome::Done(SweepOutput {
        dir,
        name: spec.name.clone(),
        runs: runs.len(),
        skipped,
        jobs,
        files,
        wall_seconds: t0.elapsed().as_secs_f64(),
    }))
}

fn progress_bar(show: bool, len: usize) -> ProgressBar {
    let target = if show {
        ProgressDrawTarget::stderr()
    } else {
        ProgressDrawTarget::hidden()
    };
    let bar = ProgressBar::with_draw_target(Some(len as u64), target);
    bar.set_style(
        ProgressStyle::with_template(
            "{elapsed_precise} [{wide_bar}] {pos}/{len} runs, ETA {eta_precise} {msg}",
        )
        .expect("the template is valid")
        .progress_chars("=> "),
    );
    if show {
        // The clock and ETA move while a long run or a reference is computed.
        bar.enable_steady_tick(std::time::Duration::from_millis(500));
    }
    bar
}

/// Lines, each followed by a newline.
fn joined(lines: &BTreeMap<usize, String>) -> Vec<u8> {
    let mut out = String::new();
    for line in lines.values() {
        out.push_str(line);
        out.push('\n');
    }
    out.into_bytes()
}

/// A directory that holds results must hold this spec's.
fn check_same_spec(dir: &Path, spec: &Spec) -> Result<()> {
    let path = dir.join(SPEC_JSON);
    let text = match std::fs::read_to_string(&path) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            if dir.join(RESULTS_JSONL).exists() {
                return Err(Error::invalid(
                    dir.display().to_string(),
                    SPEC_JSON,
                    "missing",
                    "the directory holds results.jsonl but no spec.json, so its runs cannot be matched to this spec; use another --out",
                ));
            }
            return Ok(());
        }
        Err(source) => return Err(Error::Read { path, source }),
    };
    let file = path.display().to_string();
    let theirs: Value = serde_json::from_str(&text).map_err(|e| Error::Parse {
        file: file.clone(),
        field: String::new(),
        message: e.to_string(),
    })?;
    if theirs != spec.value {
        return Err(spec_difference(&file, &theirs, &spec.value, &spec.file));
    }
    Ok(())
}

/// Names the first top-level field where two specs differ.
fn spec_difference(file: &str, theirs: &Value, ours: &Value, our_file: &str) -> Error {
    let empty = serde_json::Map::new();
    let (a, b) = (
        theirs.as_object().unwrap_or(&empty),
        ours.as_object().unwrap_or(&empty),
    );
    let field = a
        .keys()
        .chain(b.keys())
        .find(|k| a.get(*k) != b.get(*k))
        .cloned()
        .unwrap_or_default();
    Error::invalid(
        file,
        &field,
        a.get(&field).unwrap_or(&Value::Null),
        format!(
            "differs from {our_file}'s ({}): these are results of another spec; use another --out",
            b.get(&field).unwrap_or(&Value::Null)
        ),
    )
}

/// The records already in `results.jsonl`, by index, and whether a truncated or
/// unreadable last line was dropped. Each must be a run of this spec and shard.
fn read_partial(path: &Path, spec: &Spec, shard: Shard) -> Result<(BTreeMap<usize, String>, bool)> {
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok((BTreeMap::new(), false)),
        Err(source) => {
            return Err(Error::Read {
                path: path.to_path_buf(),
                source,
            })
        }
    };
    let file = path.display().to_string();
    let mut lines = BTreeMap::new();
    let mut dropped = false;
    let all: Vec<&str> = text.split_inclusive('\n').collect();
    for (n, raw) in all.iter().enumerate() {
        let last = n + 1 == all.len();
        let line = raw.strip_suffix('\n');
        let parsed = line.and_then(|l| record_id(l).ok());
        let Some((index, key)) = parsed else {
            if last {
                // A kill mid-write leaves a partial last line: the run is redone.
                dropped = true;
                continue;
            }
            let message = match line {
                Some(l) => record_id(l).err().unwrap_or_default(),
                None => "no newline".into(),
            };
            return Err(Error::Parse {
                file,
                field: format!("line {}", n + 1),
                message,
            });
        };
        let line = line.expect("parsed");
        check_record(&file, n, index, &key, spec, shard)?;
        if lines.insert(index, line.to_string()).is_some() {
            return Err(Error::invalid(
                file,
                format!("line {}", n + 1),
                index,
                "a second record of the same run",
            ));
        }
    }
    Ok((lines, dropped))
}

/// A record's index and key.
fn record_id(line: &str) -> std::result::Result<(usize, String), String> {
    #[derive(Deserialize)]
    struct Id {
        index: usize,
        key: String,
    }
    serde_json::from_str::<Id>(line)
        .map(|id| (id.index, id.key))
        .map_err(|e| e.to_string())
}

/// A record read back must be run `index` of this spec, in this shard.
fn check_record(
    file: &str,
    n: usize,
    index: usize,
    key: &str,
    spec: &Spec,
    shard: Shard,
) -> Result<()> {
    let expected = spec.runs.get(index).map(|r| r.key.as_str());
    let reason = if expected != Some(key) {
        format!(
            "is not run {index} of {} (whose key is {}): the records are another spec's",
            spec.file,
            expected.unwrap_or("absent")
        )
    } else if !shard.keeps(index) {
        format!(
            "run {index} is not in shard {}/{}: the records are another shard's; use another --out",
            shard.index, shard.count
        )
    } else {
        return Ok(());
    };
    Err(Error::invalid(file, format!("line {}", n + 1), key, reason))
}

/// Writes the finished directory as one atomic set: results.jsonl in index order,
/// results.csv, spec.json and the plots.
fn write_final(
    dir: &Path,
    spec_text: &[u8],
    lines: &BTreeMap<usize, String>,
) -> Result<Vec<String>> {
    let records: Vec<Value> = lines
        .values()
        .map(|l| serde_json::from_str(l).expect("every line was parsed or written as JSON"))
        .collect();
    // The plots are drawn first so that the records, the table and the plots are one
    // atomic set.
    let plots = crate::plot::plot_files(&records)?;
    let mut files: Vec<(&str, Vec<u8>)> = vec![
        (RESULTS_JSONL, joined(lines)),
        (RESULTS_CSV, csv_bytes(&records)?),
        (SPEC_JSON, spec_text.to_vec()),
    ];
    files.extend(plots.iter().map(|(name, svg)| (name.as_str(), svg.clone())));
    write_files(dir, &files)?;
    Ok(files.iter().map(|(name, _)| name.to_string()).collect())
}

// ---- results.csv ---------------------------------------------------------------------

/// Sort key of a unit name: its kind in dataflow order, then its instance number
/// (`Segmenter[10]` after `Segmenter[9]`).
fn unit_order(name: &str) -> (usize, u64, String) {
    let (kind, instance) = match name.split_once('[') {
        Some((k, rest)) => (k, rest.trim_end_matches(']').parse().unwrap_or(0)),
        None => (name, 0),
    };
    let rank = KINDS
        .iter()
        .position(|k| k.name() == kind)
        .unwrap_or(KINDS.len());
    (rank, instance, name.to_string())
}

/// A CSV cell: strings bare, null and absent empty, numbers and booleans as JSON.
fn cell(v: Option<&Value>) -> String {
    match v {
        None | Some(Value::Null) => String::new(),
        Some(Value::String(s)) => s.clone(),
        Some(other) => other.to_string(),
    }
}

/// `results.csv`: one row per record, columns as `sim/sweeps/README.md` lists them.
pub fn csv_bytes(records: &[Value]) -> Result<Vec<u8>> {
    let mut params = BTreeSet::new();
    let mut units = BTreeSet::new();
    let mut metrics = BTreeSet::new();
    for r in records {
        if let Some(p) = r["params"].as_object() {
            params.extend(p.keys().cloned());
        }
        for u in r["report"]["cycles"]["units"]
            .as_array()
            .into_iter()
            .flatten()
        {
            if let Some(name) = u["name"].as_str() {
                units.insert(unit_order(name));
            }
        }
        if let Some(a) = r["report"]["accuracy"].as_object() {
            metrics.extend(a.keys().cloned());
        }
    }
    let mut header: Vec<String> = vec!["index".into(), "scene".into()];
    header.extend(params.iter().cloned());
    header.extend(["cycles_total", "fps", "bottleneck"].map(String::from));
    header.extend(units.iter().map(|(_, _, n)| format!("util.{n}")));
    header.extend(metrics.iter().map(|m| format!("acc.{m}")));
    header.extend(
        [
            "primitives",
            "primitive_bytes",
            "fragments",
            "lembo_pieces",
            "blend.error_mean",
            "blend.error_max",
            "wall_seconds",
        ]
        .map(String::from),
    );

    let mut w = csv::Writer::from_writer(Vec::new());
    let csv_err = |e: csv::Error| Error::Internal(format!("results.csv: {e}"));
    w.write_record(&header).map_err(csv_err)?;
    for r in records {
        let report = &r["report"];
        let cycles = &report["cycles"];
        let mut row = vec![cell(r.get("index")), cell(r.get("scene"))];
        row.extend(params.iter().map(|p| cell(r["params"].get(p))));
        row.push(cell(cycles.get("total")));
        row.push(cell(cycles.get("fps")));
        row.push(cell(cycles.get("bottleneck")));
        let total = cycles["total"].as_u64();
        let busy: BTreeMap<&str, u64> = cycles["units"]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(|u| Some((u["name"].as_str()?, u["busy"].as_u64()?)))
            .collect();
        for (_, _, name) in &units {
            row.push(match (busy.get(name.as_str()), total) {
                (Some(&b), Some(t)) if t > 0 => (b as f64 / t as f64).to_string(),
                _ => String::new(),
            });
        }
        row.extend(metrics.iter().map(|m| cell(report["accuracy"].get(m))));
        row.push(cell(report["primitives"].get("count")));
        row.push(cell(report["primitives"].get("bytes")));
        row.push(cell(report["counts"].get("fragments")));
        row.push(cell(report["counts"].get("lembo_pieces")));
        row.push(cell(report["blend"].get("error_mean")));
        row.push(cell(report["blend"].get("error_max")));
        row.push(cell(report["host"].get("wall_seconds")));
        w.write_record(&row).map_err(csv_err)?;
    }
    w.into_inner()
        .map_err(|e| Error::Internal(format!("results.csv: {e}")))
}

// ---- sweep-merge ---------------------------------------------------------------------

/// A merge request: the shards' directories and where the union goes.
#[derive(Clone, Debug)]
pub struct MergeJob {
    pub out: PathBuf,
    pub shards: Vec<PathBuf>,
}

#[derive(Debug)]
pub struct MergeOutput {
    pub dir: PathBuf,
    pub name: String,
    pub runs: usize,
    pub files: Vec<String>,
}

/// Unions the shards' records into what an unsharded sweep writes. The shards must hold
/// the same spec; a run found in two shards must have the same record but for host timing
/// (`report.host`); every run of the spec must be found.
pub fn run_merge(job: &MergeJob) -> Result<MergeOutput> {
    if job.shards.is_empty() {
        return Err(Error::invalid(
            COMMAND_LINE,
            "SHARD_DIR",
            "none",
            "name at least one shard directory",
        ));
    }
    let mut spec: Option<(Spec, Vec<u8>)> = None;
    let mut lines: BTreeMap<usize, (String, Value, String)> = BTreeMap::new();
    for shard in &job.shards {
        let spec_path = shard.join(SPEC_JSON);
        let text = read_text_file(&spec_path)?;
        let this = Spec::parse(&text, &spec_path.display().to_string())?;
        match &spec {
            None => spec = Some((this, text.into_bytes())),
            Some((first, _)) if first.value != this.value => {
                return Err(spec_difference(
                    &this.file,
                    &this.value,
                    &first.value,
                    &first.file,
                ))
            }
            Some(_) => {}
        }
        let (spec, _) = spec.as_ref().expect("set above");

        let path = shard.join(RESULTS_JSONL);
        let file = path.display().to_string();
        let text = std::fs::read_to_string(&path).map_err(|source| Error::Read {
            path: path.clone(),
            source,
        })?;
        for (n, raw) in text.split_inclusive('\n').enumerate() {
            let field = format!("line {}", n + 1);
            let Some(line) = raw.strip_suffix('\n') else {
                return Err(Error::Parse {
                    file,
                    field,
                    message: "no newline: the shard did not finish; run it again".into(),
                });
            };
            let (index, key) = record_id(line).map_err(|message| Error::Parse {
                file: file.clone(),
                field: field.clone(),
                message,
            })?;
            check_record(&file, n, index, &key, spec, Shard::ALL)?;
            let mut masked: Value = serde_json::from_str(line).expect("parsed above");
            if let Some(report) = masked.get_mut("report").and_then(Value::as_object_mut) {
                report.remove("host");
            }
            match lines.get(&index) {
                Some((_, other, from)) if *other != masked => {
                    return Err(Error::invalid(
                        file,
                        field,
                        key,
                        format!(
                            "differs from the record of the same run in {from} beyond host timing"
                        ),
                    ))
                }
                Some(_) => {}
                None => {
                    lines.insert(index, (line.to_string(), masked, file.clone()));
                }
            }
        }
    }
    let (spec, spec_bytes) = spec.expect("at least one shard");
    let missing: Vec<usize> = (0..spec.runs.len())
        .filter(|i| !lines.contains_key(i))
        .collect();
    if !missing.is_empty() {
        let shown: Vec<String> = missing.iter().take(8).map(|i| i.to_string()).collect();
        return Err(Error::invalid(
            COMMAND_LINE,
            "SHARD_DIR",
            format!(
                "runs {}{}",
                shown.join(", "),
                if missing.len() > 8 { ", ..." } else { "" }
            ),
            format!(
                "{} of the spec's {} runs are in no shard: did every shard finish?",
                missing.len(),
                spec.runs.len()
            ),
        ));
    }
    let lines: BTreeMap<usize, String> = lines.into_iter().map(|(i, (l, _, _))| (i, l)).collect();
    let files = write_final(&job.out, &spec_bytes, &lines)?;
    Ok(MergeOutput {
        dir: job.out.clone(),
        name: spec.name,
        runs: spec.runs.len(),
        files,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const BASE: &str = r#""name": "t", "scenes": ["a.json", "b.json"]"#;

    fn spec(rest: &str) -> Result<Spec> {
        Spec::parse(&format!("{{{BASE}, {rest}}}"), "s.json")
    }

    fn field_of(e: Error) -> String {
        match e {
            Error::Invalid { field, .. } | Error::Parse { field, .. } => field,
            other => panic!("unexpected error {other}"),
        }
    }

    #[test]
    fn grid_is_a_product_with_the_first_parameter_slowest_then_points() {
        let s = spec(
            r#""grid": [{"tess": [1, 2], "path": ["triangle"]}, {"k": [2, 1]}],
               "points": [{"k": 1}, {"k": 0.25, "scenes": ["b.json"]}]"#,
        )
        .unwrap();
        let keys: Vec<&str> = s.runs.iter().map(|r| r.key.as_str()).collect();
        assert_eq!(
            keys,
            [
                r#"a.json|path="triangle"|tess=1"#,
                r#"b.json|path="triangle"|tess=1"#,
                r#"a.json|path="triangle"|tess=2"#,
                r#"b.json|path="triangle"|tess=2"#,
                "a.json|k=2.0",
                "b.json|k=2.0",
                // points[0] equals grid[1]'s second point: the union keeps it once.
                "a.json|k=1.0",
                "b.json|k=1.0",
                "b.json|k=0.25",
            ]
        );
        assert!(s.runs.iter().enumerate().all(|(i, r)| r.index == i));
    }

    #[test]
    fn arch_values_are_canonical_and_unknown_fields_named() {
        let s = spec(r#""points": [{"arch.clock_mhz": 400, "arch.segmenter.count": 4}]"#).unwrap();
        assert_eq!(
            s.points[0].params["arch.clock_mhz"],
            serde_json::json!(400.0)
        );
        let e = spec(r#""points": [{"arch.segmenter.cnt": 4}]"#).unwrap_err();
        assert!(e.to_string().contains("cycles_per_segment"), "{e}");
        assert_eq!(field_of(e), "points[0].arch.segmenter.cnt");
        let e = spec(r#""points": [{"arch.links": 4}]"#).unwrap_err();
        assert!(e.to_string().contains("group of fields"), "{e}");
        let e = spec(r#""grid": [{"arch.rop.count": [2, 1.5]}]"#).unwrap_err();
        assert_eq!(field_of(e), "grid[0].arch.rop.count[1]");
    }

    #[test]
    fn bad_values_and_combinations_name_their_field() {
        for (rest, field) in [
            (r#""grid": [{"k": []}]"#, "grid[0].k"),
            (r#""grid": [{"k": [1, 100]}]"#, "grid[0].k[1]"),
            (r#""grid": [{"k": 1}]"#, "grid[0].k"),
            (r#""grid": [{}]"#, "grid[0]"),
            (r#""grid": []"#, "grid"),
            (
                r#""points": [{"tess": 0, "path": "triangle"}]"#,
                "points[0].tess",
            ),
            (r#""points": [{"tess": 2}]"#, "points[0].tess"),
            (r#""points": [{"k": 1, "path": "triangle"}]"#, "points[0].k"),
            (r#""points": [{"datapath": "f16"}]"#, "points[0].datapath"),
            (r#""points": [{"threshold": -1}]"#, "points[0].threshold"),
            (r#""points": [{"colour": 1}]"#, "points[0].colour"),
            (
                r#""points": [{"scenes": ["c.json"]}]"#,
                "points[0].scenes[0]",
            ),
            (r#""points": [{}], "viewport": [0, 4]"#, "viewport[0]"),
            (r#""points": [{}], "extra": 1"#, "extra"),
        ] {
            let e = spec(rest)
                .err()
                .unwrap_or_else(|| panic!("{rest} accepted"));
            assert_eq!(field_of(e), field, "{rest}");
        }
        let e = Spec::parse(r#"{"name": "t", "scenes": [], "points": [{}]}"#, "s").unwrap_err();
        assert_eq!(field_of(e), "scenes");
    }

    #[test]
    fn huge_grids_are_refused_before_expansion() {
        let list: Vec<String> = (1..=400).map(|i| i.to_string()).collect();
        let l = list.join(", ");
        let e = spec(&format!(
            r#""grid": [{{"arch.clock_mhz": [{l}], "arch.setup.latency_cycles": [{l}]}}]"#
        ))
        .unwrap_err();
        assert_eq!(field_of(e), "grid[0]");
    }

    #[test]
    fn shards_partition_the_indices() {
        assert!(Shard::new(2, 2).is_err());
        assert!(Shard::new(0, 0).is_err());
        let shards: Vec<Shard> = (0..3).map(|i| Shard::new(i, 3).unwrap()).collect();
        for index in 0..20 {
            assert_eq!(shards.iter().filter(|s| s.keeps(index)).count(), 1);
        }
    }

    #[test]
    fn units_sort_in_dataflow_order_and_by_instance() {
        let mut names = [
            "Rop[1]",
            "Segmenter[10]",
            "Setup",
            "Segmenter[9]",
            "FrameBuffer",
        ]
        .map(unit_order);
        names.sort();
        let names: Vec<&str> = names.iter().map(|(_, _, n)| n.as_str()).collect();
        assert_eq!(
            names,
            [
                "Setup",
                "Segmenter[9]",
                "Segmenter[10]",
                "Rop[1]",
                "FrameBuffer"
            ]
        );
    }

    #[test]
    fn csv_leaves_absent_values_empty() {
        let records = vec![
            serde_json::json!({"index": 0, "scene": "s", "params": {"k": 1.0},
                "report": {"cycles": {"total": 10, "fps": 5.0, "bottleneck": "Rop",
                    "units": [{"name": "Rop", "busy": 5}]},
                    "accuracy": null, "primitives": {"count": 2, "bytes": 8},
                    "counts": {"fragments": 3, "lembo_pieces": 4}, "blend": null,
                    "host": {"wall_seconds": 0.5}}}),
            serde_json::json!({"index": 1, "scene": "s, \"quoted\"", "params": {"tess": 2},
                "report": {"cycles": null, "accuracy": {"psnr_db": 40.0},
                    "primitives": {"count": 2, "bytes": 8}, "counts": {"fragments": 3},
                    "blend": null, "host": {"wall_seconds": 0.25}}}),
        ];
        let text = String::from_utf8(csv_bytes(&records).unwrap()).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "index,scene,k,tess,cycles_total,fps,bottleneck,util.Rop,acc.psnr_db,primitives,primitive_bytes,fragments,lembo_pieces,blend.error_mean,blend.error_max,wall_seconds");
        assert_eq!(lines[1], "0,s,1.0,,10,5.0,Rop,0.5,,2,8,3,4,,,0.5");
        assert_eq!(
            lines[2],
            "1,\"s, \"\"quoted\"\"\",,2,,,,,40.0,2,8,3,,,,0.25"
        );
    }
}
