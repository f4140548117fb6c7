//! The lembo model (Martinelli 2006, section 2).
//!
//! A lembo is a quadratic triangular patch on the fixed domain `u >= 0, v >= 0, u + v <= 1`
//! with a separate quadratic normal function on the same domain:
//!
//! ```text
//!   q(u, v) = a u² + b v² + c uv + d u + e v + f        (one per coordinate)
//!
//!   v
//!   1 C
//!     | \            reference points of the domain:
//!   ½ E   F          A(0,0) B(1,0) C(0,1) D(½,0) E(0,½) F(½,½)
//!     |     \
//!   0 A---D---B u
//! ```
//!
//! The six coefficients of each coordinate come from the values at the six reference points
//! through the paper's linear transform ([`Quadratic::from_reference_values`]); the inverse
//! is plain evaluation at the reference points ([`Quadratic::reference_values`]).

pub mod construct;
pub mod lattice;
pub mod set;
pub mod shapes;
pub mod tessellate;

use crate::datapath::Real;
use glam::DVec3;

/// Bytes of one lembo as it is stored in memory and fetched for Setup: six points and six
/// normals in f32; the default of the architecture's `fetch.bytes_per_lembo`, which the
/// counts use (a curved discoid's record is this and its extra fields, whatever the
/// architecture says).
pub const LEMBO_BYTES: u64 = 6 * 2 * 3 * 4;

/// The six reference points of the domain, in the paper's order A, B, C, D, E, F.
pub const REFERENCE_UV: [(f64, f64); 6] = [
    (0.0, 0.0),
    (1.0, 0.0),
    (0.0, 1.0),
    (0.5, 0.0),
    (0.0, 0.5),
    (0.5, 0.5),
];

/// A scalar quadratic `a u² + b v² + c uv + d u + e v + f` in the paper's coefficient names.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Quadratic<R> {
    /// Coefficient of u².
    pub a: R,
    /// Coefficient of v².
    pub b: R,
    /// Coefficient of uv.
    pub c: R,
    /// Coefficient of u.
    pub d: R,
    /// Coefficient of v.
    pub e: R,
    /// The constant term.
    pub f: R,
}

impl<R: Real> Quadratic<R> {
    /// The paper's transform: coefficients from the values at A, B, C, D, E, F.
    pub fn from_reference_values(p: [R; 6]) -> Self {
        let [a_, b_, c_, d_, e_, f_] = p;
        let two = R::of(2.0);
        let four = R::of(4.0);
        let f = a_;
        let e = four * (e_ - a_) - (c_ - a_);
        let d = four * (d_ - a_) - (b_ - a_);
        let b = c_ - a_ - e;
        let a = b_ - a_ - d;
        let c = four * f_ - a - b - two * d - two * e - four * a_;
        Quadratic { a, b, c, d, e, f }
    }

    /// The inverse transform: the values at A, B, C, D, E, F.
    pub fn reference_values(&self) -> [R; 6] {
        REFERENCE_UV.map(|(u, v)| self.eval(R::of(u), R::of(v)))
    }

    /// The value at (u, v).
    #[inline(always)]
    pub fn eval(&self, u: R, v: R) -> R {
        // Horner form: (a u + c v + d) u + (b v + e) v + f.
        (self.a * u + self.c * v + self.d) * u + (self.b * v + self.e) * v + self.f
    }

    /// The gradient (∂q/∂u, ∂q/∂v).
    #[inline(always)]
    pub fn grad(&self, u: R, v: R) -> (R, R) {
        let two = R::of(2.0);
        (
            two * self.a * u + self.c * v + self.d,
            two * self.b * v + self.c * u + self.e,
        )
    }

    /// The (constant) Hessian as (q_uu, q_uv, q_vv).
    #[inline(always)]
    pub fn hessian(&self) -> (R, R, R) {
        let two = R::of(2.0);
        (two * self.a, self.c, two * self.b)
    }

    /// The same quadratic in another datapath.
    pub fn cast<S: Real>(&self) -> Quadratic<S> {
        Quadratic {
            a: S::of(self.a.f64()),
            b: S::of(self.b.f64()),
            c: S::of(self.c.f64()),
            d: S::of(self.d.f64()),
            e: S::of(self.e.f64()),
            f: S::of(self.f.f64()),
        }
    }

    /// The largest absolute coefficient, a scale for relative tolerances.
    pub fn magnitude(&self) -> R {
        self.a
            .abs()
            .max(self.b.abs())
            .max(self.c.abs())
            .max(self.d.abs())
            .max(self.e.abs())
            .max(self.f.abs())
    }
}

/// Three quadratics, one per coordinate of a vector function.
pub type Quadratic3<R> = [Quadratic<R>; 3];

/// Builds the three coordinate quadratics from six vectors.
pub fn quadratic3_from(values: &[DVec3; 6]) -> Quadratic3<f64> {
    [0, 1, 2].map(|k| Quadratic::from_reference_values(values.map(|p| p[k])))
}

/// Evaluates a vector quadratic.
#[inline(always)]
pub fn eval3<R: Real>(q: &Quadratic3<R>, u: R, v: R) -> [R; 3] {
    [q[0].eval(u, v), q[1].eval(u, v), q[2].eval(u, v)]
}

/// A lembo in world space: the six construction points and normals (the modelling data a
/// scene stores) and the position and normal functions built from them.
#[derive(Clone, Debug, PartialEq)]
pub struct Lembo {
    /// Construction points A', B', C', D', E', F' [world units].
    pub points: [DVec3; 6],
    /// Construction normals at the same points (not necessarily unit length).
    pub normals: [DVec3; 6],
    /// Position function b(u, v), one quadratic per coordinate.
    pub position: Quadratic3<f64>,
    /// Normal function n(u, v), one quadratic per coordinate (normalise before use).
    pub normal: Quadratic3<f64>,
}

