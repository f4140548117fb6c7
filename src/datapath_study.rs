//! The datapath study (issue 7, item 2): the paper's guarantee and the coverage errors of the
//! `f32` datapath against the `f64` one, over seeded random lembos in families that matter
//! for numerics.
//!
//! ```text
//!  (seed, family, index) ─► case(): two lembos sharing a curved edge, as scene JSON
//!        ─► Scene::from_json ─► exact reference once ─► for each datapath and k:
//!           render_functional(analyse) ─► Accuracy, probe ─► Measurement
//!  measurements ─► summarise(): per family, datapath and k ─► markdown, JSON, CSV
//! ```
//!
//! A case is a pair of lembos sharing a curved edge (the same three world points), so that
//! besides the guarantee metric (`max_scanline_deviation_px`, which the segmenter promises
//! is at most k) the shared edge's cracks and double hits are measured too. Every case is a
//! function of the study seed, its family and its index alone ([`case`]), through a
//! SplitMix64 generator written here: the library takes no `rand` dependency, and no
//! upstream change of a distribution's algorithm can change the cases. A case's scene JSON
//! is a complete scene file: `lembo-sim render FILE --reference` reproduces it.
//!
//! The families ([`Family`]) are drawn on a 256 x 256 viewport; all but the perspective one
//! use an orthographic camera down −z, one world unit per pixel, so the screen coordinates
//! are the world ones shifted. The study measures the scan-line datapath only: Setup
//! projects in `f64` and rounds the six screen points to the datapath (as
//! `raster::setup` does), so world-space magnitudes reach `f32` only through the screen
//! coordinates. The probe measures the deviation against the datapath's own screen
//! quadratic, so rounding the six screen points shows in the coverage errors, not in the
//! guarantee metric.
//!
//! Not measured: the triangle path, the timed pipeline (its image equals the functional
//! one bit for bit, tested elsewhere), and f32 world-space input to Setup.

use crate::camera::View;
use crate::datapath::Datapath;
use crate::frame::render_functional;
use crate::job::{measure_frame, render_reference, PrimitivePath};
use crate::lembo::Lembo;
use crate::reference::PixelsPerDegree;
use crate::rop::FrameBuffer;
use crate::scene::Scene;
use glam::{DVec2, DVec3};
use rayon::prelude::*;
use serde::Serialize;
use serde_json::json;
use std::fmt::Write as _;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;
use std::time::Instant;

/// Side of the study's square viewport \[pixels\].
pub const SIDE: u32 = 256;

/// A case's guarantee "holds" when `max_scanline_deviation_px` is at most k plus this
/// \[pixels\].
pub const HOLD_TOLERANCE_PX: f64 = 1e-3;

/// The families of random cases, each aimed at one numerical hazard.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Family {
    /// Curved patches 10 to 200 px across, centred within 100 px of the viewport centre.
    Ordinary,
    /// The ordinary case of the same index, translated 10³ world units from the origin in
    /// a random direction, the camera following.
    #[serde(rename = "far_1e3")]
    Far1e3,
    /// The same at 10⁵.
    #[serde(rename = "far_1e5")]
    Far1e5,
    /// The same at 10⁷ (f32's ulp is 1 there).
    #[serde(rename = "far_1e7")]
    Far1e7,
    /// Patches 10³ to 10⁶ px across, placed so that a random point of the first lembo lands
    /// on the viewport: mostly off screen, screen coordinates up to about 10⁶.
    Large,
    /// Ordinary patches whose edge middles are off their chords by 10⁻¹³ to 10⁻¹¹ of the
    /// edge length: the quadratics' leading coefficients are about 10⁻¹² relative.
    NearlyFlat,
    /// Even indices: slivers 10⁻⁴ to 10⁻¹·⁵ of their length wide, bent into a banana; odd
    /// indices: corners collinear to 10⁻¹⁰ to 10⁻³ relative, with ordinary bends.
    NearlyDegenerate,
    /// A bumpy patch pair in the plane Z = 0 seen in perspective from 1° to 15° above it.
    SteepPerspective,
}

/// Every family, in table order.
pub const FAMILIES: [Family; 8] = [
    Family::Ordinary,
    Family::Far1e3,
    Family::Far1e5,
    Family::Far1e7,
    Family::Large,
    Family::NearlyFlat,
    Family::NearlyDegenerate,
    Family::SteepPerspective,
];

impl Family {
    /// The family's name in tables, files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Family::Ordinary => "ordinary",
            Family::Far1e3 => "far_1e3",
            Family::Far1e5 => "far_1e5",
            Family::Far1e7 => "far_1e7",
            Family::Large => "large",
            Family::NearlyFlat => "nearly_flat",
            Family::NearlyDegenerate => "nearly_degenerate",
            Family::SteepPerspective => "steep_perspective",
        }
    }

    /// The family of a name, as [`Family::name`] spells it.
    pub fn parse(name: &str) -> Option<Family> {
        FAMILIES.into_iter().find(|f| f.name() == name)
    }

    /// One line on what the family exercises.
    pub fn description(self) -> &'static str {
        match self {
            Family::Ordinary => "curved patches 10-200 px across, orthographic",
            Family::Far1e3 => "the ordinary cases translated 1e3 world units, camera following",
            Family::Far1e5 => "the ordinary cases translated 1e5 world units, camera following",
            Family::Far1e7 => "the ordinary cases translated 1e7 world units, camera following",
            Family::Large => "patches 1e3-1e6 px across, mostly off screen",
            Family::NearlyFlat => "edge middles 1e-13 to 1e-11 of the edge off the chord",
            Family::NearlyDegenerate => {
                "slivers 1e-4 to 3e-2 of their length wide; corners collinear to 1e-10 to 1e-3"
            }
            Family::SteepPerspective => {
                "bumpy patches in perspective, seen 1-15 deg above their plane"
            }
        }
    }

    /// The translation [world units] of the far families.
    fn offset(self) -> Option<f64> {
        match self {
            Family::Far1e3 => Some(1e3),
            Family::Far1e5 => Some(1e5),
            Family::Far1e7 => Some(1e7),
            _ => None,
        }
    }

    fn ordinal(self) -> u64 {
        FAMILIES.iter().position(|&f| f == self).unwrap_or(0) as u64
    }
}

