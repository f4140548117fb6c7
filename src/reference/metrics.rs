//! Accuracy of a rendered frame against the reference (DESIGN.md §6), under the names the
//! report carries.
//!
//! Coverage is per pixel centre: the render covers a pixel when some primitive won it, the
//! reference when its centre sample hit a surface. Where the two disagree (a *misplaced*
//! pixel), the silhouette error is the distance from the pixel's centre to the reference's
//! true outline, sub-pixel ([`super::outline`]): the nearest pixel centre of the other
//! reference state, from an exact distance transform of the reference mask (Felzenszwalb
//! and Huttenlocher, "Distance Transforms of Sampled Functions", 2012), bounds it, and the
//! reference is asked about the points in between. Crack pixels (holes inside the
//! reference coverage) are counted apart and left out of the silhouette error.

use super::distance::Bounds;
use super::flip::FlipMap;
use super::oracle::ReferenceImage;
use super::outline::{outline_distances, Misplaced, ReferenceCoverage, SILHOUETTE_RESOLUTION_PX};
use crate::rop::framebuffer::{FrameBuffer, NO_PRIMITIVE};
use crate::rop::plane::Plane;
use serde::Serialize;

/// The PSNR reported for identical images \[dB\] (the true value is infinite, which JSON
/// cannot carry).
pub const PSNR_CAP_DB: f64 = 100.0;

/// The accuracy section of the report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Accuracy {
    /// Pixels the render covers and the reference does not \[pixels\].
    pub coverage_false_positive: u64,
    /// Pixels the reference covers and the render does not, cracks included \[pixels\].
    pub coverage_false_negative: u64,
    /// Largest distance from the centre of a misplaced pixel (covered by the render and not
    /// the reference, or the reverse; cracks excluded) to the reference's true outline,
    /// sub-pixel \[pixels\]; 0 when no pixel is misplaced (an outline off by less than the
    /// distance to the nearest centre shows no error). When the reference has no pixel
    /// centre of the other state at all (it covers nothing, or everything), the distance is
    /// the image diagonal.
    pub silhouette_max_px: f64,
    /// Mean of the same distances over the misplaced pixels \[pixels\]; 0 when none.
    pub silhouette_mean_px: f64,
    /// How finely the outline is located for the two figures above: points of the
    /// reference outline are bisected to within this \[pixels\].
    pub silhouette_resolution_px: f64,
    /// Largest |render depth - reference depth| over pixels both cover, in depth-buffer
    /// units [0, 1]; includes the error of the perspective approximation.
    pub depth_max_abs: f64,
    /// Largest angle between the render's and the reference's normals, up to sign (shading
    /// is two-sided), over pixels both cover \[degrees\].
    pub normal_max_deg: f64,
    /// Mean of the same angles \[degrees\].
    pub normal_mean_deg: f64,
    /// PSNR of the RGB8 image against the reference's centre-sample colours over the whole
    /// image \[dB\], capped at [`PSNR_CAP_DB`] (identical images).
    pub psnr_db: f64,
    /// Largest channel difference [0-255].
    pub max_abs_error: u64,
    /// Mean FLIP of the RGB8 image against the same colours (Andersson et al. 2020, by
    /// its reference implementation, [`super::flip`]): 0 for identical images, at most 1.
    pub flip_mean: f64,
    /// The observer FLIP was computed for \[pixels per degree\].
    pub flip_pixels_per_degree: f64,
    /// Holes in the render's surface \[pixels\]: pixels the reference covers together with
    /// their 4 neighbours, that the render misses while covering both neighbours of an
    /// opposite pair (left and right, or above and below). A band of misses along the
    /// silhouette (the outline drawn slightly inside the true one) is not a crack.
    pub crack_pixels: u64,
    /// Pixels written by more than one primitive on a shared edge, as the renderer counted
    /// them \[pixels\].
    pub double_hit_pixels: u64,
    /// Pixels where the input mesh's own flat triangles show a front-facing surface but the
    /// render shows the background, a surface facing away from the eye, or a surface behind
    /// that triangle from a primitive sharing no corner with it: a gap between primitives
    /// one can see through (`see_through.rs`) \[pixels\]; null for scenes without a mesh.
    pub see_through_px: Option<u64>,
    /// Pixels where the exact reference shows a front face and the render shows the
    /// background, a back face, or a farther surface of another part of the scene, where
    /// the reference shows nothing of the kind within a margin (a displaced outline): a
    /// renderer leak (`leak.rs`) \[pixels\]; null where the surfaces are not lembos
    /// (discoids).
    pub leak_px: Option<u64>,
    /// The paper's guarantee: largest |y(u, v) - (j + 0.5)| over all lembo fragments, as
    /// the renderer measured it \[pixels\]; null for the triangle path (no curve to follow).
    pub max_scanline_deviation_px: Option<f64>,
    /// Sub-samples per pixel side of the reference.
    pub supersample: u64,
    /// Pixels both cover, over which depth and normals are compared \[pixels\].
    pub pixels_compared: u64,
}

