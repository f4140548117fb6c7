//! The three passes of the atlas of discoids (Piranda et al. 2006 section 3, DESIGN.md §4) in the
//! functional model.
//!
//! 1. **Depth**: every discoid fragment with beta > 0 that faces the eye writes the nearest
//!    depth (visibility splatting); no colour.
//! 2. **Accumulation**: fragments that face away from the eye are culled, fragments with
//!    beta = 0 discarded, and fragments farther than the threshold t behind the depth pass's
//!    surface (`linear_depth(z) > linear_depth(depth) + t`, t in world units along the view
//!    direction) discarded; the rest are blended by the ROP blend unit of the chosen
//!    [`BlendMode`] in equation (5)'s incremental form, with the interest values
//!    cos(alpha) and cos^N(gamma) of equation (6). Beside it, an f64 accumulation of the
//!    same fragments ([`ExactAccum`]) is the error reference. Rounded blending depends on
//!    order, so each pixel blends its fragments in primitive order (then by texture
//!    coordinates, for a folded lembo's two fragments), as GPU ROPs blend in API order:
//!    the pass collects the fragments it keeps and [`DiscoidTarget::blend_in_order`] blends
//!    them, so any unit order (functional or timed) gives the same bits.
//! 3. **Resolve**: per pixel, equation (6) from the averaged interest values, in the colour
//!    of the discoid that won the depth pass.
//!
//! Planar discoids are squares (two triangles) through the triangle path, their texture
//! coordinates from the world position in their tangent frame; curved discoids are lembos
//! through the lembo path, their texture coordinates from quadratics through the six
//! reference points' coordinates. Both use the datapath of the run.
//!
//! Deviations from the paper: the depth pass also culls back faces and discards beta = 0
//! (a square's corners outside the disk must not hide what is behind them), and the
//! threshold is in world units rather than depth-buffer units, so that it means the same
//! at every distance. The counters of fragments culled and discarded are those of the
//! accumulation pass.

use super::blend::{Accum, BlendInput, BlendMode, ExactAccum};
use super::texture::{BetaTexture, TEXTURE_SIZE};
use super::{BetaShape, Discoid};
use crate::camera::View;
use crate::datapath::{Datapath, Op, Real};
use crate::error::{Error, Result};
use crate::graph::UnitKind;
use crate::lembo::tessellate::Triangle;
use crate::lembo::{eval3, Quadratic};
use crate::raster::fragment::FragmentSink;
use crate::raster::setup::ScreenLembo;
use crate::raster::subsegmenter::Subsegment;
use crate::raster::triangle::{
    render_triangles, ScreenTriangle, TriangleFragment, TriangleSink, TriangleSource,
};
use crate::raster::{render_lembos, Counts, DEFAULT_SEGMENT_CAP};
use crate::rop::fragment_shader::{normalize, FragmentShader};
use crate::rop::framebuffer::{depth_test, NO_PRIMITIVE};
use crate::rop::shade::to_u8;
use crate::rop::FrameBuffer;
use crate::scene::Scene;
use crate::tolerance::Tolerance;
use serde::Serialize;

/// The blend units' counters and error, what the functional passes find (`blend` in
/// report.json, with the timed passes' cycles beside them: `report::BlendSection`).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct BlendReport {
    /// `rgba8`, `f16` or `f32`.
    pub mode: String,
    /// Accumulation-target bytes per accumulated fragment (read and write) \[bytes\].
    pub bytes_per_fragment: u64,
    /// Size of the accumulation target: a pixel holds half the bytes per fragment \[bytes\].
    pub accumulation_buffer_bytes: u64,
    /// Fragments blended in the accumulation pass.
    pub fragments_accumulated: u64,
    /// Fragments farther than the threshold behind the depth pass's surface.
    pub discarded_threshold: u64,
    /// Fragments outside their discoid (beta = 0).
    pub discarded_beta_zero: u64,
    /// Fragments of discoids facing away from the eye.
    pub culled_backface: u64,
    /// Fragments whose blend saturated an 8-bit word (rgba8 only; 0 otherwise).
    pub saturations: u64,
    /// Largest |L - L_f64| over resolved pixels, L = Ka + Kd cos + Ks cos^N from the
    /// averaged interest values (colour-free luminance).
    pub error_max: f64,
    /// Mean of the same over resolved pixels.
    pub error_mean: f64,
    /// The threshold t used [world units].
    pub threshold: f64,
    /// Uncovered pixels with covered pixels within 3 px to their left, right, top and
    /// bottom (holes inside the silhouette, [`count_holes`]), for every kind of discoid.
    pub holes: Option<u64>,
}

