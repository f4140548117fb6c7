//! What a pixel shows, and which way it faces: the questions [`super::see_through`] and
//! [`super::leak`] both ask of a render.
//!
//! A pixel shows a primitive ([`Shown`]: its id, window depth and stored normal); the id
//! names a surface through [`Drawn`] (a lembo on the lembo path and in the reference, a
//! triangle of a tessellation on the triangle path). The pixel shows a *back face* when its
//! stored normal faces away from the pixel's ray and the drawn surface itself does too: the
//! shading normal alone does not say so, since across a crease a lembo's normal function
//! leans up to half the crease angle away from its surface, so a face seen at a grazing
//! angle can have its front to the eye and its shading normal turned away (a rock
//! auto-smoothed at 40 degrees counted up to 313 such pixels at 512x512, `rock_creased` 97).

use super::oracle::{intersect_ray, LemboSource};
use crate::camera::View;
use crate::lembo::set::LastParent;
use crate::lembo::tessellate::Tessellation;
use crate::lembo::Lembo;
use crate::rop::framebuffer::{FrameBuffer, NO_PRIMITIVE};
use glam::{DVec2, DVec3};

/// What a pixel shows: the winning primitive, its window depth and its stored normal.
#[derive(Clone, Copy, Debug)]
pub(super) struct Shown {
    /// The winning primitive's id, or [`NO_PRIMITIVE`] for the background.
    pub winner: u32,
    /// Its window depth.
    pub depth: f64,
    /// Its stored normal.
    pub normal: DVec3,
}

impl Shown {
    /// What pixel `k` of `render` shows; `normals` is its normal buffer.
    pub fn of_render(render: &FrameBuffer, normals: &[[f32; 3]], k: usize) -> Shown {
        Shown {
            winner: render.primitive[k],
            depth: f64::from(render.depth[k]),
            normal: DVec3::from_array(normals[k].map(f64::from)),
        }
    }

    /// Whether the background shows.
    pub fn is_background(&self) -> bool {
        self.winner == NO_PRIMITIVE
    }
}

/// How a render's primitive ids name the surfaces it drew: `ids_per_lembo` ids a lembo
/// (1 on the lembo path, n² on the triangle path at tessellation level n, where id / n² is
/// the lembo) and, on the triangle path, the tessellation whose triangles were drawn.
#[derive(Clone, Copy)]
pub struct Drawn<'a> {
    /// Primitive ids a lembo.
    pub ids_per_lembo: u64,
    /// The triangles drawn, on the triangle path.
    pub triangles: Option<&'a Tessellation<'a>>,
}

impl Drawn<'_> {
    /// Lembos drawn as themselves, one id each: the lembo path.
    pub const EXACT: Drawn<'static> = Drawn {
        ids_per_lembo: 1,
        triangles: None,
    };

    /// The lembo primitive `winner` belongs to.
    pub(super) fn lembo_of(&self, winner: u32) -> u64 {
        u64::from(winner) / self.ids_per_lembo.max(1)
    }

    /// Whether `shown` (not the background) is a back face at the pixel whose ray is
    /// `origin + t dir`: its stored normal faces away from the ray, and so does the surface
    /// drawn there (the winning triangle's plane turned to the side of its vertex normals,
    /// else the winning lembo's own surface, [`surface_faces`]).
    pub(super) fn back_face(
        &self,
        shown: &Shown,
        origin: DVec3,
        dir: DVec3,
        made: &mut Made,
    ) -> bool {
        if shown.normal.dot(-dir) >= 0.0 {
            return false;
        }
        let surface_to_eye = match self.triangles {
            Some(t) if u64::from(shown.winner) < t.len() => {
                let tri = t.triangle(u64::from(shown.winner));
                oriented_normal(tri.positions, tri.normals).dot(-dir) > 0.0
            }
            _ => made
                .get(self.lembo_of(shown.winner))
                .is_some_and(|l| surface_faces(l, origin, dir)),
        };
        !surface_to_eye
    }
}

/// A flat triangle's geometric normal turned to the side of the sum of its vertex normals.
pub(super) fn oriented_normal([a, b, c]: [DVec3; 3], normals: [DVec3; 3]) -> DVec3 {
    let n = (b - a).cross(c - a);
    if n.dot(normals[0] + normals[1] + normals[2]) < 0.0 {
        -n
    } else {
        n
    }
}

/// How far a lembo strays from its flat triangle on screen \[pixels\]: 4/3 of the largest
/// screen offset of an edge midpoint from its chord's middle. With barycentrics (w, u, v)
/// the patch is its triangle plus 4 (wu e_AB + wv e_CA + uv e_BC), e the midpoint offsets,
/// and wu + wv + uv <= 1/3.
pub(super) fn screen_deviation(l: &Lembo, view: &View) -> f64 {
    [(0, 1, 3), (1, 2, 5), (2, 0, 4)]
        .into_iter()
        .map(|(a, b, m)| {
            let chord = view.project(0.5 * (l.points[a] + l.points[b]));
            let mid = view.project(l.points[m]);
            DVec2::new(mid.x - chord.x, mid.y - chord.y).length()
        })
        .fold(0.0, f64::max)
        * (4.0 / 3.0)
}