/// SplitMix64 (Steele, Lea and Flood, "Fast splittable pseudorandom number generators",
/// OOPSLA 2014): a 64-bit state, one multiply-xorshift finaliser per draw.
#[derive(Clone, Debug)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// A generator started at `seed`.
    pub fn new(seed: u64) -> Self {
        SplitMix64(seed)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1), 53 bits.
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }

    /// Log-uniform in [lo, hi), both > 0.
    pub fn log_range(&mut self, lo: f64, hi: f64) -> f64 {
        (lo.ln() + (hi.ln() - lo.ln()) * self.unit()).exp()
    }

    /// A uniform point of the unit disc.
    pub fn disc(&mut self) -> DVec2 {
        let (r, a) = (self.unit().sqrt(), self.range(0.0, std::f64::consts::TAU));
        DVec2::new(r * a.cos(), r * a.sin())
    }

    /// A uniform unit vector.
    pub fn direction(&mut self) -> DVec3 {
        let z = self.range(-1.0, 1.0);
        let a = self.range(0.0, std::f64::consts::TAU);
        let r = (1.0 - z * z).sqrt();
        DVec3::new(r * a.cos(), r * a.sin(), z)
    }
}

/// The seed of one stream of a case: (study seed, family, index, stream) mixed through
/// SplitMix64, so that cases are independent of each other and of the case count.
fn stream(seed: u64, family: Family, index: u32, what: u64) -> SplitMix64 {
    let mut g = SplitMix64::new(seed);
    let mut s = g.next_u64() ^ family.ordinal().wrapping_mul(0xD6E8_FEB8_6659_FD93);
    s = SplitMix64::new(s).next_u64() ^ (index as u64).wrapping_mul(0xA076_1D64_78BD_642F);
    s = SplitMix64::new(s).next_u64() ^ what.wrapping_mul(0xE703_7ED1_A0B4_28DB);
    SplitMix64::new(SplitMix64::new(s).next_u64())
}

/// One random case: a scene of two lembos sharing a curved edge.
#[derive(Clone, Debug)]
pub struct Case {
    /// The case's family.
    pub family: Family,
    /// Its index within the family.
    pub index: u32,
    /// The study seed it was drawn with.
    pub seed: u64,
    /// A complete scene file (`Scene::from_json`; `lembo-sim render` reads it).
    pub scene_json: String,
}

/// How a flat quadrilateral is drawn before bending: corners P1, P2 at the ends of a
/// diagonal of length `size`, P0 and P3 on either side of it.
struct Quad {
    size: f64,
    /// Distance of P0 and P3 from the diagonal, relative to `size`.
    thickness: f64,
    /// Largest move of an edge middle off its chord, relative to the edge length.
    bend: f64,
    /// Largest depth of a point, and of an edge middle off its chord's [world units].
    z_amplitude: f64,
    /// A quadratic warp of the whole plane across the diagonal, relative to `size`
    /// (a banana); 0 for independent bends only.
    warp: f64,
}

/// The points of a patch pair: corners P0..P3 and the middles of P0P1, P0P2, P1P2, P1P3,
/// P2P3, in a local frame centred on the diagonal's middle.
struct Pair {
    corners: [DVec3; 4],
    middles: [DVec3; 5],
}

const MIDDLE_ENDS: [(usize, usize); 5] = [(0, 1), (0, 2), (1, 2), (1, 3), (2, 3)];

impl Pair {
    fn draw(q: &Quad, rng: &mut SplitMix64) -> Pair {
        let angle = rng.range(0.0, std::f64::consts::TAU);
        let (along, across) = (
            DVec2::new(angle.cos(), angle.sin()),
            DVec2::new(-angle.sin(), angle.cos()),
        );
        let half = 0.5 * q.size;
        let mut flat = [DVec2::ZERO; 4];
        flat[1] = -half * along;
        flat[2] = half * along;
        for (n, side) in [(0, 1.0), (3, -1.0)] {
            let h = q.size * q.thickness * rng.range(0.5, 1.0);
            flat[n] = rng.range(-0.3, 0.3) * q.size * along + side * h * across;
        }
        let warp = q.warp * rng.range(-1.0, 1.0);
        let bent = |p: DVec2| {
            let t = p.dot(along) / half;
            p + warp * q.size * t * t * across
        };
        let mut corners = [DVec3::ZERO; 4];
        for (c, f) in corners.iter_mut().zip(flat) {
            *c = bent(f).extend(q.z_amplitude * rng.range(-1.0, 1.0));
        }
        let mut middles = [DVec3::ZERO; 5];
        for (m, (a, b)) in middles.iter_mut().zip(MIDDLE_ENDS) {
            let chord = 0.5 * (flat[a] + flat[b]);
            let len = (flat[b] - flat[a]).length();
            let xy = bent(chord) + q.bend * len * rng.disc();
            let z =
                0.5 * (corners[a].z + corners[b].z) + 0.5 * q.z_amplitude * rng.range(-1.0, 1.0);
            *m = xy.extend(z);
        }
        Pair { corners, middles }
    }

    /// The two lembos' six points each, through `map`.
    fn lembo_points(&self, map: impl Fn(DVec3) -> DVec3) -> [[DVec3; 6]; 2] {
        by_lembo(self.corners.map(&map), self.middles.map(&map))
    }
}

