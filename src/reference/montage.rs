//! The comparison image (`montage.png`): several images side by side, each under its label.
//!
//! `lembo-sim compare` lays out the lembo render, the triangle render, the reference and the
//! two error heat maps this way, so a person sees at a glance what differs and what each
//! image is. Labels are drawn with the public-domain 8 x 8 bitmap font of the `font8x8`
//! crate, each glyph pixel a `scale` x `scale` block, so no TTF font or plotting stack is
//! needed.
//!
//! ```text
//!   ┌───────────────────────────────────────────┐ ─┬─ GAP
//!   │ label 0      label 1          label 2     │  │ label band: as many lines of
//!   │              second line                  │  │ LINE_ADVANCE x LABEL_SCALE pixels
//!   │ ┌────────┐   ┌────────────┐   ┌───────┐   │ ─┴─ as the label with most lines
//!   │ │panel 0 │   │  panel 1   │   │panel 2│   │
//!   │ └────────┘   │            │   └───────┘   │
//!   │              └────────────┘               │ ─── GAP
//!   └───────────────────────────────────────────┘
//!    GAP        GAP            GAP           GAP
//! ```

use font8x8::legacy::BASIC_LEGACY;
use image::{Rgb, RgbImage};

/// Pixels per glyph pixel in the labels.
pub const LABEL_SCALE: u32 = 2;
/// Space between panels and around the edge of the montage \[pixels\].
pub const GAP: u32 = 8;

/// Side of a glyph cell, and so the horizontal advance [glyph pixels].
const GLYPH_SIZE: u32 = 8;
/// Distance from one text line's top to the next: the glyph and two rows of leading
/// [glyph pixels].
const LINE_ADVANCE: u32 = 10;
const BACKGROUND: Rgb<u8> = Rgb([24, 24, 24]);
const TEXT: Rgb<u8> = Rgb([255, 255, 255]);

/// One image of a montage with its label.
pub struct Panel<'a> {
    /// Text above the image; `'\n'` starts a new line, and an empty label takes no line.
    pub label: &'a str,
    /// The image.
    pub image: &'a RgbImage,
}

/// The panels side by side, left to right, each under its label (white 8x8 glyphs scaled by
/// `LABEL_SCALE`, lines split at `'\n'`), on a dark background with [`GAP`] pixels between
/// panels and around the edge.
///
/// Panels may differ in size; they are aligned at the top. The montage is
/// `GAP + Σ (width + GAP)` wide and `GAP + band + tallest panel + GAP` tall, where the label
/// band holds as many lines as the label with most lines (`LINE_ADVANCE` x `LABEL_SCALE`
/// pixels each). Characters outside printable ASCII are drawn as `'?'`. A label wider than
/// its panel is clipped at the panel's right edge, never drawn over a neighbour. No panels
/// give a blank `GAP` x `2 GAP` image.
pub fn montage(panels: &[Panel]) -> RgbImage {
    let lines = panels
        .iter()
        .map(|p| line_count(p.label))
        .max()
        .unwrap_or(0);
    let top = GAP + lines * LINE_ADVANCE * LABEL_SCALE;
    let width = GAP + panels.iter().map(|p| p.image.width() + GAP).sum::<u32>();
    let tallest = panels.iter().map(|p| p.image.height()).max().unwrap_or(0);
    let mut out = RgbImage::from_pixel(width, top + tallest + GAP, BACKGROUND);
    let mut x = GAP;
    for panel in panels {
        let right = x + panel.image.width();
        draw_text(&mut out, x, GAP, LABEL_SCALE, TEXT, panel.label, right);
        image::imageops::replace(&mut out, panel.image, x.into(), top.into());
        x = right + GAP;
    }
    out
}

/// Draws `text` with its top-left corner at (x, y), `scale` pixels per glyph pixel, clipped to
/// the image and to x < `clip_right`.
///
/// Glyphs advance 8 x `scale` pixels; `'\n'` starts a new line `LINE_ADVANCE` x `scale`
/// pixels lower at x. Characters outside printable ASCII are drawn as `'?'`. Only set glyph
/// pixels are written; the rest of the cell keeps what is under it.
pub fn draw_text(
    img: &mut RgbImage,
    x: u32,
    y: u32,
    scale: u32,
    color: Rgb<u8>,
    text: &str,
    clip_right: u32,
) {
    // u64 so that no position overflows, however long the text or large the scale.
    let (x, y, scale) = (u64::from(x), u64::from(y), u64::from(scale));
    let right = u64::from(clip_right.min(img.width()));
    let bottom = u64::from(img.height());
    let advance = u64::from(GLYPH_SIZE) * scale;
    for (row, line) in text.split('\n').enumerate() {
        let line_top = y + row as u64 * u64::from(LINE_ADVANCE) * scale;
        if line_top >= bottom {
            break;
        }
        for (col, ch) in line.chars().enumerate() {
            let left = x + col as u64 * advance;
            if left >= right {
                break;
            }
            for (gy, bits) in (0u64..).zip(glyph(ch)) {
                for gx in (0..u64::from(GLYPH_SIZE)).filter(|gx| bits >> gx & 1 == 1) {
                    let (px, py) = (left + gx * scale, line_top + gy * scale);
                    for py in py..(py + scale).min(bottom) {
                        for px in px..(px + scale).min(right) {
                            img.put_pixel(px as u32, py as u32, color);
                        }
                    }
                }
            }
        }
    }
}

