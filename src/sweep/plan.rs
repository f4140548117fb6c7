//! The validated plan: a spec with its scenes and architectures loaded and every run's
//! `RenderJob` built and validated before the first run starts; a run's record.

use super::{
    bracket::Knob,
    grid::{arch_field, reword, set_arch_field, set_field},
    spec::{key, too_many, Point, Run, Setting, Shard, Spec, ARCH, MAX_RUNS, TECH},
};
use crate::camera::{Samples, View};
use crate::config::ArchConfig;
use crate::cost::tech::Tech;
use crate::datapath::Datapath;
use crate::discoid::blend::BlendMode;
use crate::error::{parent_dir, read_text_file, Error, Result};
use crate::frame::discoid::check_scene;
use crate::job::{
    check_available, check_samples, check_triangle_budget, memory_estimate, run_path, Given, Mode,
    PrimitivePath, RenderJob, TechSource, AA_SUPERSAMPLE,
};
use crate::reference::oracle::ReferenceImage;
use crate::reference::PixelsPerDegree;
use crate::report::Report;
use crate::scene::Scene;
use crate::tolerance::{PerspectiveTol, DEFAULT_K_PX};
use serde::Serialize;
use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::sync::Arc;

// ---- The validated plan --------------------------------------------------------------

/// A spec with its scenes loaded and every run's job built and validated: nothing in it
/// can be refused once a run starts, except what only a run can find (a patch beyond the
/// segment cap).
pub struct Plan {
    /// The expanded spec.
    pub spec: Spec,
    /// Its scenes, loaded, in the spec's order.
    pub scenes: Vec<Scene>,
    /// Each scene at each viewport its runs use: the spec's scenes first, in their order
    /// (frame s is scene s as loaded), then a frame a point's `viewport` asks for.
    pub(super) frames: Vec<Frame>,
    /// Each run's frame, by run index.
    pub(super) frame_of: Vec<usize>,
    /// Each point's architecture; None in functional mode.
    pub(super) archs: Vec<Option<ArchConfig>>,
    /// Each run's job, by index.
    pub(super) jobs: Vec<RenderJob>,
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
        let mut frames: Vec<Frame> = scenes
            .iter()
            .enumerate()
            .map(|(s, scene)| Frame {
                scene: s,
                viewport: None,
                own: None,
                view: View::new(&scene.camera, scene.viewport),
            })
            .collect();

        let mut archs = Vec::with_capacity(spec.points.len());
        let mut techs = Vec::with_capacity(spec.points.len());
        for point in &spec.points {
            archs.push(match &base {
                None => None,
                Some(base) => Some(point_arch(file, base, point)?),
            });
            techs.push(point_tech(file, point)?);
        }

