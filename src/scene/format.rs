//! The scene file's shape: private `*Spec` structs that serde reads with
//! `deny_unknown_fields`, before any value is checked.

use super::Light;
use crate::camera::Viewport;
use crate::discoid::BetaShape;
use serde::Deserialize;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SceneSpec {
    pub(super) name: String,
    pub(super) viewport: Option<Viewport>,
    pub(super) camera: CameraSpec,
    pub(super) light: Option<LightSpec>,
    pub(super) background: Option<[f64; 3]>,
    pub(super) discoid_threshold: Option<f64>,
    pub(super) objects: Vec<ObjectSpec>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CameraSpec {
    pub(super) eye: [f64; 3],
    pub(super) target: [f64; 3],
    #[serde(default = "default_up")]
    pub(super) up: [f64; 3],
    pub(super) projection: ProjectionSpec,
}

pub(super) fn default_up() -> [f64; 3] {
    [0.0, 1.0, 0.0]
}

/// The serde shape of [`Projection`], flattened so that errors name the exact field (an
/// internally tagged enum would buffer its content and lose the path below `projection`).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ProjectionSpec {
    pub(super) kind: ProjectionKind,
    pub(super) fovy_deg: Option<f64>,
    pub(super) height: Option<f64>,
    pub(super) near: f64,
    pub(super) far: f64,
}

#[derive(Clone, Copy, Deserialize)]
#[serde(rename_all = "lowercase")]
pub(super) enum ProjectionKind {
    Perspective,
    Orthographic,
}

/// A light whose missing terms take [`Light::default`]'s values.
#[derive(Deserialize)]
#[serde(default, deny_unknown_fields)]
pub(super) struct LightSpec {
    pub(super) direction_to_light: [f64; 3],
    pub(super) ka: f64,
    pub(super) kd: f64,
    pub(super) ks: f64,
    pub(super) shininess: f64,
}

impl Default for LightSpec {
    fn default() -> Self {
        let Light {
            direction_to_light,
            ka,
            kd,
            ks,
            shininess,
        } = Light::default();
        LightSpec {
            direction_to_light,
            ka,
            kd,
            ks,
            shininess,
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ObjectSpec {
    pub(super) builtin: Option<String>,
    pub(super) lembos: Option<Vec<LemboSpec>>,
    pub(super) mesh: Option<String>,
    pub(super) discoids: Option<DiscoidsSpec>,
    pub(super) color: Option<[f64; 3]>,
    pub(super) transform: Option<TransformSpec>,
    /// With `mesh` only: recompute the normals by auto-smooth at this crease angle.
    pub(super) crease_angle_deg: Option<f64>,
    /// Not with `discoids`: split each lembo into 4^s lembos over the same surface.
    pub(super) subdivide: Option<u32>,
}

/// An object's discoids: exactly one source, and the beta texture they carry.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct DiscoidsSpec {
    pub(super) items: Option<Vec<DiscoidItemSpec>>,
    pub(super) from_mesh: Option<String>,
    /// 0 or 1, with `from_mesh` only.
    pub(super) subdivide: Option<u32>,
    /// With `from_mesh` only.
    pub(super) radius_scale: Option<f64>,
    pub(super) builtin: Option<String>,
    pub(super) surfels: Option<String>,
    pub(super) beta: Option<BetaShape>,
    /// The mesh (OBJ) the discoids stand for, with `items` or `surfels`; `from_mesh` and
    /// `builtin` imply theirs.
    pub(super) surface: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct DiscoidItemSpec {
    pub(super) center: [f64; 3],
    pub(super) normal: [f64; 3],
    pub(super) radius: f64,
}

/// The one source of an object's discoids.
pub(super) enum DiscoidSource<'a> {
    Items(&'a [DiscoidItemSpec]),
    FromMesh(&'a str),
    Builtin(&'a str),
    Surfels(&'a str),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct LemboSpec {
    pub(super) points: [[f64; 3]; 6],
    pub(super) normals: [[f64; 3]; 6],
}

#[derive(Deserialize)]
#[serde(default, deny_unknown_fields)]
pub(super) struct TransformSpec {
    pub(super) scale: f64,
    pub(super) rotate_deg: [f64; 3],
    pub(super) translate: [f64; 3],
}

impl Default for TransformSpec {
    fn default() -> Self {
        TransformSpec {
            scale: 1.0,
            rotate_deg: [0.0; 3],
            translate: [0.0; 3],
        }
    }
}
