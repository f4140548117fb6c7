//! The ROP's shading in lanes: [`LANES`] fragments of one primitive shaded together, by the
//! same IEEE operations in the same order as [`FragmentShader::shade_at`] does them one at a
//! time, so the compiler can hold the lanes in SIMD registers and every colour stays bit for
//! bit what the scalar shader gives (the tests below compare lane by lane).
//!
//! What changes is only the control flow. Each branch of the scalar shader becomes a select
//! between both of its sides, computed for every lane (a discarded side has no effect on
//! plain `f32`/`f64` arithmetic), so one lane's work up to the specular power is a body
//! without branches in a loop over the lanes, which the compiler vectorises across them (a
//! loop vectorises better than the same work written as operations on arrays of lanes,
//! measured). `powi` is the same square-and-multiply sequence that the runtime's
//! `__powisf2`/`__powidf2` runs, written out so it can run in lanes. No operation is fused
//! (Rust never contracts `a * b + c` into a fused multiply-add).
//!
//! A counting datapath (`cost::counted::Counted`) never comes here: selects would
//! count both sides of every branch, so the ROP shades its fragments one at a time and the
//! counts stay those of the formula as written.

use super::fragment_shader::FragmentShader;
use super::shade::{to_u8, Shader};
use crate::datapath::Real;

/// Fragments shaded together.
pub const LANES: usize = 8;

/// One value per lane.
pub type Lanes<R> = [R; LANES];

/// A vector per lane, as three lanes of coordinates.
pub type Lanes3<R> = [Lanes<R>; 3];

/// `[f(0), f(1), ...]` for every lane. (Loops, not `array::map` or `array::from_fn`: those
/// are not always inlined, and a call out of the AVX2 batch leaves its registers.)
#[inline(always)]
pub fn lanes<T: Copy + Default>(mut f: impl FnMut(usize) -> T) -> [T; LANES] {
    let mut out = [T::default(); LANES];
    for (k, x) in out.iter_mut().enumerate() {
        *x = f(k);
    }
    out
}

/// `[f(0), f(1), f(2)]`: the three coordinates of a vector.
#[inline(always)]
pub fn three<T>(mut f: impl FnMut(usize) -> T) -> [T; 3] {
    [f(0), f(1), f(2)]
}

/// `if c { a } else { b }` in every lane.
#[inline(always)]
fn select<R: Copy + Default>(c: &[bool; LANES], a: &Lanes<R>, b: &Lanes<R>) -> Lanes<R> {
    lanes(|k| if c[k] { a[k] } else { b[k] })
}

/// `x.powi(n)` per lane, bit for bit: the runtime's `powi` (compiler-builtins, as libgcc)
/// multiplies the powers x, x², x⁴, ... that the bits of |n| select, lowest first, into an
/// accumulator that starts at 1, and takes the reciprocal for n < 0.
#[inline(always)]
pub fn powi<R: Real>(x: &Lanes<R>, n: i32) -> Lanes<R> {
    let mut power = *x;
    let mut acc = [R::one(); LANES];
    let mut bits = n.unsigned_abs();
    loop {
        if bits & 1 != 0 {
            acc = lanes(|k| acc[k] * power[k]);
        }
        bits >>= 1;
        if bits == 0 {
            break;
        }
        power = lanes(|k| power[k] * power[k]);
    }
    if n < 0 {
        lanes(|k| R::one() / acc[k])
    } else {
        acc
    }
}

impl<R: Real> Shader<R> {
    /// [`Shader::combine`] per lane, quantised to 8 bits as the ROP writes it.
    #[inline(always)]
    pub fn combine_lanes(
        &self,
        cos_a: &Lanes<R>,
        cos_g_n: &Lanes<R>,
        color: [R; 3],
    ) -> [[u8; 3]; LANES] {
        let spec = if self.ks > R::zero() {
            lanes(|k| self.ks * cos_g_n[k])
        } else {
            [R::zero(); LANES]
        };
        let diffuse = lanes(|k| self.ka + self.kd * cos_a[k]);
        // Each channel in lanes, packed into a word per lane with vector shifts, then
        // unpacked from the word: one move out of the vector registers a fragment, not one
        // per channel.
        let q = three(|c| lanes(|k| to_u8(color[c] * diffuse[k] + spec[k]) as u32));
        let packed: [u32; LANES] = lanes(|k| q[0][k] | q[1][k] << 8 | q[2][k] << 16);
        lanes(|k| {
            let [r, g, b, _] = packed[k].to_le_bytes();
            [r, g, b]
        })
    }
}

