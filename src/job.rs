//! The `render` job: load the scene and the architecture, run the timed pipeline (or the
//! functional model alone), optionally the exact reference and its metrics, and write the
//! outputs. Flags arrive here already parsed; this
//! module validates them once into a [`RenderJob`] and nothing downstream re-checks them.

use crate::camera::{View, MAX_VIEWPORT_SIDE};
use crate::config::ArchConfig;
use crate::datapath::Datapath;
use crate::error::{Error, Result};
use crate::pipeline::{self, actor::SimOptions};
use crate::raster;
use crate::reference::{heatmap, metrics, oracle};
use crate::report::{png_bytes, write_files, Host, Report, SceneInfo, Settings, SCHEMA_VERSION};
use crate::scene::Scene;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Where command-line errors say they come from.
pub const COMMAND_LINE: &str = "command line";
/// Accepted range of the tolerance k [pixels] (DESIGN §8).
pub const K_RANGE: (f64, f64) = (1e-4, 64.0);
/// Largest accepted reference supersampling factor (samples per pixel side).
pub const MAX_SUPERSAMPLE: u32 = 8;

/// How a render is simulated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Mode {
    /// The Figure 5 pipeline with cycle accounting (the default).
    #[default]
    Timed,
    /// The functional model alone: the same image, no cycles.
    Functional,
}

/// A validated render request.
#[derive(Clone, Debug)]
pub struct RenderJob {
    /// Scene file, or None for the embedded default scene.
    pub scene: Option<PathBuf>,
    /// Output directory; None for `out/<scene name>/`.
    pub out: Option<PathBuf>,
    /// Tolerance k [pixels].
    pub k: f64,
    pub datapath: Datapath,
    pub reference: bool,
    /// Reference samples per pixel side.
    pub supersample: u32,
    /// Viewport override (width, height) [pixels].
    pub viewport: Option<(u32, u32)>,
    pub mode: Mode,
    /// Architecture file; None for the embedded baseline. Timed mode only.
    pub arch: Option<PathBuf>,
    /// Where to write the Chrome trace-event timeline. Timed mode only.
    pub trace_out: Option<PathBuf>,
}

impl RenderJob {
    /// Checks every flag; errors name the flag and the value.
    pub fn validate(&self) -> Result<()> {
        let (lo, hi) = K_RANGE;
        if !(self.k.is_finite() && self.k >= lo && self.k <= hi) {
            return Err(Error::invalid(
                COMMAND_LINE,
                "--k",
                self.k,
                format!("k must be a number in [{lo}, {hi}] pixels"),
            ));
        }
        if !(1..=MAX_SUPERSAMPLE).contains(&self.supersample) {
            return Err(Error::invalid(
                COMMAND_LINE,
                "--supersample",
                self.supersample,
                format!("must be in 1..={MAX_SUPERSAMPLE} samples per pixel side"),
            ));
        }
        if let Some((w, h)) = self.viewport {
            for (name, v) in [("--viewport width", w), ("--viewport height", h)] {
                if !(1..=MAX_VIEWPORT_SIDE).contains(&v) {
                    return Err(Error::invalid(
                        COMMAND_LINE,
                        name,
                        v,
                        format!("must be in 1..={MAX_VIEWPORT_SIDE} pixels"),
                    ));
                }
            }
        }
        if let Some(path) = &self.trace_out {
            if path.file_name().is_none() {
                return Err(Error::invalid(
                    COMMAND_LINE,
                    "--trace-out",
                    path.display(),
                    "must name a file",
                ));
            }
        }
        if self.mode == Mode::Functional {
            for (flag, set) in [
                ("--arch", self.arch.is_some()),
                ("--trace-out", self.trace_out.is_some()),
            ] {
                if set {
                    return Err(Error::invalid(
                        COMMAND_LINE,
                        flag,
                        "given",
                        "only meaningful with --mode timed",
                    ));
                }
            }
        }
        Ok(())
    }
}

/// What a finished render hands back to the caller for its summary.
pub struct RenderOutput {
    pub report: Report,
    pub dir: PathBuf,
    pub files: Vec<String>,
}

/// Loads the job's scene (or the embedded default) with the viewport override applied.
pub fn load_scene(job: &RenderJob) -> Result<Scene> {
    let mut scene = match &job.scene {
        Some(path) => Scene::load(path)?,
        None => Scene::default_scene(),
    };
    if let Some((w, h)) = job.viewport {
        scene.set_viewport(w, h)?;
    }
    Ok(scene)
}