impl Accuracy {
    /// Name and value with its unit, one per field, for the text report.
    pub fn lines(&self) -> Vec<(String, String)> {
        let px = |n: u64| format!("{n} px");
        [
            ("coverage_false_positive", px(self.coverage_false_positive)),
            ("coverage_false_negative", px(self.coverage_false_negative)),
            (
                "silhouette_max_px",
                format!("{:.3} px", self.silhouette_max_px),
            ),
            (
                "silhouette_mean_px",
                format!("{:.3} px", self.silhouette_mean_px),
            ),
            (
                "silhouette_resolution_px",
                format!("{:.4} px", self.silhouette_resolution_px),
            ),
            ("depth_max_abs", format!("{:.3e}", self.depth_max_abs)),
            ("normal_max_deg", format!("{:.3} deg", self.normal_max_deg)),
            (
                "normal_mean_deg",
                format!("{:.3} deg", self.normal_mean_deg),
            ),
            (
                "psnr_db",
                if self.psnr_db >= PSNR_CAP_DB {
                    format!("{PSNR_CAP_DB:.2} dB (identical)")
                } else {
                    format!("{:.2} dB", self.psnr_db)
                },
            ),
            ("max_abs_error", format!("{} / 255", self.max_abs_error)),
            ("flip_mean", format!("{:.4} (0 to 1)", self.flip_mean)),
            (
                "flip_pixels_per_degree",
                format!("{:.2} px/deg", self.flip_pixels_per_degree),
            ),
            ("crack_pixels", px(self.crack_pixels)),
            ("double_hit_pixels", px(self.double_hit_pixels)),
            (
                "see_through_px",
                self.see_through_px
                    .map(px)
                    .unwrap_or_else(|| "n/a (no mesh)".into()),
            ),
            (
                "leak_px",
                self.leak_px.map(px).unwrap_or_else(|| "n/a".into()),
            ),
            (
                "max_scanline_deviation_px",
                self.max_scanline_deviation_px
                    .map(|d| format!("{d:.4} px"))
                    .unwrap_or_else(|| "n/a (triangle path)".into()),
            ),
            ("supersample", format!("{0}x{0}", self.supersample)),
            ("pixels_compared", px(self.pixels_compared)),
        ]
        .into_iter()
        .map(|(name, value)| (name.to_string(), value))
        .collect()
    }
}

/// The visibility counts measured beside the image: see-through against the flat mesh
/// ([`super::see_through`]) and leaks against the exact surface ([`super::leak`]); None
/// where not measured.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Visibility {
    /// [`Accuracy::see_through_px`].
    pub see_through_px: Option<u64>,
    /// [`Accuracy::leak_px`].
    pub leak_px: Option<u64>,
}

