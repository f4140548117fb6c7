//! The surface an atlas of discoids stands for, as the exact reference renders it
//! (`--reference` on a discoid scene): each discoid object's [`DiscoidSurface`] turned into
//! lembos the ray caster of `reference::oracle` intersects exactly.
//!
//! - A **mesh** (the mesh `from_mesh` discoids were placed on, or a `surface` given beside
//!   `items` or `surfels`) becomes one flat lembo per triangle: its corners, its edges'
//!   straight midpoints, and normals linear between the vertex normals (the midpoints'
//!   normals are the means of their ends'), so the reference is the flat mesh shaded with
//!   interpolated vertex normals, exactly.
//! - A **sphere** (the builtin curved discoids) becomes [`sphere_lembos`] at
//!   [`SPHERE_REFERENCE_LEVELS`]: 20 480 lembos within a millionth of the radius of the true
//!   sphere (tested in `discoid::shapes`), under 0.01 px even for a sphere as wide as the
//!   largest viewport (16 384 px); the normals are the sphere's exactly at the reference
//!   points.

use super::{Scene, SceneObject};
use crate::discoid::shapes::{sphere_lembos, SPHERE_REFERENCE_LEVELS};
use crate::discoid::DiscoidSurface;
use crate::lembo::Lembo;

/// The lembos of `surface`, in world space.
pub fn surface_lembos(surface: &DiscoidSurface) -> Vec<Lembo> {
    match surface {
        DiscoidSurface::Sphere { center, radius } => sphere_lembos(SPHERE_REFERENCE_LEVELS)
            .into_iter()
            .map(|l| Lembo::new(l.points.map(|p| *center + *radius * p), l.normals))
            .collect(),
        DiscoidSurface::Mesh(mesh) => mesh
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
                let [na, nb, nc] = t.map(|i| mesh.normals[i as usize]);
                Lembo::new(
                    [a, b, c, 0.5 * (a + b), 0.5 * (a + c), 0.5 * (b + c)],
                    [
                        na,
                        nb,
                        nc,
                        0.5 * (na + nb),
                        0.5 * (na + nc),
                        0.5 * (nb + nc),
                    ],
                )
            })
            .collect(),
    }
}

/// Whether every discoid object of `scene` says what surface it stands for; Err names the
/// first that does not. Builds nothing: what a check before any work needs.
pub fn check_surfaces(scene: &Scene) -> Result<(), String> {
    match scene
        .objects
        .iter()
        .enumerate()
        .find(|(_, o)| o.discoids.as_ref().is_some_and(|d| d.surface.is_none()))
    {
        Some((k, o)) => Err(format!(
            "objects[{k}] ({}) does not say what surface its discoids stand for: give it a \
             `surface` mesh, or use `from_mesh` or a builtin",
            o.label
        )),
        None => Ok(()),
    }
}

/// The scene the exact reference of a discoid scene renders: every discoid object replaced
/// by its surface's lembos, in its colour. Err as [`check_surfaces`].
pub fn surface_scene(scene: &Scene) -> Result<Scene, String> {
    check_surfaces(scene)?;
    let mut out = scene.clone();
    for o in out.objects.iter_mut() {
        let Some(surface) = o.discoids.take().and_then(|set| set.surface) else {
            continue;
        };
        *o = SceneObject {
            label: format!("surface of {}", o.label),
            color: o.color,
            lembos: surface_lembos(&surface).into(),
            from_mesh: false,
            discoids: None,
        };
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lembo::construct::TriangleMesh;
    use glam::DVec3;

    #[test]
    fn a_mesh_surface_is_its_flat_triangles_with_linear_normals() {
        let mesh = TriangleMesh {
            positions: vec![DVec3::ZERO, DVec3::X, DVec3::Y],
            normals: vec![
                DVec3::Z,
                DVec3::new(0.0, 0.6, 0.8),
                DVec3::new(0.6, 0.0, 0.8),
            ],
            triangles: vec![[0, 1, 2]],
        };
        let lembos = surface_lembos(&DiscoidSurface::Mesh(mesh));
        assert_eq!(lembos.len(), 1);
        let l = &lembos[0];
        for (u, v) in [(0.2, 0.3), (0.5, 0.5), (0.0, 0.9)] {
            // Flat: the position is the affine map of the triangle.
            let p = l.position_at(u, v);
            let w = 1.0 - u - v;
            let want = w * DVec3::ZERO + u * DVec3::X + v * DVec3::Y;
            assert!(p.distance(want) < 1e-12, "{p} {want}");
        }
    }

    #[test]
    fn a_sphere_surface_is_placed_and_sized() {
        let lembos = surface_lembos(&DiscoidSurface::Sphere {
            center: DVec3::new(1.0, 2.0, 3.0),
            radius: 2.0,
        });
        for l in lembos.iter().step_by(97) {
            let r = (l.position_at(0.3, 0.3) - DVec3::new(1.0, 2.0, 3.0)).length();
            assert!((r - 2.0).abs() < 1e-5, "{r}");
        }
    }
}
