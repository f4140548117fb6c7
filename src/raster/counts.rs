//! What the functional model produced, stage by stage ([`Counts`]): every stage adds to the
//! counts it is handed, and the drivers add up the shares of parallel units and bands.

use super::screen::{Cull, Split};
use serde::Serialize;

/// What the functional model produced, stage by stage.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Counts {
    /// Lembos in the scene.
    pub lembos: u64,
    /// Lembos dropped at the eye: with a perspective tolerance, those wholly nearer than the
    /// near plane; with `--perspective-tol off` (the paper's Setup, which does not clip),
    /// those with a point of their hull behind the eye.
    pub lembos_culled_behind_eye: u64,
    /// Lembos whose hull lies outside the viewport or depth range (one cull test each).
    pub lembos_culled_outside: u64,
    /// Lembos (or pieces of a split lembo) MinMax culled as facing away from the eye over
    /// their whole surface, by the conservative test of `raster::facing` (0 unless the run
    /// culls back faces: `minmax.cull_backfaces`).
    pub lembos_culled_backface: u64,
    /// Lembos whose screen map has zero area everywhere (a point, a line or a curve on
    /// screen): they cover no pixel centre and are dropped after the cull test.
    pub lembos_degenerate: u64,
    /// Lembos whose hull reaches beyond the split guard band, split by Setup into pieces
    /// (`setup::setup_pieces`).
    pub lembos_split: u64,
    /// Pieces of split lembos that go down the pipeline.
    pub lembo_pieces: u64,
    /// Sub-patches of split lembos dropped because their hull misses the viewport.
    pub lembo_pieces_culled: u64,
    /// Lembos split because their rebuilt screen quadratics were farther than the
    /// perspective tolerance from the true projection (`refine.rs`).
    pub lembos_split_perspective: u64,
    /// Lembos split because part of them lies too near the eye to be projected (they cross
    /// the near plane; `refine.rs`).
    pub lembos_split_near: u64,
    /// Sub-patches of split lembos dropped because they lie wholly nearer than the near plane.
    pub lembo_pieces_culled_near: u64,
    /// Sub-patches kept at the split depth or piece cap while still over the perspective
    /// tolerance or the guard band (or dropped there, still unprojectable).
    pub lembo_pieces_capped: u64,
    /// (lembo, scanline) pairs handed to the interval manager.
    pub scanlines: u64,
    /// Roots of Y = y_j found on domain edges.
    pub edge_roots: u64,
    /// Roots on the partition line (ellipse tips around an interior extremum).
    pub virtual_roots: u64,
    /// Intervals (curve pieces) produced.
    pub intervals: u64,
    /// Roots that could not be paired (0 unless rounding broke the walk order).
    pub unpaired_roots: u64,
    /// Intervals split at a saddle crossing.
    pub saddle_splits: u64,
    /// Segments (chords of midpoint error k) produced.
    pub segments: u64,
    /// Segments clamped to their interval end (the last of each walk, flat curves).
    pub segments_clamped: u64,
    /// Extra splits of a walk's clamped last chord whose midpoint error exceeded k.
    pub segments_refined: u64,
    /// Subsegments (pieces along which x is linear) produced.
    pub subsegments: u64,
    /// Segments split at a fold of x(t).
    pub folds: u64,
    /// Triangles of the triangle path (tessellated lembos).
    pub triangles: u64,
    /// Triangles dropped because they lie wholly on the eye's side of the near plane
    /// (nearer than it, or behind the eye).
    pub triangles_culled_behind_eye: u64,
    /// Triangles (or pieces of a clipped one, counted once for the triangle) setup culled as
    /// facing away from the eye by their snapped signed area (0 unless the run culls back
    /// faces: `triangle_setup.cull_backfaces`).
    pub triangles_culled_backface: u64,
    /// Triangles with a vertex beyond the 16.8 guard band (±32767 px), clipped to it and
    /// fanned into pieces that are set up and rasterized as triangles with their parent's id.
    pub triangles_clipped: u64,
    /// Triangles crossing the near or the far plane, clipped to the depth range in clip
    /// space (then to the guard band if they still reach beyond it) and fanned into pieces
    /// as above.
    pub triangles_clipped_depth: u64,
    /// Triangles beside the viewport or wholly beyond the far plane (one cull test each).
    pub triangles_culled_outside: u64,
    /// Triangles of zero area after snapping, or covering no pixel centre of their box.
    pub triangles_degenerate: u64,
    /// 2x2 quads with at least one covered pixel (triangle path).
    pub quads: u64,
    /// Fragments generated (pixel centres covered by subsegments or triangles, inside the
    /// viewport).
    pub fragments: u64,
    /// Fragments that passed the depth test when they arrived.
    pub fragments_passed_depth: u64,
    /// Pixels covered in the final image.
    pub pixels_covered: u64,
}

