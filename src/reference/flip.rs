//! FLIP (Andersson et al., "FLIP: A Difference Evaluator for Alternating Images", HPG 2020):
//! the perceptual difference of a render from the reference, as rendering papers report
//! it beside PSNR. Computed by NVIDIA's reference implementation (the C++ LDR-FLIP of
//! NVlabs/flip, BSD-3, compiled through the `nv-flip` crate), not a port: the per-pixel
//! error map in [0, 1] and its mean.
//!
//! The viewing condition is the observer's pixels per degree of visual angle
//! ([`PixelsPerDegree`]); the reference's default is a 0.7 m wide 3840-pixel monitor seen
//! from 0.7 m, 67.02 pixels per degree. Both images are read as sRGB, RGB8.

use super::oracle::ReferenceImage;
use crate::rop::framebuffer::FrameBuffer;
use image::RgbImage;

/// Most pixels per degree accepted: the filters' radii grow with it (about 0.12 px per
/// pixel per degree for the widest), and a 4K monitor seen from 30 cm is about 110.
pub const MAX_PIXELS_PER_DEGREE: f64 = 1000.0;

/// The observer FLIP assumes: pixels per degree of visual angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelsPerDegree(f64);

impl Default for PixelsPerDegree {
    /// The reference implementation's default observer: a 0.7 m wide monitor of 3840
    /// pixels seen from 0.7 m (67.02 pixels per degree).
    fn default() -> Self {
        PixelsPerDegree::from_monitor(0.7, 3840.0, 0.7)
    }
}

impl PixelsPerDegree {
    /// A checked value: positive, finite and at most [`MAX_PIXELS_PER_DEGREE`].
    pub fn new(value: f64) -> Result<Self, String> {
        if value.is_finite() && value > 0.0 && value <= MAX_PIXELS_PER_DEGREE {
            Ok(PixelsPerDegree(value))
        } else {
            Err(format!(
                "pixels per degree must be positive, finite and at most {MAX_PIXELS_PER_DEGREE} \
                 (the reference's default is {:.2})",
                PixelsPerDegree::default().0
            ))
        }
    }

    /// The pixels per degree of a monitor `width_m` wide of `pixels` columns seen from
    /// `distance_m` (the reference implementation's formula).
    fn from_monitor(distance_m: f64, pixels: f64, width_m: f64) -> Self {
        PixelsPerDegree(distance_m * (pixels / width_m) * std::f64::consts::PI / 180.0)
    }

    /// The value.
    pub fn get(self) -> f64 {
        self.0
    }
}

/// A FLIP error map: one value in [0, 1] per pixel, row by row.
pub struct FlipMap {
    width: u32,
    height: u32,
    values: Vec<f32>,
    /// The mean over every pixel (the reference's pooled mean).
    pub mean: f64,
    /// The observer it was computed for.
    pub ppd: PixelsPerDegree,
}

/// FLIP of `test` against `reference` (RGB8 pixels, row by row, `width` x `height`).
///
/// # Panics
/// If either image is not `width` x `height` (a bug of the caller).
pub fn flip(
    reference: &[[u8; 3]],
    test: &[[u8; 3]],
    width: u32,
    height: u32,
    ppd: PixelsPerDegree,
) -> FlipMap {
    let n = width as usize * height as usize;
    assert!(
        reference.len() == n && test.len() == n,
        "images differ from {width}x{height}"
    );
    let image =
        |px: &[[u8; 3]]| nv_flip::FlipImageRgb8::with_data(width, height, px.as_flattened());
    let map = nv_flip::flip(image(reference), image(test), ppd.get() as f32);
    let mean = nv_flip::FlipPool::from_image(&map).mean() as f64;
    FlipMap {
        width,
        height,
        values: map.to_vec(),
        mean,
        ppd,
    }
}

/// FLIP of a rendered frame against the reference's centre-sample colours (the image PSNR
/// is taken of).
///
/// # Panics
/// If the two differ in size (a bug of the caller).
pub fn flip_frame(
    render: &FrameBuffer,
    reference: &ReferenceImage,
    ppd: PixelsPerDegree,
) -> FlipMap {
    assert_eq!(
        (render.width, render.height),
        (reference.width, reference.height),
        "render and reference differ in size"
    );
    flip(
        &reference.color,
        &render.color,
        render.width,
        render.height,
        ppd,
    )
}

