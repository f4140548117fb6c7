//! The screen as the ROPs share it: the tile interleave that says which ROP owns a pixel
//! ([`RopTiles`]; the rasterizers route their output by it), and the one frame buffer every
//! ROP writes its own tiles of in place ([`SharedFrame`], reached through [`RopPixels`]).

use crate::rop::framebuffer::depth_test;
use crate::rop::FrameBuffer;

/// Screen interleaving: tile (tx, ty) of `tile_px` x `tile_px` pixels belongs to ROP
/// (tx + ty) mod Np, so neighbouring tiles, along rows and columns, go to different ROPs.
#[derive(Clone, Debug)]
pub struct RopTiles {
    /// Tile side \[pixels\].
    pub tile_px: u32,
    /// Tiles per row.
    pub tiles_x: u32,
    /// Tiles per column.
    pub tiles_y: u32,
    /// ROPs sharing the screen.
    pub rops: u32,
    /// log2 of `tile_px` and `rops - 1` when they are powers of two (the usual sizes): the
    /// owner of a pixel is then found without a division.
    shift: Option<u32>,
    mask: Option<u32>,
}

impl RopTiles {
    /// The tiles of a `width` x `height` screen over `rops` ROPs.
    pub fn new(width: u32, height: u32, tile_px: u32, rops: u32) -> Self {
        RopTiles {
            tile_px,
            tiles_x: width.div_ceil(tile_px),
            tiles_y: height.div_ceil(tile_px),
            rops,
            shift: tile_px.is_power_of_two().then(|| tile_px.trailing_zeros()),
            mask: rops.is_power_of_two().then(|| rops - 1),
        }
    }

    /// The ROP owning pixel (i, j) and the first pixel column past its tile.
    #[inline]
    pub fn owner(&self, i: u32, j: u32) -> (usize, u32) {
        let (tx, ty) = match self.shift {
            Some(s) => (i >> s, j >> s),
            None => (i / self.tile_px, j / self.tile_px),
        };
        let rop = match self.mask {
            Some(m) => (tx + ty) & m,
            None => (tx + ty) % self.rops,
        };
        (rop as usize, (tx + 1) * self.tile_px)
    }

    /// The first pixel column past the tile holding column `i`: where a rasterizer cuts a
    /// run so that each piece lies in one ROP's tile.
    #[inline]
    pub fn tile_end(&self, i: u32) -> u32 {
        let tx = match self.shift {
            Some(s) => i >> s,
            None => i / self.tile_px,
        };
        (tx + 1) * self.tile_px
    }
}

/// The frame buffer the ROPs write in place, each only the pixels of its own tiles.
///
/// The ROPs run as units of one host thread or of several; a pixel belongs to exactly one
/// ROP ([`RopTiles`]), so no two ROPs ever touch the same pixel and the frame needs no
/// lock and no per-ROP copy. Each ROP reaches it through [`RopPixels`], which checks that
/// every row of pixels it is given lies inside one of its own tiles.
pub struct SharedFrame<'f> {
    depth: *mut f32,
    primitive: *mut u32,
    color: *mut [u8; 3],
    len: usize,
    _frame: std::marker::PhantomData<&'f mut FrameBuffer>,
}

// SAFETY: the pointers come from a `&'f mut FrameBuffer` held for 'f, and every access goes
// through a `RopPixels`, which confines ROP r to the pixels of its own tiles (its type doc:
// runs checked per row, accesses promised inside them, one `RopPixels` a ROP); distinct
// ROPs therefore never access the same element, from any thread. (A prefetch, which any
// unit may ask for, accesses nothing.)
unsafe impl Send for SharedFrame<'_> {}
unsafe impl Sync for SharedFrame<'_> {}

impl<'f> SharedFrame<'f> {
    /// Shares `fb`'s depth, winner and colour planes among the ROPs for `'f`.
    pub fn new(fb: &'f mut FrameBuffer) -> Self {
        SharedFrame {
            depth: fb.depth.as_mut_ptr(),
            primitive: fb.primitive.as_mut_ptr(),
            color: fb.color.as_mut_ptr(),
            len: fb.depth.len(),
            _frame: std::marker::PhantomData,
        }
    }

