//! Lossless tile codes: what an 8x8 tile of depth or colour occupies in memory once
//! compressed, from the tile's actual values.
//!
//! Each encoder writes a real bit stream ([`Code`]) and each decoder reads the tile back from
//! it, so a code's size is the length of a stream that decodes to the tile, not an estimate:
//! `decode(encode(tile)) == tile` for every tile (tested as a property), and an encoder
//! falls back to the raw tile when no encoding is shorter.
//!
//! **Depth** ([`encode_depth`]): plane encoding after Hasselgren and Akenine-Möller,
//! "Efficient Depth Buffer Compression", Graphics Hardware 2006. Depth interpolated over a
//! triangle is linear in screen space, so a tile covered by one triangle is a plane and a
//! tile crossed by one edge is two. A plane here is anchored at a corner pixel with its two
//! neighbours' differences as slopes (their anchor encoding's idea, simplified): plane A at
//! pixel (0, 0), plane B at (7, 7). One plane: each pixel stores its residual from plane A
//! in the fewest signed bits that hold every residual of the tile. Two planes: a selector
//! bit per pixel picks the plane with the smaller residual. Values are the stored format's
//! 24-bit depths ([`depth24`]: the D24S8 word the frame-buffer port prices, whose stencil
//! byte this project never uses and no code stores).
//!
//! **Colour** ([`encode_colour`]): delta encoding, per channel of an RGBA8 word a base (the
//! tile's minimum) and every pixel's difference from it in the fewest bits that hold the
//! tile's range, as the delta colour compression of current GPUs (issue 51 cites 2:1 to 8:1)
//! does in its simplest form.

/// Pixels of a tile (8 x 8).
pub const TILE_PIXELS: usize = 64;

/// A tile's values in screen order, pixel (x, y) of the tile at index x + 8 y, whatever the
/// memory layout ([`crate::memory::tiles::PixelOrder`]): a 24-bit depth ([`depth24`]) or an
/// RGBA8 colour ([`rgba8`]).
pub type TileValues = [u32; TILE_PIXELS];

/// Bits of a stored depth.
pub const DEPTH_BITS: u32 = 24;
/// The largest stored depth (depth 1.0).
pub const DEPTH_MAX: u32 = (1 << DEPTH_BITS) - 1;

/// A depth in [0, 1] as the 24-bit unsigned normalised value a D24 buffer stores (rounded to
/// nearest; outside [0, 1] clamped, NaN to 0). The simulator keeps `f32` depth; this is the
/// stored format the tile codes are sized in.
pub fn depth24(z: f32) -> u32 {
    (z.clamp(0.0, 1.0) as f64 * DEPTH_MAX as f64).round() as u32
}

/// An RGB8 colour as the RGBA8 word the frame-buffer port prices (alpha 255).
pub fn rgba8(rgb: [u8; 3]) -> u32 {
    u32::from_le_bytes([rgb[0], rgb[1], rgb[2], 255])
}

/// A compressed tile: a bit stream and its length.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Code {
    words: Vec<u64>,
    len: u32,
}

impl Code {
    /// The stream's length \[bits\].
    pub fn len_bits(&self) -> u32 {
        self.len
    }

    /// The whole sectors of `sector_bytes` bytes the stream occupies (at least one).
    pub fn sectors(&self, sector_bytes: u32) -> u32 {
        self.len.div_ceil(8 * sector_bytes).max(1)
    }

    fn new() -> Self {
        Code {
            words: Vec::new(),
            len: 0,
        }
    }

    /// Appends the low `bits` bits of `value` (bits <= 32).
    fn put(&mut self, value: u64, bits: u32) {
        debug_assert!(bits <= 32);
        if bits == 0 {
            return;
        }
        let v = value & ((1u64 << bits) - 1);
        let (w, off) = ((self.len / 64) as usize, self.len % 64);
        if w == self.words.len() {
            self.words.push(0);
        }
        self.words[w] |= v << off;
        if off + bits > 64 {
            self.words.push(v >> (64 - off));
        }
        self.len += bits;
    }

    /// Appends `value` as a two's-complement signed field of `bits` bits.
    fn put_signed(&mut self, value: i64, bits: u32) {
        self.put(value as u64, bits);
    }

    fn reader(&self) -> Reader<'_> {
        Reader { code: self, at: 0 }
    }
}

/// Reads a [`Code`] back field by field.
struct Reader<'c> {
    code: &'c Code,
    at: u32,
}

