//! See-through: gaps between primitives that let one look into or through a mesh.
//!
//! A lembo built from a mesh triangle keeps the triangle as its corners A, B, C
//! (`points[0..3]`), so the input mesh itself is known exactly. It is rasterized flat here,
//! in f64: at every pixel centre, the nearest triangle whose projection holds the centre
//! (edges included, window depth in [0, 1], interpolated affinely in screen space, exact for
//! a plane; triangles with a corner at or behind the eye are skipped). Where that triangle
//! T faces the eye, the mesh puts a front-facing surface at the pixel, and the pixel is
//! *see-through* when the render shows there:
//! - **the background**: no primitive won it;
//! - **a back face**: the winning fragment's normal faces away from the eye (the render's
//!   normal buffer, against the pixel centre's ray) and so does the winning lembo's own
//!   surface there (its geometric normal, turned to the side of its normal function, where
//!   the ray meets it first; on the triangle path, the winning triangle's plane, turned to
//!   the side of its vertex normals), i.e. one looks at the inside of the surface. The shading
//!   normal alone does not say so: across a crease a lembo's normal function leans up to
//!   half the crease angle away from its surface, so a face seen at a grazing angle can
//!   have its front to the eye and its shading normal turned away (a rock auto-smoothed at
//!   40 degrees counted up to 313 such pixels at 512x512, `rock_creased` 97);
//! - **a foreign surface behind T**: the winner shares no corner position with T (a corner
//!   of the winning lembo equal, bit for bit, to a corner of T; T's own lembo shares all
//!   three) and its depth is greater than T's at the pixel, i.e. one looks past T at some
//!   other part of the scene.
//!
//! Not see-through, when facing the eye: T's own lembo or a neighbour sharing a corner,
//! wherever it lies (a smooth patch may lie a little behind its flat triangle in concave
//! places, or reach past it), and any surface in front of T (a smooth patch bulging over a
//! part of the mesh behind it, near an outline).
//!
//! Not checked: pixels near the flat mesh's outline (`near_outline`: within
//! [`OUTLINE_MARGIN_PX`] plus the lembos' own deviation from their triangles), where the
//! smooth surface's outline legitimately differs from the flat one, by up to a few pixels
//! on a coarse mesh (a smooth rim bulging past its chord shows what is behind the flat
//! triangle, an interpolated normal faces away near a contour). Without this the bunny
//! at 512x512 counted 92 such pixels; with the fixed margin alone cylinder24 (open, 24
//! coarse triangles) still counted 30.
//!
//! T faces the eye when its geometric normal, oriented by its vertex normals (the side of
//! the sum of its three corner normals, since an OBJ's winding need not be consistent),
//! points towards the eye at its centroid.
//!
//! The winner's id is a lembo id on the lembo path (Setup's pieces keep their lembo's id),
//! and `lembo * n² + k` on the triangle path at tessellation level n: [`Drawn`] maps it
//! back.

use super::oracle::LemboSource;
use super::surface::{corners_share, oriented_normal, screen_deviation, Drawn, Made, Shown};
use crate::camera::View;
use crate::lembo::construct::bits_key;
use crate::lembo::set::LastParent;
use crate::rop::framebuffer::{FrameBuffer, NO_PRIMITIVE};
use glam::{DVec2, DVec3};
use rayon::prelude::*;

/// Pixels this close to the flat mesh's outline, beyond the lembos' own deviation from
/// their triangles, are not checked \[pixels\] (see `near_outline`).
pub const OUTLINE_MARGIN_PX: f64 = 2.0;

/// See-through pixels by what the render shows there (see the module documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SeeThrough {
    /// The background.
    pub background: u64,
    /// A surface facing away from the eye.
    pub back_face: u64,
    /// A surface sharing no corner with the mesh triangle, behind it.
    pub foreign_behind: u64,
    /// Pixels where the mesh shows a front-facing triangle (the population checked).
    pub front_facing: u64,
}

impl SeeThrough {
    /// See-through pixels in all.
    pub fn total(&self) -> u64 {
        self.background + self.back_face + self.foreign_behind
    }
}

/// The nearest flat mesh triangle per pixel centre.
struct FlatMesh {
    /// Lembo id of the nearest triangle, or [`NO_PRIMITIVE`].
    owner: Vec<u32>,
    /// Its window depth.
    depth: Vec<f64>,
}

