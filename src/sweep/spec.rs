//! A sweep spec: the file's shape (`SpecFile`), the expanded spec (`Spec`: points, runs and
//! their keys) and `Spec::parse`, which validates the shape and expands the grid with
//! the `grid` module.

use super::{grid::Expander, MAX_RUNS};
use crate::camera::MAX_VIEWPORT_SIDE;
use crate::config::ArchConfig;
use crate::datapath::Datapath;
use crate::discoid::blend::BlendMode;
use crate::error::{Error, Result};
use crate::job::{Mode, PrimitivePath};
use crate::json::parse_strict;
use crate::raster::PerspectiveTol;
use serde::de::{self, MapAccess, Visitor};
use serde::{Deserialize, Deserializer};
use serde_json::Value;
use std::collections::BTreeMap;
use std::fmt;

// ---- The file's shape ----------------------------------------------------------------

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SpecFile {
    name: String,
    scenes: Vec<String>,
    viewport: Option<[u32; 2]>,
    #[serde(default)]
    mode: ModeSpec,
    reference: Option<bool>,
    arch: Option<String>,
    area_budget_mm2: Option<f64>,
    grid: Option<Vec<Params>>,
    points: Option<Vec<Params>>,
}

#[derive(Deserialize, Default, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub(super) enum ModeSpec {
    #[default]
    Timed,
    Functional,
}

/// A JSON object of parameters in the file's order (the order of a grid's product), with
/// duplicate names refused.
pub(super) struct Params(pub(super) Vec<(String, Value)>);

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
pub(super) enum Setting {
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
    pub(super) fields: BTreeMap<String, String>,
    pub(super) settings: Vec<Setting>,
}

impl Point {
    fn setting<T>(&self, pick: impl Fn(&Setting) -> Option<T>) -> Option<T> {
        self.settings.iter().find_map(pick)
    }
    pub(super) fn path(&self) -> Option<PrimitivePath> {
        self.setting(|s| match s {
            Setting::Path(p) => Some(*p),
            _ => None,
        })
    }
    pub(super) fn arch_overrides(&self) -> impl Iterator<Item = (&str, &Value)> {
        self.settings.iter().filter_map(|s| match s {
            Setting::Arch(p, v) => Some((p.as_str(), v)),
            _ => None,
        })
    }
    /// The spec field of parameter `name`, or the point's origin.
    pub(super) fn field(&self, name: &str) -> String {
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
    /// Its point's index in `Spec::points`.
    pub point: usize,
    /// Its scene's index in `Spec::scenes`.
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
    /// The spec's name: it names the default folder `out/sweeps/<name>/`.
    pub name: String,
    /// The scenes as the spec writes them (relative to its directory).
    pub scenes: Vec<String>,
    /// Viewport override for every scene (width, height) \[pixels\].
    pub viewport: Option<(u32, u32)>,
    /// Timed or functional, for every run.
    pub mode: Mode,
    /// Whether runs on scenes without discoids are measured against the exact reference.
    pub reference: bool,
    /// The base architecture as the spec writes it; None for the embedded baseline.
    pub arch: Option<String>,
    /// The area budget the plots hold the configurations to (report.json `cost.area_mm2`)
    /// \[mm²\]; None for no budget.
    pub area_budget_mm2: Option<f64>,
    /// The points, in expansion order.
    pub points: Vec<Point>,
    /// Every (point, scene) pair, point-major.
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

        if let Some(b) = f.area_budget_mm2 {
            if mode == Mode::Functional {
                return Err(Error::invalid(
                    file,
                    "area_budget_mm2",
                    b,
                    "only meaningful with mode timed (a functional run has no cost)",
                ));
            }
            if !(b.is_finite() && b > 0.0) {
                return Err(Error::invalid(
                    file,
                    "area_budget_mm2",
                    b,
                    "must be a finite area above 0 mm2",
                ));
            }
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
            area_budget_mm2: f.area_budget_mm2,
            points: ex.points,
            runs,
            scenes: f.scenes,
        })
    }
}

/// The canonical key of a run.
pub(super) fn key(scene: &str, params: &BTreeMap<String, Value>) -> String {
    let mut k = scene.to_string();
    for (name, value) in params {
        k.push('|');
        k.push_str(name);
        k.push('=');
        k.push_str(&value.to_string());
    }
    k
}

pub(super) fn check_name(file: &str, name: &str) -> Result<()> {
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

pub(super) fn empty_list(file: &str, field: &str) -> Error {
    Error::invalid(file, field, "[]", "must not be an empty list")
}

pub(super) fn too_many(file: &str, field: &str, runs: usize) -> Error {
    Error::invalid(
        file,
        field,
        format!("{runs} runs"),
        format!("a sweep may have at most {MAX_RUNS} runs (points x scenes)"),
    )
}
