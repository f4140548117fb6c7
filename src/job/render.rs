//! `lembo-sim render`: the scene and architecture loaded, the reference rendered when asked,
//! one path run, and its files written as one set, nothing unless everything succeeded.

use super::memory::check_memory;
use super::path::run_path;
use super::reference::{reference_scene, render_reference_with};
use super::route::{check_samples, check_triangle_budget, Model};
use super::validate::{Mode, PrimitivePath, RenderJob};
use crate::camera::View;
use crate::config::ArchConfig;
use crate::error::{Result, COMMAND_LINE};
use crate::output::write_set;
use crate::report::html::{self, REPORT_HTML};
use crate::report::{peak_rss_bytes, png_bytes, Report};
use crate::scene::Scene;
use std::path::{Path, PathBuf};

/// What a finished render hands back to the caller for its summary.
pub struct RenderOutput {
    /// What `report.json` holds.
    pub report: Report,
    /// The folder the files were written to.
    pub dir: PathBuf,
    /// The files written, by name (the trace, when written elsewhere, is not listed).
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

/// The architecture a job runs on: None in functional mode.
pub fn load_arch(job: &RenderJob) -> Result<Option<ArchConfig>> {
    Ok(match (&job.arch, job.mode) {
        (_, Mode::Functional) => None,
        (Some(path), Mode::Timed) => {
            Some(ArchConfig::load(path)?.with_fields(&job.arch_set, "--set")?)
        }
        (None, Mode::Timed) => Some(ArchConfig::baseline().with_fields(&job.arch_set, "--set")?),
    })
}

/// The render's `report.html`: its images with what they show, links to its other files
/// (report.json, report.txt), and the report.
fn render_page(
    report: &Report,
    files: &[(&str, Vec<u8>)],
    trace: Option<&PathBuf>,
    dir: &Path,
) -> String {
    let images: Vec<(&str, String)> = files
        .iter()
        .filter(|(name, _)| name.ends_with(".png"))
        .map(|(name, _)| {
            let caption = match *name {
                "image.png" => format!(
                    "{} path, as the simulated unit drew it",
                    report.settings.path
                ),
                "reference.png" => {
                    "exact reference: each sample's ray against the true lembos, in f64".to_string()
                }
                "flip.png" => html::flip_map_caption(report),
                _ => html::ERROR_MAP_CAPTION.to_string(),
            };
            (*name, caption)
        })
        .collect();
    let others: Vec<&str> = files
        .iter()
        .map(|(name, _)| *name)
        .filter(|name| !name.ends_with(".png"))
        .collect();
    let trace = trace.map(|t| html::link_from(dir, t));
    html::render_page(report, &images, &others, trace.as_deref())
}

/// Runs a render job to completion: nothing is written unless everything succeeded.
pub fn run_render(job: &RenderJob) -> Result<RenderOutput> {
    job.validate()?;
    let scene = load_scene(job)?;
    check_samples(job.samples, &scene, COMMAND_LINE, "--samples")?;
    check_memory(job, &scene, 0.0)?;
    let view = View::new(&scene.camera, scene.viewport);
    let arch = load_arch(job)?;
    if job.path == PrimitivePath::Triangle {
        check_triangle_budget(&scene, job.tess.unwrap_or(1))?;
    }
    let reference = match job.reference {
        true => Some(render_reference_with(
            reference_scene(&scene)?.as_ref(),
            &view,
            job.reference_supersample(),
            job.samples,
            job.trace,
        )?),
        false => None,
    };
    let run = run_path(
        job,
        &scene,
        &view,
        Model::new(arch.as_ref()),
        reference.as_ref().map(|(r, w)| (r, *w)),
    )?;

    let mut images: Vec<(&str, image::RgbImage)> = vec![("image.png", run.framebuffer.to_image())];
    if let (Some((reference, _)), Some(maps)) = (&reference, run.error_maps) {
        let shown = reference
            .to_image_supersampled()
            .unwrap_or_else(|| reference.to_image());
        images.push(("reference.png", shown));
        images.push(("error.png", maps.colour));
        images.push(("flip.png", maps.flip));
    }
    // Encoded on the pool's threads, one image each, in the order listed.
    let mut files: Vec<(&str, Vec<u8>)> = {
        use rayon::prelude::*;
        images
            .par_iter()
            .map(|(name, image)| (*name, png_bytes(image)))
            .collect()
    };
    let mut report = run.report;
    // The images are encoded: what remains to allocate is the report and the writes.
    report.host.peak_rss_bytes = peak_rss_bytes();
    let json = serde_json::to_vec_pretty(&report).expect("the report serialises");
    files.push(("report.json", json));
    files.push(("report.txt", report.to_text().into_bytes()));

    let dir = job
        .out
        .clone()
        .unwrap_or_else(|| Path::new("out").join(&scene.name));
    // The timeline, where --trace-out says, is part of the same atomic set: a trace that
    // cannot be written leaves no image or report either.
    let mut elsewhere: Vec<(PathBuf, &[u8])> = Vec::new();
    if let (Some(path), Some(trace)) = (&job.trace_out, &run.trace) {
        elsewhere.push((path.clone(), trace.as_bytes()));
    }
    let page = render_page(&report, &files, elsewhere.first().map(|(p, _)| p), &dir);
    files.push((REPORT_HTML, page.into_bytes()));
    write_set(&dir, "render", &files, &elsewhere)?;
    Ok(RenderOutput {
        report,
        dir,
        files: files.iter().map(|(n, _)| n.to_string()).collect(),
    })
}