/// Measures `render` against `reference`, whose coverage at any screen position `outline`
/// gives (the reference's [`super::oracle::Tracer`]); the renderer-side counts, the
/// visibility counts and the FLIP map of the two ([`super::flip::flip_frame`]) are passed
/// through.
///
/// # Panics
/// If the two images differ in size, or the render kept no normal buffer
/// (`FrameBuffer::new(.., keep_normals: true)`): both are bugs of the caller.
pub fn measure(
    render: &FrameBuffer,
    reference: &ReferenceImage,
    outline: &dyn ReferenceCoverage,
    double_hit_pixels: u64,
    max_scanline_deviation_px: Option<f64>,
    visibility: Visibility,
    flip: &FlipMap,
) -> Accuracy {
    assert_eq!(
        (render.width, render.height),
        (reference.width, reference.height),
        "render and reference differ in size"
    );
    let normals = render
        .normal
        .as_ref()
        .expect("accuracy needs the render's normal buffer (keep_normals)");
    let (w, h) = (render.width as usize, render.height as usize);
    let ours: Vec<bool> = render
        .primitive
        .iter()
        .map(|&p| p != NO_PRIMITIVE)
        .collect();
    let theirs: Vec<bool> = reference.hits.iter().map(|h| h.is_some()).collect();

    let cracks = crack_mask(&ours, &theirs, w, h);
    let mut bounds = Bounds::new(&theirs, w, h);
    let diagonal = ((w * w + h * h) as f64).sqrt();
    let t = tally(render, reference, normals, &ours, &cracks, &mut bounds);
    let distances = outline_distances(&theirs, w, h, &t.misplaced, outline);
    let (sil_max, silhouette_mean_px) = silhouette(&distances, t.unbounded, diagonal);
    let psnr_db = psnr_db(t.squared_error, w, h);
    Accuracy {
        coverage_false_positive: t.fp,
        coverage_false_negative: t.fn_,
        silhouette_max_px: sil_max,
        silhouette_mean_px,
        silhouette_resolution_px: SILHOUETTE_RESOLUTION_PX,
        depth_max_abs: t.depth_max,
        normal_max_deg: t.normal_max,
        normal_mean_deg: if t.compared > 0 {
            t.normal_sum / t.compared as f64
        } else {
            0.0
        },
        psnr_db,
        max_abs_error: t.max_abs,
        flip_mean: flip.mean,
        flip_pixels_per_degree: flip.ppd.get(),
        crack_pixels: t.n_crack,
        double_hit_pixels,
        see_through_px: visibility.see_through_px,
        leak_px: visibility.leak_px,
        max_scanline_deviation_px,
        supersample: reference.supersample as u64,
        pixels_compared: t.compared,
    }
}

/// What one pass over the pixels finds: colour errors, the coverage disagreements and
/// cracks, the misplaced pixels to measure to the outline, and the depth and normal
/// errors where both cover.
struct Tally {
    /// Pixels the render covers and the reference does not.
    fp: u64,
    /// Pixels the reference covers and the render does not.
    fn_: u64,
    /// Misplaced pixels that are cracks (left out of the silhouette error).
    n_crack: u64,
    /// Misplaced pixels with a bound on their distance to the outline, to search.
    misplaced: Vec<Misplaced>,
    /// Misplaced pixels without one (no pixel of the other state): the diagonal each.
    unbounded: u64,
    depth_max: f64,
    /// Largest and summed normal angle \[degrees\] over the `compared` pixels.
    normal_max: f64,
    normal_sum: f64,
    /// Pixels both cover.
    compared: u64,
    /// Sum of the squared channel differences, and the largest difference.
    squared_error: u64,
    max_abs: u64,
}

/// The pass over every pixel, in index order: the colour error, and by coverage either
/// the depth and normal errors (both cover) or a misplaced pixel (one covers), a crack or
/// bounded by the nearest reference pixel of the other state.
fn tally(
    render: &FrameBuffer,
    reference: &ReferenceImage,
    normals: &Plane<[f32; 3]>,
    ours: &[bool],
    cracks: &[bool],
    bounds: &mut Bounds,
) -> Tally {
    let (w, h) = (render.width as usize, render.height as usize);
    let (mut fp, mut fn_, mut n_crack) = (0u64, 0u64, 0u64);
    // Misplaced pixels with a bound, to search; those without one are the diagonal.
    let (mut misplaced, mut unbounded) = (Vec::new(), 0u64);
    let (mut depth_max, mut normal_max, mut normal_sum, mut compared) =
        (0.0f64, 0.0f64, 0.0f64, 0u64);
    let (mut squared_error, mut max_abs) = (0u64, 0u64);
    for k in 0..w * h {
        for (a, b) in render.color[k].iter().zip(reference.color[k]) {
            let d = (*a as i64 - b as i64).unsigned_abs();
            squared_error += d * d;
            max_abs = max_abs.max(d);
        }
        match (ours[k], reference.hits[k]) {
            (true, Some(hit)) => {
                compared += 1;
                depth_max = depth_max.max((render.depth[k] as f64 - hit.depth).abs());
                let n = normals[k].map(|c| c as f64);
                let angle = angle_up_to_sign(glam::DVec3::from_array(n), hit.normal);
                normal_max = normal_max.max(angle);
                normal_sum += angle;
            }
            (false, None) => {}
            (covered, _) => {
                if covered {
                    fp += 1;
                } else {
                    fn_ += 1;
                }
                if cracks[k] {
                    n_crack += 1;
                    continue;
                }
                match bounds.nearest(k, covered) {
                    Some(bound) => misplaced.push(Misplaced { index: k, bound }),
                    None => unbounded += 1,
                }
            }
        }
    }
    Tally {
        fp,
        fn_,
        n_crack,
        misplaced,
        unbounded,
        depth_max,
        normal_max,
        normal_sum,
        compared,
        squared_error,
        max_abs,
    }
}