impl Reader<'_> {
    fn get(&mut self, bits: u32) -> u64 {
        if bits == 0 {
            return 0;
        }
        let (w, off) = ((self.at / 64) as usize, self.at % 64);
        let mut v = self.code.words[w] >> off;
        if off + bits > 64 {
            v |= self.code.words[w + 1] << (64 - off);
        }
        self.at += bits;
        v & ((1u64 << bits) - 1)
    }

    fn get_signed(&mut self, bits: u32) -> i64 {
        if bits == 0 {
            return 0;
        }
        let v = self.get(bits);
        ((v << (64 - bits)) as i64) >> (64 - bits)
    }
}

/// The fewest two's-complement bits that hold `r` (0 for 0).
fn signed_bits(r: i64) -> u32 {
    match r {
        0 => 0,
        r if r > 0 => 65 - r.leading_zeros(),
        r => 65 - (!r).leading_zeros(),
    }
}

/// The fewest unsigned bits that hold `v`.
fn unsigned_bits(v: u32) -> u32 {
    32 - v.leading_zeros()
}

/// Depth stream modes (2 bits).
const RAW: u64 = 0;
const ONE_PLANE: u64 = 1;
const TWO_PLANES: u64 = 2;
/// A slope field: a difference of two 24-bit depths needs 25 signed bits.
const SLOPE_BITS: u32 = DEPTH_BITS + 1;
/// The residual width field: residuals from a plane of 24-bit depths fit in 29 bits.
const WIDTH_BITS: u32 = 5;

/// A plane anchored at a corner pixel of the tile.
#[derive(Clone, Copy)]
struct Plane {
    x: i64,
    y: i64,
    anchor: i64,
    dx: i64,
    dy: i64,
}

impl Plane {
    /// The plane through corner (x, y) and its neighbours inward along x and y.
    fn at(tile: &TileValues, x: usize, y: usize) -> Plane {
        let at = |x: usize, y: usize| tile[x + 8 * y] as i64;
        let (sx, sy) = (
            if x == 0 { 1 } else { x - 1 },
            if y == 0 { 1 } else { y - 1 },
        );
        let step = |a: usize, b: usize| if b > a { 1 } else { -1 };
        Plane {
            x: x as i64,
            y: y as i64,
            anchor: at(x, y),
            dx: (at(sx, y) - at(x, y)) * step(x, sx),
            dy: (at(x, sy) - at(x, y)) * step(y, sy),
        }
    }

    fn predict(&self, i: usize) -> i64 {
        let (x, y) = ((i % 8) as i64, (i / 8) as i64);
        self.anchor + (x - self.x) * self.dx + (y - self.y) * self.dy
    }

    fn put(&self, code: &mut Code) {
        code.put(self.anchor as u64, DEPTH_BITS);
        code.put_signed(self.dx, SLOPE_BITS);
        code.put_signed(self.dy, SLOPE_BITS);
    }

    fn get(r: &mut Reader, x: i64, y: i64) -> Plane {
        let anchor = r.get(DEPTH_BITS) as i64;
        let (dx, dy) = (r.get_signed(SLOPE_BITS), r.get_signed(SLOPE_BITS));
        Plane {
            x,
            y,
            anchor,
            dx,
            dy,
        }
    }
}

/// The tile's 24-bit depths (each < 2^24) as the shortest of: raw, one plane, two planes.
pub fn encode_depth(tile: &TileValues) -> Code {
    debug_assert!(tile.iter().all(|&d| d <= DEPTH_MAX));
    let a = Plane::at(tile, 0, 0);
    let b = Plane::at(tile, 7, 7);
    let one: Vec<i64> = (0..TILE_PIXELS)
        .map(|i| tile[i] as i64 - a.predict(i))
        .collect();
    let one_width = one.iter().map(|&r| signed_bits(r)).max().unwrap_or(0);
    let mut select = 0u64;
    let two: Vec<i64> = (0..TILE_PIXELS)
        .map(|i| {
            let (ra, rb) = (tile[i] as i64 - a.predict(i), tile[i] as i64 - b.predict(i));
            if signed_bits(rb) < signed_bits(ra) {
                select |= 1 << i;
                rb
            } else {
                ra
            }
        })
        .collect();
    let two_width = two.iter().map(|&r| signed_bits(r)).max().unwrap_or(0);
    let plane_bits = DEPTH_BITS + 2 * SLOPE_BITS;
    let px = TILE_PIXELS as u32;
    let sizes = [
        px * DEPTH_BITS,
        plane_bits + WIDTH_BITS + px * one_width,
        2 * plane_bits + px + WIDTH_BITS + px * two_width,
    ];
    let best = (0..3).min_by_key(|&m| sizes[m]).unwrap_or(0);
    let mut code = Code::new();
    code.put(best as u64, 2);
    match best as u64 {
        ONE_PLANE => {
            a.put(&mut code);
            put_residuals(&mut code, &one, one_width);
        }
        TWO_PLANES => {
            a.put(&mut code);
            b.put(&mut code);
            code.put(select & 0xffff_ffff, 32);
            code.put(select >> 32, 32);
            put_residuals(&mut code, &two, two_width);
        }
        _ => tile.iter().for_each(|&d| code.put(d as u64, DEPTH_BITS)),
    }
    code
}