/// The scene's planar discoids as a triangle source: two triangles per discoid, after the
/// `first_id` ids of the curved discoids.
pub struct PlanarDiscoids {
    /// Discoid, material colour and beta shape, in scene order.
    pub items: Vec<(Discoid, [f64; 3], BetaShape)>,
    /// The primitive id of the first planar discoid (after the curved discoids' lembos).
    pub first_id: u32,
}

impl PlanarDiscoids {
    /// The planar discoids of `scene`'s objects, in scene order.
    pub fn new(scene: &Scene) -> Self {
        let items = scene
            .objects
            .iter()
            .filter_map(|o| o.discoids.as_ref().map(|d| (o, d)))
            .flat_map(|(o, d)| d.planar.iter().map(move |p| (*p, o.color, d.beta)))
            .collect();
        PlanarDiscoids {
            items,
            first_id: scene.lembo_count() as u32,
        }
    }

    /// The planar discoid that triangle `id` belongs to.
    #[inline]
    pub fn of_triangle(&self, id: u32) -> usize {
        ((id - self.first_id) / 2) as usize
    }
}

impl TriangleSource for PlanarDiscoids {
    fn chunks(&self) -> usize {
        self.items.len()
    }

    fn per_chunk(&self) -> u64 {
        2
    }

    fn bytes(&self, _: &crate::config::FetchConfig) -> u64 {
        super::PLANAR_DISCOID_BYTES * self.items.len() as u64
    }

    fn chunk(&self, c: usize, out: &mut Vec<Triangle>) {
        let (d, color, _) = &self.items[c];
        let q = d.corners();
        out.clear();
        for [a, b, e] in [[0, 1, 2], [0, 2, 3]] {
            out.push(Triangle {
                positions: [q[a], q[b], q[e]],
                normals: [d.normal; 3],
                color: *color,
            });
        }
    }

    fn first_id(&self) -> u32 {
        self.first_id
    }
}

/// What the ROP blend units know of every discoid, by primitive id.
pub struct DiscoidTable<R> {
    /// The planar discoids (surfels included).
    pub planar: PlanarDiscoids,
    /// Per lembo id: the texture-coordinate quadratics (s, t) and the beta shape of a
    /// curved discoid; None for a lembo that is not one.
    curved: Vec<Option<([Quadratic<R>; 2], BetaShape)>>,
    /// Material colour per lembo id.
    lembo_color: Vec<[f64; 3]>,
    /// One texture per shape, indexed by [`shape_index`].
    textures: [BetaTexture; 3],
    /// Whether the scene's planar discoids are surfels.
    pub surfels: bool,
    /// Per planar discoid: its EWA kernel, for the `ewa` beta.
    ewa: Vec<Option<EwaKernel>>,
}

fn shape_index(s: BetaShape) -> usize {
    match s {
        BetaShape::Disk => 0,
        BetaShape::Star => 1,
        BetaShape::Gaussian | BetaShape::Ewa => 2,
    }
}

/// The EWA resampling kernel of one planar discoid (Zwicker et al. 2001, "Surface
/// splatting", section 4): the tangent-plane gaussian of standard deviation σ = R/3 (the
/// `gaussian` beta's) mapped to the screen by the Jacobian J of the projection at the
/// discoid's centre, and convolved with a unit-variance screen-space low-pass filter. For a
/// tangent-plane offset u (world units, along the discoid's frame), the screen offset is
/// J·u, so the resampled gaussian is `exp(−½ uᵀ Jᵀ M⁻¹ J u)` with `M = σ² J Jᵀ + I`,
/// weighted by `σ² |det J| / √det M`: EWA's normalised kernel times the reconstruction
/// kernel's area 2πσ², so that a discoid much larger than a pixel gets the `gaussian` beta
/// in the limit (within 2/255 at 700 px across; tested) and β ≤ 1 fits the blend units' 8-bit beta (surfels of equal size weigh as EWA
/// weighs them). Like the textures, β is 0 outside the disk and quantised to 1/255 (a
/// hardware unit would look exp up in a one-dimensional table indexed by the quadratic form,
/// as Weyrich et al. 2007 do). Where the projection is not finite (a centre behind the eye)
/// the kernel is the tangent-plane gaussian.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EwaKernel {
    /// The quadratic form Jᵀ M⁻¹ J: (xx, xy, yy) \[world units⁻²\].
    q: [f64; 3],
    /// The weight σ² |det J| / √det M, in (0, 1].
    scale: f64,
    /// The discoid's radius \[world units\].
    radius: f64,
}

