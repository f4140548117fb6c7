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
        tobj::load_obj_buf(&mut std::io::Cursor::new(&bytes), &options, |_| {
            Err(tobj::LoadError::OpenFileFailed)
        })
        .map_err(|e| match first_bad_line(&bytes) {
            Some((line, text)) => mesh_err(format!("line {line} ({text:?}): not valid OBJ: {e}")),
            None => mesh_err(format!("not a valid OBJ file: {e}")),
        })?;
    // tobj takes a face of two corners (a truncated line) for a line, and drops it.
    if let Some((line, text)) = first_bad_line(&bytes) {
        return Err(mesh_err(format!(
            "line {line} ({text:?}): not valid OBJ (a face needs three corners, each naming a vertex the file gives)"
        )));
    }

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

/// The first line (1-based, with its text) of an OBJ file that is not a well-formed vertex,
/// normal, texture coordinate or face (a face needs three corners, each naming a vertex the
/// file gives): where a truncated or hand-broken file went wrong. None when every such line
/// is well formed.
fn first_bad_line(bytes: &[u8]) -> Option<(usize, String)> {
    let text = String::from_utf8_lossy(bytes);
    let numbers = |rest: &[&str], least: usize| {
        rest.len() >= least && rest[..least].iter().all(|t| t.parse::<f64>().is_ok())
    };
    // Vertices, texture coordinates and normals the file gives.
    let mut given = [0usize; 3];
    let mut faces = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let keyword = words.next().unwrap_or("");
        let rest: Vec<&str> = words.collect();
        let ok = match keyword {
            "v" => numbers(&rest, 3),
            "vt" => numbers(&rest, 1),
            "vn" => numbers(&rest, 3),
            "f" => {
                faces.push(n);
                rest.len() >= 3
            }
            _ => true,
        };
        if !ok {
            return Some((n + 1, line.to_string()));
        }
        if let Some(k) = ["v", "vt", "vn"].iter().position(|&w| w == keyword) {
            given[k] += 1;
        }
    }
    // A corner is v, v/t, v//n or v/t/n, 1-based (negative: back from the last one).
    let index = |t: &str, count: usize| {
        t.parse::<i64>()
            .is_ok_and(|i| i != 0 && i.unsigned_abs() as usize <= count)
    };
    let corner = |c: &str| {
        let parts: Vec<&str> = c.split('/').collect();
        parts.len() <= 3
            && index(parts[0], given[0])
            && parts
                .get(1)
                .is_none_or(|t| t.is_empty() || index(t, given[1]))
            && parts.get(2).is_none_or(|t| index(t, given[2]))
    };
    let lines: Vec<&str> = text.lines().collect();
    faces
        .into_iter()
        .find(|&n| !lines[n].split_whitespace().skip(1).all(corner))
        .map(|n| (n + 1, lines[n].to_string()))
}