/// Per-pair values (corners P0..P3, middles in [`MIDDLE_ENDS`] order) as the two lembos'
/// six: (P0, P1, P2) and (P2, P1, P3), which share the edge P1P2 and its middle.
fn by_lembo<T: Copy>(c: [T; 4], m: [T; 5]) -> [[T; 6]; 2] {
    [
        [c[0], c[1], c[2], m[0], m[1], m[2]],
        [c[2], c[1], c[3], m[2], m[4], m[3]],
    ]
}

/// Normals tilted at random about `up`, one per point of the pair, so that the shared edge
/// has one normal function as in a mesh (they shade; coverage ignores them).
fn normals(rng: &mut SplitMix64, up: DVec3) -> [[DVec3; 6]; 2] {
    let mut tilted = || up + 0.5 * rng.direction();
    let corners: [DVec3; 4] = std::array::from_fn(|_| tilted());
    let middles: [DVec3; 5] = std::array::from_fn(|_| tilted());
    by_lembo(corners, middles)
}

fn lembo_json(points: &[DVec3; 6], normals: &[DVec3; 6]) -> serde_json::Value {
    json!({
        "points": points.map(|p| p.to_array()),
        "normals": normals.map(|n| n.to_array()),
    })
}

fn ortho_camera(centre: DVec3) -> serde_json::Value {
    json!({
        "eye": (centre + DVec3::new(0.0, 0.0, 10.0)).to_array(),
        "target": centre.to_array(),
        "up": [0, 1, 0],
        "projection": {"kind": "orthographic", "height": SIDE, "near": 0.1, "far": 100}
    })
}

fn scene_json(
    family: Family,
    index: u32,
    camera: serde_json::Value,
    lembos: [[DVec3; 6]; 2],
    rng: &mut SplitMix64,
    up: DVec3,
) -> String {
    let normals = normals(rng, up);
    let objects: Vec<serde_json::Value> = lembos
        .iter()
        .zip(&normals)
        .enumerate()
        .map(|(n, (ps, ns))| {
            json!({
                "lembos": [lembo_json(ps, ns)],
                "color": if n == 0 { [0.8, 0.5, 0.3] } else { [0.3, 0.6, 0.8] },
            })
        })
        .collect();
    let scene = json!({
        "name": format!("datapath_study_{}_{index}", family.name()),
        "viewport": {"width": SIDE, "height": SIDE},
        "camera": camera,
        "objects": objects,
    });
    serde_json::to_string_pretty(&scene).expect("a JSON value serialises")
}

/// The shape of an ordinary case (shared by the far families, so that their rows differ
/// from the ordinary one by the translation alone).
fn ordinary_pair(rng: &mut SplitMix64) -> (Pair, DVec3) {
    let q = Quad {
        size: rng.log_range(10.0, 200.0),
        thickness: rng.range(0.3, 0.8),
        bend: rng.range(0.0, 0.25),
        z_amplitude: 5.0,
        warp: 0.0,
    };
    let pair = Pair::draw(&q, rng);
    let centre = DVec3::new(rng.range(-100.0, 100.0), rng.range(-100.0, 100.0), 0.0);
    (pair, centre)
}

/// Draws case `index` of `family` for the study seed `seed`.
pub fn case(family: Family, seed: u64, index: u32) -> Case {
    // Streams: 0 the shape, 1 the placement and camera, 2 the normals.
    let mut shape = stream(seed, family, index, 0);
    let mut place = stream(seed, family, index, 1);
    // The far families reuse the ordinary case's shape and normals.
    let like = if family.offset().is_some() {
        Family::Ordinary
    } else {
        family
    };
    let mut shade = stream(seed, like, index, 2);
    let z = DVec3::Z;
    let (camera, lembos, up) = match family {
        Family::Ordinary => {
            let (pair, centre) = ordinary_pair(&mut shape);
            let points = pair.lembo_points(|p| p + centre);
            (ortho_camera(DVec3::ZERO), points, z)
        }
        Family::Far1e3 | Family::Far1e5 | Family::Far1e7 => {
            let mut same = stream(seed, like, index, 0);
            let (pair, centre) = ordinary_pair(&mut same);
            let offset = family.offset().unwrap_or(0.0) * place.direction();
            let points = pair.lembo_points(|p| p + centre + offset);
            (ortho_camera(offset), points, z)
        }
        Family::Large => large_case(&mut shape, &mut place),
        Family::NearlyFlat => {
            let q = Quad {
                size: shape.log_range(10.0, 200.0),
                thickness: shape.range(0.3, 0.8),
                bend: shape.log_range(1e-13, 1e-11),
                z_amplitude: 5.0,
                warp: 0.0,
            };
            let pair = Pair::draw(&q, &mut shape);
            let centre = DVec3::new(place.range(-100.0, 100.0), place.range(-100.0, 100.0), 0.0);
            (
                ortho_camera(DVec3::ZERO),
                pair.lembo_points(|p| p + centre),
                z,
            )
        }
        Family::NearlyDegenerate => nearly_degenerate_case(index, &mut shape, &mut place),
        Family::SteepPerspective => steep_perspective_case(&mut shape, &mut place),
    };
    Case {
        family,
        index,
        seed,
        scene_json: scene_json(family, index, camera, lembos, &mut shade, up),
    }
}

