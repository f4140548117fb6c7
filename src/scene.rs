//! Scenes: the JSON trace files of `traces/` (DESIGN §7), parsed and validated once into a
//! [`Scene`] that nothing downstream re-checks.
//!
//! A scene file holds a name, a viewport, a camera, a light, a background colour and a
//! list of objects. Each object is a builtin shape (paper 001 Figures 6-8), inline lembos
//! (six points and six normals each) or a triangle mesh in an OBJ file, with a material
//! colour and a similarity transform. Every object ends up as world-space lembos; builtins
//! and meshes also keep their world-space triangle mesh for the triangle path.
//!
//! The file is read into private `*Spec` structs (serde, `deny_unknown_fields`) and then
//! validated field by field. Every error names the file, the field path in one style
//! (`viewport.width`, `camera.projection.near`, `objects[1].transform.scale`) and the
//! value (DESIGN §8): serde errors become [`Error::Parse`] with the path that
//! `serde_path_to_error` tracked, refused values become [`Error::Invalid`], and mesh files
//! that cannot be loaded or hold bad numbers become [`Error::Mesh`].
//!
//! Not modelled here: triangles, discoids and point clouds as scene objects, and
//! non-uniform scaling (which would need the inverse transpose for normals).

use crate::camera::{Camera, Projection, Viewport, MAX_VIEWPORT_SIDE};
use crate::error::{Error, Result};
use crate::lembo::construct::TriangleMesh;
use crate::lembo::shapes::{builtin_mesh, BUILTIN_NAMES};
use crate::lembo::Lembo;
use crate::rop::shade::Light;
use glam::{DMat3, DVec3};
use serde::Deserialize;
use std::fmt;
use std::path::{Path, PathBuf};

/// The viewport of a scene file without one [pixels].
pub const DEFAULT_VIEWPORT: Viewport = Viewport {
    width: 512,
    height: 512,
};
/// The background of a scene file without one: dark grey, linear RGB.
pub const DEFAULT_BACKGROUND: [f64; 3] = [0.1, 0.1, 0.1];
/// The colour of an object without one: light grey, linear RGB.
pub const DEFAULT_COLOR: [f64; 3] = [0.8, 0.8, 0.8];
/// The largest accepted magnitude of a world-space coordinate or lembo coefficient after
/// an object's transform [world units]. Far beyond any sensible scene, it keeps products
/// of a few coordinates (projection, the rasterizer's quadratics) inside f64's and f32's
/// range.
pub const MAX_WORLD_COORDINATE: f64 = 1e12;

/// The embedded default scene (`lembo-sim` with no arguments renders it).
const DEFAULT_SCENE_JSON: &str = include_str!("../traces/default.json");
/// Where the embedded default scene's relative paths point.
const DEFAULT_SCENE_DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/traces");

/// A validated scene: everything in world space, every number finite and in range.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Made of `[A-Za-z0-9_-]` only: it names the output directory `out/<name>/`.
    pub name: String,
    /// File the scene came from; None for the embedded default.
    pub source: Option<PathBuf>,
    pub viewport: Viewport,
    pub camera: Camera,
    pub light: Light,
    /// Background colour, linear RGB in [0, 1].
    pub background: [f64; 3],
    pub objects: Vec<SceneObject>,
}

/// One object of a scene, in world space.
#[derive(Clone, Debug)]
pub struct SceneObject {
    /// "builtin sphere24", "mesh meshes/bunny.obj", "inline lembos", for reports.
    pub label: String,
    /// Material colour, linear RGB in [0, 1].
    pub color: [f64; 3],
    /// World-space lembos (after the object's transform).
    pub lembos: Vec<Lembo>,
    /// World-space triangle mesh for objects given as meshes or builtins (after transform);
    /// None for inline lembos.
    pub mesh: Option<TriangleMesh>,
}

impl Scene {
    /// Reads and validates a scene file; mesh paths in it are relative to its directory.
    pub fn load(path: &Path) -> Result<Scene> {
        let text = std::fs::read_to_string(path).map_err(|source| Error::Read {
            path: path.to_path_buf(),
            source,
        })?;
        let base_dir = match path.parent() {
            Some(dir) if !dir.as_os_str().is_empty() => dir,
            _ => Path::new("."),
        };
        let mut scene = Scene::from_json(&text, &path.display().to_string(), base_dir)?;
        scene.source = Some(path.to_path_buf());
        Ok(scene)
    }

    /// Parses and validates a scene from JSON text. `file` is the name used in error
    /// messages; mesh paths are relative to `base_dir`.
    pub fn from_json(text: &str, file: &str, base_dir: &Path) -> Result<Scene> {
        let de = &mut serde_json::Deserializer::from_str(text);
        let spec: SceneSpec =
            serde_path_to_error::deserialize(&mut *de).map_err(|e| parse_error(file, e))?;
        // Text after the scene object is an error, not ignored.
        de.end().map_err(|e| Error::Parse {
            file: file.to_string(),
            field: String::new(),
            message: e.to_string(),
        })?;
        spec.validate(&Check { file }, base_dir)
    }

