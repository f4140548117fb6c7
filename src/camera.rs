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

/// Samples per pixel of a multisampled render (1, 2, 4 or 8), at Direct3D's standard
/// sample positions (DESIGN.md §2, "Multisampling").
///
/// The standard patterns put each of a pixel's samples on its own row, evenly spaced:
/// sample row s of n sits (2s + 1 - n) / (2n) pixels below the pixel centre (so the
/// patterns are n-rooks). A multisampled frame is drawn on the *sample grid*: a view whose
/// viewport has n times the rows ([`View::with_samples`]), where row r = n j + s holds
/// sample s of pixel row j, its samples displaced from the column centre i + 0.5 by
/// [`Samples::row_dx16`] sixteenths of a pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(try_from = "u32", into = "u32")]
pub struct Samples(u32);

impl Samples {
    /// One sample per pixel, at its centre: the render as it always was.
    pub const ONE: Samples = Samples(1);

    /// The counts accepted.
    pub const ACCEPTED: [u32; 4] = [1, 2, 4, 8];

    /// `n` samples per pixel, if it is 1, 2, 4 or 8.
    pub fn new(n: u32) -> Option<Samples> {
        Self::ACCEPTED.contains(&n).then_some(Samples(n))
    }

    /// Samples per pixel.
    pub fn get(self) -> u32 {
        self.0
    }

    /// Direct3D's standard positions of the pattern [1/16 pixel from the pixel centre, y
    /// down], in Direct3D's sample order (D3D11_STANDARD_MULTISAMPLE_PATTERN).
    pub fn positions(self) -> &'static [(i8, i8)] {
        match self.0 {
            1 => &[(0, 0)],
            2 => &[(4, 4), (-4, -4)],
            4 => &[(-2, -6), (6, -2), (-6, 2), (2, 6)],
            _ => &[
                (1, -3),
                (-1, 3),
                (5, 1),
                (-3, -5),
                (-5, 5),
                (-7, -1),
                (3, 7),
                (7, -7),
            ],
        }
    }

    /// The horizontal offsets of the pattern's sample rows, top to bottom [1/16 pixel]: the
    /// dx of the sample whose dy is (2s + 1 - n) 8 / n, row s (read from [`Self::positions`],
    /// tested against it).
    fn row_dx(self) -> &'static [i8] {
        match self.0 {
            1 => &[0],
            2 => &[-4, 4],
            4 => &[-2, 6, -6, 2],
            _ => &[7, -3, 1, -7, 5, -1, -5, 3],
        }
    }

    /// The horizontal offset from the column centre of the samples on row `row` of the
    /// sample grid [1/16 pixel]; 0 for one sample.
    #[inline(always)]
    pub fn row_dx16(self, row: u32) -> i64 {
        if self.0 == 1 {
            return 0;
        }
        self.row_dx()[(row % self.0) as usize] as i64
    }

    /// Where pixel column i's sample on sample-grid row `row` lies, from i \[pixels\]: 0.5
    /// plus the row's offset (exact in binary).
    #[inline(always)]
    pub fn row_centre_x(self, row: u32) -> f64 {
        0.5 + self.row_dx16(row) as f64 / 16.0
    }

    /// The smallest and largest [`Self::row_dx16`] [1/16 pixel].
    pub fn dx16_range(self) -> (i64, i64) {
        let dx = self.row_dx().iter().map(|&d| d as i64);
        (dx.clone().min().unwrap_or(0), dx.max().unwrap_or(0))
    }

    /// The position of the pixel's first sample row's sample relative to its centre
    /// \[pixels\]: where a multisampled frame's depth, winner and normal are kept per pixel
    /// (the accuracy metrics' point, DESIGN.md §6).
    pub fn first_row_offset(self) -> [f64; 2] {
        let n = self.0 as f64;
        [self.row_dx()[0] as f64 / 16.0, (1.0 - n) / (2.0 * n)]
    }
}

impl Default for Samples {
    fn default() -> Self {
        Samples::ONE
    }
}

impl TryFrom<u32> for Samples {
    type Error = String;
    fn try_from(n: u32) -> Result<Self, String> {
        Samples::new(n).ok_or_else(|| format!("{n}: samples per pixel must be 1, 2, 4 or 8"))
    }
}

impl From<Samples> for u32 {
    fn from(s: Samples) -> u32 {
        s.0
    }
}

impl std::fmt::Display for Samples {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.fmt(f)
    }
}

/// A camera resolved against a viewport: matrices and the viewport transform.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// The image the camera renders into: for a multisampled frame, its sample grid
    /// ([`View::with_samples`]).
    pub viewport: Viewport,
    /// The samples per pixel this view's viewport rows are the sample rows of (1: the
    /// viewport is the image).
    pub samples: Samples,
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
    /// The unit direction the camera looks in (eye to target): an orthographic view's rays.
    pub forward: DVec3,
    /// Which faces the rasterizers cull (none unless [`View::with_culling`] says so): the
    /// render state a GPU's cull mode and front face set, resolved once per run from the
    /// architecture and the scene (DESIGN.md §5, "Back-face culling").
    pub culling: Culling,
}

/// The winding of a primitive's corners (A, B, C) as seen from the side it faces:
/// OpenGL's `glFrontFace`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Winding {
    /// Counter-clockwise: the front is the side (B - A) x (C - A) points to (a lembo's
    /// P_u x P_v).
    Ccw,
    /// Clockwise: the front is the other side.
    Cw,
}