impl EwaKernel {
    /// The kernel of discoid `d` seen through `view`.
    pub fn new(d: &Discoid, view: &View) -> Self {
        let sigma = super::texture::GAUSSIAN_SIGMA * d.radius;
        let (e1, e2) = d.frame();
        let h = 1e-4 * d.radius;
        let column = |e: glam::DVec3| {
            let (a, b) = (
                view.project(d.center + h * e),
                view.project(d.center - h * e),
            );
            [(a.x - b.x) / (2.0 * h), (a.y - b.y) / (2.0 * h)]
        };
        let (j1, j2) = (column(e1), column(e2));
        // J = [j1 j2] (columns): screen offset = j1 u.x + j2 u.y.
        let s2 = sigma * sigma;
        let m = [
            s2 * (j1[0] * j1[0] + j2[0] * j2[0]) + 1.0,
            s2 * (j1[0] * j1[1] + j2[0] * j2[1]),
            s2 * (j1[1] * j1[1] + j2[1] * j2[1]) + 1.0,
        ];
        let det_m = m[0] * m[2] - m[1] * m[1];
        let det_j = j1[0] * j2[1] - j2[0] * j1[1];
        let inv = [m[2] / det_m, -m[1] / det_m, m[0] / det_m];
        // Jᵀ M⁻¹ J, entry (a, b) = j_a · (M⁻¹ j_b).
        let form = |a: [f64; 2], b: [f64; 2]| {
            a[0] * (inv[0] * b[0] + inv[1] * b[1]) + a[1] * (inv[1] * b[0] + inv[2] * b[1])
        };
        let q = [form(j1, j1), form(j1, j2), form(j2, j2)];
        let scale = s2 * det_j.abs() / det_m.sqrt();
        if q.iter().chain([&scale]).all(|x| x.is_finite()) && det_m > 0.0 {
            EwaKernel {
                q,
                scale: scale.min(1.0),
                radius: d.radius,
            }
        } else {
            EwaKernel {
                q: [1.0 / s2, 0.0, 1.0 / s2],
                scale: 1.0,
                radius: d.radius,
            }
        }
    }

    /// β at texture coordinates (s, t) of the discoid.
    pub fn beta(&self, st: [f64; 2]) -> f64 {
        let u = [
            (st[0] - 0.5) * 2.0 * self.radius,
            (st[1] - 0.5) * 2.0 * self.radius,
        ];
        if u[0] * u[0] + u[1] * u[1] >= self.radius * self.radius {
            return 0.0;
        }
        let e = self.q[0] * u[0] * u[0] + 2.0 * self.q[1] * u[0] * u[1] + self.q[2] * u[1] * u[1];
        (255.0 * self.scale * (-0.5 * e).exp()).round() / 255.0
    }
}

impl<R: Real> DiscoidTable<R> {
    /// The table of `scene`'s discoids in the datapath's precision, seen through `view`
    /// (the EWA kernels depend on it).
    pub fn new(scene: &Scene, view: &View) -> Self {
        let mut curved = Vec::with_capacity(scene.lembo_count());
        let mut lembo_color = Vec::with_capacity(scene.lembo_count());
        for o in &scene.objects {
            for (k, _) in o.lembos.iter().enumerate() {
                lembo_color.push(o.color);
                curved.push(o.discoids.as_ref().and_then(|d| {
                    d.lembo_texcoords.get(k).map(|st| {
                        let q =
                            |c: usize| Quadratic::from_reference_values(st.map(|p| R::of(p[c])));
                        ([q(0), q(1)], d.beta)
                    })
                }));
            }
        }
        let planar = PlanarDiscoids::new(scene);
        let ewa = planar
            .items
            .iter()
            .map(|(d, _, shape)| (*shape == BetaShape::Ewa).then(|| EwaKernel::new(d, view)))
            .collect();
        DiscoidTable {
            ewa,
            planar,
            curved,
            lembo_color,
            textures: [BetaShape::Disk, BetaShape::Star, BetaShape::Gaussian]
                .map(|s| BetaTexture::new(s, TEXTURE_SIZE)),
            surfels: scene
                .objects
                .iter()
                .any(|o| o.discoids.as_ref().is_some_and(|d| d.surfels)),
        }
    }

    /// The discoid fragment of lembo `l` at (u, v), depth z; None when the lembo is not a
    /// curved discoid (the run checks the scene, so it does not happen).
    #[inline]
    pub fn lembo_fragment(
        &self,
        l: &ScreenLembo<R>,
        u: R,
        v: R,
        z: R,
    ) -> Option<DiscoidFragment<R>> {
        let (tex, shape) = self.curved[l.id as usize].as_ref()?;
        // The texture coordinates are quadratics over the lembo's domain; a piece of a split
        // lembo maps its (u, v) there first.
        let (lu, lv) = l.lembo_uv(u, v);
        Some(DiscoidFragment {
            id: l.id,
            z,
            normal: eval3(&l.normal, u, v),
            position: eval3(&l.position, u, v),
            st: [tex[0].eval(lu, lv).f64(), tex[1].eval(lu, lv).f64()],
            shape: *shape,
        })
    }

