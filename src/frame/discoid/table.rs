//! What the ROP blend units know of every discoid of a scene, by primitive id
//! ([`DiscoidTable`]; the planar discoids as a triangle source, [`PlanarDiscoids`]), and a
//! discoid fragment as the ROP sees it, evaluated before any test ([`evaluate`]: facing,
//! beta, depth).

use crate::camera::View;
use crate::datapath::Real;
use crate::discoid::ewa::EwaKernel;
use crate::discoid::texture::{BetaTexture, TEXTURE_SIZE};
use crate::discoid::{BetaShape, Discoid, PLANAR_DISCOID_BYTES};
use crate::lembo::tessellate::Triangle;
use crate::lembo::{eval3, Quadratic};
use crate::raster::setup::ScreenLembo;
use crate::raster::triangle::{ScreenTriangle, TriangleFragment, TriangleSource};
use crate::rop::fragment_shader::{normalize, FragmentShader};
use crate::scene::Scene;

/// The scene's planar discoids as a triangle source: two triangles per discoid, after the
/// `first_id` ids of the curved discoids.
pub struct PlanarDiscoids {
    /// Discoid, material colour and beta shape, in scene order.
    pub items: Vec<(Discoid, [f64; 3], BetaShape)>,
    /// The primitive id of the first planar discoid (after the curved discoids' lembos).
    pub first_id: u32,
}

impl PlanarDiscoids {
    /// The planar discoids of `scene`'s objects, in scene order.
    pub fn new(scene: &Scene) -> Self {
        let items = scene
            .objects
            .iter()
            .filter_map(|o| o.discoids.as_ref().map(|d| (o, d)))
            .flat_map(|(o, d)| d.planar.iter().map(move |p| (*p, o.color, d.beta)))
            .collect();
        PlanarDiscoids {
            items,
            first_id: scene.lembo_count() as u32,
        }
    }

    /// The planar discoid that triangle `id` belongs to.
    #[inline]
    pub fn of_triangle(&self, id: u32) -> usize {
        ((id - self.first_id) / 2) as usize
    }
}

impl TriangleSource for PlanarDiscoids {
    fn chunks(&self) -> usize {
        self.items.len()
    }

    fn per_chunk(&self) -> u64 {
        2
    }

    fn bytes(&self, _: &crate::config::FetchConfig) -> u64 {
        PLANAR_DISCOID_BYTES * self.items.len() as u64
    }

    fn chunk(&self, c: usize, out: &mut Vec<Triangle>) {
        let (d, color, _) = &self.items[c];
        let q = d.corners();
        out.clear();
        for [a, b, e] in [[0, 1, 2], [0, 2, 3]] {
            out.push(Triangle {
                positions: [q[a], q[b], q[e]],
                normals: [d.normal; 3],
                color: *color,
            });
        }
    }

    fn first_id(&self) -> u32 {
        self.first_id
    }
}

/// What the ROP blend units know of every discoid, by primitive id.
pub struct DiscoidTable<R> {
    /// The planar discoids (surfels included).
    pub planar: PlanarDiscoids,
    /// Per lembo id: the texture-coordinate quadratics (s, t) and the beta shape of a
    /// curved discoid; None for a lembo that is not one.
    curved: Vec<Option<([Quadratic<R>; 2], BetaShape)>>,
    /// Material colour per lembo id.
    lembo_color: Vec<[f64; 3]>,
    /// One texture per shape, indexed by [`shape_index`].
    textures: [BetaTexture; 3],
    /// Whether the scene's planar discoids are surfels.
    pub surfels: bool,
    /// Per planar discoid: its EWA kernel, for the `ewa` beta.
    ewa: Vec<Option<EwaKernel>>,
}

fn shape_index(s: BetaShape) -> usize {
    match s {
        BetaShape::Disk => 0,
        BetaShape::Star => 1,
        BetaShape::Gaussian | BetaShape::Ewa => 2,
    }
}

