//! The frame buffer: colour, depth and the id of the primitive that won each pixel.
//!
//! The depth test orders fragments by (depth, primitive id) so that the winner of a pixel
//! does not depend on the order fragments arrive in: parallel ROPs and any interleaving
//! give the same image. Depth is stored as `f32` whatever the datapath, as a depth buffer
//! would hold it. The normal buffer exists only when accuracy is measured.

use super::plane::{fill, Plane};
use crate::camera::Samples;

/// No primitive has written this pixel.
pub const NO_PRIMITIVE: u32 = u32::MAX;

/// The depth test of every ROP: whether fragment (z, id) beats a pixel holding depth
/// `depth` from primitive `primitive`. Nearer wins; equal depths go to the smaller id, so
/// the result does not depend on arrival order. Fragments outside [0, 1] are clipped.
#[inline(always)]
pub fn depth_test(z: f32, id: u32, depth: f32, primitive: u32) -> bool {
    (0.0..=1.0).contains(&z) && (z < depth || (z == depth && id < primitive))
}

/// Pixels of a winner plane some primitive wrote, counted in eight `u32` lanes, which the
/// compiler keeps in vector registers (a plane holds fewer than 2^32 pixels a lane).
fn covered(primitive: &[u32]) -> usize {
    let mut lanes = [0u32; 8];
    let chunks = primitive.chunks_exact(8);
    let rest = chunks.remainder();
    for c in chunks {
        for k in 0..8 {
            lanes[k] += (c[k] != NO_PRIMITIVE) as u32;
        }
    }
    let tail = rest.iter().filter(|&&p| p != NO_PRIMITIVE).count();
    lanes.iter().map(|&n| n as usize).sum::<usize>() + tail
}

/// `sum / n` rounded to nearest, halves to even: a resolve's mean of `n` stored samples,
/// unbiased (halves up would brighten every pixel whose samples differ by an odd sum).
fn mean_rounded(sum: u32, n: u32) -> u8 {
    let (q, r) = (sum / n, sum % n);
    let up = match (2 * r).cmp(&n) {
        std::cmp::Ordering::Greater => true,
        std::cmp::Ordering::Equal => q % 2 == 1,
        std::cmp::Ordering::Less => false,
    };
    (q + up as u32) as u8
}

/// Colour, depth and winner id per pixel, row 0 at the top.
#[derive(Clone, Debug)]
pub struct FrameBuffer {
    /// Width \[pixels\].
    pub width: u32,
    /// Height \[pixels\].
    pub height: u32,
    /// RGB8 per pixel.
    pub color: Plane<[u8; 3]>,
    /// Depth in [0, 1] per pixel; 1 where nothing was drawn.
    pub depth: Plane<f32>,
    /// Id of the primitive whose fragment won, or [`NO_PRIMITIVE`].
    pub primitive: Plane<u32>,
    /// Unit normal of the winning fragment, kept only when accuracy is measured.
    pub normal: Option<Plane<[f32; 3]>>,
}

impl FrameBuffer {
    /// Bytes one pixel takes as stored: RGB8 colour, f32 depth and u32 winner id (the
    /// normal buffer is the accuracy metrics', not the unit's, and is not counted) \[bytes\].
    pub const BYTES_PER_PIXEL: u64 = (std::mem::size_of::<[u8; 3]>()
        + std::mem::size_of::<f32>()
        + std::mem::size_of::<u32>()) as u64;

    /// Bytes of a `width` x `height` frame buffer as stored (see [`Self::BYTES_PER_PIXEL`]).
    pub fn stored_bytes(width: u32, height: u32) -> u64 {
        width as u64 * height as u64 * Self::BYTES_PER_PIXEL
    }

    /// A cleared frame: the background colour, depth 1, no winner; normals kept when asked (the
    /// accuracy metrics read them).
    pub fn new(width: u32, height: u32, background: [u8; 3], keep_normals: bool) -> Self {
        let n = width as usize * height as usize;
        FrameBuffer {
            width,
            height,
            color: Plane::filled(n, background),
            depth: Plane::filled(n, 1.0),
            primitive: Plane::filled(n, NO_PRIMITIVE),
            normal: keep_normals.then(|| Plane::filled(n, [0.0; 3])),
        }
    }

    /// The index of pixel (i, j) in the per-pixel vectors, row-major.
    #[inline(always)]
    pub fn index(&self, i: u32, j: u32) -> usize {
        j as usize * self.width as usize + i as usize
    }