    /// The discoid fragment of a planar discoid's triangle `t`.
    #[inline]
    pub fn planar_fragment(
        &self,
        t: &ScreenTriangle<R>,
        f: &TriangleFragment<R>,
    ) -> DiscoidFragment<R> {
        let (d, _, shape) = &self.planar.items[self.planar.of_triangle(t.id)];
        let p = f.position.map(|c| c.f64());
        DiscoidFragment {
            id: t.id,
            z: f.z,
            normal: f.normal,
            position: f.position,
            st: d.texcoord(glam::DVec3::from_array(p)),
            shape: *shape,
        }
    }

    /// The material colour of primitive `id`.
    pub fn color(&self, id: u32) -> [f64; 3] {
        match self.lembo_color.get(id as usize) {
            Some(c) => *c,
            None => self.planar.items[self.planar.of_triangle(id)].1,
        }
    }
}

/// Which pass the ROPs run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pass {
    /// The depth pass: nearest depth per pixel, no blending.
    Depth,
    /// The accumulation pass: the kept fragments' sums of equation (5).
    Accumulate,
}

/// The per-pixel state of the discoid passes and their counters; the ROP side of one
/// frame, whichever unit feeds it.
pub struct DiscoidTarget {
    /// Frame width \[pixels\].
    pub width: u32,
    /// Precision of the blend units.
    pub mode: BlendMode,
    /// World units, along the view direction.
    pub threshold: f64,
    /// Nearest depth per pixel (depth pass), 1 where none.
    pub depth: Vec<f32>,
    /// The primitive that won the depth pass, for the resolve's colour.
    pub winner: Vec<u32>,
    /// The blend units' sums per pixel, in the mode's precision.
    pub accum: Vec<Accum>,
    /// The same sums in f64, to measure the mode's error.
    pub exact: Vec<ExactAccum>,
    /// Fragments kept by the accumulation pass, blended in order at its end.
    pub kept: Vec<KeptFragment>,
    /// The depth pass winner's unit normal per pixel, kept only when accuracy is measured
    /// against the surface (the metrics', not the unit's).
    pub normal: Option<Vec<[f32; 3]>>,
    /// The passes' counters and the blend error.
    pub report: BlendReport,
}

/// A fragment the accumulation pass keeps: pixel, primitive id, texture coordinates (the
/// order within a primitive) and what it blends.
#[derive(Clone, Copy, Debug)]
pub struct KeptFragment {
    /// Pixel index, row-major.
    pub idx: u32,
    /// Primitive id.
    pub id: u32,
    /// Texture coordinates as f64 bits (an exact sort key within a primitive).
    pub st: [u64; 2],
    /// What the fragment adds to the pixel's sums.
    pub input: BlendInput,
}

impl DiscoidTarget {
    /// An empty target of `width` x `height` pixels: depth 1, no winner, zero sums.
    pub fn new(width: u32, height: u32, mode: BlendMode, threshold: f64) -> Self {
        let n = width as usize * height as usize;
        DiscoidTarget {
            width,
            mode,
            threshold,
            depth: vec![1.0; n],
            winner: vec![NO_PRIMITIVE; n],
            accum: vec![Accum::default(); n],
            exact: vec![ExactAccum::default(); n],
            kept: Vec::new(),
            normal: None,
            report: BlendReport {
                mode: mode.name().to_string(),
                bytes_per_fragment: mode.bytes_per_fragment(),
                accumulation_buffer_bytes: n as u64 * mode.bytes_per_pixel(),
                threshold,
                ..BlendReport::default()
            },
        }
    }
}

impl DiscoidTarget {
    /// Blends the pending fragments, pixel by pixel in primitive order, with the blend
    /// ALU's word `B` (`f32`, or a counting `f32` charged to the blend units).
    pub fn blend_in_order<B: Real>(&mut self) {
        B::charge(UnitKind::BlendUnit);
        let mut pending = std::mem::take(&mut self.kept);
        pending.sort_unstable_by_key(|p| (p.idx, p.id, p.st));
        for p in &pending {
            let idx = p.idx as usize;
            if self
                .mode
                .blend_in::<B>(&mut self.accum[idx], p.input)
                .saturated
            {
                self.report.saturations += 1;
            }
            self.exact[idx].add(p.input);
        }
        self.report.fragments_accumulated += pending.len() as u64;
    }
}

