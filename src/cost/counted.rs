//! Operation counting by the code that does the arithmetic: [`Counted<R>`] is a datapath word
//! that performs exactly `R`'s IEEE operation and adds one to a per-thread counter of that
//! operation's class, charged to the unit kind the driver says is working
//! ([`charge_to`]). Every stage of the extreme method, the ROP's shading and the triangle
//! path's interpolation are generic over [`Real`], so instantiating them with
//! `Counted<f32>` counts what they do without a formula anybody has to keep in step with
//! the code; the pixels are the same bits (`tests/integration/cost.rs`).
//!
//! What is counted as what (DESIGN.md §12): `+ -` an add; `*` a multiply; `/`, `%` and
//! `recip` a divide; `sqrt` a square root; `< <= > >= == !=`, `min`, `max` a compare;
//! `floor`, `ceil`, `round`, `trunc` a rounding (an adder's worth of logic); `powi(n)` its
//! `|n| - 1` multiplies (and a divide when `n < 0`); `mul_add` a multiply and an add;
//! `hypot` two multiplies, an add and a square root. Negation, `abs`, sign and class tests
//! are wiring and are not counted; conversions between the datapath and `f64` (constants,
//! the reports) are not counted. Anything else (`exp`, `ln`, trigonometry) is counted as
//! `other`, which the extreme method never needs (a test says it stays 0).

use crate::camera::take_projections;
use crate::datapath::{Event, Op, Real, EVENTS, OPS};
use crate::graph::{UnitKind, KINDS};
use num_traits::{Float, Num, NumCast, One, ToPrimitive, Zero};
use std::cell::Cell;
use std::cmp::Ordering;
use std::num::FpCategory;
use std::ops::{Add, Div, Mul, Neg, Rem, Sub};

const CELLS: usize = OPS.len() * KINDS.len();

thread_local! {
    static COUNTS: [Cell<u64>; CELLS] = const { [const { Cell::new(0) }; CELLS] };
    static CHARGED: Cell<usize> = const { Cell::new(0) };
    static EVENT_COUNTS: [Cell<u64>; EVENTS.len()] = const { [const { Cell::new(0) }; EVENTS.len()] };
}

/// Charges this thread's following operations to `kind` until the next call; returns the
/// kind charged before, so a caller can restore it.
pub fn charge_to(kind: UnitKind) -> UnitKind {
    count_projections();
    let before = CHARGED.with(|c| c.replace(kind_index(kind)));
    KINDS[before]
}

fn kind_index(kind: UnitKind) -> usize {
    KINDS
        .iter()
        .position(|&k| k == kind)
        .expect("every kind is in KINDS")
}

#[inline(always)]
fn count(op: Op, n: u64) {
    let cell = CHARGED.with(|c| c.get()) * OPS.len() + op as usize;
    COUNTS.with(|c| c[cell].set(c[cell].get() + n));
}

/// Counts the [`View::project`](crate::camera::View::project) calls the camera tallied since the last charge, charged to
/// the kind charged while they ran. One projection is the 4x4 view-projection of (p, 1) (16
/// multiplies, 12 adds), the perspective divide (a reciprocal and 3 multiplies) and the
/// viewport map (5 multiplies, 3 adds). Setup projects in `f64` on the host, as the
/// hardware's would in its datapath; this is the one count taken beside the code rather
/// than by [`Counted`]. Every change of the charged kind and every counting run's start and
/// end take the tally first, so each projection lands where it would have been counted
/// when it ran.
fn count_projections() {
    let n = take_projections();
    if n > 0 {
        count(Op::Mul, 24 * n);
        count(Op::Add, 15 * n);
        count(Op::Div, n);
    }
}

/// Operation counts per unit kind, and the hardware events the run tallied
/// ([`Event`], for the units priced as built: `cost::built`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct OpTable([[u64; OPS.len()]; KINDS.len()], [u64; EVENTS.len()]);

impl OpTable {
    /// The count of `op` charged to `kind`.
    pub fn get(&self, kind: UnitKind, op: Op) -> u64 {
        self.0[kind_index(kind)][op as usize]
    }