/// The silhouette error's maximum and mean \[pixels\] over the measured misplaced
/// pixels' `distances` and the `unbounded` ones, which count as the image's `diagonal`.
fn silhouette(distances: &[f64], unbounded: u64, diagonal: f64) -> (f64, f64) {
    let sil_n = distances.len() as u64 + unbounded;
    let sil_max = if unbounded > 0 {
        diagonal
    } else {
        distances.iter().copied().fold(0.0, f64::max)
    };
    let sil_sum = distances.iter().sum::<f64>() + unbounded as f64 * diagonal;
    let sil_mean = if sil_n > 0 {
        sil_sum / sil_n as f64
    } else {
        0.0
    };
    (sil_max, sil_mean)
}

/// The PSNR \[dB\] of `squared_error` summed over the three channels of `w` x `h`
/// pixels, capped at [`PSNR_CAP_DB`] (identical images).
fn psnr_db(squared_error: u64, w: usize, h: usize) -> f64 {
    let mse = squared_error as f64 / (3 * w * h).max(1) as f64;
    if mse == 0.0 {
        PSNR_CAP_DB
    } else {
        (10.0 * (255.0 * 255.0 / mse).log10()).min(PSNR_CAP_DB)
    }
}

/// The angle between two directions up to sign \[degrees\], in [0, 90]; 90 when either is
/// zero. `atan2` keeps small angles accurate where `acos` of a dot product would not.
fn angle_up_to_sign(a: glam::DVec3, b: glam::DVec3) -> f64 {
    if a == glam::DVec3::ZERO || b == glam::DVec3::ZERO {
        return 90.0;
    }
    a.cross(b).length().atan2(a.dot(b).abs()).to_degrees()
}

