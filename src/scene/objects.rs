//! Validation of one scene object (a builtin shape, inline lembos or an OBJ mesh): its
//! world-space lembos and mesh, in range, with its crease angle.

use super::{
    format::{LemboSpec, ObjectSpec},
    mesh::{load_obj, transform_mesh, Transform},
    validate::{given, lembo_in_range, Check},
    SceneObject, DEFAULT_COLOR, MAX_WORLD_COORDINATE,
};
use crate::error::{Error, Result};
use crate::lembo::construct::{CollapsedTriangle, TriangleMesh};
use crate::lembo::lattice::MAX_SUBDIVIDE;
use crate::lembo::set::Lembos;
use crate::lembo::shapes::{builtin_mesh, BUILTIN_NAMES, MAX_TERRAIN_CELLS};

/// The most lembos a scene with a subdivided object may have: 2^23, room for the bunny
/// subdivided five times (3 762 176) twice over. Subdivided lembos are made on demand from
/// their parents, so what bounds them is time (about a microsecond a lembo through a
/// functional frame), not memory.
pub const MAX_SUBDIVIDED_LEMBOS: u64 = 1 << 23;
use glam::DVec3;
use std::path::Path;

impl Check<'_> {
    /// Validates object `i`. `radii` holds the radii of the discoids of the objects before
    /// it and receives this object's (its length is the scene's discoid count so far);
    /// `lembos_before` is the lembos of the objects before it, and receives this one's.
    pub(super) fn object(
        &self,
        i: usize,
        o: &ObjectSpec,
        base_dir: &Path,
        radii: &mut Vec<f64>,
        lembos_before: &mut u64,
    ) -> Result<SceneObject> {
        let field = format!("objects[{i}]");
        let color = self.color(&format!("{field}.color"), o.color.unwrap_or(DEFAULT_COLOR))?;
        let transform = match &o.transform {
            Some(t) => Some(self.transform(&format!("{field}.transform"), t)?),
            None => None,
        };
        let crease = match o.crease_angle_deg {
            Some(a) => Some(self.crease_angle(&field, a, o.mesh.is_some())?),
            None => None,
        };
        let (label, lembos, discoids) = match (&o.builtin, &o.lembos, &o.mesh, &o.discoids) {
            (Some(name), None, None, None) => (
                format!("builtin {name}"),
                self.builtin_object(&field, name, transform.as_ref())?,
                None,
            ),
            (None, Some(specs), None, None) => (
                "inline lembos".to_string(),
                self.inline_object(&field, specs, transform.as_ref())?,
                None,
            ),
            (None, None, Some(path), None) => (
                format!("mesh {path}"),
                self.mesh_object(&field, path, base_dir, transform.as_ref(), crease)?,
                None,
            ),
            (None, None, None, Some(spec)) => {
                let (label, lembos, set) =
                    self.discoids(&field, spec, transform.as_ref(), base_dir, radii)?;
                (label, Lembos::Held(lembos), Some(set))
            }
            _ => {
                let value = given(&[
                    ("builtin", o.builtin.is_some()),
                    ("lembos", o.lembos.is_some()),
                    ("mesh", o.mesh.is_some()),
                    ("discoids", o.discoids.is_some()),
                ]);
                return Err(self.invalid(
                    field,
                    value,
                    "an object needs exactly one of `builtin`, `lembos`, `mesh` or `discoids`",
                ));
            }
        };
        // Finite input can still be huge, or become so after the transform; refuse it here
        // rather than let the rasterizer overflow.
        if let Some(j) = lembos.iter().position(|l| !lembo_in_range(&l)) {
            return Err(self.out_of_range(&field, transform.is_some(), j));
        }
        let lembos = match o.subdivide {
            None => lembos,
            Some(s) => self.subdivided(&field, s, discoids.is_some(), lembos, *lembos_before)?,
        };
        *lembos_before += lembos.len() as u64;
        Ok(SceneObject {
            label,
            color,
            from_mesh: lembos.mesh().is_some(),
            lembos,
            discoids,
        })
    }

    /// The lembos of the builtin shape `name` (`field.builtin`), transformed, in range and
    /// welded.
    fn builtin_object(
        &self,
        field: &str,
        name: &str,
        transform: Option<&Transform>,
    ) -> Result<Lembos> {
        let Some(mesh) = builtin_mesh(name) else {
            return Err(self.invalid(
                format!("{field}.builtin"),
                format!("{name:?}"),
                format!(
                    "unknown builtin shape; known: {}, terrainN (N from 1 to {MAX_TERRAIN_CELLS})",
                    BUILTIN_NAMES.join(", ")
                ),
            ));
        };
        let mesh = transform_mesh(mesh, transform);
        self.mesh_in_range(field, transform.is_some(), &mesh)?;
        let mesh = mesh.welded();
        // Only a transform can collapse a builtin's triangle (a scale so small that
        // positions round together).
        let lembos = mesh.into_lembos().map_err(|c| {
            self.invalid(
                format!("{field}.transform"),
                "(world-space geometry)",
                format!("builtin {name}: {c}"),
            )
        })?;
        Ok(Lembos::Mesh(lembos))
    }

    /// The inline lembos `specs` (`field.lembos`, at least one), each transformed.
    fn inline_object(
        &self,
        field: &str,
        specs: &[LemboSpec],
        transform: Option<&Transform>,
    ) -> Result<Lembos> {
        if specs.is_empty() {
            return Err(self.invalid(
                format!("{field}.lembos"),
                "[]",
                "must hold at least one lembo",
            ));
        }
        let lembos = specs
            .iter()
            .enumerate()
            .map(|(j, l)| self.inline_lembo(&format!("{field}.lembos[{j}]"), l, transform))
            .collect::<Result<Vec<_>>>()?;
        Ok(Lembos::Held(lembos))
    }

    /// The lembos of the OBJ mesh at `path` (`field.mesh`, relative to `base_dir`),
    /// transformed, in range, welded and with normals split at the `crease` angle if given;
    /// a triangle the weld collapses is refused naming the file.
    fn mesh_object(
        &self,
        field: &str,
        path: &str,
        base_dir: &Path,
        transform: Option<&Transform>,
        crease: Option<f64>,
    ) -> Result<Lembos> {
        let mesh_field = format!("{field}.mesh");
        let full = base_dir.join(path);
        let mesh = load_obj(self.file, &mesh_field, &full)?;
        let mesh = transform_mesh(mesh, transform);
        self.mesh_in_range(field, transform.is_some(), &mesh)?;
        let mesh = mesh.welded();
        let collapsed = |c: CollapsedTriangle| Error::Mesh {
            file: self.file.to_string(),
            field: mesh_field.clone(),
            path: full.clone(),
            message: c.to_string(),
        };
        let mesh = match crease {
            Some(angle) => mesh.with_crease_angle(angle).map_err(collapsed)?,
            None => mesh,
        };
        let lembos = mesh.into_lembos().map_err(collapsed)?;
        Ok(Lembos::Mesh(lembos))
    }

    /// `lembos` subdivided `s` times (`field.subdivide`): each into 4^s over the same
    /// surface ([`subdivide`](crate::lembo::lattice::subdivide)), made on demand;
    /// refused with discoids, beyond [`MAX_SUBDIVIDE`], or when the scene's lembos (`before`
    /// of the objects before) would exceed [`MAX_SUBDIVIDED_LEMBOS`].
    fn subdivided(
        &self,
        field: &str,
        s: u32,
        discoids: bool,
        lembos: Lembos,
        before: u64,
    ) -> Result<Lembos> {
        let field = format!("{field}.subdivide");
        if discoids {
            return Err(self.invalid(
                field,
                s,
                "applies to `builtin`, `lembos` and `mesh` objects (discoids from a mesh have their own `discoids.subdivide`)",
            ));
        }
        if s > MAX_SUBDIVIDE {
            return Err(self.invalid(
                field,
                s,
                format!("must be 0 to {MAX_SUBDIVIDE} (4^s lembos for each)"),
            ));
        }
        let total = before + lembos.len() as u64 * (1u64 << (2 * s));
        if total > MAX_SUBDIVIDED_LEMBOS {
            return Err(self.invalid(
                field,
                s,
                format!(
                    "would make the scene {total} lembos, more than the {MAX_SUBDIVIDED_LEMBOS} a subdivided scene may have"
                ),
            ));
        }
        Ok(Lembos::Subdivided {
            base: Box::new(lembos),
            s,
        })
    }

    /// The error for lembo `j` of the object at `field` being out of range.
    fn out_of_range(&self, field: &str, transformed: bool, j: usize) -> Error {
        let where_ = if transformed {
            format!("{field}.transform")
        } else {
            field.to_string()
        };
        let reason = format!(
            "lembo {j} of this object has a world coordinate or coefficient beyond \
             {MAX_WORLD_COORDINATE:e} in magnitude (after the transform)"
        );
        self.invalid(where_, "(world-space geometry)", reason)
    }

    /// Refuses a mesh with a vertex beyond [`MAX_WORLD_COORDINATE`] before welding and
    /// building lembos from it (as the lembo of its first triangle using the vertex).
    fn mesh_in_range(&self, field: &str, transformed: bool, mesh: &TriangleMesh) -> Result<()> {
        let small = |p: DVec3| p.is_finite() && p.abs().max_element() <= MAX_WORLD_COORDINATE;
        match mesh
            .triangles
            .iter()
            .position(|t| t.iter().any(|&i| !small(mesh.positions[i as usize])))
        {
            Some(j) => Err(self.out_of_range(field, transformed, j)),
            None => Ok(()),
        }
    }

    /// Validates the crease angle of the object at `field` (`mesh` objects only).
    fn crease_angle(&self, field: &str, angle: f64, mesh: bool) -> Result<f64> {
        let name = format!("{field}.crease_angle_deg");
        if !mesh {
            return Err(self.invalid(
                name,
                angle,
                "applies to `mesh` objects only (it recomputes an OBJ mesh's normals)",
            ));
        }
        let angle = self.finite(&name, angle)?;
        if !(0.0..=180.0).contains(&angle) {
            return Err(self.invalid(name, angle, "must be in [0, 180] degrees"));
        }
        Ok(angle)
    }
}
