//! The triangle path's setup and rasterizer (DESIGN.md §5): the fair baseline, rasterized as
//! a GPU does it.
//!
//! - **Setup** projects the three vertices, snaps x and y to 16.8 fixed point (16 integer
//!   bits, 8 fractional: 1/256 pixel), orients the triangle so that its edge functions are
//!   positive inside, and keeps per vertex the window depth, 1/w, and normal/w and
//!   position/w for perspective-correct interpolation.
//! - **Coverage** is decided in integers: pixel (i, j) samples its centre
//!   (256 i + 128, 256 j + 128) and is covered when every edge function is positive there,
//!   or zero on a *top* or *left* edge (the top-left fill rule of Direct3D and of OpenGL
//!   implementations: a top edge is horizontal with the triangle below it, a left edge has
//!   the triangle to its right). Two triangles sharing an edge therefore never both cover,
//!   nor both miss, a pixel centre on it.
//! - **Quads**: the rasterizer walks the bounding box in 2x2 pixel quads aligned to even
//!   coordinates, as GPUs shade; a quad with at least one covered pixel is emitted with its
//!   4-bit mask.
//! - **Fragments**: barycentrics are the three edge functions at the pixel centre over twice
//!   the area. Window depth is interpolated linearly in screen space, which is exact for a
//!   plane under perspective (z_ndc is affine in screen x and y); the normal and the world
//!   position are interpolated perspective-correctly (the weights divided by w, then
//!   normalised). A fragment is a function of the triangle and the pixel only, so any order
//!   of evaluation (functional model, or the timed ROPs tile by tile) gives the same bits.
//!
//! - **Near- and far-plane clipping**: a triangle crossing the near or the far plane is
//!   clipped, as GPUs do, in homogeneous clip space before the divide, to -w <= z <= w (GL).
//!   Clip coordinates are linear in the world point (c = M (p, 1)), so each clip-space plane
//!   e · c >= 0 is the world plane (Mᵀ e) · (p, 1) >= 0, and Sutherland–Hodgman on the world
//!   triangle is the clip-space clip, for any sign of w (vertices behind the eye included).
//!   A triangle wholly nearer than the near plane (or behind the eye) is culled as
//!   [`TriangleCull::BehindEye`], one wholly beyond the far plane or (clip-space outcodes)
//!   beside the viewport as [`TriangleCull::Outside`]. What the depth planes leave is then
//!   clipped to the guard band (below) and fanned the same way; its vertices' window depths
//!   are clamped to [0, 1] (removing only the rounding of a crossing on a depth plane), so
//!   its fragments' depths are in [0, 1] too (the far end up to one rounding, which the
//!   ROP's depth test discards).
//! - **Guard-band clipping**: a triangle with a vertex beyond the 16.8 range (±32767
//!   pixels) is clipped, as GPUs do, against the four planes x = ±[`CLIP_PX`] and
//!   y = ±[`CLIP_PX`]. Screen x is (c_x / c_w + 1) W / 2 for clip coordinates c, so each
//!   plane is linear in the world point, and Sutherland–Hodgman on the world triangle gives
//!   exact world-space vertices; position and normal are blended linearly along the edges
//!   (they are affine over the flat triangle), so the pieces' perspective-correct fragments
//!   are the unclipped triangle's. The polygon (at most 7 vertices, 9 after the depth
//!   planes too) is projected and snapped once and fanned into at most 5 (7) pieces that
//!   share their snapped vertices and the parent's id; the top-left rule then covers each
//!   pixel once. Edge crossings are computed from the edge's lexicographically smaller end,
//!   so two triangles sharing an edge cut it at the same points, bit for bit. A triangle
//!   inside the depth range and the guard band takes the unclipped path unchanged.
//!
//! Not modelled: back-face culling (the lembo path has none either; both paths shade
//! two-sided). The lembo path's counterpart of near-plane clipping is Setup's near-plane
//! split (`refine.rs`), which leaves the near plane itself to the depth test per fragment.

use super::Counts;
use crate::camera::{ScreenPoint, View, Viewport};
use crate::datapath::Real;
use crate::lembo::tessellate::{Tessellation, Triangle};
use glam::{DVec3, DVec4};

/// Fractional bits of the snapped vertex coordinates (16.8 fixed point).
pub const SUBPIXEL_BITS: u32 = 8;
/// Sub-pixel steps per pixel.
pub const SUBPIXEL: i64 = 1 << SUBPIXEL_BITS;
/// The largest |x| or |y| a snapped vertex may have \[pixels\]: 16 integer bits, signed.
pub const GUARD_BAND_PX: f64 = 32767.0;

/// One edge function `E(X, Y) = a X + b Y + c` in sub-pixel units, positive inside.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EdgeFunction {
    pub a: i64,
    pub b: i64,
    pub c: i64,
    /// The smallest value that counts as inside: 0 on a top or left edge, 1 otherwise.
    pub min: i64,
}

impl EdgeFunction {
    /// The edge from `(x0, y0)` to `(x1, y1)` of a triangle oriented so that the third
    /// vertex gives a positive value.
    fn new(x0: i64, y0: i64, x1: i64, y1: i64) -> Self {
        let (dx, dy) = (x1 - x0, y1 - y0);
        // E = dx (Y - y0) - dy (X - x0). With E > 0 inside and y pointing down, an edge
        // with dy < 0 has the triangle to its right (a left edge); dy = 0 and dx > 0 has
        // it below (a top edge).
        let top_left = dy < 0 || (dy == 0 && dx > 0);
        EdgeFunction {
            a: -dy,
            b: dx,
            c: dy * x0 - dx * y0,
            min: if top_left { 0 } else { 1 },
        }
    }

    /// The value at sub-pixel position (x, y).
    #[inline(always)]
    pub fn at(&self, x: i64, y: i64) -> i64 {
        self.a * x + self.b * y + self.c
    }
}

/// The sub-pixel position of pixel (i, j)'s centre.
#[inline(always)]
pub fn pixel_centre(i: u32, j: u32) -> (i64, i64) {
    (
        i as i64 * SUBPIXEL + SUBPIXEL / 2,
        j as i64 * SUBPIXEL + SUBPIXEL / 2,
    )
}

/// Snaps a screen coordinate \[pixels\] to 16.8 fixed point, rounding to nearest.
#[inline]
pub fn snap<R: Real>(x: R) -> i64 {
    (x * R::of(SUBPIXEL as f64)).round().to_i64().unwrap_or(0)
}

/// A triangle ready for the rasterizer, in the datapath precision.
#[derive(Clone, Debug, PartialEq)]
pub struct ScreenTriangle<R> {
    /// Global id (tessellation order), also the depth-test tie breaker; the pieces of a
    /// clipped triangle keep their parent's (they never cover a pixel twice).
    pub id: u32,
    /// Snapped vertex positions [1/256 pixel], counter-clockwise on screen as seen with y
    /// down (edge functions positive inside).
    pub x: [i64; 3],
    pub y: [i64; 3],
    /// Edge function `k` is the edge opposite vertex `k`.
    pub edges: [EdgeFunction; 3],
    /// Twice the area [1/256 pixel, squared], > 0.
    pub area2: i64,
    /// Pixels the triangle may cover, clipped to the viewport: columns i0..i1, rows j0..j1
    /// (half-open, non-empty).
    pub bbox: [u32; 4],
    /// Window depth per vertex.
    pub z: [R; 3],
    /// 1/w per vertex (1 for orthographic views).
    pub inv_w: [R; 3],
    /// World-space unit normal / w per vertex.
    pub normal_w: [[R; 3]; 3],
    /// World-space position / w per vertex.
    pub position_w: [[R; 3]; 3],
    /// Material colour, linear RGB.
    pub color: [R; 3],
}

/// Why a triangle produced no [`ScreenTriangle`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TriangleCull {
    /// Wholly on the eye's side of the near plane: nearer than it, or behind the eye.
    BehindEye,
    /// The bounding box misses the viewport, or the triangle lies beyond the far plane.
    Outside,
    /// Zero area after snapping, or no pixel centre inside the bounding box.
    Degenerate,
}

/// One fragment of a triangle: what the ROP needs to test and shade it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleFragment<R> {
    /// Window depth [0, 1].
    pub z: R,
    /// World-space normal, perspective-correct, not normalised.
    pub normal: [R; 3],
    /// World-space position, perspective-correct.
    pub position: [R; 3],
}

/// The clip rectangle of guard-band clipping: |x| <= `CLIP_PX` and |y| <= `CLIP_PX`
/// \[pixels\]. One pixel inside [`GUARD_BAND_PX`]: a clipped vertex lies on a clip line up to
/// rounding, and stays inside the 16.8 range after its conversion to the datapath (an f32
/// ulp is 1/256 pixel there) and snapping (1/512 pixel). Beyond every viewport (sides of
/// at most 16384 pixels), so clipping never removes a visible pixel.
pub const CLIP_PX: f64 = GUARD_BAND_PX - 1.0;

/// Room for the clipped polygon: a triangle gains at most one vertex per clip plane
/// (3 + 2 depth planes + 4 guard-band planes), and rounding can add a near-duplicate where a
/// vertex lies on a plane; snapping merges those again ([`make_convex`]).
const POLYGON_CAPACITY: usize = 16;

/// What setup made of one triangle; its pieces are in the caller's buffer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SetupOutcome {
    /// Triangles the clipper fanned the triangle into, each set up (and perhaps culled) as a
    /// triangle of its own: 0 when the triangle is inside the depth range and every vertex
    /// inside the guard band (or nothing of it is in view), else the snapped polygon's
    /// vertices minus 2, 1 to 7 (three vertices, and at most one more per clip plane).
    pub fan: usize,
    /// Clipped to the guard band (a guard-band plane cut the triangle, or what the depth
    /// planes left of it) and fanned: counted in `triangles_clipped`.
    pub guard_band: bool,
    /// Crossed the near or the far plane, clipped there and fanned: counted in
    /// `triangles_clipped_depth`.
    pub depth: bool,
    /// Why the triangle yielded no piece; `None` when it yielded at least one.
    pub cull: Option<TriangleCull>,
}

impl SetupOutcome {
    fn culled(cull: TriangleCull) -> Self {
        SetupOutcome {
            cull: Some(cull),
            ..Default::default()
        }
    }

    /// Counts the triangle: `triangles`, `triangles_clipped`, `triangles_clipped_depth`, and
    /// its cull if it had one.
    pub fn count(&self, counts: &mut Counts) {
        counts.triangles += 1;
        counts.triangles_clipped += self.guard_band as u64;
        counts.triangles_clipped_depth += self.depth as u64;
        if let Some(cull) = self.cull {
            count_cull(cull, counts);
        }
    }
}

