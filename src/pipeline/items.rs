//! What the links carry: every item type of the unit graph, in dataflow order (the
//! triangle path's set-up triangle is an `Arc<ScreenTriangle>`). A unit declares the item
//! it reads and the item it writes ([`super::unit::Unit`]); the builder creates each
//! boundary's typed links from the producer's output type and refuses a graph whose
//! consumer reads another type.
//!
//! An item is what the simulator passes, which is sometimes less than what the hardware
//! moves: a lembo travels as a [`Piece`], its id and a shared pointer to its screen form,
//! where a hardware Setup would write that form into a parameter buffer the later stages
//! index. The screen form lives as long as an item in flight points at it, so a run holds
//! the set-up lembos in flight, not every lembo of the scene. What the hardware FIFO holds,
//! for its area and energy (DESIGN.md §12), is each producing unit's
//! [`super::unit::Unit::OUT_WORDS`].
//!
//! Every item type is an [`Item`]: what the runtime needs to know of it to dispatch it (an
//! item dispatched by screen tile says where on screen it lies).

use crate::datapath::Real;
use crate::raster::fragment::Span;
use crate::raster::interval::Interval;
use crate::raster::screen::ScreenLembo;
use crate::raster::segmenter::Segment;
use crate::raster::subsegmenter::Subsegment;
use crate::raster::triangle::ScreenTriangle;
use std::sync::Arc;

/// Piece `piece` of lembo `lembo` (piece 0 of a lembo Setup kept whole).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PieceId {
    /// The lembo's id in the scene.
    pub lembo: u32,
    /// The piece's index among those Setup split the lembo into.
    pub piece: u32,
}

/// A set-up lembo piece: its id and its screen form, shared by every item in flight that
/// comes from it and dropped with the last of them.
#[derive(Clone, Debug)]
pub struct Piece<R> {
    /// Which piece of which lembo.
    pub id: PieceId,
    /// Its screen form, as Setup made it.
    pub screen: Arc<ScreenLembo<R>>,
}

/// A set-up lembo piece (Setup to MinMax).
#[derive(Clone, Debug)]
pub struct LemboReady<R> {
    /// The lembo piece.
    pub piece: Piece<R>,
}

/// The scanlines j0..=j1 of a lembo piece (MinMax to the IntervalManager).
#[derive(Clone, Debug)]
pub struct ScanlineRange<R> {
    /// The lembo piece.
    pub piece: Piece<R>,
    /// The first scanline it covers.
    pub j0: u32,
    /// The last scanline it covers.
    pub j1: u32,
}

/// One interval of scanline `j` of a lembo piece (IntervalManager to the Segmenters).
#[derive(Clone, Debug)]
pub struct ScanInterval<R> {
    /// The lembo piece.
    pub piece: Piece<R>,
    /// The scanline.
    pub j: u32,
    /// The piece of the curve Y = y_j to walk.
    pub interval: Interval<R>,
}

/// One chord of scanline `j` of a lembo piece (Segmenter to the Subsegmenters).
#[derive(Clone, Debug)]
pub struct ScanSegment<R> {
    /// The lembo piece.
    pub piece: Piece<R>,
    /// The scanline.
    pub j: u32,
    /// The chord of midpoint error k.
    pub segment: Segment<R>,
}

/// One subsegment of scanline `j` of a lembo piece (Subsegmenter to the FragmentRasterizers).
#[derive(Clone, Debug)]
pub struct ScanSubsegment<R> {
    /// The lembo piece.
    pub piece: Piece<R>,
    /// The scanline.
    pub j: u32,
    /// The piece of the chord along which x is linear.
    pub subsegment: Subsegment<R>,
}

/// Fragments of a lembo piece on scanline `j` inside one ROP tile.
#[derive(Clone, Debug)]
pub struct FragmentSpan<R> {
    /// The lembo piece.
    pub piece: Piece<R>,
    /// The scanline.
    pub j: u32,
    /// The pixels of one subsegment inside one ROP tile.
    pub span: Span<R>,
}

/// The covered pixels of triangle `tri` in rows `j` and `j + 1` inside one ROP tile:
/// `rows[r]` is the half-open column range of row j + r (empty when start >= end).
#[derive(Clone, Debug, PartialEq)]
pub struct TrianglePiece<R> {
    /// The set-up triangle.
    pub tri: Arc<ScreenTriangle<R>>,
    /// The first of the two rows (even).
    pub j: u32,
    /// Each row's half-open column range.
    pub rows: [(u32, u32); 2],
}

impl<R> TrianglePiece<R> {
    /// Fragments in the piece.
    pub fn len(&self) -> u64 {
        self.rows
            .iter()
            .map(|&(a, b)| b.saturating_sub(a) as u64)
            .sum()
    }

    /// Whether the piece holds no fragment.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// What a ROP takes: fragments of a lembo or of a triangle inside one of its tiles (a
/// rasterizer of either path to the ROPs).
#[derive(Clone, Debug)]
pub enum RopItem<R> {
    /// A lembo's span of fragments.
    Lembo(FragmentSpan<R>),
    /// A triangle's piece of two rows.
    Triangle(TrianglePiece<R>),
}

/// A lembo to tessellate on chip (a Tessellator to a DomainEval): its domain triangles are
/// the triangle source's chunk `lembo`, their domain points the lattice of its level.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Patch {
    /// The lembo: the chunk of the triangle source.
    pub lembo: u32,
}

