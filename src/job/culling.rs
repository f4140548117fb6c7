//! Back-face culling resolved for one run (DESIGN.md §5, "Back-face culling"): the
//! architecture's switch for the path drawn (`minmax.cull_backfaces`,
//! `triangle_setup.cull_backfaces`) and the scene decide, once, whether the rasterizers
//! cull and which winding is the front; the result travels in the run's
//! [`View`](crate::camera::View) to the functional model, the timed units and the counting
//! run alike, so that they cull the same primitives.

use super::route::{Model, Route};
use super::validate::RenderJob;
use crate::camera::{Culling, View, Winding};
use crate::config::{ArchConfig, CullBackfaces};
use crate::error::{Error, Result};
use crate::report::CullingSetting;
use crate::scene::Scene;

/// The field of `arch` that switches culling on the path `route` draws, and its value.
fn switch(arch: &ArchConfig, route: &Route) -> (&'static str, CullBackfaces) {
    match route {
        Route::Triangles(_) => (
            "triangle_setup.cull_backfaces",
            arch.triangle_setup.cull_backfaces,
        ),
        _ => ("minmax.cull_backfaces", arch.minmax.cull_backfaces),
    }
}

/// The architecture file as errors name it.
fn arch_file(job: &RenderJob) -> String {
    job.arch
        .as_ref()
        .map(|p| p.display().to_string())
        .unwrap_or_else(|| "(embedded baseline)".into())
}

/// Refuses culling asked of a discoid scene: its passes need every discoid's fragments
/// (the depth pass and the accumulation cull back-facing fragments one by one, §4), and an
/// atlas of overlapping discoids is no closed mesh a whole-primitive test could rely on.
pub fn check_discoids(job: &RenderJob, scene: &Scene, model: Model) -> Result<()> {
    let Some(arch) = model.arch() else {
        return Ok(());
    };
    for (field, value) in [
        ("minmax.cull_backfaces", arch.minmax.cull_backfaces),
        (
            "triangle_setup.cull_backfaces",
            arch.triangle_setup.cull_backfaces,
        ),
    ] {
        if value == CullBackfaces::On {
            return Err(Error::invalid(
                arch_file(job),
                field,
                value.name(),
                format!(
                    "does not apply to {}, a scene of {} discoids: the discoid passes cull \
                     back-facing fragments themselves and cannot cull whole primitives; use \
                     \"off\" or \"auto\"",
                    scene.name,
                    scene.discoid_count()
                ),
            ));
        }
    }
    Ok(())
}

/// The culling of a lembo or triangle `route` of `scene` seen through `view` on `model`,
/// and how the report states it. Functional mode, with no architecture, culls nothing.
pub fn resolve(
    scene: &Scene,
    view: &View,
    model: Model,
    route: &Route,
) -> (Culling, CullingSetting) {
    let value = model
        .arch()
        .map_or(CullBackfaces::Off, |a| switch(a, route).1);
    // Whether the scene is closed is asked only of a switch that reads it: the test sorts
    // every edge, 1.6 s of a 5 M-lembo functional frame's 11.
    let closed = match value {
        CullBackfaces::Off => None,
        _ => scene.outward_winding(),
    };
    let beyond = match (value, closed) {
        (CullBackfaces::Auto, Some(_)) => Some(scene.beyond_near_plane(view)),
        _ => None,
    };
    let culling = match (value, closed, beyond) {
        (CullBackfaces::On, w, _) => Culling::Back {
            front: w.unwrap_or(Winding::Ccw),
        },
        (CullBackfaces::Auto, Some(front), Some(true)) => Culling::Back { front },
        _ => Culling::Off,
    };
    let setting = CullingSetting {
        switch: value.name().into(),
        culled: culling != Culling::Off,
        front: match culling {
            Culling::Back { front } => Some(front),
            Culling::Off => None,
        },
        closed_outward: closed,
        beyond_near_plane: beyond,
    };
    (culling, setting)
}
