//! The exact Euclidean distance \[pixels\] from a pixel to the nearest pixel of a mask
//! value, as the silhouette error bounds a misplaced pixel's distance to the outline
//! (`metrics.rs`): a search of the rings around the pixel, or past a few rings the
//! distance transform of the whole mask (Felzenszwalb and Huttenlocher, "Distance
//! Transforms of Sampled Functions", 2012), the lower envelope of parabolas along columns
//! then rows.

/// Rings searched around a pixel for the nearest centre of a mask value before the whole
/// image's distance transform is computed instead.
const RING_SEARCH_LIMIT: usize = 16;

/// The distance from a pixel to the nearest pixel of a mask value: by searching rings
/// around it (misplaced pixels are mostly near the outline), or, past
/// [`RING_SEARCH_LIMIT`], from the exact distance transform of the whole mask, computed
/// once per value when first needed. Both give the same exact distance.
pub(super) struct Bounds<'a> {
    mask: &'a [bool],
    w: usize,
    h: usize,
    /// The transforms to `false` and `true` pixels, when computed.
    transforms: [Option<Vec<Option<f64>>>; 2],
}

impl<'a> Bounds<'a> {
    pub(super) fn new(mask: &'a [bool], w: usize, h: usize) -> Self {
        Bounds {
            mask,
            w,
            h,
            transforms: [None, None],
        }
    }

    /// The Euclidean distance \[pixels\] from pixel `k` to the nearest pixel whose mask
    /// value is `value`; None when there is none.
    pub(super) fn nearest(&mut self, k: usize, value: bool) -> Option<f64> {
        let (w, h) = (self.w as i64, self.h as i64);
        let (x, y) = ((k % self.w) as i64, (k / self.w) as i64);
        if self.mask[k] == value {
            return Some(0.0);
        }
        let mut best = i64::MAX;
        for r in 1..=RING_SEARCH_LIMIT as i64 {
            // Every pixel of ring r (Chebyshev distance r) is at least r away.
            if r * r >= best {
                return Some((best as f64).sqrt());
            }
            for j in (y - r).max(0)..=(y + r).min(h - 1) {
                let dy = j - y;
                // The ring's pixels in row j: both ends, or the whole row at the top and bottom.
                let step = if dy.abs() == r { 1 } else { 2 * r };
                let mut i = x - r;
                while i <= x + r {
                    if i >= 0 && i < w && self.mask[(j * w + i) as usize] == value {
                        best = best.min((i - x) * (i - x) + dy * dy);
                    }
                    i += step;
                }
            }
        }
        if best <= (RING_SEARCH_LIMIT as i64 + 1).pow(2) {
            return Some((best as f64).sqrt());
        }
        let (mask, w, h) = (self.mask, self.w, self.h);
        self.transforms[value as usize].get_or_insert_with(|| distance_to(mask, w, h, value))[k]
    }
}

/// Per pixel, the Euclidean distance \[pixels\] to the nearest pixel whose mask value is
/// `value`; `None` everywhere when there is no such pixel.
fn distance_to(mask: &[bool], w: usize, h: usize, value: bool) -> Vec<Option<f64>> {
    if !mask.contains(&value) {
        return vec![None; w * h];
    }
    // Squared distances: 0 at the features, "infinity" elsewhere. A finite stand-in keeps
    // the parabola intersections free of inf - inf.
    const FAR: f64 = 1e20;
    let mut grid: Vec<f64> = mask
        .iter()
        .map(|&m| if m == value { 0.0 } else { FAR })
        .collect();
    let mut buf = Transform1d::new(w.max(h));
    let mut column = vec![0.0; h];
    for i in 0..w {
        for j in 0..h {
            column[j] = grid[j * w + i];
        }
        buf.run(&mut column);
        for j in 0..h {
            grid[j * w + i] = column[j];
        }
    }
    for row in grid.chunks_mut(w) {
        buf.run(row);
    }
    grid.into_iter().map(|d2| Some(d2.sqrt())).collect()
}

/// Buffers of the 1D squared distance transform (the lower envelope of parabolas).
struct Transform1d {
    f: Vec<f64>,
    v: Vec<usize>,
    z: Vec<f64>,
}

