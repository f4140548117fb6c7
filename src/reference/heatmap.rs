//! The error image (`error.png`): where and how much a render differs from the reference.
//!
//! Each pixel shows the largest channel difference (0-255 levels) through an
//! "inferno"-like ramp on a logarithmic scale: black for no difference, then one ramp stop
//! per doubling (1, 3, 7, 15, 31, 63, 127 and 255 levels) through purple, red and orange to
//! pale yellow, so a 1-level error is a visible purple, not a black a linear scale would
//! give it. Coverage disagreements are flat colours outside the ramp, so silhouette errors
//! stand out: cyan where the render covers a pixel the reference does not (false positive,
//! FP), bright green where it misses one (false negative, FN). A legend strip of
//! [`legend_height`] pixels below the image shows the ramp with its ticks in levels and the
//! two swatches, in a built-in 5 x 7 pixel font.

use super::oracle::ReferenceImage;
use crate::rop::framebuffer::{FrameBuffer, NO_PRIMITIVE};
use image::{Rgb, RgbImage};

/// Colour of a pixel the render covers and the reference does not.
pub const FALSE_POSITIVE: [u8; 3] = [0, 255, 255];
/// Colour of a pixel the reference covers and the render does not.
pub const FALSE_NEGATIVE: [u8; 3] = [0, 255, 0];

const LEGEND_HEIGHT: u32 = 28;
const LEGEND_BACKGROUND: [u8; 3] = [24, 24, 24];
const LEGEND_TEXT: [u8; 3] = [230, 230, 230];
const LEGEND_FRAME: [u8; 3] = [128, 128, 128];

/// Ramp stops at errors of 0, 1, 3, 7, ..., 255 levels (2^k - 1 for stop k), after
/// matplotlib's "inferno" with the first stop pure black and the second brightened to
/// inferno's 0.2, so that one level reads against black.
const RAMP: [[u8; 3]; 9] = [
    [0, 0, 0],
    [87, 16, 110],
    [101, 21, 110],
    [159, 42, 99],
    [212, 72, 66],
    [245, 125, 21],
    [250, 193, 39],
    [245, 235, 110],
    [252, 255, 164],
];

/// Height of the legend strip appended below the image \[pixels\].
pub fn legend_height() -> u32 {
    LEGEND_HEIGHT
}

/// The error heat map of `render` against `reference`'s centre samples, with the legend
/// below: an image of `width` x (`height` + [`legend_height`]) pixels.
///
/// # Panics
/// If the two images differ in size (a bug of the caller).
pub fn error_heatmap(render: &FrameBuffer, reference: &ReferenceImage) -> RgbImage {
    assert_eq!(
        (render.width, render.height),
        (reference.width, reference.height),
        "render and reference differ in size"
    );
    let (w, h) = (render.width, render.height);
    let mut img = RgbImage::from_pixel(w, h + LEGEND_HEIGHT, Rgb(LEGEND_BACKGROUND));
    for j in 0..h {
        for i in 0..w {
            let k = (j * w + i) as usize;
            let ours = render.primitive[k] != NO_PRIMITIVE;
            let theirs = reference.hits[k].is_some();
            let color = match (ours, theirs) {
                (true, false) => FALSE_POSITIVE,
                (false, true) => FALSE_NEGATIVE,
                _ => {
                    let (a, b) = (render.color[k], reference.color[k]);
                    let diff = (0..3).map(|c| a[c].abs_diff(b[c])).max().unwrap_or(0);
                    ramp(diff)
                }
            };
            img.put_pixel(i, j, Rgb(color));
        }
    }
    draw_legend(&mut img, h);
    img
}

/// Where an error of `levels` (0-255, fractional on the legend) sits on the ramp, 0 to 1:
/// log2(1 + levels) / 8.
fn scale(levels: f64) -> f64 {
    (1.0 + levels).log2() / (RAMP.len() - 1) as f64
}

/// The ramp colour of a difference 0-255 levels, on the logarithmic scale, interpolated
/// linearly between stops.
pub fn ramp(diff: u8) -> [u8; 3] {
    ramp_at(scale(diff as f64))
}