impl<R: Real> DiscoidTable<R> {
    /// The table of `scene`'s discoids in the datapath's precision, seen through `view`
    /// (the EWA kernels depend on it).
    pub fn new(scene: &Scene, view: &View) -> Self {
        let mut curved = Vec::with_capacity(scene.lembo_count());
        let mut lembo_color = Vec::with_capacity(scene.lembo_count());
        for o in &scene.objects {
            for (k, _) in o.lembos.iter().enumerate() {
                lembo_color.push(o.color);
                curved.push(o.discoids.as_ref().and_then(|d| {
                    d.lembo_texcoords.get(k).map(|st| {
                        let q =
                            |c: usize| Quadratic::from_reference_values(st.map(|p| R::of(p[c])));
                        ([q(0), q(1)], d.beta)
                    })
                }));
            }
        }
        let planar = PlanarDiscoids::new(scene);
        let ewa = planar
            .items
            .iter()
            .map(|(d, _, shape)| (*shape == BetaShape::Ewa).then(|| EwaKernel::new(d, view)))
            .collect();
        DiscoidTable {
            ewa,
            planar,
            curved,
            lembo_color,
            textures: [BetaShape::Disk, BetaShape::Star, BetaShape::Gaussian]
                .map(|s| BetaTexture::new(s, TEXTURE_SIZE)),
            surfels: scene
                .objects
                .iter()
                .any(|o| o.discoids.as_ref().is_some_and(|d| d.surfels)),
        }
    }

    /// The discoid fragment of lembo `l` at (u, v), depth z; None when the lembo is not a
    /// curved discoid (the run checks the scene, so it does not happen).
    #[inline]
    pub fn lembo_fragment(
        &self,
        l: &ScreenLembo<R>,
        u: R,
        v: R,
        z: R,
    ) -> Option<DiscoidFragment<R>> {
        let (tex, shape) = self.curved[l.id as usize].as_ref()?;
        // The texture coordinates are quadratics over the lembo's domain; a piece of a split
        // lembo maps its (u, v) there first.
        let (lu, lv) = l.lembo_uv(u, v);
        Some(DiscoidFragment {
            id: l.id,
            z,
            normal: eval3(&l.normal, u, v),
            position: eval3(&l.position, u, v),
            st: [tex[0].eval(lu, lv).f64(), tex[1].eval(lu, lv).f64()],
            shape: *shape,
        })
    }

    /// The discoid fragment of a planar discoid's triangle `t`.
    #[inline]
    pub fn planar_fragment(
        &self,
        t: &ScreenTriangle<R>,
        f: &TriangleFragment<R>,
    ) -> DiscoidFragment<R> {
        let (d, _, shape) = &self.planar.items[self.planar.of_triangle(t.id)];
        let p = f.position.map(|c| c.f64());
        DiscoidFragment {
            id: t.id,
            z: f.z,
            normal: f.normal,
            position: f.position,
            st: d.texcoord(glam::DVec3::from_array(p)),
            shape: *shape,
        }
    }

    /// The material colour of primitive `id`.
    pub fn color(&self, id: u32) -> [f64; 3] {
        match self.lembo_color.get(id as usize) {
            Some(c) => *c,
            None => self.planar.items[self.planar.of_triangle(id)].1,
        }
    }
}

/// One discoid fragment as the ROP sees it.
pub struct DiscoidFragment<R> {
    /// Primitive id.
    pub id: u32,
    /// Window depth [0, 1].
    pub z: R,
    /// World-space normal (not necessarily unit) and position.
    pub normal: [R; 3],
    /// World-space position.
    pub position: [R; 3],
    /// Texture coordinates and the discoid's shape.
    pub st: [f64; 2],
    /// The discoid's beta shape.
    pub shape: BetaShape,
}

/// What the ROP computes of a discoid fragment before any test; the interest values of
/// equation (6) are computed only for a fragment the accumulation pass keeps.
#[derive(Clone, Copy, Debug)]
pub struct Evaluated<R> {
    /// The discoid faces the eye at this fragment.
    pub facing: bool,
    /// beta from the discoid's texture (0 outside it).
    pub beta: f64,
    /// Depth as the depth buffer holds it.
    pub z: f32,
    /// Unit normal and unit direction to the eye.
    pub normal: [R; 3],
    /// Unit direction to the eye.
    pub to_eye: [R; 3],
}

/// Evaluates a discoid fragment: facing, beta, depth.
#[inline]
pub fn evaluate<R: Real>(
    table: &DiscoidTable<R>,
    shader: &FragmentShader<R>,
    f: &DiscoidFragment<R>,
) -> Evaluated<R> {
    let (n, e) = (normalize(f.normal), shader.to_eye(f.position));
    Evaluated {
        facing: n[0] * e[0] + n[1] * e[1] + n[2] * e[2] >= R::zero(),
        beta: match f.shape {
            BetaShape::Ewa => table.ewa[table.planar.of_triangle(f.id)]
                .expect("every ewa discoid has its kernel")
                .beta(f.st),
            shape => table.textures[shape_index(shape)].sample(f.st[0], f.st[1]),
        },
        z: f.z.f64() as f32,
        normal: n,
        to_eye: e,
    }
}