    /// Adds `n` operations `op` to `kind` (operations done outside the datapath type, such
    /// as Setup's `f64` view transform, counted by their caller).
    pub fn add(&mut self, kind: UnitKind, op: Op, n: u64) {
        self.0[kind_index(kind)][op as usize] += n;
    }

    /// All of `kind`'s counts, in [`OPS`] order.
    pub fn of(&self, kind: UnitKind) -> [u64; OPS.len()] {
        self.0[kind_index(kind)]
    }

    /// Sets all of `kind`'s counts, in [`OPS`] order (a unit priced as built).
    pub fn set(&mut self, kind: UnitKind, ops: [u64; OPS.len()]) {
        self.0[kind_index(kind)] = ops;
    }

    /// How many times `event` happened.
    pub fn events(&self, event: Event) -> u64 {
        self.1[event as usize]
    }

    /// Adds `n` occurrences of `event`.
    pub fn add_events(&mut self, event: Event, n: u64) {
        self.1[event as usize] += n;
    }
}

/// Runs `f` with this thread's counters from zero, charged first to `first`; returns its
/// result and what it counted. Counters of the caller (a counting run around this one) are
/// restored afterwards, so counting runs nest.
pub fn counting<T>(first: UnitKind, f: impl FnOnce() -> T) -> (T, OpTable) {
    count_projections();
    let saved: Vec<u64> = COUNTS.with(|c| c.iter().map(|x| x.replace(0)).collect());
    let saved_events: Vec<u64> = EVENT_COUNTS.with(|c| c.iter().map(|x| x.replace(0)).collect());
    let before = charge_to(first);
    let out = f();
    charge_to(before);
    let mut table = OpTable::default();
    COUNTS.with(|c| {
        for (i, (cell, old)) in c.iter().zip(saved).enumerate() {
            table.0[i / OPS.len()][i % OPS.len()] = cell.replace(old);
        }
    });
    EVENT_COUNTS.with(|c| {
        for (i, (cell, old)) in c.iter().zip(saved_events).enumerate() {
            table.1[i] = cell.replace(old);
        }
    });
    (out, table)
}

/// A datapath word that counts the operations done on it (see the module docs).
#[derive(Clone, Copy, Debug, Default)]
#[repr(transparent)]
pub struct Counted<R>(pub R);

impl<R: Real> PartialEq for Counted<R> {
    #[inline(always)]
    fn eq(&self, other: &Self) -> bool {
        count(Op::Cmp, 1);
        self.0 == other.0
    }
}

impl<R: Real> Real for Counted<R> {
    const NAME: &'static str = R::NAME;
    const COUNTS_OPERATIONS: bool = true;
    #[inline(always)]
    fn of(x: f64) -> Self {
        Counted(R::of(x))
    }
    #[inline(always)]
    fn f64(self) -> f64 {
        self.0.f64()
    }
    #[inline(always)]
    fn charge(kind: UnitKind) {
        charge_to(kind);
    }
    #[inline(always)]
    fn count_beside(op: Op, n: u64) {
        count(op, n);
    }
    #[inline(always)]
    fn tally(event: Event, n: u64) {
        EVENT_COUNTS.with(|c| {
            let cell = &c[event as usize];
            cell.set(cell.get() + n)
        });
    }
}

macro_rules! binary {
    ($trait:ident, $method:ident, $op:expr) => {
        impl<R: Real> $trait for Counted<R> {
            type Output = Self;
            #[inline(always)]
            fn $method(self, rhs: Self) -> Self {
                count($op, 1);
                Counted(self.0.$method(rhs.0))
            }
        }
    };
}
binary!(Add, add, Op::Add);
binary!(Sub, sub, Op::Add);
binary!(Mul, mul, Op::Mul);
binary!(Div, div, Op::Div);
binary!(Rem, rem, Op::Div);

impl<R: Real> Neg for Counted<R> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Counted(-self.0)
    }
}

impl<R: Real> PartialOrd for Counted<R> {
    #[inline(always)]
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        count(Op::Cmp, 1);
        self.0.partial_cmp(&other.0)
    }
}

