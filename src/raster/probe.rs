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
use std::hash::{BuildHasherDefault, Hasher};
use std::sync::{Mutex, MutexGuard};

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

/// What the probe keeps of one row of a frame's pixels.
struct ProbeRow {
    /// Up to two fragments per pixel (id u32::MAX = empty).
    slots: Vec<[Slot; 2]>,
    /// Pixels found double-hit.
    double: Vec<bool>,
}

/// What the probes of one frame share: the slots of every pixel, row by row, the pairs of
/// lembos that share an edge curve, and what the probes measured. A frame drawn in bands
/// (`frame::bands`) has a probe a band, each holding its own rows' locks while it draws
/// (the bands' rows are disjoint, so none waits); every pixel still meets its fragments in
/// drawing order, and the measurements are maxima and sums, so the report is the
/// single-threaded one whatever the bands.
pub struct ProbeBoard {
    rows: Vec<Mutex<ProbeRow>>,
    adjacent: Adjacent,
    measured: Mutex<ProbeReport>,
}

impl ProbeBoard {
    /// The board of a frame of `scene` on viewport `vp`, its shared edges found on
    /// `threads` host threads ([`shared_edges`]).
    pub fn new(scene: &Scene, vp: Viewport, threads: u32) -> Self {
        let row = || ProbeRow {
            slots: vec![[EMPTY; 2]; vp.width as usize],
            double: vec![false; vp.width as usize],
        };
        ProbeBoard {
            rows: (0..vp.height).map(|_| Mutex::new(row())).collect(),
            adjacent: shared_edges(scene, threads),
            measured: Mutex::new(ProbeReport::default()),
        }
    }

    /// A probe of rows `lo..hi` forwarding every fragment to `inner`; what it measures is
    /// added to the board's when it is dropped.
    pub fn probe<'a, S>(&'a self, lo: u32, hi: u32, inner: &'a mut S) -> Probe<'a, S> {
        Probe {
            inner,
            board: self,
            lo,
            rows: self.rows[lo as usize..hi as usize]
                .iter()
                .map(lock)
                .collect(),
            report: ProbeReport::default(),
        }
    }

    /// What the probes measured (those still alive not included).
    pub fn report(&self) -> ProbeReport {
        let double_hit_pixels = (self.rows.iter())
            .map(|r| lock(r).double.iter().filter(|&&d| d).count() as u64)
            .sum();
        ProbeReport {
            double_hit_pixels,
            ..*lock(&self.measured)
        }
    }
}

/// A mutex's value; one poisoned by a panicking band is still read (the panic itself is
/// what the frame reports).
fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// A fragment sink that measures each fragment of its rows (the scanline deviation, the
/// domain excess, double hits on shared edges) and forwards it to the sink it wraps
/// ([`ProbeBoard::probe`]).
pub struct Probe<'a, S> {
    inner: &'a mut S,
    board: &'a ProbeBoard,
    /// The first of its rows.
    lo: u32,
    rows: Vec<MutexGuard<'a, ProbeRow>>,
    report: ProbeReport,
}

impl<S> Drop for Probe<'_, S> {
    fn drop(&mut self) {
        let mut m = lock(&self.board.measured);
        m.fragments += self.report.fragments;
        m.max_scanline_deviation_px =
            (m.max_scanline_deviation_px).max(self.report.max_scanline_deviation_px);
        m.max_domain_excess = m.max_domain_excess.max(self.report.max_domain_excess);
    }
}

/// Pairs of lembo ids (smaller first) sharing an edge curve, with the shared edge's index in
/// each ([`shared_edges`]).
pub type Adjacent = HashMap<(u32, u32), (u8, u8), BuildHasherDefault<PairHasher>>;

/// A hasher for [`Adjacent`]'s keys, two lembo ids: a multiply and a rotate a word (the
/// keys are ours, not an attacker's, so SipHash's protection against chosen keys buys
/// nothing here).
#[derive(Default)]
pub struct PairHasher(u64);

impl Hasher for PairHasher {
    fn write(&mut self, bytes: &[u8]) {
        bytes.iter().for_each(|&b| self.write_u64(b.into()));
    }

    fn write_u32(&mut self, n: u32) {
        self.write_u64(n.into());
    }

