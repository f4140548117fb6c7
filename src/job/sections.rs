//! The sections of a report every route fills in the same way: the scene, the settings and
//! the host.

use super::route::Model;
use super::validate::RenderJob;
use crate::pipeline::Cycle;
use crate::report::{
    peak_rss_bytes, CullingSetting, Host, PerspectiveSetting, SceneInfo, Settings,
};
use crate::scene::Scene;

/// The scene section of a report.
pub(super) fn scene_info(scene: &Scene) -> SceneInfo {
    SceneInfo {
        name: scene.name.clone(),
        source: scene.source_name(),
        width: scene.viewport.width,
        height: scene.viewport.height,
        lembos: scene.lembo_count() as u64,
        objects: scene
            .objects
            .iter()
            .map(|o| match &o.discoids {
                Some(d) => format!(
                    "{} ({} discoids, {} beta)",
                    o.label,
                    d.planar.len() + d.lembo_texcoords.len(),
                    d.beta.name()
                ),
                None => format!("{} ({} lembos)", o.label, o.lembos.len()),
            })
            .collect(),
    }
}

/// The settings section of a report.
pub(super) fn settings(
    job: &RenderJob,
    model: Model,
    path: &str,
    k_px: Option<f64>,
    tess: Option<u32>,
    reference: bool,
    culling: Option<CullingSetting>,
) -> Settings {
    let perspective_tol = k_px.map(|_| match job.tolerance().perspective {
        Some(px) => PerspectiveSetting::Px(px),
        None => PerspectiveSetting::Off("off"),
    });
    Settings {
        mode: match model {
            Model::Timed(_) => "timed",
            Model::Functional => "functional",
        }
        .into(),
        arch_file: model.arch().map(|_| {
            job.arch
                .as_ref()
                .map(|p| p.display().to_string())
                .unwrap_or_else(|| "(embedded baseline)".into())
        }),
        path: path.into(),
        k_px,
        perspective_tol,
        tess,
        datapath: job.datapath.name().into(),
        reference,
        supersample: job.reference_supersample(),
        samples: job.samples.get(),
        culling,
    }
}

/// The host section of a report; `timed` is the frame's cycles and the host threads.
pub(super) fn host(
    wall: f64,
    fragments: u64,
    timed: Option<(Cycle, u32)>,
    reference_wall: Option<f64>,
    metrics_wall: Option<f64>,
) -> Host {
    Host {
        wall_seconds: wall,
        fragments_per_second: if wall > 0.0 {
            fragments as f64 / wall
        } else {
            0.0
        },
        simulated_cycles_per_second: timed.map(|(c, _)| c.as_f64() / wall.max(1e-9)),
        host_threads: timed.map(|(_, n)| n),
        reference_wall_seconds: reference_wall,
        metrics_wall_seconds: metrics_wall,
        reference_tile_px: None,
        reference_threads: None,
        peak_rss_bytes: peak_rss_bytes(),
    }
}