    /// A frame of `width` x `height` whose pixels are all zero (not a cleared frame): for
    /// [`Self::bands_mut`], whose bands each clear their own rows, on their own threads.
    /// A large frame's zeroed planes are mapped lazily ([`Plane::zeroed`]), so nothing is
    /// touched here. Normals are kept when asked, as in [`Self::new`].
    pub fn zeroed(width: u32, height: u32, keep_normals: bool) -> Self {
        let n = width as usize * height as usize;
        FrameBuffer {
            width,
            height,
            color: Plane::zeroed(n),
            depth: Plane::zeroed(n),
            primitive: Plane::zeroed(n),
            normal: keep_normals.then(|| Plane::zeroed(n)),
        }
    }

    /// All the rows, to write through a ROP.
    pub fn rows_mut(&mut self) -> FrameRows<'_> {
        FrameRows {
            width: self.width,
            color: &mut self.color,
            depth: &mut self.depth,
            primitive: &mut self.primitive,
            normal: self.normal.as_deref_mut(),
        }
    }

    /// The rows of each band `lo..hi`, for bands that follow one another from row 0 to the
    /// last (`frame::bands`), to write on separate threads.
    pub fn bands_mut(&mut self, bands: &[(u32, u32)]) -> Vec<FrameRows<'_>> {
        let width = self.width;
        let (mut color, mut depth, mut primitive) = (
            &mut self.color[..],
            &mut self.depth[..],
            &mut self.primitive[..],
        );
        let mut normal = self.normal.as_deref_mut();
        let mut out = Vec::with_capacity(bands.len());
        let mut row = 0;
        for &(lo, hi) in bands {
            assert_eq!(lo, row, "bands follow one another");
            let n = (hi - lo) as usize * width as usize;
            let (c, rest) = std::mem::take(&mut color).split_at_mut(n);
            color = rest;
            let (d, rest) = std::mem::take(&mut depth).split_at_mut(n);
            depth = rest;
            let (p, rest) = std::mem::take(&mut primitive).split_at_mut(n);
            primitive = rest;
            let nm = match normal.take() {
                Some(all) => {
                    let (a, rest) = all.split_at_mut(n);
                    normal = Some(rest);
                    Some(a)
                }
                None => None,
            };
            out.push(FrameRows {
                width,
                color: c,
                depth: d,
                primitive: p,
                normal: nm,
            });
            row = hi;
        }
        assert_eq!(row, self.height, "bands cover the frame");
        out
    }

    /// The depth test: whether a fragment (z, id) beats what pixel `idx` holds.
    /// Fragments outside the depth range [0, 1] are clipped.
    #[inline(always)]
    pub fn passes(&self, idx: usize, z: f32, id: u32) -> bool {
        depth_test(z, id, self.depth[idx], self.primitive[idx])
    }

    /// Writes a fragment that passed [`FrameBuffer::passes`].
    #[inline(always)]
    pub fn write(&mut self, idx: usize, z: f32, id: u32, rgb: [u8; 3]) {
        self.depth[idx] = z;
        self.primitive[idx] = id;
        self.color[idx] = rgb;
    }

    /// Pixels some primitive wrote.
    pub fn covered(&self) -> usize {
        covered(&self.primitive)
    }

    /// Bytes the frame buffer of a `width` x `height` image with `samples` per pixel holds:
    /// every sample as [`Self::BYTES_PER_PIXEL`], and with more than one sample the resolved
    /// RGB8 image beside them \[bytes\].
    pub fn stored_bytes_sampled(width: u32, height: u32, samples: Samples) -> u64 {
        let n = samples.get();
        let resolved = if n > 1 {
            Self::resolve_bytes_written(width, height)
        } else {
            0
        };
        Self::stored_bytes(width, height * n) + resolved
    }

    /// The RGB8 image a resolve writes \[bytes\].
    fn resolve_bytes_written(width: u32, height: u32) -> u64 {
        width as u64 * height as u64 * std::mem::size_of::<[u8; 3]>() as u64
    }

    /// Bytes the resolve of a `width` x `height` image with `samples` per pixel moves through
    /// the frame-buffer port: every sample's colour read and every pixel's written; none with
    /// one sample (nothing to resolve) \[bytes\].
    pub fn resolve_bytes(width: u32, height: u32, samples: Samples) -> u64 {
        let n = samples.get() as u64;
        match n {
            1 => 0,
            _ => (n + 1) * Self::resolve_bytes_written(width, height),
        }
    }

    /// The image of this sample grid of `samples` per pixel (its rows the sample rows,
    /// [`Samples`]): each pixel's colour the mean of its samples' (a box filter on the stored
    /// linear RGB8, rounded to nearest, halves to even), and its depth, winner and normal its first sample
    /// row's (where the accuracy metrics look, DESIGN.md §6). One sample: the frame itself.
    pub fn resolve(self, samples: Samples) -> FrameBuffer {
        let n = samples.get();
        if n == 1 {
            return self;
        }
        assert_eq!(self.height % n, 0, "a sample grid has whole pixels");
        let (w, h) = (self.width as usize, (self.height / n) as usize);
        let mut out = FrameBuffer::new(self.width, self.height / n, [0; 3], self.normal.is_some());
        for j in 0..h {
            let first = j * n as usize * w;
            for i in 0..w {
                let mut sum = [0u32; 3];
                for s in 0..n as usize {
                    let c = self.color[first + s * w + i];
                    for k in 0..3 {
                        sum[k] += c[k] as u32;
                    }
                }
                let at = j * w + i;
                out.color[at] = sum.map(|c| mean_rounded(c, n));
                out.depth[at] = self.depth[first + i];
                out.primitive[at] = self.primitive[first + i];
                if let (Some(to), Some(from)) = (out.normal.as_mut(), self.normal.as_ref()) {
                    to[at] = from[first + i];
                }
            }
        }
        out
    }

    /// The colour buffer as an `image` RGB8 image.
    pub fn to_image(&self) -> image::RgbImage {
        let raw: Vec<u8> = self.color.iter().flatten().copied().collect();
        image::RgbImage::from_raw(self.width, self.height, raw).expect("buffer matches its size")
    }
}