/// A mesh triangle projected for [`FlatMesh::draw`]: its lembo's id, its corners' screen
/// positions and window depths, its signed screen area, and the pixel centres its box
/// holds (columns `i0..=i1`, rows `j0..=j1`).
struct ScreenTriangle {
    id: u32,
    xy: [DVec2; 3],
    depth: [f64; 3],
    area: f64,
    columns: (usize, usize),
    rows: (usize, usize),
}

impl ScreenTriangle {
    /// Triangle `corners` of lembo `id` seen by `view`; None when no pixel centre can see
    /// it (a corner at or behind the eye, a zero or non-finite area, a box holding no
    /// centre).
    fn new(id: u32, corners: &[DVec3; 3], view: &View) -> Option<Self> {
        let (w, h) = (view.viewport.width as usize, view.viewport.height as usize);
        let s = corners.map(|c| view.project(c));
        if s.iter()
            .any(|p| p.w.is_nan() || p.w <= 0.0 || !p.x.is_finite() || !p.y.is_finite())
        {
            return None;
        }
        let xy = s.map(|p| DVec2::new(p.x, p.y));
        let area = (xy[1] - xy[0]).perp_dot(xy[2] - xy[0]);
        if area == 0.0 || !area.is_finite() {
            return None;
        }
        let lo = xy[0].min(xy[1]).min(xy[2]);
        let hi = xy[0].max(xy[1]).max(xy[2]);
        let first = |v: f64| (v - 0.5).ceil().max(0.0);
        let last = |v: f64, n: usize| (v - 0.5).floor().min(n as f64 - 1.0);
        let (i0, i1) = (first(lo.x), last(hi.x, w));
        let (j0, j1) = (first(lo.y), last(hi.y, h));
        if i0 > i1 || j0 > j1 {
            return None;
        }
        Some(ScreenTriangle {
            id,
            xy,
            depth: s.map(|p| p.depth),
            area,
            columns: (i0 as usize, i1 as usize),
            rows: (j0 as usize, j1 as usize),
        })
    }
}

impl FlatMesh {
    /// No triangle anywhere on a `view`'s pixels.
    fn new(view: &View) -> Self {
        let (w, h) = (view.viewport.width as usize, view.viewport.height as usize);
        FlatMesh {
            owner: vec![NO_PRIMITIVE; w * h],
            depth: vec![f64::INFINITY; w * h],
        }
    }

    /// Rasterizes `triangles` at pixel centres, keeping the nearest at each (ties to the
    /// smaller id, so neither the order triangles come in nor the bands of rows they are
    /// drawn in, in parallel, matter).
    fn draw(&mut self, triangles: &[ScreenTriangle], w: usize) {
        const BAND_ROWS: usize = 16;
        let bands = self.owner.len().div_ceil(BAND_ROWS * w);
        let mut of_band: Vec<Vec<&ScreenTriangle>> = vec![Vec::new(); bands];
        for t in triangles {
            for band in &mut of_band[t.rows.0 / BAND_ROWS..=t.rows.1 / BAND_ROWS] {
                band.push(t);
            }
        }
        self.owner
            .par_chunks_mut(BAND_ROWS * w)
            .zip(self.depth.par_chunks_mut(BAND_ROWS * w))
            .zip(of_band)
            .enumerate()
            .for_each(|(band, ((owner, depth), triangles))| {
                let rows = band * BAND_ROWS..band * BAND_ROWS + owner.len() / w;
                for t in triangles {
                    for j in t.rows.0.max(rows.start)..=t.rows.1.min(rows.end - 1) {
                        let row = (j - rows.start) * w;
                        draw_row(t, j, &mut owner[row..row + w], &mut depth[row..row + w]);
                    }
                }
            });
    }
}