    /// The embedded `traces/default.json`: the sphere of 24 lembos.
    pub fn default_scene() -> Scene {
        // The text is part of the binary and checked by a unit test, so failing here is a
        // build defect, not bad input.
        Scene::from_json(
            DEFAULT_SCENE_JSON,
            "traces/default.json (embedded)",
            Path::new(DEFAULT_SCENE_DIR),
        )
        .expect("the embedded default scene is valid")
    }

    /// The number of lembos over all objects.
    pub fn lembo_count(&self) -> usize {
        self.objects.iter().map(|o| o.lembos.len()).sum()
    }

    /// All lembos in scene order with their object's colour; the index in this order is the
    /// lembo's global id.
    pub fn lembos(&self) -> impl Iterator<Item = (&Lembo, [f64; 3])> {
        self.objects
            .iter()
            .flat_map(|o| o.lembos.iter().map(move |l| (l, o.color)))
    }

    /// Sets the viewport (CLI override), validated like the file's.
    pub fn set_viewport(&mut self, width: u32, height: u32) -> Result<()> {
        let viewport = Viewport { width, height };
        Check {
            file: "command line",
        }
        .viewport(&viewport)?;
        self.viewport = viewport;
        Ok(())
    }
}

pub(crate) fn parse_error(file: &str, e: serde_path_to_error::Error<serde_json::Error>) -> Error {
    // A syntax error leaves an unknown (`?`) last segment, and one before any field an
    // empty path (printed "."): drop both, serde's message gives the line and column.
    let mut field = e.path().to_string();
    while field.ends_with('?') {
        field.pop();
        if field.ends_with('.') {
            field.pop();
        }
    }
    if field == "." {
        field.clear();
    }
    Error::Parse {
        file: file.to_string(),
        field,
        message: e.into_inner().to_string(),
    }
}

// ---- The file's shape ----------------------------------------------------------------

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneSpec {
    name: String,
    viewport: Option<Viewport>,
    camera: CameraSpec,
    light: Option<LightSpec>,
    background: Option<[f64; 3]>,
    objects: Vec<ObjectSpec>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraSpec {
    eye: [f64; 3],
    target: [f64; 3],
    #[serde(default = "default_up")]
    up: [f64; 3],
    projection: ProjectionSpec,
}

fn default_up() -> [f64; 3] {
    [0.0, 1.0, 0.0]
}

/// The serde shape of [`Projection`], flattened so that errors name the exact field (an
/// internally tagged enum would buffer its content and lose the path below `projection`).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ProjectionSpec {
    kind: ProjectionKind,
    fovy_deg: Option<f64>,
    height: Option<f64>,
    near: f64,
    far: f64,
}

#[derive(Clone, Copy, Deserialize)]
#[serde(rename_all = "lowercase")]
enum ProjectionKind {
    Perspective,
    Orthographic,
}

/// A light whose missing terms take [`Light::default`]'s values.
#[derive(Deserialize)]
#[serde(default, deny_unknown_fields)]
struct LightSpec {
    direction_to_light: [f64; 3],
    ka: f64,
    kd: f64,
    ks: f64,
    shininess: f64,
}

impl Default for LightSpec {
    fn default() -> Self {
        let Light {
            direction_to_light,
            ka,
            kd,
            ks,
            shininess,
        } = Light::default();
        LightSpec {
            direction_to_light,
            ka,
            kd,
            ks,
            shininess,
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectSpec {
    builtin: Option<String>,
    lembos: Option<Vec<LemboSpec>>,
    mesh: Option<String>,
    color: Option<[f64; 3]>,
    transform: Option<TransformSpec>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LemboSpec {
    points: [[f64; 3]; 6],
    normals: [[f64; 3]; 6],
}

#[derive(Deserialize)]
#[serde(default, deny_unknown_fields)]
struct TransformSpec {
    scale: f64,
    rotate_deg: [f64; 3],
    translate: [f64; 3],
}

impl Default for TransformSpec {
    fn default() -> Self {
        TransformSpec {
            scale: 1.0,
            rotate_deg: [0.0; 3],
            translate: [0.0; 3],
        }
    }
}

// ---- Validation ------------------------------------------------------------------------

/// Builds errors that name the file being validated.
struct Check<'a> {
    file: &'a str,
}

/// Formats a vector as the file spells it, e.g. `[0, 1, 0.5]`.
struct Vec3Value([f64; 3]);

impl fmt::Display for Vec3Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let [x, y, z] = self.0;
        write!(f, "[{x}, {y}, {z}]")
    }
}

impl Check<'_> {
    fn invalid(
        &self,
        field: impl Into<String>,
        value: impl fmt::Display,
        reason: impl Into<String>,
    ) -> Error {
        Error::invalid(self.file, field, value, reason)
    }

    fn parse(&self, field: impl Into<String>, message: impl Into<String>) -> Error {
        Error::Parse {
            file: self.file.to_string(),
            field: field.into(),
            message: message.into(),
        }
    }