    /// Asks the cache for the depth and winner at pixel index `idx`, which a ROP will soon
    /// test. A hint: it reads nothing (so any unit may give it for any pixel); an index past
    /// the frame is ignored.
    #[inline(always)]
    pub fn prefetch(&self, idx: usize) {
        #[cfg(target_arch = "x86_64")]
        if idx < self.len {
            use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
            // SAFETY: a prefetch is a hint; it reads nothing and the address is in bounds.
            unsafe {
                _mm_prefetch::<_MM_HINT_T0>(self.depth.add(idx) as *const i8);
                _mm_prefetch::<_MM_HINT_T0>(self.primitive.add(idx) as *const i8);
            }
        }
    }
}

/// ROP `rop`'s access to the pixels of its tiles.
///
/// Two guards make its unsynchronised accesses sound, one checked and one promised:
/// [`Self::row`] admits a run of pixels only inside one of this ROP's tiles (checked, and
/// tested at the tile's and the row's edges), and every access is to a pixel of a run it
/// admitted (the `unsafe` accessors' promise); [`Self::new`] promises one `RopPixels` per
/// ROP. So no two of them reach the same pixel, from any thread.
pub struct RopPixels<'a, 'f> {
    frame: &'a SharedFrame<'f>,
    tiles: &'a RopTiles,
    rop: usize,
    width: usize,
}

impl<'a, 'f> RopPixels<'a, 'f> {
    /// ROP `rop`'s pixels of `frame`, `width` pixels a row.
    ///
    /// # Safety
    /// While it lives, no other `RopPixels` of `frame` is for ROP `rop` or uses other
    /// `tiles`, and `width` is the frame's: the ROPs' pixels are then disjoint.
    pub unsafe fn new(
        frame: &'a SharedFrame<'f>,
        tiles: &'a RopTiles,
        rop: usize,
        width: u32,
    ) -> Self {
        RopPixels {
            frame,
            tiles,
            rop,
            width: width as usize,
        }
    }

    /// The index of pixel (0, j): pixels i0..i1 of row j are `row + i`. Panics unless the
    /// run lies inside one tile of this ROP (the rasterizers cut their output at tile
    /// borders) and inside the row (a frame's last column of tiles may reach past its
    /// width), which is what makes the unsynchronised writes sound.
    #[inline]
    pub fn row(&self, i0: u32, i1: u32, j: u32) -> usize {
        let (owner, tile_end) = self.tiles.owner(i0, j);
        assert!(
            owner == self.rop && i1 <= tile_end && i0 < i1 && i1 as usize <= self.width,
            "ROP {} given pixels {i0}..{i1} of row {j}",
            self.rop
        );
        let row = j as usize * self.width;
        assert!(row + (i1 as usize) <= self.frame.len);
        row
    }

    /// Asks the cache for the depth and winner at pixel index `idx` (usually the pixel
    /// below a span, which the primitive's next row will test): [`SharedFrame::prefetch`].
    #[inline(always)]
    pub fn prefetch(&self, idx: usize) {
        self.frame.prefetch(idx);
    }

    /// Pixels a row.
    #[inline(always)]
    pub fn width(&self) -> usize {
        self.width
    }

    /// The depth at pixel index `idx`.
    ///
    /// # Safety
    /// `idx` is a pixel of a run [`Self::row`] admitted (`row + i`, i in i0..i1).
    #[inline(always)]
    pub unsafe fn depth(&self, idx: usize) -> f32 {
        // SAFETY: idx is a pixel `row` admitted: in the frame, and this ROP's alone.
        unsafe { *self.frame.depth.add(idx) }
    }

    /// The winning primitive at pixel index `idx`.
    ///
    /// # Safety
    /// As for [`Self::depth`].
    #[inline(always)]
    pub unsafe fn primitive(&self, idx: usize) -> u32 {
        // SAFETY: as for `depth`.
        unsafe { *self.frame.primitive.add(idx) }
    }

    /// Writes depth `z` and winner `id` at pixel index `idx`.
    ///
    /// # Safety
    /// As for [`Self::depth`].
    #[inline(always)]
    pub unsafe fn set_depth(&mut self, idx: usize, z: f32, id: u32) {
        // SAFETY: as for `depth`; `&mut self` keeps one writer per ROP.
        unsafe {
            *self.frame.depth.add(idx) = z;
            *self.frame.primitive.add(idx) = id;
        }
    }