/// Sets up triangle `id` (world-space `positions`, unit `normals`, `color`) for `view` into
/// `out` (cleared first): the triangle itself when it lies inside the depth range and its
/// vertices inside the 16.8 guard band; when it crosses the near or far plane, or a vertex
/// is beyond the guard band, the pieces of the triangle clipped to the depth range and to
/// [`CLIP_PX`], all with id `id`; nothing when it is culled.
pub fn setup<R: Real>(
    id: u32,
    positions: &[DVec3; 3],
    normals: &[DVec3; 3],
    color: [f64; 3],
    view: &View,
    out: &mut Vec<ScreenTriangle<R>>,
) -> SetupOutcome {
    out.clear();
    // The near and far planes: a triangle wholly beyond one is culled, one crossing either
    // is clipped to both before anything is projected.
    let depth = depth_planes(view);
    let d = depth.map(|q| positions.map(|p| q.dot(p.extend(1.0))));
    if d[0].iter().all(|&d| d < 0.0) {
        return SetupOutcome::culled(TriangleCull::BehindEye);
    }
    if d[1].iter().all(|&d| d < 0.0) {
        return SetupOutcome::culled(TriangleCull::Outside);
    }
    let color = color.map(R::of);
    if d.iter().flatten().any(|&d| d < 0.0) {
        return clip_depth(id, positions, normals, color, view, out);
    }
    // Inside the depth range: every vertex is in front of the eye (w >= near > 0, or w = 1
    // for orthographic views); the checks below only catch rounding.
    let s = positions.map(|p| view.project(p));
    if s.iter()
        .any(|s| s.w <= 0.0 || !s.x.is_finite() || !s.y.is_finite())
    {
        return SetupOutcome::culled(TriangleCull::BehindEye);
    }
    if s.iter().all(|s| s.depth < 0.0) || s.iter().all(|s| s.depth > 1.0) {
        return SetupOutcome::culled(TriangleCull::Outside);
    }
    if s.iter()
        .all(|s| s.x.abs() <= GUARD_BAND_PX && s.y.abs() <= GUARD_BAND_PX)
    {
        let x = s.map(|s| snap(R::of(s.x)));
        let y = s.map(|s| snap(R::of(s.y)));
        let v = [0, 1, 2].map(|k| vertex(view, &s[k], positions[k], normals[k]));
        return match ScreenTriangle::assemble(id, x, y, v, color, view.viewport) {
            Ok(t) => {
                out.push(t);
                SetupOutcome::default()
            }
            Err(cull) => SetupOutcome::culled(cull),
        };
    }
    clip(id, positions, normals, &s, color, view, out)
}

/// A vertex's attributes for the rasterizer, from its projection `s`, world position `p` and
/// world normal `n`.
fn vertex<R: Real>(view: &View, s: &ScreenPoint, p: DVec3, n: DVec3) -> Vertex<R> {
    let inv_w = if view.orthographic { 1.0 } else { 1.0 / s.w };
    let r3 = |v: DVec3| [R::of(v.x * inv_w), R::of(v.y * inv_w), R::of(v.z * inv_w)];
    Vertex {
        z: R::of(s.depth),
        inv_w: R::of(inv_w),
        normal_w: r3(n),
        position_w: r3(p),
    }
}

/// The guard-band clip planes of `view` in world space: a point p in front of the eye is
/// inside plane q where q · (p, 1) >= 0. Screen x is (c_x / c_w + 1) W / 2 for the clip
/// coordinates c = M (p, 1), so x >= -G is c_x + (1 + 2G/W) c_w >= 0 (c_w > 0): linear in
/// c, hence in p. Likewise x <= G, and y (1 - c_y / c_w) H / 2 against ±G.
fn guard_band_planes(view: &View) -> [DVec4; 4] {
    let kx = 2.0 * CLIP_PX / view.viewport.width as f64;
    let ky = 2.0 * CLIP_PX / view.viewport.height as f64;
    let m = view.view_proj.transpose();
    [
        DVec4::new(1.0, 0.0, 0.0, 1.0 + kx),
        DVec4::new(-1.0, 0.0, 0.0, kx - 1.0),
        DVec4::new(0.0, -1.0, 0.0, 1.0 + ky),
        DVec4::new(0.0, 1.0, 0.0, ky - 1.0),
    ]
    .map(|l| m * l)
}

/// The near and far planes of `view` in world space. Clip space keeps -w <= z <= w (GL),
/// that is e · c >= 0 for e = (0, 0, 1, 1) and (0, 0, -1, 1), and the clip coordinates are
/// linear in the world point, c = M (p, 1); so q = Mᵀ e gives q · (p, 1) = e · c exactly:
/// the clip-space half-spaces, before the divide, for any sign of w. Clipping the world
/// triangle against q is clipping in homogeneous clip space, and blends position and normal
/// linearly, as the clip-space blend does (both are affine over the flat triangle).
fn depth_planes(view: &View) -> [DVec4; 2] {
    let m = view.view_proj.transpose();
    [
        DVec4::new(0.0, 0.0, 1.0, 1.0),
        DVec4::new(0.0, 0.0, -1.0, 1.0),
    ]
    .map(|e| m * e)
}

/// The viewport's four sides in world space, as [`depth_planes`]: -w <= x, y <= w.
fn viewport_planes(view: &View) -> [DVec4; 4] {
    let m = view.view_proj.transpose();
    [
        DVec4::new(1.0, 0.0, 0.0, 1.0),
        DVec4::new(-1.0, 0.0, 0.0, 1.0),
        DVec4::new(0.0, 1.0, 0.0, 1.0),
        DVec4::new(0.0, -1.0, 0.0, 1.0),
    ]
    .map(|e| m * e)
}

/// A vertex of the clipped polygon: world position and world normal (a linear blend of the
/// triangle's unit normals, not normalised).
#[derive(Clone, Copy, Debug, Default)]
struct ClipVertex {
    p: DVec3,
    n: DVec3,
}

/// The triangle clipped so far, in order around it.
#[derive(Clone, Copy, Debug)]
struct Polygon {
    v: [ClipVertex; POLYGON_CAPACITY],
    len: usize,
}

impl Polygon {
    fn new(positions: &[DVec3; 3], normals: &[DVec3; 3]) -> Self {
        let mut v = [ClipVertex::default(); POLYGON_CAPACITY];
        for k in 0..3 {
            v[k] = ClipVertex {
                p: positions[k],
                n: normals[k],
            };
        }
        Polygon { v, len: 3 }
    }

    fn vertices(&self) -> &[ClipVertex] {
        &self.v[..self.len]
    }

    /// Clipped against each plane in turn; `None` if it outgrows its room ([`Self::clip`]).
    fn clip_all(self, planes: impl IntoIterator<Item = DVec4>) -> Option<Polygon> {
        planes.into_iter().try_fold(self, |p, q| p.clip(q))
    }

    /// Sutherland–Hodgman against one plane: the part where q · (p, 1) >= 0. A vertex on
    /// the plane is kept once (a crossing needs strictly opposite signs). `None` if the
    /// polygon outgrows its room, which only rounding at astronomic coordinates could do.
    fn clip(&self, q: DVec4) -> Option<Polygon> {
        let d = |v: &ClipVertex| q.dot(v.p.extend(1.0));
        let mut out = Polygon { v: self.v, len: 0 };
        let mut push = |v: ClipVertex| {
            (out.len < POLYGON_CAPACITY).then(|| {
                out.v[out.len] = v;
                out.len += 1;
            })
        };
        for (k, a) in self.vertices().iter().enumerate() {
            let b = &self.v[(k + 1) % self.len];
            let (da, db) = (d(a), d(b));
            if da >= 0.0 {
                push(*a)?;
            }
            if (da > 0.0 && db < 0.0) || (da < 0.0 && db > 0.0) {
                push(crossing(a, da, b, db))?;
            }
        }
        Some(out)
    }
}

/// Where edge (a, b), with signed distances `da` and `db` of opposite signs, crosses the
/// plane. Interpolated from the lexicographically smaller end, so that two triangles sharing
/// the edge compute the same bits and their pieces still share it exactly. Position and
/// normal are affine over the flat world triangle, so the linear blend is exact.
fn crossing(a: &ClipVertex, da: f64, b: &ClipVertex, db: f64) -> ClipVertex {
    let (a, da, b, db) = if a.p.to_array() <= b.p.to_array() {
        (a, da, b, db)
    } else {
        (b, db, a, da)
    };
    let t = da / (da - db);
    ClipVertex {
        p: a.p + (b.p - a.p) * t,
        n: a.n + (b.n - a.n) * t,
    }
}

/// Clips a triangle inside the depth range with a vertex beyond the guard band (every
/// vertex in front of the eye) to [`CLIP_PX`] in world space and fans the snapped polygon
/// into pieces.
fn clip<R: Real>(
    id: u32,
    positions: &[DVec3; 3],
    normals: &[DVec3; 3],
    s: &[ScreenPoint; 3],
    color: [R; 3],
    view: &View,
    out: &mut Vec<ScreenTriangle<R>>,
) -> SetupOutcome {
    // Trivial reject: every vertex beyond the same side of the viewport.
    let (w, h) = (view.viewport.width as f64, view.viewport.height as f64);
    if s.iter().all(|s| s.x < 0.0)
        || s.iter().all(|s| s.x > w)
        || s.iter().all(|s| s.y < 0.0)
        || s.iter().all(|s| s.y > h)
    {
        return SetupOutcome::culled(TriangleCull::Outside);
    }
    let Some(polygon) = Polygon::new(positions, normals).clip_all(guard_band_planes(view)) else {
        return SetupOutcome::culled(TriangleCull::Degenerate);
    };
    if polygon.len == 0 {
        return SetupOutcome::culled(TriangleCull::Outside);
    }
    let outcome = fan(id, &polygon, color, view, false, out);
    SetupOutcome {
        guard_band: outcome.fan > 0,
        ..outcome
    }
}

/// Clips a triangle that crosses the near or the far plane (a vertex may be behind the eye)
/// to both, in homogeneous coordinates before any divide ([`depth_planes`]), then what is
/// left to the guard band when it reaches beyond it, and fans the snapped polygon into
/// pieces.
fn clip_depth<R: Real>(
    id: u32,
    positions: &[DVec3; 3],
    normals: &[DVec3; 3],
    color: [R; 3],
    view: &View,
    out: &mut Vec<ScreenTriangle<R>>,
) -> SetupOutcome {
    // Trivial reject by clip-space outcodes: every vertex beyond the same side of the
    // viewport, which holds whatever the signs of the vertices' w.
    if viewport_planes(view)
        .iter()
        .any(|q| positions.iter().all(|p| q.dot(p.extend(1.0)) < 0.0))
    {
        return SetupOutcome::culled(TriangleCull::Outside);
    }
    let Some(polygon) = Polygon::new(positions, normals).clip_all(depth_planes(view)) else {
        return SetupOutcome::culled(TriangleCull::Degenerate);
    };
    // Every vertex is now in front of the eye (at or beyond the near plane, up to rounding),
    // where the guard band's planes hold.
    let planes = guard_band_planes(view);
    let guard_band = planes.iter().any(|q| {
        polygon
            .vertices()
            .iter()
            .any(|v| q.dot(v.p.extend(1.0)) < 0.0)
    });
    let Some(polygon) = polygon.clip_all(planes) else {
        return SetupOutcome::culled(TriangleCull::Degenerate);
    };
    if polygon.len == 0 {
        return SetupOutcome::culled(TriangleCull::Outside);
    }
    let outcome = fan(id, &polygon, color, view, true, out);
    SetupOutcome {
        guard_band: guard_band && outcome.fan > 0,
        depth: outcome.fan > 0,
        ..outcome
    }
}

