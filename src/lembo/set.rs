//! An object's lembos as a scene holds them: the lembos themselves where there are few
//! (inline lembos, a discoid sphere's), or what they are made from, each lembo made when it
//! is asked for (a mesh's lembos, subdivided lembos). A scene of millions of lembos then
//! holds its mesh, 36 bytes a lembo for a terrain, rather than 576 bytes a lembo, and the
//! stages that read it in order (Setup, the geometry fetch, the tessellator) make each lembo
//! as it comes (DESIGN.md §3, "Streamed primitives").
//!
//! Making a lembo is deterministic: [`Lembos::get`] gives the same lembo, bit for bit, every
//! time and as [`TriangleMesh::to_lembos`](super::construct::TriangleMesh::to_lembos) and
//! [`subdivide`](super::lattice::subdivide) give it.

use super::construct::{MeshLembos, TriangleMesh};
use super::lattice::subdivided;
use super::Lembo;
use glam::DVec3;

/// A lembo's corners A, B, C and their normals (`points[0..3]`, `normals[0..3]`).
pub type Corners = ([DVec3; 3], [DVec3; 3]);

/// The parent a subdivided lembo was last made from, with the tag and index it was made
/// for ([`Lembos::get_near`]).
#[derive(Clone, Debug, Default)]
pub struct LastParent(Option<(usize, usize, Lembo)>);

/// An object's lembos, held or made on demand.
#[derive(Clone, Debug, PartialEq)]
pub enum Lembos {
    /// The lembos themselves.
    Held(Vec<Lembo>),
    /// One lembo a triangle of a mesh, made on demand.
    Mesh(MeshLembos),
    /// Each lembo of the base subdivided `s` times, into 4^s lembos made on demand.
    Subdivided {
        /// The lembos subdivided.
        base: Box<Lembos>,
        /// The subdivision level.
        s: u32,
    },
}

impl Default for Lembos {
    fn default() -> Self {
        Lembos::Held(Vec::new())
    }
}

impl From<Vec<Lembo>> for Lembos {
    fn from(lembos: Vec<Lembo>) -> Self {
        Lembos::Held(lembos)
    }
}

impl Lembos {
    /// How many lembos there are.
    pub fn len(&self) -> usize {
        match self {
            Lembos::Held(v) => v.len(),
            Lembos::Mesh(m) => m.len(),
            Lembos::Subdivided { base, s } => base.len() << (2 * s),
        }
    }

    /// Whether there is none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Lembo `i` (`i < len()`), made if it is not held.
    pub fn get(&self, i: usize) -> Lembo {
        match self {
            Lembos::Held(v) => v[i].clone(),
            Lembos::Mesh(m) => m.get(i),
            Lembos::Subdivided { base, s } => {
                let shift = 2 * s;
                subdivided(&base.get(i >> shift), *s, i & ((1 << shift) - 1))
            }
        }
    }

    /// Lembo `i` as [`Lembos::get`] makes it, a subdivided lembo's parent taken from `last`
    /// when it was the last one made there for `tag` (the caller's name for these lembos),
    /// else made and kept there: children taken in order make their parent once.
    pub fn get_near(&self, i: usize, tag: usize, last: &mut LastParent) -> Lembo {
        let Lembos::Subdivided { base, s } = self else {
            return self.get(i);
        };
        let shift = 2 * s;
        let p = i >> shift;
        let parent = match &mut last.0 {
            Some((t, q, parent)) if (*t, *q) == (tag, p) => parent,
            kept => &kept.insert((tag, p, base.get(p))).2,
        };
        subdivided(parent, *s, i & ((1 << shift) - 1))
    }

    /// Lembo `i`'s corners A, B, C and their normals, bit for bit those of the lembo
    /// [`Lembos::get_near`] makes: a mesh's lembos give their triangle without making the
    /// lembo's edges; the others are made.
    pub fn corners_near(&self, i: usize, tag: usize, last: &mut LastParent) -> Corners {
        match self {
            Lembos::Mesh(m) => m.corners(i),
            _ => {
                let l = self.get_near(i, tag, last);
                (
                    [l.points[0], l.points[1], l.points[2]],
                    [l.normals[0], l.normals[1], l.normals[2]],
                )
            }
        }
    }

    /// Lembo `i`'s six reference points, bit for bit those of the lembo
    /// [`Lembos::get_near`] makes: a mesh's lembos give them without their normals; the
    /// others are made.
    pub fn points_near(&self, i: usize, tag: usize, last: &mut LastParent) -> [DVec3; 6] {
        match self {
            Lembos::Mesh(m) => m.points(i),
            _ => self.get_near(i, tag, last).points,
        }
    }

