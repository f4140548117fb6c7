//! A fragment sink that measures what the paper guarantees and what a closed mesh must
//! satisfy, then forwards each fragment to the real sink:
//! - the largest |y(u, v) - (j + 0.5)| over all fragments, in f64 from the lembo's screen
//!   quadratic (paper 001: the curve is followed within k);
//! - the largest distance of a fragment's (u, v) outside the domain;
//! - double hits on shared edges: a pixel claimed by two lembos that share an edge, each
//!   through a subsegment that ends on that edge, from opposite sides of the crossing along
//!   the scanline. Neighbours on opposite sides must split the scanline at the crossing, so
//!   any pixel both claim is a pixel-rule fault (the crossing's x computed differently on
//!   the two sides). Neighbours on the same side overlap because the surface folds over
//!   itself in projection (at a contour): that is geometry, measured against the reference,
//!   not a rasterization fault. The probe keeps the first two fragments per pixel, so with
//!   more than two layers later ones are compared only against those two.

use super::fragment::FragmentSink;
use super::interval::INTERIOR;
use super::setup::ScreenLembo;
use super::subsegmenter::Subsegment;
use crate::camera::Viewport;
use crate::datapath::Real;
use crate::lembo::construct::canonical_order;
use crate::scene::Scene;
use std::collections::HashMap;

/// What the probe measured.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ProbeReport {
    pub max_scanline_deviation_px: f64,
    /// Largest distance of a fragment's (u, v) outside the domain (0 if all inside).
    pub max_domain_excess: f64,
    pub double_hit_pixels: u64,
    pub fragments: u64,
}

/// What the probe keeps of a fragment.
#[derive(Clone, Copy)]
struct Slot {
    id: u32,
    /// Bit e set when the fragment's subsegment ends on domain edge e.
    touches: u8,
    /// Bit e set when that subsegment extends towards +x from its end on edge e.
    right_of: u8,
}

const EMPTY: Slot = Slot {
    id: u32::MAX,
    touches: 0,
    right_of: 0,
};

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

    pub fn report(&self) -> ProbeReport {
        ProbeReport {
            double_hit_pixels: self.double.iter().filter(|&&d| d).count() as u64,
            ..self.report
        }
    }
}

/// Pairs of lembo ids (smaller first) whose world-space edges have identical end points,
/// with the domain edge index (0: AB, 1: BC, 2: CA) of the shared edge in each.
pub fn shared_edges(scene: &Scene) -> HashMap<(u32, u32), (u8, u8)> {
    let mut by_edge: HashMap<[u64; 6], Vec<(u32, u8)>> = HashMap::new();
    for (id, (l, _)) in scene.lembos().enumerate() {
        for (edge, (s, e)) in [(0, 1), (1, 2), (2, 0)].into_iter().enumerate() {
            let (mut p, mut q) = (l.points[s], l.points[e]);
            if canonical_order(p, q).is_gt() {
                std::mem::swap(&mut p, &mut q);
            }
            let key = [p.x, p.y, p.z, q.x, q.y, q.z].map(f64::to_bits);
            by_edge
                .entry(key)
                .or_default()
                .push((id as u32, edge as u8));
        }
    }
    let mut pairs = HashMap::new();
    for ids in by_edge.values() {
        for (n, &(a, ea)) in ids.iter().enumerate() {
            for &(b, eb) in &ids[n + 1..] {
                if a < b {
                    pairs.insert((a, b), (ea, eb));
                } else if b < a {
                    pairs.insert((b, a), (eb, ea));
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
        let (mut touches, mut right_of) = (0u8, 0u8);
        for (end, other) in [(&sub.a, &sub.b), (&sub.b, &sub.a)] {
            if end.edge != INTERIOR {
                touches |= 1 << end.edge;
                if other.x > end.x {
                    right_of |= 1 << end.edge;
                }
            }
        }
        let me = Slot {
            id: l.id,
            touches,
            right_of,
        };
        let slots = &mut self.slots[idx];
        for o in slots.iter() {
            if o.id == u32::MAX || o.id == me.id {
                continue;
            }
            let (lo, hi) = if o.id < me.id { (o, &me) } else { (&me, o) };
            if let Some(&(elo, ehi)) = self.adjacent.get(&(lo.id, hi.id)) {
                let touch = lo.touches & (1 << elo) != 0 && hi.touches & (1 << ehi) != 0;
                let opposite = (lo.right_of >> elo & 1) != (hi.right_of >> ehi & 1);
                if touch && opposite {
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
