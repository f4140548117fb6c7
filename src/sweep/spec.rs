//! A sweep spec: its names and bounds (the settings a point can set, the most runs, the
//! default k), the file's shape (`SpecFile`), the expanded spec (`Spec`: points, runs and
//! their keys) and the runs a shard keeps. The lowest file of the sweep: `grid` expands
//! into these types and `parse` (`Spec::parse`) builds them; it imports neither.

use crate::camera::Samples;
use crate::datapath::Datapath;
use crate::discoid::blend::BlendMode;
use crate::error::{Error, Result, COMMAND_LINE};
use crate::job::{Mode, PrimitivePath};
use crate::tolerance::PerspectiveTol;
use serde::de::{self, MapAccess, Visitor};
use serde::{Deserialize, Deserializer};
use serde_json::Value;
use std::collections::BTreeMap;
use std::fmt;

// ---- Names and bounds ----------------------------------------------------------------

/// The most runs (points × scenes) a spec may expand to: beyond it a sweep takes days, and
/// a typo in a grid should be refused rather than expanded.
pub const MAX_RUNS: usize = 100_000;

/// The render settings a point can set, besides `arch.<field>` and `tech.<field>`.
pub(super) const SETTINGS: [&str; 9] = [
    "viewport",
    "path",
    "k",
    "perspective_tol",
    "tess",
    "samples",
    "datapath",
    "blend",
    "threshold",
];

/// A block's or point's scene restriction: not a parameter.
pub(super) const SCENES: &str = "scenes";

pub(super) use super::names::{empty_list, ARCH, TECH};

// ---- The file's shape ----------------------------------------------------------------

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SpecFile {
    pub(super) name: String,
    pub(super) scenes: Vec<String>,
    /// One viewport (`[w, h]`), or a list of them (`[[w, h], "WxH", ...]`) that every point
    /// runs at.
    pub(super) viewport: Option<Value>,
    #[serde(default)]
    pub(super) mode: Mode,
    pub(super) reference: Option<bool>,
    pub(super) arch: Option<String>,
    pub(super) area_budget_mm2: Option<f64>,
    pub(super) by: Option<String>,
    pub(super) refine: Option<super::bracket::RefineFile>,
    pub(super) targets: Option<super::curves::TargetsFile>,
    pub(super) sensitivity: Option<super::sensitivity::SensitivityFile>,
    pub(super) grid: Option<Vec<Params>>,
    pub(super) points: Option<Vec<Params>>,
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
    /// Samples per pixel (`--samples`).
    Samples(Samples),
    Datapath(Datapath),
    Blend(BlendMode),
    Threshold(f64),
    /// The image size (width, height) \[pixels\], canonical as `"WxH"`.
    Viewport((u32, u32)),
    /// An architecture field: its dotted path (without `arch.`) and value.
    Arch(String, Value),
    /// A sensitivity variant's parameter scaled by a factor: its sweep name
    /// (`arch.rop.count`) and the factor; the value is the point's architecture's times it.
    Scale(String, f64),
    /// A technology field: its dotted path (without `tech.`) and value.
    Tech(String, Value),
}

/// A point of the parameter space.
#[derive(Clone, Debug)]
pub struct Point {
    /// Every parameter the point sets, by name, in canonical form (`k` and `threshold` as
    /// floats, `tess` as an integer, names as strings, architecture and technology fields
    /// as the architecture and the technology file serialise them).
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
    pub(super) fn setting<T>(&self, pick: impl Fn(&Setting) -> Option<T>) -> Option<T> {
        self.settings.iter().find_map(pick)
    }
    pub(super) fn path(&self) -> Option<PrimitivePath> {
        self.setting(|s| match s {
            Setting::Path(p) => Some(*p),
            _ => None,
        })
    }
    /// The parameters a sensitivity variant scales, with their factors.
    pub(super) fn scales(&self) -> impl Iterator<Item = (&str, f64)> {
        self.settings.iter().filter_map(|s| match s {
            Setting::Scale(p, f) => Some((p.as_str(), *f)),
            _ => None,
        })
    }
    pub(super) fn arch_overrides(&self) -> impl Iterator<Item = (&str, &Value)> {
        self.settings.iter().filter_map(|s| match s {
            Setting::Arch(p, v) => Some((p.as_str(), v)),
            _ => None,
        })
    }
    pub(super) fn tech_overrides(&self) -> impl Iterator<Item = (&str, &Value)> {
        self.settings.iter().filter_map(|s| match s {
            Setting::Tech(p, v) => Some((p.as_str(), v)),
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
    /// Viewport override for every scene (width, height) \[pixels\]; a spec whose
    /// `viewport` lists several sets each point's `viewport` parameter instead.
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
    /// The swept field the answer is also given by value for (`by`; `super::by`).
    pub by: Option<String>,
    /// How far refinement rounds take each path's accuracy knob beyond the grid
    /// (`refine`); None for the grid alone.
    pub refine: Option<super::bracket::Refine>,
    /// The target levels the answer tabulates (`targets`).
    pub targets: super::curves::Targets,
    /// The one-at-a-time sensitivity study (`sensitivity`), whose variant points follow the
    /// grid's; None for none.
    pub sensitivity: Option<super::sensitivity::Sensitivity>,
    /// The points, in expansion order (refinement rounds append theirs).
    pub points: Vec<Point>,
    /// Every (point, scene) pair, point-major.
    pub runs: Vec<Run>,
}

// ---- Shards --------------------------------------------------------------------------

/// `--shard I/N`: the runs whose index is I modulo N.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// This shard's index I, in 0..N.
    pub index: u32,
    /// The number of shards N.
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

    /// Whether run `index` belongs to this shard.
    pub fn keeps(self, index: usize) -> bool {
        index % self.count as usize == self.index as usize
    }
}

// ---- Helpers -------------------------------------------------------------------------

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

pub(super) fn too_many(file: &str, field: &str, runs: usize) -> Error {
    Error::invalid(
        file,
        field,
        format!("{runs} runs"),
        format!("a sweep may have at most {MAX_RUNS} runs (points x scenes)"),
    )
}
