//! One functional frame on several host threads (`--threads N`), bit-identical to the
//! single-threaded render for every N.
//!
//! The frame's rows are cut into bands of an even number of rows (so no 2x2 quad straddles
//! two), more bands than threads so that rayon can balance uneven ones. Setup runs once, in
//! primitive order, keeping every set-up piece with its rows (lembos: minmax's scanline range;
//! triangles: the bounding box); each band is handed the pieces that meet its rows, in the
//! same order (`Pieces::by_band`), and walks them through the scan-line stages of its own
//! rows only, into its own rows of the frame buffer (`FrameBuffer::bands_mut`, `Rop::band`),
//! which its thread also clears. Every stage after setup works on one scanline (one row pair
//! for a quad) and a pixel is only ever written by fragments of its own row, so each pixel
//! meets the same fragments in the same order as in the single-threaded render: the same
//! depth tests, the same shading, the same winner. The counts are setup's plus the sum of the
//! bands' (each counts only its rows, covered pixels included), and equal the
//! single-threaded ones; the first error (a segment cap) is the smallest (piece, scanline)
//! any band met, the one the single-threaded walk meets first.
//!
//! The analysed frame (`--reference`, with the fragment probe) and the counting runs of the
//! cost model stay single-threaded.

use super::setup::ScreenLembo;
use super::triangle::{rasterize_rows, setup as setup_triangle, ScreenTriangle, TriangleSource};
use super::{
    scanline_range, scanlines, set_up, Buffers, Counts, Frame, Tolerance, DEFAULT_SEGMENT_CAP,
};
use crate::camera::View;
use crate::datapath::Real;
use crate::error::{Error, Result};
use crate::rop::framebuffer::FrameRows;
use crate::rop::{FrameBuffer, Rop};
use crate::scene::Scene;
use rayon::prelude::*;

/// Bands per thread: enough for rayon to even out bands of unequal work.
const BANDS_PER_THREAD: u32 = 8;

/// The bands of a frame `height` rows high for `threads` threads: half-open row ranges,
/// each starting on an even row, in order, covering every row.
pub fn bands(height: u32, threads: u32) -> Vec<(u32, u32)> {
    let pairs = height.div_ceil(2).max(1);
    let count = (threads.max(1) * BANDS_PER_THREAD).min(pairs);
    (0..count)
        .map(|b| {
            let lo = 2 * (pairs * b / count);
            let hi = (2 * (pairs * (b + 1) / count)).min(height);
            (lo, hi)
        })
        .filter(|(lo, hi)| lo < hi)
        .collect()
}

/// Most primitives per setup task.
const SETUP_CHUNK: usize = 64;

/// A set-up lembo piece with its first and last scanline (minmax).
type Piece<R> = (ScreenLembo<R>, u32, u32);

/// A lembo of the scene with its colour.
type SceneLembo<'a> = (&'a crate::lembo::Lembo, [f64; 3]);