/// One discoid fragment as the ROP sees it.
pub struct DiscoidFragment<R> {
    /// Primitive id.
    pub id: u32,
    /// Window depth [0, 1].
    pub z: R,
    /// World-space normal (not necessarily unit) and position.
    pub normal: [R; 3],
    /// World-space position.
    pub position: [R; 3],
    /// Texture coordinates and the discoid's shape.
    pub st: [f64; 2],
    /// The discoid's beta shape.
    pub shape: BetaShape,
}

/// What the ROP computes of a discoid fragment before any test; the interest values of
/// equation (6) are computed only for a fragment the accumulation pass keeps.
#[derive(Clone, Copy, Debug)]
pub struct Evaluated<R> {
    /// The discoid faces the eye at this fragment.
    pub facing: bool,
    /// beta from the discoid's texture (0 outside it).
    pub beta: f64,
    /// Depth as the depth buffer holds it.
    pub z: f32,
    /// Unit normal and unit direction to the eye.
    pub normal: [R; 3],
    /// Unit direction to the eye.
    pub to_eye: [R; 3],
}

/// Evaluates a discoid fragment: facing, beta, depth.
#[inline]
pub fn evaluate<R: Real>(
    table: &DiscoidTable<R>,
    shader: &FragmentShader<R>,
    f: &DiscoidFragment<R>,
) -> Evaluated<R> {
    let (n, e) = (normalize(f.normal), shader.to_eye(f.position));
    Evaluated {
        facing: n[0] * e[0] + n[1] * e[1] + n[2] * e[2] >= R::zero(),
        beta: match f.shape {
            BetaShape::Ewa => table.ewa[table.planar.of_triangle(f.id)]
                .expect("every ewa discoid has its kernel")
                .beta(f.st),
            shape => table.textures[shape_index(shape)].sample(f.st[0], f.st[1]),
        },
        z: f.z.f64() as f32,
        normal: n,
        to_eye: e,
    }
}

/// The depth pass: whether fragment `e` of primitive `id` replaces a pixel holding
/// (`depth`, `winner`). Only fragments facing the eye, inside their discoid and inside the
/// depth range count; ties go to the smaller id, so the result does not depend on order.
#[inline]
pub fn depth_pass_wins<R: Real>(e: &Evaluated<R>, id: u32, depth: f32, winner: u32) -> bool {
    if !(e.facing && e.beta > 0.0) {
        return false;
    }
    // The depth test's compare (on the stored f32 depth, beside the datapath), as the
    // surface ROP counts it.
    R::count_beside(Op::Cmp, 1);
    depth_test(e.z, id, depth, winner)
}

/// Counts the accumulation pass's depth tests as the datapath would do them: they run in
/// `f64` beside it ([`View::linear_depth`]). The depth range is two compares; the threshold
/// test linear_depth(z) > linear_depth(depth) + t is two linear depths (in perspective
/// 2 z - 1, (f + n) - ndc (f - n) and 2 f n over it: 2 multiplies, 2 adds and a divide
/// each; orthographic n + z (f - n): a multiply and an add), the threshold's add and a
/// compare.
#[inline(always)]
fn count_threshold_test<R: Real>(view: &View) {
    let (mul, add, div) = if view.orthographic {
        (1, 1, 0)
    } else {
        (2, 2, 1)
    };
    R::count_beside(Op::Mul, 2 * mul);
    R::count_beside(Op::Add, 2 * add + 1);
    R::count_beside(Op::Div, 2 * div);
    R::count_beside(Op::Cmp, 2 + 1);
}

/// The accumulation pass's tests on fragment `e` at a pixel whose depth pass left
/// (`depth`, `winner`): back-face cull, beta = 0 discard, threshold; counted in `report`.
/// Returns what to blend for a fragment kept.
#[inline]
pub fn accumulation_keeps<R: Real>(
    report: &mut BlendReport,
    view: &View,
    shader: &FragmentShader<R>,
    threshold: f64,
    e: &Evaluated<R>,
    depth: f32,
    winner: u32,
) -> Option<BlendInput> {
    if !e.facing {
        report.culled_backface += 1;
        return None;
    }
    if e.beta <= 0.0 {
        report.discarded_beta_zero += 1;
        return None;
    }
    count_threshold_test::<R>(view);
    if !(0.0..=1.0).contains(&e.z)
        || winner == NO_PRIMITIVE
        || view.linear_depth(e.z as f64) > view.linear_depth(depth as f64) + threshold
    {
        report.discarded_threshold += 1;
        return None;
    }
    let (cos_a, cos_g_n) = shader.shader().terms(e.normal, e.to_eye);
    Some(BlendInput {
        beta: e.beta,
        diffuse: cos_a.f64(),
        specular: cos_g_n.f64(),
    })
}