/// A large lembo pair (10³ to 10⁶ world units) with a random point of the first on a random
/// point of the viewport.
fn large_case(
    shape: &mut SplitMix64,
    place: &mut SplitMix64,
) -> (serde_json::Value, [[DVec3; 6]; 2], DVec3) {
    let z = DVec3::Z;
    let q = Quad {
        size: shape.log_range(1e3, 1e6),
        thickness: shape.range(0.3, 0.8),
        bend: shape.range(0.0, 0.25),
        z_amplitude: 5.0,
        warp: 0.0,
    };
    let pair = Pair::draw(&q, shape);
    // A random point of the first lembo lands on a random point of the viewport.
    let [first, _] = pair.lembo_points(|p| p);
    let lembo = Lembo::new(first, [z; 6]);
    let (a, b) = (place.unit(), place.unit());
    let (u, v) = if a + b > 1.0 {
        (1.0 - a, 1.0 - b)
    } else {
        (a, b)
    };
    let on = lembo.position_at(u, v);
    let at = DVec3::new(place.range(-110.0, 110.0), place.range(-110.0, 110.0), 0.0);
    let shift = DVec3::new(at.x - on.x, at.y - on.y, 0.0);
    (
        ortho_camera(DVec3::ZERO),
        pair.lembo_points(|p| p + shift),
        z,
    )
}

/// A sliver pair: even cases thin and bent as much as they are thick, with warp; odd cases
/// thin down to 10⁻¹⁰.
fn nearly_degenerate_case(
    index: u32,
    shape: &mut SplitMix64,
    place: &mut SplitMix64,
) -> (serde_json::Value, [[DVec3; 6]; 2], DVec3) {
    let z = DVec3::Z;
    let size = shape.log_range(20.0, 200.0);
    let q = if index.is_multiple_of(2) {
        let thickness = shape.log_range(1e-4, 10f64.powf(-1.5));
        Quad {
            size,
            thickness,
            bend: thickness,
            z_amplitude: 5.0,
            warp: shape.range(0.0, 0.2),
        }
    } else {
        Quad {
            size,
            thickness: shape.log_range(1e-10, 1e-3),
            bend: shape.range(0.0, 0.25),
            z_amplitude: 5.0,
            warp: 0.0,
        }
    };
    let pair = Pair::draw(&q, shape);
    let centre = DVec3::new(place.range(-80.0, 80.0), place.range(-80.0, 80.0), 0.0);
    (
        ortho_camera(DVec3::ZERO),
        pair.lembo_points(|p| p + centre),
        z,
    )
}

/// A pair seen in perspective from 1° to 15° above its plane, 1.5 to 4 radii away.
fn steep_perspective_case(
    shape: &mut SplitMix64,
    place: &mut SplitMix64,
) -> (serde_json::Value, [[DVec3; 6]; 2], DVec3) {
    let z = DVec3::Z;
    let size = shape.log_range(5.0, 20.0);
    let q = Quad {
        size,
        thickness: shape.range(0.3, 0.8),
        bend: shape.range(0.0, 0.25),
        z_amplitude: 0.1 * size,
        warp: 0.0,
    };
    let pair = Pair::draw(&q, shape);
    let points = pair.lembo_points(|p| p);
    let radius = points
        .iter()
        .flatten()
        .map(|p| p.length())
        .fold(0.0, f64::max);
    let target = (0.2 * size * place.disc()).extend(0.0);
    let azimuth = place.range(0.0, std::f64::consts::TAU);
    let elevation = place.range(1.0, 15.0).to_radians();
    let distance = radius * place.range(1.5, 4.0);
    let eye = target
        + distance
            * DVec3::new(
                elevation.cos() * azimuth.cos(),
                elevation.cos() * azimuth.sin(),
                elevation.sin(),
            );
    let camera = json!({
        "eye": eye.to_array(),
        "target": target.to_array(),
        "up": [0, 0, 1],
        "projection": {
            "kind": "perspective",
            "fovy_deg": place.range(30.0, 70.0),
            "near": 0.01 * distance,
            "far": 4.0 * distance,
        }
    });
    (camera, points, z)
}

/// What one render of a case measured.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Measurement {
    /// The case's family.
    pub family: Family,
    /// Its index within the family.
    pub index: u32,
    /// The study seed it was drawn from.
    pub seed: u64,
    /// The datapath rendered in.
    pub datapath: Datapath,
    /// The segmenter's k \[pixels\].
    pub k_px: f64,
    /// `ok`, or the error or panic message: a refused scene, an `Error` from the renderer,
    /// or a panic (a defect).
    pub status: String,
    /// Lembos culled (behind the eye, outside, degenerate) of the case's two.
    pub lembos_culled: u64,
    /// Fragments generated.
    pub fragments: u64,
    /// The probe's largest |y(u, v) − (j + 0.5)| over the fragments \[pixels\]; 0 without
    /// fragments.
    pub max_scanline_deviation_px: f64,
    /// `max_scanline_deviation_px − k` \[pixels\]; None without fragments.
    pub slack_px: Option<f64>,
    /// Pixel centres the reference covers \[pixels\].
    pub reference_covered_px: u64,
    /// Largest |x| or |y| of the case's projected points \[pixels\]: the magnitude of the
    /// screen coordinates the datapath works with.
    pub max_screen_coordinate_px: f64,
    /// Pixels covered by the render and not the reference \[pixels\].
    pub false_positive_px: u64,
    /// Pixels covered by the reference and not the render \[pixels\].
    pub false_negative_px: u64,
    /// False positives over `max(reference_covered_px, 1)`.
    pub false_positive_frac: f64,
    /// False negatives over `max(reference_covered_px, 1)`.
    pub false_negative_frac: f64,
    /// Pixels whose winning lembo (or none) differs from the f64 render's at the same k
    /// \[pixels\] (0 for f64).
    pub winner_diff_vs_f64_px: u64,
    /// Largest difference of a colour channel from the f64 render's at the same k, over
    /// the pixels with the same winner: the shading's share of f32 [0-255] (0 for f64).
    pub shade_diff_vs_f64_max: u64,
    /// Domain-edge roots the interval manager could not pair (0 when sound).
    pub unpaired_roots: u64,
    /// Holes inside the reference's coverage (the accuracy metric) \[pixels\].
    pub crack_pixels: u64,
    /// Pixels written twice along the pair's shared edge \[pixels\].
    pub double_hit_pixels: u64,
    /// PSNR against the reference \[dB\].
    pub psnr_db: f64,
    /// Wall time of the render with the probe \[seconds\] (host-dependent).
    pub render_seconds: f64,
}

