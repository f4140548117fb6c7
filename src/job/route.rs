//! What a run is, as types decided once: the [`Model`] it is simulated on and the [`Route`]
//! its scene is drawn by; a setting given where the route does not use it is refused, and a
//! tessellation must stay within [`MAX_TRIANGLES`]. Also what a route yields ([`PathRun`])
//! and the host options a timed run is simulated with.

use super::reference::check_reference_scene;
use super::validate::{PrimitivePath, RenderJob};
use crate::camera::{Samples, MAX_VIEWPORT_SIDE};
use crate::config::ArchConfig;
use crate::error::{Error, Result, COMMAND_LINE};
use crate::lembo::tessellate::Tessellation;
use crate::pipeline::SimOptions;
use crate::report::Report;
use crate::rop::FrameBuffer;
use crate::scene::Scene;

/// The most triangles a tessellated scene may have: beyond it a run takes hours, and
/// triangle ids must fit 32 bits.
pub const MAX_TRIANGLES: u64 = 1 << 26;

/// The scene tessellated at level n must stay within [`MAX_TRIANGLES`].
pub fn check_triangle_budget(scene: &Scene, n: u32) -> Result<()> {
    let triangles = scene.lembo_count() as u64 * n as u64 * n as u64;
    if triangles > MAX_TRIANGLES {
        return Err(Error::invalid(
            COMMAND_LINE,
            "--tess",
            n,
            format!(
                "{} lembos x {n}² = {triangles} triangles, more than the {MAX_TRIANGLES} accepted",
                scene.lembo_count()
            ),
        ));
    }
    Ok(())
}

/// Which model a run is simulated on.
#[derive(Clone, Copy, Debug)]
pub enum Model<'a> {
    /// The functional model alone: the image and its counts, no cycles.
    Functional,
    /// The timed pipeline of this architecture (the image is checked against the
    /// functional model's wherever both ran).
    Timed(&'a ArchConfig),
}

impl<'a> Model<'a> {
    /// The model of a job whose architecture [`load_arch`](super::load_arch) gave: timed when there is one.
    pub fn new(arch: Option<&'a ArchConfig>) -> Self {
        arch.map_or(Model::Functional, Model::Timed)
    }

    /// The architecture, for a timed run.
    pub fn arch(self) -> Option<&'a ArchConfig> {
        match self {
            Model::Functional => None,
            Model::Timed(arch) => Some(arch),
        }
    }
}

/// What a scene is drawn as: decided once, from the scene and `--path`.
pub enum Route<'s> {
    /// Its lembos, by the extreme method.
    Lembos,
    /// Its lembos tessellated into triangles, rasterized as a GPU does.
    Triangles(Tessellation<'s>),
    /// Its atlas of discoids, in three passes through the ROPs' blend units.
    Discoids,
}

impl<'s> Route<'s> {
    /// The route of `job` on `scene`; a tessellation must stay within [`MAX_TRIANGLES`].
    pub fn new(job: &RenderJob, scene: &'s Scene) -> Result<Self> {
        check_applies(job, scene)?;
        if scene.discoid_count() > 0 {
            return Ok(Route::Discoids);
        }
        Ok(match job.path {
            PrimitivePath::Lembo => Route::Lembos,
            PrimitivePath::Triangle => {
                let level = job.tess.unwrap_or(1);
                check_triangle_budget(scene, level)?;
                Route::Triangles(Tessellation::new(scene.lembo_sets(), level))
            }
        })
    }
}