/// Projects and snaps each vertex of the clipped `polygon` (non-empty, every vertex in
/// front of the eye) once and fans it into pieces with id `id`, into `out`. With
/// `clamp_depth` (a polygon clipped to the depth range) the vertices' window depths are
/// clamped into [0, 1], which only removes the rounding of a crossing on the near or far
/// plane: fragments, convex blends of the vertices' depths, then stay >= 0.
fn fan<R: Real>(
    id: u32,
    polygon: &Polygon,
    color: [R; 3],
    view: &View,
    clamp_depth: bool,
    out: &mut Vec<ScreenTriangle<R>>,
) -> SetupOutcome {
    // Each vertex is projected and snapped once, so the pieces share their vertices exactly
    // and the top-left rule gives each pixel on a shared edge to one piece.
    let mut x = [0i64; POLYGON_CAPACITY];
    let mut y = [0i64; POLYGON_CAPACITY];
    let first = &polygon.v[0];
    let mut v = [vertex::<R>(view, &view.project(first.p), first.p, first.n); POLYGON_CAPACITY];
    for (k, c) in polygon.vertices().iter().enumerate() {
        let mut sp = view.project(c.p);
        // A convex blend of points in front of the eye is in front of it (and the near clip
        // leaves only such points); only rounding at coordinates near the f64 range could
        // break that.
        if !(sp.w > 0.0 && sp.x.is_finite() && sp.y.is_finite()) {
            return SetupOutcome::culled(TriangleCull::Degenerate);
        }
        if clamp_depth {
            sp.depth = sp.depth.clamp(0.0, 1.0);
        }
        // A clipped vertex is on a clip line up to rounding: the clamp puts it there.
        x[k] = snap(R::of(sp.x.clamp(-CLIP_PX, CLIP_PX)));
        y[k] = snap(R::of(sp.y.clamp(-CLIP_PX, CLIP_PX)));
        v[k] = vertex(view, &sp, c.p, c.n);
    }
    let mut order: [usize; POLYGON_CAPACITY] = std::array::from_fn(|k| k);
    let n = make_convex(&x, &y, &mut order, polygon.len);
    if n < 3 {
        return SetupOutcome::culled(TriangleCull::Degenerate);
    }
    let mut all_outside = true;
    for k in 1..n - 1 {
        let [a, b, c] = [order[0], order[k], order[k + 1]];
        match ScreenTriangle::assemble(
            id,
            [x[a], x[b], x[c]],
            [y[a], y[b], y[c]],
            [v[a], v[b], v[c]],
            color,
            view.viewport,
        ) {
            Ok(t) => out.push(t),
            Err(cull) => all_outside &= cull == TriangleCull::Outside,
        }
    }
    SetupOutcome {
        fan: n - 2,
        cull: out.is_empty().then_some(if all_outside {
            TriangleCull::Outside
        } else {
            TriangleCull::Degenerate
        }),
        ..Default::default()
    }
}

/// Drops the vertices (of the first `n` of `order`, indices into `x` and `y`) where the
/// snapped polygon is not strictly convex: duplicates and collinear runs, and the rare dent
/// where snapping moves a vertex of a nearly straight angle across the line of its
/// neighbours (filling it changes the polygon by less than a 1/256-pixel sliver). The fan of
/// a strictly convex polygon tiles it with triangles of one orientation. Returns the
/// vertices left; fewer than 3 when the polygon has no area.
fn make_convex(x: &[i64], y: &[i64], order: &mut [usize], mut n: usize) -> usize {
    while n >= 3 {
        // Twice the signed area (shoelace); |coordinates| < 2^23, so no overflow.
        let area2: i64 = (0..n)
            .map(|k| {
                let (a, b) = (order[k], order[(k + 1) % n]);
                x[a] * y[b] - x[b] * y[a]
            })
            .sum();
        if area2 == 0 {
            return 0;
        }
        let turns_wrong = |k: usize| {
            let (a, b, c) = (order[(k + n - 1) % n], order[k], order[(k + 1) % n]);
            let turn = (x[b] - x[a]) * (y[c] - y[a]) - (y[b] - y[a]) * (x[c] - x[a]);
            turn.signum() != area2.signum()
        };
        match (0..n).find(|&k| turns_wrong(k)) {
            Some(k) => {
                order.copy_within(k + 1..n, k);
                n -= 1;
            }
            None => break,
        }
    }
    n
}

/// What a vertex carries into the rasterizer besides its snapped position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vertex<R> {
    pub z: R,
    pub inv_w: R,
    pub normal_w: [R; 3],
    pub position_w: [R; 3],
}

impl<R: Real> ScreenTriangle<R> {
    /// Orients, bounds and sets up the edge functions of a triangle with snapped vertices
    /// (x, y) [1/256 pixel].
    pub fn assemble(
        id: u32,
        mut x: [i64; 3],
        mut y: [i64; 3],
        mut v: [Vertex<R>; 3],
        color: [R; 3],
        viewport: Viewport,
    ) -> Result<Self, TriangleCull> {
        let mut area2 = (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]);
        if area2 == 0 {
            return Err(TriangleCull::Degenerate);
        }
        if area2 < 0 {
            // Clockwise as seen with y down: swap two vertices so the edge functions are
            // positive inside (no back-face culling).
            x.swap(1, 2);
            y.swap(1, 2);
            v.swap(1, 2);
            area2 = -area2;
        }
        let (vw, vh) = (viewport.width as i64, viewport.height as i64);
        // Pixel i's centre 256 i + 128 is inside [lo, hi] for first(lo) <= i <= last(hi).
        let first = |lo: i64| (lo - SUBPIXEL / 2 + SUBPIXEL - 1).div_euclid(SUBPIXEL);
        let last = |hi: i64| (hi - SUBPIXEL / 2).div_euclid(SUBPIXEL);
        let (xmin, xmax) = (x[0].min(x[1]).min(x[2]), x[0].max(x[1]).max(x[2]));
        let (ymin, ymax) = (y[0].min(y[1]).min(y[2]), y[0].max(y[1]).max(y[2]));
        let (i0, i1) = (first(xmin).max(0), (last(xmax) + 1).min(vw));
        let (j0, j1) = (first(ymin).max(0), (last(ymax) + 1).min(vh));
        if i0 >= i1 || j0 >= j1 {
            let outside =
                last(xmax) < 0 || first(xmin) >= vw || last(ymax) < 0 || first(ymin) >= vh;
            return Err(if outside {
                TriangleCull::Outside
            } else {
                TriangleCull::Degenerate
            });
        }
        Ok(ScreenTriangle {
            id,
            x,
            y,
            edges: [
                EdgeFunction::new(x[1], y[1], x[2], y[2]),
                EdgeFunction::new(x[2], y[2], x[0], y[0]),
                EdgeFunction::new(x[0], y[0], x[1], y[1]),
            ],
            area2,
            bbox: [i0 as u32, i1 as u32, j0 as u32, j1 as u32],
            z: v.map(|v| v.z),
            inv_w: v.map(|v| v.inv_w),
            normal_w: v.map(|v| v.normal_w),
            position_w: v.map(|v| v.position_w),
            color,
        })
    }
}

impl<R: Real> ScreenTriangle<R> {
    /// The three edge functions at pixel (i, j)'s centre.
    #[inline(always)]
    fn edge_values(&self, i: u32, j: u32) -> [i64; 3] {
        let (px, py) = pixel_centre(i, j);
        self.edges.map(|e| e.at(px, py))
    }

    /// Whether pixel (i, j)'s centre is inside, by the top-left rule.
    #[inline(always)]
    pub fn covers(&self, i: u32, j: u32) -> bool {
        let e = self.edge_values(i, j);
        (0..3).all(|k| e[k] >= self.edges[k].min)
    }

    /// The fragment at pixel (i, j) (meaningful where [`Self::covers`]).
    #[inline]
    pub fn fragment(&self, i: u32, j: u32) -> TriangleFragment<R> {
        let e = self.edge_values(i, j);
        let area = R::of(self.area2 as f64);
        let l = e.map(|v| R::of(v as f64) / area);
        let z = l[0] * self.z[0] + l[1] * self.z[1] + l[2] * self.z[2];
        // Perspective-correct: sum(l_k a_k / w_k) / sum(l_k / w_k), with a_k / w_k kept
        // per vertex.
        let sum = l[0] * self.inv_w[0] + l[1] * self.inv_w[1] + l[2] * self.inv_w[2];
        let lerp = |v: &[[R; 3]; 3]| {
            [0, 1, 2].map(|c| (l[0] * v[0][c] + l[1] * v[1][c] + l[2] * v[2][c]) / sum)
        };
        TriangleFragment {
            z,
            normal: lerp(&self.normal_w),
            position: lerp(&self.position_w),
        }
    }

    /// The covered pixels of row `j` as a half-open column range (empty when start >= end,
    /// and for rows outside the bounding box). Coverage of a row is contiguous: each edge
    /// function is linear along it, so each admits a half-line of columns.
    #[inline]
    pub fn row_span(&self, j: u32) -> (u32, u32) {
        let [i0, i1, j0, j1] = self.bbox;
        if j < j0 || j >= j1 {
            return (i0, i0);
        }
        let mut a = i0;
        while a < i1 && !self.covers(a, j) {
            a += 1;
        }
        let mut b = a;
        while b < i1 && self.covers(b, j) {
            b += 1;
        }
        (a, b)
    }

    /// Calls `quad(qi, qj, rows, mask)` for every 2x2 quad (top-left pixel (qi, qj), both
    /// even) with at least one covered pixel, row by row, left to right. `rows` are the
    /// covered spans of rows qj and qj + 1 ([`Self::row_span`]); mask bit 0 is (qi, qj),
    /// bit 1 (qi + 1, qj), bit 2 (qi, qj + 1), bit 3 (qi + 1, qj + 1).
    pub fn quads(&self, mut quad: impl FnMut(u32, u32, &[(u32, u32); 2], u8)) {
        let [_, _, j0, j1] = self.bbox;
        let mut qj = j0 & !1;
        while qj < j1 {
            let rows = [self.row_span(qj), self.row_span(qj + 1)];
            let live = rows.iter().filter(|r| r.0 < r.1);
            let lo = live.clone().map(|r| r.0).min();
            let hi = live.map(|r| r.1).max();
            if let (Some(lo), Some(hi)) = (lo, hi) {
                let mut qi = lo & !1;
                while qi < hi {
                    let mut mask = 0u8;
                    for bit in 0..4u32 {
                        let (a, b) = rows[(bit >> 1) as usize];
                        let i = qi + (bit & 1);
                        if a <= i && i < b {
                            mask |= 1 << bit;
                        }
                    }
                    if mask != 0 {
                        quad(qi, qj, &rows, mask);
                    }
                    qi += 2;
                }
            }
            qj += 2;
        }
    }
}