impl<R: Real> Zero for Counted<R> {
    fn zero() -> Self {
        Counted(R::zero())
    }
    fn is_zero(&self) -> bool {
        count(Op::Cmp, 1);
        self.0.is_zero()
    }
}

impl<R: Real> One for Counted<R> {
    fn one() -> Self {
        Counted(R::one())
    }
}

impl<R: Real> Num for Counted<R> {
    type FromStrRadixErr = R::FromStrRadixErr;
    fn from_str_radix(s: &str, radix: u32) -> Result<Self, Self::FromStrRadixErr> {
        R::from_str_radix(s, radix).map(Counted)
    }
}

impl<R: Real> ToPrimitive for Counted<R> {
    fn to_i64(&self) -> Option<i64> {
        self.0.to_i64()
    }
    fn to_u64(&self) -> Option<u64> {
        self.0.to_u64()
    }
    fn to_f32(&self) -> Option<f32> {
        self.0.to_f32()
    }
    fn to_f64(&self) -> Option<f64> {
        self.0.to_f64()
    }
}

impl<R: Real> NumCast for Counted<R> {
    fn from<T: ToPrimitive>(n: T) -> Option<Self> {
        <R as NumCast>::from(n).map(Counted)
    }
}

/// Methods that are constants or wiring: not counted.
macro_rules! free {
    ($($name:ident),*) => {$(
        #[inline(always)]
        fn $name() -> Self {
            Counted(R::$name())
        }
    )*};
}
macro_rules! tests {
    ($($name:ident),*) => {$(
        #[inline(always)]
        fn $name(self) -> bool {
            self.0.$name()
        }
    )*};
}
macro_rules! unary {
    ($op:expr; $($name:ident),*) => {$(
        #[inline(always)]
        fn $name(self) -> Self {
            count($op, 1);
            Counted(self.0.$name())
        }
    )*};
}
macro_rules! unary_free {
    ($($name:ident),*) => {$(
        #[inline(always)]
        fn $name(self) -> Self {
            Counted(self.0.$name())
        }
    )*};
}
macro_rules! binary_fn {
    ($op:expr; $($name:ident),*) => {$(
        #[inline(always)]
        fn $name(self, other: Self) -> Self {
            count($op, 1);
            Counted(self.0.$name(other.0))
        }
    )*};
}

impl<R: Real> Float for Counted<R> {
    free!(
        nan,
        infinity,
        neg_infinity,
        neg_zero,
        min_value,
        min_positive_value,
        max_value,
        epsilon
    );
    tests!(
        is_nan,
        is_infinite,
        is_finite,
        is_normal,
        is_sign_positive,
        is_sign_negative
    );
    unary!(Op::Round; floor, ceil, round, trunc);
    unary!(Op::Div; recip);
    unary!(Op::Sqrt; sqrt);
    unary!(Op::Other; exp, exp2, ln, log2, log10, cbrt, sin, cos, tan, asin, acos, atan,
        exp_m1, ln_1p, sinh, cosh, tanh, asinh, acosh, atanh);
    unary_free!(abs, signum);
    binary_fn!(Op::Cmp; max, min);
    binary_fn!(Op::Other; powf, log, atan2);