    fn finite(&self, field: &str, x: f64) -> Result<f64> {
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.invalid(field, x, "must be a finite number"))
        }
    }

    fn vec3(&self, field: &str, v: [f64; 3]) -> Result<DVec3> {
        if v.iter().all(|x| x.is_finite()) {
            Ok(DVec3::from_array(v))
        } else {
            Err(self.invalid(
                field,
                Vec3Value(v),
                "every component must be a finite number",
            ))
        }
    }

    fn color(&self, field: &str, c: [f64; 3]) -> Result<[f64; 3]> {
        if c.iter().all(|x| (0.0..=1.0).contains(x)) {
            Ok(c)
        } else {
            Err(self.invalid(
                field,
                Vec3Value(c),
                "every channel must be in [0, 1] (linear RGB)",
            ))
        }
    }

    fn viewport(&self, v: &Viewport) -> Result<()> {
        for (field, side) in [("viewport.width", v.width), ("viewport.height", v.height)] {
            if !(1..=MAX_VIEWPORT_SIDE).contains(&side) {
                return Err(self.invalid(
                    field,
                    side,
                    format!("must be in 1..={MAX_VIEWPORT_SIDE} pixels"),
                ));
            }
        }
        Ok(())
    }

    fn name(&self, name: &str) -> Result<()> {
        let ok = !name.is_empty()
            && name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
        if ok {
            Ok(())
        } else {
            Err(self.invalid(
                "name",
                format!("{name:?}"),
                "must be non-empty and made only of A-Z, a-z, 0-9, `_` and `-`: it names the output directory out/<name>/",
            ))
        }
    }

    fn camera(&self, c: &CameraSpec) -> Result<Camera> {
        let eye = self.vec3("camera.eye", c.eye)?;
        let target = self.vec3("camera.target", c.target)?;
        let up = self.vec3("camera.up", c.up)?;
        if eye == target {
            return Err(self.invalid(
                "camera.target",
                Vec3Value(c.target),
                "must differ from camera.eye",
            ));
        }
        let dir = target - eye;
        // Parallel (or zero) up leaves the camera's roll undefined.
        if up.cross(dir).length() <= 1e-9 * up.length() * dir.length() {
            return Err(self.invalid(
                "camera.up",
                Vec3Value(c.up),
                "must be non-zero and not parallel to the view direction (target - eye)",
            ));
        }
        let projection = self.projection(&c.projection)?;
        Ok(Camera {
            eye: c.eye,
            target: c.target,
            up: c.up,
            projection,
        })
    }

    fn projection(&self, p: &ProjectionSpec) -> Result<Projection> {
        let near = self.finite("camera.projection.near", p.near)?;
        let far = self.finite("camera.projection.far", p.far)?;
        if near <= 0.0 {
            return Err(self.invalid("camera.projection.near", near, "must be > 0"));
        }
        if far <= near {
            return Err(self.invalid(
                "camera.projection.far",
                far,
                format!("must be > near ({near})"),
            ));
        }
        match p.kind {
            ProjectionKind::Perspective => {
                if p.height.is_some() {
                    return Err(self.parse(
                        "camera.projection.height",
                        "a perspective projection takes `fovy_deg`, not `height` (which is for orthographic)",
                    ));
                }
                let Some(fovy_deg) = p.fovy_deg else {
                    return Err(self.parse(
                        "camera.projection",
                        "missing field `fovy_deg` (a perspective projection needs it)",
                    ));
                };
                let fovy_deg = self.finite("camera.projection.fovy_deg", fovy_deg)?;
                if !(fovy_deg > 0.0 && fovy_deg < 180.0) {
                    return Err(self.invalid(
                        "camera.projection.fovy_deg",
                        fovy_deg,
                        "must be in (0, 180) degrees",
                    ));
                }
                Ok(Projection::Perspective {
                    fovy_deg,
                    near,
                    far,
                })
            }
            ProjectionKind::Orthographic => {
                if p.fovy_deg.is_some() {
                    return Err(self.parse(
                        "camera.projection.fovy_deg",
                        "an orthographic projection takes `height`, not `fovy_deg` (which is for perspective)",
                    ));
                }
                let Some(height) = p.height else {
                    return Err(self.parse(
                        "camera.projection",
                        "missing field `height` (an orthographic projection needs it)",
                    ));
                };
                let height = self.finite("camera.projection.height", height)?;
                if height <= 0.0 {
                    return Err(self.invalid(
                        "camera.projection.height",
                        height,
                        "must be > 0 world units",
                    ));
                }
                Ok(Projection::Orthographic { height, near, far })
            }
        }
    }

    fn light(&self, l: &LightSpec) -> Result<Light> {
        let dir = self.vec3("light.direction_to_light", l.direction_to_light)?;
        if dir == DVec3::ZERO {
            return Err(self.invalid(
                "light.direction_to_light",
                Vec3Value(l.direction_to_light),
                "must be non-zero",
            ));
        }
        for (field, x) in [
            ("light.ka", l.ka),
            ("light.kd", l.kd),
            ("light.ks", l.ks),
            ("light.shininess", l.shininess),
        ] {
            self.finite(field, x)?;
            if x < 0.0 {
                return Err(self.invalid(field, x, "must be >= 0"));
            }
        }
        Ok(Light {
            direction_to_light: l.direction_to_light,
            ka: l.ka,
            kd: l.kd,
            ks: l.ks,
            shininess: l.shininess,
        })
    }

    fn transform(&self, field: &str, t: &TransformSpec) -> Result<Transform> {
        let scale = self.finite(&format!("{field}.scale"), t.scale)?;
        if scale <= 0.0 {
            return Err(self.invalid(
                format!("{field}.scale"),
                scale,
                "must be > 0 (uniform scale)",
            ));
        }
        let r = self.vec3(&format!("{field}.rotate_deg"), t.rotate_deg)?;
        let translate = self.vec3(&format!("{field}.translate"), t.translate)?;
        // X first, then Y, then Z: the rightmost factor applies first.
        let rotate = DMat3::from_rotation_z(r.z.to_radians())
            * DMat3::from_rotation_y(r.y.to_radians())
            * DMat3::from_rotation_x(r.x.to_radians());
        Ok(Transform {
            scale,
            rotate,
            translate,
        })
    }

    fn object(&self, i: usize, o: &ObjectSpec, base_dir: &Path) -> Result<SceneObject> {
        let field = format!("objects[{i}]");
        let color = self.color(&format!("{field}.color"), o.color.unwrap_or(DEFAULT_COLOR))?;
        let transform = match &o.transform {
            Some(t) => Some(self.transform(&format!("{field}.transform"), t)?),
            None => None,
        };
        let (label, lembos, mesh) = match (&o.builtin, &o.lembos, &o.mesh) {
            (Some(name), None, None) => {
                let Some(mesh) = builtin_mesh(name) else {
                    return Err(self.invalid(
                        format!("{field}.builtin"),
                        format!("{name:?}"),
                        format!("unknown builtin shape; known: {}", BUILTIN_NAMES.join(", ")),
                    ));
                };
                let mesh = transform_mesh(mesh, transform.as_ref());
                (format!("builtin {name}"), mesh.to_lembos(), Some(mesh))
            }
            (None, Some(specs), None) => {
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
                    .map(|(j, l)| {
                        self.inline_lembo(&format!("{field}.lembos[{j}]"), l, transform.as_ref())
                    })
                    .collect::<Result<Vec<_>>>()?;
                ("inline lembos".to_string(), lembos, None)
            }
            (None, None, Some(path)) => {
                let mesh = load_obj(self.file, &format!("{field}.mesh"), &base_dir.join(path))?;
                let mesh = transform_mesh(mesh, transform.as_ref());
                (format!("mesh {path}"), mesh.to_lembos(), Some(mesh))
            }
            _ => {
                let given: Vec<&str> = [
                    ("builtin", o.builtin.is_some()),
                    ("lembos", o.lembos.is_some()),
                    ("mesh", o.mesh.is_some()),
                ]
                .into_iter()
                .filter_map(|(k, present)| present.then_some(k))
                .collect();
                let value = if given.is_empty() {
                    "none".to_string()
                } else {
                    given.join(" and ")
                };
                return Err(self.invalid(
                    field,
                    value,
                    "an object needs exactly one of `builtin`, `lembos` or `mesh`",
                ));
            }
        };
        // Finite input can still be huge, or become so after the transform; refuse it here
        // rather than let the rasterizer overflow.
        if let Some(j) = lembos.iter().position(|l| !lembo_in_range(l)) {
            let where_ = if transform.is_some() {
                format!("{field}.transform")
            } else {
                field.clone()
            };
            let reason = format!(
                "lembo {j} of this object has a world coordinate or coefficient beyond \
                 {MAX_WORLD_COORDINATE:e} in magnitude (after the transform)"
            );
            return Err(self.invalid(where_, "(world-space geometry)", reason));
        }
        Ok(SceneObject {
            label,
            color,
            lembos,
            mesh,
        })
    }

    fn inline_lembo(&self, field: &str, l: &LemboSpec, t: Option<&Transform>) -> Result<Lembo> {
        let mut points = [DVec3::ZERO; 6];
        let mut normals = [DVec3::ZERO; 6];
        for k in 0..6 {
            points[k] = self.vec3(&format!("{field}.points[{k}]"), l.points[k])?;
            normals[k] = self.vec3(&format!("{field}.normals[{k}]"), l.normals[k])?;
        }
        if let Some(t) = t {
            // Normals keep their length: the file's normal function is the modeller's.
            points = points.map(|p| t.point(p));
            normals = normals.map(|n| t.rotate * n);
        }
        Ok(Lembo::new(points, normals))
    }
}

