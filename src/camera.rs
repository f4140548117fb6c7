//! Camera and viewport, with OpenGL conventions (DESIGN.md §2).
//!
//! World to clip space by `look_at_rh` and `perspective_rh_gl` (or `orthographic_rh_gl`),
//! then to the viewport: pixel (i, j) is centred at (i + 0.5, j + 0.5), row 0 at the top,
//! depth in [0, 1] with smaller nearer.

use glam::{DMat4, DVec3, DVec4};
use serde::{Deserialize, Serialize};
use std::cell::Cell;

thread_local! {
    /// [`View::project`] calls on this thread not yet taken by [`take_projections`].
    static PROJECTIONS: Cell<u64> = const { Cell::new(0) };
}

/// How many times [`View::project`] ran on this thread since the last call; counting starts
/// again from zero. Setup projects in `f64` on the host, outside the datapath word that
/// counts operations, so the camera tallies its projections (always: a thread-local add,
/// so no path can project uncounted) and the cost layer, which knows what a projection
/// costs, takes and prices them (`cost::counted`); the camera knows nothing of costs.
pub fn take_projections() -> u64 {
    PROJECTIONS.with(|c| c.replace(0))
}

/// The largest accepted viewport side \[pixels\] (DESIGN.md §8).
pub const MAX_VIEWPORT_SIDE: u32 = 16384;

/// Image size \[pixels\].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Viewport {
    /// Width \[pixels\], 1..=16384.
    pub width: u32,
    /// Height \[pixels\], 1..=16384.
    pub height: u32,
}

impl Viewport {
    /// Pixels in the viewport.
    pub fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }
}

/// The projection of a camera.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum Projection {
    /// `Mat4::perspective_rh_gl(fovy, aspect, near, far)`.
    Perspective {
        /// Vertical field of view \[degrees\], in (0, 180).
        fovy_deg: f64,
        /// Near plane distance [world units], > 0.
        near: f64,
        /// Far plane distance [world units], > near.
        far: f64,
    },
    /// `Mat4::orthographic_rh_gl` with the given visible height, width from the aspect.
    Orthographic {
        /// Visible height [world units], > 0.
        height: f64,
        /// Near plane distance [world units].
        near: f64,
        /// Far plane distance [world units], > near.
        far: f64,
    },
}

/// A camera: eye, target, up and a projection.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    /// Eye position [world units].
    pub eye: [f64; 3],
    /// Point looked at [world units].
    pub target: [f64; 3],
    /// Up direction (need not be unit length or orthogonal to the view direction).
    pub up: [f64; 3],
    /// Perspective or orthographic, with its planes.
    pub projection: Projection,
}

/// A camera resolved against a viewport: matrices and the viewport transform.
#[derive(Clone, Copy, Debug)]
pub struct View {
    /// The image the camera renders into.
    pub viewport: Viewport,
    /// The eye's world position.
    pub eye: DVec3,
    /// World to clip.
    pub view_proj: DMat4,
    /// Clip to world.
    pub inv_view_proj: DMat4,
    /// Whether the projection is orthographic (rays are parallel).
    pub orthographic: bool,
    /// Near and far plane distances [world units].
    pub near: f64,
    /// Far plane distance \[world units\].
    pub far: f64,
}

/// A point projected to the viewport.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScreenPoint {
    /// Horizontal position \[pixels\], 0 at the left edge.
    pub x: f64,
    /// Vertical position \[pixels\], 0 at the top edge.
    pub y: f64,
    /// Depth in [0, 1] inside the frustum, smaller is nearer.
    pub depth: f64,
    /// Clip-space w (positive in front of the eye for perspective).
    pub w: f64,
}

impl View {
    /// The view of `camera` on `viewport`: OpenGL's look-at and projection matrices.
    pub fn new(camera: &Camera, viewport: Viewport) -> View {
        let eye = DVec3::from_array(camera.eye);
        let view = DMat4::look_at_rh(
            eye,
            DVec3::from_array(camera.target),
            DVec3::from_array(camera.up),
        );
        let aspect = viewport.width as f64 / viewport.height as f64;
        let (near, far) = match camera.projection {
            Projection::Perspective { near, far, .. } => (near, far),
            Projection::Orthographic { near, far, .. } => (near, far),
        };
        let (proj, orthographic) = match camera.projection {
            Projection::Perspective {
                fovy_deg,
                near,
                far,
            } => (
                DMat4::perspective_rh_gl(fovy_deg.to_radians(), aspect, near, far),
                false,
            ),
            Projection::Orthographic { height, near, far } => {
                let (h, w) = (0.5 * height, 0.5 * height * aspect);
                (DMat4::orthographic_rh_gl(-w, w, -h, h, near, far), true)
            }
        };
        let view_proj = proj * view;
        View {
            viewport,
            eye,
            view_proj,
            inv_view_proj: view_proj.inverse(),
            orthographic,
            near,
            far,
        }
    }