/// [`super::fragment_shader::normalize`] of one vector, without a branch.
#[inline(always)]
fn normalize_one<R: Real>(v: [R; 3]) -> [R; 3] {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let positive = n > R::zero();
    let q = [v[0] / n, v[1] / n, v[2] / n];
    three(|c| if positive { q[c] } else { R::zero() })
}

impl<R: Real> FragmentShader<R> {
    /// [`FragmentShader::shade_at`] per lane: the colours of `LANES` surface points, lane k
    /// with the normal and world position `surface(k)` gives (the position is unused for
    /// orthographic views), and the unit normals they were shaded with.
    #[inline(always)]
    pub fn shade_lanes(
        &self,
        surface: impl Fn(usize) -> ([R; 3], [R; 3]),
        color: [R; 3],
    ) -> ([[u8; 3]; LANES], Lanes3<R>) {
        let s = self.shader();
        let (zero, two) = (R::zero(), R::of(2.0));
        let eye = self.eye();
        let constant = self.to_eye_constant();
        let mut unit = [[zero; LANES]; 3];
        let (mut cos_a, mut cos_g, mut lit) = ([zero; LANES], [zero; LANES], [false; LANES]);
        // One lane's body, without branches, in a loop the compiler vectorises across lanes
        // ([`Shader::terms`] up to the power).
        for k in 0..LANES {
            let (normal, position) = surface(k);
            let n = normalize_one(normal);
            let v = match constant {
                Some(d) => d,
                None => normalize_one(three(|c| eye[c] - position[c])),
            };
            let dot = |a: [R; 3], b: [R; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
            let back = dot(n, v) < zero;
            let m = three(|c| if back { -n[c] } else { n[c] });
            let nl = dot(m, s.l);
            let r = three(|c| two * nl * m[c] - s.l[c]);
            let g = dot(r, v).max(zero);
            for (c, x) in n.into_iter().enumerate() {
                unit[c][k] = x;
            }
            cos_a[k] = nl.max(zero);
            cos_g[k] = g;
            lit[k] = g > zero && nl > zero;
        }
        let power = match s.shininess_int() {
            Some(n) => powi(&cos_g, n),
            None => lanes(|k| cos_g[k].powf(s.shininess)),
        };
        let cos_g_n = select(&lit, &power, &[zero; LANES]);
        (s.combine_lanes(&cos_a, &cos_g_n, color), unit)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Camera, Projection, View, Viewport};
    use crate::scene::Light;

    fn rng(seed: u8) -> crate::testkit::SplitMix64 {
        crate::testkit::SplitMix64::new(seed as u64)
    }

    fn view(projection: Projection) -> View {
        let camera = Camera {
            eye: [1.0, 2.0, 5.0],
            target: [0.0; 3],
            up: [0.0, 1.0, 0.0],
            projection,
        };
        View::new(
            &camera,
            Viewport {
                width: 64,
                height: 64,
            },
        )
    }

    /// A value that reaches the corners the shader's branches turn on: zero (both signs),
    /// tiny, huge and ordinary values of either sign.
    fn value(rng: &mut crate::testkit::SplitMix64) -> f64 {
        match rng.below(10) {
            0 => 0.0,
            1 => -0.0,
            2 => rng.range(-1e-30, 1e-30),
            3 => rng.range(-1e30, 1e30),
            _ => rng.range(-2.0, 2.0),
        }
    }

    /// [`FragmentShader::shade_lanes`] compiled for AVX2, as the ROP runs it there.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn shade_lanes_avx2<R: Real>(
        shader: &FragmentShader<R>,
        normal: &Lanes3<R>,
        position: &Lanes3<R>,
        color: [R; 3],
    ) -> ([[u8; 3]; LANES], Lanes3<R>) {
        shader.shade_lanes(|k| lane(normal, position, k), color)
    }

