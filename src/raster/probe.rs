//! A fragment sink that measures what the paper guarantees and what a closed mesh must
//! satisfy, then forwards each fragment to the real sink:
//! - the largest |y(u, v) - (j + 0.5)| over all fragments, in f64 from the lembo's screen
//!   quadratic (Martinelli 2006: the curve is followed within k);
//! - the largest distance of a fragment's (u, v) outside the domain;
//! - double hits on shared edges: a pixel claimed by two lembos that share an edge curve
//!   (the same three points: both ends and the midpoint; [`shared_edges`]), each
//!   through a subsegment that ends on the *same crossing* of that edge, from opposite sides
//!   of it along the scanline. Neighbours on opposite sides must split the scanline at the
//!   crossing, so any pixel both claim is a pixel-rule fault (the crossing's x computed
//!   differently on the two sides). Neighbours on the same side overlap because the surface
//!   folds over itself in projection (at a contour): that is geometry, measured against the
//!   reference, not a rasterization fault. A curved edge can cross a scanline twice, so a
//!   crossing is told apart from the other by the side of the edge parabola's extremum it
//!   lies on, which both neighbours compute from the same canonical edge; ends on the two
//!   different crossings of one edge say nothing about each other. The probe keeps the
//!   first two fragments per pixel, so with more than two layers later ones are compared
//!   only against those two.

use super::fragment::FragmentSink;
use super::interval::{ConicPoint, INTERIOR};
use super::screen::ScreenLembo;
use super::subsegmenter::Subsegment;
use crate::camera::Viewport;
use crate::datapath::Real;
use crate::lembo::construct::{bits_key, canonical_order};
use crate::scene::Scene;
use std::collections::HashMap;

/// What the probe measured.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ProbeReport {
    /// The paper's guarantee: largest \|y(u, v) - (j + 0.5)\| over the fragments \[pixels\].
    pub max_scanline_deviation_px: f64,
    /// Largest distance of a fragment's (u, v) outside the domain (0 if all inside).
    pub max_domain_excess: f64,
    /// Pixels written by more than one primitive along a shared edge \[pixels\].
    pub double_hit_pixels: u64,
    /// Fragments measured.
    pub fragments: u64,
}

/// One end of a fragment's subsegment that lies on a domain edge.
#[derive(Clone, Copy)]
struct EdgeEnd {
    /// The domain edge (0: AB, 1: BC, 2: CA), or [`INTERIOR`] for no end.
    edge: u8,
    /// Which crossing of that edge on the scanline (see [`crossing_index`]).
    crossing: u8,
    /// The subsegment extends towards +x from this end.
    right: bool,
}

const NO_END: EdgeEnd = EdgeEnd {
    edge: INTERIOR,
    crossing: 0,
    right: false,
};

/// What the probe keeps of a fragment.
#[derive(Clone, Copy)]
struct Slot {
    id: u32,
    /// The ends of the fragment's subsegment that lie on domain edges.
    ends: [EdgeEnd; 2],
}

const EMPTY: Slot = Slot {
    id: u32::MAX,
    ends: [NO_END; 2],
};

/// A fragment sink that measures each fragment (the scanline deviation, the domain excess,
/// double hits on shared edges) and forwards it to the sink it wraps.
pub struct Probe<'a, S> {
    inner: &'a mut S,
    width: u32,
    /// Up to two fragments per pixel (id u32::MAX = empty).
    slots: Vec<[Slot; 2]>,
    double: Vec<bool>,
    adjacent: HashMap<(u32, u32), (u8, u8)>,
    report: ProbeReport,
}

impl<'a, S> Probe<'a, S> {
    /// A probe over `scene` on viewport `vp`, forwarding every fragment to `inner`.
    pub fn new(scene: &Scene, vp: Viewport, inner: &'a mut S) -> Self {
        Probe {
            inner,
            width: vp.width,
            slots: vec![[EMPTY; 2]; vp.pixels()],
            double: vec![false; vp.pixels()],
            adjacent: shared_edges(scene),
            report: ProbeReport::default(),
        }
    }

    /// What was measured so far.
    pub fn report(&self) -> ProbeReport {
        ProbeReport {
            double_hit_pixels: self.double.iter().filter(|&&d| d).count() as u64,
            ..self.report
        }
    }
}