    /// The lembos in order, each made as it is reached (a subdivided lembo's parent once for
    /// all its children).
    pub fn iter(&self) -> impl Iterator<Item = Lembo> + '_ {
        let mut last = LastParent::default();
        (0..self.len()).map(move |i| self.get_near(i, 0, &mut last))
    }

    /// Every lembo, made and held (what a test or a small scene's metric wants).
    pub fn to_vec(&self) -> Vec<Lembo> {
        self.iter().collect()
    }

    /// The triangle mesh the lembos were made from, if any (a subdivided mesh's lembos
    /// included).
    pub fn mesh(&self) -> Option<&TriangleMesh> {
        match self {
            Lembos::Held(_) => None,
            Lembos::Mesh(m) => Some(m.mesh()),
            Lembos::Subdivided { base, .. } => base.mesh(),
        }
    }

    /// The heap it holds \[bytes\].
    pub fn bytes(&self) -> usize {
        match self {
            Lembos::Held(v) => std::mem::size_of_val(&v[..]),
            Lembos::Mesh(m) => m.bytes(),
            Lembos::Subdivided { base, .. } => base.bytes(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lembo::lattice::subdivide;
    use crate::lembo::shapes::builtin_mesh;

    #[test]
    fn made_lembos_are_the_held_ones_bit_for_bit() {
        let mesh = builtin_mesh("sphere24").expect("a builtin").welded();
        let held = mesh.to_lembos().expect("lembos");
        let made = Lembos::Mesh(mesh.clone().into_lembos().expect("lembos"));
        assert_eq!(made.len(), held.len());
        assert_eq!(made.to_vec(), held);
        assert_eq!(made.mesh(), Some(&mesh));
        assert!(made.bytes() < std::mem::size_of_val(&held[..]) / 4);
        for s in 0..=2 {
            let sub = Lembos::Subdivided {
                base: Box::new(made.clone()),
                s,
            };
            let mut want = Vec::new();
            for l in &held {
                subdivide(l, s, &mut want);
            }
            assert_eq!(sub.len(), want.len());
            assert_eq!(sub.to_vec(), want, "s = {s}");
            for i in [0, 1, want.len() / 3, want.len() - 1] {
                assert_eq!(sub.get(i), want[i], "s = {s}, lembo {i}");
            }
            // One kept parent shared by two sets under their tags, in no particular order:
            // each lembo is still its own, whichever parent was kept.
            let mut last = LastParent::default();
            for i in [5, 0, 6, want.len() - 1, 5, 1] {
                let i = i.min(want.len() - 1);
                assert_eq!(sub.get_near(i, 7, &mut last), want[i], "s = {s}, lembo {i}");
                assert_eq!(
                    made.get_near(i % held.len(), 8, &mut last),
                    held[i % held.len()]
                );
                let other = sub.get_near(want.len() - 1 - i, 9, &mut last);
                assert_eq!(other, want[want.len() - 1 - i]);
            }
        }
    }

    /// A lembo's corners and corner normals, and its six points, read without making it are
    /// the made lembo's, bit for bit: on a mesh whose normals are neither unit nor shared
    /// across its creases, and on its subdivided lembos (made).
    #[test]
    fn corners_and_points_read_without_making_are_the_made_lembos_bit_for_bit() {
        let mut mesh = builtin_mesh("sphere24")
            .expect("a builtin")
            .with_crease_angle(20.0)
            .expect("no triangle collapses");
        for (k, n) in mesh.normals.iter_mut().enumerate() {
            *n *= 0.5 + k as f64;
        }
        let made = Lembos::Mesh(mesh.into_lembos().expect("lembos"));
        let sub = Lembos::Subdivided {
            base: Box::new(made.clone()),
            s: 1,
        };
        let bits = |v: &[DVec3]| {
            v.iter()
                .map(|p| p.to_array().map(f64::to_bits))
                .collect::<Vec<_>>()
        };
        for set in [&made, &sub] {
            let mut last = LastParent::default();
            for i in 0..set.len() {
                let l = set.get(i);
                let (corners, normals) = set.corners_near(i, 0, &mut last);
                assert_eq!(bits(&corners), bits(&l.points[..3]), "lembo {i}");
                assert_eq!(bits(&normals), bits(&l.normals[..3]), "lembo {i}");
                assert_eq!(bits(&set.points_near(i, 0, &mut last)), bits(&l.points));
            }
        }
    }
}