        let mut jobs = Vec::with_capacity(spec.runs.len());
        let mut frame_of = Vec::with_capacity(spec.runs.len());
        for run in &spec.runs {
            let point = &spec.points[run.point];
            let f = frame(&mut frames, &scenes, run.scene, point, file)?;
            frame_of.push(f);
            let scene = frames[f].own.as_ref().unwrap_or(&scenes[run.scene]);
            check_applies(&spec, point, scene, run.scene)?;
            let mut job = render_job(&spec, point, scene, 1);
            job.tech = techs[run.point].clone().map(TechSource::Given);
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
            check_samples(job.samples, scene, file, &point.field("samples"))?;
            jobs.push(job);
        }
        one_target_a_frame(&mut jobs, &spec.runs, &frame_of, frames.len());
        Ok(Plan {
            spec,
            scenes,
            frames,
            frame_of,
            archs,
            jobs,
        })
    }

    /// The scene of frame `f`, at its viewport.
    pub(super) fn frame_scene(&self, f: usize) -> &Scene {
        let frame = &self.frames[f];
        frame.own.as_ref().unwrap_or(&self.scenes[frame.scene])
    }

    /// Run `run`'s scene, at its viewport.
    pub(super) fn run_scene(&self, run: &Run) -> &Scene {
        self.frame_scene(self.frame_of[run.index])
    }

    /// Refuses, before any run, runs that at `jobs` at once are estimated to need more
    /// memory than is available: the `jobs` largest estimates together, each with its own
    /// reference where it has one (DESIGN.md §8), unless `insist`.
    pub fn check_memory(&self, runs: &[&Run], jobs: usize, insist: bool) -> Result<()> {
        let mut estimates: Vec<(f64, usize)> = runs
            .iter()
            .map(|r| {
                let scene = self.run_scene(r);
                (memory_estimate(&self.jobs[r.index], scene, 0.0), r.index)
            })
            .collect();
        estimates.sort_by(|a, b| b.0.total_cmp(&a.0));
        let at_once = &estimates[..jobs.min(estimates.len())];
        let Some(&(_, largest)) = at_once.first() else {
            return Ok(());
        };
        let need: f64 = at_once.iter().map(|(e, _)| e).sum();
        let largest = &self.spec.runs[largest];
        let v = self.run_scene(largest).viewport;
        check_available(
            need,
            insist,
            ("--jobs", &jobs.to_string()),
            &format!(
                "{} runs at once (the largest {} at {}x{} px)",
                at_once.len(),
                self.spec.scenes[largest.scene],
                v.width,
                v.height
            ),
            "lower --jobs or the spec's viewports",
        )
    }

    /// Adds refinement runs (DESIGN.md §7, "Bracketing"): each `(from, knob)` is run
    /// `from`'s point with its accuracy knob set to `knob`, on run `from`'s scene and
    /// architecture. A run whose key the sweep has is not added again. Returns the added
    /// runs' indices, which follow every earlier run's.
    pub(super) fn extend(&mut self, additions: &[(usize, Knob)]) -> Result<Vec<usize>> {
        let file = self.spec.file.clone();
        let mut keys: BTreeSet<String> = self.spec.runs.iter().map(|r| r.key.clone()).collect();
        let mut added = Vec::new();
        for &(from, knob) in additions {
            let parent = self.spec.runs[from].clone();
            let mut point = self.spec.points[parent.point].clone();
            point.params.insert(knob.param().to_string(), knob.value());
            point
                .fields
                .insert(knob.param().to_string(), "refine".to_string());
            point
                .settings
                .retain(|s| !matches!(s, Setting::K(_) | Setting::Tess(_)));
            point.settings.push(match knob {
                Knob::K(k) => Setting::K(k),
                Knob::Tess(n) => Setting::Tess(n),
            });
            point.origin = "refine".to_string();
            point.scenes = vec![parent.scene];
            let run_key = key(&self.spec.scenes[parent.scene], &point.params);
            if !keys.insert(run_key.clone()) {
                continue;
            }
            if self.spec.runs.len() >= MAX_RUNS {
                return Err(too_many(&file, "refine", self.spec.runs.len() + 1));
            }
            let f = self.frame_of[from];
            let scene = self.frame_scene(f);
            let parent_job = &self.jobs[from];
            let mut job = render_job(&self.spec, &point, scene, parent_job.host_threads);
            // The same target as its series (a scene whose runs mix sample counts).
            job.tech = parent_job.tech.clone();
            job.supersample = parent_job.supersample;
            job.given.supersample = parent_job.given.supersample;
            job.validate()
                .map_err(|e| reword(e, &file, &point.field(knob.param())))?;
            if let Knob::Tess(n) = knob {
                check_triangle_budget(scene, n)
                    .map_err(|e| reword(e, &file, &point.field("tess")))?;
            }
            let p = match self
                .spec
                .points
                .iter()
                .position(|q| q.params == point.params)
            {
                Some(p) => {
                    let scenes = &mut self.spec.points[p].scenes;
                    scenes.push(parent.scene);
                    scenes.sort_unstable();
                    scenes.dedup();
                    p
                }
                None => {
                    self.archs.push(self.archs[parent.point].clone());
                    self.spec.points.push(point);
                    self.spec.points.len() - 1
                }
            };
            let index = self.spec.runs.len();
            self.spec.runs.push(Run {
                index,
                point: p,
                scene: parent.scene,
                key: run_key,
            });
            self.jobs.push(job);
            self.frame_of.push(f);
            added.push(index);
        }
        Ok(added)
    }

    /// Whether `scene` (by name, or by label with its viewport:
    /// [`crate::plot::scene_label`]; a scene's name has no space) can be tessellated at n
    /// triangles a lembo edge.
    pub(super) fn triangle_ok(&self, scene: &str, n: u32) -> bool {
        let scene = scene.split_once(' ').map_or(scene, |(name, _)| name);
        self.scenes
            .iter()
            .find(|s| s.name == scene)
            .is_some_and(|s| check_triangle_budget(s, n).is_ok())
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
    pub(super) fn run(&self, run: &Run, references: &[SweepReference]) -> Result<String> {
        let job = &self.jobs[run.index];
        let f = self.frame_of[run.index];
        let reference = if job.reference {
            references
                .iter()
                .find(|r| (r.frame, r.samples) == (f, job.samples))
                .map(|r| (&r.image, r.wall))
        } else {
            None
        };
        let mut out = run_path(
            job,
            self.frame_scene(f),
            &self.frames[f].view,
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

/// A frame whose measured runs mix sample counts measures them all against one target, the
/// area-averaged colours (DESIGN.md §6): its one-sample runs' reference is supersampled as
/// the others' ([`SweepReference::area_averaged`]).
fn one_target_a_frame(jobs: &mut [RenderJob], runs: &[Run], frame_of: &[usize], frames: usize) {
    for f in 0..frames {
        let measured: Vec<(usize, Samples)> = jobs
            .iter()
            .zip(runs)
            .filter(|(j, r)| frame_of[r.index] == f && j.reference)
            .map(|(j, r)| (r.index, j.samples))
            .collect();
        if measured.iter().any(|(_, n)| *n != Samples::ONE) {
            for (i, _) in measured.iter().filter(|(_, n)| *n == Samples::ONE) {
                jobs[*i].supersample = AA_SUPERSAMPLE;
                jobs[*i].given.supersample = true;
            }
        }
    }
}

/// One scene at one viewport: the spec's scene as loaded, or a copy at the viewport a
/// point's `viewport` parameter gives.
pub(super) struct Frame {
    /// The scene, an index into the plan's scenes.
    pub(super) scene: usize,
    /// The point's viewport; None for the scene as loaded.
    pub(super) viewport: Option<(u32, u32)>,
    /// The scene at that viewport; None for the scene as loaded.
    pub(super) own: Option<Scene>,
    /// Its view.
    pub(super) view: View,
}

/// The frame of scene `s` at `point`'s viewport, added to `frames` when new.
fn frame(
    frames: &mut Vec<Frame>,
    scenes: &[Scene],
    s: usize,
    point: &Point,
    file: &str,
) -> Result<usize> {
    let viewport = point.setting(|set| match set {
        Setting::Viewport(v) => Some(*v),
        _ => None,
    });
    let Some((w, h)) = viewport else {
        return Ok(s);
    };
    if let Some(f) = frames
        .iter()
        .position(|f| f.scene == s && f.viewport == viewport)
    {
        return Ok(f);
    }
    let mut scene = scenes[s].clone();
    scene
        .set_viewport(w, h)
        .map_err(|e| reword(e, file, &point.field(super::grid::VIEWPORT)))?;
    frames.push(Frame {
        scene: s,
        viewport,
        view: View::new(&scene.camera, scene.viewport),
        own: Some(scene),
    });
    Ok(frames.len() - 1)
}

/// The exact reference of one scene for the runs of one sample count: with more than one
/// sample a pixel, area-averaged ([`crate::job::render_reference`]); with one, the pixel
/// centres, or where the scene's runs mix sample counts the area-averaged colours with the
/// hits at the pixel centres ([`Self::area_averaged`]).
pub(super) struct SweepReference {
    /// The scene at its viewport, an index into the plan's frames.
    pub(super) frame: usize,
    /// The samples a pixel of the runs it measures.
    pub(super) samples: Samples,
    /// The image.
    pub(super) image: ReferenceImage,
    /// The wall time it took \[seconds\].
    pub(super) wall: f64,
}

impl SweepReference {
    /// Whether the one-sample runs of a scene are measured against the area-averaged
    /// colours: where the plan made their reference supersampled, because the scene's runs
    /// mix sample counts.
    pub(super) fn area_averaged(samples: Samples, supersample: u32) -> bool {
        samples == Samples::ONE && supersample > 1
    }
}

/// A point's architecture: the base with the point's `arch.<field>` values, validated; an
/// error names the spec field that set the refused value.
pub(super) fn point_arch(file: &str, base: &ArchConfig, point: &Point) -> Result<ArchConfig> {
    let mut value = serde_json::to_value(base).expect("the architecture serialises");
    for (path, v) in point.arch_overrides() {
        set_arch_field(&mut value, path, v.clone()).map_err(|message| Error::Parse {
            file: file.into(),
            field: point.field(&format!("{ARCH}{path}")),
            message,
        })?;
    }
    for (name, factor) in point.scales() {
        let Some(path) = name.strip_prefix(ARCH) else {
            continue;
        };
        let field = point.field(super::sensitivity::PARAM);
        let base = arch_field(&value, path).cloned().unwrap_or(Value::Null);
        let v = super::sensitivity::scaled(&base, factor)
            .map_err(|why| Error::invalid(file, &field, name, format!("{name} {why}")))?;
        set_arch_field(&mut value, path, v).map_err(|message| Error::Parse {
            file: file.into(),
            field: field.clone(),
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
        let at = e.path().to_string();
        // A field a sensitivity variant scaled to a value it does not take.
        if let Some((name, factor)) = point
            .scales()
            .find(|(name, _)| name.strip_prefix(ARCH) == Some(at.as_str()))
        {
            return Error::Parse {
                file: file.into(),
                field: point.field(super::sensitivity::PARAM),
                message: format!(
                    "{name} x{factor}: {}; a field of whole numbers takes only factors that keep it whole: give the parameter's `low` and `high` instead",
                    e.into_inner()
                ),
            };
        }
        Error::Parse {
            file: file.into(),
            field: blame(&at),
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

/// A point's technology: the embedded 45 nm file with the point's `tech.<field>` values,
/// validated as a technology file is; None when the point sets none (the run then prices
/// with the embedded file, as `render` without `--tech` does). An error names the spec
/// field that set the refused value.
pub(super) fn point_tech(file: &str, point: &Point) -> Result<Option<Arc<Tech>>> {
    let scales: Vec<(&str, f64)> = point
        .scales()
        .filter_map(|(name, f)| Some((name.strip_prefix(TECH)?, f)))
        .collect();
    if point.tech_overrides().next().is_none() && scales.is_empty() {
        return Ok(None);
    }
    let mut value = serde_json::to_value(Tech::default_45nm()).expect("the technology serialises");
    for (path, v) in point.tech_overrides() {
        set_field(&mut value, path, v.clone(), "technology").map_err(|message| Error::Parse {
            file: file.into(),
            field: point.field(&format!("{TECH}{path}")),
            message,
        })?;
    }
    // A sensitivity variant's technology figure, scaled from the point's.
    for (path, factor) in scales {
        let field = point.field(super::sensitivity::PARAM);
        let base = arch_field(&value, path).cloned().unwrap_or(Value::Null);
        let v = super::sensitivity::scaled(&base, factor)
            .map_err(|why| Error::invalid(file, &field, path, format!("{TECH}{path} {why}")))?;
        set_field(&mut value, path, v, "technology").map_err(|message| Error::Parse {
            file: file.into(),
            field,
            message,
        })?;
    }
    let blame = |tech_field: &str| {
        point
            .tech_overrides()
            .map(|(p, _)| p)
            .find(|p| *p == tech_field || tech_field.starts_with(&format!("{p}.")))
            .map(|p| point.field(&format!("{TECH}{p}")))
            .unwrap_or_else(|| point.origin.clone())
    };
    let tech: Tech = serde_path_to_error::deserialize(value).map_err(|e| Error::Parse {
        file: file.into(),
        field: blame(&e.path().to_string()),
        message: e.into_inner().to_string(),
    })?;
    tech.validate(file).map_err(|e| {
        let field = match &e {
            Error::Invalid { field, .. } => blame(field),
            _ => point.origin.clone(),
        };
        reword(e, file, &field)
    })?;
    Ok(Some(Arc::new(tech)))
}

/// Refuses settings that the scene would ignore, so that no two runs differ only in a
/// parameter that had no effect.
pub(super) fn check_applies(spec: &Spec, point: &Point, scene: &Scene, s: usize) -> Result<()> {
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
            "path" | "tess" | "samples" => !discoids,
            "k" | "perspective_tol" => curved,
            "blend" | "threshold" => discoids,
            // The discoid passes cull back-facing fragments, not whole primitives.
            "arch.minmax.cull_backfaces" | "arch.triangle_setup.cull_backfaces" => {
                !(discoids && point.params[name] == "on")
            }
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
pub(super) fn render_job(
    spec: &Spec,
    point: &Point,
    scene: &Scene,
    host_threads: u32,
) -> RenderJob {
    let mut job = RenderJob {
        trace: Default::default(),
        scene: None,
        out: None,
        k: DEFAULT_K_PX,
        perspective_tol: PerspectiveTol::FollowK,
        datapath: Datapath::F32,
        // A discoid scene is measured against the surface it stands for, where it says.
        reference: spec.reference && crate::job::check_reference_scene(scene).is_ok(),
        supersample: 1,
        samples: Samples::ONE,
        flip_ppd: PixelsPerDegree::default(),
        viewport: spec.viewport,
        mode: spec.mode,
        // Shown in the report's settings only: the architecture itself is the point's.
        arch: match spec.mode {
            Mode::Timed => spec.arch.as_ref().map(PathBuf::from),
            Mode::Functional => None,
        },
        arch_set: Vec::new(),
        trace_out: None,
        tech: None,
        path: PrimitivePath::Lembo,
        tess: None,
        blend: BlendMode::Rgba8,
        threshold: None,
        host_threads,
        // The runs at once (--jobs) fill the cores: one thread a frame.
        threads: (spec.mode == Mode::Functional).then_some(1),
        given: Given::default(),
        no_memory_check: false,
    };
    for s in &point.settings {
        match s {
            Setting::Path(p) => job.path = *p,
            Setting::K(k) => job.k = *k,
            Setting::PerspectiveTol(t) => job.perspective_tol = *t,
            Setting::Tess(n) => job.tess = Some(*n),
            Setting::Samples(n) => job.samples = *n,
            Setting::Datapath(d) => job.datapath = *d,
            Setting::Blend(m) => job.blend = *m,
            Setting::Threshold(t) => job.threshold = Some(*t),
            Setting::Viewport(v) => job.viewport = Some(*v),
            Setting::Arch(..) | Setting::Tech(..) | Setting::Scale(..) => {}
        }
    }
    job
}

/// One line of `results.jsonl`.
#[derive(Serialize)]
pub(super) struct Record<'a> {
    index: usize,
    key: &'a str,
    /// The scene's name.
    scene: &'a str,
    /// Every parameter the point sets, canonical.
    params: &'a BTreeMap<String, Value>,
    /// The run's full report.json.
    report: &'a Report,
}