/// Pairs of lembo ids (smaller first) that share an edge curve, with the domain edge index
/// (0: AB, 1: BC, 2: CA) of the shared edge in each. An edge's curve is the quadratic
/// through its three world-space points (both ends and the curved midpoint), so two lembos
/// share it exactly when the three points are the same, bit for bit: corners alone are not
/// enough, since split normals at the corners (a hard edge) give each side its own
/// midpoint, two different curves between the same corners, which do not split the
/// scanline between them (the gap or overlap between them is see-through's to measure, not
/// a pixel-rule fault).
///
/// The nine coordinates' bits are matched through a 128-bit hash of them ([`bits_key`]),
/// sorted: 32 bytes an edge's use instead of a map of the 72-byte keys (about 300 bytes a
/// lembo at its peak), so that a measured run's memory stays bounded per lembo.
pub fn shared_edges(scene: &Scene) -> HashMap<(u32, u32), (u8, u8)> {
    let mut uses: Vec<(u128, u32, u8)> = Vec::with_capacity(3 * scene.lembo_count());
    for (id, (l, _)) in scene.lembos().enumerate() {
        for (edge, (s, e, m)) in [(0, 1, 3), (1, 2, 5), (2, 0, 4)].into_iter().enumerate() {
            let (mut p, mut q) = (l.points[s], l.points[e]);
            if canonical_order(p, q).is_gt() {
                std::mem::swap(&mut p, &mut q);
            }
            let mid = l.points[m];
            let key = [p.x, p.y, p.z, q.x, q.y, q.z, mid.x, mid.y, mid.z].map(f64::to_bits);
            uses.push((bits_key(&key), id as u32, edge as u8));
        }
    }
    uses.sort_unstable();
    let mut pairs = HashMap::new();
    for curve in uses.chunk_by(|a, b| a.0 == b.0) {
        for (n, &(_, a, ea)) in curve.iter().enumerate() {
            for &(_, b, eb) in &curve[n + 1..] {
                // Sorted, so a <= b; a lembo meeting itself is not a pair.
                if a < b {
                    pairs.insert((a, b), (ea, eb));
                }
            }
        }
    }
    pairs
}

impl<R: Real, S: FragmentSink<R>> FragmentSink<R> for Probe<'_, S> {
    fn fragment(
        &mut self,
        l: &ScreenLembo<R>,
        sub: &Subsegment<R>,
        i: u32,
        j: u32,
        u: R,
        v: R,
        z: R,
    ) {
        let (uf, vf) = (u.f64(), v.f64());
        let y = l.y.cast::<f64>().eval(uf, vf);
        let r = &mut self.report;
        r.fragments += 1;
        r.max_scanline_deviation_px = r
            .max_scanline_deviation_px
            .max((y - (j as f64 + 0.5)).abs());
        r.max_domain_excess = r.max_domain_excess.max((-uf).max(-vf).max(uf + vf - 1.0));

        let idx = j as usize * self.width as usize + i as usize;
        let mut ends = [NO_END; 2];
        // Ends on a piece's edges (a lembo Setup split) are not recorded: a piece's edge
        // indices and crossings are its own, not the lembo's, so they cannot be matched
        // with a neighbour's; double hits across a split lembo's outer edge go uncounted.
        for (n, (end, other)) in [(&sub.a, &sub.b), (&sub.b, &sub.a)].into_iter().enumerate() {
            if end.edge != INTERIOR && l.domain.is_none() {
                ends[n] = EdgeEnd {
                    edge: end.edge,
                    crossing: crossing_index(l, end),
                    right: other.x > end.x,
                };
            }
        }
        let me = Slot { id: l.id, ends };
        let slots = &mut self.slots[idx];
        for o in slots.iter() {
            if o.id == u32::MAX || o.id == me.id {
                continue;
            }
            let (lo, hi) = if o.id < me.id { (o, &me) } else { (&me, o) };
            if let Some(&(elo, ehi)) = self.adjacent.get(&(lo.id, hi.id)) {
                // Both end on the same crossing of the shared edge, from opposite sides.
                let split = lo.ends.iter().filter(|a| a.edge == elo).any(|a| {
                    hi.ends
                        .iter()
                        .filter(|b| b.edge == ehi)
                        .any(|b| b.crossing == a.crossing && b.right != a.right)
                });
                if split {
                    self.double[idx] = true;
                }
            }
        }
        if let Some(slot) = slots.iter_mut().find(|s| s.id == u32::MAX) {
            *slot = me;
        }
        self.inner.fragment(l, sub, i, j, u, v, z);
    }
}