/// Whether two lembos' corner triangles share a corner position (bit for bit).
pub(super) fn share_a_corner(a: &Lembo, b: &Lembo) -> bool {
    let corners = |l: &Lembo| [l.points[0], l.points[1], l.points[2]];
    corners_share(&corners(a), &corners(b))
}

/// Whether two corner triangles share a corner position (bit for bit).
pub(super) fn corners_share(a: &[DVec3; 3], b: &[DVec3; 3]) -> bool {
    let bits = |p: DVec3| p.to_array().map(f64::to_bits);
    a.iter().any(|p| b.iter().any(|q| bits(*p) == bits(*q)))
}

/// Whether the surface of `lembo` at domain point (u, v) faces a ray of direction `dir`:
/// its geometric normal (the position's partial derivatives crossed), turned to the side
/// of the lembo's normal function there, against the ray. False where the normal is
/// degenerate.
pub(super) fn faces_at(lembo: &Lembo, u: f64, v: f64, dir: DVec3) -> bool {
    let (pu, pv) = lembo.position_derivatives(u, v);
    let geometric = pu.cross(pv);
    let side = lembo.normal_at(u, v);
    let outward = if geometric.dot(side) < 0.0 {
        -geometric
    } else {
        geometric
    };
    outward.dot(-dir) > 0.0
}

/// Whether the surface of `lembo` nearest along the ray `origin + t dir` (t > 0) faces
/// the ray's origin ([`faces_at`]). Where the exact solve misses the lembo (a pixel the
/// render covers along the lembo's border, the f64 ray just outside its domain), the
/// border point nearest the ray stands for it.
pub(super) fn surface_faces(lembo: &Lembo, origin: DVec3, dir: DVec3) -> bool {
    let (u, v) = match intersect_ray(lembo, origin, dir)
        .iter()
        .find(|&&(t, _, _)| t > 0.0)
    {
        Some(&(_, u, v)) => (u, v),
        None => border_point_nearest(lembo, origin, dir),
    };
    faces_at(lembo, u, v, dir)
}

/// The domain point on the border of `lembo` (its three edges, each at 65 points) whose
/// surface point is nearest the line `origin + t dir`.
fn border_point_nearest(lembo: &Lembo, origin: DVec3, dir: DVec3) -> (f64, f64) {
    const STEPS: u32 = 64;
    let d = dir.normalize_or_zero();
    let distance = |(u, v): (f64, f64)| {
        let p = lembo.position_at(u, v) - origin;
        (p - d * p.dot(d)).length_squared()
    };
    (0..=STEPS)
        .flat_map(|i| {
            let s = i as f64 / STEPS as f64;
            [(s, 0.0), (0.0, s), (s, 1.0 - s)]
        })
        .min_by(|&a, &b| distance(a).total_cmp(&distance(b)))
        .expect("the border has points")
}

/// The last lembo made by id, kept while consecutive pixels ask for it again.
pub(super) struct Made<'a> {
    lembos: &'a dyn LemboSource,
    kept: Option<(u64, Lembo)>,
    last: LastParent,
}

impl<'a> Made<'a> {
    pub fn new(lembos: &'a dyn LemboSource) -> Self {
        Made {
            lembos,
            kept: None,
            last: LastParent::default(),
        }
    }

    /// Lembo `id`, or None beyond the last.
    pub fn get(&mut self, id: u64) -> Option<&Lembo> {
        if id >= self.lembos.len() as u64 {
            return None;
        }
        if self.kept.as_ref().is_none_or(|(k, _)| *k != id) {
            let (l, _) = self.lembos.lembo(id as usize, &mut self.last);
            self.kept = Some((id, l));
        }
        self.kept.as_ref().map(|(_, l)| l)
    }

    /// Lembo `id`'s corners, or None beyond the last: the kept lembo's when it is that one,
    /// else read from the source without making it ([`LemboSource::corners`]).
    pub fn corners(&mut self, id: u64) -> Option<[DVec3; 3]> {
        if id >= self.lembos.len() as u64 {
            return None;
        }
        match &self.kept {
            Some((k, l)) if *k == id => Some([l.points[0], l.points[1], l.points[2]]),
            _ => Some(self.lembos.corners(id as usize, &mut self.last).0),
        }
    }
}