/// What a run of the study measured, case by case.
#[derive(Clone, Debug, Serialize)]
pub struct CaseResult {
    /// The case's family.
    pub family: Family,
    /// Its index within the family.
    pub index: u32,
    /// Wall time of the exact reference \[seconds\] (host-dependent).
    pub reference_seconds: f64,
    /// One per datapath and k: f64 then f32, k in the given order.
    pub measurements: Vec<Measurement>,
}

fn panic_message(p: Box<dyn std::any::Any + Send>) -> String {
    if let Some(s) = p.downcast_ref::<&str>() {
        s.to_string()
    } else if let Some(s) = p.downcast_ref::<String>() {
        s.clone()
    } else {
        "(no message)".into()
    }
}

/// A measurement of `case` at `datapath` and `k` with every figure zero: what a run that
/// could not measure records, with its `status`.
fn blank(case: &Case, datapath: Datapath, k: f64, status: String) -> Measurement {
    Measurement {
        family: case.family,
        index: case.index,
        seed: case.seed,
        datapath,
        k_px: k,
        status,
        lembos_culled: 0,
        fragments: 0,
        max_scanline_deviation_px: 0.0,
        slack_px: None,
        reference_covered_px: 0,
        max_screen_coordinate_px: 0.0,
        false_positive_px: 0,
        false_negative_px: 0,
        false_positive_frac: 0.0,
        false_negative_frac: 0.0,
        winner_diff_vs_f64_px: 0,
        shade_diff_vs_f64_max: 0,
        unpaired_roots: 0,
        crack_pixels: 0,
        double_hit_pixels: 0,
        psnr_db: 0.0,
        render_seconds: 0.0,
    }
}

/// Against the f64 render's winners and colours: the pixels won by another primitive,
/// and the largest channel difference where the same primitive won; (0, 0) without one.
fn diff_vs_f64(fb: &FrameBuffer, f64_image: Option<&(Vec<u32>, Vec<[u8; 3]>)>) -> (u64, u64) {
    match f64_image {
        Some((winner64, color64)) => {
            let same = |i: &usize| fb.primitive[*i] == winner64[*i];
            let n = fb.primitive.len();
            (
                (0..n).filter(|i| !same(i)).count() as u64,
                (0..n)
                    .filter(same)
                    .flat_map(|i| {
                        fb.color[i]
                            .iter()
                            .zip(color64[i])
                            .map(|(a, b)| a.abs_diff(b) as u64)
                    })
                    .max()
                    .unwrap_or(0),
            )
        }
        None => (0, 0),
    }
}

/// Renders one case against the exact reference in both datapaths at every k. A refused
/// scene, a renderer error or a panic is recorded in the measurements' `status`, not
/// propagated: the study goes on and reports it.
pub fn measure_case(case: &Case, ks: &[f64]) -> CaseResult {
    let blank = |datapath: Datapath, k: f64, status: String| blank(case, datapath, k, status);
    let all = |status: String| -> Vec<Measurement> {
        [Datapath::F64, Datapath::F32]
            .into_iter()
            .flat_map(|d| ks.iter().map(move |&k| (d, k)))
            .map(|(d, k)| blank(d, k, status.clone()))
            .collect()
    };
    let file = format!("datapath study {} {}", case.family.name(), case.index);
    let scene = match Scene::from_json(&case.scene_json, &file, Path::new(".")) {
        Ok(s) => s,
        Err(e) => {
            return CaseResult {
                family: case.family,
                index: case.index,
                reference_seconds: 0.0,
                measurements: all(format!("error: scene refused: {e}")),
            }
        }
    };
    let view = View::new(&scene.camera, scene.viewport);
    let max_screen_coordinate_px = scene
        .lembos()
        .flat_map(|(l, _)| l.points)
        .map(|p| view.project(p))
        .map(|s| s.x.abs().max(s.y.abs()))
        .fold(0.0, f64::max);
    let reference = match catch_unwind(AssertUnwindSafe(|| {
        render_reference(&scene, &view, 1, crate::camera::Samples::ONE)
    })) {
        Ok(r) => r,
        Err(p) => {
            return CaseResult {
                family: case.family,
                index: case.index,
                reference_seconds: 0.0,
                measurements: all(format!("panic in the reference: {}", panic_message(p))),
            }
        }
    };
    let (reference, reference_seconds) = reference;
    let covered = reference.hits.iter().filter(|h| h.is_some()).count() as u64;
    let mut measurements = Vec::new();
    for &k in ks {
        // The f64 render's winning primitives and colours, to compare f32's with.
        let mut f64_image: Option<(Vec<u32>, Vec<[u8; 3]>)> = None;
        for datapath in [Datapath::F64, Datapath::F32] {
            let t = Instant::now();
            let run = catch_unwind(AssertUnwindSafe(|| {
                render_functional(&scene, &view, k, datapath, true)
            }));
            let seconds = t.elapsed().as_secs_f64();
            let frame = match run {
                Ok(Ok(frame)) => frame,
                Ok(Err(e)) => {
                    measurements.push(blank(datapath, k, format!("error: {e}")));
                    continue;
                }
                Err(p) => {
                    measurements.push(blank(datapath, k, format!("panic: {}", panic_message(p))));
                    continue;
                }
            };
            let probe = frame.probe.unwrap_or_default();
            let a = measure_frame(
                &scene,
                &view,
                &frame,
                &reference,
                PrimitivePath::Lembo,
                1,
                PixelsPerDegree::default(),
            );
            let fb = &frame.framebuffer;
            let (winner_diff, shade_diff) = diff_vs_f64(fb, f64_image.as_ref());
            if datapath == Datapath::F64 {
                f64_image = Some((fb.primitive.to_vec(), fb.color.to_vec()));
            }
            let c = &frame.counts;
            let denominator = covered.max(1) as f64;
            measurements.push(Measurement {
                status: "ok".into(),
                lembos_culled: c.lembos_culled_behind_eye
                    + c.lembos_culled_outside
                    + c.lembos_degenerate,
                fragments: probe.fragments,
                max_scanline_deviation_px: probe.max_scanline_deviation_px,
                slack_px: (probe.fragments > 0).then_some(probe.max_scanline_deviation_px - k),
                reference_covered_px: covered,
                max_screen_coordinate_px,
                false_positive_px: a.coverage_false_positive,
                false_negative_px: a.coverage_false_negative,
                false_positive_frac: a.coverage_false_positive as f64 / denominator,
                false_negative_frac: a.coverage_false_negative as f64 / denominator,
                winner_diff_vs_f64_px: winner_diff,
                shade_diff_vs_f64_max: shade_diff,
                unpaired_roots: c.unpaired_roots,
                crack_pixels: a.crack_pixels,
                double_hit_pixels: a.double_hit_pixels,
                psnr_db: a.psnr_db,
                render_seconds: seconds,
                ..blank(datapath, k, String::new())
            });
        }
    }
    CaseResult {
        family: case.family,
        index: case.index,
        reference_seconds,
        measurements,
    }
}