impl SceneSpec {
    fn validate(self, check: &Check, base_dir: &Path) -> Result<Scene> {
        check.name(&self.name)?;
        let viewport = self.viewport.unwrap_or(DEFAULT_VIEWPORT);
        check.viewport(&viewport)?;
        let camera = check.camera(&self.camera)?;
        let light = check.light(&self.light.unwrap_or_default())?;
        let background =
            check.color("background", self.background.unwrap_or(DEFAULT_BACKGROUND))?;
        let objects = self
            .objects
            .iter()
            .enumerate()
            .map(|(i, o)| check.object(i, o, base_dir))
            .collect::<Result<Vec<_>>>()?;
        Ok(Scene {
            name: self.name,
            source: None,
            viewport,
            camera,
            light,
            background,
            objects,
        })
    }
}

/// Whether every point and every position coefficient is finite and at most
/// [`MAX_WORLD_COORDINATE`] in magnitude, and every normal finite.
fn lembo_in_range(l: &Lembo) -> bool {
    let small = |x: f64| x.abs() <= MAX_WORLD_COORDINATE;
    l.is_finite()
        && l.points.iter().all(|p| small(p.abs().max_element()))
        && l.position.iter().all(|q| small(q.magnitude()))
        && l.normal.iter().all(|q| q.magnitude().is_finite())
}

