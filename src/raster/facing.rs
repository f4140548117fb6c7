//! Back-face culling of a lembo (DESIGN.md §5, "Back-face culling"): MinMax drops a lembo
//! (or a piece of a split one) whose whole surface faces away from the eye, by a test that
//! never drops one any point of which faces the eye.
//!
//! The surface P(u, v) is quadratic over the domain triangle, its geometric normal
//! G = P_u x P_v quadratic too, and which side the eye sees at a point is the sign of the
//! *facing function* f = (P - eye) · G (perspective; an orthographic view's rays all run
//! along `forward`, so there f = forward · G): with G turned to the front (the side the
//! mesh's winding says, [`Winding`]), f > 0 where the eye sees the back. f is a polynomial
//! of degree 4 (2 orthographically) over the triangle; written in the Bernstein basis of
//! the triangle its value at every point is a convex combination of its coefficients, so
//! when every coefficient is above a margin, f is above it everywhere: the whole patch
//! faces away. The test is exact in that direction only (a patch whose coefficients
//! straddle 0 may still face away everywhere; it is drawn).
//!
//! The arithmetic is the datapath word's, charged to the unit that runs it (MinMax): the
//! Bernstein points of P - eye, the six of G (nine cross products), the fifteen
//! coefficients of f (36 dot products of a point and a normal, scaled Bernstein form, so no
//! divide), the margin and fifteen compares. The margin, [`MARGIN`] of a bound on the
//! terms' size, covers the datapath's rounding and the position function's rounding to it
//! many times over.

use super::screen::ScreenLembo;
use crate::camera::{Culling, View, Winding};
use crate::datapath::Real;
use crate::lembo::Quadratic3;

/// The relative margin a coefficient of the facing function must clear, of the bound
/// ‖P - eye‖ ‖P_u‖ ‖P_v‖ on its terms (sums of absolute coefficients): 2^-12, about 4000
/// times an f32 rounding, where the test does about 40 roundings in a row.
pub const MARGIN: f64 = 1.0 / 4096.0;

/// The multi-indices (powers of w = 1 - u - v, u, v) of the quadratic Bernstein basis in the
/// order the test keeps its points: A, B, C (the corners), then AB, AC, BC.
const QUADRATIC: [[usize; 3]; 6] = [
    [2, 0, 0],
    [0, 2, 0],
    [0, 0, 2],
    [1, 1, 0],
    [1, 0, 1],
    [0, 1, 1],
];

/// Whether lembo (or piece) `l` faces away from the eye of `view` over its whole surface,
/// with the front the side `view.culling` says; false when the view culls nothing.
pub fn faces_away<R: Real>(l: &ScreenLembo<R>, view: &View) -> bool {
    let Culling::Back { front } = view.culling else {
        return false;
    };
    // A piece's (u, v) runs over a sub-triangle of the lembo's domain, whose corners may
    // be in the other order: its P_u x P_v is then the lembo's turned over. (The split
    // knows the order; hardware carries it with the piece as a bit.)
    let flipped = l.domain.is_some_and(|[a, b, c]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) < 0.0
    });
    let front_is_g = (front == Winding::Ccw) != flipped;
    away(&l.position, view, front_is_g)
}

