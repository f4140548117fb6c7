//! The functional stage driver: the order in which a path's stages run, written once for
//! every functional run: the single-threaded frame (`render_functional`, `render_lembos`,
//! `render_triangles`), the frame drawn in bands on several host threads
//! (`frame::bands`) and the cost model's counting run (the `cost` module).
//!
//! ```text
//! per primitive, in drawing order:   Setup ─► pieces               (set_up)
//! per piece:                         its rows, or dropped          (set_up)
//! per piece, over the rows asked:    the later stages ─► sink      (draw)
//! ```
//!
//! A path supplies its stage functions ([`Stages`], [`Draw`]): the lembo path
//! ([`LemboPath`](super::lembo_path::LemboPath): Setup, minmax's scanlines, then per scanline
//! the interval manager, segmenter, subsegmenter and fragment rasterizer) and the triangle
//! path ([`TrianglePath`](super::triangle::TrianglePath): triangle setup, its bounding box's
//! rows, then the rasterizer a pair of rows at a time). A caller supplies the rest: which
//! rows (all of a piece's, or a band's), which sink (the ROP, a probe, a sink that charges
//! the ROP's operations to it), the datapath (`f32`, `f64`, or a counting one) and the
//! threads. In a counting datapath each stage function charges its unit kind
//! (`Real::charge`) before its first operation, so every operation is charged to its stage
//! whatever the order the driver interleaves pieces in.
//!
//! All of it is generic, monomorphised per path, datapath and sink: no dynamic dispatch in
//! the loops over pieces, rows and fragments, and the buffers are reused from piece to
//! piece and row to row.

use super::counts::Counts;
use crate::datapath::Real;
use crate::error::{Error, Result};
use std::ops::Range;

/// A path's Setup and its pieces' rows, as the driver runs them.
pub trait Stages<R: Real>: Sync {
    /// A set-up piece: a lembo or a piece of one; a triangle or a piece of a clipped one.
    type Piece: Send + Sync;
    /// What Setup reuses from one primitive to the next.
    type SetupScratch: Default;
    /// What the stages after the rows reuse from one piece to the next.
    type Buffers: Default;

    /// The primitives, in drawing order.
    fn primitives(&self) -> usize;

    /// How many consecutive primitives Setup fetches together (a lembo's triangles are
    /// tessellated together): a run of primitives starting on a multiple of it fetches
    /// nothing twice.
    fn fetched_together(&self) -> usize {
        1
    }

    /// Setup of primitive `n`: its pieces appended to `pieces` (what it holds stays),
    /// counted.
    fn set_up(
        &self,
        n: usize,
        scratch: &mut Self::SetupScratch,
        pieces: &mut Vec<Self::Piece>,
        counts: &mut Counts,
    );

    /// The rows `piece` covers, half-open, or None (counted) when it covers none of the
    /// viewport's.
    fn rows(&self, piece: &Self::Piece, counts: &mut Counts) -> Option<(u32, u32)>;
}

/// A path's stages after the rows, into a sink of type `S`.
pub trait Draw<R: Real, S>: Stages<R> {
    /// Rows `lo..hi` of `piece` (not empty, within its [`Stages::rows`]) through the path's
    /// stages after the rows into `sink`; an error comes with the row it was met on.
    fn draw(
        &self,
        piece: &Self::Piece,
        lo: u32,
        hi: u32,
        sink: &mut S,
        counts: &mut Counts,
        buffers: &mut Self::Buffers,
    ) -> std::result::Result<(), (u32, Error)>;
}

/// A set-up piece with its number in drawing order and its rows (half-open).
pub type Placed<'a, T> = (usize, &'a T, (u32, u32));

/// Setup of the primitives `run`, in order: the pieces of each that cover some row are
/// appended to `pieces` (the others are dropped), each handed with its rows to `keep` as
/// it is kept; all of it counted.
pub fn set_up<R: Real, P: Stages<R>>(
    path: &P,
    run: Range<usize>,
    scratch: &mut P::SetupScratch,
    pieces: &mut Vec<P::Piece>,
    mut keep: impl FnMut(&P::Piece, (u32, u32)),
    counts: &mut Counts,
) {
    for n in run {
        let first = pieces.len();
        path.set_up(n, scratch, pieces, counts);
        // Compacted in place: a kept piece moves down over the dropped ones before it.
        let mut kept = first;
        for at in first..pieces.len() {
            if let Some(rows) = path.rows(&pieces[at], counts) {
                keep(&pieces[at], rows);
                if kept != at {
                    pieces.swap(kept, at);
                }
                kept += 1;
            }
        }
        pieces.truncate(kept);
    }
}

