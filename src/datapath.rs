//! The datapath precision of the functional model, and the classes of operation a datapath
//! word does ([`Op`]), which a counting word (`cost::counted::Counted`) tallies.
//!
//! Every stage of the extreme method is written once, generic over [`Real`], and
//! instantiated for `f32` (the default, as a hardware unit would be built) and `f64`
//! (to separate the method's own error from rounding). The reference renderer does not use
//! this trait: it is always `f64`.

use crate::graph::UnitKind;
use num_traits::Float;
use std::fmt::Debug;

/// A floating-point datapath word: `f32` or `f64`.
pub trait Real: Float + Debug + Default + Send + Sync + 'static {
    /// Name used in reports and on the command line.
    const NAME: &'static str;
    /// Whether this word counts its operations (`cost::counted::Counted`): code
    /// that would do extra arithmetic for speed (the ROP's shading in lanes, which computes
    /// both sides of a branch) does the formula as written instead.
    const COUNTS_OPERATIONS: bool = false;
    /// Converts from `f64`, rounding to nearest.
    fn of(x: f64) -> Self;
    /// Widens to `f64` exactly.
    fn f64(self) -> f64;
    /// Charges the operations that follow to the unit kind `kind` (a counting datapath,
    /// `cost::counted::Counted`, keeps per-kind counts; for `f32` and `f64` this is
    /// nothing).
    #[inline(always)]
    fn charge(_kind: UnitKind) {}
    /// Counts `n` operations `op` done beside the datapath words, in fixed point (the
    /// triangle path's edge functions); nothing for `f32` and `f64`.
    #[inline(always)]
    fn count_beside(_op: Op, _n: u64) {}
    /// Counts `n` occurrences of a hardware event ([`Event`]) that a unit priced as built
    /// is charged for per event (`cost::built`); nothing for `f32` and `f64`.
    #[inline(always)]
    fn tally(_event: Event, _n: u64) {}
    /// sqrt(self² + other²) without overflow: [`Float::hypot`], bit for bit.
    #[inline(always)]
    fn length(self, other: Self) -> Self {
        self.hypot(other)
    }
}

impl Real for f32 {
    const NAME: &'static str = "f32";
    #[inline(always)]
    fn of(x: f64) -> Self {
        x as f32
    }
    #[inline(always)]
    fn f64(self) -> f64 {
        self as f64
    }
    /// glibc's `hypotf` inline (sysdeps/ieee754/flt-32/e_hypotf.c): the squares of two
    /// `f32` are exact in `f64` and cannot overflow there, so their sum's square root,
    /// rounded to `f32`, is what the library call returns for finite operands (tested
    /// against it); infinities and NaN go to the library.
    #[inline(always)]
    fn length(self, other: Self) -> Self {
        if !(self.is_finite() && other.is_finite()) {
            return self.hypot(other);
        }
        let (x, y) = (self as f64, other as f64);
        (x * x + y * y).sqrt() as f32
    }
}

impl Real for f64 {
    const NAME: &'static str = "f64";
    #[inline(always)]
    fn of(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn f64(self) -> f64 {
        self
    }
}

/// The classes of datapath operation a unit is charged for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Op {
    /// Addition or subtraction.
    Add,
    /// Multiplication.
    Mul,
    /// Division, remainder or reciprocal.
    Div,
    /// Square root.
    Sqrt,
    /// Comparison (a subtraction whose sign is kept), `min`, `max`.
    Cmp,
    /// Rounding to an integer (`floor`, `ceil`, `round`, `trunc`).
    Round,
    /// Any other function (transcendental); the model never needs one.
    Other,
    /// A fixed-point (integer) addition, subtraction or comparison beside the datapath.
    IntAdd,
    /// A fixed-point (integer) multiplication beside the datapath.
    IntMul,
}

/// Every class, in report order.
pub const OPS: [Op; 9] = [
    Op::Add,
    Op::Mul,
    Op::Div,
    Op::Sqrt,
    Op::Cmp,
    Op::Round,
    Op::Other,
    Op::IntAdd,
    Op::IntMul,
];

impl Op {
    /// The class's name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Op::Add => "add",
            Op::Mul => "mul",
            Op::Div => "div",
            Op::Sqrt => "sqrt",
            Op::Cmp => "cmp",
            Op::Round => "round",
            Op::Other => "other",
            Op::IntAdd => "int_add",
            Op::IntMul => "int_mul",
        }
    }
}

/// The events of the triangle rasterizer's hierarchical walk, as hardware would do it (a
/// counting datapath tallies them, `Real::tally`): the units priced as built are charged
/// per event by `cost::built`, where the model computes differently for exactness.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Event {
    /// A set-up triangle (or a piece of a clipped one) handed to the rasterizer.
    Triangle,
    /// A coarse tile of a triangle's bounding box tested against its three edges.
    Tile,
    /// A 2x2 quad of a tile that was not rejected, its four pixel centres tested.
    QuadTested,
    /// A tested quad with at least one covered pixel centre.
    QuadCovered,
    /// A covered pixel centre: a fragment.
    Fragment,
    /// A covered sample of a multisampled triangle (whose fragments are its samples, and
    /// whose attributes are worked out once a pixel by the ROP that shades it).
    Sample,
}

/// Every event, in the order of `cost::counted::OpTable::events`.
pub const EVENTS: [Event; 6] = [
    Event::Triangle,
    Event::Tile,
    Event::QuadTested,
    Event::QuadCovered,
    Event::Fragment,
    Event::Sample,
];

/// The datapath selected on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Datapath {
    /// IEEE binary32 throughout the extreme method (the default, as hardware).
    #[default]
    F32,
    /// IEEE binary64 throughout the extreme method.
    F64,
}

impl Datapath {
    /// The name used in reports: `f32` or `f64`.
    pub fn name(self) -> &'static str {
        match self {
            Datapath::F32 => f32::NAME,
            Datapath::F64 => f64::NAME,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn f32_length_is_the_library_hypot_bit_for_bit() {
        // Random bit patterns (every exponent, subnormals, both signs) and values of the
        // sizes the extreme method meets, against `f32::hypot` (the C library's `hypotf`).
        let mut rng = crate::testkit::SplitMix64::new(0x9e37_79b9_7f4a_7c15);
        let mut next = || rng.next_u64();
        for n in 0..2_000_000u32 {
            let r = next();
            let (x, y) = if n % 2 == 0 {
                (f32::from_bits(r as u32), f32::from_bits((r >> 32) as u32))
            } else {
                let s = |b: u64| (b % 2_000_001) as f32 / 1000.0 - 1000.0;
                (s(r & 0xffff_ffff), s(r >> 32))
            };
            let (got, want) = (x.length(y), x.hypot(y));
            assert!(
                got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()),
                "length({x:e}, {y:e}) = {got:e}, hypot says {want:e}"
            );
        }
        for (x, y) in [
            (f32::INFINITY, f32::NAN),
            (f32::NAN, 1.0),
            (0.0, -0.0),
            (f32::MAX, f32::MAX),
        ] {
            let (got, want) = (x.length(y), x.hypot(y));
            assert!(got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()));
        }
    }
}