impl FlipMap {
    /// The error of pixel (i, j).
    pub fn at(&self, i: u32, j: u32) -> f32 {
        self.values[j as usize * self.width as usize + i as usize]
    }

    /// The map as the reference shows it: its magma colour ramp, black for no difference
    /// to pale yellow for 1 (`flip.png`).
    pub fn to_image(&self) -> RgbImage {
        let map = nv_flip::FlipImageFloat::with_data(self.width, self.height, &self.values);
        let rgb = map.apply_color_lut(&nv_flip::magma_lut());
        RgbImage::from_raw(self.width, self.height, rgb.to_vec()).expect("the map's own size")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn disc(w: u32, h: u32, r: f64, colour: [u8; 3]) -> Vec<[u8; 3]> {
        (0..h)
            .flat_map(|j| (0..w).map(move |i| (i, j)))
            .map(|(i, j)| {
                let (x, y) = (
                    i as f64 + 0.5 - w as f64 / 2.0,
                    j as f64 + 0.5 - h as f64 / 2.0,
                );
                if x * x + y * y <= r * r {
                    colour
                } else {
                    [20, 20, 30]
                }
            })
            .collect()
    }

    #[test]
    fn flip_of_identical_images_is_zero() {
        let a = disc(64, 48, 15.0, [200, 120, 40]);
        let m = flip(&a, &a, 64, 48, PixelsPerDegree::default());
        assert_eq!(m.mean, 0.0);
        assert!(m.values.iter().all(|&v| v == 0.0));
    }

    /// The error is where the images differ, grows with the difference, and its mean is
    /// the mean of the map.
    #[test]
    fn flip_is_where_and_as_large_as_the_difference() {
        let (w, h) = (96, 64);
        let reference = disc(w, h, 20.0, [200, 120, 40]);
        let near = disc(w, h, 20.0, [190, 120, 40]);
        let far = disc(w, h, 20.0, [60, 200, 220]);
        let ppd = PixelsPerDegree::default();
        let (mn, mf) = (
            flip(&reference, &near, w, h, ppd),
            flip(&reference, &far, w, h, ppd),
        );
        assert!(
            0.0 < mn.mean && mn.mean < mf.mean,
            "{} {}",
            mn.mean,
            mf.mean
        );
        let mean = mf.values.iter().map(|&v| v as f64).sum::<f64>() / mf.values.len() as f64;
        assert!((mf.mean - mean).abs() < 1e-4, "{} against {mean}", mf.mean);
        // Inside the disc (changed) against a corner far from it (unchanged).
        assert!(mf.at(w / 2, h / 2) > 0.1);
        assert_eq!(mf.at(1, 1), 0.0);
        // The map's image: same size, the ramp's black where nothing differs.
        let img = mf.to_image();
        assert_eq!(img.dimensions(), (w, h));
        assert_eq!(img.get_pixel(1, 1).0, [0, 0, 4]);
    }

    /// A finer observer (more pixels per degree) sees a one-pixel pattern less.
    #[test]
    fn flip_falls_as_the_observer_moves_away() {
        let (w, h) = (64, 64);
        let flat = vec![[128u8, 128, 128]; (w * h) as usize];
        let checker: Vec<[u8; 3]> = (0..w * h)
            .map(|k| {
                if (k % w + k / w) % 2 == 0 {
                    [148, 148, 148]
                } else {
                    [108, 108, 108]
                }
            })
            .collect();
        let near = flip(&flat, &checker, w, h, PixelsPerDegree::new(10.0).unwrap());
        let far = flip(&flat, &checker, w, h, PixelsPerDegree::new(200.0).unwrap());
        assert!(near.mean > far.mean, "{} {}", near.mean, far.mean);
    }

    #[test]
    fn pixels_per_degree_default_and_bounds() {
        assert!((PixelsPerDegree::default().get() - 67.0206).abs() < 1e-4);
        for bad in [
            0.0,
            -1.0,
            f64::NAN,
            f64::INFINITY,
            MAX_PIXELS_PER_DEGREE * 1.01,
        ] {
            assert!(PixelsPerDegree::new(bad).is_err(), "{bad}");
        }
        assert!(PixelsPerDegree::new(MAX_PIXELS_PER_DEGREE).is_ok());
    }
}