/// The `pieces`, in order, through the stages after the rows into `sink`, each over its
/// rows within `lo..hi`; the first error comes with the (piece, row) it was met at.
pub fn draw<'a, R: Real, S, P: Draw<R, S>>(
    path: &P,
    pieces: impl Iterator<Item = Placed<'a, P::Piece>>,
    (lo, hi): (u32, u32),
    sink: &mut S,
    counts: &mut Counts,
    buffers: &mut P::Buffers,
) -> std::result::Result<(), ((usize, u32), Error)>
where
    P::Piece: 'a,
{
    for (n, piece, (first, end)) in pieces {
        let (a, b) = (first.max(lo), end.min(hi));
        if a < b {
            path.draw(piece, a, b, sink, counts, buffers)
                .map_err(|(j, e)| ((n, j), e))?;
        }
    }
    Ok(())
}

/// Every primitive of `path` in drawing order through every stage into `sink`, one
/// primitive at a time (its pieces drawn while they are fresh): the single-threaded frame
/// and the counting run.
pub fn draw_in_order<R: Real, S, P: Draw<R, S>>(
    path: &P,
    sink: &mut S,
    counts: &mut Counts,
) -> Result<()> {
    let (mut scratch, mut buffers) = (P::SetupScratch::default(), P::Buffers::default());
    let (mut pieces, mut rows) = (Vec::new(), Vec::new());
    crate::progress::add_total(path.primitives() as u64);
    for n in 0..path.primitives() {
        crate::progress::advance(1);
        pieces.clear();
        rows.clear();
        let keep = |_: &P::Piece, r| rows.push(r);
        set_up(path, n..n + 1, &mut scratch, &mut pieces, keep, counts);
        let placed = pieces.iter().zip(&rows).enumerate();
        let placed = placed.map(|(k, (piece, &r))| (k, piece, r));
        draw(path, placed, (0, u32::MAX), sink, counts, &mut buffers).map_err(|(_, e)| e)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    /// What the toy path did, in order: ("set up", primitive, 0, 0), ("rows", primitive,
    /// piece, 0), ("draw", primitive, piece, first row).
    type Log = Mutex<Vec<(&'static str, usize, u32, u32)>>;

    /// A path of `n` primitives: primitive p sets up pieces (p, 0), (p, 1), (p, 2); piece
    /// (p, 1) covers no row, piece (p, k) otherwise rows p..p + k + 1. Drawing row `fail`
    /// fails.
    struct Toy {
        n: usize,
        fail: u32,
        log: Log,
    }

    impl Toy {
        fn new(n: usize, fail: u32) -> Self {
            Toy {
                n,
                fail,
                log: Mutex::new(Vec::new()),
            }
        }

        fn log(&self, what: &'static str, p: usize, k: u32, j: u32) {
            self.log.lock().unwrap().push((what, p, k, j));
        }
    }

    impl Stages<f64> for Toy {
        type Piece = (usize, u32);
        type SetupScratch = usize;
        type Buffers = ();

        fn primitives(&self) -> usize {
            self.n
        }

        fn set_up(
            &self,
            n: usize,
            calls: &mut usize,
            pieces: &mut Vec<(usize, u32)>,
            c: &mut Counts,
        ) {
            *calls += 1;
            c.lembos += 1;
            self.log("set up", n, 0, 0);
            pieces.extend((0..3).map(|k| (n, k)));
        }

        fn rows(&self, &(p, k): &(usize, u32), c: &mut Counts) -> Option<(u32, u32)> {
            self.log("rows", p, k, 0);
            if k == 1 {
                c.lembos_culled_outside += 1;
                return None;
            }
            Some((p as u32, p as u32 + k + 1))
        }
    }

    /// Rows drawn: (primitive, piece, row).
    type Drawn = Vec<(usize, u32, u32)>;

    impl Draw<f64, Drawn> for Toy {
        fn draw(
            &self,
            &(p, k): &(usize, u32),
            lo: u32,
            hi: u32,
            sink: &mut Drawn,
            c: &mut Counts,
            _: &mut (),
        ) -> std::result::Result<(), (u32, Error)> {
            self.log("draw", p, k, lo);
            for j in lo..hi {
                if j == self.fail {
                    let e = Error::SegmentCap {
                        lembo: p,
                        scanline: j,
                        cap: 0,
                    };
                    return Err((j, e));
                }
                c.scanlines += 1;
                sink.push((p, k, j));
            }
            Ok(())
        }
    }

    #[test]
    fn set_up_keeps_the_pieces_that_cover_a_row_in_order_with_their_rows() {
        let toy = Toy::new(4, u32::MAX);
        let (mut calls, mut pieces, mut rows) = (0, vec![(9, 9)], Vec::new());
        let mut counts = Counts::default();
        let keep = |&piece: &(usize, u32), r| rows.push((piece, r));
        set_up(&toy, 1..4, &mut calls, &mut pieces, keep, &mut counts);
        let kept = [(9, 9), (1, 0), (1, 2), (2, 0), (2, 2), (3, 0), (3, 2)];
        assert_eq!(
            pieces, kept,
            "what the vector held stays, the dropped piece goes"
        );
        let spans = [((1, 0), (1, 2)), ((1, 2), (1, 4)), ((2, 0), (2, 3))];
        assert_eq!(rows[..3], spans);
        assert_eq!(rows.len(), 6);
        assert_eq!(
            (calls, counts.lembos, counts.lembos_culled_outside),
            (3, 3, 3)
        );
    }

    #[test]
    fn draw_clips_each_piece_to_the_rows_asked_and_names_the_piece_of_an_error() {
        let toy = Toy::new(0, 5);
        let pieces = [(0, 0), (1, 0), (2, 0), (3, 0), (7, 0)];
        let placed = |lo_rows: [(u32, u32); 5]| {
            pieces
                .iter()
                .zip(lo_rows)
                .enumerate()
                .map(|(n, (piece, r))| (n + 10, piece, r))
                .collect::<Vec<_>>()
        };
        let rows = [(0, 2), (1, 4), (4, 5), (3, 9), (8, 9)];
        let (mut sink, mut counts) = (Drawn::new(), Counts::default());
        let band = draw(
            &toy,
            placed(rows).into_iter(),
            (2, 6),
            &mut sink,
            &mut counts,
            &mut (),
        );
        let Err(((n, j), _)) = band else {
            panic!("row 5 fails: {band:?}");
        };
        // Piece 0 has no row in 2..6; piece 1 draws 2..4, piece 2 row 4, piece 3 rows 3 and 4
        // and fails on 5; piece 4 is not reached.
        assert_eq!((n, j), (13, 5), "the failing piece's place and row");
        let drawn = [(1, 0, 2), (1, 0, 3), (2, 0, 4), (3, 0, 3), (3, 0, 4)];
        assert_eq!(sink, drawn);
        assert_eq!(counts.scanlines, 5);
    }

    #[test]
    fn draw_in_order_draws_each_primitive_after_its_setup_over_all_its_rows() {
        let toy = Toy::new(3, u32::MAX);
        let (mut sink, mut counts) = (Drawn::new(), Counts::default());
        draw_in_order(&toy, &mut sink, &mut counts).unwrap();
        let log = toy.log.into_inner().unwrap();
        let per_primitive = |p| {
            [
                ("set up", p, 0, 0),
                ("rows", p, 0, 0),
                ("rows", p, 1, 0),
                ("rows", p, 2, 0),
                ("draw", p, 0, p as u32),
                ("draw", p, 2, p as u32),
            ]
        };
        assert_eq!(
            log,
            [per_primitive(0), per_primitive(1), per_primitive(2)].concat()
        );
        assert_eq!(sink.len(), 3 * (1 + 3));
        assert_eq!((counts.lembos, counts.scanlines), (3, 12));
        let failing = Toy::new(3, 3);
        let drawn = draw_in_order(&failing, &mut Drawn::new(), &mut Counts::default());
        assert!(
            matches!(
                drawn,
                Err(Error::SegmentCap {
                    lembo: 1,
                    scanline: 3,
                    ..
                })
            ),
            "{drawn:?}"
        );
    }
}
