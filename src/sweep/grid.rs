//! Grid expansion: each block's or point's parameters parsed into canonical values
//! (`Given`), checked against the render settings and the architecture's shape, and
//! multiplied out into points (`Expander`).

use super::names::SENSITIVITY as PARAM;
use super::sensitivity::{Sensitivity, Vary};
use super::spec::{
    empty_list, key, too_many, Params, Point, Setting, ARCH, MAX_RUNS, SCENES, SETTINGS, TECH,
};
use crate::camera::{Samples, MAX_VIEWPORT_SIDE};
use crate::config::ArchConfig;
use crate::cost::tech::Tech;
use crate::datapath::Datapath;
use crate::discoid::blend::BlendMode;
use crate::error::{Error, Result};
use crate::job::{check_tess_range, check_threshold, Mode, PrimitivePath};
use crate::tolerance::{check_k, PerspectiveTol};
use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};

/// The parameter that sets a run's viewport.
pub(super) const VIEWPORT: &str = "viewport";

/// A viewport as a spec gives it, `[w, h]` or `"WxH"`, each side in
/// 1..=[`MAX_VIEWPORT_SIDE`] pixels; an error names `field`.
pub(super) fn viewport(file: &str, field: &str, v: &Value) -> Result<(u32, u32)> {
    let sides: Option<Vec<u64>> = match v {
        Value::Array(items) => items.iter().map(Value::as_u64).collect(),
        Value::String(s) => s
            .split_once('x')
            .and_then(|(w, h)| Some(vec![w.parse().ok()?, h.parse().ok()?])),
        _ => None,
    };
    let Some([w, h]) = sides.as_deref().and_then(|s| <[u64; 2]>::try_from(s).ok()) else {
        return Err(Error::Parse {
            file: file.into(),
            field: field.into(),
            message: format!(
                "expected a viewport as [width, height] or \"WIDTHxHEIGHT\" in pixels, found {v}"
            ),
        });
    };
    for side in [w, h] {
        if !(1..=MAX_VIEWPORT_SIDE as u64).contains(&side) {
            return Err(Error::invalid(
                file,
                field,
                v,
                format!("each side must be in 1..={MAX_VIEWPORT_SIDE} pixels"),
            ));
        }
    }
    Ok((w as u32, h as u32))
}

/// A parameter value as given: parsed, canonical, and where in the spec.
#[derive(Clone)]
pub(super) struct Given {
    setting: Setting,
    canonical: Value,
    field: String,
}

/// Builds the points of a spec, block by block.
pub(super) struct Expander<'a> {
    pub(super) file: &'a str,
    pub(super) scenes: &'a [String],
    pub(super) mode: Mode,
    /// `ArchConfig::default()` as JSON: the shape every architecture file has, against
    /// which `arch.<field>` names and value types are checked.
    pub(super) arch_shape: Value,
    /// The embedded technology file as JSON, against which `tech.<field>` names and value
    /// types are checked.
    pub(super) tech_shape: Value,
    pub(super) points: Vec<Point>,
    pub(super) by_params: BTreeMap<String, usize>,
    /// The spec's `viewport` list where it lists several: every point runs at each.
    pub(super) viewports: Vec<(Setting, Value, String)>,
}