/// The pieces of the scene's `lembos` after setup and minmax, in order, with their rows and
/// what setup counted; set up in chunks on the current rayon pool, joined in order.
fn lembo_pieces<R: Real>(
    lembos: &[SceneLembo<'_>],
    view: &View,
    tol: Tolerance,
) -> (Pieces<Piece<R>>, Counts) {
    // Up to SETUP_CHUNK lembos a task, fewer where there are few (a lembo's setup may split
    // it into many pieces), so that every thread gets some.
    let size = lembos
        .len()
        .div_ceil(rayon::current_num_threads() * BANDS_PER_THREAD as usize)
        .clamp(1, SETUP_CHUNK);
    let chunks: Vec<(Vec<Piece<R>>, Counts)> = lembos
        .par_chunks(size)
        .enumerate()
        .map(|(c, chunk)| {
            let (mut out, mut counts) = (Vec::with_capacity(chunk.len()), Counts::default());
            let mut pieces = Vec::new();
            for (k, (lembo, color)) in chunk.iter().enumerate() {
                let id = (c * size + k) as u32;
                set_up(id, lembo, *color, view, tol, &mut pieces, &mut counts);
                for l in pieces.drain(..) {
                    if let Some((j0, j1)) = scanline_range(&l, view.viewport.height, &mut counts) {
                        out.push((l, j0, j1));
                    }
                }
            }
            (out, counts)
        })
        .collect();
    let mut counts = Counts::default();
    let pieces = join_in_order(chunks, &mut counts);
    (pieces, counts)
}

/// The setup tasks' pieces in task order, their counts added to `counts`. The tasks' own
/// vectors are kept as they are (copying a few megabytes of set-up lembos into one vector
/// would be serial work between setup and the bands).
fn join_in_order<T>(tasks: Vec<(Vec<T>, Counts)>, counts: &mut Counts) -> Pieces<T> {
    let mut out = Vec::with_capacity(tasks.len());
    for (pieces, c) in tasks {
        out.push(pieces);
        *counts += c;
    }
    Pieces(out)
}

/// Set-up pieces in drawing order, as the setup tasks left them: one vector a task.
struct Pieces<T>(Vec<Vec<T>>);

impl<T> Pieces<T> {
    /// For each band of `bands` (in order, following one another), the pieces whose rows
    /// `rows(piece)` (half-open) meet it, in drawing order, with their index in that order.
    /// A band walks only its own pieces (a frame of small lembos has thousands, and each
    /// band would otherwise look at every one).
    fn by_band(
        &self,
        bands: &[(u32, u32)],
        rows: impl Fn(&T) -> (u32, u32),
    ) -> Vec<Vec<(usize, &T)>> {
        let mut out = vec![Vec::new(); bands.len()];
        for (n, piece) in self.0.iter().flatten().enumerate() {
            let (r0, r1) = rows(piece);
            let first = bands.partition_point(|&(_, hi)| hi <= r0);
            for (b, &(lo, _)) in bands.iter().enumerate().skip(first) {
                if lo >= r1 {
                    break;
                }
                out[b].push((n, piece));
            }
        }
        out
    }
}

/// The set-up pieces of a triangle source, in order; set up in chunks of the source on the
/// current rayon pool, joined in order.
fn triangle_pieces<R: Real>(
    source: &dyn TriangleSource,
    view: &View,
    counts: &mut Counts,
) -> Pieces<ScreenTriangle<R>> {
    // A task takes a run of the source's chunks (a chunk may be one lembo's few triangles),
    // so its buffers are reused across them.
    let per_task = SETUP_CHUNK.div_ceil(source.per_chunk().max(1) as usize);
    let tasks = source.chunks().div_ceil(per_task);
    let chunks: Vec<(Vec<ScreenTriangle<R>>, Counts)> = (0..tasks)
        .into_par_iter()
        .map(|task| {
            let (mut out, mut counts) = (Vec::new(), Counts::default());
            let (mut triangles, mut set_up) = (Vec::new(), Vec::new());
            for c in task * per_task..((task + 1) * per_task).min(source.chunks()) {
                source.chunk(c, &mut triangles);
                for (k, t) in triangles.iter().enumerate() {
                    let id = source.id(c, k);
                    setup_triangle::<R>(id, &t.positions, &t.normals, t.color, view, &mut set_up)
                        .count(&mut counts);
                    out.append(&mut set_up);
                }
            }
            (out, counts)
        })
        .collect();
    join_in_order(chunks, counts)
}

/// What one band drew: its counts, its passed depth tests and covered pixels
/// ([`Rop::finish`]); or the first error it met with the (piece, scanline) it met it at.
type Band = std::result::Result<(Counts, (u64, u64)), ((usize, u32), Error)>;

/// Runs `draw(b, lo, hi, rows)` for every band `b` (rows `lo..hi`) of `bands` on the
/// current rayon pool, each into its own rows of one frame buffer (cleared by the band's
/// thread), and adds the bands' counts to setup's `counts`: the frame, or the first error
/// any band met.
fn in_bands(
    scene: &Scene,
    view: &View,
    bands: &[(u32, u32)],
    mut counts: Counts,
    draw: impl Fn(usize, u32, u32, FrameRows<'_>) -> Band + Sync,
) -> Result<Frame> {
    let vp = view.viewport;
    let background = scene.background.map(crate::rop::shade::to_u8::<f64>);
    let mut framebuffer = FrameBuffer::zeroed(vp.width, vp.height);
    let drawn: Vec<Band> = framebuffer
        .bands_mut(bands)
        .into_par_iter()
        .zip(bands.par_iter())
        .enumerate()
        .map(|(b, (mut rows, &(lo, hi)))| {
            rows.clear(background);
            draw(b, lo, hi, rows)
        })
        .collect();
    let mut first_error: Option<((usize, u32), Error)> = None;
    let (mut passed, mut covered) = (0, 0);
    for band in drawn {
        match band {
            Ok((c, (p, n))) => {
                counts += c;
                passed += p;
                covered += n;
            }
            Err((at, e)) => {
                if first_error.as_ref().is_none_or(|(first, _)| at < *first) {
                    first_error = Some((at, e));
                }
            }
        }
    }
    if let Some((_, e)) = first_error {
        return Err(e);
    }
    counts.fragments_passed_depth = passed;
    counts.pixels_covered = covered;
    Ok(Frame {
        framebuffer,
        counts,
        probe: None,
    })
}

/// A rayon pool of `threads` threads for one frame.
fn pool(threads: u32) -> Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads as usize)
        .thread_name(|i| format!("frame-{i}"))
        .build()
        .map_err(|e| Error::Internal(format!("cannot start the frame's threads: {e}")))
}

