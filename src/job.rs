//! The `render` job: load the scene, run the functional model, optionally the exact
//! reference and its metrics, and write the outputs. Flags arrive here already parsed; this
//! module validates them once into a [`RenderJob`] and nothing downstream re-checks them.

use crate::camera::{View, MAX_VIEWPORT_SIDE};
use crate::datapath::Datapath;
use crate::error::{Error, Result};
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

    let t0 = Instant::now();
    let frame = raster::render_functional(&scene, &view, job.k, job.datapath, job.reference)?;
    let wall = t0.elapsed().as_secs_f64();

    let mut files: Vec<(&str, Vec<u8>)> =
        vec![("image.png", png_bytes(&frame.framebuffer.to_image()))];
    let mut accuracy = None;
    let mut reference_wall = None;
    if job.reference {
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
            mode: "functional".into(),
            path: "lembo".into(),
            k_px: job.k,
            datapath: job.datapath.name().into(),
            reference: job.reference,
            supersample: job.supersample,
        },
        counts: frame.counts,
        cycles: None,
        accuracy,
        host: Host {
            wall_seconds: wall,
            fragments_per_second: if wall > 0.0 {
                frame.counts.fragments as f64 / wall
            } else {
                0.0
            },
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
    write_files(&dir, &files)?;
    Ok(RenderOutput {
        report,
        dir,
        files: files.iter().map(|(n, _)| n.to_string()).collect(),
    })
}