    fn write_u64(&mut self, n: u64) {
        self.0 = (self.0.rotate_left(5) ^ n).wrapping_mul(0x517c_c1b7_2722_0a95);
    }

    fn finish(&self) -> u64 {
        // The table takes its control bits from the top: bring the low words' mixing up.
        self.0.rotate_left(26)
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
/// lembo at its peak), so that a measured run's memory stays bounded per lembo. The edges'
/// uses are made on `threads` host threads, each a run of lembos.
pub fn shared_edges(scene: &Scene, threads: u32) -> Adjacent {
    let count = scene.lembo_count();
    let per_thread = count.div_ceil(threads.max(1) as usize).max(1);
    let index = scene.lembo_index();
    // Three uses a lembo, each thread filling its run's share of one vector in place.
    let mut uses: Vec<(u128, u32, u8)> = vec![(0, 0, 0); 3 * count];
    let fill = |first: usize, out: &mut [(u128, u32, u8)]| {
        let mut last = crate::lembo::set::LastParent::default();
        for (n, three) in out.chunks_exact_mut(3).enumerate() {
            let id = first + n;
            let points = scene.points_near(&index, id, &mut last);
            for (edge, (s, e, m)) in [(0, 1, 3), (1, 2, 5), (2, 0, 4)].into_iter().enumerate() {
                let (mut p, mut q) = (points[s], points[e]);
                if canonical_order(p, q).is_gt() {
                    std::mem::swap(&mut p, &mut q);
                }
                let mid = points[m];
                let key = [p.x, p.y, p.z, q.x, q.y, q.z, mid.x, mid.y, mid.z].map(f64::to_bits);
                three[edge] = (bits_key(&key), id as u32, edge as u8);
            }
        }
    };
    std::thread::scope(|s| {
        for (t, out) in uses.chunks_mut(3 * per_thread).enumerate() {
            let fill = &fill;
            s.spawn(move || fill(t * per_thread, out));
        }
    });
    // Every use is distinct (its lembo and edge), so the order is the same for any count
    // and any split of the sort.
    rayon::slice::ParallelSliceMut::par_sort_unstable(&mut uses[..]);
    // About one pair an interior edge, two uses each: sized once, not grown.
    let mut pairs = Adjacent::with_capacity_and_hasher(uses.len() / 2, Default::default());
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
        let row = &mut *self.rows[(j - self.lo) as usize];
        let slots = &mut row.slots[i as usize];
        for o in slots.iter() {
            if o.id == u32::MAX || o.id == me.id {
                continue;
            }
            let (lo, hi) = if o.id < me.id { (o, &me) } else { (&me, o) };
            if let Some(&(elo, ehi)) = self.board.adjacent.get(&(lo.id, hi.id)) {
                // Both end on the same crossing of the shared edge, from opposite sides.
                let split = lo.ends.iter().filter(|a| a.edge == elo).any(|a| {
                    hi.ends
                        .iter()
                        .filter(|b| b.edge == ehi)
                        .any(|b| b.crossing == a.crossing && b.right != a.right)
                });
                if split {
                    row.double[i as usize] = true;
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
            let board = ProbeBoard::new(&scene, scene.viewport, 1);
            let mut probe = board.probe(0, scene.viewport.height, &mut sink);
            for (n, (sub, i)) in subs.into_iter().enumerate() {
                probe.fragment(&ls[n], &sub, i, 38, 0.3, 0.3, 0.5);
            }
            drop(probe);
            board.report().double_hit_pixels
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
            let adjacent = shared_edges(&scene, 2).contains_key(&(0, 1));
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
            // Rows 37..39 alone: a band's probe, its rows counted from its first.
            let board = ProbeBoard::new(&scene, scene.viewport, 1);
            let mut probe = board.probe(37, 39, &mut sink);
            probe.fragment(&ls[0], &right, 58, 38, 0.3, 0.3, 0.5);
            probe.fragment(&ls[1], &left, 58, 38, 0.3, 0.3, 0.5);
            drop(probe);
            (adjacent, board.report().double_hit_pixels)
        };
        assert_eq!(run(m), (true, 1));
        assert_eq!(run([45.0, 36.0]), (false, 0));
    }
}