/// The lembo path's functional frame on `threads` threads (module doc).
pub fn render_lembos_in_bands<R: Real>(
    scene: &Scene,
    view: &View,
    tol: Tolerance,
    threads: u32,
) -> Result<Frame> {
    pool(threads)?.install(|| {
        let lembos: Vec<SceneLembo<'_>> = scene.lembos().collect();
        let (pieces, counts) = lembo_pieces::<R>(&lembos, view, tol);
        let k = R::of(tol.k);
        let (width, height) = (view.viewport.width, view.viewport.height);
        let bands = bands(height, threads);
        let by_band = pieces.by_band(&bands, |&(_, j0, j1)| (j0, j1 + 1));
        in_bands(scene, view, &bands, counts, |b, lo, hi, rows| {
            let mut rop = Rop::<R>::band(rows, &scene.light, view, lo);
            let mut c = Counts::default();
            let mut buffers = Buffers::default();
            for &(n, (l, j0, j1)) in &by_band[b] {
                scanlines(
                    l,
                    (*j0).max(lo),
                    (*j1).min(hi - 1),
                    width,
                    k,
                    DEFAULT_SEGMENT_CAP,
                    &mut rop,
                    &mut c,
                    &mut buffers,
                )
                .map_err(|(j, e)| ((n, j), e))?;
            }
            Ok((c, rop.finish()))
        })
    })
}

/// The triangle path's functional frame on `threads` threads (module doc).
pub fn render_triangles_in_bands<R: Real>(
    scene: &Scene,
    view: &View,
    source: &dyn TriangleSource,
    threads: u32,
) -> Result<Frame> {
    pool(threads)?.install(|| {
        let mut counts = Counts::default();
        let pieces = triangle_pieces::<R>(source, view, &mut counts);
        let vp = view.viewport;
        let bands = bands(vp.height, threads);
        let by_band = pieces.by_band(&bands, |t| (t.bbox[2], t.bbox[3]));
        in_bands(scene, view, &bands, counts, |b, lo, hi, rows| {
            let mut rop = Rop::<R>::band(rows, &scene.light, view, lo);
            let mut c = Counts::default();
            for &(_, t) in &by_band[b] {
                rasterize_rows(t, lo, hi, &mut rop, &mut c);
            }
            Ok((c, rop.finish()))
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_band_gets_the_pieces_that_meet_its_rows_in_order() {
        let bands = [(0, 4), (4, 8), (8, 10)];
        // Pieces as half-open row ranges, over two setup tasks.
        let pieces = Pieces(vec![
            vec![(0, 1), (3, 5), (9, 10)],
            vec![(0, 10), (4, 4), (7, 8)],
        ]);
        let got: Vec<Vec<usize>> = pieces
            .by_band(&bands, |&r| r)
            .iter()
            .map(|b| b.iter().map(|&(n, _)| n).collect())
            .collect();
        let want: Vec<Vec<usize>> = bands
            .iter()
            .map(|&(lo, hi)| {
                pieces
                    .0
                    .iter()
                    .flatten()
                    .enumerate()
                    .filter(|(_, &(r0, r1))| r0 < hi && lo < r1)
                    .map(|(n, _)| n)
                    .collect()
            })
            .collect();
        assert_eq!(got, want);
        assert_eq!(got, vec![vec![0, 1, 3], vec![1, 3, 5], vec![2, 3]]);
    }

    #[test]
    fn bands_cover_every_row_once_from_even_rows() {
        for height in [1, 2, 3, 7, 64, 511, 512, 1024] {
            for threads in [1, 2, 3, 16] {
                let b = bands(height, threads);
                assert_eq!(b[0].0, 0);
                assert_eq!(b.last().unwrap().1, height);
                for w in b.windows(2) {
                    assert_eq!(w[0].1, w[1].0);
                }
                assert!(b.iter().all(|(lo, hi)| lo % 2 == 0 && lo < hi));
            }
        }
    }
}
