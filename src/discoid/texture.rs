//! The beta textures of Piranda et al. 2006 (section 2, Figure 5): the 8-bit gray-level textures a
//! discoid carries, generated procedurally, and their bilinear sampling.
//!
//! Texture coordinates (s, t) span the discoid's square, [0, 1]², with the discoid's centre
//! at (0.5, 0.5) (see [`Discoid::texcoord`](super::Discoid::texcoord)). Texel (x, y) covers
//! [x/size, (x+1)/size) × [y/size, (y+1)/size) and holds `round(255·beta)` of its centre
//! ((x + 0.5)/size, (y + 0.5)/size). With r = 2·|(s, t) − (0.5, 0.5)| (0 at the centre, 1 at
//! the rim of the inscribed disk), the shapes are:
//!
//! - **disk** (Figure 5a): `1 − r` for r < 1, else 0: white centre fading to a black rim;
//! - **star** (Figure 5b): `1 − r/R(θ)` inside the outline R(θ), else 0, where R(θ) is a
//!   five-pointed star polygon: straight edges between five tips at radius 1 and five
//!   valleys at radius 0.45. One tip points towards t = 0 (up in [`BetaTexture::to_image`]);
//! - **gaussian**: `exp(−r²/(2σ²))` with σ = 1/3, cut to 0 for r >= 1 (it is 0.011 there,
//!   so the cut is a step of 3/255).
//!
//! Texels outside a shape's support are exactly 0 (black is outside the discoid, and the
//! accumulation pass discards beta = 0). The texture is 8-bit, as in the paper, so beta is
//! quantized to 1/255 before blending.
//!
//! What this does not model: mipmapping and anisotropic filtering (every fragment samples
//! the one level, however small or oblique the discoid appears), and the GPU's fixed-point
//! bilinear weights (f64 here).
//! Bilinear sampling is continuous, so within one texel outside a shape's support it
//! returns small positive values (a blend of the last nonzero texels and the zeros beyond):
//! the sampled discoid is up to one texel larger than its texels.

use super::BetaShape;
use image::GrayImage;
use std::f64::consts::PI;

/// The side of the textures the renderers use, in texels.
pub const TEXTURE_SIZE: u32 = 64;

/// The gaussian's standard deviation, in units of the discoid's radius (also the EWA
/// kernel's in the tangent plane).
pub const GAUSSIAN_SIGMA: f64 = 1.0 / 3.0;
/// The star's valleys' radius, in units of the discoid's radius (its tips are at 1).
const STAR_INNER_RADIUS: f64 = 0.45;
/// The star's number of points.
const STAR_POINTS: u32 = 5;
/// The direction of one of the star's tips, atan2(t − 0.5, s − 0.5): towards t = 0.
const STAR_TIP_ANGLE: f64 = -PI / 2.0;

/// A square 8-bit gray texture of one beta shape.
#[derive(Clone, Debug, PartialEq)]
pub struct BetaTexture {
    shape: BetaShape,
    /// Side, in texels, >= 1.
    size: u32,
    /// Row-major, `texels[y·size + x]` = round(255·beta) at the centre of texel (x, y).
    texels: Vec<u8>,
}

impl BetaTexture {
    /// Generates the texture of `shape` with `size`² texels. Panics if `size` is 0.
    pub fn new(shape: BetaShape, size: u32) -> Self {
        assert!(size >= 1, "a beta texture has at least one texel");
        let n = f64::from(size);
        let mut texels = Vec::with_capacity(size as usize * size as usize);
        for y in 0..size {
            for x in 0..size {
                let beta = shape_beta(shape, (f64::from(x) + 0.5) / n, (f64::from(y) + 0.5) / n);
                texels.push((255.0 * beta).round() as u8);
            }
        }
        BetaTexture {
            shape,
            size,
            texels,
        }
    }

    /// The shape this texture samples.
    pub fn shape(&self) -> BetaShape {
        self.shape
    }

    /// Side, in texels.
    pub fn size(&self) -> u32 {
        self.size
    }

    /// The 8-bit value of texel (x, y), x and y < size (panics otherwise).
    pub fn texel(&self, x: u32, y: u32) -> u8 {
        assert!(
            x < self.size && y < self.size,
            "texel ({x}, {y}) of a {0}x{0} texture",
            self.size
        );
        self.texels[(y * self.size + x) as usize]
    }

