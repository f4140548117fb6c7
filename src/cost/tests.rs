//! Tests that count a stage's operations with the counting word ([`super::counted`]): the
//! hand-worked counts of MinMax, the fragment rasterizer and the blend ALU, and that
//! counting changes no bit of a blend. They name the stages, which sit below the cost
//! module, so they live here rather than beside the stages.

use super::counted::{counting, Counted};
use crate::datapath::{Op, Real, OPS};
use crate::discoid::blend::tests::{frag, stream};
use crate::discoid::blend::{Accum, BlendMode};
use crate::graph::UnitKind;
use crate::raster::fragment::{rasterize, Columns};
use crate::raster::interval::{ConicPoint, INTERIOR};
use crate::raster::minmax::y_range;
use crate::raster::screen::Partition;
use crate::raster::setup::tests::{screen_lembo, x_linear, y_bowl, y_plane, Collect, SIDE};
use crate::raster::subsegmenter::Subsegment;
use crate::raster::Counts;
use crate::testkit::SplitMix64;

/// The operation counts of a hand-worked subsegment of n fragments: the span's setup
/// (order the ends: a compare; dx: an add and a compare; each end's pixel: an add, a
/// ceil and a clamp compare; the empty test: a compare; du/dx and dv/dx: an add and a
/// divide each; the first centre's offset: 2 adds; u and v there: a multiply and an add
/// each), then per fragment the depth quadratic in Horner form (5 multiplies, 5 adds)
/// and the two increments (2 adds).
#[test]
fn fragment_counts_what_a_hand_worked_subsegment_costs() {
    type C = Counted<f64>;
    let l = screen_lembo::<C>(x_linear(), y_plane());
    let p = |x: f64| ConicPoint {
        uv: [C::of(0.2), C::of(0.3)],
        x: C::of(x),
        edge: INTERIOR,
    };
    for (x0, x1, n) in [(10.5, 12.5, 2u64), (3.2, 9.9, 7)] {
        let s = Subsegment { a: p(x1), b: p(x0) };
        let (mut sink, mut counts) = (Collect::default(), Counts::default());
        let ((), ops) = counting(UnitKind::FragmentRasterizer, || {
            rasterize(&l, 7, &s, Columns::plain(SIDE), &mut sink, &mut counts)
        });
        assert_eq!(counts.fragments, n);
        let got = [Op::Add, Op::Mul, Op::Div, Op::Cmp, Op::Round, Op::Sqrt]
            .map(|op| ops.get(UnitKind::FragmentRasterizer, op));
        assert_eq!(got, [9 + 7 * n, 2 + 5 * n, 2, 5, 2, 0], "{n} fragments");
    }
}

/// The operation counts of a hand-worked lembo, the bowl: its three edge extrema and the
/// diagonal's are inside the domain, so each candidate costs its own arithmetic, the
/// domain test (3 compares and an add), an evaluation in Horner form (5 multiplies, 5
/// adds) and the running min and max (2 compares); the vertices' min and max cost 4
/// compares. Candidates: -d / 2a (a multiply, a divide), -e / 2b (the same), the
/// diagonal's uc (2 multiplies, 5 adds, a divide) with 1 - uc (an add), and the interior
/// centre of a central partition (given by Setup).
#[test]
fn minmax_counts_what_a_hand_worked_lembo_costs() {
    let l = screen_lembo::<Counted<f64>>(x_linear(), y_bowl());
    let (_, ops) = counting(UnitKind::MinMax, || y_range(&l));
    let central = matches!(l.partition, Partition::Central { .. }) as u64;
    let candidate = |mul: u64, add: u64, div: u64| [mul + 5, add + 6, div, 5];
    let sum = [
        candidate(1, 0, 1),
        candidate(1, 0, 1),
        candidate(2, 6, 1),
        candidate(0, 0, 0).map(|x| x * central),
    ]
    .iter()
    .fold([0, 0, 0, 4], |a, c| {
        [a[0] + c[0], a[1] + c[1], a[2] + c[2], a[3] + c[3]]
    });
    let got = [Op::Mul, Op::Add, Op::Div, Op::Cmp].map(|op| ops.get(UnitKind::MinMax, op));
    assert_eq!(got, sum, "central partition: {central}");
    let others: u64 = OPS
        .iter()
        .filter(|op| ![Op::Mul, Op::Add, Op::Div, Op::Cmp].contains(op))
        .map(|&op| ops.get(UnitKind::MinMax, op))
        .sum();
    assert_eq!(others, 0);
    assert_eq!(ops.of(UnitKind::Setup), [0; OPS.len()]);
}

/// Counted per fragment, as the module doc says: a float mode's zero test of β, its
/// S_old + β and two averages of two multiplies, an add and a divide each; rgba8 the
/// same averages (its S_new is the nibble adds') and five integer operations: the
/// code's zero test, two saturating nibble adds, two Σβ recombinations. A β that
/// changes nothing costs its zero test. The resolve's Σβ test is a compare, or in
/// rgba8 a recombination and an integer test.
#[test]
fn the_blend_alu_counts_equation_5_per_mode() {
    use UnitKind::BlendUnit;
    type C = Counted<f32>;
    let f = frag(0.5, 0.25, 0.75);
    for (mode, blend, resolve) in [
        (
            BlendMode::F32,
            [3, 4, 2, 0, 1, 0, 0, 0, 0],
            [0, 0, 0, 0, 1, 0, 0, 0, 0],
        ),
        (
            BlendMode::F16,
            [3, 4, 2, 0, 1, 0, 0, 0, 0],
            [0, 0, 0, 0, 1, 0, 0, 0, 0],
        ),
        (
            BlendMode::Rgba8,
            [2, 4, 2, 0, 0, 0, 0, 5, 0],
            [0, 0, 0, 0, 0, 0, 0, 2, 0],
        ),
    ] {
        let mut px = Accum::default();
        let (_, ops) = counting(BlendUnit, || mode.blend_in::<C>(&mut px, f));
        assert_eq!(ops.of(BlendUnit), blend, "{mode:?} blend");
        let (r, ops) = counting(BlendUnit, || mode.resolve_in::<C>(&px));
        assert!(r.is_some());
        assert_eq!(ops.of(BlendUnit), resolve, "{mode:?} resolve");
        let (_, ops) = counting(BlendUnit, || {
            mode.blend_in::<C>(&mut px, frag(0.0, 1.0, 1.0))
        });
        let zero_test = if mode == BlendMode::Rgba8 { 7 } else { 4 };
        assert_eq!(ops.of(BlendUnit).iter().sum::<u64>(), 1, "{mode:?}");
        assert_eq!(ops.of(BlendUnit)[zero_test], 1, "{mode:?}");
    }
}

/// The counting word blends and resolves every mode to the same bits.
#[test]
fn counting_the_blend_changes_no_bit() {
    let mut rng = SplitMix64::new(0x5eed_0003);
    for _ in 0..5_000 {
        let frags = stream(&mut rng);
        for mode in BlendMode::ALL {
            let (plain, counted) = (&mut Accum::default(), &mut Accum::default());
            for &f in &frags {
                let a = mode.blend(plain, f);
                let b = mode.blend_in::<Counted<f32>>(counted, f);
                assert_eq!((a, *plain), (b, *counted), "{mode:?}");
            }
            assert_eq!(
                mode.resolve(plain),
                mode.resolve_in::<Counted<f32>>(counted)
            );
        }
    }
}