/// Whether the surface `p` (world-space quadratics over the domain triangle) faces away
/// from the eye of `view` everywhere, the front being the side of P_u x P_v when
/// `front_is_g`, else the other: every Bernstein coefficient of the facing function,
/// turned to the back, clears [`MARGIN`].
pub fn away<R: Real>(p: &Quadratic3<R>, view: &View, front_is_g: bool) -> bool {
    let two = R::of(2.0);
    // P_u and P_v at the corners A (0, 0), B (1, 0), C (0, 1): they are linear.
    let pu: [[R; 3]; 3] = [
        p.map(|q| q.d),
        p.map(|q| two * q.a + q.d),
        p.map(|q| q.c + q.d),
    ];
    let pv: [[R; 3]; 3] = [
        p.map(|q| q.e),
        p.map(|q| q.c + q.e),
        p.map(|q| two * q.b + q.e),
    ];
    // G's scaled Bernstein points (each times its multinomial weight, so that products
    // add exponents): a corner's G there, an edge's the two mixed cross products.
    let g: [[R; 3]; 6] = [
        cross(pu[0], pv[0]),
        cross(pu[1], pv[1]),
        cross(pu[2], pv[2]),
        add(cross(pu[0], pv[1]), cross(pu[1], pv[0])),
        add(cross(pu[0], pv[2]), cross(pu[2], pv[0])),
        add(cross(pu[1], pv[2]), cross(pu[2], pv[1])),
    ];
    // The bound on the terms: every Bernstein point of P is within the sum of |coefficients|
    // of the origin, and every P_u, P_v within twice the sum of the non-constant ones.
    let abs_sum = |f: &dyn Fn(&crate::lembo::Quadratic<R>) -> R| {
        p.iter().map(f).fold(R::zero(), |s, x| s + x)
    };
    let slope = abs_sum(&|q| q.a.abs() + q.b.abs() + q.c.abs() + q.d.abs() + q.e.abs());
    let g_bound = two * slope * two * slope;
    let back = |c: R| if front_is_g { c } else { -c };
    if view.orthographic {
        // f = forward · G, degree 2: coefficient β is g[β] / C(2; β).
        let d = view.forward.to_array().map(R::of);
        let bound = d.iter().fold(R::zero(), |s, x| s + x.abs()) * g_bound * R::of(MARGIN);
        return g
            .iter()
            .zip(QUADRATIC)
            .all(|(g, beta)| back(dot(d, *g)) > bound * R::of(multinomial(beta)));
    }
    // P - eye's scaled Bernstein points: A, B, C, then twice the edge points.
    let eye = view.eye.to_array().map(R::of);
    let q0 = sub(p.map(|q| q.f), eye);
    let q: [[R; 3]; 6] = [
        q0,
        add(q0, p.map(|q| q.a + q.d)),
        add(q0, p.map(|q| q.b + q.e)),
        add(add(q0, q0), p.map(|q| q.d)),
        add(add(q0, q0), p.map(|q| q.e)),
        add(add(q0, q0), p.map(|q| q.c + q.d + q.e)),
    ];
    let p_bound =
        abs_sum(&|q| q.a.abs() + q.b.abs() + q.c.abs() + q.d.abs() + q.e.abs() + q.f.abs())
            + eye.iter().fold(R::zero(), |s, x| s + x.abs());
    let bound = p_bound * g_bound * R::of(MARGIN);
    // f's fifteen scaled coefficients, by the power of w and of u (that of v is the rest).
    let mut f: [[Option<R>; 5]; 5] = [[None; 5]; 5];
    for (qa, alpha) in q.iter().zip(QUADRATIC) {
        for (gb, beta) in g.iter().zip(QUADRATIC) {
            let term = dot(*qa, *gb);
            let at = &mut f[alpha[0] + beta[0]][alpha[1] + beta[1]];
            *at = Some(at.map_or(term, |s| s + term));
        }
    }
    (0..5).all(|i| {
        (0..5 - i).all(|j| {
            let c = f[i][j].expect("every degree-4 index is a sum of two quadratic ones");
            back(c) > bound * R::of(multinomial([i, j, 4 - i - j]))
        })
    })
}

/// n! / (i! j! k!) for the multi-index (i, j, k) of total degree n.
fn multinomial(alpha: [usize; 3]) -> f64 {
    let fact = |n: usize| (1..=n).product::<usize>() as f64;
    fact(alpha.iter().sum()) / alpha.iter().map(|&k| fact(k)).product::<f64>()
}

