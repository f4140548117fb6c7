//! The EWA resampling kernel of a planar discoid (Zwicker et al. 2001, "Surface splatting"):
//! the `ewa` beta, a discoid's tangent-plane gaussian as the screen resamples it.

use super::texture::GAUSSIAN_SIGMA;
use super::Discoid;
use crate::camera::View;

/// The EWA resampling kernel of one planar discoid (Zwicker et al. 2001, "Surface
/// splatting", section 4): the tangent-plane gaussian of standard deviation σ = R/3 (the
/// `gaussian` beta's) mapped to the screen by the Jacobian J of the projection at the
/// discoid's centre, and convolved with a unit-variance screen-space low-pass filter. For a
/// tangent-plane offset u (world units, along the discoid's frame), the screen offset is
/// J·u, so the resampled gaussian is `exp(−½ uᵀ Jᵀ M⁻¹ J u)` with `M = σ² J Jᵀ + I`,
/// weighted by `σ² |det J| / √det M`: EWA's normalised kernel times the reconstruction
/// kernel's area 2πσ², so that a discoid much larger than a pixel gets the `gaussian` beta
/// in the limit (within 2/255 at 700 px across; tested) and β ≤ 1 fits the blend units' 8-bit beta (surfels of equal size weigh as EWA
/// weighs them). Like the textures, β is 0 outside the disk and quantised to 1/255 (a
/// hardware unit would look exp up in a one-dimensional table indexed by the quadratic form,
/// as Weyrich et al. 2007 do). Where the projection is not finite (a centre behind the eye)
/// the kernel is the tangent-plane gaussian.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EwaKernel {
    /// The quadratic form Jᵀ M⁻¹ J: (xx, xy, yy) \[world units⁻²\].
    q: [f64; 3],
    /// The weight σ² |det J| / √det M, in (0, 1].
    scale: f64,
    /// The discoid's radius \[world units\].
    radius: f64,
}

impl EwaKernel {
    /// The kernel of discoid `d` seen through `view`.
    pub fn new(d: &Discoid, view: &View) -> Self {
        let sigma = GAUSSIAN_SIGMA * d.radius;
        let (e1, e2) = d.frame();
        let h = 1e-4 * d.radius;
        let column = |e: glam::DVec3| {
            let (a, b) = (
                view.project(d.center + h * e),
                view.project(d.center - h * e),
            );
            [(a.x - b.x) / (2.0 * h), (a.y - b.y) / (2.0 * h)]
        };
        let (j1, j2) = (column(e1), column(e2));
        // J = [j1 j2] (columns): screen offset = j1 u.x + j2 u.y.
        let s2 = sigma * sigma;
        let m = [
            s2 * (j1[0] * j1[0] + j2[0] * j2[0]) + 1.0,
            s2 * (j1[0] * j1[1] + j2[0] * j2[1]),
            s2 * (j1[1] * j1[1] + j2[1] * j2[1]) + 1.0,
        ];
        let det_m = m[0] * m[2] - m[1] * m[1];
        let det_j = j1[0] * j2[1] - j2[0] * j1[1];
        let inv = [m[2] / det_m, -m[1] / det_m, m[0] / det_m];
        // Jᵀ M⁻¹ J, entry (a, b) = j_a · (M⁻¹ j_b).
        let form = |a: [f64; 2], b: [f64; 2]| {
            a[0] * (inv[0] * b[0] + inv[1] * b[1]) + a[1] * (inv[1] * b[0] + inv[2] * b[1])
        };
        let q = [form(j1, j1), form(j1, j2), form(j2, j2)];
        let scale = s2 * det_j.abs() / det_m.sqrt();
        if q.iter().chain([&scale]).all(|x| x.is_finite()) && det_m > 0.0 {
            EwaKernel {
                q,
                scale: scale.min(1.0),
                radius: d.radius,
            }
        } else {
            EwaKernel {
                q: [1.0 / s2, 0.0, 1.0 / s2],
                scale: 1.0,
                radius: d.radius,
            }
        }
    }