    /// Lane k's normal and position.
    fn lane<R: Real>(normal: &Lanes3<R>, position: &Lanes3<R>, k: usize) -> ([R; 3], [R; 3]) {
        (three(|c| normal[c][k]), three(|c| position[c][k]))
    }

    fn check<R: Real>(light: &Light, view: &View, rng: &mut crate::testkit::SplitMix64) {
        #[cfg(target_arch = "x86_64")]
        let avx2 = crate::isa::avx2_comparable("the AVX2 shading lanes");
        let shader = FragmentShader::<R>::new(light, view);
        let color = [0.9, 0.45, 0.1].map(R::of);
        // Under Miri, which checks the AVX2 call's unsafe block, a few batches suffice.
        for _ in 0..if cfg!(miri) { 8 } else { 4000 } {
            let normal: Lanes3<R> = [0; 3].map(|_| lanes(|_| R::of(value(rng))));
            let position: Lanes3<R> = [0; 3].map(|_| lanes(|_| R::of(rng.range(-3.0, 3.0))));
            let (rgb, n) = shader.shade_lanes(|k| lane(&normal, &position, k), color);
            #[cfg(target_arch = "x86_64")]
            if avx2 {
                // SAFETY: `avx2_comparable` is true only where the kernels run as AVX2.
                let wide = unsafe { shade_lanes_avx2(&shader, &normal, &position, color) };
                assert_eq!(wide.0, rgb);
                assert_eq!(
                    wide.1.map(|c| c.map(|x| x.f64().to_bits())),
                    n.map(|c| c.map(|x| x.f64().to_bits()))
                );
            }
            for k in 0..LANES {
                let (want_rgb, want_n) = shader.shade_at(
                    [normal[0][k], normal[1][k], normal[2][k]],
                    [position[0][k], position[1][k], position[2][k]],
                    color,
                );
                assert_eq!(rgb[k], want_rgb, "lane {k} of {normal:?}");
                let got_n = [n[0][k], n[1][k], n[2][k]];
                assert_eq!(
                    got_n.map(|c| c.f64().to_bits()),
                    want_n.map(|c| c.f64().to_bits()),
                    "lane {k}"
                );
            }
        }
    }

    #[test]
    fn lanes_shade_bit_for_bit_as_the_scalar_shader() {
        let mut rng = rng(18);
        let perspective = view(Projection::Perspective {
            fovy_deg: 60.0,
            near: 1.0,
            far: 10.0,
        });
        let orthographic = view(Projection::Orthographic {
            height: 4.0,
            near: 1.0,
            far: 10.0,
        });
        assert!(orthographic.orthographic && !perspective.orthographic);
        let lights = [
            Light::default(),
            Light {
                shininess: 7.0,
                ..Light::default()
            },
            Light {
                shininess: 2.5,
                ks: 0.0,
                ..Light::default()
            },
            Light {
                shininess: 0.0,
                ka: 0.0,
                ..Light::default()
            },
        ];
        for light in &lights {
            for view in [&perspective, &orthographic] {
                check::<f32>(light, view, &mut rng);
                check::<f64>(light, view, &mut rng);
            }
        }
    }

    #[test]
    fn powi_in_lanes_is_the_runtime_powi_bit_for_bit() {
        let mut rng = rng(24);
        for n in (-40..=40).chain([127, 255, 1000, 1024, -1024]) {
            let x: Lanes<f32> = lanes(|_| rng.range(0.0, 1.5) as f32);
            let y: Lanes<f64> = lanes(|_| rng.range(0.0, 1.5));
            let (px, py) = (powi(&x, n), powi(&y, n));
            for k in 0..LANES {
                assert_eq!(px[k].to_bits(), x[k].powi(n).to_bits(), "{}^{n}", x[k]);
                assert_eq!(py[k].to_bits(), y[k].powi(n).to_bits(), "{}^{n}", y[k]);
            }
        }
    }
}