/// Rows of a frame buffer, written by one ROP: the whole frame, or one band of it.
pub struct FrameRows<'a> {
    width: u32,
    color: &'a mut [[u8; 3]],
    depth: &'a mut [f32],
    primitive: &'a mut [u32],
    normal: Option<&'a mut [[f32; 3]]>,
}

impl FrameRows<'_> {
    /// The index of pixel (i, j) of these rows (j counted from their first).
    #[inline(always)]
    pub fn index(&self, i: u32, j: u32) -> usize {
        j as usize * self.width as usize + i as usize
    }

    /// The index of pixel (i, j) in these rows' planes, if they hold it (the guard of
    /// [`FrameRows::prefetch`]'s addresses).
    #[inline(always)]
    pub fn held(&self, i: u32, j: u32) -> Option<usize> {
        let idx = self.index(i, j);
        (idx < self.depth.len()).then_some(idx)
    }

    /// Asks the cache for the depth and winner of pixel (i, j) (if these rows hold it),
    /// which a depth test will soon read: a drawn primitive's next row of pixels starts a
    /// new 4 KiB row of each plane, where the hardware prefetcher does not follow.
    #[inline(always)]
    pub fn prefetch(&self, i: u32, j: u32) {
        #[cfg(target_arch = "x86_64")]
        if let Some(idx) = self.held(i, j) {
            use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
            // SAFETY: a prefetch is a hint; it reads nothing, and `held` puts the addresses
            // in bounds.
            unsafe {
                _mm_prefetch::<_MM_HINT_T0>(self.depth.as_ptr().add(idx) as *const i8);
                _mm_prefetch::<_MM_HINT_T0>(self.primitive.as_ptr().add(idx) as *const i8);
            }
        }
    }

    /// [`FrameBuffer::passes`] on these rows.
    #[inline(always)]
    pub fn passes(&self, idx: usize, z: f32, id: u32) -> bool {
        depth_test(z, id, self.depth[idx], self.primitive[idx])
    }

    /// [`FrameBuffer::write`] on these rows, with the fragment's normal where normals are
    /// kept.
    #[inline(always)]
    pub fn write(
        &mut self,
        idx: usize,
        z: f32,
        id: u32,
        rgb: [u8; 3],
        normal: impl FnOnce() -> [f32; 3],
    ) {
        self.write_depth(idx, z, id);
        self.write_color(idx, rgb, normal);
    }

    /// The depth and winner of a fragment that passed, written before its colour
    /// ([`Self::write_color`]) when the ROP shades fragments in batches.
    #[inline(always)]
    pub fn write_depth(&mut self, idx: usize, z: f32, id: u32) {
        self.depth[idx] = z;
        self.primitive[idx] = id;
    }

    /// The colour of a fragment whose depth [`Self::write_depth`] wrote, with its normal
    /// where normals are kept.
    #[inline(always)]
    pub fn write_color(&mut self, idx: usize, rgb: [u8; 3], normal: impl FnOnce() -> [f32; 3]) {
        self.color[idx] = rgb;
        if let Some(normals) = self.normal.as_deref_mut() {
            normals[idx] = normal();
        }
    }

    /// Pixels of these rows some primitive wrote.
    pub fn covered(&self) -> usize {
        covered(self.primitive)
    }

    /// Clears these rows as [`FrameBuffer::new`] clears a frame.
    pub fn clear(&mut self, background: [u8; 3]) {
        fill(self.color, background);
        fill(self.depth, 1.0);
        fill(self.primitive, NO_PRIMITIVE);
        if let Some(n) = self.normal.as_deref_mut() {
            fill(n, [0.0; 3]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth_ties_resolve_by_primitive_id_whatever_the_order() {
        let mut a = FrameBuffer::new(1, 1, [0; 3], false);
        let mut b = a.clone();
        for (fb, order) in [
            (&mut a, [(5u32, [1u8; 3]), (3, [2; 3])]),
            (&mut b, [(3, [2; 3]), (5, [1; 3])]),
        ] {
            for (id, rgb) in order {
                if fb.passes(0, 0.5, id) {
                    fb.write(0, 0.5, id, rgb);
                }
            }
        }
        assert_eq!(a.color, b.color);
        assert_eq!(a.primitive[0], 3);
        // A primitive's second fragment at the same depth keeps its first (a tie with itself
        // is no win), so a pixel a lembo covers twice holds what it wrote first.
        assert!(!depth_test(0.5, 3, 0.5, 3));
    }

    /// Each band's rows are the frame's rows lo..hi: what a band writes at its row j lands in
    /// the frame's row lo + j, in every plane; a band's depth test, coverage and clear see
    /// its own rows only, and the image shows each band's colour where it wrote.
    #[test]
    fn bands_are_the_frames_rows_and_the_image_shows_them() {
        let (w, h) = (5, 7);
        let mut fb = FrameBuffer::new(w, h, [0; 3], true);
        let bands = [(0, 2), (2, 3), (3, 7)];
        for (b, mut rows) in fb.bands_mut(&bands).into_iter().enumerate() {
            let (lo, hi) = bands[b];
            let n = ((hi - lo) * w) as usize;
            for j in 0..hi - lo {
                for i in 0..w {
                    let idx = rows.index(i, j);
                    let tag = (lo + j) * w + i;
                    assert!(rows.passes(idx, 0.5, tag));
                    rows.write(idx, 0.5, tag, [b as u8; 3], || [tag as f32; 3]);
                    assert!(!rows.passes(idx, 0.6, tag), "nearer was written");
                }
            }
            assert_eq!(rows.covered(), n);
            if b == 1 {
                // A band cleared is as new, and its neighbours keep what they wrote.
                rows.clear([9; 3]);
                assert_eq!(rows.covered(), 0);
                assert!(rows.passes(rows.index(0, 0), 0.99, 0));
            }
        }
        assert_eq!(fb.covered(), (w * (h - 1)) as usize);
        let image = fb.to_image();
        assert_eq!(image.dimensions(), (w, h));
        for (b, &(lo, hi)) in bands.iter().enumerate() {
            for j in lo..hi {
                if b == 1 {
                    assert!((0..w).all(|i| image.get_pixel(i, j).0 == [9; 3]));
                    assert!((0..w).all(|i| fb.primitive[(j * w + i) as usize] == NO_PRIMITIVE));
                    continue;
                }
                assert!((0..w).all(|i| image.get_pixel(i, j).0 == [b as u8; 3]));
                for i in 0..w {
                    let k = (j * w + i) as usize;
                    assert_eq!(fb.primitive[k], j * w + i, "({i}, {j})");
                    assert_eq!(fb.color[k], [b as u8; 3]);
                    assert_eq!(fb.normal.as_ref().unwrap()[k], [(j * w + i) as f32; 3]);
                }
            }
        }
    }

    #[test]
    fn prefetches_up_to_a_bands_end_and_past_it_form_no_address() {
        // The guard's edge: the band's last pixel is prefetched, one at or past its end is
        // not (run under Miri, `cargo +nightly miri test --lib rop::`, a pointer formed
        // past the end is refused).
        let mut fb = FrameBuffer::new(5, 4, [0; 3], false);
        for rows in fb.bands_mut(&[(0, 2), (2, 4)]) {
            for (i, j) in [(4, 1), (0, 2), (4, 2), (0, 200)] {
                rows.prefetch(i, j);
            }
            assert_eq!(rows.index(4, 1), 9, "the band's last pixel");
            assert_eq!(rows.held(4, 1), Some(9), "the band's last pixel");
            assert_eq!(rows.held(0, 0), Some(0), "the band's first pixel");
            for (i, j) in [(0, 2), (4, 2), (0, 200)] {
                assert_eq!(rows.held(i, j), None, "({i}, {j}) is past the band");
            }
        }
    }

    #[test]
    fn covered_counts_the_pixels_with_a_winner() {
        for len in [0, 1, 7, 8, 9, 100, 1029] {
            let p: Vec<u32> = (0..len as u32)
                .map(|i| if i % 3 == 0 { NO_PRIMITIVE } else { i })
                .collect();
            assert_eq!(
                covered(&p),
                (0..len).filter(|i| i % 3 != 0).count(),
                "{len}"
            );
        }
    }

    #[test]
    fn stored_bytes_count_colour_depth_and_winner_per_pixel() {
        assert_eq!(FrameBuffer::BYTES_PER_PIXEL, 3 + 4 + 4);
        assert_eq!(FrameBuffer::stored_bytes(640, 480), 640 * 480 * 11);
    }

    #[test]
    fn fragments_outside_the_depth_range_are_clipped() {
        let fb = FrameBuffer::new(1, 1, [0; 3], false);
        assert!(!fb.passes(0, -0.01, 0));
        assert!(!fb.passes(0, 1.01, 0));
        assert!(fb.passes(0, 0.99, 0));
    }

    /// A resolve averages each pixel's samples (rounded to nearest) and keeps its first
    /// sample row's depth, winner and normal; one sample is the frame itself.
    #[test]
    fn a_resolve_averages_the_samples_and_keeps_the_first_rows_geometry() {
        let four = Samples::new(4).unwrap();
        let mut grid = FrameBuffer::new(2, 8, [10; 3], true);
        // Pixel (0, 0): samples rows 0..4 of column 0.
        for (s, c) in [[0u8, 0, 0], [255, 0, 0], [255, 255, 0], [255, 255, 1]]
            .iter()
            .enumerate()
        {
            grid.color[s * 2] = *c;
            grid.depth[s * 2] = 0.25 + s as f32;
            grid.primitive[s * 2] = 7 + s as u32;
            grid.normal.as_mut().unwrap()[s * 2] = [s as f32; 3];
        }
        let image = grid.clone().resolve(four);
        assert_eq!((image.width, image.height), (2, 2));
        // Means rounded to nearest, halves to even: 765 / 4 = 191.25 -> 191, 510 / 4 = 127.5
        // -> 128, 1 / 4 -> 0; and below, 3 / 2 = 1.5 -> 2, 5 / 2 = 2.5 -> 2.
        assert_eq!(image.color[0], [191, 128, 0]);
        assert_eq!((image.depth[0], image.primitive[0]), (0.25, 7));
        assert_eq!(image.normal.as_ref().unwrap()[0], [0.0; 3]);
        assert_eq!(image.color[1..], [[10; 3]; 3]);
        assert_eq!(image.primitive[1], NO_PRIMITIVE);
        // Every sample's geometry its index: pixel (i, j) keeps sample (i, 4 j)'s, index
        // 8 j + i (rows of 2 samples), so 0, 1, 8 and 9.
        let mut tagged = grid.clone();
        let normals = tagged.normal.as_mut().unwrap();
        for s in 0..tagged.depth.len() {
            (tagged.depth[s], tagged.primitive[s]) = (s as f32, s as u32);
            normals[s] = [s as f32; 3];
        }
        let image = tagged.resolve(four);
        assert_eq!(image.depth[..], [0.0, 1.0, 8.0, 9.0]);
        assert_eq!(image.primitive[..], [0, 1, 8, 9]);
        assert_eq!(
            image.normal.unwrap()[..],
            [0.0, 1.0, 8.0, 9.0].map(|s| [s; 3])
        );
        assert_eq!(grid.clone().resolve(Samples::ONE).color, grid.color);
        assert_eq!(
            (mean_rounded(3, 2), mean_rounded(5, 2), mean_rounded(7, 2)),
            (2, 2, 4)
        );
        assert_eq!((mean_rounded(2040, 8), mean_rounded(13, 8)), (255, 2));
        assert_eq!(FrameBuffer::resolve_bytes(2, 2, four), 5 * 3 * 4);
        assert_eq!(FrameBuffer::resolve_bytes(2, 2, Samples::ONE), 0);
        assert_eq!(
            FrameBuffer::stored_bytes_sampled(2, 2, four),
            FrameBuffer::stored_bytes(2, 8) + 12
        );
        assert_eq!(
            FrameBuffer::stored_bytes_sampled(2, 2, Samples::ONE),
            FrameBuffer::stored_bytes(2, 2),
            "one sample per pixel: no resolved image beside the samples"
        );
    }
}
