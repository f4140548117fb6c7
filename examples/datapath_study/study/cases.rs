//! The study's cases: the families, and each case drawn from (seed, family, index).

use glam::{DVec2, DVec3};
use lembo_sim::lembo::Lembo;
use lembo_sim::testkit::SplitMix64;
use serde::Serialize;
use serde_json::json;

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

#[cfg(test)]
mod tests {
    use super::*;
    use lembo_sim::scene::Scene;
    use std::path::Path;

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
}