/// What the tests of this module, [`super::see_through`] and [`super::leak`] draw on.
#[cfg(test)]
pub(super) mod fixtures {
    use crate::camera::{Camera, Projection, View, Viewport};
    use crate::lembo::construct::lembo_from_triangle;
    use crate::lembo::Lembo;
    use glam::DVec3;

    /// Orthographic 128 x 128 view down -z: world (X, Y) on screen (X + 64, 64 - Y).
    pub fn view() -> View {
        view_sized(128, 128)
    }

    /// Orthographic `width` x `height` view down -z, one world unit a pixel: world (X, Y)
    /// on screen (X + width / 2, height / 2 - Y).
    pub fn view_sized(width: u32, height: u32) -> View {
        let camera = Camera {
            eye: [0.0, 0.0, 10.0],
            target: [0.0; 3],
            up: [0.0, 1.0, 0.0],
            projection: Projection::Orthographic {
                height: f64::from(height),
                near: 0.1,
                far: 100.0,
            },
        };
        View::new(&camera, Viewport { width, height })
    }

    /// A flat triangle at height z whose normals are `n` (+z faces the eye; wound either
    /// way, since the normals orient it).
    pub fn flat(p: [[f64; 2]; 3], z: f64, n: DVec3) -> Lembo {
        lembo_from_triangle(p.map(|[x, y]| DVec3::new(x, y, z)), [n; 3])
    }

    /// A square of two flat triangles at height 0 facing the eye, sharing its diagonal, on
    /// screen [24, 104]² of [`view`]; the second is wound the other way.
    pub fn square() -> [Lembo; 2] {
        [
            flat([[-40.0, -40.0], [40.0, -40.0], [40.0, 40.0]], 0.0, DVec3::Z),
            flat([[-40.0, -40.0], [-40.0, 40.0], [40.0, 40.0]], 0.0, DVec3::Z),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::fixtures::{flat, view};
    use super::*;
    use crate::lembo::construct::lembo_from_triangle;

    /// The surface's own facing: its geometric normal on the side of its normal function,
    /// at the ray's first hit, or at the border point nearest a ray that misses it.
    #[test]
    fn surface_faces_asks_the_surface_not_its_shading_normal() {
        let view = view();
        let (origin, dir) = view.ray(64.5, 64.5);
        let up = flat([[-10.0, -10.0], [10.0, -10.0], [0.0, 10.0]], 0.0, DVec3::Z);
        assert!(surface_faces(&up, origin, dir));
        // Normals leaning 80 degrees towards x: the shading normal at the hit still on
        // the eye's side, the surface too.
        let tilted = [DVec3::new(0.98, 0.0, 0.17); 3];
        let leaning = lembo_from_triangle(up.points[..3].try_into().unwrap(), tilted);
        assert!(surface_faces(&leaning, origin, dir));
        // Normals past 90 degrees: the lembo says its outside is the other side.
        let down = lembo_from_triangle(up.points[..3].try_into().unwrap(), [-DVec3::Z; 3]);
        assert!(!surface_faces(&down, origin, dir));
        // A ray just outside the triangle: its nearest border point decides.
        let (o2, d2) = view.ray(64.5 + 11.0, 64.5);
        assert!(intersect_ray(&up, o2, d2).is_empty());
        assert!(surface_faces(&up, o2, d2));
        assert!(!surface_faces(&down, o2, d2));
    }

    /// A back face needs both the stored normal and the drawn surface turned away.
    #[test]
    fn a_back_face_is_a_turned_normal_on_a_turned_surface() {
        let view = view();
        let (origin, dir) = view.ray(64.5, 64.5);
        let up = flat([[-10.0, -10.0], [10.0, -10.0], [0.0, 10.0]], 0.0, DVec3::Z);
        let down = lembo_from_triangle(up.points[..3].try_into().unwrap(), [-DVec3::Z; 3]);
        let lembos: Vec<(&Lembo, bool)> = vec![(&up, true), (&down, true)];
        let mut made = Made::new(&lembos);
        let shown = |winner: u32, normal: DVec3| Shown {
            winner,
            depth: 0.5,
            normal,
        };
        let exact = Drawn::EXACT;
        assert!(!exact.back_face(&shown(0, DVec3::Z), origin, dir, &mut made));
        assert!(!exact.back_face(&shown(0, -DVec3::Z), origin, dir, &mut made));
        assert!(!exact.back_face(&shown(1, DVec3::Z), origin, dir, &mut made));
        assert!(exact.back_face(&shown(1, -DVec3::Z), origin, dir, &mut made));
        // Ids of the triangle path: n² a lembo.
        let four = Drawn {
            ids_per_lembo: 4,
            triangles: None,
        };
        assert!(four.back_face(&shown(7, -DVec3::Z), origin, dir, &mut made));
        assert!(!four.back_face(&shown(3, -DVec3::Z), origin, dir, &mut made));
    }
}