/// Quads (2x2, aligned to even columns) touched by the union of two row spans.
pub fn quads_in(rows: &[(u32, u32); 2]) -> u64 {
    let q = |(a, b): (u32, u32)| (a < b).then(|| (a / 2, (b - 1) / 2));
    match (q(rows[0]), q(rows[1])) {
        (None, None) => 0,
        (Some((a, b)), None) | (None, Some((a, b))) => (b - a + 1) as u64,
        (Some((a0, b0)), Some((a1, b1))) => {
            if a1 > b0 + 1 || a0 > b1 + 1 {
                (b0 - a0 + 1) as u64 + (b1 - a1 + 1) as u64
            } else {
                (b0.max(b1) - a0.min(a1) + 1) as u64
            }
        }
    }
}

/// Receives triangle fragments: the ROP in a render, a probe in tests and accuracy runs.
pub trait TriangleSink<R: Real> {
    fn fragment(&mut self, t: &ScreenTriangle<R>, i: u32, j: u32, f: &TriangleFragment<R>);
}

/// Rasterizes one set-up triangle into `sink`, quad by quad.
pub fn rasterize<R: Real, S: TriangleSink<R>>(
    t: &ScreenTriangle<R>,
    sink: &mut S,
    counts: &mut Counts,
) {
    t.quads(|qi, qj, _, mask| {
        counts.quads += 1;
        for bit in 0..4 {
            if mask & (1 << bit) != 0 {
                let (i, j) = (qi + (bit & 1), qj + (bit >> 1));
                sink.fragment(t, i, j, &t.fragment(i, j));
                counts.fragments += 1;
            }
        }
    });
}

/// Counts a culled triangle.
fn count_cull(cull: TriangleCull, counts: &mut Counts) {
    match cull {
        TriangleCull::BehindEye => counts.triangles_culled_behind_eye += 1,
        TriangleCull::Outside => counts.triangles_culled_outside += 1,
        TriangleCull::Degenerate => counts.triangles_degenerate += 1,
    }
}

/// A triangle sink that counts double hits on shared edges, then forwards each fragment.
///
/// Two triangles on opposite sides of a shared edge can both contain a pixel centre only if
/// it lies exactly on that edge, where the fill rule must give it to one of them. So a
/// double hit is a pixel whose centre lies exactly on an edge (edge function 0) of two
/// triangles with the same snapped end points, on opposite sides of it. Fragments off every
/// edge need no bookkeeping, so the probe costs little.
pub struct TriangleProbe<'a, S> {
    inner: &'a mut S,
    width: u32,
    /// Per pixel with an on-edge fragment: (triangle id, canonical edge, side) of each.
    on_edge: std::collections::HashMap<u32, Vec<(u32, [i64; 4], bool)>>,
    doubles: std::collections::HashSet<u32>,
}

impl<'a, S> TriangleProbe<'a, S> {
    pub fn new(width: u32, inner: &'a mut S) -> Self {
        TriangleProbe {
            inner,
            width,
            on_edge: Default::default(),
            doubles: Default::default(),
        }
    }

    /// Pixels claimed from both sides of a shared edge.
    pub fn double_hit_pixels(&self) -> u64 {
        self.doubles.len() as u64
    }
}

impl<R: Real, S: TriangleSink<R>> TriangleSink<R> for TriangleProbe<'_, S> {
    fn fragment(&mut self, t: &ScreenTriangle<R>, i: u32, j: u32, f: &TriangleFragment<R>) {
        let e = t.edge_values(i, j);
        for (k, &ek) in e.iter().enumerate() {
            if ek != 0 {
                continue;
            }
            // Edge k joins vertices k + 1 and k + 2; order its ends canonically and note on
            // which side of it the third vertex lies.
            let (a, b) = ((k + 1) % 3, (k + 2) % 3);
            let (pa, pb) = ((t.x[a], t.y[a]), (t.x[b], t.y[b]));
            let (p, q) = if pa <= pb { (pa, pb) } else { (pb, pa) };
            let side = (q.0 - p.0) * (t.y[k] - p.1) - (q.1 - p.1) * (t.x[k] - p.0) > 0;
            let key = [p.0, p.1, q.0, q.1];
            let pixel = j * self.width + i;
            let seen = self.on_edge.entry(pixel).or_default();
            if seen
                .iter()
                .any(|&(id, other, s)| id != t.id && other == key && s != side)
            {
                self.doubles.insert(pixel);
            }
            seen.push((t.id, key, side));
        }
        self.inner.fragment(t, i, j, f);
    }
}

/// Where the triangle path's triangles come from, chunk by chunk (a lembo's n², a planar
/// discoid's two). Triangle k of chunk c has id `first_id + c * per_chunk + k`.
pub trait TriangleSource: Sync {
    /// Chunks, in drawing order.
    fn chunks(&self) -> usize;
    /// Triangles per chunk.
    fn per_chunk(&self) -> u64;
    /// The triangles of chunk `c`, in order, into `out` (cleared first).
    fn chunk(&self, c: usize, out: &mut Vec<Triangle>);
    /// The id of the first triangle (ids of other primitives drawn in the same frame come
    /// before it).
    fn first_id(&self) -> u32 {
        0
    }
    /// The id of triangle `k` of chunk `c`.
    fn id(&self, c: usize, k: usize) -> u32 {
        (self.first_id() as u64 + c as u64 * self.per_chunk() + k as u64) as u32
    }
}

impl TriangleSource for Tessellation<'_> {
    fn chunks(&self) -> usize {
        self.lembos()
    }

    fn per_chunk(&self) -> u64 {
        self.triangles_per_lembo()
    }

    fn chunk(&self, c: usize, out: &mut Vec<Triangle>) {
        self.lembo_triangles(c, out);
    }
}