/// The ROP's work on one discoid fragment at pixel `idx` in `pass`, on a whole-frame
/// target (the functional model).
#[inline]
pub fn process<R: Real>(
    pass: Pass,
    target: &mut DiscoidTarget,
    table: &DiscoidTable<R>,
    shader: &FragmentShader<R>,
    view: &View,
    idx: usize,
    f: &DiscoidFragment<R>,
) {
    let e = evaluate(table, shader, f);
    let (depth, winner) = (target.depth[idx], target.winner[idx]);
    match pass {
        Pass::Depth => {
            if depth_pass_wins(&e, f.id, depth, winner) {
                target.depth[idx] = e.z;
                target.winner[idx] = f.id;
                if let Some(normals) = target.normal.as_mut() {
                    normals[idx] = e.normal.map(|c| c.f64() as f32);
                }
            }
        }
        Pass::Accumulate => {
            let threshold = target.threshold;
            if let Some(input) = accumulation_keeps(
                &mut target.report,
                view,
                shader,
                threshold,
                &e,
                depth,
                winner,
            ) {
                target.kept.push(KeptFragment {
                    idx: idx as u32,
                    id: f.id,
                    st: f.st.map(f64::to_bits),
                    input,
                });
            }
        }
    }
}

/// A fragment sink for both paths that feeds [`process`] in the functional model.
struct Sink<'a, R> {
    pass: Pass,
    target: &'a mut DiscoidTarget,
    table: &'a DiscoidTable<R>,
    shader: &'a FragmentShader<R>,
    view: &'a View,
}

impl<R: Real> Sink<'_, R> {
    /// Fragment `f` at pixel (i, j) through this pass.
    #[inline]
    fn put(&mut self, i: u32, j: u32, f: &DiscoidFragment<R>) {
        let idx = (j * self.target.width + i) as usize;
        process(
            self.pass,
            self.target,
            self.table,
            self.shader,
            self.view,
            idx,
            f,
        );
    }
}

impl<R: Real> FragmentSink<R> for Sink<'_, R> {
    fn fragment(
        &mut self,
        l: &ScreenLembo<R>,
        _sub: &Subsegment<R>,
        i: u32,
        j: u32,
        u: R,
        v: R,
        z: R,
    ) {
        // The ROP's work, as the timed ROP does it (a counting datapath charges it there);
        // then the charge goes back to the rasterizer that called.
        R::charge(UnitKind::Rop);
        if let Some(f) = self.table.lembo_fragment(l, u, v, z) {
            self.put(i, j, &f);
        }
        R::charge(UnitKind::FragmentRasterizer);
    }
}

impl<R: Real> TriangleSink<R> for Sink<'_, R> {
    fn fragment(&mut self, t: &ScreenTriangle<R>, i: u32, j: u32, tf: &TriangleFragment<R>) {
        R::charge(UnitKind::Rop);
        let f = self.table.planar_fragment(t, tf);
        self.put(i, j, &f);
        R::charge(UnitKind::TriangleRasterizer);
    }
}

/// The resolve pass: the image, and the error and hole counters in the target's report.
/// The ROPs resolve (the timed model's resolve pass): each pixel's Σβ test in the blend
/// ALU's word `B`, equation (6) in the datapath's `R`; a counting run charges both to the
/// ROP. The blend error beside them is the simulator's measurement, in `f64`, not counted.
pub fn resolve<R: Real, B: Real>(
    target: &mut DiscoidTarget,
    table: &DiscoidTable<R>,
    shader: &FragmentShader<R>,
    background: [u8; 3],
    height: u32,
) -> FrameBuffer {
    R::charge(UnitKind::Rop);
    B::charge(UnitKind::Rop);
    let width = target.width;
    let mut fb = FrameBuffer::new(width, height, background, target.normal.is_some());
    let s = shader.shader();
    let (ka, kd, ks) = (s.ka.f64(), s.kd.f64(), s.ks.f64().max(0.0));
    let luminance = |d: f64, g: f64| ka + kd * d + if ks > 0.0 { ks * g } else { 0.0 };
    let (mut max, mut sum, mut n) = (0.0f64, 0.0f64, 0u64);
    for idx in 0..fb.color.len() {
        let Some((d, g)) = target.mode.resolve_in::<B>(&target.accum[idx]) else {
            continue;
        };
        let color = table.color(target.winner[idx]).map(R::of);
        let c = s.combine(R::of(d), R::of(g), color);
        fb.write(idx, target.depth[idx], target.winner[idx], c.map(to_u8));
        if let (Some(out), Some(normals)) = (fb.normal.as_mut(), target.normal.as_ref()) {
            out[idx] = normals[idx];
        }
        if let Some((ed, eg)) = target.exact[idx].resolve() {
            let e = (luminance(d, g) - luminance(ed, eg)).abs();
            max = max.max(e);
            sum += e;
            n += 1;
        }
    }
    let r = &mut target.report;
    r.error_max = max;
    r.error_mean = if n > 0 { sum / n as f64 } else { 0.0 };
    r.holes = Some(count_holes(&fb, HOLE_REACH));
    fb
}