    /// Bilinear sample at texture coordinates (s, t), as beta in [0, 1]; 0 outside [0, 1]²
    /// (beta = 0 is outside the discoid).
    ///
    /// The texels beyond the texture's edge count as 0 (a clamp-to-border sampler with a
    /// black border), so at the square's edge the sample is half the edge texels (a few
    /// 255ths where the inscribed disk touches the edge) and falls to 0 beyond. At a texel
    /// centre the sample is that texel / 255 exactly (for a power-of-two size, whose centres
    /// are exact in binary). Near a shape's rim it is a small positive value up to one texel
    /// outside the support (see the module doc).
    pub fn sample(&self, s: f64, t: f64) -> f64 {
        // `contains` is false for NaN, which therefore samples as outside.
        if !((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t)) {
            return 0.0;
        }
        let n = f64::from(self.size);
        let (u, v) = (s * n - 0.5, t * n - 0.5);
        let (x0, y0) = (u.floor(), v.floor());
        let (fx, fy) = (u - x0, v - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let at = |x: i64, y: i64| -> f64 {
            let inside =
                (0..i64::from(self.size)).contains(&x) && (0..i64::from(self.size)).contains(&y);
            if inside {
                f64::from(self.texels[(y * i64::from(self.size) + x) as usize])
            } else {
                0.0
            }
        };
        let top = at(x0, y0) * (1.0 - fx) + at(x0 + 1, y0) * fx;
        let bottom = at(x0, y0 + 1) * (1.0 - fx) + at(x0 + 1, y0 + 1) * fx;
        (top * (1.0 - fy) + bottom * fy) / 255.0
    }

    /// The texture as a gray image: pixel (x, y) is texel (x, y), so t grows downwards.
    pub fn to_image(&self) -> GrayImage {
        GrayImage::from_raw(self.size, self.size, self.texels.clone())
            .expect("size² texels fill a size x size image")
    }
}

/// The exact beta of `shape` at texture coordinates (s, t) (see the module doc).
fn shape_beta(shape: BetaShape, s: f64, t: f64) -> f64 {
    let (dx, dy) = (s - 0.5, t - 0.5);
    let r = 2.0 * dx.hypot(dy);
    match shape {
        BetaShape::Disk if r < 1.0 => 1.0 - r,
        BetaShape::Star => {
            let outline = star_outline(dy.atan2(dx));
            if r < outline {
                1.0 - r / outline
            } else {
                0.0
            }
        }
        // The EWA kernel's texture is its tangent-plane profile (the renderer evaluates the
        // kernel itself, render::EwaKernel).
        BetaShape::Gaussian | BetaShape::Ewa if r < 1.0 => {
            (-r * r / (2.0 * GAUSSIAN_SIGMA * GAUSSIAN_SIGMA)).exp()
        }
        BetaShape::Disk | BetaShape::Gaussian | BetaShape::Ewa => 0.0,
    }
}

/// The star's outline radius R(θ) in the direction θ = atan2(t − 0.5, s − 0.5), in units of
/// the discoid's radius: 1 at the tips, 0.45 in the valleys, straight edges between them.
fn star_outline(theta: f64) -> f64 {
    let sector = 2.0 * PI / f64::from(STAR_POINTS);
    let half = sector / 2.0;
    // The angle from the nearest tip, folded into [0, half]: the outline is five-fold and
    // mirror-symmetric about each tip.
    let a = (theta - STAR_TIP_ANGLE).rem_euclid(sector);
    let a = if a > half { sector - a } else { a };
    // The edge from the tip P0 = (1, 0) to the valley P1 = inner·(cos half, sin half), in the
    // tip's frame; the ray d = (cos a, sin a) meets it at R = (P0 × P1) / (d × (P1 − P0)).
    let (p1x, p1y) = (
        STAR_INNER_RADIUS * half.cos(),
        STAR_INNER_RADIUS * half.sin(),
    );
    let (ex, ey) = (p1x - 1.0, p1y);
    p1y / (a.cos() * ey - a.sin() * ex)
}

#[cfg(test)]
mod tests {
    use super::*;

    const SHAPES: [BetaShape; 3] = [BetaShape::Disk, BetaShape::Star, BetaShape::Gaussian];

    /// The texel centre of (x, y) rotated by `angle` about the texture's centre.
    fn rotated_centre(size: u32, x: u32, y: u32, angle: f64) -> (f64, f64) {
        let n = f64::from(size);
        let (dx, dy) = (
            (f64::from(x) + 0.5) / n - 0.5,
            (f64::from(y) + 0.5) / n - 0.5,
        );
        let (sin, cos) = angle.sin_cos();
        (0.5 + cos * dx - sin * dy, 0.5 + sin * dx + cos * dy)
    }