/// The ramp colour at position `t` in [0, 1].
fn ramp_at(t: f64) -> [u8; 3] {
    let x = t.clamp(0.0, 1.0) * (RAMP.len() - 1) as f64;
    let k = (x.floor() as usize).min(RAMP.len() - 2);
    let f = x - k as f64;
    let (a, b) = (RAMP[k], RAMP[k + 1]);
    [0, 1, 2].map(|c| (a[c] as f64 + f * (b[c] as f64 - a[c] as f64)).round() as u8)
}

/// Draws the legend into the strip starting at row `top`:
///
/// ```text
///   ┌──────────────── ramp ────────────────┐  ■ FP
///   0        64       128       192      255  ■ FN
/// ```
///
/// Tick labels that would overlap a neighbour are left out, so narrow images keep "0" and
/// "255" at least.
fn draw_legend(img: &mut RgbImage, top: u32) {
    const MARGIN: i64 = 3;
    const BOX: i64 = 7;
    let w = img.width() as i64;
    let top = top as i64;
    // Swatch column on the right: a 7 x 7 box, a gap and a two-letter label.
    let swatch_width = BOX + 2 + text_width("FP");
    let swatch_x = w - MARGIN - swatch_width;
    let (ramp_x0, ramp_x1) = (MARGIN + 1, swatch_x - 2 * MARGIN);
    let (bar_y0, bar_y1) = (top + 3, top + 11);
    let label_y = top + 15;

    for (y, label, color) in [
        (bar_y0, "FP", FALSE_POSITIVE),
        (label_y, "FN", FALSE_NEGATIVE),
    ] {
        fill(img, swatch_x, y, swatch_x + BOX, y + BOX, color);
        draw_text(img, swatch_x + BOX + 2, y, label);
    }

    if ramp_x1 - ramp_x0 < 4 {
        return;
    }
    let span = (ramp_x1 - ramp_x0 - 1) as f64;
    for x in ramp_x0..ramp_x1 {
        fill(
            img,
            x,
            bar_y0,
            x + 1,
            bar_y1,
            ramp_at((x - ramp_x0) as f64 / span),
        );
    }
    fill(
        img,
        ramp_x0 - 1,
        bar_y0 - 1,
        ramp_x1 + 1,
        bar_y0,
        LEGEND_FRAME,
    );
    fill(
        img,
        ramp_x0 - 1,
        bar_y1,
        ramp_x1 + 1,
        bar_y1 + 1,
        LEGEND_FRAME,
    );
    fill(img, ramp_x0 - 1, bar_y0, ramp_x0, bar_y1, LEGEND_FRAME);
    fill(img, ramp_x1, bar_y0, ramp_x1 + 1, bar_y1, LEGEND_FRAME);

    // Ends first so they always appear, then 1 (the smallest error), the middle and the
    // rest, each where it fits: the ticks are in levels, on the logarithmic scale.
    let mut drawn: Vec<(i64, i64)> = Vec::new();
    for value in [0u32, 255, 1, 15, 3, 63, 7, 31, 127] {
        let tick = ramp_x0 + (scale(value as f64) * span).round() as i64;
        let label = value.to_string();
        let width = text_width(&label);
        let x = match value {
            0 => ramp_x0,
            255 => ramp_x1 - width,
            _ => tick - width / 2,
        };
        if drawn.iter().any(|&(a, b)| x < b + 3 && x + width + 3 > a) {
            continue;
        }
        drawn.push((x, x + width));
        fill(img, tick, bar_y1 + 1, tick + 1, bar_y1 + 3, LEGEND_TEXT);
        draw_text(img, x, label_y, &label);
    }
}

/// Fills the rectangle [x0, x1) x [y0, y1), clipped to the image.
fn fill(img: &mut RgbImage, x0: i64, y0: i64, x1: i64, y1: i64, color: [u8; 3]) {
    let (w, h) = (img.width() as i64, img.height() as i64);
    for y in y0.max(0)..y1.min(h) {
        for x in x0.max(0)..x1.min(w) {
            img.put_pixel(x as u32, y as u32, Rgb(color));
        }
    }
}