/// How far [`count_holes`] looks for covered pixels around an uncovered one \[pixels\].
pub const HOLE_REACH: u32 = 3;

/// Uncovered pixels with a covered pixel within `reach` pixels to their left, right, top
/// and bottom: holes inside the silhouette (the hole detection of Pfister et al. 2000, on the
/// image). A pixel the depth pass covered but whose every fragment the accumulation pass
/// discarded is uncovered too (the resolve leaves it the background). The one definition
/// of holes for every kind of discoid (planar, curved, surfels).
pub fn count_holes(fb: &FrameBuffer, reach: u32) -> u64 {
    let (w, h) = (fb.width as i64, fb.height as i64);
    let covered = |i: i64, j: i64| {
        (0..w).contains(&i)
            && (0..h).contains(&j)
            && fb.primitive[(j * w + i) as usize] != NO_PRIMITIVE
    };
    let r = reach as i64;
    let mut holes = 0;
    for j in 0..h {
        for i in 0..w {
            if covered(i, j) {
                continue;
            }
            let near = |di: i64, dj: i64| (1..=r).any(|k| covered(i + k * di, j + k * dj));
            if near(1, 0) && near(-1, 0) && near(0, 1) && near(0, -1) {
                holes += 1;
            }
        }
    }
    holes
}

/// A discoid frame: the image, the counts of the paths that drew it, and the blend report.
pub struct DiscoidFrame {
    /// The resolved image.
    pub framebuffer: FrameBuffer,
    /// The counts of the path that drew the discoids (the accumulation pass's).
    pub counts: Counts,
    /// The passes' counters and the blend error.
    pub blend: BlendReport,
}

/// Refuses scenes that mix discoid objects with ordinary ones (not modelled).
pub fn check_scene(scene: &Scene) -> Result<()> {
    let has = scene.objects.iter().any(|o| o.discoids.is_some());
    if let Some((k, o)) = scene
        .objects
        .iter()
        .enumerate()
        .find(|(_, o)| has && o.discoids.is_none())
    {
        return Err(Error::invalid(
            scene.source_name(),
            format!("objects[{k}]"),
            &o.label,
            "a scene with discoids may hold only discoid objects (mixing opaque surfaces with the blend passes is not modelled)",
        ));
    }
    Ok(())
}

/// Renders a discoid scene's three passes with the functional model.
pub fn render_discoids_functional(
    scene: &Scene,
    view: &View,
    tol: impl Into<Tolerance>,
    datapath: Datapath,
    mode: BlendMode,
    threshold: f64,
) -> Result<DiscoidFrame> {
    render_discoids(scene, view, tol.into(), datapath, (mode, threshold), false)
}

/// [`render_discoids_functional`], keeping in the frame buffer the depth pass winner's
/// normal at each pixel when `keep_normals` (for the accuracy metrics); the same image.
pub fn render_discoids(
    scene: &Scene,
    view: &View,
    tol: Tolerance,
    datapath: Datapath,
    (mode, threshold): (BlendMode, f64),
    keep_normals: bool,
) -> Result<DiscoidFrame> {
    let settings = (mode, threshold);
    match datapath {
        Datapath::F32 => render_discoids_in::<f32, f32>(scene, view, tol, settings, keep_normals),
        Datapath::F64 => render_discoids_in::<f64, f32>(scene, view, tol, settings, keep_normals),
    }
}