fn put_residuals(code: &mut Code, residuals: &[i64], width: u32) {
    code.put(width as u64, WIDTH_BITS);
    residuals.iter().for_each(|&r| code.put_signed(r, width));
}

/// The tile a depth [`Code`] holds.
pub fn decode_depth(code: &Code) -> TileValues {
    let mut r = code.reader();
    let mut tile = [0u32; TILE_PIXELS];
    match r.get(2) {
        RAW => tile.iter_mut().for_each(|d| *d = r.get(DEPTH_BITS) as u32),
        ONE_PLANE => {
            let a = Plane::get(&mut r, 0, 0);
            let width = r.get(WIDTH_BITS) as u32;
            for (i, d) in tile.iter_mut().enumerate() {
                *d = (a.predict(i) + r.get_signed(width)) as u32;
            }
        }
        _ => {
            let a = Plane::get(&mut r, 0, 0);
            let b = Plane::get(&mut r, 7, 7);
            let select = r.get(32) | r.get(32) << 32;
            let width = r.get(WIDTH_BITS) as u32;
            for (i, d) in tile.iter_mut().enumerate() {
                let plane = if select >> i & 1 == 1 { &b } else { &a };
                *d = (plane.predict(i) + r.get_signed(width)) as u32;
            }
        }
    }
    tile
}

/// Colour stream: 1 bit of mode, then raw words or per channel a base and a width.
const CHANNEL_BITS: u32 = 8;
/// A channel's residual width, 0 to 8.
const CHANNEL_WIDTH_BITS: u32 = 4;

/// The tile's RGBA8 words, delta-encoded per channel when shorter than raw.
pub fn encode_colour(tile: &TileValues) -> Code {
    let channel = |c: usize| tile.map(|w| (w >> (8 * c)) & 0xff);
    let bases: [u32; 4] = std::array::from_fn(|c| channel(c).into_iter().min().unwrap_or(0));
    let widths: [u32; 4] = std::array::from_fn(|c| {
        unsigned_bits(channel(c).into_iter().max().unwrap_or(0) - bases[c])
    });
    let px = TILE_PIXELS as u32;
    let delta = 4 * (CHANNEL_BITS + CHANNEL_WIDTH_BITS) + px * widths.iter().sum::<u32>();
    let mut code = Code::new();
    if delta < px * 32 {
        code.put(1, 1);
        for c in 0..4 {
            code.put(bases[c] as u64, CHANNEL_BITS);
            code.put(widths[c] as u64, CHANNEL_WIDTH_BITS);
        }
        for &w in tile {
            for c in 0..4 {
                code.put(((w >> (8 * c) & 0xff) - bases[c]) as u64, widths[c]);
            }
        }
    } else {
        code.put(0, 1);
        tile.iter().for_each(|&w| code.put(w as u64, 32));
    }
    code
}