/// Row `j` of `t` at its pixel centres into that row's `owner` and `depth`.
fn draw_row(t: &ScreenTriangle, j: usize, owner: &mut [u32], depth: &mut [f64]) {
    let (xy, area) = (&t.xy, t.area);
    for i in t.columns.0..=t.columns.1 {
        let c = DVec2::new(i as f64 + 0.5, j as f64 + 0.5);
        // Barycentrics from the edge functions, positive inside whatever the winding.
        let b = [
            (xy[2] - xy[1]).perp_dot(c - xy[1]) / area,
            (xy[0] - xy[2]).perp_dot(c - xy[2]) / area,
            (xy[1] - xy[0]).perp_dot(c - xy[0]) / area,
        ];
        if b.iter().any(|&x| x < 0.0) {
            continue;
        }
        let z = b[0] * t.depth[0] + b[1] * t.depth[1] + b[2] * t.depth[2];
        let nearer = z < depth[i] || (z == depth[i] && t.id < owner[i]);
        if (0.0..=1.0).contains(&z) && nearer {
            depth[i] = z;
            owner[i] = t.id;
        }
    }
}

/// Whether the mesh triangle of corners `[a, b, c]` with normals `normals` faces the eye
/// of `view`.
fn faces_eye([a, b, c]: [DVec3; 3], normals: [DVec3; 3], view: &View) -> bool {
    oriented_normal([a, b, c], normals).dot(view.to_eye((a + b + c) / 3.0)) > 0.0
}

/// One use of a mesh edge by a triangle: the edge's corner positions hashed
/// ([`bits_key`]), the lembo, which edge (0: AB, 1: BC, 2: CA), and whether the triangle
/// faces the eye.
#[derive(Clone, Copy)]
struct EdgeUse {
    key: u128,
    id: u32,
    edge: u8,
    front: bool,
}

/// The corners of the three edges of a mesh triangle, by edge index.
const EDGES: [(usize, usize); 3] = [(0, 1), (1, 2), (2, 0)];

/// An edge's corner positions, bit for bit, in a canonical order (the smaller bits first);
/// `corners` are its triangle's.
fn edge_corners(corners: &[DVec3; 3], edge: usize) -> [[u64; 3]; 2] {
    let bits = |p: DVec3| p.to_array().map(f64::to_bits);
    let (a, b) = EDGES[edge];
    let (p, q) = (bits(corners[a]), bits(corners[b]));
    if p <= q {
        [p, q]
    } else {
        [q, p]
    }
}

