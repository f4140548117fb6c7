//! Discoids (Piranda et al. 2006): disk-like patches carrying a gray-level beta texture, blended in
//! the ROP into one smooth surface (DESIGN.md §4).
//!
//! A discoid is *planar* (centre, unit normal, radius: drawn as a square through the
//! triangle path, the texture coordinates from the world position in its tangent frame)
//! or *curved* (a lembo whose six reference points carry texture coordinates, drawn
//! through the lembo path). Surfels (Pfister et al. 2000) are planar discoids tangent to a point
//! cloud. beta = 0 is outside the discoid.
//!
//! These types are what the scene hands the renderers; the textures, the blend modes, the
//! EWA kernel and the blend report live in the submodules. The three passes, which draw a
//! scene, are `frame::discoid`, above the scene, the rasterizer and the ROP.

use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Bytes of a planar discoid as it is stored in memory and fetched: centre, normal and
/// radius in f32.
pub const PLANAR_DISCOID_BYTES: u64 = 7 * 4;
/// Bytes of a curved discoid as it is stored in memory and fetched: a lembo and six
/// texture-coordinate pairs in f32.
pub const CURVED_DISCOID_BYTES: u64 = crate::lembo::LEMBO_BYTES + 6 * 2 * 4;

pub mod blend;
pub mod ewa;
pub mod report;
pub mod shapes;
pub mod texture;

/// The gray-level texture a discoid carries (Piranda et al. 2006 Figure 5, and a gaussian).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BetaShape {
    /// 1 in the centre falling to 0 at the rim (Figure 5a).
    Disk,
    /// A five-pointed star, 1 in the centre falling to 0 at its outline (Figure 5b).
    Star,
    /// exp(-r²/2σ²) with σ = 1/3 of the radius, cut to 0 at the rim.
    Gaussian,
    /// Planar discoids and surfels only: the gaussian as EWA splatting resamples it
    /// (Zwicker et al. 2001): the tangent-plane gaussian mapped to the screen and
    /// convolved with a one-pixel low-pass filter ([`ewa::EwaKernel`]).
    Ewa,
}

impl BetaShape {
    /// The shape's name in scene files and reports.
    pub fn name(self) -> &'static str {
        match self {
            BetaShape::Disk => "disk",
            BetaShape::Star => "star",
            BetaShape::Gaussian => "gaussian",
            BetaShape::Ewa => "ewa",
        }
    }
}

/// A planar discoid in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Discoid {
    /// Centre [world units].
    pub center: DVec3,
    /// Unit normal.
    pub normal: DVec3,
    /// Radius [world units], > 0.
    pub radius: f64,
}

impl Discoid {
    /// An orthonormal tangent frame (e1, e2) with e1 x e2 = normal, a deterministic
    /// function of the normal alone (Duff et al., "Building an orthonormal basis,
    /// revisited", 2017).
    pub fn frame(&self) -> (DVec3, DVec3) {
        let n = self.normal;
        let sign = 1f64.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        (
            DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
            DVec3::new(b, sign + n.y * n.y * a, -n.y),
        )
    }

    /// The four corners of the square of side 2 radius that carries the texture, counter-
    /// clockwise about the normal, at texture coordinates (0,0), (1,0), (1,1), (0,1).
    pub fn corners(&self) -> [DVec3; 4] {
        let (e1, e2) = self.frame();
        let (c, r) = (self.center, self.radius);
        [
            c - r * e1 - r * e2,
            c + r * e1 - r * e2,
            c + r * e1 + r * e2,
            c - r * e1 + r * e2,
        ]
    }

    /// Texture coordinates (s, t) in [0, 1]² of a point of the discoid's plane.
    pub fn texcoord(&self, p: DVec3) -> [f64; 2] {
        let (e1, e2) = self.frame();
        let d = p - self.center;
        let k = 0.5 / self.radius;
        [0.5 + k * d.dot(e1), 0.5 + k * d.dot(e2)]
    }
}

/// The discoids of one scene object.
#[derive(Clone, Debug, PartialEq)]
pub struct DiscoidSet {
    /// The beta texture every discoid of the object carries.
    pub beta: BetaShape,
    /// Planar discoids (drawn as squares through the triangle path).
    pub planar: Vec<Discoid>,
    /// Curved discoids: texture coordinates (s, t) at the six reference points of each of
    /// the object's lembos, in the same order as `SceneObject::lembos`.
    pub lembo_texcoords: Vec<[[f64; 2]; 6]>,
    /// The planar discoids are surfels of a point cloud.
    pub surfels: bool,
    /// The surface the discoids stand for, in world space, which `--reference` renders
    /// exactly; None where the scene does not say (inline discoids, surfels without a
    /// `surface`).
    pub surface: Option<DiscoidSurface>,
}

/// The surface an atlas of discoids stands for.
#[derive(Clone, Debug, PartialEq)]
pub enum DiscoidSurface {
    /// A sphere (the builtin curved discoids).
    Sphere {
        /// Centre [world units].
        center: DVec3,
        /// Radius [world units].
        radius: f64,
    },
    /// A triangle mesh with vertex normals (the mesh discoids were placed on): its flat
    /// triangles, shaded with the vertex normals linearly interpolated (Phong).
    Mesh(crate::lembo::construct::TriangleMesh),
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn discoid_frame_is_orthonormal_and_right_handed() {
        for n in [
            DVec3::Z,
            -DVec3::Z,
            DVec3::X,
            DVec3::new(0.3, -0.5, 0.8).normalize(),
            DVec3::new(-0.2, 0.1, -0.97).normalize(),
        ] {
            let d = Discoid {
                center: DVec3::new(1.0, 2.0, 3.0),
                normal: n,
                radius: 0.5,
            };
            let (e1, e2) = d.frame();
            assert!((e1.length() - 1.0).abs() < 1e-12 && (e2.length() - 1.0).abs() < 1e-12);
            assert!(e1.dot(e2).abs() < 1e-12 && e1.dot(n).abs() < 1e-12);
            assert!((e1.cross(e2) - n).length() < 1e-12, "{n}");
            let st = d.corners().map(|p| d.texcoord(p));
            for (got, want) in st
                .iter()
                .zip([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
            {
                assert!((got[0] - want[0]).abs() < 1e-12 && (got[1] - want[1]).abs() < 1e-12);
            }
            assert_eq!(d.texcoord(d.center), [0.5, 0.5]);
        }
    }
}