impl Lembo {
    /// Builds a lembo from its six construction points and normals (Martinelli 2006, section 2).
    pub fn new(points: [DVec3; 6], normals: [DVec3; 6]) -> Self {
        Lembo {
            position: quadratic3_from(&points),
            normal: quadratic3_from(&normals),
            points,
            normals,
        }
    }

    /// Position b(u, v).
    pub fn position_at(&self, u: f64, v: f64) -> DVec3 {
        DVec3::from_array(eval3(&self.position, u, v))
    }

    /// The normal function n(u, v), not normalised.
    pub fn normal_at(&self, u: f64, v: f64) -> DVec3 {
        DVec3::from_array(eval3(&self.normal, u, v))
    }

    /// The unit normal n(u, v) / |n(u, v)|, or zero where the normal function vanishes.
    pub fn unit_normal_at(&self, u: f64, v: f64) -> DVec3 {
        self.normal_at(u, v).normalize_or_zero()
    }

    /// Partial derivatives (∂b/∂u, ∂b/∂v) of the position.
    pub fn position_derivatives(&self, u: f64, v: f64) -> (DVec3, DVec3) {
        let g = self.position.map(|q| q.grad(u, v));
        (
            DVec3::new(g[0].0, g[1].0, g[2].0),
            DVec3::new(g[0].1, g[1].1, g[2].1),
        )
    }

    /// Second derivatives (b_uu, b_uv, b_vv) of the position (constant over the patch).
    pub fn position_second_derivatives(&self) -> (DVec3, DVec3, DVec3) {
        let h = self.position.map(|q| q.hessian());
        (
            DVec3::new(h[0].0, h[1].0, h[2].0),
            DVec3::new(h[0].1, h[1].1, h[2].1),
            DVec3::new(h[0].2, h[1].2, h[2].2),
        )
    }

    /// Control points of the equivalent quadratic Bézier triangle, in the order
    /// A, B, C, then the edge controls of AB, AC, BC. The patch lies in their convex hull,
    /// which makes them a conservative bound for culling.
    pub fn bezier_control_points(&self) -> [DVec3; 6] {
        bezier_controls(&self.points)
    }

    /// Whether every number in the lembo is finite.
    pub fn is_finite(&self) -> bool {
        self.points
            .iter()
            .chain(self.normals.iter())
            .all(|p| p.is_finite())
    }
}

/// Bézier control net of a quadratic triangle given by its six reference values
/// (corners, then the edge controls of AB, AC, BC: `2 mid - (end0 + end1) / 2`).
pub fn bezier_controls(p: &[DVec3; 6]) -> [DVec3; 6] {
    [
        p[0],
        p[1],
        p[2],
        2.0 * p[3] - 0.5 * (p[0] + p[1]),
        2.0 * p[4] - 0.5 * (p[0] + p[2]),
        2.0 * p[5] - 0.5 * (p[1] + p[2]),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample_lembo() -> Lembo {
        let pts = [
            DVec3::new(0.1, -0.3, 0.7),
            DVec3::new(1.3, 0.2, -0.4),
            DVec3::new(-0.2, 1.1, 0.3),
            DVec3::new(0.8, -0.1, 0.5),
            DVec3::new(-0.1, 0.4, 0.9),
            DVec3::new(0.6, 0.8, 0.2),
        ];
        let nrm = pts.map(|p| (p + DVec3::new(0.1, 0.2, 1.5)).normalize());
        Lembo::new(pts, nrm)
    }

    #[test]
    fn six_point_construction_round_trips_points_and_normals() {
        let l = sample_lembo();
        for (k, &(u, v)) in REFERENCE_UV.iter().enumerate() {
            assert!(
                (l.position_at(u, v) - l.points[k]).length() < 1e-14,
                "point {k}"
            );
            assert!(
                (l.normal_at(u, v) - l.normals[k]).length() < 1e-14,
                "normal {k}"
            );
        }
    }

    #[test]
    fn forward_and_inverse_transform_are_inverse() {
        let q = Quadratic::<f64> {
            a: 1.5,
            b: -2.0,
            c: 0.25,
            d: 3.0,
            e: -0.5,
            f: 7.0,
        };
        let back = Quadratic::from_reference_values(q.reference_values());
        for (x, y) in [
            (q.a, back.a),
            (q.b, back.b),
            (q.c, back.c),
            (q.d, back.d),
            (q.e, back.e),
            (q.f, back.f),
        ] {
            assert!((x - y).abs() < 1e-12);
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let l = sample_lembo();
        let (bu, bv) = l.position_derivatives(0.2, 0.3);
        let h = 1e-6;
        let fu = (l.position_at(0.2 + h, 0.3) - l.position_at(0.2 - h, 0.3)) / (2.0 * h);
        let fv = (l.position_at(0.2, 0.3 + h) - l.position_at(0.2, 0.3 - h)) / (2.0 * h);
        assert!((bu - fu).length() < 1e-8);
        assert!((bv - fv).length() < 1e-8);
    }

    #[test]
    fn bezier_net_reproduces_the_patch() {
        // A quadratic Bézier triangle with this net evaluates to the same surface.
        let l = sample_lembo();
        let n = l.bezier_control_points();
        let (u, v) = (0.3, 0.45);
        let w = 1.0 - u - v;
        let p = n[0] * w * w
            + n[1] * u * u
            + n[2] * v * v
            + n[3] * 2.0 * w * u
            + n[4] * 2.0 * w * v
            + n[5] * 2.0 * u * v;
        assert!((p - l.position_at(u, v)).length() < 1e-13);
    }
}