    /// The depth test of fragment (z, id) at pixel index `idx`, and its depth and winner
    /// written when it passes; whether it passed.
    ///
    /// # Safety
    /// As for [`Self::depth`].
    #[inline(always)]
    pub unsafe fn test_depth(&mut self, idx: usize, z: f32, id: u32) -> bool {
        // SAFETY: the caller's promise, passed on.
        unsafe {
            let pass = depth_test(z, id, self.depth(idx), self.primitive(idx));
            if pass {
                self.set_depth(idx, z, id);
            }
            pass
        }
    }

    /// Whether pixel (i, j) lies in one of this ROP's tiles.
    pub fn owns(&self, i: u32, j: u32) -> bool {
        self.tiles.owner(i, j).0 == self.rop
    }

    /// The colour at pixel index `idx`.
    ///
    /// # Safety
    /// As for [`Self::depth`].
    #[inline(always)]
    pub unsafe fn color(&self, idx: usize) -> [u8; 3] {
        // SAFETY: as for `depth`.
        unsafe { *self.frame.color.add(idx) }
    }

    /// Writes colour `rgb` at pixel index `idx`.
    ///
    /// # Safety
    /// As for [`Self::depth`].
    #[inline(always)]
    pub unsafe fn set_color(&mut self, idx: usize, rgb: [u8; 3]) {
        // SAFETY: as for `depth`; `&mut self` keeps one writer per ROP.
        unsafe { *self.frame.color.add(idx) = rgb };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 20 x 12 frame in 8-pixel tiles over two ROPs: tile (tx, ty) is ROP (tx + ty) mod 2,
    /// and its last column of tiles (16..24) reaches past the width.
    fn frame() -> (FrameBuffer, RopTiles) {
        (
            FrameBuffer::new(20, 12, [0; 3], false),
            RopTiles::new(20, 12, 8, 2),
        )
    }

    /// Whether ROP `rop` may be given pixels `i0..i1` of row `j`.
    fn given(rop: usize, i0: u32, i1: u32, j: u32) -> bool {
        let (mut fb, tiles) = frame();
        let shared = SharedFrame::new(&mut fb);
        // SAFETY: the only RopPixels of this frame, over its tiles and width.
        let pixels = unsafe { RopPixels::new(&shared, &tiles, rop, 20) };
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| pixels.row(i0, i1, j))).is_ok()
    }

    #[test]
    fn a_rop_is_given_runs_inside_its_own_tiles_and_the_row_only() {
        // A whole tile, and one pixel past its end.
        assert!(given(0, 0, 8, 0));
        assert!(!given(0, 0, 9, 0));
        // Another ROP's tile.
        assert!(given(1, 8, 16, 0) && !given(0, 8, 16, 0));
        // The last column of tiles ends at the width, not at the tile's end.
        assert!(given(0, 16, 20, 0) && !given(0, 16, 21, 0));
        // The frame's last pixel, and an empty run.
        assert!(given(1, 16, 20, 11));
        assert!(!given(0, 3, 3, 0));
    }

    #[test]
    fn a_rops_reads_and_writes_land_on_the_frames_pixels() {
        let (mut fb, tiles) = frame();
        {
            let shared = SharedFrame::new(&mut fb);
            // SAFETY: the only RopPixels of this frame, over its tiles and width.
            let mut pixels = unsafe { RopPixels::new(&shared, &tiles, 1, 20) };
            // The frame's last pixel, (19, 11).
            let idx = pixels.row(16, 20, 11) + 19;
            assert_eq!(idx, 20 * 12 - 1);
            // SAFETY: idx is in the run `row` admitted just above.
            unsafe {
                assert!(pixels.test_depth(idx, 0.5, 7));
                assert!(!pixels.test_depth(idx, 0.75, 3));
                pixels.set_color(idx, [1, 2, 3]);
                assert_eq!((pixels.depth(idx), pixels.primitive(idx)), (0.5, 7));
                assert_eq!(pixels.color(idx), [1, 2, 3]);
            }
            // Prefetches at the frame's end and past it are hints, never addresses formed.
            for idx in [idx, idx + 1, idx + 1000] {
                pixels.prefetch(idx);
            }
        }
        assert_eq!(fb.depth[20 * 12 - 1], 0.5);
        assert_eq!(fb.primitive[20 * 12 - 1], 7);
        assert_eq!(fb.color[20 * 12 - 1], [1, 2, 3]);
        assert_eq!(fb.depth[20 * 12 - 2], 1.0);
    }
}