impl Counts {
    /// Covered pixels over pixels of the quads rasterized, fragments / (4 quads); None
    /// when no quad was rasterized (the lembo path).
    pub fn quad_efficiency(&self) -> Option<f64> {
        (self.quads > 0).then(|| self.fragments as f64 / (4 * self.quads) as f64)
    }

    /// Counts a lembo Setup dropped.
    pub fn add_cull(&mut self, cull: Cull) {
        match cull {
            Cull::BehindEye => self.lembos_culled_behind_eye += 1,
            Cull::Outside => self.lembos_culled_outside += 1,
            Cull::Degenerate => self.lembos_degenerate += 1,
        }
    }

    /// Counts what splitting a lembo into `pieces` pieces took (nothing for a whole lembo).
    pub fn add_split(&mut self, split: Split, pieces: usize) {
        if split != Split::default() {
            self.lembos_split += 1;
            self.lembo_pieces += pieces as u64;
            self.lembo_pieces_culled += split.culled as u64;
            self.lembos_split_perspective += split.perspective as u64;
            self.lembos_split_near += split.near as u64;
            self.lembo_pieces_culled_near += split.culled_near as u64;
            self.lembo_pieces_capped += split.capped as u64;
        }
    }
}

impl std::ops::AddAssign for Counts {
    /// Sums the shares of parallel units.
    fn add_assign(&mut self, o: Counts) {
        self.lembos += o.lembos;
        self.lembos_culled_behind_eye += o.lembos_culled_behind_eye;
        self.lembos_culled_outside += o.lembos_culled_outside;
        self.lembos_culled_backface += o.lembos_culled_backface;
        self.lembos_degenerate += o.lembos_degenerate;
        self.lembos_split += o.lembos_split;
        self.lembo_pieces += o.lembo_pieces;
        self.lembo_pieces_culled += o.lembo_pieces_culled;
        self.lembos_split_perspective += o.lembos_split_perspective;
        self.lembos_split_near += o.lembos_split_near;
        self.lembo_pieces_culled_near += o.lembo_pieces_culled_near;
        self.lembo_pieces_capped += o.lembo_pieces_capped;
        self.scanlines += o.scanlines;
        self.edge_roots += o.edge_roots;
        self.virtual_roots += o.virtual_roots;
        self.intervals += o.intervals;
        self.unpaired_roots += o.unpaired_roots;
        self.saddle_splits += o.saddle_splits;
        self.segments += o.segments;
        self.segments_clamped += o.segments_clamped;
        self.segments_refined += o.segments_refined;
        self.subsegments += o.subsegments;
        self.folds += o.folds;
        self.triangles += o.triangles;
        self.triangles_culled_behind_eye += o.triangles_culled_behind_eye;
        self.triangles_culled_backface += o.triangles_culled_backface;
        self.triangles_clipped += o.triangles_clipped;
        self.triangles_clipped_depth += o.triangles_clipped_depth;
        self.triangles_culled_outside += o.triangles_culled_outside;
        self.triangles_degenerate += o.triangles_degenerate;
        self.quads += o.quads;
        self.fragments += o.fragments;
        self.fragments_passed_depth += o.fragments_passed_depth;
        self.pixels_covered += o.pixels_covered;
    }
}