    #[test]
    fn texture_centre_is_white_and_corners_are_black() {
        // An odd size has a texel centred on the discoid's centre: r = 0 there, beta = 1.
        for shape in SHAPES {
            let tex = BetaTexture::new(shape, 65);
            assert_eq!(tex.texel(32, 32), 255, "{}", shape.name());
            assert_eq!(tex.sample(0.5, 0.5), 1.0, "{}", shape.name());
        }
        // TEXTURE_SIZE is even: the centre is the corner of four texels whose centres are at
        // r = 2·(√2/2)/64 = √2/64, so its peak is just below white, and bilinear sampling
        // at the centre averages the four.
        // 255·(1 − r) = 249.36 and 255·exp(−4.5 r²) = 254.44; the star's outline is at
        // least 0.45 away, 255·(1 − r/0.45) = 242.48.
        for (shape, peak) in [
            (BetaShape::Disk, 249),
            (BetaShape::Gaussian, 254),
            (BetaShape::Star, 242),
        ] {
            let tex = BetaTexture::new(shape, TEXTURE_SIZE);
            let centre = [
                tex.texel(31, 31),
                tex.texel(32, 31),
                tex.texel(31, 32),
                tex.texel(32, 32),
            ];
            let max = *tex.texels.iter().max().unwrap();
            assert!(
                centre.iter().all(|&c| c >= peak),
                "{}: {centre:?}",
                shape.name()
            );
            assert!(
                centre.contains(&max),
                "{}: the peak is at the centre",
                shape.name()
            );
            let mean = centre.iter().map(|&c| f64::from(c)).sum::<f64>() / 4.0 / 255.0;
            assert!(
                (tex.sample(0.5, 0.5) - mean).abs() < 1e-12,
                "{}",
                shape.name()
            );
        }
        for shape in SHAPES {
            for size in [TEXTURE_SIZE, 65] {
                let tex = BetaTexture::new(shape, size);
                for (x, y) in [(0, 0), (size - 1, 0), (0, size - 1), (size - 1, size - 1)] {
                    assert_eq!(tex.texel(x, y), 0, "{} corner ({x}, {y})", shape.name());
                }
                for (s, t) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
                    assert_eq!(tex.sample(s, t), 0.0, "{} corner ({s}, {t})", shape.name());
                }
            }
        }
    }

    #[test]
    fn texture_texels_follow_the_shape_formulas() {
        let n = f64::from(TEXTURE_SIZE);
        // Texel (32, 48): centre (32.5/64, 48.5/64), r = 2·hypot(0.5/64, 16.5/64) = 0.51586:
        // disk 255·(1 − r) = 123.46, gaussian 255·exp(−4.5·r²) = 77.00.
        let disk = BetaTexture::new(BetaShape::Disk, TEXTURE_SIZE);
        assert_eq!(disk.texel(32, 48), 123);
        let gauss = BetaTexture::new(BetaShape::Gaussian, TEXTURE_SIZE);
        assert_eq!(gauss.texel(32, 48), 77);
        // Just inside the rim the gaussian is 255·exp(−4.5) ≈ 3, then steps to 0.
        assert_eq!(gauss.texel(32, 63), 3);
        assert_eq!(gauss.texel(32, 0), 3);
        // Every shape is 0 outside the inscribed disk.
        for shape in SHAPES {
            let tex = BetaTexture::new(shape, TEXTURE_SIZE);
            for y in 0..TEXTURE_SIZE {
                for x in 0..TEXTURE_SIZE {
                    let (s, t) = ((f64::from(x) + 0.5) / n, (f64::from(y) + 0.5) / n);
                    if 2.0 * (s - 0.5).hypot(t - 0.5) >= 1.0 {
                        assert_eq!(tex.texel(x, y), 0, "{} ({x}, {y})", shape.name());
                    }
                }
            }
        }
        // The star reaches the rim at its tip (towards t = 0) and only 0.45 of it in the
        // valley opposite (towards t = 1): along the column beside the centre, texel row 2
        // (r = 0.92, outline 0.96) is inside the tip, row 44 (r = 0.39, outline 0.46) inside
        // the valley and row 48 (r = 0.52, outline 0.46) outside it.
        let star = BetaTexture::new(BetaShape::Star, TEXTURE_SIZE);
        assert_eq!((star.texel(32, 2), star.texel(31, 2)), (10, 10)); // 255·(1 − 0.922/0.961)
        assert_eq!(star.texel(32, 44), 39); // 255·(1 − 0.391/0.462)
        assert_eq!(star.texel(32, 48), 0);
    }

