//! Scenes: the JSON trace files of `traces/` (DESIGN.md §7), parsed and validated once into a
//! [`Scene`] that nothing downstream re-checks.
//!
//! A scene file holds a name, a viewport, a camera, a light, a background colour, a
//! discoid blending threshold and a list of objects. Each object is a builtin shape (Martinelli
//! 2006 Figures 6-8), inline lembos (six points and six normals each), a triangle mesh in an
//! OBJ file, or discoids (Piranda et al. 2006; DESIGN.md §4), with a material colour and a
//! similarity transform. Builtins, inline lembos and meshes end up as world-space lembos; builtins
//! and meshes also keep their world-space triangle mesh for the triangle path. Discoid objects end
//! up as a [`DiscoidSet`]: planar discoids given inline, placed at the vertices of an OBJ mesh, or
//! read as surfels from a PLY point cloud (Pfister et al. 2000); or the curved discoids of
//! `sphere20` (Piranda et al. 2006 Figure 10), whose lembos also go into the object's lembos so
//! that the lembo path draws them.
//!
//! The file is read into private `*Spec` structs (serde, `deny_unknown_fields`) and then
//! validated field by field. Every error names the file, the field path in one style
//! (`viewport.width`, `camera.projection.near`, `objects[1].transform.scale`) and the
//! value (DESIGN.md §8): serde errors become [`Error::Parse`] with the path that
//! [`crate::json`] tracked, refused values become [`Error::Invalid`], and mesh files and
//! point-cloud files that cannot be loaded or hold bad numbers become [`Error::Mesh`].
//!
//! [`Error::Parse`]: crate::error::Error::Parse
//! [`Error::Invalid`]: crate::error::Error::Invalid
//! [`Error::Mesh`]: crate::error::Error::Mesh
//!
//! Layout: this file the validated [`Scene`] and the format's defaults and bounds, which the
//! children import (it imports none of them); [`load`] (a file, JSON text or the embedded
//! default into a `Scene`), [`format`](mod@format) (the file's shape), [`validate`] (the
//! scene-wide checks and the walk over the objects), [`objects`] (builtin, inline and mesh
//! objects), [`discoids`] (an object's discoids), [`mesh`] (transforms and OBJ files),
//! [`pointcloud`] (PLY surfels), [`surface`] (the surface a discoid scene stands for, as
//! lembos, for the reference).
//!
//! Not modelled here: triangles as scene objects, point clouds in formats other than PLY,
//! and non-uniform scaling (which would need the inverse transpose for normals).

pub mod closed;
pub mod discoids;
pub mod format;
pub mod load;
pub mod mesh;
pub mod objects;
pub mod pointcloud;
pub mod surface;
pub mod validate;

use crate::camera::{Camera, Viewport};
use crate::discoid::DiscoidSet;
use crate::lembo::construct::TriangleMesh;
use crate::lembo::set::{Corners, LastParent, Lembos};
use crate::lembo::Lembo;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// One directional light with the Phong terms of Piranda et al. 2006 equation (6).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Light {
    /// Direction from the surface towards the light (any length but zero).
    pub direction_to_light: [f64; 3],
    /// Ambient term Ka, >= 0.
    pub ka: f64,
    /// Lambertian diffuse term Kd, >= 0.
    pub kd: f64,
    /// Specular term Ks, >= 0.
    pub ks: f64,
    /// Shininess exponent N, >= 0.
    pub shininess: f64,
}

impl Default for Light {
    fn default() -> Self {
        Light {
            direction_to_light: [0.4, 0.6, 1.0],
            ka: 0.1,
            kd: 0.75,
            ks: 0.35,
            shininess: 24.0,
        }
    }
}

/// The viewport of a scene file without one \[pixels\].
pub const DEFAULT_VIEWPORT: Viewport = Viewport {
    width: 512,
    height: 512,
};
/// The background of a scene file without one: dark grey, linear RGB.
pub const DEFAULT_BACKGROUND: [f64; 3] = [0.1, 0.1, 0.1];
/// The colour of an object without one: light grey, linear RGB.
pub const DEFAULT_COLOR: [f64; 3] = [0.8, 0.8, 0.8];
/// The largest accepted magnitude of a world-space coordinate or lembo coefficient after
/// an object's transform [world units]. Far beyond any sensible scene, it keeps products
/// of a few coordinates (projection, the rasterizer's quadratics) inside f64's and f32's
/// range.
pub const MAX_WORLD_COORDINATE: f64 = 1e12;
/// The most discoids a scene may hold, over all its objects: far beyond the paper's scenes
/// (8,800 and 2 x 7,176 discoids), it bounds the memory and time of a run.
pub const MAX_DISCOIDS: usize = 1_000_000;
/// The default blending threshold as a fraction of the scene's median discoid radius
/// (Piranda et al. 2006: the threshold "must be chosen much smaller than the dimension of the
/// discoids").
pub const DEFAULT_THRESHOLD_PER_RADIUS: f64 = 0.25;

/// A validated scene: everything in world space, every number finite and in range.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Made of `[A-Za-z0-9_-]` only: it names the output directory `out/<name>/`.
    pub name: String,
    /// File the scene came from; None for the embedded default.
    pub source: Option<PathBuf>,
    /// The image size \[pixels\].
    pub viewport: Viewport,
    /// Where the eye is and how it projects, in OpenGL conventions.
    pub camera: Camera,
    /// The light and the Phong material constants.
    pub light: Light,
    /// Background colour, linear RGB in [0, 1].
    pub background: [f64; 3],
    /// The discoid blending threshold t [world units] (Piranda et al. 2006 section 3, Figure 9): a
    /// discoid fragment farther than t behind the depth pass's surface, along the view
    /// direction, is not blended. From the file's `discoid_threshold` (> 0); without one,
    /// [`DEFAULT_THRESHOLD_PER_RADIUS`] × the median of the scene's discoid radii (planar
    /// radii and curved discoids' disk radii, after each object's scale; the mean of the two
    /// middle values for an even count); 0 for a scene without discoids.
    pub discoid_threshold: f64,
    /// The objects, in file order (their lembos' ids follow this order).
    pub objects: Vec<SceneObject>,
}