// ---- Transforms and meshes -----------------------------------------------------------------

/// A similarity transform: uniform scale, then rotation, then translation.
struct Transform {
    scale: f64,
    rotate: DMat3,
    translate: DVec3,
}

impl Transform {
    fn point(&self, p: DVec3) -> DVec3 {
        self.rotate * (p * self.scale) + self.translate
    }
}

fn transform_mesh(mut mesh: TriangleMesh, t: Option<&Transform>) -> TriangleMesh {
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
fn load_obj(file: &str, field: &str, path: &Path) -> Result<TriangleMesh> {
    let mesh_err = |message: String| Error::Mesh {
        file: file.to_string(),
        field: field.to_string(),
        path: path.to_path_buf(),
        message,
    };
    // Read the bytes ourselves: tobj's own open reports "open file failed" without the OS
    // reason.
    let bytes = std::fs::read(path).map_err(|e| mesh_err(e.to_string()))?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    fn traces() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("traces")
    }

    const SPHERE: &str = r#"{
        "name": "t",
        "camera": {"eye": [0, 0, 4], "target": [0, 0, 0],
                   "projection": {"kind": "perspective", "fovy_deg": 40, "near": 0.1, "far": 100}},
        "objects": [{"builtin": "sphere24"}]
    }"#;

    fn parse(text: &str) -> Result<Scene> {
        Scene::from_json(text, "test.json", &traces())
    }

    /// The sphere scene with one substring replaced; panics if it is absent.
    fn sphere_with(from: &str, to: &str) -> Result<Scene> {
        assert!(SPHERE.contains(from), "{from}");
        parse(&SPHERE.replacen(from, to, 1))
    }

    /// The error, or the scene's name (a scene's Debug output is pages of numbers).
    fn summary(r: &Result<Scene>) -> String {
        match r {
            Ok(scene) => format!("Ok(scene {:?})", scene.name),
            Err(e) => format!("{e:?}"),
        }
    }

    fn assert_parse_err(r: Result<Scene>, want_field: &str) -> String {
        match r {
            Err(Error::Parse {
                file,
                field,
                message,
            }) => {
                assert_eq!(file, "test.json");
                assert!(
                    field.contains(want_field),
                    "field {field:?} lacks {want_field:?}: {message}"
                );
                message
            }
            other => panic!(
                "expected a parse error at {want_field}, got {}",
                summary(&other)
            ),
        }
    }

    fn assert_invalid(r: Result<Scene>, want_field: &str) -> String {
        match r {
            Err(Error::Invalid {
                file,
                field,
                reason,
                ..
            }) => {
                assert_eq!(file, "test.json");
                assert_eq!(field, want_field, "{reason}");
                reason
            }
            other => panic!(
                "expected an invalid-value error at {want_field}, got {}",
                summary(&other)
            ),
        }
    }

    fn assert_mesh_err(r: Result<Scene>, want_field: &str) -> String {
        match r {
            Err(Error::Mesh { field, message, .. }) => {
                assert_eq!(field, want_field, "{message}");
                message
            }
            other => panic!(
                "expected a mesh error at {want_field}, got {}",
                summary(&other)
            ),
        }
    }

    #[test]
    fn committed_traces_load_with_their_lembo_counts() {
        for (file, lembos) in [
            ("sphere24", 24),
            ("cylinder24", 24),
            ("surface96", 96),
            ("bunny", 3674),
            ("default", 24),
        ] {
            let path = traces().join(format!("{file}.json"));
            let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(scene.name, file);
            assert_eq!(scene.lembo_count(), lembos, "{file}");
            assert_eq!(scene.lembos().count(), lembos, "{file}");
            assert_eq!(scene.source.as_deref(), Some(path.as_path()));
            assert_eq!(scene.viewport, DEFAULT_VIEWPORT);
            assert!(scene.objects.iter().all(|o| o.mesh.is_some()));
        }
    }

    #[test]
    fn default_scene_is_the_sphere() {
        let scene = Scene::default_scene();
        assert_eq!(scene.name, "default");
        assert!(scene.source.is_none());
        assert_eq!(scene.lembo_count(), 24);
        let sphere = Scene::load(&traces().join("sphere24.json")).unwrap();
        assert_eq!(scene.camera, sphere.camera);
        assert_eq!(scene.light, sphere.light);
        assert_eq!(scene.objects[0].lembos, sphere.objects[0].lembos);
    }

    #[test]
    fn defaults_fill_optional_fields() {
        let scene = parse(SPHERE).unwrap();
        assert_eq!(scene.viewport, DEFAULT_VIEWPORT);
        assert_eq!(scene.light, Light::default());
        assert_eq!(scene.background, DEFAULT_BACKGROUND);
        assert_eq!(scene.camera.up, [0.0, 1.0, 0.0]);
        assert_eq!(scene.objects[0].color, DEFAULT_COLOR);
        assert_eq!(scene.objects[0].label, "builtin sphere24");
        // A partial light keeps the other terms' defaults.
        let scene = sphere_with(r#""objects""#, r#""light": {"ka": 0.5}, "objects""#).unwrap();
        assert_eq!(
            scene.light,
            Light {
                ka: 0.5,
                ..Light::default()
            }
        );
    }

    #[test]
    fn missing_scene_file_is_a_read_error() {
        let path = traces().join("no_such_scene.json");
        assert!(matches!(Scene::load(&path), Err(Error::Read { path: p, .. }) if p == path));
    }

    #[test]
    fn malformed_json_is_a_parse_error_with_line_and_column() {
        for text in ["not json", "{ \"name\": \"t\",, }", ""] {
            match parse(text) {
                Err(Error::Parse { field, message, .. }) => {
                    assert_eq!(field, "", "{text}");
                    assert!(message.contains("line 1 column"), "{message}");
                }
                other => panic!("{}", summary(&other)),
            }
        }
        match parse(&format!("{SPHERE} {{}}")) {
            Err(Error::Parse { field, message, .. }) => {
                assert_eq!(field, "");
                assert!(message.contains("trailing characters"), "{message}");
            }
            other => panic!("{}", summary(&other)),
        }
        // Inside a value the path names where the parser stopped.
        let r = sphere_with(r#""eye": [0, 0, 4]"#, r#""eye": [0, 0 4]"#);
        assert_parse_err(r, "camera.eye");
    }

    #[test]
    fn unknown_field_names_its_parent() {
        let message = assert_parse_err(sphere_with(r#""eye""#, r#""eyes""#), "camera");
        assert!(message.contains("eyes"), "{message}");
        assert_parse_err(sphere_with(r#""builtin""#, r#""shape""#), "objects[0]");
    }

    #[test]
    fn wrong_type_names_the_field() {
        assert_parse_err(
            sphere_with(r#""fovy_deg": 40"#, r#""fovy_deg": "wide""#),
            "camera.projection.fovy_deg",
        );
        let inline = r#"{"lembos": [{"points": [[0,0,0],[1,0,0],[0,1,0],[0.5,0,0],[0,0.5,0],[0.5,0.5,0]],
                                     "normals": [[0,0,1],[0,0,1],[0,0,1],[0,0,1],[0,0,1]]}]}"#;
        // Five normals where six are needed.
        assert_parse_err(
            sphere_with(r#"{"builtin": "sphere24"}"#, inline),
            "objects[0].lembos[0].normals",
        );
    }

    #[test]
    fn perspective_and_orthographic_fields_are_not_mixed() {
        assert_parse_err(
            sphere_with(r#""fovy_deg": 40"#, r#""height": 3"#),
            "camera.projection",
        );
        let r = sphere_with(
            r#""kind": "perspective""#,
            r#""kind": "orthographic", "height": 3"#,
        );
        assert_parse_err(r, "camera.projection.fovy_deg");
        let scene = sphere_with(
            r#""kind": "perspective", "fovy_deg": 40"#,
            r#""kind": "orthographic", "height": 3"#,
        )
        .unwrap();
        assert_eq!(
            scene.camera.projection,
            Projection::Orthographic {
                height: 3.0,
                near: 0.1,
                far: 100.0
            }
        );
    }

    #[test]
    fn infinite_number_names_the_field() {
        // serde_json refuses numbers beyond f64's range as it parses; the path is kept.
        let message = assert_parse_err(
            sphere_with(r#""far": 100"#, r#""far": 1e999"#),
            "camera.projection.far",
        );
        assert!(message.contains("out of range"), "{message}");
        assert_parse_err(
            sphere_with(r#""eye": [0, 0, 4]"#, r#""eye": [0, -1e400, 4]"#),
            "camera.eye[1]",
        );
    }

    #[test]
    fn viewport_sides_outside_1_to_16384_are_refused() {
        let with = |w: u32, h: u32| {
            sphere_with(
                r#""objects""#,
                &format!(r#""viewport": {{"width": {w}, "height": {h}}}, "objects""#),
            )
        };
        assert_invalid(with(0, 512), "viewport.width");
        assert_invalid(with(512, 16385), "viewport.height");
        assert_eq!(
            with(16384, 1).unwrap().viewport,
            Viewport {
                width: 16384,
                height: 1
            }
        );
        // A negative side does not fit a u32: a parse error at the field.
        assert_parse_err(
            sphere_with(
                r#""objects""#,
                r#""viewport": {"width": -1, "height": 8}, "objects""#,
            ),
            "viewport.width",
        );
    }

    #[test]
    fn set_viewport_is_validated_like_the_file() {
        let mut scene = parse(SPHERE).unwrap();
        scene.set_viewport(640, 480).unwrap();
        assert_eq!(
            scene.viewport,
            Viewport {
                width: 640,
                height: 480
            }
        );
        match scene.set_viewport(640, 16385) {
            Err(Error::Invalid { field, .. }) => assert_eq!(field, "viewport.height"),
            other => panic!("{other:?}"),
        }
        assert_eq!(
            scene.viewport,
            Viewport {
                width: 640,
                height: 480
            }
        );
    }

    #[test]
    fn near_must_be_positive_and_far_beyond_it() {
        assert_invalid(
            sphere_with(r#""near": 0.1"#, r#""near": 0"#),
            "camera.projection.near",
        );
        assert_invalid(
            sphere_with(r#""near": 0.1"#, r#""near": -1"#),
            "camera.projection.near",
        );
        assert_invalid(
            sphere_with(r#""far": 100"#, r#""far": 0.1"#),
            "camera.projection.far",
        );
        assert_invalid(
            sphere_with(r#""fovy_deg": 40"#, r#""fovy_deg": 180"#),
            "camera.projection.fovy_deg",
        );
    }

    #[test]
    fn degenerate_cameras_are_refused() {
        assert_invalid(
            sphere_with(r#""target": [0, 0, 0]"#, r#""target": [0, 0, 4]"#),
            "camera.target",
        );
        let r = sphere_with(
            r#""target": [0, 0, 0]"#,
            r#""target": [0, 0, 0], "up": [0, 0, -2]"#,
        );
        assert_invalid(r, "camera.up");
    }

    #[test]
    fn out_of_range_colours_and_light_terms_are_refused() {
        assert_invalid(
            sphere_with(r#""objects""#, r#""background": [0, 0, 1.5], "objects""#),
            "background",
        );
        let r = sphere_with(
            r#"{"builtin": "sphere24"}"#,
            r#"{"builtin": "sphere24", "color": [0.5, -0.1, 0]}"#,
        );
        assert_invalid(r, "objects[0].color");
        assert_invalid(
            sphere_with(r#""objects""#, r#""light": {"kd": -0.5}, "objects""#),
            "light.kd",
        );
        let r = sphere_with(
            r#""objects""#,
            r#""light": {"direction_to_light": [0, 0, 0]}, "objects""#,
        );
        assert_invalid(r, "light.direction_to_light");
    }

    #[test]
    fn scene_name_must_be_a_directory_name() {
        let reason = assert_invalid(sphere_with(r#""name": "t""#, r#""name": "../up""#), "name");
        assert!(reason.contains("out/<name>/"), "{reason}");
        assert_invalid(sphere_with(r#""name": "t""#, r#""name": """#), "name");
    }

    #[test]
    fn object_with_two_kinds_or_none_is_refused() {
        let r = sphere_with(
            r#"{"builtin": "sphere24"}"#,
            r#"{"builtin": "sphere24", "mesh": "meshes/bunny.obj"}"#,
        );
        let _ = assert_invalid(r, "objects[0]");
        assert_invalid(
            sphere_with(r#"{"builtin": "sphere24"}"#, r#"{"color": [1, 1, 1]}"#),
            "objects[0]",
        );
    }

    #[test]
    fn unknown_builtin_lists_the_known_names() {
        let reason = assert_invalid(sphere_with("sphere24", "teapot"), "objects[0].builtin");
        for name in BUILTIN_NAMES {
            assert!(reason.contains(name), "{reason}");
        }
    }

    #[test]
    fn bad_transform_is_refused() {
        let r = sphere_with(
            r#"{"builtin": "sphere24"}"#,
            r#"{"builtin": "sphere24", "transform": {"scale": 0}}"#,
        );
        assert_invalid(r, "objects[0].transform.scale");
        let r = sphere_with(
            r#"{"builtin": "sphere24"}"#,
            r#"{"builtin": "sphere24", "transform": {"scale": 1e300}}"#,
        );
        assert_invalid(r, "objects[0].transform");
    }

    #[test]
    fn missing_obj_file_is_a_mesh_error_with_the_os_reason() {
        let message = assert_mesh_err(
            sphere_with(
                r#""builtin": "sphere24""#,
                r#""mesh": "meshes/missing.obj""#,
            ),
            "objects[0].mesh",
        );
        let os = std::fs::read("/nonexistent/lembo-sim")
            .unwrap_err()
            .to_string();
        assert_eq!(message, os);
    }

    fn scene_with_obj(obj: &str) -> Result<Scene> {
        let dir = tempfile::tempdir().unwrap();
        let mut f = std::fs::File::create(dir.path().join("m.obj")).unwrap();
        f.write_all(obj.as_bytes()).unwrap();
        let text = SPHERE.replacen(r#""builtin": "sphere24""#, r#""mesh": "m.obj""#, 1);
        Scene::from_json(&text, "test.json", dir.path())
    }

    #[test]
    fn obj_with_nan_coordinate_is_a_mesh_error() {
        let message = assert_mesh_err(
            scene_with_obj("v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n"),
            "objects[0].mesh",
        );
        assert!(message.contains("non-finite"), "{message}");
    }

    #[test]
    fn obj_without_triangles_or_with_bad_indices_is_a_mesh_error() {
        assert_mesh_err(
            scene_with_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\n"),
            "objects[0].mesh",
        );
        assert_mesh_err(
            scene_with_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n"),
            "objects[0].mesh",
        );
    }

    #[test]
    fn obj_quads_are_triangulated_and_normals_computed() {
        let scene = scene_with_obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n").unwrap();
        let mesh = scene.objects[0].mesh.as_ref().unwrap();
        assert_eq!(mesh.triangles.len(), 2);
        assert!(mesh.normals.iter().all(|n| *n == DVec3::Z));
        assert_eq!(scene.lembo_count(), 2);
    }

    const INLINE: &str = r#"{"lembos": [{"points": [[0,0,0],[1,0,0],[0,1,0],[0.5,0,0.25],[0,0.5,0.25],[0.5,0.5,0.125]],
                                         "normals": [[0,0,1],[0,0,2],[0,0,1],[0,0.1,1],[0.1,0,1],[0.1,0.1,1]]}],
                            "transform": {"scale": 1, "rotate_deg": [0, 0, 0], "translate": [0, 0, 0]}}"#;

    #[test]
    fn inline_lembo_round_trips_through_an_identity_transform() {
        let scene = sphere_with(r#"{"builtin": "sphere24"}"#, INLINE).unwrap();
        let o = &scene.objects[0];
        assert!(o.mesh.is_none());
        assert_eq!(o.label, "inline lembos");
        let l = &o.lembos[0];
        let points = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.5, 0.0, 0.25],
            [0.0, 0.5, 0.25],
            [0.5, 0.5, 0.125],
        ];
        assert_eq!(l.points.map(|p| p.to_array()), points);
        // Inline normals keep their length.
        assert_eq!(l.normals[1], DVec3::new(0.0, 0.0, 2.0));
    }

    #[test]
    fn inline_lembo_is_rotated_with_its_normals() {
        let text = INLINE.replace(r#""rotate_deg": [0, 0, 0]"#, r#""rotate_deg": [0, 0, 90]"#);
        let scene = sphere_with(r#"{"builtin": "sphere24"}"#, &text).unwrap();
        let l = &scene.objects[0].lembos[0];
        // 90 degrees about z takes x to y.
        assert!((l.points[1] - DVec3::Y).length() < 1e-15);
        assert!((l.normals[1] - DVec3::new(0.0, 0.0, 2.0)).length() < 1e-15);
    }

    #[test]
    fn inline_lembos_must_not_be_empty() {
        assert_invalid(
            sphere_with(r#"{"builtin": "sphere24"}"#, r#"{"lembos": []}"#),
            "objects[0].lembos",
        );
    }

    #[test]
    fn transform_scales_then_rotates_then_translates() {
        let plain = parse(SPHERE).unwrap();
        let moved = sphere_with(
            r#"{"builtin": "sphere24"}"#,
            r#"{"builtin": "sphere24", "transform": {"scale": 2, "translate": [1, -2, 3]}}"#,
        )
        .unwrap();
        let offset = DVec3::new(1.0, -2.0, 3.0);
        for (a, b) in plain.objects[0].lembos.iter().zip(&moved.objects[0].lembos) {
            for k in 0..6 {
                assert!((b.points[k] - (2.0 * a.points[k] + offset)).length() < 1e-12);
                assert!((b.normals[k] - a.normals[k]).length() < 1e-12);
            }
        }
        let mesh = moved.objects[0].mesh.as_ref().unwrap();
        assert!((mesh.positions[0] - (2.0 * DVec3::Y + offset)).length() < 1e-12);
        // X first, then Y: a 90-degree turn about x takes +y to +z, then 90 about y takes
        // +z to +x.
        let turned = sphere_with(
            r#"{"builtin": "sphere24"}"#,
            r#"{"builtin": "sphere24", "transform": {"rotate_deg": [90, 90, 0]}}"#,
        )
        .unwrap();
        let north = turned.objects[0].mesh.as_ref().unwrap().positions[0];
        assert!((north - DVec3::X).length() < 1e-12, "{north}");
    }
}