/// Number of text lines in a label; an empty label has none.
fn line_count(text: &str) -> u32 {
    if text.is_empty() {
        0
    } else {
        text.split('\n').count() as u32
    }
}

/// The 8 x 8 glyph of `ch`, one byte per row from the top with the leftmost pixel in bit 0;
/// anything outside printable ASCII gets the glyph of `'?'`.
fn glyph(ch: char) -> [u8; 8] {
    let ch = if ch == ' ' || ch.is_ascii_graphic() {
        ch
    } else {
        '?'
    };
    BASIC_LEGACY[ch as usize]
}

#[cfg(test)]
mod tests {
    use super::*;

    const LINE: u32 = LINE_ADVANCE * LABEL_SCALE;
    /// A panel colour that is neither the text nor the background.
    const PANEL: [u8; 3] = [10, 120, 200];

    /// A w x h image whose pixels all differ from their neighbours, so a shifted or
    /// transposed copy cannot pass for the original.
    fn pattern(w: u32, h: u32, seed: u8) -> RgbImage {
        RgbImage::from_fn(w, h, |x, y| {
            Rgb([x as u8, y as u8, seed.wrapping_add((x * 7 + y * 13) as u8)])
        })
    }

    /// Left edge of each panel in the montage, from the documented layout.
    fn offsets(images: &[RgbImage]) -> Vec<u32> {
        let mut x = GAP;
        images
            .iter()
            .map(|img| {
                let left = x;
                x += img.width() + GAP;
                left
            })
            .collect()
    }

    /// Number of pixels `text` sets when nothing clips it.
    fn ink(text: &str, scale: u32) -> usize {
        text.chars()
            .filter(|&c| c != '\n')
            .map(|c| glyph(c).iter().map(|r| r.count_ones()).sum::<u32>() * scale * scale)
            .sum::<u32>() as usize
    }

    #[test]
    fn montage_copies_every_panel_unchanged_at_its_offset() {
        let images = [pattern(30, 20, 1), pattern(50, 60, 2), pattern(7, 45, 3)];
        let labels = ["one", "two\nlines", "a label far wider than its panel"];
        let panels: Vec<Panel> = labels
            .iter()
            .zip(&images)
            .map(|(label, image)| Panel { label, image })
            .collect();
        let out = montage(&panels);
        let top = GAP + 2 * LINE;
        for (img, left) in images.iter().zip(offsets(&images)) {
            for (x, y, p) in img.enumerate_pixels() {
                assert_eq!(
                    out.get_pixel(left + x, top + y),
                    p,
                    "panel at {left}: ({x}, {y})"
                );
            }
        }
    }

    #[test]
    fn labels_draw_only_in_the_band_above_their_own_panel() {
        let images = [
            RgbImage::from_pixel(24, 30, Rgb(PANEL)),
            RgbImage::from_pixel(80, 20, Rgb(PANEL)),
            RgbImage::from_pixel(40, 10, Rgb(PANEL)),
            RgbImage::from_pixel(40, 25, Rgb(PANEL)),
        ];
        // The first label is clipped by its narrow panel; the third is empty.
        let labels = ["clipped by the panel", "two\nlines", "", "x"];
        let panels: Vec<Panel> = labels
            .iter()
            .zip(&images)
            .map(|(label, image)| Panel { label, image })
            .collect();
        let out = montage(&panels);
        let band = GAP..GAP + 2 * LINE;
        let lefts = offsets(&images);
        let mut per_panel = [0usize; 4];
        for (x, y, p) in out.enumerate_pixels() {
            if *p != TEXT {
                continue;
            }
            assert!(
                band.contains(&y),
                "text pixel at ({x}, {y}) outside the label band"
            );
            let owner = (0..images.len())
                .find(|&i| (lefts[i]..lefts[i] + images[i].width()).contains(&x))
                .unwrap_or_else(|| panic!("text pixel at ({x}, {y}) above no panel"));
            per_panel[owner] += 1;
        }
        assert!(per_panel[0] > 0 && per_panel[0] < ink(labels[0], LABEL_SCALE));
        for i in 1..4 {
            assert_eq!(per_panel[i], ink(labels[i], LABEL_SCALE), "label {i}");
        }
    }