/// One memory transaction: a geometry fetch's batch of primitives (to the setup engine it
/// is dealt to and, with the DRAM model, as a read to the memory controller), or a ROP's
/// frame-buffer traffic for one item (to the memory controller): the bytes the port model
/// moves (`memory.model = "port"`), and with the DRAM model the transfers between its caches
/// and DRAM ([`crate::pipeline::rop_memory`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MemAccess {
    /// Bytes moved: a ROP's depth reads and colour and depth writes, or the primitives'
    /// bytes read \[bytes\].
    pub bytes: u64,
    /// The first primitive read (its index in submission order); 0 for a ROP's traffic.
    pub first: u32,
    /// Primitives read, from `first` on; 0 for a ROP's traffic.
    pub count: u32,
    /// A batch's first byte in the primitives as stored (the bytes read before it); 0 for a
    /// ROP's traffic.
    pub offset: u64,
    transfers: [LineTransfer; MemAccess::CAP],
    len: u8,
}

impl MemAccess {
    /// The transfers one item can carry: a fill and a write-back in each of two caches.
    pub const CAP: usize = 4;

    /// A ROP's traffic of `bytes` through the port, no transfer.
    pub fn frame(bytes: u64) -> Self {
        MemAccess {
            bytes,
            ..MemAccess::default()
        }
    }

    /// A batch of `count` primitives from `first` on, `bytes` read from `offset` on in the
    /// primitives as stored (0 and 0 for one made on chip).
    pub fn batch(first: u32, count: u32, bytes: u64, offset: u64) -> Self {
        MemAccess {
            bytes,
            first,
            count,
            offset,
            ..MemAccess::default()
        }
    }

    /// Whether it is a geometry fetch's batch (else a ROP's traffic).
    pub fn is_geometry(&self) -> bool {
        self.count > 0
    }

    /// Adds a transfer.
    ///
    /// # Panics
    /// When it holds [`Self::CAP`] already (a span makes at most that many).
    pub fn push(&mut self, t: LineTransfer) {
        self.transfers[self.len as usize] = t;
        self.len += 1;
    }

    /// Its transfers.
    pub fn transfers(&self) -> &[LineTransfer] {
        &self.transfers[..self.len as usize]
    }
}

/// A transfer between a ROP cache and DRAM: sectors (bit s) of the line at `addr`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LineTransfer {
    /// The line's first byte in memory.
    pub addr: u64,
    /// The sectors moved.
    pub sectors: u64,
    /// A write-back (else a fill).
    pub write: bool,
}

impl LineTransfer {
    /// Transfer `t` of a surface starting at `base`.
    pub fn at(base: u64, t: crate::memory::tiles::Transfer, write: bool) -> Self {
        LineTransfer {
            addr: base + t.addr,
            sectors: t.sectors,
            write,
        }
    }
}

/// What a link carries, as the runtime dispatches it ([`crate::graph::Dispatch`]).
pub trait Item: Send + 'static {
    /// Whether items of this type say where on screen they lie ([`Item::pixel`]): a
    /// boundary dispatched by screen tile must carry such items (the builder checks it).
    const ON_SCREEN: bool = false;

    /// The item's first pixel (column, row), for an item on screen.
    fn pixel(&self) -> Option<(u32, u32)> {
        None
    }

    /// The primitives the item carries, as a source's items count them for the person
    /// watching the run ([`crate::progress`]); 0 for an item that carries none.
    fn primitives(&self) -> u64 {
        0
    }
}

impl Item for () {}

impl Item for MemAccess {
    fn primitives(&self) -> u64 {
        u64::from(self.count)
    }
}

impl Item for Patch {}
impl<R: Real> Item for LemboReady<R> {}
impl<R: Real> Item for ScanlineRange<R> {}
impl<R: Real> Item for ScanInterval<R> {}
impl<R: Real> Item for ScanSegment<R> {}
impl<R: Real> Item for ScanSubsegment<R> {}
impl<R: Real> Item for Arc<ScreenTriangle<R>> {}

impl<R: Real> RopItem<R> {
    /// The rows it covers, (row, first column, column past the last), an empty row where it
    /// has none (a span has one row).
    pub fn rows(&self) -> [(u32, u32, u32); 2] {
        match self {
            RopItem::Lembo(f) => [(f.j, f.span.i0, f.span.i1), (f.j, 0, 0)],
            RopItem::Triangle(t) => {
                let [(a0, b0), (a1, b1)] = t.rows;
                [(t.j, a0, b0), (t.j + 1, a1, b1)]
            }
        }
    }
}

impl<R: Real> Item for RopItem<R> {
    const ON_SCREEN: bool = true;

    /// A span's first pixel; a triangle piece's first pixel in its first row with any (a
    /// piece lies inside one tile, so any of its pixels names the tile's ROP).
    #[inline]
    fn pixel(&self) -> Option<(u32, u32)> {
        Some(match self {
            RopItem::Lembo(f) => (f.span.i0, f.j),
            RopItem::Triangle(t) => match t.rows {
                [(a, b), _] if a < b => (a, t.j),
                [_, (a, _)] => (a, t.j + 1),
            },
        })
    }
}