/// The tile a colour [`Code`] holds.
pub fn decode_colour(code: &Code) -> TileValues {
    let mut r = code.reader();
    let mut tile = [0u32; TILE_PIXELS];
    if r.get(1) == 0 {
        tile.iter_mut().for_each(|w| *w = r.get(32) as u32);
        return tile;
    }
    let mut bases = [0u32; 4];
    let mut widths = [0u32; 4];
    for c in 0..4 {
        bases[c] = r.get(CHANNEL_BITS) as u32;
        widths[c] = r.get(CHANNEL_WIDTH_BITS) as u32;
    }
    for w in tile.iter_mut() {
        for c in 0..4 {
            *w |= (bases[c] + r.get(widths[c]) as u32) << (8 * c);
        }
    }
    tile
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::SplitMix64;

    /// A tile of depths on the plane a + bx x + by y, rounded to the stored format.
    fn plane_tile(a: f64, bx: f64, by: f64) -> TileValues {
        std::array::from_fn(|i| depth24((a + bx * (i % 8) as f64 + by * (i / 8) as f64) as f32))
    }

    fn random_depths(rng: &mut SplitMix64) -> TileValues {
        let kind = rng.below(4);
        match kind {
            0 => std::array::from_fn(|_| rng.below(DEPTH_MAX as u64 + 1) as u32),
            1 => plane_tile(rng.unit(), rng.range(-1e-3, 1e-3), rng.range(-1e-3, 1e-3)),
            _ => {
                // Two triangles meeting along a random edge, each its own plane.
                let p = plane_tile(rng.range(0.2, 0.8), rng.range(-1e-3, 1e-3), 1e-4);
                let q = plane_tile(rng.range(0.2, 0.8), 2e-4, rng.range(-1e-3, 1e-3));
                let (k, m) = (rng.range(-8.0, 16.0), rng.range(-2.0, 2.0));
                std::array::from_fn(|i| {
                    let (x, y) = ((i % 8) as f64, (i / 8) as f64);
                    if y > m * x + k - 4.0 {
                        p[i]
                    } else {
                        q[i]
                    }
                })
            }
        }
    }

    #[test]
    fn depth_codes_are_lossless_on_random_planar_and_noisy_tiles() {
        let mut rng = SplitMix64::new(51);
        for _ in 0..4000 {
            let tile = random_depths(&mut rng);
            assert_eq!(decode_depth(&encode_depth(&tile)), tile);
        }
        // The extremes of the stored range, where a slope field overflows first.
        for tile in [
            [0; 64],
            [DEPTH_MAX; 64],
            std::array::from_fn(|i| DEPTH_MAX * (i as u32 % 2)),
        ] {
            assert_eq!(decode_depth(&encode_depth(&tile)), tile);
        }
    }

    #[test]
    fn colour_codes_are_lossless_on_random_tiles() {
        let mut rng = SplitMix64::new(7);
        for _ in 0..4000 {
            let spread = 1u64 << rng.below(9);
            let base = rng.next_u64() as u32;
            let tile: TileValues = std::array::from_fn(|_| {
                let d = rng.next_u64();
                let ch =
                    |c: u32| ((base >> (8 * c) & 0xff) as u64 + (d >> (16 * c)) % spread).min(255);
                (ch(0) | ch(1) << 8 | ch(2) << 16 | ch(3) << 24) as u32
            });
            assert_eq!(decode_colour(&encode_colour(&tile)), tile);
        }
    }

    #[test]
    fn constant_tiles_compress_to_one_sector() {
        let depth = encode_depth(&[depth24(0.5); 64]);
        // Mode, one plane (24 + 2 x 25 bits), a residual width of 0.
        assert_eq!(depth.len_bits(), 2 + 74 + 5);
        assert_eq!(depth.sectors(32), 1);
        let colour = encode_colour(&[rgba8([10, 200, 30]); 64]);
        assert_eq!(colour.len_bits(), 1 + 4 * 12);
        assert_eq!(colour.sectors(32), 1);
    }

    #[test]
    fn a_planar_depth_tile_takes_two_sectors_and_an_edge_tile_three() {
        // Rounding to 24 bits leaves the anchored plane's slopes a step off at most, so
        // residuals of a few bits: 81 bits of plane and width, then 64 residuals.
        let plane = plane_tile(0.3, 1.7e-4, -2.9e-4);
        let code = encode_depth(&plane);
        assert_eq!(decode_depth(&code), plane);
        assert_eq!(code.sectors(32), 2, "{} bits", code.len_bits());
        let p = plane_tile(0.3, 1.7e-4, -2.9e-4);
        let q = plane_tile(0.6, -3.1e-4, 1.3e-4);
        let edge: TileValues = std::array::from_fn(|i| if i % 8 + i / 8 < 8 { p[i] } else { q[i] });
        let code = encode_depth(&edge);
        assert_eq!(decode_depth(&code), edge);
        assert!(code.sectors(32) <= 3, "{} bits", code.len_bits());
    }

    #[test]
    fn noise_does_not_compress() {
        let mut rng = SplitMix64::new(3);
        let depth: TileValues = std::array::from_fn(|_| rng.below(DEPTH_MAX as u64 + 1) as u32);
        // Raw: the mode and 64 x 24 bits, 6.1 sectors of the 8 a D24S8 tile takes.
        assert_eq!(encode_depth(&depth).len_bits(), 2 + 64 * 24);
        let colour: TileValues = std::array::from_fn(|_| rng.next_u64() as u32);
        assert_eq!(encode_colour(&colour).len_bits(), 1 + 64 * 32);
        assert_eq!(encode_colour(&colour).sectors(32), 9);
    }

    #[test]
    fn signed_widths_hold_their_extremes() {
        assert_eq!(signed_bits(0), 0);
        assert_eq!(signed_bits(-1), 1);
        assert_eq!(signed_bits(1), 2);
        assert_eq!(signed_bits(-2), 2);
        assert_eq!(signed_bits(127), 8);
        assert_eq!(signed_bits(-128), 8);
        assert_eq!(signed_bits(128), 9);
    }
}
