//! [`TriangleProbe`]: fragment-level measurements of the triangle path, forwarded to the
//! sink it wraps.

use super::{
    rasterize::{TriangleFragment, TriangleSink},
    setup::ScreenTriangle,
};
use crate::datapath::Real;

/// A triangle sink that counts double hits on shared edges, then forwards each fragment.
///
/// Two triangles on opposite sides of a shared edge can both contain a pixel centre only if
/// it lies exactly on that edge, where the fill rule must give it to one of them. So a
/// double hit is a pixel whose centre lies exactly on an edge (edge function 0) of two
/// triangles with the same snapped end points, on opposite sides of it. Fragments off every
/// edge need no bookkeeping, so the probe costs little.
pub struct TriangleProbe<'a, S> {
    inner: &'a mut S,
    width: u32,
    /// Per pixel with an on-edge fragment: (triangle id, canonical edge, side) of each.
    on_edge: std::collections::HashMap<u32, Vec<(u32, [i64; 4], bool)>>,
    doubles: std::collections::HashSet<u32>,
}

impl<'a, S> TriangleProbe<'a, S> {
    /// A probe over a frame `width` pixels wide, forwarding every fragment to `inner`.
    pub fn new(width: u32, inner: &'a mut S) -> Self {
        TriangleProbe {
            inner,
            width,
            on_edge: Default::default(),
            doubles: Default::default(),
        }
    }

    /// Pixels claimed from both sides of a shared edge.
    pub fn double_hit_pixels(&self) -> u64 {
        self.doubles.len() as u64
    }
}

impl<R: Real, S: TriangleSink<R>> TriangleSink<R> for TriangleProbe<'_, S> {
    fn fragment(&mut self, t: &ScreenTriangle<R>, i: u32, j: u32, f: &TriangleFragment<R>) {
        let e = t.edge_values(i, j);
        for (k, &ek) in e.iter().enumerate() {
            if ek != 0 {
                continue;
            }
            // Edge k joins vertices k + 1 and k + 2; order its ends canonically and note on
            // which side of it the third vertex lies.
            let (a, b) = ((k + 1) % 3, (k + 2) % 3);
            let (pa, pb) = ((t.x[a], t.y[a]), (t.x[b], t.y[b]));
            let (p, q) = if pa <= pb { (pa, pb) } else { (pb, pa) };
            let side = (q.0 - p.0) * (t.y[k] - p.1) - (q.1 - p.1) * (t.x[k] - p.0) > 0;
            let key = [p.0, p.1, q.0, q.1];
            let pixel = j * self.width + i;
            let seen = self.on_edge.entry(pixel).or_default();
            if seen
                .iter()
                .any(|&(id, other, s)| id != t.id && other == key && s != side)
            {
                self.doubles.insert(pixel);
            }
            seen.push((t.id, key, side));
        }
        self.inner.fragment(t, i, j, f);
    }
}