    /// Projects a world point to the viewport (no clipping; check `w` for points behind).
    pub fn project(&self, p: DVec3) -> ScreenPoint {
        PROJECTIONS.with(|c| c.set(c.get() + 1));
        let c = self.view_proj * p.extend(1.0);
        let inv_w = 1.0 / c.w;
        let (nx, ny, nz) = (c.x * inv_w, c.y * inv_w, c.z * inv_w);
        ScreenPoint {
            x: (nx + 1.0) * 0.5 * self.viewport.width as f64,
            y: (1.0 - ny) * 0.5 * self.viewport.height as f64,
            depth: (nz + 1.0) * 0.5,
            w: c.w,
        }
    }

    /// The world-space ray through viewport position (sx, sy) \[pixels\]: origin on the near
    /// plane and unit direction.
    pub fn ray(&self, sx: f64, sy: f64) -> (DVec3, DVec3) {
        let nx = 2.0 * sx / self.viewport.width as f64 - 1.0;
        let ny = 1.0 - 2.0 * sy / self.viewport.height as f64;
        let unproject = |nz: f64| {
            let p: DVec4 = self.inv_view_proj * DVec4::new(nx, ny, nz, 1.0);
            p.truncate() / p.w
        };
        let (near, far) = (unproject(-1.0), unproject(1.0));
        (near, (far - near).normalize())
    }

    /// Depth in [0, 1] of a world point (as the rasterizer's depth buffer holds it).
    pub fn depth_of(&self, p: DVec3) -> f64 {
        self.project(p).depth
    }

    /// Distance along the view direction [world units] of a point at window depth `z`
    /// (the inverse of the projection's depth mapping; linear for orthographic views).
    pub fn linear_depth(&self, z: f64) -> f64 {
        let (n, f) = (self.near, self.far);
        if self.orthographic {
            n + z * (f - n)
        } else {
            // z_ndc = (f + n)/(f - n) - 2 f n / ((f - n) d), z_ndc = 2 z - 1.
            let ndc = 2.0 * z - 1.0;
            2.0 * f * n / ((f + n) - ndc * (f - n))
        }
    }

    /// Unit direction from a world point towards the eye (constant for orthographic).
    pub fn to_eye(&self, p: DVec3) -> DVec3 {
        if self.orthographic {
            let (a, b) = (self.unproject_dir(-1.0), self.unproject_dir(1.0));
            (a - b).normalize()
        } else {
            (self.eye - p).normalize()
        }
    }

    fn unproject_dir(&self, nz: f64) -> DVec3 {
        let p = self.inv_view_proj * DVec4::new(0.0, 0.0, nz, 1.0);
        p.truncate() / p.w
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam(projection: Projection) -> View {
        View::new(
            &Camera {
                eye: [0.0, 0.0, 5.0],
                target: [0.0; 3],
                up: [0.0, 1.0, 0.0],
                projection,
            },
            Viewport {
                width: 200,
                height: 100,
            },
        )
    }

    #[test]
    fn target_projects_to_the_viewport_centre_and_up_is_row_zero() {
        let v = cam(Projection::Perspective {
            fovy_deg: 60.0,
            near: 1.0,
            far: 10.0,
        });
        let c = v.project(DVec3::ZERO);
        assert!((c.x - 100.0).abs() < 1e-9 && (c.y - 50.0).abs() < 1e-9);
        assert!(v.project(DVec3::new(0.0, 1.0, 0.0)).y < 50.0);
        assert!(v.project(DVec3::new(1.0, 0.0, 0.0)).x > 100.0);
        // Nearer points have smaller depth, in [0, 1].
        let (near, far) = (
            v.depth_of(DVec3::new(0.0, 0.0, 2.0)),
            v.depth_of(DVec3::new(0.0, 0.0, -2.0)),
        );
        assert!(0.0 < near && near < far && far < 1.0);
    }

    /// A perspective and an orthographic projection with the same depth range.
    fn both_projections() -> [Projection; 2] {
        [
            Projection::Perspective {
                fovy_deg: 45.0,
                near: 0.5,
                far: 20.0,
            },
            Projection::Orthographic {
                height: 3.0,
                near: 0.5,
                far: 20.0,
            },
        ]
    }

    #[test]
    fn linear_depth_inverts_the_depth_mapping() {
        for projection in both_projections() {
            let v = cam(projection);
            for d in [0.5, 1.0, 4.0, 19.0] {
                let z = v.depth_of(DVec3::new(0.2, -0.1, 5.0 - d));
                assert!((v.linear_depth(z) - d).abs() < 1e-9, "{projection:?} {d}");
            }
        }
    }

    #[test]
    fn rays_pass_through_the_points_that_project_to_their_sample() {
        for projection in both_projections() {
            let v = cam(projection);
            let p = DVec3::new(0.3, -0.4, 0.7);
            let s = v.project(p);
            let (o, d) = v.ray(s.x, s.y);
            let off = (p - o) - d * (p - o).dot(d);
            assert!(off.length() < 1e-9, "{projection:?}");
        }
    }
}
