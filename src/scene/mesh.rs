//! Similarity transforms and OBJ meshes (tobj): a mesh file loaded, checked and placed
//! in world space.

use crate::error::{read_input, Error, Result, MAX_DATA_INPUT_BYTES};
use crate::lembo::construct::TriangleMesh;
use glam::{DMat3, DVec3};
use std::path::Path;

/// A similarity transform: uniform scale, then rotation, then translation.
pub(super) struct Transform {
    pub(super) scale: f64,
    pub(super) rotate: DMat3,
    pub(super) translate: DVec3,
}

impl Transform {
    pub(super) fn point(&self, p: DVec3) -> DVec3 {
        self.rotate * (p * self.scale) + self.translate
    }
}

pub(super) fn transform_mesh(mut mesh: TriangleMesh, t: Option<&Transform>) -> TriangleMesh {
    if let Some(t) = t {
        for p in &mut mesh.positions {
            *p = t.point(*p);
        }
        for n in &mut mesh.normals {
            *n = (t.rotate * *n).normalize_or_zero();
        }
    }
    mesh
}

/// Loads an OBJ file as one triangle mesh (all its models merged). `field` names the scene
/// field that gave the path, for errors.
pub(super) fn load_obj(file: &str, field: &str, path: &Path) -> Result<TriangleMesh> {
    let mesh_err = |message: String| Error::Mesh {
        file: file.to_string(),
        field: field.to_string(),
        path: path.to_path_buf(),
        message,
    };
    // Read the bytes ourselves: tobj's own open reports "open file failed" without the OS
    // reason.
    let bytes = read_input(path, MAX_DATA_INPUT_BYTES).map_err(|e| mesh_err(e.to_string()))?;
    // tobj's optional `merging` and `reordering` features add fields to LoadOptions.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    // Materials are not used: every `mtllib` is skipped.
    let (models, _materials) =
        tobj::load_obj_buf(&mut std::io::Cursor::new(bytes), &options, |_| {
            Err(tobj::LoadError::OpenFileFailed)
        })
        .map_err(|e| mesh_err(format!("not a valid OBJ file: {e}")))?;

    let mut mesh = TriangleMesh::default();
    let mut all_normals = true;
    for model in &models {
        let m = &model.mesh;
        let base = mesh.positions.len();
        let n_vertices = m.positions.len() / 3;
        mesh.positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|c| DVec3::new(c[0], c[1], c[2])),
        );
        // Normals are used only when every vertex of every model has one.
        all_normals &= m.normals.len() == m.positions.len();
        if all_normals {
            mesh.normals.extend(
                m.normals
                    .chunks_exact(3)
                    .map(|c| DVec3::new(c[0], c[1], c[2])),
            );
        }
        for (t, tri) in m.indices.chunks_exact(3).enumerate() {
            if let Some(&i) = tri.iter().find(|&&i| i as usize >= n_vertices) {
                return Err(mesh_err(format!(
                    "model {:?}, triangle {t}: vertex index {i} is out of range ({n_vertices} vertices)",
                    model.name
                )));
            }
            let offset = |i: u32| {
                u32::try_from(base + i as usize)
                    .map_err(|_| mesh_err("more than 2^32 vertices".into()))
            };
            mesh.triangles
                .push([offset(tri[0])?, offset(tri[1])?, offset(tri[2])?]);
        }
    }
    if mesh.triangles.is_empty() {
        return Err(mesh_err("holds no triangles".into()));
    }
    if let Some(i) = mesh.positions.iter().position(|p| !p.is_finite()) {
        return Err(mesh_err(format!(
            "vertex {i} has a non-finite coordinate {}",
            mesh.positions[i]
        )));
    }
    if all_normals {
        if let Some(i) = mesh.normals.iter().position(|n| !n.is_finite()) {
            return Err(mesh_err(format!(
                "vertex {i} has a non-finite normal {}",
                mesh.normals[i]
            )));
        }
        Ok(mesh)
    } else {
        Ok(mesh.with_computed_normals())
    }
}