const GLYPH_WIDTH: i64 = 5;
const GLYPH_ADVANCE: i64 = 6;

/// Width of a string in the legend font \[pixels\].
fn text_width(s: &str) -> i64 {
    (s.chars().count() as i64 * GLYPH_ADVANCE - 1).max(0)
}

/// Draws `s` with its top-left corner at (x, y), clipped to the image.
fn draw_text(img: &mut RgbImage, x: i64, y: i64, s: &str) {
    for (n, ch) in s.chars().enumerate() {
        let Some(rows) = glyph(ch) else { continue };
        let gx = x + n as i64 * GLYPH_ADVANCE;
        for (dy, bits) in rows.iter().enumerate() {
            for dx in 0..GLYPH_WIDTH {
                if bits >> (GLYPH_WIDTH - 1 - dx) & 1 == 1 {
                    fill(
                        img,
                        gx + dx,
                        y + dy as i64,
                        gx + dx + 1,
                        y + dy as i64 + 1,
                        LEGEND_TEXT,
                    );
                }
            }
        }
    }
}

/// The 5 x 7 glyph of a character, one row per byte with the leftmost pixel in bit 4.
fn glyph(ch: char) -> Option<[u8; 7]> {
    Some(match ch {
        '0' => [
            0b01110, 0b10001, 0b10011, 0b10101, 0b11001, 0b10001, 0b01110,
        ],
        '1' => [
            0b00100, 0b01100, 0b00100, 0b00100, 0b00100, 0b00100, 0b01110,
        ],
        '2' => [
            0b01110, 0b10001, 0b00001, 0b00010, 0b00100, 0b01000, 0b11111,
        ],
        '3' => [
            0b11111, 0b00010, 0b00100, 0b00010, 0b00001, 0b10001, 0b01110,
        ],
        '4' => [
            0b00010, 0b00110, 0b01010, 0b10010, 0b11111, 0b00010, 0b00010,
        ],
        '5' => [
            0b11111, 0b10000, 0b11110, 0b00001, 0b00001, 0b10001, 0b01110,
        ],
        '6' => [
            0b00110, 0b01000, 0b10000, 0b11110, 0b10001, 0b10001, 0b01110,
        ],
        '7' => [
            0b11111, 0b00001, 0b00010, 0b00100, 0b01000, 0b01000, 0b01000,
        ],
        '8' => [
            0b01110, 0b10001, 0b10001, 0b01110, 0b10001, 0b10001, 0b01110,
        ],
        '9' => [
            0b01110, 0b10001, 0b10001, 0b01111, 0b00001, 0b00010, 0b01100,
        ],
        'F' => [
            0b11111, 0b10000, 0b10000, 0b11110, 0b10000, 0b10000, 0b10000,
        ],
        'N' => [
            0b10001, 0b11001, 0b10101, 0b10011, 0b10001, 0b10001, 0b10001,
        ],
        'P' => [
            0b11110, 0b10001, 0b10001, 0b11110, 0b10000, 0b10000, 0b10000,
        ],
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::oracle::ReferenceHit;
    use glam::DVec3;

    fn pair(w: u32, h: u32) -> (FrameBuffer, ReferenceImage) {
        let n = (w * h) as usize;
        let fb = FrameBuffer::new(w, h, [0; 3], true);
        let reference = ReferenceImage {
            width: w,
            height: h,
            supersample: 1,
            hits: vec![None; n],
            hits_offset_px: [0.0; 2],
            bins: None,
            color: vec![[0; 3]; n],
            color_supersampled: None,
            coverage: None,
        };
        (fb, reference)
    }

    fn hit() -> Option<ReferenceHit> {
        Some(ReferenceHit {
            depth: 0.5,
            normal: DVec3::Z,
            lembo: 0,
            u: 0.0,
            v: 0.0,
        })
    }

    #[test]
    fn error_heatmap_has_the_legend_below_and_flat_colours_for_coverage_errors() {
        let (mut fb, mut reference) = pair(64, 40);
        // (3, 4): render only, a false positive; (5, 6): reference only; (7, 8): both, off
        // by 255 in one channel.
        let k = fb.index(3, 4);
        fb.write(k, 0.5, 0, [9; 3]);
        reference.hits[fb.index(5, 6)] = hit();
        let k = fb.index(7, 8);
        fb.write(k, 0.5, 0, [255, 0, 0]);
        reference.hits[k] = hit();
        let img = error_heatmap(&fb, &reference);
        assert_eq!(img.dimensions(), (64, 40 + legend_height()));
        assert_eq!(img.get_pixel(3, 4).0, FALSE_POSITIVE);
        assert_eq!(img.get_pixel(5, 6).0, FALSE_NEGATIVE);
        assert_eq!(img.get_pixel(7, 8).0, RAMP[8]);
        assert_eq!(img.get_pixel(0, 0).0, [0, 0, 0]);
    }

    #[test]
    fn ramp_runs_from_black_to_pale_yellow_through_its_stops() {
        assert_eq!(ramp(0), [0, 0, 0]);
        assert_eq!(ramp(255), RAMP[8]);
        // One stop per doubling: 2^k - 1 levels land on stop k.
        for k in 0..9u32 {
            assert_eq!(ramp(((1u32 << k) - 1) as u8), RAMP[k as usize], "stop {k}");
        }
        // A 1-level error is far from black: a person sees it.
        let luma = |c: [u8; 3]| 0.2126 * c[0] as f64 + 0.7152 * c[1] as f64 + 0.0722 * c[2] as f64;
        assert!(luma(ramp(1)) > 30.0, "{}", luma(ramp(1)));
        // Brightness never decreases along the ramp.
        assert!((0..255u8).all(|d| luma(ramp(d + 1)) >= luma(ramp(d)) - 1.0));
    }

    #[test]
    fn legend_keeps_the_end_labels_and_both_swatches_from_64_pixels_wide() {
        for w in [64, 200, 512] {
            let (fb, reference) = pair(w, 8);
            let img = error_heatmap(&fb, &reference);
            let legend = |x: u32, y: u32| img.get_pixel(x, 8 + y).0;
            let count = |c: [u8; 3]| {
                (0..w)
                    .flat_map(|x| (0..LEGEND_HEIGHT).map(move |y| (x, y)))
                    .filter(|&(x, y)| legend(x, y) == c)
                    .count()
            };
            assert_eq!(count(FALSE_POSITIVE), 49, "width {w}");
            assert_eq!(count(FALSE_NEGATIVE), 49, "width {w}");
            // The ramp's ends are on the bar.
            assert!((0..w).any(|x| legend(x, 6) == RAMP[8]), "width {w}");
            // Text pixels: "0" and "255" at least, five labels when wide.
            let text = count(LEGEND_TEXT);
            let glyph_pixels = |s: &str| {
                s.chars()
                    .map(|c| {
                        glyph(c)
                            .unwrap()
                            .iter()
                            .map(|r| r.count_ones() as usize)
                            .sum::<usize>()
                    })
                    .sum::<usize>()
            };
            let at_least = glyph_pixels("0255FPFN");
            assert!(text >= at_least, "width {w}: {text} < {at_least}");
            // The doublings when wide: 0 1 3 7 15 31 63 255, and 127 at 512.
            if w >= 200 {
                let labels = ["0", "1", "3", "7", "15", "31", "63", "255", "FP", "FN"].concat();
                assert!(text >= glyph_pixels(&labels), "width {w}");
            }
            if w >= 512 {
                let labels = [
                    "0", "1", "3", "7", "15", "31", "63", "127", "255", "FP", "FN",
                ];
                assert!(text >= glyph_pixels(&labels.concat()), "width {w}");
            }
        }
        // Tiny images still get a legend without panicking.
        let (fb, reference) = pair(3, 2);
        assert_eq!(
            error_heatmap(&fb, &reference).dimensions(),
            (3, 2 + LEGEND_HEIGHT)
        );
    }
}
