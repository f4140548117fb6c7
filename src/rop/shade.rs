//! Per-fragment Phong shading, Piranda et al. 2006 equation (6): `L = Ka + Kd cos(alpha) + Ks
//! cos^N(gamma)`.
//!
//! `alpha` is the angle between the unit normal and the direction to the light, `gamma` the
//! angle between the light reflected about the normal and the direction to the eye. The
//! material colour scales the ambient and diffuse terms; the specular term is white. Lighting
//! is two-sided: a normal facing away from the eye is flipped, so open surfaces seen from
//! behind are lit like their front.

use crate::datapath::Real;
use crate::scene::Light;

/// The light and material terms in a datapath's precision, ready for the fragment loop.
#[derive(Clone, Copy, Debug)]
pub struct Shader<R> {
    /// Unit direction towards the light.
    pub l: [R; 3],
    /// Ambient term.
    pub ka: R,
    /// Diffuse term.
    pub kd: R,
    /// Specular term.
    pub ks: R,
    /// Shininess exponent.
    pub shininess: R,
    /// The shininess as an integer when it is one (repeated multiplication, as a hardware
    /// exponent unit would do, instead of exp/log).
    shininess_int: Option<i32>,
}

impl<R: Real> Shader<R> {
    /// The terms of `light` in the datapath's precision.
    pub fn new(light: &Light) -> Self {
        let d = glam::DVec3::from_array(light.direction_to_light).normalize_or_zero();
        Shader {
            l: [R::of(d.x), R::of(d.y), R::of(d.z)],
            ka: R::of(light.ka),
            kd: R::of(light.kd),
            ks: R::of(light.ks),
            shininess: R::of(light.shininess),
            shininess_int: (light.shininess.fract() == 0.0 && light.shininess.abs() <= 1024.0)
                .then_some(light.shininess as i32),
        }
    }

    /// The shininess as an integer, when it is one.
    #[inline(always)]
    pub(super) fn shininess_int(&self) -> Option<i32> {
        self.shininess_int
    }

    /// Linear RGB in [0, 1] for a unit normal `n`, unit direction to the eye `v` and a
    /// material colour.
    #[inline]
    pub fn shade(&self, n: [R; 3], v: [R; 3], color: [R; 3]) -> [R; 3] {
        let (cos_a, cos_g_n) = self.terms(n, v);
        self.combine(cos_a, cos_g_n, color)
    }

