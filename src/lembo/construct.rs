//! Construction of lembos from triangles with vertex normals (paper 001, section 2).
//!
//! The edge midpoint comes from the near-least-squares quadratic edge of [Bar00a] as the
//! paper prints it, with two repairs documented in ARCHITECTURE.md:
//! - the printed `T2 = -N1 - N2 (N1·N2)` is not tangent at P2; we use the tangent
//!   `T2 = -N1 + N2 (N1·N2)` (the mirror image of `T1`), which makes the construction
//!   symmetric and reproduces circular arcs' tangents on a sphere;
//! - `alpha * beta` simplifies to `(P·T1)/(T1·T1)` and `alpha' * beta'` to
//!   `(P·T2)/(T2·T2)`, which removes the division by `T1·T2` (zero for perpendicular end
//!   normals); a vanishing tangent (parallel end normals) contributes nothing, so parallel
//!   normals give a straight edge.
//!
//! The edge mid-normal is the PN-triangle mid-normal (the paper: "in the similar way used for
//! PN Triangles"): the average end normal reflected in the plane perpendicular to the edge.
//!
//! Both are computed from the edge's two end points in a canonical order (the smaller
//! position first, compared coordinate by coordinate), so two lembos that share an edge get
//! bit-identical edge points whatever their winding.

use super::Lembo;
use glam::DVec3;
use std::cmp::Ordering;

/// The point and normal in the middle of the curved edge from `p1` (normal `n1`) to `p2`
/// (normal `n2`), computed in a canonical order of the two ends.
pub fn edge_midpoint(p1: DVec3, n1: DVec3, p2: DVec3, n2: DVec3) -> (DVec3, DVec3) {
    if canonical_order(p1, p2) == Ordering::Greater {
        edge_midpoint_ordered(p2, n2, p1, n1)
    } else {
        edge_midpoint_ordered(p1, n1, p2, n2)
    }
}

/// Total order on positions used to make edge computations independent of winding.
pub fn canonical_order(p: DVec3, q: DVec3) -> Ordering {
    p.x.total_cmp(&q.x)
        .then(p.y.total_cmp(&q.y))
        .then(p.z.total_cmp(&q.z))
}

fn edge_midpoint_ordered(p1: DVec3, n1: DVec3, p2: DVec3, n2: DVec3) -> (DVec3, DVec3) {
    let n1 = n1.normalize_or_zero();
    let n2 = n2.normalize_or_zero();
    let p = p2 - p1;
    let c = n1.dot(n2);
    let t1 = n2 - n1 * c;
    let t2 = -n1 + n2 * c;
    // alpha*beta*T1 and alpha'*beta'*T2: the projections of P on the two end tangents.
    let proj = |t: DVec3| {
        let tt = t.dot(t);
        if tt > 1e-24 {
            t * (p.dot(t) / tt)
        } else {
            DVec3::ZERO
        }
    };
    let (a1, a2) = (proj(t1), proj(t2));
    // f(t) = (a2 - a1)/2 t² + (P + (a1 - a2)/2) t + P1, so f(1/2) = P1 + P/2 + (a1 - a2)/8.
    let mid = p1 + 0.5 * p + 0.125 * (a1 - a2);

    let nsum = n1 + n2;
    let pp = p.dot(p);
    let v = if pp > 0.0 {
        2.0 * p.dot(nsum) / pp
    } else {
        0.0
    };
    let nmid = (nsum - v * p).normalize_or_zero();
    // Opposite end normals have no defined mid-normal; fall back to the first end's.
    let nmid = if nmid == DVec3::ZERO { n1 } else { nmid };
    (mid, nmid)
}

/// A lembo through the triangle `p` with vertex normals `n`: A, B, C are the vertices,
/// D, E, F the midpoints of edges AB, AC, BC.
pub fn lembo_from_triangle(p: [DVec3; 3], n: [DVec3; 3]) -> Lembo {
    let (d, nd) = edge_midpoint(p[0], n[0], p[1], n[1]);
    let (e, ne) = edge_midpoint(p[0], n[0], p[2], n[2]);
    let (f, nf) = edge_midpoint(p[1], n[1], p[2], n[2]);
    let unit = |v: DVec3| v.normalize_or_zero();
    Lembo::new(
        [p[0], p[1], p[2], d, e, f],
        [unit(n[0]), unit(n[1]), unit(n[2]), nd, ne, nf],
    )
}