/// Pixels the reference covers together with their 4 neighbours (inside the image), that
/// the render misses between two covered opposite neighbours.
fn crack_mask(ours: &[bool], theirs: &[bool], w: usize, h: usize) -> Vec<bool> {
    let mut out = vec![false; w * h];
    for j in 1..h.saturating_sub(1) {
        for i in 1..w.saturating_sub(1) {
            let k = j * w + i;
            let interior =
                theirs[k] && theirs[k - 1] && theirs[k + 1] && theirs[k - w] && theirs[k + w];
            let gap = (ours[k - 1] && ours[k + 1]) || (ours[k - w] && ours[k + w]);
            out[k] = !ours[k] && interior && gap;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::flip::{flip_frame, PixelsPerDegree};
    use super::*;
    use crate::reference::oracle::ReferenceHit;
    use glam::DVec3;

    const SIZE: u32 = 32;
    const COLOR: [u8; 3] = [200, 150, 100];
    const BACKGROUND: [u8; 3] = [0, 0, 20];

    fn in_disc(i: u32, j: u32, cx: f64) -> bool {
        let (x, y) = (i as f64 + 0.5 - cx, j as f64 + 0.5 - 16.0);
        x * x + y * y <= 10.0 * 10.0
    }

    fn reference_disc() -> ReferenceImage {
        let n = (SIZE * SIZE) as usize;
        let mut image = ReferenceImage {
            width: SIZE,
            height: SIZE,
            supersample: 1,
            hits: vec![None; n],
            hits_offset_px: [0.0; 2],
            bins: None,
            color: vec![BACKGROUND; n],
            color_supersampled: None,
            coverage: None,
        };
        for j in 0..SIZE {
            for i in 0..SIZE {
                if in_disc(i, j, 16.0) {
                    let k = (j * SIZE + i) as usize;
                    image.hits[k] = Some(ReferenceHit {
                        depth: 0.5,
                        normal: DVec3::Z,
                        lembo: 0,
                        u: 0.2,
                        v: 0.2,
                    });
                    image.color[k] = COLOR;
                }
            }
        }
        image
    }

    /// A render of the disc centred at `cx`, depth 0.5, normal +z.
    fn render_disc(cx: f64) -> FrameBuffer {
        let mut fb = FrameBuffer::new(SIZE, SIZE, BACKGROUND, true);
        for j in 0..SIZE {
            for i in 0..SIZE {
                if in_disc(i, j, cx) {
                    let k = fb.index(i, j);
                    fb.write(k, 0.5, 0, COLOR);
                    fb.normal.as_mut().unwrap()[k] = [0.0, 0.0, 1.0];
                }
            }
        }
        fb
    }

    /// The reference disc's coverage anywhere: its outline is the circle of radius 10 about
    /// (16, 16).
    struct Disc;

    impl ReferenceCoverage for Disc {
        fn covered(&self, x: f64, y: f64) -> bool {
            (x - 16.0).powi(2) + (y - 16.0).powi(2) <= 100.0
        }
    }

    fn measure_disc(render: &FrameBuffer, double_hits: u64, deviation: Option<f64>) -> Accuracy {
        let reference = reference_disc();
        let flip = flip_frame(render, &reference, PixelsPerDegree::default());
        measure(
            render,
            &reference,
            &Disc,
            double_hits,
            deviation,
            Default::default(),
            &flip,
        )
    }

    /// The exact silhouette figures of a render of the disc centred at `cx`: the distance
    /// from each misplaced centre to the circle, max and mean.
    fn exact_silhouette(cx: f64) -> (f64, f64, u64) {
        let mut d = Vec::new();
        for j in 0..SIZE {
            for i in 0..SIZE {
                if in_disc(i, j, cx) != in_disc(i, j, 16.0) {
                    let (x, y) = (i as f64 + 0.5 - 16.0, j as f64 + 0.5 - 16.0);
                    d.push(((x * x + y * y).sqrt() - 10.0).abs());
                }
            }
        }
        let max = d.iter().copied().fold(0.0, f64::max);
        (max, d.iter().sum::<f64>() / d.len() as f64, d.len() as u64)
    }

    fn count(f: impl Fn(u32, u32) -> bool) -> u64 {
        (0..SIZE)
            .flat_map(|j| (0..SIZE).map(move |i| (i, j)))
            .filter(|&(i, j)| f(i, j))
            .count() as u64
    }

    #[test]
    fn measure_identical_images_have_no_error_and_capped_psnr() {
        let a = measure_disc(&render_disc(16.0), 0, Some(0.0));
        assert_eq!(
            a.coverage_false_positive
                + a.coverage_false_negative
                + a.crack_pixels
                + a.max_abs_error,
            0
        );
        assert_eq!(
            (a.silhouette_max_px, a.silhouette_mean_px, a.depth_max_abs),
            (0.0, 0.0, 0.0)
        );
        assert_eq!((a.normal_max_deg, a.normal_mean_deg), (0.0, 0.0));
        assert_eq!(a.psnr_db, PSNR_CAP_DB);
        assert_eq!(a.pixels_compared, count(|i, j| in_disc(i, j, 16.0)));
        assert!(serde_json::to_string(&a)
            .unwrap()
            .contains("\"psnr_db\":100.0"));
    }

    #[test]
    fn measure_one_pixel_shifted_disc_is_measured_to_the_true_outline() {
        let a = measure_disc(&render_disc(17.0), 3, Some(0.25));
        let fp = count(|i, j| in_disc(i, j, 17.0) && !in_disc(i, j, 16.0));
        let fn_ = count(|i, j| !in_disc(i, j, 17.0) && in_disc(i, j, 16.0));
        assert!(fp > 0);
        assert_eq!(
            (a.coverage_false_positive, a.coverage_false_negative),
            (fp, fn_)
        );
        // Misplaced centres lie between the two outlines, within 1 px of the reference's.
        let (max, mean, n) = exact_silhouette(17.0);
        assert_eq!(n, fp + fn_);
        let r = a.silhouette_resolution_px;
        assert_eq!(r, SILHOUETTE_RESOLUTION_PX);
        assert!((a.silhouette_max_px - max).abs() <= r, "{a:?} vs {max}");
        assert!((a.silhouette_mean_px - mean).abs() <= r, "{a:?} vs {mean}");
        assert!(
            a.silhouette_max_px > 0.7 && a.silhouette_max_px < 1.0,
            "{a:?}"
        );
        assert_eq!(a.crack_pixels, 0);
        assert_eq!(
            (a.double_hit_pixels, a.max_scanline_deviation_px),
            (3, Some(0.25))
        );
        assert_eq!(a.max_abs_error, 200);
        assert!(a.psnr_db < 30.0);
    }

    #[test]
    fn measure_sub_pixel_shift_gives_a_sub_pixel_silhouette_error() {
        // The disc drawn 0.3 px to the right: the misplaced centres are those the shift
        // moves across the outline, each less than 0.3 px from the reference's.
        let a = measure_disc(&render_disc(16.3), 0, Some(0.0));
        let (max, mean, n) = exact_silhouette(16.3);
        assert!(n > 0);
        assert_eq!(a.coverage_false_positive + a.coverage_false_negative, n);
        let r = a.silhouette_resolution_px;
        assert!((a.silhouette_max_px - max).abs() <= r, "{a:?} vs {max}");
        assert!((a.silhouette_mean_px - mean).abs() <= r, "{a:?} vs {mean}");
        assert!(a.silhouette_max_px < 0.3, "{a:?}");
    }

    #[test]
    fn measure_against_the_exact_reference_of_a_square_shifted_by_0_4_px() {
        use crate::camera::{Camera, Projection, View, Viewport};
        use crate::lembo::construct::lembo_from_triangle;
        use crate::reference::oracle::{render_reference, ReferenceInput, Tracer, DEFAULT_TILE};
        use crate::scene::Light;
        // Orthographic, world (X, Y) on screen (X + 32, 32 - Y): the square of two flat
        // lembos covers screen x in [10.2, 50.2], y in [10.25, 50.25].
        let camera = Camera {
            eye: [0.0, 0.0, 10.0],
            target: [0.0; 3],
            up: [0.0, 1.0, 0.0],
            projection: Projection::Orthographic {
                height: 64.0,
                near: 0.1,
                far: 100.0,
            },
        };
        let view = View::new(
            &camera,
            Viewport {
                width: 64,
                height: 64,
            },
        );
        let corner = |x: f64, y: f64| DVec3::new(x - 32.0, 32.0 - y, 0.0);
        let (a, b, c, d) = (
            corner(10.2, 50.25),
            corner(50.2, 50.25),
            corner(50.2, 10.25),
            corner(10.2, 10.25),
        );
        let lembos = [
            lembo_from_triangle([a, b, c], [DVec3::Z; 3]),
            lembo_from_triangle([a, c, d], [DVec3::Z; 3]),
        ];
        let colored: Vec<_> = lembos.iter().map(|l| (l, [0.8, 0.6, 0.4])).collect();
        let reference = render_reference(&ReferenceInput {
            lembos: &colored,
            view: &view,
            light: &Light::default(),
            background: [0.0; 3],
            supersample: 1,
            tile: DEFAULT_TILE,
        });
        // The render: the square 0.4 px to the right, x in [10.6, 50.6].
        let mut fb = FrameBuffer::new(64, 64, [0; 3], true);
        for j in 0..64 {
            for i in 0..64 {
                let (x, y) = (i as f64 + 0.5, j as f64 + 0.5);
                if (10.6..=50.6).contains(&x) && (10.25..=50.25).contains(&y) {
                    let k = fb.index(i, j);
                    fb.write(k, 0.5, 0, [200; 3]);
                }
            }
        }
        let tracer = Tracer::of(lembos.iter(), &view);
        let flip = flip_frame(&fb, &reference, PixelsPerDegree::default());
        let a = measure(&fb, &reference, &tracer, 0, None, Default::default(), &flip);
        // Column x = 10.5 is the reference's and not the render's, x = 50.5 the reverse:
        // each centre 0.3 px from the reference's outline.
        assert_eq!(
            (a.coverage_false_negative, a.coverage_false_positive),
            (40, 40)
        );
        let r = a.silhouette_resolution_px;
        assert!((a.silhouette_max_px - 0.3).abs() <= r, "{a:?}");
        assert!((a.silhouette_mean_px - 0.3).abs() <= r, "{a:?}");
    }

    #[test]
    fn measure_silhouette_band_of_misses_is_not_a_crack() {
        // The render's outline drawn two pixels inside the true one on the right side.
        let mut fb = render_disc(16.0);
        for j in 0..SIZE {
            let covered: Vec<u32> = (0..SIZE)
                .filter(|&i| fb.primitive[fb.index(i, j)] != NO_PRIMITIVE)
                .collect();
            for &i in covered.iter().rev().take(2) {
                let k = fb.index(i, j);
                fb.primitive[k] = NO_PRIMITIVE;
                fb.color[k] = BACKGROUND;
            }
        }
        let a = measure_disc(&fb, 0, Some(0.0));
        assert!(a.coverage_false_negative > 10);
        assert_eq!(a.crack_pixels, 0);
    }

    #[test]
    fn measure_hole_inside_the_disc_is_a_crack_not_a_silhouette_error() {
        let mut fb = render_disc(16.0);
        let k = fb.index(16, 16);
        fb.primitive[k] = NO_PRIMITIVE;
        fb.color[k] = BACKGROUND;
        let a = measure_disc(&fb, 0, Some(0.0));
        assert_eq!(
            (
                a.crack_pixels,
                a.coverage_false_negative,
                a.coverage_false_positive
            ),
            (1, 1, 0)
        );
        assert_eq!((a.silhouette_max_px, a.silhouette_mean_px), (0.0, 0.0));
    }

    #[test]
    fn measure_normal_and_depth_errors_compare_up_to_sign() {
        let mut fb = render_disc(16.0);
        let k = fb.index(16, 16);
        let tilt = 10f64.to_radians();
        fb.normal.as_mut().unwrap()[k] = [0.0, -tilt.sin() as f32, -tilt.cos() as f32];
        fb.depth[k] = 0.25;
        let a = measure_disc(&fb, 0, Some(0.0));
        assert!(
            (a.normal_max_deg - 10.0).abs() < 1e-4,
            "{}",
            a.normal_max_deg
        );
        assert_eq!(a.depth_max_abs, 0.25);
    }

    #[test]
    fn measure_normal_mean_is_the_mean_angle_over_the_pixels_both_cover() {
        // Four pixels of the disc off +z: by 10 and 40 degrees, by 20 degrees on the far side
        // (the same up to sign) and with no normal at all (90 degrees); the rest exact.
        let mut fb = render_disc(16.0);
        let normals = fb.normal.as_mut().unwrap();
        for (k, deg, sign) in [
            (16 * 32 + 16, 10.0, 1.0),
            (15 * 32 + 12, 20.0, -1.0),
            (20 * 32 + 18, 40.0, 1.0),
        ] {
            let t = f64::to_radians(deg);
            normals[k] = [(sign * t.sin()) as f32, 0.0, (sign * t.cos()) as f32];
        }
        normals[10 * 32 + 16] = [0.0; 3];
        let a = measure_disc(&fb, 0, Some(0.0));
        let compared = count(|i, j| in_disc(i, j, 16.0));
        assert_eq!(a.pixels_compared, compared);
        assert_eq!(a.normal_max_deg, 90.0);
        let mean = (10.0 + 20.0 + 40.0 + 90.0) / compared as f64;
        assert!((a.normal_mean_deg - mean).abs() < 1e-5, "{a:?} vs {mean}");
    }

    #[test]
    fn angle_up_to_sign_is_90_degrees_against_a_zero_normal() {
        // A missing normal on either side is as wrong as a normal can be.
        for v in [DVec3::Z, DVec3::new(0.3, -0.4, 2.0)] {
            assert_eq!(angle_up_to_sign(DVec3::ZERO, v), 90.0);
            assert_eq!(angle_up_to_sign(v, DVec3::ZERO), 90.0);
            assert_eq!(angle_up_to_sign(v, -2.0 * v), 0.0);
        }
    }

    /// A reference of `w` x `h` covering every pixel or none.
    fn uniform_reference(w: u32, h: u32, covered: bool) -> ReferenceImage {
        let n = (w * h) as usize;
        let hit = ReferenceHit {
            depth: 0.5,
            normal: DVec3::Z,
            lembo: 0,
            u: 0.2,
            v: 0.2,
        };
        ReferenceImage {
            width: w,
            height: h,
            supersample: 1,
            hits: vec![covered.then_some(hit); n],
            hits_offset_px: [0.0; 2],
            bins: None,
            color: vec![if covered { COLOR } else { BACKGROUND }; n],
            color_supersampled: None,
            coverage: None,
        }
    }

    /// The coverage of a reference covering everything or nothing.
    struct Uniform(bool);

    impl ReferenceCoverage for Uniform {
        fn covered(&self, _: f64, _: f64) -> bool {
            self.0
        }
    }

    #[test]
    fn measure_against_a_reference_covering_nothing_or_everything() {
        // No outline to measure to: each misplaced pixel counts the image diagonal. A
        // non-square image, so that the diagonal's two sides cannot be confused.
        let (w, h) = (7u32, 5u32);
        let diagonal = f64::from(w * w + h * h).sqrt();
        // Three pixels on the border, so that a miss is never a crack.
        let border = [(0, 0), (3, 0), (6, 4)];
        for covered in [false, true] {
            let mut fb = FrameBuffer::new(w, h, BACKGROUND, true);
            for j in 0..h {
                for i in 0..w {
                    if covered != border.contains(&(i, j)) {
                        let k = fb.index(i, j);
                        fb.write(k, 0.5, 0, COLOR);
                        fb.normal.as_mut().unwrap()[k] = [0.0, 0.0, 1.0];
                    }
                }
            }
            let reference = uniform_reference(w, h, covered);
            let flip = flip_frame(&fb, &reference, PixelsPerDegree::default());
            let a = measure(
                &fb,
                &reference,
                &Uniform(covered),
                0,
                None,
                Default::default(),
                &flip,
            );
            let misplaced = if covered {
                (a.coverage_false_negative, a.coverage_false_positive)
            } else {
                (a.coverage_false_positive, a.coverage_false_negative)
            };
            assert_eq!(misplaced, (3, 0), "{a:?}");
            assert_eq!(a.crack_pixels, 0);
            assert_eq!(
                (a.silhouette_max_px, a.silhouette_mean_px),
                (diagonal, diagonal)
            );
            let both = if covered { w * h - 3 } else { 0 };
            assert_eq!(a.pixels_compared, u64::from(both));
            // Nothing compared: no normal error (not 0 / 0).
            assert_eq!((a.normal_max_deg, a.normal_mean_deg), (0.0, 0.0));
            // Three pixels differ by (200, 150, 80) out of 3 w h channel values.
            let mse =
                (200f64.powi(2) + 150f64.powi(2) + 80f64.powi(2)) * 3.0 / f64::from(3 * w * h);
            let psnr = 10.0 * (255.0f64.powi(2) / mse).log10();
            assert!((a.psnr_db - psnr).abs() < 1e-9, "{a:?} vs {psnr}");
            assert_eq!(a.max_abs_error, 200);
        }
    }

    #[test]
    fn crack_mask_matches_its_definition_on_random_masks() {
        // A crack: the reference covers the pixel and its 4 neighbours (all inside the
        // image), the render misses it and covers both its left and right neighbours or
        // both those above and below.
        let (w, h) = (9, 7);
        let mut random = crate::testkit::SplitMix64::new(7);
        let mut cracks = 0;
        for _ in 0..300 {
            let mut draw = |p: f64| (0..w * h).map(|_| random.unit() < p).collect::<Vec<_>>();
            let (theirs, ours) = (draw(0.9), draw(0.6));
            let mask = crack_mask(&ours, &theirs, w, h);
            for j in 0..h as i64 {
                for i in 0..w as i64 {
                    let at = |m: &[bool], x: i64, y: i64| {
                        (0..w as i64).contains(&x)
                            && (0..h as i64).contains(&y)
                            && m[y as usize * w + x as usize]
                    };
                    let interior = [(0, 0), (-1, 0), (1, 0), (0, -1), (0, 1)]
                        .iter()
                        .all(|&(di, dj)| at(&theirs, i + di, j + dj));
                    let gap = (at(&ours, i - 1, j) && at(&ours, i + 1, j))
                        || (at(&ours, i, j - 1) && at(&ours, i, j + 1));
                    let want = interior && !at(&ours, i, j) && gap;
                    assert_eq!(mask[j as usize * w + i as usize], want, "({i}, {j})");
                    cracks += want as u32;
                }
            }
        }
        assert!(cracks > 100, "{cracks}");
    }

    #[test]
    fn lines_name_every_field_with_its_unit() {
        let a = measure_disc(&render_disc(16.0), 0, Some(0.0));
        let lines = a.lines();
        let json = serde_json::to_value(&a).unwrap();
        assert_eq!(lines.len(), json.as_object().unwrap().len());
        for (name, _) in &lines {
            assert!(json.get(name).is_some(), "{name}");
        }
        assert!(lines
            .iter()
            .any(|(n, v)| n == "psnr_db" && v.ends_with("dB (identical)")));
    }
}