    /// The two interest values of equation (6) at a unit normal `n` seen along the unit
    /// direction to the eye `v`: cos(alpha) and cos^N(gamma), each in [0, 1] (two-sided:
    /// a normal facing away from the eye is flipped). The discoid blend units average them.
    #[inline]
    pub fn terms(&self, n: [R; 3], v: [R; 3]) -> (R, R) {
        let zero = R::zero();
        let dot = |a: [R; 3], b: [R; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let n = if dot(n, v) < zero {
            [-n[0], -n[1], -n[2]]
        } else {
            n
        };
        let nl = dot(n, self.l);
        let cos_a = nl.max(zero);
        let two = R::of(2.0);
        let r = [
            two * nl * n[0] - self.l[0],
            two * nl * n[1] - self.l[1],
            two * nl * n[2] - self.l[2],
        ];
        let cos_g = dot(r, v).max(zero);
        let cos_g_n = if cos_g > zero && nl > zero {
            match self.shininess_int {
                Some(n) => cos_g.powi(n),
                None => cos_g.powf(self.shininess),
            }
        } else {
            zero
        };
        (cos_a, cos_g_n)
    }

    /// Equation (6) from its two interest values: `color (Ka + Kd cos_a) + Ks cos_g_n`
    /// (the specular term is white).
    #[inline]
    pub fn combine(&self, cos_a: R, cos_g_n: R, color: [R; 3]) -> [R; 3] {
        let zero = R::zero();
        let spec = if self.ks > zero {
            self.ks * cos_g_n
        } else {
            zero
        };
        let diffuse = self.ka + self.kd * cos_a;
        [
            color[0] * diffuse + spec,
            color[1] * diffuse + spec,
            color[2] * diffuse + spec,
        ]
    }
}

/// Quantises a linear [0, 1] channel to 8 bits (clamped, rounded to nearest; NaN gives 0).
///
/// The clamp is `max` then `min` (a NaN becomes 0 at the `max`, where `clamp` would keep it
/// and the cast would make it 0), so the sum is in [0.5, 255.5] and truncates with a plain
/// conversion, which the compiler vectorises across a batch's lanes; `as u8` on a float
/// would check each value for NaN and range one by one. The same bits as
/// `(c.clamp(0, 1) * 255 + 0.5) as u8` for every input (tested).
// Not `clamp`: it keeps a NaN, which the unchecked conversion must not see.
#[allow(clippy::manual_clamp)]
#[inline]
pub fn to_u8<R: Real>(c: R) -> u8 {
    let x = c.f64().max(0.0).min(1.0) * 255.0;
    // SAFETY: x is in [0, 255] (never NaN: `max` returns 0 for a NaN), so x + 0.5 is in
    // [0.5, 255.5] and its truncation fits an i32.
    let t: i32 = unsafe { (x + 0.5).to_int_unchecked() };
    t as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equation_6_terms_at_known_angles() {
        let light = Light {
            direction_to_light: [0.0, 0.0, 1.0],
            ka: 0.1,
            kd: 0.5,
            ks: 0.4,
            shininess: 2.0,
        };
        let s = Shader::<f64>::new(&light);
        // Normal, light and eye aligned: cos(alpha) = cos(gamma) = 1.
        let c = s.shade([0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [1.0, 0.5, 0.0]);
        assert!((c[0] - (0.1 + 0.5 + 0.4)).abs() < 1e-12);
        assert!((c[1] - (0.5 * 0.6 + 0.4)).abs() < 1e-12);
        // Normal at 60 degrees to the light, eye along the reflection: cos(alpha) = 1/2.
        let n = [3f64.sqrt() / 2.0, 0.0, 0.5];
        let r = [2.0 * 0.5 * n[0], 0.0, 2.0 * 0.5 * n[2] - 1.0];
        let c = s.shade(n, r, [1.0, 1.0, 1.0]);
        assert!((c[0] - (0.1 + 0.25 + 0.4)).abs() < 1e-12);
    }

    /// The quantisation as first written: clamp, scale, round, saturating cast.
    fn to_u8_as_written(c: f64) -> u8 {
        (c.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
    }

    #[test]
    fn to_u8_gives_the_bits_of_the_clamped_saturating_cast() {
        let mut values = vec![
            f64::NAN,
            -f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            0.0,
            -0.0,
            1.0,
            -1.0,
            2.0,
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
            1.0 + f64::EPSILON,
            1.0 - f64::EPSILON / 2.0,
            1e300,
            -1e300,
        ];
        // Either side of every rounding boundary (k + 0.5) / 255.
        for k in 0..=255 {
            let b = (k as f64 + 0.5) / 255.0;
            let (up, down) = (b.next_up(), b.next_down());
            values.extend([b, up, down, k as f64 / 255.0]);
            values.extend([b as f32, (b as f32).next_up(), (b as f32).next_down()].map(f64::from));
        }
        let mut rng = crate::testkit::SplitMix64::new(7);
        // Under Miri, which checks `to_u8`'s unchecked conversion on each value, the
        // boundaries above and a few random values are enough.
        let random = if cfg!(miri) { 200 } else { 100_000 };
        values.extend((0..random).map(|_| rng.range(-0.5, 1.5)));
        for c in values {
            assert_eq!(to_u8(c), to_u8_as_written(c), "f64 {c:e}");
            let f = c as f32;
            assert_eq!(to_u8(f), to_u8_as_written(f as f64), "f32 {f:e}");
        }
    }

    /// Equation (6) written out in f64 for the unit normal `n` facing the eye along `v`.
    fn phong(light: &Light, n: [f64; 3], v: [f64; 3], color: [f64; 3]) -> [f64; 3] {
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let l = glam::DVec3::from_array(light.direction_to_light)
            .normalize()
            .to_array();
        let nl = dot(n, l);
        let r = [0, 1, 2].map(|i| 2.0 * nl * n[i] - l[i]);
        let cos_g = dot(r, v).max(0.0);
        let spec = if cos_g > 0.0 && nl > 0.0 {
            light.ks * cos_g.powf(light.shininess)
        } else {
            0.0
        };
        color.map(|c| c * (light.ka + light.kd * nl.max(0.0)) + spec)
    }

    /// A normal facing away from the eye is lit as its flip, which faces the eye: both give
    /// equation (6) of the flipped normal, and a different normal gives another colour (a
    /// shader that ignored normals would pass the equality alone).
    #[test]
    fn back_facing_normals_are_lit_as_front_facing() {
        let light = Light::default();
        let s = Shader::<f32>::new(&light);
        let v = [0.0, 0.0, 1.0];
        let colour = [0.8, 0.5, 0.2];
        for front in [
            [0.0, 0.6, 0.8],
            [0.6, 0.0, 0.8],
            [0.0, 0.0, 1.0],
            [-0.48, 0.6, 0.64],
        ] {
            let back = front.map(|c: f64| -c);
            let lit = s.shade(front.map(|c| c as f32), v, colour);
            assert_eq!(lit, s.shade(back.map(|c| c as f32), v, colour), "{front:?}");
            let expected = phong(&light, front, [0.0, 0.0, 1.0], colour.map(f64::from));
            for (got, want) in lit.iter().zip(expected) {
                assert!(
                    (*got as f64 - want).abs() < 1e-5,
                    "{front:?}: {lit:?} {expected:?}"
                );
            }
        }
        let (a, b) = (
            s.shade([0.0, 0.6, 0.8], v, colour),
            s.shade([0.6, 0.0, 0.8], v, colour),
        );
        assert!((a[0] - b[0]).abs() > 0.01, "{a:?} {b:?}");
    }
}