/// Which crossing of its domain edge the point `p` (on that edge) is: 0 or 1 by the side of
/// the extremum of the canonical edge parabola y(t) it lies on (a scanline meets the edge
/// at most once on each side). Two lembos sharing the edge have bit-identical canonical
/// edges, so they agree on the index of every crossing.
fn crossing_index<R: Real>(l: &ScreenLembo<R>, p: &ConicPoint<R>) -> u8 {
    let c = &l.edges[p.edge as usize];
    // Lembo-order parameter along the edge (the inverse of `setup::edge_uv`), then canonical.
    let tl = match p.edge {
        0 => p.uv[0].f64(),
        1 => p.uv[1].f64(),
        _ => 1.0 - p.uv[1].f64(),
    };
    let t = if c.reversed { 1.0 - tl } else { tl };
    let [y0, y1, y2] = c.y.map(R::f64);
    let a = 2.0 * y0 + 2.0 * y2 - 4.0 * y1;
    let b = 4.0 * y1 - 3.0 * y0 - y2;
    if a == 0.0 {
        return 0;
    }
    u8::from(t > -b / (2.0 * a))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::View;
    use crate::lembo::Lembo;
    use crate::raster::setup::{setup, tests::Collect};
    use glam::DVec3;
    use std::path::Path;

    /// A scene of `lembos` seen by the orthographic 128 x 128 view of the raster fixtures
    /// (world (X, Y) on screen (X + 64, 64 - Y)).
    fn scene_of(lembos: Vec<Lembo>) -> Scene {
        let text = r#"{"name": "probe", "viewport": {"width": 128, "height": 128},
            "camera": {"eye": [0, 0, 10], "target": [0, 0, 0], "up": [0, 1, 0],
                       "projection": {"kind": "orthographic", "height": 128, "near": 0.1, "far": 100}},
            "objects": [{"lembos": [{"points": [[0,0,0],[1,0,0],[0,1,0],[0.5,0,0],[0,0.5,0],[0.5,0.5,0]],
                                     "normals": [[0,0,1],[0,0,1],[0,0,1],[0,0,1],[0,0,1],[0,0,1]]}]}]}"#;
        let mut scene = Scene::from_json(text, "probe", Path::new(".")).unwrap();
        scene.objects[0].lembos = lembos.into();
        scene
    }

    /// A lembo with corners `a`, `b`, `c` and the middle of edge AB at `d` (straight other
    /// edges), given in screen pixels.
    fn lembo(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> Lembo {
        let w = |p: [f64; 2]| DVec3::new(p[0] - 64.0, 64.0 - p[1], 0.0);
        let mid = |p: [f64; 2], q: [f64; 2]| [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])];
        Lembo::new(
            [w(a), w(b), w(c), w(d), w(mid(a, c)), w(mid(b, c))],
            [DVec3::Z; 6],
        )
    }

    #[test]
    fn probe_double_hit_needs_the_same_crossing_from_opposite_sides() {
        // Two lembos share the edge P = (30, 40) -> Q = (60, 40) bulging up to (45, 35), both
        // below it: the surface folds over at the edge. Scanline 38 (y = 38.5) crosses that
        // edge twice, at t = 0.0813 (x = 32.44) and t = 0.9187 (x = 57.56).
        let (p, q, m) = ([30.0, 40.0], [60.0, 40.0], [45.0, 35.0]);
        let scene = scene_of(vec![
            lembo(p, q, [45.0, 80.0], m),
            lembo(q, p, [45.0, 70.0], m),
        ]);
        let view = View::new(&scene.camera, scene.viewport);
        let ls: Vec<ScreenLembo<f64>> = scene
            .lembos()
            .enumerate()
            .map(|(id, (l, c))| setup(id as u32, &l, c, &view).unwrap())
            .collect();
        let t = (1.0 - (1.0f64 - 4.0 * 0.075).sqrt()) / 2.0;
        // A point on edge AB of lembo n at canonical t (from P), or in the interior.
        let on_edge = |n: usize, t: f64, x: f64| {
            let u = if n == 0 { t } else { 1.0 - t };
            ConicPoint {
                uv: [u, 0.0],
                x,
                edge: 0,
            }
        };
        let inner = |x: f64| ConicPoint {
            uv: [0.3, 0.3],
            x,
            edge: INTERIOR,
        };
        let (x1, x2) = (30.0 + 30.0 * t, 30.0 + 30.0 * (1.0 - t));

        let run = |subs: [(Subsegment<f64>, u32); 2]| {
            let mut sink = Collect::default();
            let mut probe = Probe::new(&scene, scene.viewport, &mut sink);
            for (n, (sub, i)) in subs.into_iter().enumerate() {
                probe.fragment(&ls[n], &sub, i, 38, 0.3, 0.3, 0.5);
            }
            probe.report().double_hit_pixels
        };
        // Lembo 0 spans from one crossing to the other, lembo 1 from the second crossing
        // leftwards: both left of that crossing (the fold), not a fault.
        let span = Subsegment {
            a: on_edge(0, t, x1),
            b: on_edge(0, 1.0 - t, x2),
        };
        let left_of_x2 = Subsegment {
            a: on_edge(1, 1.0 - t, x2),
            b: inner(50.0),
        };
        assert_eq!(run([(span, 56), (left_of_x2, 56)]), 0);
        // Lembo 0 right of the first crossing, lembo 1 left of the second: different crossings.
        let right_of_x1 = Subsegment {
            a: inner(50.0),
            b: on_edge(0, t, x1),
        };
        assert_eq!(run([(right_of_x1, 45), (left_of_x2, 45)]), 0);
        // The same crossing from opposite sides, lembo 1 computing its x 1.1 px too far right:
        // the pixel both claim is a double hit.
        let right_of_x2 = Subsegment {
            a: on_edge(0, 1.0 - t, x2),
            b: inner(70.0),
        };
        let left_of_wrong_x2 = Subsegment {
            a: on_edge(1, 1.0 - t, x2 + 1.1),
            b: inner(50.0),
        };
        assert_eq!(run([(right_of_x2, 58), (left_of_wrong_x2, 58)]), 1);
    }

    #[test]
    fn probe_pairs_neighbours_by_their_edge_curve_not_their_corners() {
        // Two lembos with the same corners P, Q on their edge AB. With the same midpoint
        // they share the curve and a pixel both claim from opposite sides of the same
        // crossing is a double hit; with different midpoints (split normals at P and Q give
        // each side its own curve) they are not neighbours and it is not.
        let (p, q, m) = ([30.0, 40.0], [60.0, 40.0], [45.0, 35.0]);
        let run = |other_mid: [f64; 2]| {
            let scene = scene_of(vec![
                lembo(p, q, [45.0, 80.0], m),
                lembo(q, p, [45.0, 10.0], other_mid),
            ]);
            let adjacent = shared_edges(&scene).contains_key(&(0, 1));
            let view = View::new(&scene.camera, scene.viewport);
            let ls: Vec<ScreenLembo<f64>> = scene
                .lembos()
                .enumerate()
                .map(|(id, (l, c))| setup(id as u32, &l, c, &view).unwrap())
                .collect();
            // Scanline 38 (y = 38.5) crosses lembo 0's edge at t = 0.9187 (x = 57.56);
            // lembo 0 to its right, lembo 1 to its left but computing x 1.1 px too far
            // right, so both claim pixel 58.
            let t = (1.0 - (1.0f64 - 4.0 * 0.075).sqrt()) / 2.0;
            let x2 = 30.0 + 30.0 * (1.0 - t);
            let on_edge = |u: f64, x: f64| ConicPoint {
                uv: [u, 0.0],
                x,
                edge: 0,
            };
            let inner = |x: f64| ConicPoint {
                uv: [0.3, 0.3],
                x,
                edge: INTERIOR,
            };
            let right = Subsegment {
                a: on_edge(1.0 - t, x2),
                b: inner(70.0),
            };
            let left = Subsegment {
                a: on_edge(t, x2 + 1.1),
                b: inner(50.0),
            };
            let mut sink = Collect::default();
            let mut probe = Probe::new(&scene, scene.viewport, &mut sink);
            probe.fragment(&ls[0], &right, 58, 38, 0.3, 0.3, 0.5);
            probe.fragment(&ls[1], &left, 58, 38, 0.3, 0.3, 0.5);
            (adjacent, probe.report().double_hit_pixels)
        };
        assert_eq!(run(m), (true, 1));
        assert_eq!(run([45.0, 36.0]), (false, 0));
    }
}