/// What a study run draws and measures.
#[derive(Clone, Debug, Serialize)]
pub struct StudySettings {
    /// Cases (pairs of lembos) per family.
    pub cases_per_family: u32,
    /// The study seed: the same seed draws the same cases.
    pub seed: u64,
    /// The segmenter's k values \[pixels\].
    pub ks: Vec<f64>,
    /// The families drawn, in report order.
    pub families: Vec<Family>,
}

/// Draws and measures every case of `settings`, in parallel on rayon's pool; the results are
/// in (family, index) order whatever the thread count.
pub fn run(settings: &StudySettings) -> Vec<CaseResult> {
    let cases: Vec<Case> = settings
        .families
        .iter()
        .flat_map(|&f| (0..settings.cases_per_family).map(move |i| case(f, settings.seed, i)))
        .collect();
    cases
        .par_iter()
        .map(|c| measure_case(c, &settings.ks))
        .collect()
}

/// The aggregate of one family, datapath and k.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// The family summarised.
    pub family: Family,
    /// The datapath.
    pub datapath: Datapath,
    /// The tolerance k \[pixels\].
    pub k_px: f64,
    /// Cases measured.
    pub cases: u64,
    /// Cases whose render gave an error or panicked.
    pub failures: u64,
    /// Cases with at least one fragment: the slack statistics are over these.
    pub drawn: u64,
    /// Median and largest `max_scanline_deviation_px − k` \[pixels\]; None when nothing
    /// was drawn.
    pub slack_median_px: Option<f64>,
    /// Largest `slack_px` over the cases \[pixels\]; None without fragments.
    pub slack_max_px: Option<f64>,
    /// Fraction of the drawn cases whose slack is at most [`HOLD_TOLERANCE_PX`].
    pub holds_frac: f64,
    /// Over the cases rendered without failure.
    pub false_positive_frac_mean: f64,
    /// Largest `false_positive_frac`.
    pub false_positive_frac_max: f64,
    /// Mean `false_negative_frac`.
    pub false_negative_frac_mean: f64,
    /// Largest `false_negative_frac`.
    pub false_negative_frac_max: f64,
    /// Largest and mean pixels whose winning lembo differs from f64's (0 for f64).
    pub winner_diff_vs_f64_px_max: u64,
    /// Mean `winner_diff_vs_f64_px` \[pixels\].
    pub winner_diff_vs_f64_px_mean: f64,
    /// Largest colour channel difference from f64 over pixels with the same winner [0-255]
    /// (0 for f64).
    pub shade_diff_vs_f64_max: u64,
    /// Unpaired roots over the cases.
    pub unpaired_roots: u64,
    /// Cases with at least one unpaired root.
    pub cases_with_unpaired_roots: u64,
    /// Crack pixels over the cases \[pixels\].
    pub crack_pixels: u64,
    /// Double hits over the cases \[pixels\].
    pub double_hit_pixels: u64,
    /// Sum of the renders' wall times \[seconds\] (host-dependent).
    pub render_seconds: f64,
}

fn median(sorted: &[f64]) -> Option<f64> {
    let n = sorted.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(sorted[n / 2]),
        _ => Some(0.5 * (sorted[n / 2 - 1] + sorted[n / 2])),
    }
}