/// One object of a scene, in world space.
#[derive(Clone, Debug)]
pub struct SceneObject {
    /// "builtin sphere24", "mesh meshes/bunny.obj", "inline lembos", for reports.
    pub label: String,
    /// Material colour, linear RGB in [0, 1].
    pub color: [f64; 3],
    /// World-space lembos (after the object's transform): held, or made on demand from
    /// the object's mesh ([`Lembos`]).
    pub lembos: Lembos,
    /// Whether its lembos stand for a triangle mesh (`mesh` and `builtin` objects), so that
    /// the see-through metric checks them against their triangles.
    pub from_mesh: bool,
    /// The object's discoids in world space (None for ordinary objects). Curved discoids'
    /// lembos are `lembos`, in the order of `lembo_texcoords`.
    pub discoids: Option<DiscoidSet>,
}

impl Scene {
    /// The scene file as errors and reports name it, or `(embedded default)`.
    pub fn source_name(&self) -> String {
        self.source
            .as_ref()
            .map(|p| p.display().to_string())
            .unwrap_or_else(|| "(embedded default)".into())
    }

    /// The number of lembos over all objects (curved discoids' lembos included).
    pub fn lembo_count(&self) -> usize {
        self.objects.iter().map(|o| o.lembos.len()).sum()
    }

    /// The number of discoids over all objects: planar (surfels included) and curved.
    pub fn discoid_count(&self) -> usize {
        self.objects
            .iter()
            .filter_map(|o| o.discoids.as_ref())
            .map(|d| d.planar.len() + d.lembo_texcoords.len())
            .sum()
    }

    /// All lembos in scene order with their object's colour, each made as it is reached;
    /// the index in this order is the lembo's global id.
    pub fn lembos(&self) -> impl Iterator<Item = (Lembo, [f64; 3])> + '_ {
        self.objects
            .iter()
            .flat_map(|o| o.lembos.iter().map(move |l| (l, o.color)))
    }

    /// Each object's lembos with its colour, in scene order (what a
    /// [`Tessellation`](crate::lembo::tessellate::Tessellation) is made of).
    pub fn lembo_sets(&self) -> impl Iterator<Item = (&Lembos, [f64; 3])> + '_ {
        self.objects.iter().map(|o| (&o.lembos, o.color))
    }

    /// Where each object's lembos start in scene order, for [`Scene::lembo`].
    pub fn lembo_index(&self) -> LemboIndex {
        let mut start = 0;
        LemboIndex(
            self.objects
                .iter()
                .map(|o| {
                    let at = start;
                    start += o.lembos.len();
                    at
                })
                .collect(),
        )
    }

    /// Lembo `id` (scene order, below [`Scene::lembo_count`]) with its object's colour,
    /// made if it is not held; `index` is this scene's [`Scene::lembo_index`].
    pub fn lembo(&self, index: &LemboIndex, id: usize) -> (Lembo, [f64; 3]) {
        self.lembo_near(index, id, &mut LastParent::default())
    }

    /// [`Scene::lembo`] for a caller taking lembos in order: a subdivided lembo's parent is
    /// kept in `last` and made once for all its children ([`Lembos::get_near`]).
    pub fn lembo_near(
        &self,
        index: &LemboIndex,
        id: usize,
        last: &mut LastParent,
    ) -> (Lembo, [f64; 3]) {
        let o = index.object(id);
        let object = &self.objects[o];
        (
            object.lembos.get_near(id - index.0[o], o, last),
            object.color,
        )
    }

    /// Lembo `id`'s corners and their normals ([`Lembos::corners_near`]), bit for bit
    /// those of the lembo [`Scene::lembo_near`] makes.
    pub fn corners_near(&self, index: &LemboIndex, id: usize, last: &mut LastParent) -> Corners {
        let o = index.object(id);
        self.objects[o]
            .lembos
            .corners_near(id - index.0[o], o, last)
    }

    /// Lembo `id`'s six reference points ([`Lembos::points_near`]), bit for bit those of
    /// the lembo [`Scene::lembo_near`] makes.
    pub fn points_near(
        &self,
        index: &LemboIndex,
        id: usize,
        last: &mut LastParent,
    ) -> [glam::DVec3; 6] {
        let o = index.object(id);
        self.objects[o].lembos.points_near(id - index.0[o], o, last)
    }

    /// The heap the scene's lembos take \[bytes\]: the lembos held, and the meshes others
    /// are made from.
    pub fn lembo_bytes(&self) -> usize {
        self.objects.iter().map(|o| o.lembos.bytes()).sum()
    }
}

/// Where each object's lembos start in a scene's lembo order ([`Scene::lembo_index`]).
#[derive(Clone, Debug)]
pub struct LemboIndex(Vec<usize>);

impl LemboIndex {
    /// The object lembo `id` (in scene order) belongs to.
    pub fn object(&self, id: usize) -> usize {
        self.0.partition_point(|&start| start <= id) - 1
    }
}

impl SceneObject {
    /// The world-space triangle mesh of an object given as a mesh or a builtin (after its
    /// transform); None for inline lembos and discoids.
    pub fn mesh(&self) -> Option<&TriangleMesh> {
        self.lembos.mesh()
    }
}

#[cfg(test)]
mod tests;