/// Pixels near the flat mesh's outline: the projection of every edge used by a
/// front-facing triangle but not continued facing the eye (an edge between a front- and a
/// back-facing triangle, or of one triangle alone). There the smooth surface's outline
/// legitimately differs from the flat mesh's, by up to how far the lembos using the edge
/// stray from their triangles; a pixel is near when its centre is within
/// [`OUTLINE_MARGIN_PX`] plus that deviation of the edge. Edges are matched by their corner
/// positions, bit for bit (through [`bits_key`]), so split normals do not cut the mesh
/// apart; `uses` are every mesh triangle's three edges, sorted here.
fn near_outline(mut uses: Vec<EdgeUse>, lembos: &dyn LemboSource, view: &View) -> Vec<bool> {
    let (w, h) = (view.viewport.width as usize, view.viewport.height as usize);
    let mut near = vec![false; w * h];
    uses.par_sort_unstable_by_key(|u| u.key);
    let mut last = LastParent::default();
    for edge in uses.chunk_by(|a, b| a.key == b.key) {
        let front = edge.iter().filter(|u| u.front).count();
        let back = edge.len() - front;
        // Inside the front-facing surface: two front-facing triangles and no back-facing one.
        if front == 0 || (front >= 2 && back == 0) {
            continue;
        }
        // How far the lembos using the edge stray from their triangles, from the lembos
        // made again (an outline edge is rare; the pass kept only the hash), and the edge's
        // corners, from its first use's.
        let deviation = edge
            .iter()
            .map(|u| screen_deviation(&lembos.lembo(u.id as usize, &mut last).0, view))
            .fold(0.0, f64::max);
        let margin = OUTLINE_MARGIN_PX + deviation;
        if !margin.is_finite() {
            continue;
        }
        let (corners, _) = lembos.corners(edge[0].id as usize, &mut last);
        let key = edge_corners(&corners, edge[0].edge as usize);
        let [p, q] = key.map(|c| view.project(DVec3::from_array(c.map(f64::from_bits))));
        if p.w.is_nan() || q.w.is_nan() || p.w <= 0.0 || q.w <= 0.0 {
            continue;
        }
        let (a, b) = (DVec2::new(p.x, p.y), DVec2::new(q.x, q.y));
        if !(a.is_finite() && b.is_finite()) {
            continue;
        }
        let lo = a.min(b) - DVec2::splat(margin);
        let hi = a.max(b) + DVec2::splat(margin);
        let i0 = (lo.x - 0.5).ceil().max(0.0);
        let i1 = (hi.x - 0.5).floor().min(w as f64 - 1.0);
        let j0 = (lo.y - 0.5).ceil().max(0.0);
        let j1 = (hi.y - 0.5).floor().min(h as f64 - 1.0);
        if i0 > i1 || j0 > j1 {
            continue;
        }
        let ab = b - a;
        let len2 = ab.length_squared();
        for j in j0 as usize..=j1 as usize {
            for i in i0 as usize..=i1 as usize {
                let c = DVec2::new(i as f64 + 0.5, j as f64 + 0.5);
                let t = if len2 > 0.0 {
                    ((c - a).dot(ab) / len2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                if (c - (a + t * ab)).length() <= margin {
                    near[j * w + i] = true;
                }
            }
        }
    }
    near
}

/// The see-through pixels of `render` (see the module documentation). `lembos` are the
/// scene's lembos by id, made as they are needed (one pass in id order, then the winners
/// and mesh triangles of the pixels checked); `drawn` says which surface a winner's id
/// names (on the triangle path the winning triangle's own plane is the surface a back face
/// must turn away, since the lembo's surface lies elsewhere than its flat triangles).
///
/// # Panics
/// If the render kept no normal buffer, or differs in size from the viewport: bugs of the
/// caller.
pub fn see_through(
    lembos: &dyn LemboSource,
    view: &View,
    render: &FrameBuffer,
    drawn: Drawn,
) -> SeeThrough {
    let (w, h) = (view.viewport.width, view.viewport.height);
    assert_eq!(
        (render.width, render.height),
        (w, h),
        "render and view differ in size"
    );
    let normals = render
        .normal
        .as_ref()
        .expect("see-through needs the render's normal buffer (keep_normals)");
    let (flat, front, uses) = mesh_pass(lembos, view);
    let judge = Judge {
        flat,
        near: near_outline(uses, lembos, view),
        front,
        view,
    };
    let w = w as usize;
    // Rows in parallel, each with the lembos it last made; the counts are sums.
    let rows: Vec<SeeThrough> = (0..h as usize)
        .into_par_iter()
        .map(|j| {
            let mut made = [Made::new(lembos), Made::new(lembos)];
            let mut out = SeeThrough::default();
            for k in j * w..(j + 1) * w {
                if !judge.checked(k) {
                    continue;
                }
                out.front_facing += 1;
                let shown = Shown::of_render(render, normals, k);
                let [shown_made, mesh_made] = &mut made;
                match judge.kind(k, &shown, drawn, shown_made, mesh_made) {
                    Some(Kind::Background) => out.background += 1,
                    Some(Kind::BackFace) => out.back_face += 1,
                    Some(Kind::ForeignBehind) => out.foreign_behind += 1,
                    None => {}
                }
            }
            out
        })
        .collect();
    rows.into_iter()
        .fold(SeeThrough::default(), |a, b| SeeThrough {
            background: a.background + b.background,
            back_face: a.back_face + b.back_face,
            foreign_behind: a.foreign_behind + b.foreign_behind,
            front_facing: a.front_facing + b.front_facing,
        })
}

/// What a see-through pixel shows (see the module documentation).
enum Kind {
    Background,
    BackFace,
    ForeignBehind,
}

/// The flat mesh and where it is checked, to judge what a pixel shows.
struct Judge<'a> {
    flat: FlatMesh,
    near: Vec<bool>,
    /// Whether each lembo's mesh triangle faces the eye.
    front: Vec<bool>,
    view: &'a View,
}

impl Judge<'_> {
    /// Whether pixel `k` is checked: its nearest flat triangle faces the eye, and it is not
    /// near the flat mesh's outline.
    fn checked(&self, k: usize) -> bool {
        let t = self.flat.owner[k];
        t != NO_PRIMITIVE && self.front[t as usize] && !self.near[k]
    }

    /// How a checked pixel `k` showing `shown` (its ids named by `drawn`) is see-through,
    /// if it is; `shown_made` makes the shown lembos, `mesh_made` the mesh triangles'.
    fn kind(
        &self,
        k: usize,
        shown: &Shown,
        drawn: Drawn,
        shown_made: &mut Made,
        mesh_made: &mut Made,
    ) -> Option<Kind> {
        if shown.is_background() {
            return Some(Kind::Background);
        }
        let w = self.view.viewport.width as usize;
        let (x, y) = ((k % w) as f64 + 0.5, (k / w) as f64 + 0.5);
        let (origin, dir) = self.view.ray(x, y);
        if drawn.back_face(shown, origin, dir, shown_made) {
            return Some(Kind::BackFace);
        }
        if shown.depth <= self.flat.depth[k] {
            return None;
        }
        let shown = shown_made.corners(drawn.lembo_of(shown.winner))?;
        let triangle = mesh_made
            .corners(u64::from(self.flat.owner[k]))
            .expect("a flat triangle's lembo exists");
        (!corners_share(&shown, &triangle)).then_some(Kind::ForeignBehind)
    }
}