/// Runs a render job to completion: nothing is written unless everything succeeded.
pub fn run_render(job: &RenderJob) -> Result<RenderOutput> {
    job.validate()?;
    let scene = load_scene(job)?;
    let view = View::new(&scene.camera, scene.viewport);

    let arch = match (&job.arch, job.mode) {
        (_, Mode::Functional) => None,
        (Some(path), Mode::Timed) => Some(ArchConfig::load(path)?),
        (None, Mode::Timed) => Some(ArchConfig::baseline()),
    };

    let t0 = Instant::now();
    let mut timed = None;
    let mut frame = None;
    match &arch {
        Some(arch) => {
            let options = SimOptions {
                trace: job.trace_out.is_some(),
                ..SimOptions::default()
            };
            timed = Some(pipeline::run_timed(
                &scene,
                &view,
                job.k,
                job.datapath,
                arch,
                &options,
            )?);
        }
        None => {
            frame = Some(raster::render_functional(
                &scene,
                &view,
                job.k,
                job.datapath,
                job.reference,
            )?)
        }
    }
    let wall = t0.elapsed().as_secs_f64();
    // Accuracy needs the fragment probe and the normal buffer of the functional model. The
    // timed image must equal it bit for bit (DESIGN §3); checked here on every such run.
    if job.reference && frame.is_none() {
        frame = Some(raster::render_functional(
            &scene,
            &view,
            job.k,
            job.datapath,
            true,
        )?);
    }
    let (image_fb, counts) = match (&timed, &frame) {
        (Some(t), _) => (&t.framebuffer, t.counts),
        (None, Some(f)) => (&f.framebuffer, f.counts),
        (None, None) => unreachable!("one model ran"),
    };
    if let (Some(t), Some(f)) = (&timed, &frame) {
        if t.framebuffer.color != f.framebuffer.color {
            return Err(Error::Internal(
                "the timed image differs from the functional one".into(),
            ));
        }
    }

    let mut files: Vec<(&str, Vec<u8>)> = vec![("image.png", png_bytes(&image_fb.to_image()))];
    let mut accuracy = None;
    let mut reference_wall = None;
    if let (true, Some(frame)) = (job.reference, frame.as_ref()) {
        let t1 = Instant::now();
        let lembos: Vec<_> = scene.lembos().collect();
        let reference = oracle::render_reference(&oracle::ReferenceInput {
            lembos: &lembos,
            view: &view,
            light: &scene.light,
            background: scene.background,
            supersample: job.supersample,
        });
        let probe = frame.probe.unwrap_or_default();
        accuracy = Some(metrics::measure(
            &frame.framebuffer,
            &reference,
            probe.double_hit_pixels,
            probe.max_scanline_deviation_px,
        ));
        let shown = reference
            .to_image_supersampled()
            .unwrap_or_else(|| reference.to_image());
        files.push(("reference.png", png_bytes(&shown)));
        files.push((
            "error.png",
            png_bytes(&heatmap::error_heatmap(&frame.framebuffer, &reference)),
        ));
        reference_wall = Some(t1.elapsed().as_secs_f64());
    }

    let report = Report {
        schema_version: SCHEMA_VERSION,
        scene: SceneInfo {
            name: scene.name.clone(),
            source: scene
                .source
                .as_ref()
                .map(|p| p.display().to_string())
                .unwrap_or_else(|| "(embedded default)".into()),
            width: scene.viewport.width,
            height: scene.viewport.height,
            lembos: scene.lembo_count() as u64,
            objects: scene
                .objects
                .iter()
                .map(|o| format!("{} ({} lembos)", o.label, o.lembos.len()))
                .collect(),
        },
        settings: Settings {
            mode: match job.mode {
                Mode::Timed => "timed",
                Mode::Functional => "functional",
            }
            .into(),
            arch_file: arch.as_ref().map(|_| {
                job.arch
                    .as_ref()
                    .map(|p| p.display().to_string())
                    .unwrap_or_else(|| "(embedded baseline)".into())
            }),
            path: "lembo".into(),
            k_px: job.k,
            datapath: job.datapath.name().into(),
            reference: job.reference,
            supersample: job.supersample,
        },
        units: timed.as_ref().map(|t| t.units.clone()).unwrap_or_default(),
        counts,
        cycles: timed.as_ref().map(|t| t.cycles.clone()),
        arch,
        accuracy,
        host: Host {
            wall_seconds: wall,
            fragments_per_second: if wall > 0.0 {
                counts.fragments as f64 / wall
            } else {
                0.0
            },
            simulated_cycles_per_second: timed
                .as_ref()
                .map(|t| t.cycles.total as f64 / wall.max(1e-9)),
            reference_wall_seconds: reference_wall,
        },
    };
    let json = serde_json::to_vec_pretty(&report).expect("the report serialises");
    files.push(("report.json", json));
    files.push(("report.txt", report.to_text().into_bytes()));

    let dir = job
        .out
        .clone()
        .unwrap_or_else(|| Path::new("out").join(&scene.name));
    // The timeline is written last, beside the other outputs or where --trace-out says,
    // with the same write-then-rename rule.
    write_files(&dir, &files)?;
    if let (Some(path), Some(trace)) = (&job.trace_out, timed.and_then(|t| t.trace)) {
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let parent = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        write_files(parent, &[(name.as_str(), trace.into_bytes())])?;
    }
    Ok(RenderOutput {
        report,
        dir,
        files: files.iter().map(|(n, _)| n.to_string()).collect(),
    })
}