/// Aggregates the measurements per family, datapath and k, in the settings' order (family,
/// then k, then f32 before f64).
pub fn summarise(settings: &StudySettings, results: &[CaseResult]) -> Vec<Summary> {
    let mut out = Vec::new();
    for &family in &settings.families {
        for &k in &settings.ks {
            for datapath in [Datapath::F32, Datapath::F64] {
                let ms: Vec<&Measurement> = results
                    .iter()
                    .filter(|r| r.family == family)
                    .flat_map(|r| &r.measurements)
                    .filter(|m| m.datapath == datapath && m.k_px == k)
                    .collect();
                let ok: Vec<&&Measurement> = ms.iter().filter(|m| m.status == "ok").collect();
                let mut slack: Vec<f64> = ok.iter().filter_map(|m| m.slack_px).collect();
                slack.sort_by(f64::total_cmp);
                let n_ok = ok.len().max(1) as f64;
                let mean = |f: fn(&Measurement) -> f64| ok.iter().map(|m| f(m)).sum::<f64>() / n_ok;
                let max = |f: fn(&Measurement) -> f64| ok.iter().map(|m| f(m)).fold(0.0, f64::max);
                let sum = |f: fn(&Measurement) -> u64| ok.iter().map(|m| f(m)).sum::<u64>();
                out.push(Summary {
                    family,
                    datapath,
                    k_px: k,
                    cases: ms.len() as u64,
                    failures: (ms.len() - ok.len()) as u64,
                    drawn: slack.len() as u64,
                    slack_median_px: median(&slack),
                    slack_max_px: slack.last().copied(),
                    holds_frac: if slack.is_empty() {
                        1.0
                    } else {
                        slack.iter().filter(|&&s| s <= HOLD_TOLERANCE_PX).count() as f64
                            / slack.len() as f64
                    },
                    false_positive_frac_mean: mean(|m| m.false_positive_frac),
                    false_positive_frac_max: max(|m| m.false_positive_frac),
                    false_negative_frac_mean: mean(|m| m.false_negative_frac),
                    false_negative_frac_max: max(|m| m.false_negative_frac),
                    winner_diff_vs_f64_px_max: ok
                        .iter()
                        .map(|m| m.winner_diff_vs_f64_px)
                        .max()
                        .unwrap_or(0),
                    winner_diff_vs_f64_px_mean: mean(|m| m.winner_diff_vs_f64_px as f64),
                    shade_diff_vs_f64_max: ok
                        .iter()
                        .map(|m| m.shade_diff_vs_f64_max)
                        .max()
                        .unwrap_or(0),
                    unpaired_roots: sum(|m| m.unpaired_roots),
                    cases_with_unpaired_roots: ok.iter().filter(|m| m.unpaired_roots > 0).count()
                        as u64,
                    crack_pixels: sum(|m| m.crack_pixels),
                    double_hit_pixels: sum(|m| m.double_hit_pixels),
                    render_seconds: ms.iter().map(|m| m.render_seconds).sum(),
                });
            }
        }
    }
    out
}

/// f32's slack against the magnitude of the screen coordinates, half a decade per row.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ExtentSummary {
    /// The bin: largest screen coordinate in [lo_px, hi_px) \[pixels\], hi_px = √10 lo_px.
    pub lo_px: f64,
    /// Upper end of the screen-extent bucket \[pixels\].
    pub hi_px: f64,
    /// The tolerance k \[pixels\].
    pub k_px: f64,
    /// Drawn f32 cases in the bin.
    pub drawn: u64,
    /// Largest f32 slack \[pixels\].
    pub f32_slack_max_px: f64,
    /// Drawn f32 cases whose slack is at most [`HOLD_TOLERANCE_PX`].
    pub f32_holds: u64,
    /// Largest f64 slack over the same cases \[pixels\].
    pub f64_slack_max_px: f64,
}

/// f32's slack by half decade of the largest screen coordinate, over the orthographic families
/// (the perspective one is left out: its violations are the segmenter's, not f32's).
pub fn by_extent(settings: &StudySettings, results: &[CaseResult]) -> Vec<ExtentSummary> {
    let ortho = |m: &&Measurement| m.family != Family::SteepPerspective && m.status == "ok";
    let bin = |m: &Measurement| (2.0 * m.max_screen_coordinate_px.max(1.0).log10()).floor() as i32;
    let all: Vec<&Measurement> = results
        .iter()
        .flat_map(|r| &r.measurements)
        .filter(ortho)
        .filter(|m| m.slack_px.is_some())
        .collect();
    let (lo, hi) = all.iter().fold((i32::MAX, i32::MIN), |(lo, hi), m| {
        (lo.min(bin(m)), hi.max(bin(m)))
    });
    let mut out = Vec::new();
    for d in lo..=hi {
        for &k in &settings.ks {
            let of = |dp: Datapath| {
                all.iter()
                    .filter(move |m| bin(m) == d && m.k_px == k && m.datapath == dp)
                    .filter_map(|m| m.slack_px)
            };
            let f32s: Vec<f64> = of(Datapath::F32).collect();
            if f32s.is_empty() {
                continue;
            }
            out.push(ExtentSummary {
                lo_px: 10f64.powf(0.5 * d as f64),
                hi_px: 10f64.powf(0.5 * (d + 1) as f64),
                k_px: k,
                drawn: f32s.len() as u64,
                f32_slack_max_px: f32s.iter().copied().fold(f64::MIN, f64::max),
                f32_holds: f32s.iter().filter(|&&s| s <= HOLD_TOLERANCE_PX).count() as u64,
                f64_slack_max_px: of(Datapath::F64).fold(f64::MIN, f64::max),
            });
        }
    }
    out
}

/// [`by_extent`] as a markdown table.
pub fn extent_markdown(rows: &[ExtentSummary]) -> String {
    let mut t = String::from(
        "| largest screen coordinate (px) | k (px) | cases | f32 slack max (px) | f32 holds | f64 slack max (px) |\n\
         |---|---|---|---|---|---|\n",
    );
    for r in rows {
        let _ = writeln!(
            t,
            "| {:.0} - {:.0} | {} | {} | {} | {}/{} | {} |",
            r.lo_px,
            r.hi_px,
            r.k_px,
            r.drawn,
            slack(Some(r.f32_slack_max_px)),
            r.f32_holds,
            r.drawn,
            slack(Some(r.f64_slack_max_px)),
        );
    }
    t
}

/// An f64 slack above this is a defect of the method, not rounding \[pixels\]: f64 rounding
/// of screen coordinates up to 10⁶ px stays below 10⁻⁸ px.
pub const F64_DEFECT_PX: f64 = 1e-6;

/// Measurements a user should look at: a failure, an f64 slack above [`F64_DEFECT_PX`],
/// or unpaired roots.
pub fn anomalies(results: &[CaseResult]) -> Vec<&Measurement> {
    results
        .iter()
        .flat_map(|r| &r.measurements)
        .filter(|m| {
            m.status != "ok"
                || m.unpaired_roots > 0
                || (m.datapath == Datapath::F64 && m.slack_px.is_some_and(|s| s > F64_DEFECT_PX))
        })
        .collect()
}