/// Runs the triangle path over every triangle of `source`, in order, into `sink`.
pub fn render_triangles<R: Real, S: TriangleSink<R>>(
    source: &dyn TriangleSource,
    view: &View,
    sink: &mut S,
    counts: &mut Counts,
) {
    let (mut triangles, mut pieces) = (Vec::new(), Vec::new());
    for c in 0..source.chunks() {
        source.chunk(c, &mut triangles);
        for (k, t) in triangles.iter().enumerate() {
            let id = source.id(c, k);
            setup::<R>(id, &t.positions, &t.normals, t.color, view, &mut pieces).count(counts);
            for st in &pieces {
                rasterize(st, sink, counts);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Camera, Projection};
    use crate::datapath::Datapath;

    const VP: Viewport = Viewport {
        width: 64,
        height: 48,
    };

    fn flat(z: f64) -> Vertex<f64> {
        Vertex {
            z,
            inv_w: 1.0,
            normal_w: [0.0, 0.0, 1.0],
            position_w: [0.0; 3],
        }
    }

    /// A triangle from sub-pixel vertex positions.
    fn tri(id: u32, p: [(i64, i64); 3]) -> Option<ScreenTriangle<f64>> {
        ScreenTriangle::assemble(
            id,
            p.map(|p| p.0),
            p.map(|p| p.1),
            [flat(0.5); 3],
            [1.0; 3],
            VP,
        )
        .ok()
    }

    /// Sets up a triangle inside the guard band: its one piece, or why it was culled.
    fn setup_one<R: Real>(
        id: u32,
        p: &[DVec3; 3],
        n: &[DVec3; 3],
        view: &View,
    ) -> Result<ScreenTriangle<R>, TriangleCull> {
        let mut out = Vec::new();
        let o = setup::<R>(id, p, n, [1.0; 3], view, &mut out);
        assert_eq!(o.fan, 0, "not clipped");
        match o.cull {
            Some(cull) => {
                assert!(out.is_empty());
                Err(cull)
            }
            None => {
                assert_eq!(out.len(), 1);
                Ok(out.remove(0))
            }
        }
    }

    /// Pixel centre (i, j) in sub-pixel units.
    fn c(i: i64, j: i64) -> (i64, i64) {
        (i * SUBPIXEL + SUBPIXEL / 2, j * SUBPIXEL + SUBPIXEL / 2)
    }

    /// How often each pixel is covered by the triangles, through the quad walk.
    fn hits<R: Real>(tris: &[ScreenTriangle<R>]) -> Vec<u32> {
        struct Hits(Vec<u32>);
        impl<R: Real> TriangleSink<R> for Hits {
            fn fragment(&mut self, _: &ScreenTriangle<R>, i: u32, j: u32, _: &TriangleFragment<R>) {
                self.0[(j * VP.width + i) as usize] += 1;
            }
        }
        let mut sink = Hits(vec![0; VP.pixels()]);
        let mut counts = Counts::default();
        for t in tris {
            rasterize(t, &mut sink, &mut counts);
        }
        assert_eq!(
            counts.fragments,
            sink.0.iter().map(|&n| n as u64).sum::<u64>()
        );
        sink.0
    }

    fn covered(h: &[u32], i: i64, j: i64) -> u32 {
        h[(j * VP.width as i64 + i) as usize]
    }

    #[test]
    fn top_left_rule_on_pixel_centres() {
        // A rectangle from centre (2, 2) to centre (10, 6), split along its diagonal: its
        // top and left sides pass exactly through pixel centres and are included, its
        // bottom and right sides too and are excluded.
        for winding in [false, true] {
            let (a, b, cc, d) = (c(2, 2), c(10, 2), c(10, 6), c(2, 6));
            let mut t = vec![tri(0, [a, b, cc]).unwrap(), tri(1, [a, cc, d]).unwrap()];
            if winding {
                t = vec![tri(0, [a, cc, b]).unwrap(), tri(1, [a, d, cc]).unwrap()];
            }
            let h = hits(&t);
            for j in 0..VP.height as i64 {
                for i in 0..VP.width as i64 {
                    let want = (2..10).contains(&i) && (2..6).contains(&j);
                    assert_eq!(covered(&h, i, j), want as u32, "pixel ({i}, {j})");
                }
            }
        }
    }

    #[test]
    fn triangles_sharing_an_edge_cover_each_pixel_exactly_once() {
        // Shared edges of many slopes through many pixel centres, both windings: the union
        // of the two triangles (a convex quadrilateral) is covered exactly once.
        let mut seed = 12345u64;
        let mut rnd = |lo: i64, hi: i64| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            lo + (seed % (hi - lo) as u64) as i64
        };
        for case in 0..400 {
            // The shared edge from p to q; on-centre end points half the time.
            let (p, q) = if case % 2 == 0 {
                // Even offsets: the edge's midpoint is a pixel centre too.
                let (i, j) = (rnd(8, 24), rnd(8, 40));
                (c(i, j), c(i + 2 * rnd(8, 16), j + 2 * rnd(-4, 4)))
            } else {
                (
                    (rnd(2000, 6000), rnd(2000, 10000)),
                    (rnd(10000, 14000), rnd(2000, 10000)),
                )
            };
            // Third vertices on either side of the edge, far enough to keep it convex.
            let (mx, my) = ((p.0 + q.0) / 2, (p.1 + q.1) / 2);
            let (nx, ny) = (-(q.1 - p.1), q.0 - p.0);
            let f = rnd(2, 9) as f64 / 10.0;
            let r = (mx + (nx as f64 * f) as i64, my + (ny as f64 * f) as i64);
            let g = rnd(2, 9) as f64 / 10.0;
            let s = (mx - (nx as f64 * g) as i64, my - (ny as f64 * g) as i64);
            let (Some(t0), Some(t1)) = (
                tri(0, if case % 3 == 0 { [p, q, r] } else { [q, p, r] }),
                tri(1, [p, q, s]),
            ) else {
                continue;
            };
            let h = hits(&[t0.clone(), t1.clone()]);
            let quad = |i: i64, j: i64| {
                let (x, y) = c(i, j);
                let side = |a: (i64, i64), b: (i64, i64)| {
                    (b.0 - a.0) * (y - a.1) - (b.1 - a.1) * (x - a.0)
                };
                // Strictly inside the quadrilateral p r q s (either orientation).
                let e = [side(p, r), side(r, q), side(q, s), side(s, p)];
                e.iter().all(|&v| v > 0) || e.iter().all(|&v| v < 0)
            };
            let mut on_edge = 0;
            for j in 0..VP.height as i64 {
                for i in 0..VP.width as i64 {
                    let n = covered(&h, i, j);
                    assert!(n <= 1, "case {case}: pixel ({i}, {j}) covered {n} times");
                    if quad(i, j) {
                        assert_eq!(n, 1, "case {case}: pixel ({i}, {j}) missed");
                        let (x, y) = c(i, j);
                        if (q.0 - p.0) * (y - p.1) == (q.1 - p.1) * (x - p.0) {
                            on_edge += 1;
                        }
                    }
                }
            }
            if case % 2 == 0 {
                // The edge passes through pixel centres: exactly the case the fill rule
                // decides.
                assert!(on_edge >= 1, "case {case}: no centre on the shared edge");
            }
        }
    }

    #[test]
    fn a_fan_around_a_vertex_covers_each_pixel_exactly_once() {
        // Twelve triangles around a vertex on a pixel centre, outer vertices on a polygon
        // (some on centres, some not): every pixel strictly inside is covered once,
        // the centre pixel included.
        let o = c(30, 24);
        let ring: Vec<(i64, i64)> = (0..12)
            .map(|k| {
                let a = k as f64 * std::f64::consts::TAU / 12.0;
                let r = if k % 2 == 0 {
                    20.0 * 256.0
                } else {
                    17.3 * 256.0
                };
                (
                    o.0 + (r * a.cos()).round() as i64,
                    o.1 + (r * a.sin()).round() as i64,
                )
            })
            .collect();
        let tris: Vec<_> = (0..12)
            .map(|k| tri(k as u32, [o, ring[k], ring[(k + 1) % 12]]).unwrap())
            .collect();
        let h = hits(&tris);
        assert_eq!(covered(&h, 30, 24), 1);
        for j in 0..VP.height as i64 {
            for i in 0..VP.width as i64 {
                let n = covered(&h, i, j);
                assert!(n <= 1, "pixel ({i}, {j}) covered {n} times");
                let (x, y) = c(i, j);
                let inside = (0..12).all(|k| {
                    let (a, b) = (ring[k], ring[(k + 1) % 12]);
                    (b.0 - a.0) * (y - a.1) - (b.1 - a.1) * (x - a.0) > 0
                });
                if inside {
                    assert_eq!(n, 1, "pixel ({i}, {j}) missed");
                }
            }
        }
    }

    #[test]
    fn quads_are_aligned_and_their_masks_match_coverage() {
        let t = tri(
            0,
            [
                c(3, 1),
                (40 * 256 + 17, 9 * 256 + 3),
                (11 * 256 + 200, 30 * 256),
            ],
        )
        .unwrap();
        let mut seen = std::collections::BTreeSet::new();
        let mut quads = 0u64;
        t.quads(|qi, qj, rows, mask| {
            assert!(qi % 2 == 0 && qj % 2 == 0 && mask != 0);
            assert_eq!(*rows, [t.row_span(qj), t.row_span(qj + 1)]);
            for bit in 0..4 {
                let (i, j) = (qi + (bit & 1), qj + (bit >> 1));
                let inside = i < VP.width && j < VP.height && t.covers(i, j);
                assert_eq!(mask & (1 << bit) != 0, inside, "({i}, {j})");
                if inside {
                    seen.insert((i, j));
                }
            }
            quads += 1;
        });
        let all: std::collections::BTreeSet<_> = (0..VP.height)
            .flat_map(|j| (0..VP.width).map(move |i| (i, j)))
            .filter(|&(i, j)| t.covers(i, j))
            .collect();
        assert_eq!(seen, all);
        let per_row: u64 = (0..VP.height / 2)
            .map(|q| quads_in(&[t.row_span(2 * q), t.row_span(2 * q + 1)]))
            .sum();
        assert_eq!(quads, per_row);
    }

    #[test]
    fn snapping_rounds_to_the_nearest_256th_of_a_pixel() {
        assert_eq!(snap(10.0f64), 2560);
        assert_eq!(snap(10.3f64), 2637); // 2636.8
        assert_eq!(snap(-0.3f64), -77); // -76.8
        assert_eq!(snap(1.0f64 / 512.0 * 0.99), 0);
        assert_eq!(snap(3.0f32 + 1.0 / 256.0), 3 * 256 + 1);
        // A triangle nudged by less than half a sub-pixel step covers the same pixels.
        let view = ortho_view();
        // On the sub-pixel grid, then nudged by less than half a step.
        let p = [
            DVec3::new(3.25, 4.125, 0.0),
            DVec3::new(40.5 + 3.0 / 256.0, 9.0, 0.0),
            DVec3::new(12.25, 30.0 + 255.0 / 256.0, 0.0),
        ];
        let nudge = DVec3::new(0.4 / 256.0, -0.45 / 256.0, 0.0);
        let a = setup_one::<f64>(0, &p, &[DVec3::Z; 3], &view).unwrap();
        let b = setup_one::<f64>(0, &p.map(|q| q + nudge), &[DVec3::Z; 3], &view).unwrap();
        assert_eq!((a.x, a.y), (b.x, b.y));
        assert_eq!((a.x[0], a.y[0]), (3 * 256 + 64, 4 * 256 + 32));
    }

    /// World x, y = screen x, y (pixels), y down, with an orthographic camera.
    fn ortho_view() -> View {
        let (w, h) = (VP.width as f64, VP.height as f64);
        View::new(
            &Camera {
                eye: [w / 2.0, h / 2.0, -10.0],
                target: [w / 2.0, h / 2.0, 0.0],
                up: [0.0, -1.0, 0.0],
                projection: Projection::Orthographic {
                    height: h,
                    near: 1.0,
                    far: 20.0,
                },
            },
            VP,
        )
    }

    /// Asserts that the fragment of `t` at pixel (i, j) has the depth and position of the
    /// view ray's hit with the plane of the world triangle `p`, and the normal blended from
    /// `n` by the hit's world barycentrics; returns the hit.
    fn assert_fragment_on_plane(
        view: &View,
        t: &ScreenTriangle<f64>,
        i: u32,
        j: u32,
        p: &[DVec3; 3],
        n: &[DVec3; 3],
    ) -> DVec3 {
        let plane_n = (p[1] - p[0]).cross(p[2] - p[0]);
        let on_plane = |x: f64, y: f64| {
            let (o, d) = view.ray(x, y);
            o + d * (plane_n.dot(p[0] - o) / plane_n.dot(d))
        };
        let (x, y) = (i as f64 + 0.5, j as f64 + 0.5);
        let hit = on_plane(x, y);
        // The plane's depth gradient [per pixel] there (from a quarter pixel either side: a
        // pixel centre is half a pixel from a row or column where the plane may meet the
        // horizon).
        let z = |x: f64, y: f64| view.depth_of(on_plane(x, y));
        let gradient =
            2.0 * (z(x + 0.25, y) - z(x - 0.25, y)).hypot(z(x, y + 0.25) - z(x, y - 0.25));
        // World barycentrics of the hit.
        let area = plane_n.length_squared();
        let b = [
            (p[1] - hit).cross(p[2] - hit).dot(plane_n) / area,
            (p[2] - hit).cross(p[0] - hit).dot(plane_n) / area,
            (p[0] - hit).cross(p[1] - hit).dot(plane_n) / area,
        ];
        let want_n = (n[0] * b[0] + n[1] * b[1] + n[2] * b[2]).normalize();
        let f = t.fragment(i, j);
        let got_n = DVec3::from_array(f.normal).normalize();
        let got_p = DVec3::from_array(f.position);
        // Tolerances: snapping moves the vertices by up to 1/512 pixel, about 4e-4 world
        // units at the far vertex, more along the grazing plane; each moved vertex tilts the
        // depth plane by up to the gradient times 1/512 at a pixel inside (a triangle cut
        // by the near plane has depth 0 on the cut: steep).
        assert!(
            (f.z - view.depth_of(hit)).abs() < 1e-5 + gradient / 128.0,
            "depth at ({i}, {j}): {} against {}, gradient {gradient}",
            f.z,
            view.depth_of(hit)
        );
        assert!((got_p - hit).length() < 3e-3, "position at ({i}, {j})");
        assert!((got_n - want_n).length() < 1e-3, "normal at ({i}, {j})");
        hit
    }

    #[test]
    fn perspective_correct_depth_normal_and_position_match_the_plane() {
        // A triangle strongly slanted in depth, seen in perspective, with three different
        // vertex normals. At every covered pixel centre the ray meets the triangle's plane
        // at P: the fragment's depth is P's depth, its position is P, and its normal is the
        // world-space barycentric blend at P. Affine (not perspective-correct) weights miss
        // by far more than the tolerance, so the test can fail.
        let view = perspective_view();
        let p = [
            DVec3::new(-1.0, -0.6, -1.5),
            DVec3::new(2.5, -0.4, -8.0),
            DVec3::new(-0.5, 1.2, -2.0),
        ];
        let n = [
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ];
        let t = setup_one::<f64>(7, &p, &n, &view).unwrap();
        let (mut checked, mut affine_miss) = (0, 0.0f64);
        for j in 0..VP.height {
            for i in 0..VP.width {
                if !t.covers(i, j) {
                    continue;
                }
                let hit = assert_fragment_on_plane(&view, &t, i, j, &p, &n);
                // What affine screen-space weights would give.
                let e = t.edge_values(i, j).map(|v| v as f64 / t.area2 as f64);
                let affine: DVec3 = (0..3)
                    .map(|k| DVec3::from_array(t.position_w[k]) / t.inv_w[k] * e[k])
                    .sum();
                affine_miss = affine_miss.max((affine - hit).length());
                checked += 1;
            }
        }
        assert!(checked > 200, "{checked}");
        assert!(affine_miss > 0.1, "{affine_miss}");
    }

    #[test]
    fn culls_are_classified() {
        let view = ortho_view();
        let z = DVec3::Z;
        let cull = |p: [DVec3; 3]| setup_one::<f32>(0, &p, &[z; 3], &view).err();
        let (a, b, c) = (
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(9.0, 1.0, 0.0),
            DVec3::new(1.0, 9.0, 0.0),
        );
        assert_eq!(cull([a, b, c]), None);
        let off = DVec3::new(500.0, 0.0, 0.0);
        assert_eq!(
            cull([a + off, b + off, c + off]),
            Some(TriangleCull::Outside)
        );
        assert_eq!(cull([a, b, a]), Some(TriangleCull::Degenerate));
        // A vertex beyond the guard band: clipped, and drawn.
        let mut out = Vec::new();
        let far = DVec3::new(1e6, 3e5, 0.0);
        let o = setup::<f32>(0, &[a, b, far], &[z; 3], [1.0; 3], &view, &mut out);
        assert!(o.fan >= 1 && o.cull.is_none() && !out.is_empty(), "{o:?}");
        // Clipped, but beyond one side of the viewport: trivially rejected.
        let right = DVec3::new(100.0, 0.0, 0.0);
        let o = setup::<f32>(
            0,
            &[a + right, b + right, far],
            &[z; 3],
            [1.0; 3],
            &view,
            &mut out,
        );
        assert_eq!(
            (o.fan, o.cull, out.len()),
            (0, Some(TriangleCull::Outside), 0)
        );
        // Spanning the viewport's x and y ranges, but passing outside the guard band's
        // corner: nothing is left after clipping.
        let corner = [
            DVec3::new(-1e6, 1.1e6, 0.0),
            DVec3::new(1.1e6, -1e6, 0.0),
            DVec3::new(-1e6, 1.1e6 + 10.0, 0.0),
        ];
        let o = setup::<f32>(0, &corner, &[z; 3], [1.0; 3], &view, &mut out);
        assert_eq!(
            (o.fan, o.cull, out.len()),
            (0, Some(TriangleCull::Outside), 0)
        );
        // Between two pixel centres: no sample inside.
        let tiny = [
            DVec3::new(1.6, 1.6, 0.0),
            DVec3::new(1.9, 1.6, 0.0),
            DVec3::new(1.6, 1.9, 0.0),
        ];
        assert_eq!(cull(tiny), Some(TriangleCull::Degenerate));
        // Beyond the far plane (the eye is at z = -10, far = 20).
        let behind = DVec3::new(0.0, 0.0, 30.0);
        assert_eq!(
            cull([a + behind, b + behind, c + behind]),
            Some(TriangleCull::Outside)
        );
    }

    /// The camera of the perspective tests: eye at the origin looking down -z, 60 degrees.
    fn perspective_view() -> View {
        View::new(
            &Camera {
                eye: [0.0, 0.0, 0.0],
                target: [0.0, 0.0, -1.0],
                up: [0.0, 1.0, 0.0],
                projection: Projection::Perspective {
                    fovy_deg: 60.0,
                    near: 0.1,
                    far: 100.0,
                },
            },
            VP,
        )
    }

    /// Per pixel: whether an unbounded-precision rasterizer covers it for the triangle with
    /// world vertices `p` (projected, snapped to 1/256 pixel in f64 however far, edge
    /// functions in i128, the top-left rule), and the pixel centre's distance \[pixels\] to
    /// the nearest of the snapped triangle's edge lines.
    fn exact_coverage(p: &[DVec3; 3], view: &View) -> Vec<(bool, f64)> {
        let s = p.map(|q| view.project(q));
        let mut x = s.map(|s| (s.x * SUBPIXEL as f64).round() as i128);
        let mut y = s.map(|s| (s.y * SUBPIXEL as f64).round() as i128);
        if (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]) < 0 {
            x.swap(1, 2);
            y.swap(1, 2);
        }
        let mut cover = Vec::new();
        for j in 0..VP.height as i128 {
            for i in 0..VP.width as i128 {
                let (px, py) = (i * 256 + 128, j * 256 + 128);
                let (mut inside, mut dist) = (true, f64::INFINITY);
                for k in 0..3 {
                    let (a, b) = ((k + 1) % 3, (k + 2) % 3);
                    let (dx, dy) = (x[b] - x[a], y[b] - y[a]);
                    let e = dx * (py - y[a]) - dy * (px - x[a]);
                    let top_left = dy < 0 || (dy == 0 && dx > 0);
                    inside &= e > 0 || (e == 0 && top_left);
                    let length = ((dx * dx + dy * dy) as f64).sqrt();
                    dist = dist.min(e.abs() as f64 / length / SUBPIXEL as f64);
                }
                cover.push((inside, dist));
            }
        }
        cover
    }

    /// Clips triangle `p` (unit normals +z) and checks its pieces against
    /// [`exact_coverage`]: no pixel twice, and a pixel covered exactly when the exact
    /// rasterizer covers it, except a centre within 1/128 pixel of an edge (a clipped
    /// vertex, snapped on its clip line, is up to 1/512 pixel off the exact edge; an f32
    /// datapath adds up to 1/2048 before snapping). Returns the pieces and the mismatches.
    fn clip_against_exact<R: Real>(p: &[DVec3; 3], view: &View) -> (Vec<ScreenTriangle<R>>, u32) {
        let mut pieces = Vec::new();
        let o = setup::<R>(3, p, &[DVec3::Z; 3], [1.0; 3], view, &mut pieces);
        let exact = exact_coverage(p, view);
        if exact.iter().any(|e| e.0) {
            assert!(o.fan >= 1 && o.cull.is_none(), "{p:?}: {o:?}");
        }
        assert!(o.fan <= 5 && pieces.len() <= o.fan, "{o:?}");
        assert!(pieces.iter().all(|t| t.id == 3));
        let h = hits(&pieces);
        let mut mismatches = 0;
        for (k, (&n, &(want, dist))) in h.iter().zip(&exact).enumerate() {
            let (i, j) = (k as u32 % VP.width, k as u32 / VP.width);
            assert!(n <= 1, "{p:?}: pixel ({i}, {j}) covered {n} times");
            if (n == 1) != want {
                assert!(dist < 1.0 / 128.0, "{p:?}: pixel ({i}, {j}), {dist} px off");
                mismatches += 1;
            }
        }
        (pieces, mismatches)
    }

    #[test]
    fn a_triangle_a_million_pixels_across_covers_the_viewport_once() {
        let view = ortho_view();
        let p = [
            DVec3::new(-1e6, -1e6, 0.0),
            DVec3::new(1e6 + 0.3, -2e5, 0.0),
            DVec3::new(-3e5, 1e6, 0.0),
        ];
        let (pieces, mismatches) = clip_against_exact::<f64>(&p, &view);
        assert_eq!(mismatches, 0);
        assert!(hits(&pieces).iter().all(|&n| n == 1));
        // The snapped pieces stay inside the 16.8 range.
        let limit = (CLIP_PX * SUBPIXEL as f64) as i64;
        assert!(pieces
            .iter()
            .all(|t| t.x.iter().chain(&t.y).all(|c| c.abs() <= limit)));
        let (pieces, mismatches) = clip_against_exact::<f32>(&p, &view);
        assert_eq!(mismatches, 0);
        assert!(hits(&pieces).iter().all(|&n| n == 1));
    }

    #[test]
    fn clipped_triangles_cover_the_exact_pixels_of_the_unclipped_ones() {
        // Random triangles with one, two or three vertices 4·10^4 to 10^7 pixels away, edges
        // through the viewport at every angle. Both datapaths.
        let view = ortho_view();
        let mut seed = 987654321u64;
        let mut rnd = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut drawn, mut mismatches, mut pixels) = (0, 0, 0);
        for case in 0..300 {
            let p: [DVec3; 3] = std::array::from_fn(|k| {
                if k < 1 + case % 3 {
                    let (a, r) = (rnd() * std::f64::consts::TAU, 10f64.powf(4.6 + 2.4 * rnd()));
                    DVec3::new(32.0 + r * a.cos(), 24.0 + r * a.sin(), 0.0)
                } else {
                    DVec3::new(-20.0 + 104.0 * rnd(), -20.0 + 88.0 * rnd(), 0.0)
                }
            });
            let (p64, m64) = clip_against_exact::<f64>(&p, &view);
            let (p32, m32) = clip_against_exact::<f32>(&p, &view);
            drawn += !p64.is_empty() as u32;
            mismatches += m64 + m32;
            pixels += hits(&p64).iter().sum::<u32>();
            assert_eq!(p64.len(), p32.len(), "{p:?}");
        }
        assert!(drawn > 150, "{drawn}");
        // Only centres a rounding step from an edge can differ.
        assert!(mismatches * 10_000 < pixels, "{mismatches} of {pixels}");
    }

    #[test]
    fn two_clipped_triangles_sharing_an_edge_through_pixel_centres_cover_each_pixel_once() {
        // The shared edge runs through the centres (20.5 + 3k, 20.5 + k), and both its ends
        // are about 10^6 pixels away, so both triangles clip it at the same guard-band
        // crossings (computed from the same end).
        let view = ortho_view();
        let k = 333_333.0;
        let p = DVec3::new(20.5 - 3.0 * k, 20.5 - k, 0.0);
        let q = DVec3::new(20.5 + 3.0 * k, 20.5 + k, 0.0);
        let r1 = DVec3::new(-1e6, 1e6, 0.0);
        let r2 = DVec3::new(1e6, -1e6, 0.0);
        for (a, b) in [([p, q, r1], [q, p, r2]), ([q, r1, p], [r2, p, q])] {
            let (mut pa, _) = clip_against_exact::<f64>(&a, &view);
            let (pb, _) = clip_against_exact::<f64>(&b, &view);
            pa.extend(pb);
            let h = hits(&pa);
            for (k, &n) in h.iter().enumerate() {
                assert_eq!(
                    n,
                    1,
                    "pixel ({}, {})",
                    k as u32 % VP.width,
                    k as u32 / VP.width
                );
            }
        }
    }

    fn unclipped_bit_for_bit<R: Real>() {
        // One vertex between the clip line and the end of the 16.8 range: inside the guard
        // band, so not clipped (clipping would move it onto x = CLIP_PX and count the
        // triangle as clipped).
        let view = ortho_view();
        let p = [
            DVec3::new(2.3, 3.1, 0.5),
            DVec3::new(CLIP_PX + 0.75, 20.2, -1.0),
            DVec3::new(-GUARD_BAND_PX, 40.9, 2.0),
        ];
        let n = [
            DVec3::Z,
            DVec3::new(0.6, 0.0, 0.8),
            DVec3::new(0.0, -0.8, 0.6),
        ];
        let color = [0.25, 0.5, 1.0];
        // The setup of a triangle before guard-band clipping existed, written out.
        let s = p.map(|q| view.project(q));
        let r3 = |v: DVec3| v.to_array().map(R::of);
        let v = [0, 1, 2].map(|k| Vertex {
            z: R::of(s[k].depth),
            inv_w: R::of(1.0),
            normal_w: r3(n[k]),
            position_w: r3(p[k]),
        });
        let x = s.map(|s| snap(R::of(s.x)));
        let y = s.map(|s| snap(R::of(s.y)));
        let want = ScreenTriangle::assemble(5, x, y, v, color.map(R::of), VP).unwrap();
        assert!(want.x.contains(&(CLIP_PX as i64 * SUBPIXEL + 192)));
        let mut out = Vec::new();
        let o = setup::<R>(5, &p, &n, color, &view, &mut out);
        assert_eq!(o, SetupOutcome::default());
        assert_eq!(out, vec![want]);
        let mut counts = Counts::default();
        o.count(&mut counts);
        assert_eq!((counts.triangles, counts.triangles_clipped), (1, 0));
        // Half a pixel further, past the guard band: clipped onto x = CLIP_PX.
        let beyond = [p[0], p[1] + DVec3::X, p[2]];
        let o = setup::<R>(5, &beyond, &n, color, &view, &mut out);
        assert!(o.fan >= 1 && o.cull.is_none(), "{o:?}");
        let xmax = out.iter().flat_map(|t| t.x).max().unwrap();
        assert_eq!(xmax, CLIP_PX as i64 * SUBPIXEL);
        o.count(&mut counts);
        assert_eq!((counts.triangles, counts.triangles_clipped), (2, 1));
    }

    #[test]
    fn a_triangle_inside_the_guard_band_is_set_up_unclipped_bit_for_bit() {
        unclipped_bit_for_bit::<f64>();
        unclipped_bit_for_bit::<f32>();
    }

    #[test]
    fn clipped_pieces_interpolate_perspective_correctly_like_the_whole_triangle() {
        // As perspective_correct_depth_normal_and_position_match_the_plane, with a vertex
        // about 70 000 pixels to the right: every piece's fragment at a pixel is the ray's
        // hit with the whole triangle's plane, and the blend of the whole triangle's
        // normals there.
        let view = perspective_view();
        let p = [
            DVec3::new(-1.0, -0.6, -1.5),
            DVec3::new(5000.0, -0.4, -3.0),
            DVec3::new(-0.5, 1.2, -2.0),
        ];
        let n = [
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ];
        assert!(view.project(p[1]).x > 2.0 * GUARD_BAND_PX);
        let mut pieces = Vec::new();
        let o = setup::<f64>(7, &p, &n, [1.0; 3], &view, &mut pieces);
        assert!(o.fan >= 2 && pieces.len() >= 2, "{o:?}");
        assert!(o.guard_band && !o.depth, "{o:?}");
        let checked = pieces_on_plane(&view, &pieces, &p, &n);
        assert!(checked > 200, "{checked}");
        // A vertex behind the eye: the triangle is clipped at the near plane (and what is
        // left of it at the guard band), and the pieces are still the whole triangle's.
        let behind = [p[0], p[1], DVec3::new(0.0, 0.0, 1.0)];
        let o = setup::<f64>(7, &behind, &n, [1.0; 3], &view, &mut pieces);
        assert!(
            o.fan >= 2 && o.cull.is_none() && o.depth && o.guard_band,
            "{o:?}"
        );
        let checked = pieces_on_plane(&view, &pieces, &behind, &n);
        assert!(checked > 200, "{checked}");
    }

    /// Asserts that the pieces of the triangle with world vertices `p` and normals `n` cover
    /// each pixel at most once and that each fragment lies on the triangle's plane
    /// ([`assert_fragment_on_plane`]); returns the fragments checked.
    fn pieces_on_plane(
        view: &View,
        pieces: &[ScreenTriangle<f64>],
        p: &[DVec3; 3],
        n: &[DVec3; 3],
    ) -> u32 {
        let h = hits(pieces);
        let mut checked = 0;
        for t in pieces {
            for j in 0..VP.height {
                for i in 0..VP.width {
                    if !t.covers(i, j) {
                        continue;
                    }
                    assert_eq!(h[(j * VP.width + i) as usize], 1, "({i}, {j})");
                    assert_fragment_on_plane(view, t, i, j, p, n);
                    checked += 1;
                }
            }
        }
        checked
    }

    #[test]
    fn triangles_sharing_an_edge_clip_it_at_the_same_points() {
        // Edges through the view with both ends far beyond the guard band, each shared by
        // two triangles that walk it in opposite directions: their clipped polygons share
        // exactly the two crossings, bit for bit, so their pieces meet without a crack.
        let view = perspective_view();
        let planes = guard_band_planes(&view);
        let mut seed = 4242u64;
        let mut rnd = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let clip_all = |t: [DVec3; 3]| {
            let mut polygon = Polygon::new(&t, &[DVec3::Z; 3]);
            for q in planes {
                polygon = polygon.clip(q).unwrap();
            }
            polygon
        };
        for case in 0..200 {
            let mid = DVec3::new(rnd() - 0.5, rnd() - 0.5, -2.0 - 3.0 * rnd());
            let a = rnd() * std::f64::consts::TAU;
            let dir = DVec3::new(a.cos(), a.sin(), 0.0);
            let far = |r: f64| 10f64.powf(4.0 + 2.0 * r);
            let (p, q) = (mid - dir * far(rnd()), mid + dir * far(rnd()));
            let side = DVec3::new(-dir.y, dir.x, 0.0);
            let (r1, r2) = (mid + side * far(rnd()), mid - side * far(rnd()));
            let (a, b) = (clip_all([p, q, r1]), clip_all([q, p, r2]));
            let shared = a
                .vertices()
                .iter()
                .filter(|u| b.vertices().iter().any(|v| v.p == u.p))
                .count();
            assert_eq!(shared, 2, "case {case}");
        }
    }

    #[test]
    fn a_snapped_polygon_is_made_strictly_convex() {
        // A duplicate, a collinear vertex and a dent go; the square's corners stay.
        let x = [0, 0, 100, 200, 200, 200, 0, 99];
        let y = [0, 0, 1, 0, 100, 200, 200, 100];
        let mut order: [usize; 8] = std::array::from_fn(|k| k);
        let n = make_convex(&x, &y, &mut order, 8);
        assert_eq!(&order[..n], &[1, 3, 5, 6]);
        // Everything on one line: no area.
        let mut order: [usize; 3] = [0, 1, 2];
        assert_eq!(make_convex(&[0, 1, 2], &[0, 1, 2], &mut order, 3), 0);
    }

    /// A xorshift generator of numbers in [0, 1).
    fn uniform(seed: &mut u64) -> f64 {
        *seed ^= *seed << 13;
        *seed ^= *seed >> 7;
        *seed ^= *seed << 17;
        (*seed >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Per pixel: fragments received, and the range of their depths.
    struct Fragments {
        hits: Vec<u32>,
        z: [f64; 2],
    }

    impl<R: Real> TriangleSink<R> for Fragments {
        fn fragment(&mut self, _: &ScreenTriangle<R>, i: u32, j: u32, f: &TriangleFragment<R>) {
            self.hits[(j * VP.width + i) as usize] += 1;
            let z = f.z.f64();
            self.z = [self.z[0].min(z), self.z[1].max(z)];
        }
    }

    impl Fragments {
        fn new() -> Self {
            Fragments {
                hits: vec![0; VP.pixels()],
                z: [f64::INFINITY, f64::NEG_INFINITY],
            }
        }
    }

    /// Whether the view ray through screen point (sx, sy) meets the world triangle `p`
    /// between the near plane (the ray's origin) and the far plane: exact visible coverage.
    fn sees(view: &View, p: &[DVec3; 3], sx: f64, sy: f64) -> bool {
        let (o, d) = view.ray(sx, sy);
        let normal = (p[1] - p[0]).cross(p[2] - p[0]);
        let t = normal.dot(p[0] - o) / normal.dot(d);
        // A ray in the triangle's plane (t not a number) or meeting it before the near plane
        // does not see it.
        if t.is_nan() || t < 0.0 {
            return false;
        }
        let hit = o + d * t;
        (0..3).all(|k| {
            (p[(k + 1) % 3] - hit)
                .cross(p[(k + 2) % 3] - hit)
                .dot(normal)
                >= 0.0
        }) && view.depth_of(hit) <= 1.0
    }

    /// Exact visible coverage of pixel (i, j) by any of `tris`, when it is the same at the
    /// centre and 1/64 pixel away from it in the four axis directions; `None` for a centre
    /// that close to the outline of what is visible (snapping moves a vertex by up to 1/512
    /// pixel, a crossing on the near plane is exact up to rounding).
    fn sees_clearly(view: &View, tris: &[[DVec3; 3]], i: u32, j: u32) -> Option<bool> {
        let (x, y) = (i as f64 + 0.5, j as f64 + 0.5);
        let d = 1.0 / 64.0;
        let at = |x: f64, y: f64| tris.iter().any(|p| sees(view, p, x, y));
        let c = at(x, y);
        [(d, 0.0), (-d, 0.0), (0.0, d), (0.0, -d)]
            .iter()
            .all(|&(dx, dy)| at(x + dx, y + dy) == c)
            .then_some(c)
    }

    /// Sets up and rasterizes `tris` (unit normals +z) through a [`TriangleProbe`] and
    /// checks the union of their pieces against [`sees_clearly`]: no pixel twice, no double
    /// hit on a shared edge, each fragment's depth in [0, 1], and a pixel covered exactly
    /// when the rays see the triangles, except within 1/64 pixel of the outline. Returns the
    /// outcomes, the pixels covered and the pixels within 1/64 pixel of the outline.
    fn clip_against_rays<R: Real>(
        tris: &[[DVec3; 3]],
        view: &View,
    ) -> (Vec<SetupOutcome>, u32, u32) {
        let mut sink = Fragments::new();
        let mut probe = TriangleProbe::new(VP.width, &mut sink);
        let (mut pieces, mut outcomes, mut counts) = (Vec::new(), Vec::new(), Counts::default());
        for (k, p) in tris.iter().enumerate() {
            let o = setup::<R>(k as u32, p, &[DVec3::Z; 3], [1.0; 3], view, &mut pieces);
            assert!(o.fan <= 7 && pieces.len() <= o.fan.max(1), "{o:?}");
            for t in &pieces {
                rasterize(t, &mut probe, &mut counts);
            }
            outcomes.push(o);
        }
        assert_eq!(probe.double_hit_pixels(), 0, "{tris:?}");
        let (mut covered, mut unclear) = (0, 0);
        for (k, &n) in sink.hits.iter().enumerate() {
            let (i, j) = (k as u32 % VP.width, k as u32 / VP.width);
            assert!(n <= 1, "{tris:?}: pixel ({i}, {j}) covered {n} times");
            covered += n;
            match sees_clearly(view, tris, i, j) {
                Some(want) => assert_eq!(n == 1, want, "{tris:?}: pixel ({i}, {j})"),
                None => unclear += 1,
            }
        }
        if covered > 0 {
            assert!(
                0.0 <= sink.z[0] && sink.z[1] <= 1.0,
                "{tris:?}: depths {:?}",
                sink.z
            );
        }
        (outcomes, covered, unclear)
    }

    #[test]
    fn a_triangle_straddling_the_near_plane_covers_its_visible_side_once() {
        let view = perspective_view();
        // A floor 3 cm below the eye, from behind it to 6 units ahead: the near plane cuts it
        // along row 36.5 (y_ndc = -0.03 / (0.1 tan 30°)), its far vertex is on row 24.2.
        let floor = [
            DVec3::new(-3.0, -0.03, 1.0),
            DVec3::new(3.0, -0.03, 1.0),
            DVec3::new(0.0, -0.03, -6.0),
        ];
        for datapath in [Datapath::F32, Datapath::F64] {
            let (o, covered, unclear) = match datapath {
                Datapath::F32 => clip_against_rays::<f32>(&[floor], &view),
                Datapath::F64 => clip_against_rays::<f64>(&[floor], &view),
            };
            assert!(o[0].depth && o[0].cull.is_none(), "{o:?}");
            // Rows 24 to 36, narrowing towards the far vertex.
            assert!((11 * 64..=13 * 64).contains(&covered), "{covered}");
            assert!(unclear <= 2 * 64, "{unclear}");
        }
        // A ramp from 1 unit ahead, 0.5 below the eye, up to a vertex behind the eye: the near
        // plane cuts it along row 32.3 (y = -0.02 there), its front edge is on row 44.8. The
        // pieces interpolate like the whole triangle.
        let ramp = [
            DVec3::new(-1.0, -0.5, -1.0),
            DVec3::new(1.0, -0.5, -1.0),
            DVec3::new(0.0, 0.3, 0.5),
        ];
        let n = [DVec3::Y, DVec3::new(0.0, 0.8, 0.6), DVec3::Z];
        let (o, covered, _) = clip_against_rays::<f64>(&[ramp], &view);
        assert!(
            o[0].depth && (11 * 64..=13 * 64).contains(&covered),
            "{o:?} {covered}"
        );
        let mut pieces = Vec::new();
        let o = setup::<f64>(0, &ramp, &n, [1.0; 3], &view, &mut pieces);
        assert_eq!(pieces_on_plane(&view, &pieces, &ramp, &n), covered);
        let mut counts = Counts::default();
        o.count(&mut counts);
        assert_eq!(
            (counts.triangles_clipped_depth, counts.triangles_clipped),
            (1, 0)
        );

        // Random triangles around a point near the near plane, vertices 0.03 to 3 units from
        // it in any direction (behind the eye too), both datapaths.
        let mut seed = 20240611u64;
        let mut rnd = || uniform(&mut seed);
        let (mut clipped, mut pixels, mut unclear) = (0, 0, 0);
        for _ in 0..300 {
            let m = DVec3::new(
                0.06 * (2.0 * rnd() - 1.0),
                0.05 * (2.0 * rnd() - 1.0),
                -0.1 + 0.04 * (2.0 * rnd() - 1.0),
            );
            let p: [DVec3; 3] = std::array::from_fn(|_| {
                let (a, z) = (rnd() * std::f64::consts::TAU, 2.0 * rnd() - 1.0);
                let r = (1.0 - z * z).sqrt();
                m + DVec3::new(r * a.cos(), r * a.sin(), z) * 0.03 * 100f64.powf(rnd())
            });
            let (o64, c64, u64_) = clip_against_rays::<f64>(&[p], &view);
            let (o32, c32, u32_) = clip_against_rays::<f32>(&[p], &view);
            assert_eq!(o64[0].depth, o32[0].depth, "{p:?}");
            clipped += o64[0].depth as u32;
            pixels += c64 + c32;
            unclear += u64_ + u32_;
        }
        assert!(clipped > 150, "{clipped}");
        assert!(pixels > 50 * 64 * 48, "{pixels}");
        assert!(unclear * 20 < pixels, "{unclear} of {pixels}");
    }

    #[test]
    fn a_triangle_crossing_the_far_plane_is_clipped_there() {
        // The orthographic view's far plane is z = 10 (eye at z = -10, far 20).
        let view = ortho_view();
        let p = [
            DVec3::new(-10.0, 5.0, 0.0),
            DVec3::new(70.0, 10.0, 16.0),
            DVec3::new(20.0, 60.0, 8.0),
        ];
        for datapath in [Datapath::F32, Datapath::F64] {
            let (o, covered, _) = match datapath {
                Datapath::F32 => clip_against_rays::<f32>(&[p], &view),
                Datapath::F64 => clip_against_rays::<f64>(&[p], &view),
            };
            assert!(
                o[0].depth && !o[0].guard_band && o[0].cull.is_none(),
                "{o:?}"
            );
            assert!(covered > 500, "{covered}");
        }
    }

    #[test]
    fn triangles_sharing_an_edge_across_the_near_plane_have_no_crack_and_no_double_hit() {
        // Orthographic (near plane z = -9): a shared edge through the pixel centres
        // (20.5 + 3k, 20.5 + k), from 1 unit nearer than the near plane to 1 beyond it, so
        // the plane cuts it at (20.5, 20.5); the third vertices on either side reach
        // nearer than the near plane too. The fill rule must give each centre on the edge
        // to one triangle.
        let view = ortho_view();
        let (p, q) = (DVec3::new(-9.5, 10.5, -10.0), DVec3::new(50.5, 30.5, -8.0));
        for (z1, z2) in [(-9.5, -8.5), (-12.0, -3.0), (-8.0, -9.9), (0.0, -20.0)] {
            let (r1, r2) = (DVec3::new(-30.0, 60.0, z1), DVec3::new(80.0, -20.0, z2));
            for tris in [[[p, q, r1], [q, p, r2]], [[q, r1, p], [r2, p, q]]] {
                let (o, covered, unclear) = clip_against_rays::<f64>(&tris, &view);
                assert!(o.iter().all(|o| o.depth), "{o:?}");
                assert!(covered > 300 && unclear < 200, "{covered} {unclear}");
                let (_, covered32, _) = clip_against_rays::<f32>(&tris, &view);
                assert!(covered32.abs_diff(covered) < 40, "{covered32} {covered}");
            }
        }
        // Perspective: random shared edges from behind the eye to ahead of it, through the
        // view; third vertices on either side, anywhere in depth.
        let view = perspective_view();
        let planes: Vec<DVec4> = depth_planes(&view)
            .into_iter()
            .chain(guard_band_planes(&view))
            .collect();
        let clip_all = |t: [DVec3; 3]| {
            let mut polygon = Polygon::new(&t, &[DVec3::Z; 3]);
            for &q in &planes {
                polygon = polygon.clip(q).unwrap();
            }
            polygon
        };
        let mut seed = 777u64;
        let mut rnd = || uniform(&mut seed);
        let mut pixels = 0;
        for case in 0..200 {
            let at = |x: f64, y: f64, z: f64| DVec3::new(x * z.abs(), y * z.abs(), z);
            let p = at(rnd() - 0.5, rnd() - 0.5, 0.05 + 2.0 * rnd());
            let q = at(0.5 * rnd() - 0.25, 0.4 * rnd() - 0.2, -0.15 - 5.0 * rnd());
            // A planar quadrilateral split along pq (two triangles folded along a shared
            // edge may overlap on screen legitimately; coplanar ones may not).
            let e = q - p;
            let side = e
                .cross(DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5))
                .normalize()
                * e.length();
            let along = |t: f64| p + e * t;
            let r1 = along(rnd()) + side * (0.05 + 2.0 * rnd());
            let r2 = along(rnd()) - side * (0.05 + 2.0 * rnd());
            let (a, b) = (clip_all([p, q, r1]), clip_all([q, p, r2]));
            if a.len > 0 && b.len > 0 {
                let shared = a
                    .vertices()
                    .iter()
                    .filter(|u| b.vertices().iter().any(|v| v.p == u.p))
                    .count();
                assert_eq!(shared, 2, "case {case}");
            }
            let (_, c64, _) = clip_against_rays::<f64>(&[[p, q, r1], [q, p, r2]], &view);
            let (_, c32, _) = clip_against_rays::<f32>(&[[p, q, r1], [q, p, r2]], &view);
            pixels += c64 + c32;
        }
        assert!(pixels > 100 * 64 * 48, "{pixels}");
    }

    #[test]
    fn triangles_beyond_a_depth_plane_are_culled_and_clipped_ones_counted() {
        let view = perspective_view();
        let z = DVec3::Z;
        let mut out = Vec::new();
        let mut outcome = |p: [DVec3; 3]| setup::<f32>(0, &p, &[z; 3], [1.0; 3], &view, &mut out);
        let tri = |z0: f64, z1: f64, z2: f64| {
            [
                DVec3::new(-0.01, -0.01, z0),
                DVec3::new(0.01, -0.01, z1),
                DVec3::new(0.0, 0.01, z2),
            ]
        };
        // Between the eye and the near plane (z = -0.1), behind the eye, and both.
        for p in [
            tri(-0.05, -0.09, -0.02),
            tri(0.5, 1.0, 0.1),
            tri(0.5, -0.05, -0.09),
        ] {
            assert_eq!(outcome(p), SetupOutcome::culled(TriangleCull::BehindEye));
        }
        // Beyond the far plane (z = -100).
        assert_eq!(
            outcome(tri(-100.5, -120.0, -101.0)),
            SetupOutcome::culled(TriangleCull::Outside)
        );
        // Crossing the near plane, but wholly to the right of the view: rejected before any
        // clipping, whatever the sign of w.
        let right = [
            DVec3::new(1.0, 0.0, 0.5),
            DVec3::new(2.0, 0.0, -1.0),
            DVec3::new(3.0, 1.0, -1.0),
        ];
        assert_eq!(outcome(right), SetupOutcome::culled(TriangleCull::Outside));
        // Crossing near, far, both: clipped and drawn; counted once each.
        let mut counts = Counts::default();
        let big =
            |z0: f64, z1: f64, z2: f64| tri(z0, z1, z2).map(|p| p * DVec3::new(100.0, 100.0, 1.0));
        for p in [
            tri(0.5, -1.0, -1.0),
            big(-50.0, -150.0, -50.0),
            big(1.0, -200.0, -1.0),
        ] {
            let o = outcome(p);
            assert!(
                o.depth && !o.guard_band && o.fan >= 1 && o.cull.is_none(),
                "{o:?}"
            );
            o.count(&mut counts);
        }
        // Crossing the near plane and beyond the guard band: both clips.
        let wide = [
            DVec3::new(-1.0, -0.5, -2.0),
            DVec3::new(1e5, 0.0, -2.0),
            DVec3::new(0.0, 0.5, 1.0),
        ];
        let o = outcome(wide);
        assert!(o.depth && o.guard_band && o.cull.is_none(), "{o:?}");
        o.count(&mut counts);
        assert_eq!(
            (
                counts.triangles,
                counts.triangles_clipped_depth,
                counts.triangles_clipped
            ),
            (4, 4, 1)
        );
    }
}