/// An indexed triangle mesh with one normal per vertex.
#[derive(Clone, Debug, Default)]
pub struct TriangleMesh {
    pub positions: Vec<DVec3>,
    pub normals: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
}

impl TriangleMesh {
    /// Fills missing normals with area-weighted face-normal averages.
    pub fn with_computed_normals(mut self) -> Self {
        let mut acc = vec![DVec3::ZERO; self.positions.len()];
        for t in &self.triangles {
            let [a, b, c] = t.map(|i| self.positions[i as usize]);
            let n = (b - a).cross(c - a);
            for &i in t {
                acc[i as usize] += n;
            }
        }
        self.normals = acc.into_iter().map(|n| n.normalize_or_zero()).collect();
        self
    }

    /// One lembo per triangle (paper 001: "use the Lembo Model to refine a triangular mesh").
    pub fn to_lembos(&self) -> Vec<Lembo> {
        self.triangles
            .iter()
            .map(|t| {
                let i = t.map(|i| i as usize);
                lembo_from_triangle(i.map(|i| self.positions[i]), i.map(|i| self.normals[i]))
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shared_edge_gets_identical_points_from_both_sides() {
        let a = DVec3::new(0.3, 0.1, 0.9).normalize();
        let b = DVec3::new(0.9, 0.2, 0.1).normalize();
        let c = DVec3::new(0.1, 0.95, 0.2).normalize();
        let d = DVec3::new(0.7, 0.7, 0.6).normalize();
        // Triangles ABC and BDC share edge BC, traversed in opposite directions.
        let l1 = lembo_from_triangle([a, b, c], [a, b, c]);
        let l2 = lembo_from_triangle([b, d, c], [b, d, c]);
        // In l1 the BC midpoint is F; in l2 (A=b, B=d, C=c) it is E (edge AC).
        assert_eq!(l1.points[5].to_array(), l2.points[4].to_array());
        assert_eq!(l1.normals[5].to_array(), l2.normals[4].to_array());
    }

    #[test]
    fn parallel_end_normals_give_a_straight_edge() {
        let n = DVec3::Z;
        let (m, nm) = edge_midpoint(DVec3::ZERO, n, DVec3::new(2.0, 0.0, 0.0), n);
        assert_eq!(m, DVec3::new(1.0, 0.0, 0.0));
        assert_eq!(nm, n);
    }

    #[test]
    fn perpendicular_end_normals_do_not_divide_by_zero() {
        // A quarter circle: the printed formula divides by T1·T2 = 0 here.
        let (m, nm) = edge_midpoint(DVec3::X, DVec3::X, DVec3::Y, DVec3::Y);
        assert!(m.is_finite() && nm.is_finite());
        // On the diagonal, bulging outward past the chord midpoint (|chord mid| = 0.707).
        assert!((m.x - m.y).abs() < 1e-15 && m.length() > 0.8 && m.length() < 1.0);
        assert!((nm - DVec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-15);
    }

    #[test]
    fn sphere_edge_midpoint_bulges_towards_the_sphere() {
        // Ends on the unit sphere with radial normals: the midpoint leaves the chord
        // (|chord mid| = cos(theta/2)) and moves outward, without overshooting the sphere,
        // along the bisector.
        let p1 = DVec3::new(1.0, 0.0, 0.0);
        let p2 = DVec3::new(0.6, 0.8, 0.0);
        let (m, nm) = edge_midpoint(p1, p1, p2, p2);
        let chord = (0.5 * (p1 + p2)).length();
        assert!(
            m.length() > chord + 0.05 && m.length() <= 1.0,
            "{}",
            m.length()
        );
        assert!(m.normalize().cross((p1 + p2).normalize()).length() < 1e-12);
        assert!((nm - (p1 + p2).normalize()).length() < 1e-12);
    }
}
