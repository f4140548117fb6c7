//! Validation of an object's discoids (Piranda et al. 2006): inline, at a mesh's vertices,
//! builtin curved discoids, or surfels from a point cloud (Pfister et al. 2000).

use super::{
    format::{DiscoidItemSpec, DiscoidSource, DiscoidsSpec},
    mesh::{load_obj, transform_mesh, Transform},
    pointcloud::load_surfels,
    validate::{discoid_in_range, given, unit, Check, Vec3Value},
    MAX_DISCOIDS, MAX_WORLD_COORDINATE,
};
use crate::discoid::shapes::{builtin_discoids, discoids_from_mesh, BUILTIN_DISCOID_NAMES};
use crate::discoid::{BetaShape, Discoid, DiscoidSet, DiscoidSurface};
use crate::error::{Error, Result};
use crate::lembo::Lembo;
use std::path::Path;

impl Check<'_> {
    /// Validates the `discoids` of the object at `field`: its label, its lembos (curved
    /// discoids) and its discoid set, in world space. Pushes each discoid's world radius to
    /// `radii`.
    pub(super) fn discoids(
        &self,
        object: &str,
        spec: &DiscoidsSpec,
        t: Option<&Transform>,
        base_dir: &Path,
        radii: &mut Vec<f64>,
    ) -> Result<(String, Vec<Lembo>, DiscoidSet)> {
        let field = format!("{object}.discoids");
        let source = self.discoid_source(&field, spec)?;
        let mut set = DiscoidSet {
            beta: spec.beta.unwrap_or(BetaShape::Disk),
            planar: Vec::new(),
            lembo_texcoords: Vec::new(),
            surfels: false,
            surface: None,
        };
        let before = radii.len();
        let (label, lembos, source) = match source {
            DiscoidSource::Items(items) => {
                let source = format!("{field}.items");
                if items.is_empty() {
                    return Err(self.invalid(source, "[]", "must hold at least one discoid"));
                }
                self.within_limit(&source, items.len(), before)?;
                set.planar = items
                    .iter()
                    .enumerate()
                    .map(|(j, d)| self.discoid_item(&format!("{source}[{j}]"), d))
                    .collect::<Result<Vec<_>>>()?;
                ("inline discoids".to_string(), Vec::new(), source)
            }
            DiscoidSource::FromMesh(path) => {
                let source = format!("{field}.from_mesh");
                let subdivide = self.subdivide(&field, spec.subdivide)?;
                let radius_scale = self.radius_scale(&field, spec.radius_scale)?;
                let file = base_dir.join(path);
                let mesh = load_obj(self.file, &source, &file)?;
                if spec.surface.is_some() {
                    return Err(self.invalid(
                        format!("{field}.surface"),
                        "(given)",
                        "`from_mesh` discoids stand for their own mesh; `surface` is for `items` and `surfels`",
                    ));
                }
                set.surface = Some(DiscoidSurface::Mesh(transform_mesh(mesh.clone(), t)));
                set.planar = discoids_from_mesh(&mesh, subdivide, radius_scale).map_err(|e| {
                    Error::Mesh {
                        file: self.file.to_string(),
                        field: source.clone(),
                        path: file,
                        message: e.to_string(),
                    }
                })?;
                self.within_limit(&source, set.planar.len(), before)?;
                let label = format!(
                    "discoids from mesh {path} (subdivide {})",
                    u8::from(subdivide)
                );
                (label, Vec::new(), source)
            }
            DiscoidSource::Builtin(name) => {
                self.builtin_curved(&field, name, spec, t, &mut set, radii)?
            }
            DiscoidSource::Surfels(path) => {
                let source = format!("{field}.surfels");
                set.planar = load_surfels(self.file, &source, &base_dir.join(path), before)?;
                set.surfels = true;
                (format!("surfels {path}"), Vec::new(), source)
            }
        };
        if let (Some(path), None) = (&spec.surface, &set.surface) {
            let source = format!("{field}.surface");
            let mesh = load_obj(self.file, &source, &base_dir.join(path))?;
            set.surface = Some(DiscoidSurface::Mesh(transform_mesh(mesh, t)));
        }
        self.place_planar(object, source, &mut set.planar, t)?;
        radii.extend(set.planar.iter().map(|d| d.radius));
        Ok((label, lembos, set))
    }

    /// Builtin curved discoids (`discoids.builtin` of the object at `field`): their lembos
    /// placed by `t`, their texture coordinates and the sphere they stand for into `set`,
    /// their world radii pushed to `radii`; with the label and the source field.
    fn builtin_curved(
        &self,
        field: &str,
        name: &str,
        spec: &DiscoidsSpec,
        t: Option<&Transform>,
        set: &mut DiscoidSet,
        radii: &mut Vec<f64>,
    ) -> Result<(String, Vec<Lembo>, String)> {
        let source = format!("{field}.builtin");
        if set.beta == BetaShape::Ewa {
            return Err(self.invalid(
                format!("{field}.beta"),
                "\"ewa\"",
                "the EWA kernel is set up per planar discoid (its centre's projection); curved discoids take disk, star or gaussian",
            ));
        }
        let Some(curved) = builtin_discoids(name) else {
            return Err(self.invalid(
                source,
                format!("{name:?}"),
                format!(
                    "unknown builtin discoid shape; known: {}",
                    BUILTIN_DISCOID_NAMES.join(", ")
                ),
            ));
        };
        self.within_limit(&source, curved.lembos.len(), radii.len())?;
        let lembos = match t {
            Some(t) => curved
                .lembos
                .iter()
                .map(|l| {
                    Lembo::new(
                        l.points.map(|p| t.point(p)),
                        l.normals.map(|n| t.rotate * n),
                    )
                })
                .collect(),
            None => curved.lembos,
        };
        if spec.surface.is_some() {
            return Err(self.invalid(
                format!("{field}.surface"),
                "(given)",
                "builtin discoids stand for their own shape; `surface` is for `items` and `surfels`",
            ));
        }
        set.lembo_texcoords = curved.texcoords;
        let scale = t.map_or(1.0, |t| t.scale);
        set.surface = Some(DiscoidSurface::Sphere {
            center: t.map_or(glam::DVec3::ZERO, |t| t.point(glam::DVec3::ZERO)),
            radius: scale,
        });
        radii.extend(curved.radii.iter().map(|r| r * scale));
        Ok((format!("builtin discoids {name}"), lembos, source))
    }

    /// The one source of an object's discoids, with the options that apply only to
    /// `from_mesh` refused for the others.
    pub(super) fn discoid_source<'s>(
        &self,
        field: &str,
        spec: &'s DiscoidsSpec,
    ) -> Result<DiscoidSource<'s>> {
        let source = match (&spec.items, &spec.from_mesh, &spec.builtin, &spec.surfels) {
            (Some(items), None, None, None) => DiscoidSource::Items(items),
            (None, Some(path), None, None) => DiscoidSource::FromMesh(path),
            (None, None, Some(name), None) => DiscoidSource::Builtin(name),
            (None, None, None, Some(path)) => DiscoidSource::Surfels(path),
            _ => {
                let value = given(&[
                    ("items", spec.items.is_some()),
                    ("from_mesh", spec.from_mesh.is_some()),
                    ("builtin", spec.builtin.is_some()),
                    ("surfels", spec.surfels.is_some()),
                ]);
                return Err(self.invalid(
                    field.to_string(),
                    value,
                    "discoids need exactly one source: `items`, `from_mesh`, `builtin` or `surfels`",
                ));
            }
        };
        if !matches!(source, DiscoidSource::FromMesh(_)) {
            if let Some(n) = spec.subdivide {
                return Err(self.invalid(
                    format!("{field}.subdivide"),
                    n,
                    "applies only to `from_mesh` discoids",
                ));
            }
            if let Some(x) = spec.radius_scale {
                return Err(self.invalid(
                    format!("{field}.radius_scale"),
                    x,
                    "applies only to `from_mesh` discoids",
                ));
            }
        }
        Ok(source)
    }

    /// Places planar discoids in world space by `t` and refuses any out of range, naming
    /// the transform when there is one, else `source` (the field the discoids came from).
    pub(super) fn place_planar(
        &self,
        object: &str,
        source: String,
        planar: &mut [Discoid],
        t: Option<&Transform>,
    ) -> Result<()> {
        if let Some(t) = t {
            for d in planar.iter_mut() {
                *d = Discoid {
                    center: t.point(d.center),
                    normal: (t.rotate * d.normal).normalize(),
                    radius: d.radius * t.scale,
                };
            }
        }
        if let Some(j) = planar.iter().position(|d| !discoid_in_range(d)) {
            let where_ = if t.is_some() {
                format!("{object}.transform")
            } else {
                source
            };
            let reason = format!(
                "discoid {j} of this object has a centre coordinate or radius beyond \
                 {MAX_WORLD_COORDINATE:e} in magnitude, or a radius below {:e} (after the \
                 transform)",
                f64::MIN_POSITIVE
            );
            return Err(self.invalid(where_, "(world-space geometry)", reason));
        }
        Ok(())
    }

    /// Refuses `n` more discoids at `field` when the scene, which holds `before`, would hold
    /// more than [`MAX_DISCOIDS`].
    fn within_limit(&self, field: &str, n: usize, before: usize) -> Result<()> {
        let total = before.saturating_add(n);
        if total <= MAX_DISCOIDS {
            Ok(())
        } else {
            Err(self.invalid(
                field,
                format!("{n} discoids"),
                format!(
                    "the scene would hold {total} discoids; at most {MAX_DISCOIDS} are accepted"
                ),
            ))
        }
    }

    fn subdivide(&self, field: &str, n: Option<u32>) -> Result<bool> {
        match n.unwrap_or(0) {
            0 => Ok(false),
            1 => Ok(true),
            n => Err(self.invalid(
                format!("{field}.subdivide"),
                n,
                "must be 0 (the vertices) or 1 (the vertices and edge midpoints)",
            )),
        }
    }

    fn radius_scale(&self, field: &str, x: Option<f64>) -> Result<f64> {
        let field = format!("{field}.radius_scale");
        let x = self.finite(&field, x.unwrap_or(1.0))?;
        if x > 0.0 {
            Ok(x)
        } else {
            Err(self.invalid(field, x, "must be > 0"))
        }
    }

    /// A planar discoid given inline, in object space, its normal normalised.
    fn discoid_item(&self, field: &str, d: &DiscoidItemSpec) -> Result<Discoid> {
        let center = self.vec3(&format!("{field}.center"), d.center)?;
        let normal = self.vec3(&format!("{field}.normal"), d.normal)?;
        let Some(normal) = unit(normal) else {
            return Err(self.invalid(
                format!("{field}.normal"),
                Vec3Value(d.normal),
                "must be non-zero",
            ));
        };
        let radius = self.finite(&format!("{field}.radius"), d.radius)?;
        if radius <= 0.0 {
            return Err(self.invalid(format!("{field}.radius"), radius, "must be > 0 world units"));
        }
        Ok(Discoid {
            center,
            normal,
            radius,
        })
    }
}
