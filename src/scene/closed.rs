//! What back-face culling may assume of a scene (DESIGN.md §5, "Back-face culling"),
//! decided once a run: whether its surfaces are closed, consistently oriented meshes and
//! which winding faces out ([`Scene::outward_winding`]), and whether the view's near plane
//! leaves them whole ([`Scene::beyond_near_plane`]). A GPU culls what the application marks
//! cullable; `auto` culling marks a scene cullable when both hold, so that from where the
//! eye is no back face can be seen: a ray from an eye outside every closed surface meets a
//! front face (entering) before any back face (leaving).

use super::Scene;
use crate::camera::{View, Winding};
use crate::lembo::bezier_controls;
use crate::lembo::construct::TriangleMesh;

impl Scene {
    /// The winding that faces out of every object when each object is a closed,
    /// consistently oriented triangle mesh ([`outward_winding`]) and all agree; None for a
    /// scene with an open mesh, inline lembos (no mesh says how they join), discoids, or
    /// objects wound differently.
    pub fn outward_winding(&self) -> Option<Winding> {
        let mut winding = None;
        for o in &self.objects {
            if o.discoids.is_some() {
                return None;
            }
            let w = outward_winding(o.mesh()?)?;
            if winding.is_some_and(|v| v != w) {
                return None;
            }
            winding = Some(w);
        }
        winding
    }

    /// Whether every lembo's Bézier control net (which holds its surface) lies beyond the
    /// near plane of `view`: no part of the surface is clipped away, so the eye cannot
    /// look into a closed object through the cut. Makes every lembo once.
    pub fn beyond_near_plane(&self, view: &View) -> bool {
        // Perspective: the near plane is at `near` along the view direction from the eye;
        // orthographic: the same, with the eye the camera's position.
        self.lembos().all(|(l, _)| {
            bezier_controls(&l.points)
                .iter()
                .all(|&p| (p - view.eye).dot(view.forward) > view.near)
        })
    }
}

/// The winding facing out of `mesh` when it is closed and consistently oriented: every edge
/// (between welded positions) is shared by exactly two triangles that run it in opposite
/// directions. Out is the side its signed volume is positive on (counter-clockwise when
/// the triangles are counter-clockwise seen from outside). None for an open mesh, one whose
/// neighbours disagree on orientation, a non-manifold edge, or a volume of 0.
pub fn outward_winding(mesh: &TriangleMesh) -> Option<Winding> {
    if mesh.triangles.is_empty() {
        return None;
    }
    // Vertices by position (welded vertices have the same bits), numbered in sorted order.
    let key = |i: u32| mesh.positions[i as usize].to_array().map(f64::to_bits);
    let mut order: Vec<u32> = (0..mesh.positions.len() as u32).collect();
    order.sort_unstable_by_key(|&i| key(i));
    let mut id = vec![0u32; order.len()];
    let mut next = 0;
    for (k, &i) in order.iter().enumerate() {
        if k > 0 && key(order[k - 1]) != key(i) {
            next += 1;
        }
        id[i as usize] = next;
    }
    let mut edges: Vec<(u32, u32)> = Vec::with_capacity(3 * mesh.triangles.len());
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| id[i as usize]);
        edges.extend([(a, b), (b, c), (c, a)]);
    }
    edges.sort_unstable();
    // Each directed edge once, and its reverse once: two triangles an edge, opposite ways.
    if edges.windows(2).any(|w| w[0] == w[1]) {
        return None;
    }
    if !edges
        .iter()
        .all(|&(a, b)| a != b && edges.binary_search(&(b, a)).is_ok())
    {
        return None;
    }
    let volume: f64 = mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            a.dot(b.cross(c))
        })
        .sum();
    match volume {
        v if v > 0.0 => Some(Winding::Ccw),
        v if v < 0.0 => Some(Winding::Cw),
        _ => None,
    }
}

/// The triangles of a closed mesh with one triangle turned over: for tests.
#[cfg(test)]
pub(crate) fn turned(mesh: &TriangleMesh, t: usize) -> TriangleMesh {
    let mut m = mesh.clone();
    m.triangles[t].swap(1, 2);
    m
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn tetrahedron() -> TriangleMesh {
        let p = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.0, 0.0, 1.0),
        ];
        TriangleMesh {
            positions: p.to_vec(),
            normals: p.to_vec(),
            // Counter-clockwise seen from outside.
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        }
    }

    #[test]
    fn closed_meshes_say_which_way_is_out() {
        let m = tetrahedron();
        assert_eq!(outward_winding(&m), Some(Winding::Ccw));
        let mut inside_out = m.clone();
        for t in &mut inside_out.triangles {
            t.swap(1, 2);
        }
        assert_eq!(outward_winding(&inside_out), Some(Winding::Cw));
        // One face turned: its edges run the same way as its neighbours'.
        assert_eq!(outward_winding(&turned(&m, 2)), None);
        // A face missing: open.
        let mut open = m.clone();
        open.triangles.pop();
        assert_eq!(outward_winding(&open), None);
        // A split vertex at the same position joins as one (hard edges stay closed).
        let mut split = m.clone();
        split.positions.push(split.positions[3]);
        split.normals.push(DVec3::X);
        split.triangles[3][2] = 4;
        assert_eq!(outward_winding(&split), Some(Winding::Ccw));
    }

    #[test]
    fn shipped_builtins_are_closed_and_wound_outward() {
        for (file, closed) in [("traces/default.json", true), ("traces/bunny.json", true)] {
            let scene = Scene::load(std::path::Path::new(file)).unwrap();
            assert_eq!(scene.outward_winding().is_some(), closed, "{file}");
        }
    }
}