    /// β at texture coordinates (s, t) of the discoid.
    pub fn beta(&self, st: [f64; 2]) -> f64 {
        let u = [
            (st[0] - 0.5) * 2.0 * self.radius,
            (st[1] - 0.5) * 2.0 * self.radius,
        ];
        if u[0] * u[0] + u[1] * u[1] >= self.radius * self.radius {
            return 0.0;
        }
        let e = self.q[0] * u[0] * u[0] + 2.0 * self.q[1] * u[0] * u[1] + self.q[2] * u[1] * u[1];
        (255.0 * self.scale * (-0.5 * e).exp()).round() / 255.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Camera, Projection, Viewport};
    use crate::discoid::texture::BetaTexture;
    use crate::discoid::BetaShape;
    use glam::DVec3;

    fn view(eye_distance: f64) -> View {
        View::new(
            &Camera {
                eye: [0.0, 0.0, eye_distance],
                target: [0.0; 3],
                up: [0.0, 1.0, 0.0],
                projection: Projection::Perspective {
                    fovy_deg: 40.0,
                    near: 0.01,
                    far: 1e6,
                },
            },
            Viewport {
                width: 512,
                height: 512,
            },
        )
    }

    fn surfel(normal: DVec3) -> Discoid {
        Discoid {
            center: DVec3::ZERO,
            normal: normal.normalize(),
            radius: 1.0,
        }
    }

    #[test]
    fn a_large_ewa_discoid_is_the_tangent_plane_gaussian() {
        // About 700 px across: the one-pixel low-pass filter changes nothing visible.
        let k = EwaKernel::new(&surfel(DVec3::Z), &view(4.0));
        let gauss = BetaTexture::new(BetaShape::Gaussian, 1024);
        for st in [[0.5, 0.5], [0.6, 0.5], [0.5, 0.75], [0.3, 0.3], [0.05, 0.5]] {
            let (a, b) = (k.beta(st), gauss.sample(st[0], st[1]));
            assert!((a - b).abs() <= 2.0 / 255.0, "{st:?}: {a} {b}");
        }
        assert_eq!(k.beta([0.0, 0.0]), 0.0, "outside the disk");
    }

    #[test]
    fn a_small_ewa_discoid_is_widened_and_weighed_down_by_the_filter() {
        // About 2 px across: the filter dominates; the kernel is flatter and its weight,
        // EWA's normalisation, smaller.
        let k = EwaKernel::new(&surfel(DVec3::Z), &view(1400.0));
        assert!(k.scale < 0.5, "{}", k.scale);
        let (centre, rim) = (k.beta([0.5, 0.5]), k.beta([0.5, 0.95]));
        assert!(rim > 0.5 * centre, "{centre} {rim}");
    }

    #[test]
    fn an_oblique_ewa_discoid_is_an_ellipse() {
        // Seen at 75° from its normal, one tangent axis is foreshortened on screen by
        // cos 75° (about 9 px across instead of 35), where the filter's pixel is a larger
        // share: the kernel is wider along that axis in the tangent plane (its quadratic
        // form smaller, 6.3 against 8.7 /unit²), unlike the frontal one's.
        let frontal = EwaKernel::new(&surfel(DVec3::Z), &view(40.0));
        let oblique = EwaKernel::new(
            &surfel(DVec3::new(
                0.0,
                75f64.to_radians().sin(),
                75f64.to_radians().cos(),
            )),
            &view(40.0),
        );
        let eig = |q: [f64; 3]| {
            let (m, d) = (
                0.5 * (q[0] + q[2]),
                (0.25 * (q[0] - q[2]).powi(2) + q[1] * q[1]).sqrt(),
            );
            (m + d) / (m - d)
        };
        assert!(eig(frontal.q) < 1.01, "{:?}", frontal.q);
        assert!(eig(oblique.q) > 1.3, "{:?}", oblique.q);
        assert!(oblique.q[2] < oblique.q[0]);
    }
}
