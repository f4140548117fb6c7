//! The triangle path's setup: projection, clipping at the depth planes and the guard band
//! (Sutherland-Hodgman on the world triangle), 16.8 snapping, fans, and the edge functions
//! of a [`ScreenTriangle`].

use crate::camera::{Culling, Samples, ScreenPoint, View, Viewport, Winding};
use crate::datapath::Op;
use crate::datapath::Real;
use crate::raster::counts::Counts;
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
    /// Coefficient of X.
    pub a: i64,
    /// Coefficient of Y.
    pub b: i64,
    /// The constant term.
    pub c: i64,
    /// The smallest value that counts as inside: 0 on a top or left edge, 1 otherwise.
    pub min: i64,
}

impl EdgeFunction {
    /// The edge from `(x0, y0)` to `(x1, y1)` of a triangle oriented so that the third
    /// vertex gives a positive value.
    pub(super) fn new(x0: i64, y0: i64, x1: i64, y1: i64) -> Self {
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

impl<R> ScreenTriangle<R> {
    /// The sub-pixel position of the sample of column i on sample-grid row j: pixel (i, j)'s
    /// centre with one sample per pixel, else displaced along the row by the row's offset
    /// ([`Samples::row_dx16`]).
    #[inline(always)]
    pub fn sample_at(&self, i: u32, j: u32) -> (i64, i64) {
        let (x, y) = pixel_centre(i, j);
        (x + SUBPIXEL / 16 * self.samples.row_dx16(j), y)
    }

    /// The sub-pixel position of the centre of the pixel whose sample row j is (row j itself
    /// with one sample per pixel), column i: where a multisampled triangle is shaded.
    #[inline(always)]
    pub fn shading_point(&self, i: u32, j: u32) -> (i64, i64) {
        let n = self.samples.get();
        let (x, _) = pixel_centre(i, j);
        (x, (j / n * n) as i64 * SUBPIXEL + n as i64 * (SUBPIXEL / 2))
    }
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
    /// Snapped vertex x \[1/256 pixel\]; the vertices are counter-clockwise on screen as seen with
    /// y down (edge functions positive inside).
    pub x: [i64; 3],
    /// Snapped vertex y \[1/256 pixel\].
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
    /// The samples per pixel whose sample grid the triangle is set up on (one: the pixel
    /// centres).
    pub samples: Samples,
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
    /// Facing away from the eye (its snapped signed area has the back's sign) when the view
    /// culls back faces ([`Culling`]).
    BackFace,
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
pub(super) const POLYGON_CAPACITY: usize = 16;

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
    pub(super) fn culled(cull: TriangleCull) -> Self {
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

/// Counts a culled triangle.
fn count_cull(cull: TriangleCull, counts: &mut Counts) {
    match cull {
        TriangleCull::BehindEye => counts.triangles_culled_behind_eye += 1,
        TriangleCull::Outside => counts.triangles_culled_outside += 1,
        TriangleCull::Degenerate => counts.triangles_degenerate += 1,
        TriangleCull::BackFace => counts.triangles_culled_backface += 1,
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
    setup_onto(id, positions, normals, color, view, out)
}

/// [`setup`] appending to `out` (what it holds stays): a caller that keeps every set-up
/// triangle writes each once, where it stays.
pub fn setup_onto<R: Real>(
    id: u32,
    positions: &[DVec3; 3],
    normals: &[DVec3; 3],
    color: [f64; 3],
    view: &View,
    out: &mut Vec<ScreenTriangle<R>>,
) -> SetupOutcome {
    // The near and far planes: a triangle wholly beyond one is culled, one crossing either
    // is clipped to both before anything is projected.
    let depth = depth_planes(view);
    // Two planes against three vertices: a 4-dot product and a compare each.
    R::count_beside(Op::Mul, 24);
    R::count_beside(Op::Add, 18);
    R::count_beside(Op::Cmp, 6);
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
        let assembled = ScreenTriangle::assemble(
            id,
            x,
            y,
            v,
            color,
            view.viewport,
            view.samples,
            view.culling,
        );
        return match assembled {
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
pub(super) fn vertex<R: Real>(view: &View, s: &ScreenPoint, p: DVec3, n: DVec3) -> Vertex<R> {
    R::count_beside(Op::Div, 1);
    R::count_beside(Op::Mul, 6);
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
pub(super) fn guard_band_planes(view: &View) -> [DVec4; 4] {
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
pub(super) fn depth_planes(view: &View) -> [DVec4; 2] {
    let m = view.view_proj.transpose();
    [
        DVec4::new(0.0, 0.0, 1.0, 1.0),
        DVec4::new(0.0, 0.0, -1.0, 1.0),
    ]
    .map(|e| m * e)
}

/// The viewport's four sides in world space, as [`depth_planes`]: -w <= x, y <= w.
pub(super) fn viewport_planes(view: &View) -> [DVec4; 4] {
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
pub(super) struct ClipVertex {
    pub(super) p: DVec3,
    n: DVec3,
}

/// The triangle clipped so far, in order around it.
#[derive(Clone, Copy, Debug)]
pub(super) struct Polygon {
    v: [ClipVertex; POLYGON_CAPACITY],
    pub(super) len: usize,
}

impl Polygon {
    pub(super) fn new(positions: &[DVec3; 3], normals: &[DVec3; 3]) -> Self {
        let mut v = [ClipVertex::default(); POLYGON_CAPACITY];
        for k in 0..3 {
            v[k] = ClipVertex {
                p: positions[k],
                n: normals[k],
            };
        }
        Polygon { v, len: 3 }
    }

    pub(super) fn vertices(&self) -> &[ClipVertex] {
        &self.v[..self.len]
    }

    /// Clipped against each plane in turn; `None` if it outgrows its room ([`Self::clip`]).
    fn clip_all(self, planes: impl IntoIterator<Item = DVec4>) -> Option<Polygon> {
        planes.into_iter().try_fold(self, |p, q| p.clip(q))
    }

    /// Sutherland–Hodgman against one plane: the part where q · (p, 1) >= 0. A vertex on
    /// the plane is kept once (a crossing needs strictly opposite signs). `None` if the
    /// polygon outgrows its room, which only rounding at astronomic coordinates could do.
    pub(super) fn clip(&self, q: DVec4) -> Option<Polygon> {
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
pub(super) fn crossing(a: &ClipVertex, da: f64, b: &ClipVertex, db: f64) -> ClipVertex {
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
pub(super) fn clip<R: Real>(
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
pub(super) fn clip_depth<R: Real>(
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
pub(super) fn fan<R: Real>(
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
    // The fan of a strictly convex polygon has one orientation: its pieces face the same way.
    let (mut all_outside, mut back, before) = (true, false, out.len());
    for k in 1..n - 1 {
        let [a, b, c] = [order[0], order[k], order[k + 1]];
        match ScreenTriangle::assemble(
            id,
            [x[a], x[b], x[c]],
            [y[a], y[b], y[c]],
            [v[a], v[b], v[c]],
            color,
            view.viewport,
            view.samples,
            view.culling,
        ) {
            Ok(t) => out.push(t),
            Err(cull) => {
                back |= cull == TriangleCull::BackFace;
                all_outside &= cull == TriangleCull::Outside;
            }
        }
    }
    SetupOutcome {
        fan: n - 2,
        cull: (out.len() == before).then_some(if back {
            TriangleCull::BackFace
        } else if all_outside {
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
pub(super) fn make_convex(x: &[i64], y: &[i64], order: &mut [usize], mut n: usize) -> usize {
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
    /// Window depth.
    pub z: R,
    /// 1/w, for perspective-correct interpolation.
    pub inv_w: R,
    /// World normal over w.
    pub normal_w: [R; 3],
    /// World position over w.
    pub position_w: [R; 3],
}

impl<R: Real> ScreenTriangle<R> {
    /// Orients, bounds and sets up the edge functions of a triangle with snapped vertices
    /// (x, y) [1/256 pixel] on `viewport`, the sample grid of `samples` per pixel; with
    /// `culling` on, a triangle whose signed area says it faces away is culled before its
    /// edge functions are set up.
    #[allow(clippy::too_many_arguments)]
    pub fn assemble(
        id: u32,
        mut x: [i64; 3],
        mut y: [i64; 3],
        mut v: [Vertex<R>; 3],
        color: [R; 3],
        viewport: Viewport,
        samples: Samples,
        culling: Culling,
    ) -> Result<Self, TriangleCull> {
        // The doubled area (2 multiplies, 5 adds); for a triangle not culled for its facing,
        // the three edge functions (2 multiplies and 3 adds each, a compare for the top-left
        // rule) and the bounding box (8 compares).
        R::count_beside(Op::IntMul, 2);
        R::count_beside(Op::IntAdd, 5);
        let mut area2 = (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]);
        // Seen with y down, a triangle counter-clockwise from its front (OpenGL's window
        // coordinates, y up) has a negative area; the sign test is wiring.
        let back = match culling {
            Culling::Off => false,
            Culling::Back {
                front: Winding::Ccw,
            } => area2 > 0,
            Culling::Back { front: Winding::Cw } => area2 < 0,
        };
        if back {
            return Err(TriangleCull::BackFace);
        }
        R::count_beside(Op::IntMul, 6);
        R::count_beside(Op::IntAdd, 12 + 8);
        if area2 == 0 {
            return Err(TriangleCull::Degenerate);
        }
        if area2 < 0 {
            // Clockwise as seen with y down: swap two vertices so the edge functions are
            // positive inside (a face the view does not cull, whichever side it shows).
            x.swap(1, 2);
            y.swap(1, 2);
            v.swap(1, 2);
            area2 = -area2;
        }
        let (vw, vh) = (viewport.width as i64, viewport.height as i64);
        // Pixel i's centre 256 i + 128 is inside [lo, hi] for first(lo) <= i <= last(hi); a
        // sample displaced by d [1/256 pixel] from it, for first(lo - d) <= i <= last(hi - d).
        let first = |lo: i64| (lo - SUBPIXEL / 2 + SUBPIXEL - 1).div_euclid(SUBPIXEL);
        let last = |hi: i64| (hi - SUBPIXEL / 2).div_euclid(SUBPIXEL);
        let (dmin, dmax) = samples.dx16_range();
        let (first_x, last_x) = (
            |lo: i64| first(lo - SUBPIXEL / 16 * dmax),
            |hi: i64| last(hi - SUBPIXEL / 16 * dmin),
        );
        let (xmin, xmax) = (x[0].min(x[1]).min(x[2]), x[0].max(x[1]).max(x[2]));
        let (ymin, ymax) = (y[0].min(y[1]).min(y[2]), y[0].max(y[1]).max(y[2]));
        let (i0, i1) = (first_x(xmin).max(0), (last_x(xmax) + 1).min(vw));
        let (j0, j1) = (first(ymin).max(0), (last(ymax) + 1).min(vh));
        if i0 >= i1 || j0 >= j1 {
            let outside =
                last_x(xmax) < 0 || first_x(xmin) >= vw || last(ymax) < 0 || first(ymin) >= vh;
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
            samples,
        })
    }
}