/// [`render_discoids`] in the datapath word `R` with the blend ALU's word `B` (`f32` for
/// an image; the cost model's counting run gives counting words, which draw the same
/// bits).
pub fn render_discoids_in<R: Real, B: Real>(
    scene: &Scene,
    view: &View,
    tol: Tolerance,
    (mode, threshold): (BlendMode, f64),
    keep_normals: bool,
) -> Result<DiscoidFrame> {
    check_scene(scene)?;
    let vp = view.viewport;
    let table = DiscoidTable::<R>::new(scene, view);
    let shader = FragmentShader::<R>::new(&scene.light, view);
    let mut target = DiscoidTarget::new(vp.width, vp.height, mode, threshold);
    if keep_normals {
        target.normal = Some(vec![[0.0; 3]; vp.width as usize * vp.height as usize]);
    }
    let mut counts = Counts::default();
    for pass in [Pass::Depth, Pass::Accumulate] {
        let mut sink = Sink {
            pass,
            target: &mut target,
            table: &table,
            shader: &shader,
            view,
        };
        // Each pass draws every discoid; the counts are those of one pass.
        let mut c = Counts::default();
        render_lembos::<R, _>(scene, view, tol, DEFAULT_SEGMENT_CAP, &mut sink, &mut c)?;
        render_triangles::<R, _>(&table.planar, view, &mut sink, &mut c);
        counts = c;
    }
    target.blend_in_order::<B>();
    let background = scene.background.map(to_u8::<f64>);
    let framebuffer = resolve::<R, B>(&mut target, &table, &shader, background, vp.height);
    counts.fragments_passed_depth = target.report.fragments_accumulated;
    counts.pixels_covered = framebuffer.covered() as u64;
    Ok(DiscoidFrame {
        framebuffer,
        counts,
        blend: target.report,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Camera, Projection, Viewport};
    use crate::discoid::texture::BetaTexture;
    use glam::DVec3;

    fn view(eye_distance: f64) -> View {
        View::new(
            &Camera {
                eye: [0.0, 0.0, eye_distance],
                target: [0.0; 3],
                up: [0.0, 1.0, 0.0],
                projection: Projection::Perspective {
                    fovy_deg: 40.0,
                    near: 0.01,
                    far: 1e6,
                },
            },
            Viewport {
                width: 512,
                height: 512,
            },
        )
    }

    fn surfel(normal: DVec3) -> Discoid {
        Discoid {
            center: DVec3::ZERO,
            normal: normal.normalize(),
            radius: 1.0,
        }
    }

    #[test]
    fn a_large_ewa_discoid_is_the_tangent_plane_gaussian() {
        // About 700 px across: the one-pixel low-pass filter changes nothing visible.
        let k = EwaKernel::new(&surfel(DVec3::Z), &view(4.0));
        let gauss = BetaTexture::new(BetaShape::Gaussian, 1024);
        for st in [[0.5, 0.5], [0.6, 0.5], [0.5, 0.75], [0.3, 0.3], [0.05, 0.5]] {
            let (a, b) = (k.beta(st), gauss.sample(st[0], st[1]));
            assert!((a - b).abs() <= 2.0 / 255.0, "{st:?}: {a} {b}");
        }
        assert_eq!(k.beta([0.0, 0.0]), 0.0, "outside the disk");
    }

    #[test]
    fn a_small_ewa_discoid_is_widened_and_weighed_down_by_the_filter() {
        // About 2 px across: the filter dominates; the kernel is flatter and its weight,
        // EWA's normalisation, smaller.
        let k = EwaKernel::new(&surfel(DVec3::Z), &view(1400.0));
        assert!(k.scale < 0.5, "{}", k.scale);
        let (centre, rim) = (k.beta([0.5, 0.5]), k.beta([0.5, 0.95]));
        assert!(rim > 0.5 * centre, "{centre} {rim}");
    }

    #[test]
    fn an_oblique_ewa_discoid_is_an_ellipse() {
        // Seen at 75° from its normal, one tangent axis is foreshortened on screen by
        // cos 75° (about 9 px across instead of 35), where the filter's pixel is a larger
        // share: the kernel is wider along that axis in the tangent plane (its quadratic
        // form smaller, 6.3 against 8.7 /unit²), unlike the frontal one's.
        let frontal = EwaKernel::new(&surfel(DVec3::Z), &view(40.0));
        let oblique = EwaKernel::new(
            &surfel(DVec3::new(
                0.0,
                75f64.to_radians().sin(),
                75f64.to_radians().cos(),
            )),
            &view(40.0),
        );
        let eig = |q: [f64; 3]| {
            let (m, d) = (
                0.5 * (q[0] + q[2]),
                (0.25 * (q[0] - q[2]).powi(2) + q[1] * q[1]).sqrt(),
            );
            (m + d) / (m - d)
        };
        assert!(eig(frontal.q) < 1.01, "{:?}", frontal.q);
        assert!(eig(oblique.q) > 1.3, "{:?}", oblique.q);
        assert!(oblique.q[2] < oblique.q[0]);
    }
}
