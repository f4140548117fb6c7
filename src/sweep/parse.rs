//! `Spec::parse`: a spec file's own fields checked (name, scenes, viewport, mode, area
//! budget) and its grid blocks and points expanded ([`super::grid`]) into points and runs.

use super::bracket::Refine;
use super::curves::Targets;
use super::grid::{viewport as viewport_of, Expander};
use super::sensitivity::Sensitivity;
use super::spec::{
    check_name, empty_list, key, too_many, Point, Run, Setting, Spec, SpecFile, MAX_RUNS,
};
use crate::camera::MAX_VIEWPORT_SIDE;
use crate::config::ArchConfig;
use crate::cost::tech::Tech;
use crate::error::{Error, Result};
use crate::job::Mode;
use crate::json::parse_strict;
use serde_json::Value;
use std::collections::BTreeMap;

impl Spec {
    /// Parses and expands a spec; `file` names it in messages.
    pub fn parse(text: &str, file: &str) -> Result<Spec> {
        let f: SpecFile = parse_strict(text, file)?;
        let value: Value = serde_json::from_str(text).expect("the spec parsed once already");

        check_name(file, &f.name)?;
        if f.scenes.is_empty() {
            return Err(empty_list(file, "scenes"));
        }
        let viewports = check_viewport(file, f.viewport.as_ref())?;
        let mode = check_mode(file, &f)?;

        let (refine, targets) = answer_settings(file, &f)?;

        let mut ex = Expander {
            file,
            scenes: &f.scenes,
            mode,
            arch_shape: serde_json::to_value(ArchConfig::default())
                .expect("the architecture serialises"),
            tech_shape: serde_json::to_value(Tech::default_45nm())
                .expect("the technology serialises"),
            points: Vec::new(),
            by_params: BTreeMap::new(),
            viewports: viewports.axis(),
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

        let sensitivity = match &f.sensitivity {
            None => None,
            Some(sf) => {
                if f.area_budget_mm2.is_none() {
                    return Err(Error::invalid(
                        file,
                        "sensitivity",
                        "present",
                        "the speed-up it reads is the answer's, within `area_budget_mm2`",
                    ));
                }
                let study = Sensitivity::from_file(file, sf)?;
                ex.sensitivity(&study)?;
                Some(study)
            }
        };

        let runs = runs_of(file, &ex.points, &f.scenes)?;
        let spec = Spec {
            file: file.to_string(),
            text: text.to_string(),
            value,
            name: f.name,
            viewport: match viewports {
                Viewports::One(vp) => Some(vp),
                Viewports::Scenes | Viewports::Each(_) => None,
            },
            mode,
            reference: f.reference.unwrap_or(true),
            arch: f.arch,
            area_budget_mm2: f.area_budget_mm2,
            by: f.by,
            refine,
            targets,
            sensitivity,
            points: ex.points,
            runs,
            scenes: f.scenes,
        };
        if let Some(by) = &spec.by {
            super::by::check_by(&spec, file, "by", by)?;
        }
        Ok(spec)
    }
}

/// The spec's `viewport`, checked: one viewport for every scene (`[w, h]`), or a list of
/// them (`[[w, h], "WxH"]`) that every point runs at, as its `viewport` parameter. A list of
/// one is the one viewport.
fn check_viewport(file: &str, viewport: Option<&Value>) -> Result<Viewports> {
    let one = |field: &str, v: &Value| viewport_of(file, field, v);
    match viewport {
        None => Ok(Viewports::Scenes),
        Some(Value::Array(items)) if items.is_empty() => Err(empty_list(file, "viewport")),
        Some(Value::Array(items)) if items.iter().all(|v| v.is_number()) => {
            // One viewport; a side out of range is named by its index.
            for (i, side) in items.iter().enumerate() {
                if side
                    .as_u64()
                    .is_some_and(|s| s == 0 || s > MAX_VIEWPORT_SIDE as u64)
                {
                    return Err(Error::invalid(
                        file,
                        format!("viewport[{i}]"),
                        side,
                        format!("must be in 1..={MAX_VIEWPORT_SIDE} pixels"),
                    ));
                }
            }
            Ok(Viewports::One(one("viewport", viewport.expect("matched"))?))
        }
        Some(Value::Array(items)) => {
            let mut list: Vec<(u32, u32)> = Vec::new();
            for (i, v) in items.iter().enumerate() {
                let field = format!("viewport[{i}]");
                let vp = one(&field, v)?;
                if list.contains(&vp) {
                    return Err(Error::invalid(file, field, v, "is listed twice"));
                }
                list.push(vp);
            }
            Ok(match list[..] {
                [vp] => Viewports::One(vp),
                _ => Viewports::Each(list),
            })
        }
        Some(other) => Ok(Viewports::One(one("viewport", other)?)),
    }
}

/// What a spec's `viewport` asks for.
enum Viewports {
    /// Each scene's own.
    Scenes,
    /// One for every scene.
    One((u32, u32)),
    /// Every point at each of these.
    Each(Vec<(u32, u32)>),
}

impl Viewports {
    /// The `viewport` parameter's values every point is crossed with, each with its
    /// setting, canonical value and field; none unless the spec lists several.
    fn axis(&self) -> Vec<(Setting, Value, String)> {
        let Viewports::Each(list) = self else {
            return Vec::new();
        };
        list.iter()
            .enumerate()
            .map(|(i, &(w, h))| {
                (
                    Setting::Viewport((w, h)),
                    Value::from(format!("{w}x{h}")),
                    format!("viewport[{i}]"),
                )
            })
            .collect()
    }
}

/// The spec's mode, with the fields only a timed sweep may have (`arch`,
/// `area_budget_mm2`) checked against it.
fn check_mode(file: &str, f: &SpecFile) -> Result<Mode> {
    let mode = f.mode;
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
    Ok(mode)
}

/// Every point's runs, one a scene it names, in order; at most [`MAX_RUNS`].
fn runs_of(file: &str, points: &[Point], scenes: &[String]) -> Result<Vec<Run>> {
    let mut runs = Vec::new();
    for (p, point) in points.iter().enumerate() {
        for &s in &point.scenes {
            runs.push(Run {
                index: runs.len(),
                point: p,
                scene: s,
                key: key(&scenes[s], &point.params),
            });
        }
    }
    if runs.len() > MAX_RUNS {
        return Err(too_many(file, "grid", runs.len()));
    }
    Ok(runs)
}

/// The answer's settings of a spec (`refine`, `targets`), checked: refinement needs the
/// reference, targets an area budget.
fn answer_settings(file: &str, f: &SpecFile) -> Result<(Option<Refine>, Targets)> {
    let refine = match &f.refine {
        None => None,
        Some(r) => {
            if f.reference == Some(false) {
                return Err(Error::invalid(
                        file,
                        "refine",
                        "present",
                        "refinement follows the error against the exact reference; it needs `reference` true",
                    ));
            }
            Some(Refine::from_file(file, r)?)
        }
    };

    let targets = match &f.targets {
        None => Targets::default(),
        Some(t) => {
            if f.area_budget_mm2.is_none() {
                return Err(Error::invalid(
                        file,
                        "targets",
                        "present",
                        "the answer's targets need `area_budget_mm2` (the answer compares the paths within it)",
                    ));
            }
            Targets::from_file(file, t)?
        }
    };

    Ok((refine, targets))
}
