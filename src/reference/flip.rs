//! FLIP (Andersson et al., "FLIP: A Difference Evaluator for Alternating Images", HPG 2020):
//! the perceptual difference of a render from the reference, as rendering papers report
//! it beside PSNR. Computed by NVIDIA's reference implementation (the C++ LDR-FLIP of
//! NVlabs/flip, BSD-3, compiled through the `nv-flip` crate), not a port: the per-pixel
//! error map in [0, 1] and its mean.
//!
//! The reference implementation runs on one thread. The map is computed here in bands of
//! rows on all of the pool's threads, each band with the rows FLIP's filters reach above
//! and below it ([`halo_rows`]), and the bands' own rows put together: the same map, bit
//! for bit (tested), since every filter clamps at the image's border and reaches no
//! further than its radius.
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

/// Bands a thread of the pool: FLIP runs beside the visibility counts (`rayon::join`), and
/// a thread that ends its side first takes bands from FLIP's queue. With one band a
/// thread, the last band ran alone for a quarter of a second on a 1024x1024 frame
/// (RESULTS, "The measured run's idle cores").
const BANDS_A_THREAD: u32 = 4;

/// FLIP of `test` against `reference` (RGB8 pixels, row by row, `width` x `height`),
/// computed in bands of rows on the current thread pool ([`flip_in_bands`]): the map, bit
/// for bit, that the reference implementation computes of the whole image at once.
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
    let bands = BANDS_A_THREAD * rayon::current_num_threads() as u32;
    flip_in_bands(reference, test, width, height, ppd, bands)
}

/// The rows either side of a band that the map inside it reads (the halo): FLIP's widest
/// filter radius at `ppd` (the reference implementation's formulas, its spatial filter's
/// from the largest Gaussian scale, 0.04, and its feature filter's from 3 standard
/// deviations of 0.5 x 0.082 degrees), plus one row against rounding.
pub fn halo_rows(ppd: PixelsPerDegree) -> u32 {
    let ppd = f64::from(ppd.get() as f32);
    let pi_sq = std::f64::consts::PI * std::f64::consts::PI;
    let spatial = (3.0 * (0.04 / (2.0 * pi_sq)).sqrt() * ppd).ceil();
    let feature = (3.0 * 0.5 * 0.082 * ppd).ceil();
    spatial.max(feature) as u32 + 1
}

/// [`flip`] in at most `bands` bands of consecutive rows, each computed by the reference
/// implementation in parallel with its [`halo_rows`] above and below (FLIP's filters clamp
/// at the image's border, and reach no further than their radius), and the bands' own rows
/// put together. Fewer bands where a band would be under four halos tall (its halos more
/// than half its own rows): one, the whole image, for a small one.
///
/// # Panics
/// If either image is not `width` x `height` (a bug of the caller).
pub fn flip_in_bands(
    reference: &[[u8; 3]],
    test: &[[u8; 3]],
    width: u32,
    height: u32,
    ppd: PixelsPerDegree,
    bands: u32,
) -> FlipMap {
    banded(
        reference,
        test,
        (width, height),
        ppd,
        (bands, halo_rows(ppd)),
    )
}

/// [`flip_in_bands`] with halos of `halo` rows.
fn banded(
    reference: &[[u8; 3]],
    test: &[[u8; 3]],
    (width, height): (u32, u32),
    ppd: PixelsPerDegree,
    (bands, halo): (u32, u32),
) -> FlipMap {
    use rayon::prelude::*;
    let n = width as usize * height as usize;
    assert!(
        reference.len() == n && test.len() == n,
        "images differ from {width}x{height}"
    );
    let bands = bands.min(height / (4 * halo).max(1)).max(1);
    let rows = height.div_ceil(bands);
    let w = width as usize;
    let parts: Vec<Vec<f32>> = (0..height.div_ceil(rows))
        .into_par_iter()
        .map(|b| {
            let (first, end) = (b * rows, ((b + 1) * rows).min(height));
            let (top, bottom) = (first.saturating_sub(halo), (end + halo).min(height));
            let span = top as usize * w..bottom as usize * w;
            let image = |px: &[[u8; 3]]| {
                nv_flip::FlipImageRgb8::with_data(width, bottom - top, px.as_flattened())
            };
            let map = nv_flip::flip(
                image(&reference[span.clone()]),
                image(&test[span]),
                ppd.get() as f32,
            );
            let own = (first - top) as usize * w..(end - top) as usize * w;
            map.to_vec()[own].to_vec()
        })
        .collect();
    let values = parts.concat();
    let map = nv_flip::FlipImageFloat::with_data(width, height, &values);
    let mean = nv_flip::FlipPool::from_image(&map).mean() as f64;
    FlipMap {
        width,
        height,
        values,
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

    /// The map computed in bands with their halos is the whole image's, bit for bit, and
    /// so is its mean: at observers whose filters reach 2 to 130 rows, on images whose
    /// height splits into bands unevenly or is too small for more than one, with
    /// differences everywhere (noise) and right at the bands' edges.
    #[test]
    fn flip_in_bands_is_the_whole_images_flip_bit_for_bit() {
        let mut seed = 7u64;
        let mut noise = |n: usize| -> Vec<[u8; 3]> {
            (0..n)
                .map(|_| {
                    seed = seed
                        .wrapping_mul(6364136223846793005)
                        .wrapping_add(1442695040888963407);
                    let b = (seed >> 40).to_le_bytes();
                    [b[0], b[1], b[2]]
                })
                .collect()
        };
        for (w, h, ppd) in [
            (37, 203, 10.0),
            (64, 301, 67.02),
            (23, 97, 20.0),
            (16, 40, 1000.0),
        ] {
            let ppd = PixelsPerDegree::new(ppd).unwrap();
            let reference = noise((w * h) as usize);
            let mut test = disc(w, h, 9.0, [200, 120, 40]);
            for (k, t) in test.iter_mut().enumerate() {
                if k % 7 == 0 {
                    *t = reference[k];
                }
            }
            let whole = nv_flip::flip(
                nv_flip::FlipImageRgb8::with_data(w, h, reference.as_flattened()),
                nv_flip::FlipImageRgb8::with_data(w, h, test.as_flattened()),
                ppd.get() as f32,
            );
            let whole_mean = nv_flip::FlipPool::from_image(&whole).mean() as f64;
            let whole = whole.to_vec();
            for bands in [1, 2, 3, 5, 8] {
                let banded = flip_in_bands(&reference, &test, w, h, ppd, bands);
                let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert!(
                    bits(&banded.values) == bits(&whole),
                    "{w}x{h} at {} ppd in {bands} bands",
                    ppd.get()
                );
                assert_eq!(banded.mean.to_bits(), whole_mean.to_bits());
            }
        }
        // At 67.02 pixels per degree the spatial filter reaches 10 rows: the halo is 11, and
        // one of 9 changes the map.
        let (w, h) = (64, 301);
        let ppd = PixelsPerDegree::new(67.02).unwrap();
        assert_eq!(halo_rows(ppd), 11);
        let (reference, test) = (noise((w * h) as usize), noise((w * h) as usize));
        let right = banded(&reference, &test, (w, h), ppd, (3, 10));
        let short = banded(&reference, &test, (w, h), ppd, (3, 9));
        let whole = banded(&reference, &test, (w, h), ppd, (1, 0));
        assert!(right.values == whole.values && short.values != whole.values);
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