/// Refuses a setting the user gave that does not apply to `scene` or to the path: the
/// discoid settings on a scene without discoids, the path and tessellation on a discoid
/// scene, k and the perspective tolerance where no lembo is drawn.
fn check_applies(job: &RenderJob, scene: &Scene) -> Result<()> {
    let discoids = scene.discoid_count();
    if job.reference {
        check_reference_scene(scene)?;
    }
    let curved = scene.lembo_count() > 0;
    let lembos_drawn = if discoids > 0 {
        curved
    } else {
        job.path == PrimitivePath::Lembo
    };
    let on_scene = if discoids > 0 {
        format!(
            "does not apply to {}, a scene of {discoids} {} discoids",
            scene.name,
            if curved { "curved" } else { "planar" }
        )
    } else {
        format!("does not apply to {}, which has no discoids", scene.name)
    };
    let no_lembos = if discoids > 0 {
        on_scene.clone()
    } else {
        "does not apply to the triangle path (it has no tolerance k)".to_string()
    };
    let given: [(&str, bool, String, bool, &String); 6] = [
        (
            "--path",
            job.given.path,
            job.path.name().into(),
            discoids == 0,
            &on_scene,
        ),
        (
            "--tess",
            job.tess.is_some(),
            job.tess.unwrap_or_default().to_string(),
            discoids == 0,
            &on_scene,
        ),
        (
            "--blend",
            job.given.blend,
            job.blend.name().into(),
            discoids > 0,
            &on_scene,
        ),
        (
            "--threshold",
            job.threshold.is_some(),
            job.threshold.unwrap_or_default().to_string(),
            discoids > 0,
            &on_scene,
        ),
        (
            "--k",
            job.given.k,
            job.k.to_string(),
            lembos_drawn,
            &no_lembos,
        ),
        (
            "--perspective-tol",
            job.given.perspective_tol,
            "given".into(),
            lembos_drawn,
            &no_lembos,
        ),
    ];
    for (flag, set, value, applies, why) in given {
        if set && !applies {
            return Err(Error::invalid(COMMAND_LINE, flag, value, why.as_str()));
        }
    }
    check_samples(job.samples, scene, COMMAND_LINE, "--samples")
}

/// Refuses `samples` per pixel on `scene` where the unit cannot draw them: on a discoid
/// scene (the blend units keep one accumulation per pixel), and where the sample grid would
/// have more rows than [`MAX_VIEWPORT_SIDE`] (the rasterizers' fixed-point range). `file`
/// and `field` name where the value came from.
pub fn check_samples(samples: Samples, scene: &Scene, file: &str, field: &str) -> Result<()> {
    if samples == Samples::ONE {
        return Ok(());
    }
    let discoids = scene.discoid_count();
    if discoids > 0 {
        return Err(Error::invalid(
            file,
            field,
            samples,
            format!(
                "does not apply to {}, a scene of {discoids} discoids: the blend units keep one \
                 accumulation per pixel and do not multisample",
                scene.name
            ),
        ));
    }
    let rows = scene.viewport.height as u64 * samples.get() as u64;
    if rows > MAX_VIEWPORT_SIDE as u64 {
        return Err(Error::invalid(
            file,
            field,
            samples,
            format!(
                "the sample grid of {}'s {} rows would have {rows} rows; at most \
                 {MAX_VIEWPORT_SIDE} (samples x viewport height)",
                scene.name, scene.viewport.height
            ),
        ));
    }
    Ok(())
}

pub use crate::lembo::LEMBO_BYTES;

/// One path's run on a loaded scene: what `render` writes, and what `compare` puts side by
/// side.
pub struct PathRun {
    /// The run's report.
    pub report: Report,
    /// The image (the timed pipeline's, or the functional model's).
    pub framebuffer: FrameBuffer,
    /// The error maps against the reference, when one was given.
    pub error_maps: Option<super::reference::ErrorMaps>,
    /// Chrome trace-event JSON, when requested.
    pub trace: Option<String>,
}

/// The host options of a timed run of `job` on `path`: `--host-threads` is refused when it
/// exceeds the units the run instantiates (each host thread runs at least one unit).
pub(super) fn sim_options(
    job: &RenderJob,
    arch: &ArchConfig,
    path: PrimitivePath,
) -> Result<SimOptions> {
    let units = arch.instances(path).len();
    if job.host_threads as usize > units {
        return Err(Error::invalid(
            COMMAND_LINE,
            "--host-threads",
            job.host_threads,
            format!("more than the {units} units this run instantiates (each host thread runs at least one)"),
        ));
    }
    Ok(SimOptions {
        host_threads: job.host_threads as usize,
        trace: job.trace_out.is_some(),
        ..SimOptions::default()
    })
}