fn cross<R: Real>(a: [R; 3], b: [R; 3]) -> [R; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn add<R: Real>(a: [R; 3], b: [R; 3]) -> [R; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn sub<R: Real>(a: [R; 3], b: [R; 3]) -> [R; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot<R: Real>(a: [R; 3], b: [R; 3]) -> R {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Camera, Projection, Viewport};
    use crate::lembo::Lembo;
    use glam::DVec3;

    /// The facing function (P - eye) · (P_u x P_v), or forward · (P_u x P_v) for an
    /// orthographic view, of `l` at (u, v), in f64, with the size of its two factors.
    fn facing_at(l: &Lembo, view: &View, u: f64, v: f64) -> (f64, f64) {
        let p = DVec3::from_array(l.position.map(|q| q.eval(u, v)));
        let (pu, pv) = (
            DVec3::from_array(l.position.map(|q| q.grad(u, v).0)),
            DVec3::from_array(l.position.map(|q| q.grad(u, v).1)),
        );
        let g = pu.cross(pv);
        let to = if view.orthographic {
            view.forward
        } else {
            p - view.eye
        };
        (to.dot(g), to.length() * g.length())
    }

    /// A random lembo: a triangle in the unit box, its edge points off the chords by up to
    /// `bulge` of the edge's length.
    fn random_lembo(rng: &mut crate::testkit::SplitMix64, bulge: f64) -> Lembo {
        let mut r3 = |s: f64| {
            if s == 0.0 {
                return DVec3::ZERO;
            }
            DVec3::new(rng.range(-s, s), rng.range(-s, s), rng.range(-s, s))
        };
        let (a, b, c) = (r3(1.0), r3(1.0), r3(1.0));
        let mut mid = |p: DVec3, q: DVec3| 0.5 * (p + q) + (p - q).length() * r3(bulge);
        let (d, e, f) = (mid(a, b), mid(a, c), mid(b, c));
        Lembo::new([a, b, c, d, e, f], [DVec3::Z; 6])
    }

    /// A view of the point `at` from `eye`, perspective or orthographic.
    fn view_from(eye: DVec3, at: DVec3, orthographic: bool) -> View {
        let up = if (eye - at).cross(DVec3::Y).length() > 1e-6 * (eye - at).length() {
            DVec3::Y
        } else {
            DVec3::X
        };
        let projection = if orthographic {
            Projection::Orthographic {
                height: 4.0,
                near: -100.0,
                far: 100.0,
            }
        } else {
            Projection::Perspective {
                fovy_deg: 60.0,
                near: 1e-3,
                far: 1e3,
            }
        };
        View::new(
            &Camera {
                eye: eye.to_array(),
                target: at.to_array(),
                up: up.to_array(),
                projection,
            },
            Viewport {
                width: 256,
                height: 256,
            },
        )
    }

    /// The test never culls a patch that has a point facing the eye: over 40 000 random
    /// lembos (flat, nearly flat, curved and strongly curved) and views (far, close to the
    /// surface, grazing along its plane, orthographic), each side taken as the front, in
    /// both datapaths, dense sampling of every culled patch finds the facing function on
    /// the back side at every point. And it is no "never cull": it culls most flat and
    /// nearly flat patches that face clearly away (every sample's cosine beyond 0.05), and
    /// a share of curved ones.
    #[test]
    fn back_face_test_is_conservative_and_culls_what_clearly_faces_away() {
        let mut rng = crate::testkit::SplitMix64::new(48);
        let n = 40;
        let lattice: Vec<(f64, f64)> = (0..=n)
            .flat_map(|i| (0..=n - i).map(move |j| (i as f64 / n as f64, j as f64 / n as f64)))
            .collect();
        let (mut culled, mut clearly, mut clearly_culled) = ([0usize; 4], [0usize; 4], [0usize; 4]);
        for case in 0..40_000 {
            let kind = case % 4;
            let bulge = [0.0, 0.01, 0.2, 0.6][kind];
            let l = random_lembo(&mut rng, bulge);
            let centre = DVec3::from_array(l.position.map(|q| q.eval(1.0 / 3.0, 1.0 / 3.0)));
            let normal = (l.points[1] - l.points[0]).cross(l.points[2] - l.points[0]);
            let mut dir = DVec3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            )
            .normalize_or(DVec3::X);
            if case % 5 == 0 {
                // Grazing: nearly in the patch's plane.
                dir = (dir - dir.dot(normal) / normal.length_squared() * normal
                    + rng.range(-0.02, 0.02) * normal.normalize_or_zero())
                .normalize_or(DVec3::X);
            }
            let distance = 10f64.powf(rng.range(-1.5, 1.7));
            let orthographic = case % 7 == 0;
            let view = view_from(centre + distance * dir, centre, orthographic);
            let samples: Vec<(f64, f64)> = lattice
                .iter()
                .map(|&(u, v)| facing_at(&l, &view, u, v))
                .collect();
            for front_is_g in [true, false] {
                let side = |f: f64| if front_is_g { f } else { -f };
                let f32_culls = away(&l.position.map(|q| q.cast::<f32>()), &view, front_is_g);
                let f64_culls = away(&l.position, &view, front_is_g);
                for (dp, culls) in [("f32", f32_culls), ("f64", f64_culls)] {
                    if culls {
                        let worst = samples.iter().map(|s| side(s.0)).fold(f64::MAX, f64::min);
                        assert!(
                            worst > 0.0,
                            "case {case} ({dp}, front is G: {front_is_g}): culled, but a \
                             point faces the eye ({worst:e}); {l:?} {view:?}"
                        );
                    }
                }
                culled[kind] += f32_culls as usize;
                let clear = samples.iter().all(|&(f, size)| side(f) > 0.05 * size);
                clearly[kind] += clear as usize;
                clearly_culled[kind] += (clear && f32_culls) as usize;
            }
        }
        eprintln!(
            "culled {culled:?}, clearly away {clearly:?}, of those culled {clearly_culled:?}"
        );
        // Measured: 91 % of the flat, 87 % of the nearly flat, 34 % of the curved and
        // almost none of the strongly curved (edge points off their chords by up to 0.6 of
        // the edge): the Bernstein coefficients of a strongly curved patch's facing
        // function straddle 0 long after its values stop doing so.
        for kind in 0..4 {
            assert!(clearly[kind] > 250, "{clearly:?}");
            let share = clearly_culled[kind] as f64 / clearly[kind] as f64;
            let want = [0.85, 0.8, 0.25, 0.0][kind];
            assert!(share >= want, "kind {kind}: {share} of {clearly:?}");
        }
    }
}