/// Lembos a task of [`mesh_pass`] reads.
const PASS_CHUNK: usize = 4096;

/// One pass over the lembos of a mesh, in windows of chunks read in parallel: the flat
/// mesh, which triangles face the eye, and the edges' uses. It reads only each lembo's
/// corners ([`LemboSource::corners`]: a mesh's lembos are not made), and keeps a window's
/// triangles only until they are drawn.
fn mesh_pass(lembos: &dyn LemboSource, view: &View) -> (FlatMesh, Vec<bool>, Vec<EdgeUse>) {
    let n = lembos.len();
    let meshed = (0..n).filter(|&id| lembos.is_from_mesh(id)).count();
    let mut flat = FlatMesh::new(view);
    let mut front = vec![false; n];
    let mut uses = Vec::with_capacity(3 * meshed);
    let window = PASS_CHUNK * 2 * rayon::current_num_threads();
    for start in (0..n).step_by(window) {
        let end = (start + window).min(n);
        let parts: Vec<(Vec<ScreenTriangle>, Vec<EdgeUse>)> = (start..end)
            .step_by(PASS_CHUNK)
            .collect::<Vec<_>>()
            .into_par_iter()
            .map(|from| {
                let mut last = LastParent::default();
                let mut triangles = Vec::new();
                let mut uses = Vec::new();
                for id in from..(from + PASS_CHUNK).min(end) {
                    if !lembos.is_from_mesh(id) {
                        continue;
                    }
                    let (corners, normals) = lembos.corners(id, &mut last);
                    let faces = faces_eye(corners, normals, view);
                    for edge in 0..3 {
                        uses.push(EdgeUse {
                            key: bits_key(edge_corners(&corners, edge).as_flattened()),
                            id: id as u32,
                            edge: edge as u8,
                            front: faces,
                        });
                    }
                    triangles.extend(ScreenTriangle::new(id as u32, &corners, view));
                }
                (triangles, uses)
            })
            .collect();
        let mut triangles = Vec::new();
        for (part_triangles, part) in parts {
            triangles.extend(part_triangles);
            for u in &part {
                front[u.id as usize] = u.front;
            }
            uses.extend(part);
        }
        flat.draw(&triangles, view.viewport.width as usize);
    }
    (flat, front, uses)
}

#[cfg(test)]
mod tests {
    use super::super::surface::fixtures::{flat, square, view, view_sized};
    use super::*;
    use crate::lembo::construct::lembo_from_triangle;
    use crate::lembo::Lembo;