    #[test]
    fn montage_size_fits_the_tallest_panel_and_the_label_with_most_lines() {
        let (a, b, c) = (pattern(30, 20, 0), pattern(50, 60, 0), pattern(10, 5, 0));
        let panels = [
            Panel {
                label: "a",
                image: &a,
            },
            Panel {
                label: "b\nc\nd",
                image: &b,
            },
            Panel {
                label: "",
                image: &c,
            },
        ];
        // 4 gaps + 90 wide; 2 gaps + 3 lines of 20 + 60 tall.
        assert_eq!(montage(&panels).dimensions(), (122, 136));
        assert_eq!(GAP * 4 + 90, 122);
        assert_eq!(GAP * 2 + 3 * LINE + 60, 136);

        // Empty labels take no band at all.
        let unlabelled = [
            Panel {
                label: "",
                image: &a,
            },
            Panel {
                label: "",
                image: &c,
            },
        ];
        let out = montage(&unlabelled);
        assert_eq!(out.dimensions(), (GAP * 3 + 40, GAP * 2 + 20));
        assert_eq!(out.get_pixel(GAP, GAP), a.get_pixel(0, 0));

        let empty = montage(&[]);
        assert_eq!(empty.dimensions(), (GAP, 2 * GAP));
        assert!(empty.pixels().all(|p| *p == BACKGROUND));
    }

    #[test]
    fn glyph_renders_the_font_table_bits_and_non_ascii_draws_as_question_mark() {
        let black = Rgb([0, 0, 0]);
        for ch in ['L', 'I', 'g'] {
            let mut img = RgbImage::from_pixel(10, 10, black);
            draw_text(&mut img, 1, 1, 1, TEXT, &ch.to_string(), 10);
            let rows = BASIC_LEGACY[ch as usize];
            for (x, y, p) in img.enumerate_pixels() {
                let set = (1..9).contains(&x)
                    && (1..9).contains(&y)
                    && rows[(y - 1) as usize] >> (x - 1) & 1 == 1;
                assert_eq!(*p == TEXT, set, "'{ch}' at ({x}, {y})");
            }
        }
        // 'L' has its stem on the left: the font's bit 0 is the leftmost pixel.
        assert_eq!(BASIC_LEGACY['L' as usize][6], 0x7F);

        // At scale 3 each glyph pixel is a 3 x 3 block.
        let mut big = RgbImage::from_pixel(24, 24, black);
        draw_text(&mut big, 0, 0, 3, TEXT, "I", 24);
        let rows = BASIC_LEGACY['I' as usize];
        for (x, y, p) in big.enumerate_pixels() {
            let set = rows[(y / 3) as usize] >> (x / 3) & 1 == 1;
            assert_eq!(*p == TEXT, set, "'I' x3 at ({x}, {y})");
        }

        let drawn = |text: &str| {
            let mut img = RgbImage::from_pixel(40, 10, black);
            draw_text(&mut img, 0, 0, 1, TEXT, text, 40);
            img
        };
        assert_eq!(drawn("aéb"), drawn("a?b"));
        assert_eq!(drawn("a\tb\r"), drawn("a?b?"));
        assert_ne!(drawn("a?b"), drawn("a b"));
    }

    #[test]
    fn long_text_is_clipped_at_clip_right() {
        let text = "WWWWWWWWWWWWWWWWWWWW";
        let mut clipped = RgbImage::from_pixel(200, 20, BACKGROUND);
        draw_text(&mut clipped, 3, 2, 2, TEXT, text, 41);
        let mut free = RgbImage::from_pixel(200, 20, BACKGROUND);
        draw_text(&mut free, 3, 2, 2, TEXT, text, 200);
        for (x, y, p) in clipped.enumerate_pixels() {
            let expected = if x < 41 {
                free.get_pixel(x, y)
            } else {
                &BACKGROUND
            };
            assert_eq!(p, expected, "({x}, {y})");
        }
        // The cut falls inside a glyph, which is drawn up to the edge, not dropped whole.
        assert!((0..20).any(|y| *clipped.get_pixel(40, y) == TEXT));

        // Text running off the image's right and bottom edges is cut there without panicking.
        let mut small = RgbImage::from_pixel(5, 5, BACKGROUND);
        draw_text(&mut small, 2, 2, 4, TEXT, "WW\nWW", u32::MAX);
        draw_text(
            &mut small,
            u32::MAX,
            u32::MAX,
            u32::MAX,
            TEXT,
            "W",
            u32::MAX,
        );
        assert!(small.pixels().any(|p| *p == TEXT));
    }
}
