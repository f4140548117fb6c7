//! Where the reference takes its lembos from: made by id when a tile asks for them, so
//! that nothing holds every lembo of a scene (DESIGN.md §3, "Streamed primitives").

use crate::lembo::set::{Corners, LastParent};
use crate::lembo::Lembo;
use crate::scene::{LemboIndex, Scene};

/// Lembos by id, made on demand: what the reference traces and the see-through check
/// reads.
pub trait LemboSource: Sync {
    /// How many lembos there are (ids `0..len`).
    fn len(&self) -> usize;

    /// Whether there are none.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Lembo `id` and its linear RGB colour in [0, 1]. `last` is the caller's, kept from
    /// call to call: a caller taking ids in ascending order makes a subdivided lembo's
    /// parent once for all its children.
    fn lembo(&self, id: usize, last: &mut LastParent) -> (Lembo, [f64; 3]);

    /// Lembo `id`'s corners A, B, C and their normals, bit for bit those of
    /// [`LemboSource::lembo`]'s, for a caller that reads nothing else (a source that can
    /// give them without making the lembo does).
    fn corners(&self, id: usize, last: &mut LastParent) -> Corners {
        let (l, _) = self.lembo(id, last);
        (
            [l.points[0], l.points[1], l.points[2]],
            [l.normals[0], l.normals[1], l.normals[2]],
        )
    }

    /// Lembo `id`'s six reference points, bit for bit those of [`LemboSource::lembo`]'s,
    /// for a caller that reads nothing else.
    fn points(&self, id: usize, last: &mut LastParent) -> [glam::DVec3; 6] {
        self.lembo(id, last).0.points
    }

    /// Whether lembo `id` stands for a triangle of a mesh (its corners A, B, C are the
    /// triangle's), so that the see-through check holds it against that triangle.
    fn is_from_mesh(&self, id: usize) -> bool;
}

/// Held lembos with their colours, none from a mesh (tests, small scenes).
impl LemboSource for Vec<(&Lembo, [f64; 3])> {
    fn len(&self) -> usize {
        Vec::len(self)
    }

    fn lembo(&self, id: usize, _: &mut LastParent) -> (Lembo, [f64; 3]) {
        (self[id].0.clone(), self[id].1)
    }

    fn is_from_mesh(&self, _: usize) -> bool {
        false
    }
}

/// Held lembos, each marked `true` where it stands for a mesh triangle, all black.
impl LemboSource for Vec<(&Lembo, bool)> {
    fn len(&self) -> usize {
        Vec::len(self)
    }

    fn lembo(&self, id: usize, _: &mut LastParent) -> (Lembo, [f64; 3]) {
        (self[id].0.clone(), [0.0; 3])
    }

    fn is_from_mesh(&self, id: usize) -> bool {
        self[id].1
    }
}

/// A scene's lembos in scene order, made by id ([`Scene::lembo_near`]).
pub struct SceneLembos<'a> {
    scene: &'a Scene,
    index: LemboIndex,
}

impl<'a> SceneLembos<'a> {
    /// The lembos of `scene`.
    pub fn new(scene: &'a Scene) -> Self {
        SceneLembos {
            scene,
            index: scene.lembo_index(),
        }
    }
}

impl LemboSource for SceneLembos<'_> {
    fn len(&self) -> usize {
        self.scene.lembo_count()
    }

    fn lembo(&self, id: usize, last: &mut LastParent) -> (Lembo, [f64; 3]) {
        self.scene.lembo_near(&self.index, id, last)
    }

    fn corners(&self, id: usize, last: &mut LastParent) -> Corners {
        self.scene.corners_near(&self.index, id, last)
    }

    fn points(&self, id: usize, last: &mut LastParent) -> [glam::DVec3; 6] {
        self.scene.points_near(&self.index, id, last)
    }

    fn is_from_mesh(&self, id: usize) -> bool {
        self.scene.objects[self.index.object(id)].from_mesh
    }
}