    #[test]
    fn texture_star_has_five_fold_symmetry() {
        let tex = BetaTexture::new(BetaShape::Star, TEXTURE_SIZE);
        let step = 2.0 * PI / 5.0;
        let mut worst = 0.0f64;
        let mut worst_half_step = 0.0f64;
        for y in 0..TEXTURE_SIZE {
            for x in 0..TEXTURE_SIZE {
                let texel = f64::from(tex.texel(x, y));
                for k in 1..5 {
                    // Each texel is its shape value rounded: rotated by a multiple of 72° the
                    // shape gives the same value within that rounding.
                    let (s, t) = rotated_centre(TEXTURE_SIZE, x, y, f64::from(k) * step);
                    worst = worst.max((texel - 255.0 * shape_beta(BetaShape::Star, s, t)).abs());
                }
                let (s, t) = rotated_centre(TEXTURE_SIZE, x, y, step / 2.0);
                worst_half_step =
                    worst_half_step.max((texel - 255.0 * shape_beta(BetaShape::Star, s, t)).abs());
            }
        }
        assert!(worst <= 0.5 + 1e-9, "{worst}");
        // The check can fail: a 36° turn puts tips on valleys.
        assert!(worst_half_step > 100.0, "{worst_half_step}");
        // On the texel grid itself: the bilinear sample at a texel centre turned by 72° is
        // close to the texel (the sample blends neighbours across the star's edges).
        let mut sum = 0.0;
        for y in 0..TEXTURE_SIZE {
            for x in 0..TEXTURE_SIZE {
                let (s, t) = rotated_centre(TEXTURE_SIZE, x, y, step);
                sum += (f64::from(tex.texel(x, y)) / 255.0 - tex.sample(s, t)).abs();
            }
        }
        let mean = sum / f64::from(TEXTURE_SIZE * TEXTURE_SIZE);
        assert!(mean < 0.01, "{mean}");
    }

    #[test]
    fn texture_bilinear_sample_at_a_texel_centre_is_the_texel() {
        let n = f64::from(TEXTURE_SIZE);
        for shape in SHAPES {
            let tex = BetaTexture::new(shape, TEXTURE_SIZE);
            for y in 0..TEXTURE_SIZE {
                for x in 0..TEXTURE_SIZE {
                    let got = tex.sample((f64::from(x) + 0.5) / n, (f64::from(y) + 0.5) / n);
                    assert_eq!(
                        got,
                        f64::from(tex.texel(x, y)) / 255.0,
                        "{} ({x}, {y})",
                        shape.name()
                    );
                }
            }
            // Half-way between two texels it is their mean.
            let got = tex.sample(33.0 / n, 40.5 / n);
            let want = (f64::from(tex.texel(32, 40)) + f64::from(tex.texel(33, 40))) / 2.0 / 255.0;
            assert!((got - want).abs() < 1e-15, "{}", shape.name());
        }
    }

    #[test]
    fn texture_sample_outside_the_unit_square_is_zero() {
        for shape in SHAPES {
            let tex = BetaTexture::new(shape, TEXTURE_SIZE);
            for (s, t) in [
                (-1e-9, 0.5),
                (1.0 + 1e-9, 0.5),
                (0.5, -0.25),
                (0.5, 2.0),
                (f64::NAN, 0.5),
                (0.5, f64::INFINITY),
            ] {
                assert_eq!(tex.sample(s, t), 0.0, "{} ({s}, {t})", shape.name());
            }
            // At the square's edge the sample is half the edge texels (the black border beyond):
            // the disk's edge-midpoint texels are 4, so 2/255 there.
            assert!(tex.sample(0.5, 0.0) < 3.0 / 255.0, "{}", shape.name());
        }
    }

    #[test]
    fn texture_to_image_is_the_texels() {
        let tex = BetaTexture::new(BetaShape::Star, TEXTURE_SIZE);
        let img = tex.to_image();
        assert_eq!(img.dimensions(), (TEXTURE_SIZE, TEXTURE_SIZE));
        assert_eq!(tex.shape(), BetaShape::Star);
        for (x, y, p) in img.enumerate_pixels() {
            assert_eq!(p.0[0], tex.texel(x, y));
        }
    }
}