impl Expander<'_> {
    pub(super) fn block(&mut self, b: usize, block: &Params) -> Result<()> {
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

    pub(super) fn point(&mut self, p: usize, point: &Params) -> Result<()> {
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
        if self.viewports.is_empty() {
            return self.add_point(origin, point);
        }
        if point.params.contains_key(VIEWPORT) {
            return Err(Error::invalid(
                self.file,
                point.field(VIEWPORT),
                &point.params[VIEWPORT],
                "the spec's `viewport` lists several viewports, which every point runs at; give the viewports there or here, not both",
            ));
        }
        for (setting, canonical, field) in self.viewports.clone() {
            let mut at = point.clone();
            at.params.insert(VIEWPORT.to_string(), canonical);
            at.fields.insert(VIEWPORT.to_string(), field);
            at.settings.push(setting);
            self.add_point(origin, at)?;
        }
        Ok(())
    }

    /// Adds a checked point, or its scenes to an equal point already added.
    fn add_point(&mut self, origin: &str, point: Point) -> Result<()> {
        let scenes = point.scenes.clone();
        let k = key("", &point.params);
        match self.by_params.get(&k) {
            Some(&i) => {
                let known = &mut self.points[i].scenes;
                known.extend_from_slice(&scenes);
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

    /// Adds the variants of a sensitivity study (`super::sensitivity`): for each of its
    /// parameters, a low and a high variant of every point so far that sets no
    /// architecture field (the spec's architecture as it is), of the paths it names.
    pub(super) fn sensitivity(&mut self, study: &Sensitivity) -> Result<()> {
        let base: Vec<Point> = self
            .points
            .iter()
            .filter(|p| {
                !p.params
                    .keys()
                    .any(|k| k.starts_with(ARCH) || k.starts_with(TECH))
            })
            .cloned()
            .collect();
        if base.is_empty() {
            return Err(Error::invalid(
                self.file,
                "sensitivity",
                "present",
                "varies the points that set no `arch.` or `tech.` field (the spec's architecture and technology as they are); the grid and points have none",
            ));
        }
        for param in &study.params {
            if let Some(path) = param.name.strip_prefix(ARCH) {
                let found = arch_field(&self.arch_shape, path);
                if !found.is_some_and(Value::is_number) {
                    return Err(Error::invalid(
                        self.file,
                        &param.field,
                        &param.name,
                        "must name a number field of the architecture",
                    ));
                }
            }
            if let Some(path) = param.name.strip_prefix(TECH) {
                let shape = serde_json::to_value(crate::cost::tech::Tech::default_45nm())
                    .expect("the technology serialises");
                if !arch_field(&shape, path).is_some_and(Value::is_number) {
                    return Err(Error::invalid(
                        self.file,
                        &param.field,
                        &param.name,
                        "must name a number field of the technology file",
                    ));
                }
            }
            let ends: [(Setting, Option<Given>); 2] = match &param.vary {
                Vary::Factors(lo, hi) => {
                    [*lo, *hi].map(|f| (Setting::Scale(param.name.clone(), f), None))
                }
                Vary::Values(lo, hi) => {
                    let given = |v: &Value, end: &str| -> Result<(Setting, Option<Given>)> {
                        let field = format!("{}.{end}", param.field);
                        let (setting, canonical) = self.setting(&param.name, v, &field)?;
                        Ok((
                            setting.clone(),
                            Some(Given {
                                setting,
                                canonical,
                                field,
                            }),
                        ))
                    };
                    [given(lo, "low")?, given(hi, "high")?]
                }
            };
            for point in &base {
                let path = point.path().unwrap_or(PrimitivePath::Lembo);
                if !param.applies(path) {
                    continue;
                }
                for ((setting, given), tag) in ends.iter().zip(param.tags()) {
                    let mut v = point.clone();
                    v.origin = param.field.clone();
                    v.params.insert(PARAM.to_string(), Value::from(tag));
                    v.fields.insert(PARAM.to_string(), param.field.clone());
                    match given {
                        Some(g) => {
                            v.params.insert(param.name.clone(), g.canonical.clone());
                            v.fields.insert(param.name.clone(), g.field.clone());
                            v.settings.retain(|s| !same_arch_field(s, &param.name));
                            v.settings.push(g.setting.clone());
                        }
                        None => v.settings.push(setting.clone()),
                    }
                    self.add_point(&param.field, v)?;
                }
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
            if let Some(name) = point
                .params
                .keys()
                .find(|n| n.starts_with(ARCH) || n.starts_with(TECH))
            {
                return Err(Error::invalid(
                    self.file,
                    point.field(name),
                    &point.params[name],
                    "architecture and technology fields are only meaningful with mode timed",
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
                Setting::K(check_k(number()?).map_err(|why| Error::invalid(file, field, v, why))?)
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
            "samples" => {
                let n = v
                    .as_u64()
                    .ok_or_else(|| parse(format!("expected a whole number, found {v}")))?;
                let n = u32::try_from(n).unwrap_or(u32::MAX);
                Setting::Samples(
                    Samples::try_from(n).map_err(|why| Error::invalid(file, field, v, why))?,
                )
            }
            "viewport" => Setting::Viewport(viewport(file, field, v)?),
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
            "threshold" => Setting::Threshold(
                check_threshold(number()?).map_err(|why| Error::invalid(file, field, v, why))?,
            ),
            _ => {
                if let Some(path) = name.strip_prefix(ARCH) {
                    let canonical = self.arch_value(path, v, field)?;
                    return Ok((Setting::Arch(path.to_string(), v.clone()), canonical));
                }
                if let Some(path) = name.strip_prefix(TECH) {
                    let canonical = self.tech_value(path, v, field)?;
                    return Ok((Setting::Tech(path.to_string(), v.clone()), canonical));
                }
                return Err(parse(format!(
                    "unknown parameter `{name}`; expected {}, `arch.<field>`, `tech.<field>` or `scenes`",
                    SETTINGS.join(", ")
                )));
            }
        };
        let canonical = canonical_value(&setting);
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

    /// Checks that `tech.<path>` names a figure of the technology file and `v` has its
    /// type; returns the value as the file serialises it (its range is checked with the
    /// point's whole technology, by the plan).
    fn tech_value(&self, path: &str, v: &Value, field: &str) -> Result<Value> {
        let parse = |message: String| Error::Parse {
            file: self.file.into(),
            field: field.into(),
            message,
        };
        let mut shape = self.tech_shape.clone();
        set_field(&mut shape, path, v.clone(), "technology").map_err(parse)?;
        let tech: Tech = serde_path_to_error::deserialize(shape)
            .map_err(|e| parse(e.into_inner().to_string()))?;
        let back = serde_json::to_value(tech).expect("the technology serialises");
        Ok(arch_field(&back, path).cloned().unwrap_or(Value::Null))
    }
}

/// The canonical JSON of a setting [`Expander::setting`] parsed from a named parameter, as
/// the results record it. An architecture or technology field's is worked out where it is
/// parsed, and a scale is not parsed from a value.
fn canonical_value(setting: &Setting) -> Value {
    match setting {
        Setting::Path(p) => Value::from(p.name()),
        Setting::K(x) | Setting::Threshold(x) => Value::from(*x),
        Setting::PerspectiveTol(t) => match t {
            PerspectiveTol::Px(px) => Value::from(*px),
            _ => Value::from("off"),
        },
        Setting::Tess(n) => Value::from(*n),
        Setting::Samples(n) => Value::from(n.get()),
        Setting::Viewport((w, h)) => Value::from(format!("{w}x{h}")),
        Setting::Datapath(d) => Value::from(d.name()),
        Setting::Blend(m) => Value::from(m.name()),
        Setting::Arch(..) | Setting::Tech(..) | Setting::Scale(..) => {
            unreachable!("Expander::setting returns these with their canonical value")
        }
    }
}

/// Whether `s` sets the architecture field named `name` (`arch.<path>`).
fn same_arch_field(s: &Setting, name: &str) -> bool {
    matches!(s, Setting::Arch(p, _) if name.strip_prefix(ARCH) == Some(p.as_str()))
}

/// Sets the field at `path` (dotted) of an architecture's JSON; the field must exist and
/// not be a group of fields. The error says which part is unknown and what is there.
pub(super) fn set_arch_field(
    arch: &mut Value,
    path: &str,
    v: Value,
) -> std::result::Result<(), String> {
    set_field(arch, path, v, "architecture")
}

pub(super) use crate::json::{field_at as arch_field, set_field};

pub(super) use super::names::reword;