    fn classify(self) -> FpCategory {
        self.0.classify()
    }
    fn fract(self) -> Self {
        count(Op::Round, 1);
        count(Op::Add, 1);
        Counted(self.0.fract())
    }
    fn mul_add(self, a: Self, b: Self) -> Self {
        count(Op::Mul, 1);
        count(Op::Add, 1);
        Counted(self.0.mul_add(a.0, b.0))
    }
    fn powi(self, n: i32) -> Self {
        count(Op::Mul, n.unsigned_abs().saturating_sub(1) as u64);
        if n < 0 {
            count(Op::Div, 1);
        }
        Counted(self.0.powi(n))
    }
    fn abs_sub(self, other: Self) -> Self {
        count(Op::Add, 1);
        count(Op::Cmp, 1);
        #[allow(deprecated)]
        Counted(self.0.abs_sub(other.0))
    }
    fn hypot(self, other: Self) -> Self {
        count(Op::Mul, 2);
        count(Op::Add, 1);
        count(Op::Sqrt, 1);
        Counted(self.0.hypot(other.0))
    }
    fn sin_cos(self) -> (Self, Self) {
        count(Op::Other, 2);
        let (s, c) = self.0.sin_cos();
        (Counted(s), Counted(c))
    }
    fn integer_decode(self) -> (u64, i16, i8) {
        self.0.integer_decode()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    type C = Counted<f32>;

    #[test]
    fn each_operation_is_counted_once_in_its_class_and_charged_to_the_working_unit() {
        let ((), table) = counting(UnitKind::Segmenter, || {
            let (a, b) = (C::of(3.0), C::of(4.0));
            let c = a * b + a - b; // 1 mul, 2 adds
            let _ = c / b; // 1 div
            let _ = (a * a + b * b).sqrt(); // 2 mul, 1 add, 1 sqrt
            let _ = a < b && a.max(b) == b; // 3 compares
            charge_to(UnitKind::Rop);
            let _ = a.floor() + -b; // 1 round, 1 add; the negation is free
            let _ = a.powi(3); // 2 mul
        });
        let seg = table.of(UnitKind::Segmenter);
        assert_eq!(seg, [3, 3, 1, 1, 3, 0, 0, 0, 0]);
        assert_eq!(table.of(UnitKind::Rop), [1, 2, 0, 0, 0, 1, 0, 0, 0]);
        assert_eq!(table.get(UnitKind::Setup, Op::Mul), 0);
    }

    #[test]
    fn counted_arithmetic_gives_the_same_bits() {
        let xs = [0.1f32, -3.7, 1e-30, 7.25e12, f32::MIN_POSITIVE];
        for &x in &xs {
            for &y in &xs {
                let (a, b) = (Counted(x), Counted(y));
                assert_eq!((a * b + a / b).0.to_bits(), (x * y + x / y).to_bits());
                assert_eq!((a - b).sqrt().0.to_bits(), (x - y).sqrt().to_bits());
            }
        }
    }

    #[test]
    fn counting_runs_nest_and_restore_the_outer_counts() {
        let ((), outer) = counting(UnitKind::Setup, || {
            let _ = C::of(1.0) + C::of(2.0);
            let ((), inner) = counting(UnitKind::MinMax, || {
                let _ = C::of(1.0) * C::of(2.0);
            });
            assert_eq!(inner.get(UnitKind::MinMax, Op::Mul), 1);
            assert_eq!(inner.get(UnitKind::Setup, Op::Add), 0);
            let _ = C::of(1.0) + C::of(2.0);
        });
        assert_eq!(outer.get(UnitKind::Setup, Op::Add), 2);
        assert_eq!(outer.get(UnitKind::MinMax, Op::Mul), 0);
    }

    /// A projection is 24 multiplies, 15 adds and a divide, charged to the kind working when
    /// it ran, also when the kind changes or a nested run starts before anything takes the
    /// camera's tally; projections outside a counting run are in none.
    #[test]
    fn projections_are_charged_to_the_kind_working_when_they_ran() {
        use crate::camera::{Camera, Projection, View, Viewport};
        let view = View::new(
            &Camera {
                eye: [0.0, 0.0, 5.0],
                target: [0.0; 3],
                up: [0.0, 1.0, 0.0],
                projection: Projection::Orthographic {
                    height: 2.0,
                    near: 1.0,
                    far: 10.0,
                },
            },
            Viewport {
                width: 8,
                height: 8,
            },
        );
        let project = || {
            view.project(glam::DVec3::ZERO);
        };
        project();
        let ((), table) = counting(UnitKind::Setup, || {
            project();
            charge_to(UnitKind::TriangleSetup);
            project();
            project();
            let ((), inner) = counting(UnitKind::MinMax, project);
            assert_eq!(inner.of(UnitKind::MinMax)[..3], [15, 24, 1]);
            project();
        });
        assert_eq!(table.of(UnitKind::Setup)[..3], [15, 24, 1]);
        assert_eq!(table.of(UnitKind::TriangleSetup)[..3], [45, 72, 3]);
        assert_eq!(table.of(UnitKind::MinMax), [0; OPS.len()]);
    }
}