impl Transform1d {
    fn new(n: usize) -> Self {
        Transform1d {
            f: vec![0.0; n],
            v: vec![0; n],
            z: vec![0.0; n + 1],
        }
    }

    /// Replaces `d[q]` by `min_p (q - p)² + d[p]`.
    fn run(&mut self, d: &mut [f64]) {
        let n = d.len();
        if n == 0 {
            return;
        }
        let (f, v, z) = (&mut self.f, &mut self.v, &mut self.z);
        f[..n].copy_from_slice(d);
        let cross = |f: &[f64], q: usize, p: usize| {
            let (qf, pf) = (q as f64, p as f64);
            ((f[q] + qf * qf) - (f[p] + pf * pf)) / (2.0 * (qf - pf))
        };
        let mut k = 0;
        v[0] = 0;
        z[0] = f64::NEG_INFINITY;
        z[1] = f64::INFINITY;
        for q in 1..n {
            let mut s = cross(f, q, v[k]);
            while s <= z[k] {
                k -= 1;
                s = cross(f, q, v[k]);
            }
            k += 1;
            v[k] = q;
            z[k] = s;
            z[k + 1] = f64::INFINITY;
        }
        k = 0;
        for (q, out) in d.iter_mut().enumerate() {
            while z[k + 1] < q as f64 {
                k += 1;
            }
            let dq = q as f64 - v[k] as f64;
            *out = dq * dq + f[v[k]];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distance_transform_matches_brute_force() {
        let (w, h) = (13, 9);
        let mask: Vec<bool> = (0..w * h).map(|k| (k * 7919) % 11 == 0).collect();
        let fast = distance_to(&mask, w, h, true);
        for (k, d) in fast.iter().enumerate() {
            let (x, y) = ((k % w) as f64, (k / w) as f64);
            let brute = (0..w * h)
                .filter(|&p| mask[p])
                .map(|p| ((x - (p % w) as f64).powi(2) + (y - (p / w) as f64).powi(2)).sqrt())
                .fold(f64::INFINITY, f64::min);
            assert!(
                (d.unwrap() - brute).abs() < 1e-12,
                "pixel {k}: {d:?} vs {brute}"
            );
        }
        assert!(distance_to(&mask, w, h, true).iter().all(|d| d.is_some()));
        assert!(distance_to(&[false; 4], 2, 2, true)
            .iter()
            .all(|d| d.is_none()));
    }

    #[test]
    fn ring_search_matches_the_distance_transform() {
        // Sparse features: some pixels find one within the rings, others need the transform.
        let (w, h) = (61, 47);
        let mask: Vec<bool> = (0..w * h).map(|k| (k * 7919) % 401 == 0).collect();
        let mut bounds = Bounds::new(&mask, w, h);
        for value in [true, false] {
            let exact = distance_to(&mask, w, h, value);
            for (k, want) in exact.iter().enumerate() {
                assert_eq!(bounds.nearest(k, value), *want, "pixel {k}, {value}");
            }
        }
        let none = [false; 6];
        assert_eq!(Bounds::new(&none, 3, 2).nearest(4, true), None);
    }

    #[test]
    fn ring_search_matches_brute_force_on_dense_masks() {
        // Dense masks: the nearest pixel of either value is found within the rings.
        let (w, h) = (23, 17);
        let mut random = crate::testkit::SplitMix64::new(11);
        for density in [0.5, 0.1, 0.02] {
            let mask: Vec<bool> = (0..w * h).map(|_| random.unit() < density).collect();
            let mut bounds = Bounds::new(&mask, w, h);
            for value in [true, false] {
                for k in 0..w * h {
                    let (x, y) = ((k % w) as i64, (k / w) as i64);
                    let brute = (0..w * h)
                        .filter(|&p| mask[p] == value)
                        .map(|p| ((p % w) as i64 - x).pow(2) + ((p / w) as i64 - y).pow(2))
                        .min()
                        .map(|d2| (d2 as f64).sqrt());
                    assert_eq!(bounds.nearest(k, value), brute, "pixel {k}, {value}");
                }
            }
        }
    }
}