    /// The flat mesh drawn in parallel bands of rows is the one drawn row by row over the
    /// whole frame, triangle by triangle in the other order: on a viewport whose height is
    /// not a whole number of bands, with triangles spanning several bands, leaving it,
    /// meeting at equal depths (the smaller id wins) and nearer ones over farther.
    #[test]
    fn the_flat_mesh_drawn_in_bands_is_the_one_drawn_row_by_row() {
        let view = view_sized(128, 100);
        let mut triangles = Vec::new();
        let mut seed = 12345u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) * 160.0 - 80.0
        };
        for id in 0..60u32 {
            let z = if id % 3 == 0 { 0.0 } else { next() / 40.0 };
            let corners = [0; 3].map(|_| DVec3::new(next(), next(), z));
            triangles.extend(ScreenTriangle::new(id, &corners, &view));
        }
        assert!(triangles.len() > 50);
        assert!(triangles.iter().any(|t| t.rows.1 - t.rows.0 > 40));
        let w = view.viewport.width as usize;
        let mut at_once = FlatMesh::new(&view);
        at_once.draw(&triangles, w);
        // Row by row over the whole frame, last triangle first: no bands.
        let mut one_by_one = FlatMesh::new(&view);
        for t in triangles.iter().rev() {
            for j in t.rows.0..=t.rows.1 {
                let row = j * w..(j + 1) * w;
                let FlatMesh { owner, depth } = &mut one_by_one;
                draw_row(t, j, &mut owner[row.clone()], &mut depth[row]);
            }
        }
        assert_eq!(at_once.owner, one_by_one.owner);
        assert_eq!(at_once.depth, one_by_one.depth);
        assert!(at_once.owner[(100 - 1) * w..]
            .iter()
            .any(|&o| o != NO_PRIMITIVE));
        assert!(at_once.owner.iter().filter(|&&o| o != NO_PRIMITIVE).count() > 128 * 100 / 2);
    }

    #[test]
    fn see_through_counts_background_back_faces_and_foreign_surfaces_behind() {
        let view = view();
        // A square of two triangles (ids 0 and 1, the second wound the other way) on screen
        // [24, 104]², and two small triangles off it (2 and 3) to stand for other surfaces.
        let [a, b] = square();
        let lembos = [
            a,
            b,
            flat(
                [[-60.0, -60.0], [-55.0, -60.0], [-60.0, -55.0]],
                -5.0,
                DVec3::Z,
            ),
            flat([[60.0, 60.0], [55.0, 60.0], [60.0, 55.0]], 1.0, DVec3::Z),
            // A surface whose front is turned away from the eye (not from the mesh).
            lembo_from_triangle(
                [[-25.0, -35.0], [0.0, -35.0], [-25.0, -10.0]].map(|[x, y]| DVec3::new(x, y, 0.0)),
                [-DVec3::Z; 3],
            ),
        ];
        let marked: Vec<(&Lembo, bool)> =
            lembos.iter().enumerate().map(|(i, l)| (l, i < 4)).collect();
        let depth = view.depth_of(DVec3::ZERO) as f32;
        // The render: the flat square itself, then one pixel of each kind.
        let mut fb = FrameBuffer::new(128, 128, [0; 3], true);
        for j in 24..104 {
            for i in 24..104 {
                let k = fb.index(i, j);
                // Above the diagonal from (24, 104) to (104, 24) on screen is triangle 1.
                fb.write(k, depth, u32::from(i + j < 128), [200; 3]);
                fb.normal.as_mut().unwrap()[k] = [0.0, 0.0, 1.0];
            }
        }
        assert_eq!(see_through(&marked, &view, &fb, Drawn::EXACT).total(), 0);
        let mut set = |i: u32, j: u32, id: u32, z: f32, n: [f32; 3]| {
            let k = fb.index(i, j);
            fb.depth[k] = z;
            fb.primitive[k] = id;
            fb.normal.as_mut().unwrap()[k] = n;
        };
        let up = [0.0, 0.0, 1.0];
        set(40, 90, NO_PRIMITIVE, 1.0, up); // background
        set(50, 90, 4, depth, [0.0, 0.0, -1.0]); // back face
        set(45, 90, 0, depth, [0.0, 0.0, -1.0]); // a shading normal turned away: not one
        set(60, 90, 2, depth + 0.05, up); // foreign, behind
        set(70, 90, 3, depth - 0.05, up); // foreign, in front: hides, not see-through
        set(80, 90, 1, depth + 0.05, up); // the neighbour, behind: a smooth patch's sag
        set(25, 60, NO_PRIMITIVE, 1.0, up); // within 2 px of the outline
        let s = see_through(&marked, &view, &fb, Drawn::EXACT);
        assert_eq!(
            (s.background, s.back_face, s.foreign_behind, s.total()),
            (1, 1, 1, 3),
            "{s:?}"
        );
        // The triangle path's ids: n² per lembo.
        for id in fb.primitive.iter_mut().filter(|p| **p != NO_PRIMITIVE) {
            *id = *id * 4 + 3;
        }
        let four = Drawn {
            ids_per_lembo: 4,
            triangles: None,
        };
        assert_eq!(see_through(&marked, &view, &fb, four), s);
    }
}