/// Which faces the rasterizers cull.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Culling {
    /// None: both sides are drawn (and shaded two-sided).
    #[default]
    Off,
    /// Primitives whose every point faces away from the eye, the front being the side
    /// `front` says.
    Back {
        /// The winding of a front face.
        front: Winding,
    },
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
            samples: Samples::ONE,
            eye,
            view_proj,
            inv_view_proj: view_proj.inverse(),
            orthographic,
            near,
            far,
            forward: (DVec3::from_array(camera.target) - eye).normalize_or_zero(),
            culling: Culling::Off,
        }
    }

    /// This view with the rasterizers culling as `culling` says.
    pub fn with_culling(&self, culling: Culling) -> View {
        View { culling, ..*self }
    }

    /// The sample grid of this (one-sample) view with `samples` per pixel: the same camera on a
    /// viewport of `samples` times the rows (the matrices, and so the aspect ratio, are the
    /// image's), whose rows are the sample rows ([`Samples`]).
    pub fn with_samples(&self, samples: Samples) -> View {
        debug_assert_eq!(self.samples, Samples::ONE, "a sample grid of a sample grid");
        View {
            viewport: Viewport {
                width: self.viewport.width,
                height: self.viewport.height * samples.get(),
            },
            samples,
            ..*self
        }
    }

    /// The view a render of `samples` per pixel draws on: this one with one sample, else its
    /// sample grid ([`Self::with_samples`]).
    pub fn grid(&self, samples: Samples) -> View {
        match samples.get() {
            1 => *self,
            _ => self.with_samples(samples),
        }
    }

    /// This view with the image moved by (dx, dy) \[pixels\]: its pixel (i, j) sees what this
    /// view's position (i + 0.5 + dx, j + 0.5 + dy) sees, at the same depth (a translation
    /// of normalised device coordinates).
    pub fn translated(&self, [dx, dy]: [f64; 2]) -> View {
        let (w, h) = (self.viewport.width as f64, self.viewport.height as f64);
        let shift = DMat4::from_translation(DVec3::new(-2.0 * dx / w, 2.0 * dy / h, 0.0));
        let view_proj = shift * self.view_proj;
        View {
            view_proj,
            inv_view_proj: view_proj.inverse(),
            ..*self
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

    /// Direct3D's standard patterns: one sample on each of n rows, evenly spaced about the
    /// centre, the rows' offsets along them as the table gives them.
    #[test]
    fn samples_are_direct3ds_patterns_one_to_a_row() {
        for n in [1u32, 2, 4, 8] {
            let s = Samples::new(n).unwrap();
            let p = s.positions();
            assert_eq!(p.len(), n as usize);
            let mut dy: Vec<i8> = p.iter().map(|p| p.1).collect();
            dy.sort();
            let even: Vec<i8> = (0..n as i32)
                .map(|k| ((2 * k + 1 - n as i32) * 8 / n as i32) as i8)
                .collect();
            assert_eq!(dy, even, "{n}");
            for row in 0..3 * n {
                let want = p
                    .iter()
                    .find(|q| q.1 == even[(row % n) as usize])
                    .unwrap()
                    .0;
                assert_eq!(s.row_dx16(row), want as i64, "{n} row {row}");
                assert_eq!(s.row_centre_x(row), 0.5 + want as f64 / 16.0);
            }
        }
        assert_eq!(
            Samples::new(4).unwrap().first_row_offset(),
            [-0.125, -0.375]
        );
        assert_eq!(Samples::new(8).unwrap().dx16_range(), (-7, 7));
        assert_eq!(Samples::ONE.row_centre_x(5), 0.5);
        for bad in [0, 3, 16] {
            assert!(Samples::new(bad).is_none());
            assert!(Samples::try_from(bad).unwrap_err().contains("1, 2, 4 or 8"));
        }
    }

    /// The sample grid is the same camera with n times the rows; a translated view sees at
    /// its pixel centres what the view sees at the moved points, at the same depth.
    #[test]
    fn the_sample_grid_scales_rows_and_a_translated_view_moves_the_pixels() {
        let v = cam(Projection::Perspective {
            fovy_deg: 60.0,
            near: 1.0,
            far: 10.0,
        });
        let grid = v.with_samples(Samples::new(4).unwrap());
        assert_eq!((grid.viewport.width, grid.viewport.height), (200, 400));
        let p = DVec3::new(0.3, -0.2, 0.5);
        let (a, b) = (v.project(p), grid.project(p));
        assert!((b.x - a.x).abs() < 1e-9 && (b.y - 4.0 * a.y).abs() < 1e-9);
        assert_eq!(a.depth, b.depth);
        let moved = v.translated([0.25, -0.375]);
        let c = moved.project(p);
        assert!((c.x - (a.x - 0.25)).abs() < 1e-9 && (c.y - (a.y + 0.375)).abs() < 1e-9);
        assert!((c.depth - a.depth).abs() < 1e-12);
        let (o1, d1) = moved.ray(10.5, 20.5);
        let (o2, d2) = v.ray(10.75, 20.125);
        assert!((o1 - o2).length() < 1e-9 && (d1 - d2).length() < 1e-9);
        assert_eq!(v.grid(Samples::ONE).viewport, v.viewport);
    }
}