/// A slack in pixels, short: `-0.250`, `1.2e-4`, `-3.0e-12`.
fn slack(s: Option<f64>) -> String {
    match s {
        None => "-".into(),
        Some(0.0) => "0".into(),
        Some(s) if s.abs() >= 0.01 => format!("{s:.3}"),
        Some(s) => format!("{s:.1e}"),
    }
}

/// A fraction, short: `0`, `3.2e-5`.
fn frac(f: f64) -> String {
    if f == 0.0 {
        "0".into()
    } else {
        format!("{f:.1e}")
    }
}

/// The summaries as a markdown table: one row per family and k, f32 and f64 side by side.
/// Coverage errors are fractions of the pixels the reference covers.
pub fn markdown(summaries: &[Summary]) -> String {
    let mut t = String::new();
    t.push_str(
        "| family | k (px) | slack median f32 / f64 (px) | slack max f32 / f64 (px) | holds f32 / f64 | \
         false + mean / max, f32 | false + mean / max, f64 | false − mean / max, f32 | \
         false − mean / max, f64 | f32 vs f64: winner ≠ (px) mean / max; shade max | unpaired, cracks, double hits f32; f64 | \
         failures | ms per render f32 / f64 |\n",
    );
    t.push_str("|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for pair in summaries.chunks(2) {
        let [a, b] = pair else { continue };
        let (s32, s64) = if a.datapath == Datapath::F32 {
            (a, b)
        } else {
            (b, a)
        };
        let holds =
            |s: &Summary| format!("{}/{}", (s.holds_frac * s.drawn as f64).round(), s.drawn);
        let ms = |s: &Summary| 1e3 * s.render_seconds / s.cases.max(1) as f64;
        let _ = writeln!(
            t,
            "| {} | {} | {} / {} | {} / {} | {} / {} | {} / {} | {} / {} | {} / {} | {} / {} | {:.2} / {}; {} | {}, {}, {}; {}, {}, {} | {} | {:.1} / {:.1} |",
            s32.family.name(),
            s32.k_px,
            slack(s32.slack_median_px),
            slack(s64.slack_median_px),
            slack(s32.slack_max_px),
            slack(s64.slack_max_px),
            holds(s32),
            holds(s64),
            frac(s32.false_positive_frac_mean),
            frac(s32.false_positive_frac_max),
            frac(s64.false_positive_frac_mean),
            frac(s64.false_positive_frac_max),
            frac(s32.false_negative_frac_mean),
            frac(s32.false_negative_frac_max),
            frac(s64.false_negative_frac_mean),
            frac(s64.false_negative_frac_max),
            s32.winner_diff_vs_f64_px_mean,
            s32.winner_diff_vs_f64_px_max,
            s32.shade_diff_vs_f64_max,
            s32.unpaired_roots,
            s32.crack_pixels,
            s32.double_hit_pixels,
            s64.unpaired_roots,
            s64.crack_pixels,
            s64.double_hit_pixels,
            s32.failures + s64.failures,
            ms(s32),
            ms(s64),
        );
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splitmix64_matches_the_reference_sequence() {
        // The first outputs for seed 1234567 of the reference C implementation
        // (Vigna, splitmix64.c).
        let mut g = SplitMix64::new(1234567);
        assert_eq!(g.next_u64(), 6457827717110365317);
        assert_eq!(g.next_u64(), 3203168211198807973);
    }

    #[test]
    fn case_is_a_function_of_seed_family_and_index() {
        for family in FAMILIES {
            let a = case(family, 7, 3);
            assert_eq!(a.scene_json, case(family, 7, 3).scene_json);
            assert_ne!(a.scene_json, case(family, 7, 4).scene_json);
            assert_ne!(a.scene_json, case(family, 8, 3).scene_json);
        }
    }

    #[test]
    fn every_family_draws_a_valid_scene_of_two_lembos_sharing_an_edge() {
        for family in FAMILIES {
            for index in 0..4 {
                let c = case(family, 1, index);
                let scene = Scene::from_json(&c.scene_json, "test", Path::new("."))
                    .unwrap_or_else(|e| panic!("{} {index}: {e}", family.name()));
                let lembos: Vec<_> = scene.lembos().map(|(l, _)| l.clone()).collect();
                assert_eq!(lembos.len(), 2);
                // Edge BC of the first is edge AB of the second, reversed: P1P2 and its
                // middle, with their normals.
                let (a, b) = (&lembos[0].points, &lembos[1].points);
                assert_eq!((a[1], a[2], a[5]), (b[1], b[0], b[3]));
                let (a, b) = (&lembos[0].normals, &lembos[1].normals);
                assert_eq!((a[1], a[2], a[5]), (b[1], b[0], b[3]));
            }
        }
    }

    #[test]
    fn far_cases_are_the_ordinary_cases_translated() {
        let ordinary = Scene::from_json(
            &case(Family::Ordinary, 5, 2).scene_json,
            "t",
            Path::new("."),
        )
        .unwrap();
        let far =
            Scene::from_json(&case(Family::Far1e3, 5, 2).scene_json, "t", Path::new(".")).unwrap();
        let (o, f) = (
            &ordinary.objects[0].lembos.get(0),
            &far.objects[0].lembos.get(0),
        );
        let shift = f.points[0] - o.points[0];
        assert!((shift.length() - 1e3).abs() < 1e-9, "{shift}");
        for (p, q) in o.points.iter().zip(&f.points) {
            assert!((*q - *p - shift).length() < 1e-9);
        }
        assert_eq!(o.normals, f.normals);
    }

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(&[]), None);
        assert_eq!(median(&[1.0, 2.0, 9.0]), Some(2.0));
        assert_eq!(median(&[1.0, 2.0, 4.0, 9.0]), Some(3.0));
    }
}
