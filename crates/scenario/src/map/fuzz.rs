//! Map files come from strangers (a map saved on another machine, a
//! download): their decoders (the PGM and PNG image, the YAML description)
//! are fuzzed with random bytes and with mutations of valid files. None may
//! panic, allocate more than its input can justify (a length read from
//! the bytes is bounded before anything is allocated for it) or hang.
//!
//! The cases of each target are few in the normal test suite (a few
//! seconds); `PROPTEST_CASES=N` runs N of each (docs/failures.md, "Fuzzing").

use super::{MapMeta, MapMode, from_image, image, parse_meta};
use proptest::prelude::*;
use std::path::Path;

use mrsim_fuzzkit as largest;

/// What a decoder may allocate at once for `len` bytes of input: a fixed
/// allowance, plus what a compressed image can expand to (deflate's
/// largest ratio is about 1032:1, and a sample becomes a `u16`).
fn allowance(len: usize) -> usize {
    (1 << 20) + len * 1032 * 2 * 4
}

fn office_pgm() -> Vec<u8> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/maps/office.pgm");
    std::fs::read(root).expect("scenarios/maps/office.pgm")
}

/// A small PNG of `color` at `depth`.
fn png_of(color: png::ColorType, depth: png::BitDepth) -> Vec<u8> {
    let (w, h) = (5u32, 3u32);
    let channels = match color {
        png::ColorType::Grayscale | png::ColorType::Indexed => 1,
        png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
    };
    let bits = match depth {
        png::BitDepth::Sixteen => 16,
        png::BitDepth::Eight => 8,
        _ => 1,
    };
    let row = (w as usize * channels * bits).div_ceil(8);
    let data: Vec<u8> = (0..row * h as usize).map(|i| (i * 37) as u8).collect();
    let mut out = Vec::new();
    {
        let mut e = png::Encoder::new(&mut out, w, h);
        e.set_color(color);
        e.set_depth(depth);
        if color == png::ColorType::Indexed {
            e.set_palette(vec![0, 0, 0, 255, 255, 255]);
        }
        let mut w = e.write_header().expect("png header");
        w.write_image_data(&data).expect("png data");
    }
    out
}

fn valid_images() -> Vec<Vec<u8>> {
    let small_pgm = b"P5\n# a comment\n4 2\n255\n\x00\x10\x80\xff\x00\x10\x80\xff".to_vec();
    let plain = b"P2 3 2 65535\n0 1 2\n65535 4 5\n".to_vec();
    vec![
        office_pgm(),
        small_pgm,
        plain,
        png_of(png::ColorType::Grayscale, png::BitDepth::Eight),
        png_of(png::ColorType::Rgba, png::BitDepth::Sixteen),
        png_of(png::ColorType::Indexed, png::BitDepth::One),
        png_of(png::ColorType::GrayscaleAlpha, png::BitDepth::Eight),
    ]
}

fn meta() -> MapMeta {
    MapMeta {
        image: "map.pgm".into(),
        resolution: 0.05,
        origin: [0.0, 0.0, 0.0],
        negate: false,
        occupied_thresh: 0.65,
        free_thresh: 0.196,
        mode: MapMode::Trinary,
    }
}

/// One change to a file's bytes.
#[derive(Debug, Clone)]
enum Mutation {
    /// Flip bits of the byte at (a fraction of the length).
    Flip(f64, u8),
    /// Put a byte at.
    Insert(f64, u8),
    /// Cut the file at.
    Truncate(f64),
    /// Overwrite 4 bytes at with a big-endian number (a PNG's width or a
    /// chunk's length).
    Word(f64, u32),
    /// Replace the first decimal number after at with this one (a PGM's
    /// width, height or maxval).
    Number(f64, u64),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let at = 0.0..1.0f64;
    prop_oneof![
        (at.clone(), any::<u8>()).prop_map(|(a, b)| Mutation::Flip(a, b)),
        (at.clone(), any::<u8>()).prop_map(|(a, b)| Mutation::Insert(a, b)),
        at.clone().prop_map(Mutation::Truncate),
        (
            at.clone(),
            prop_oneof![any::<u32>(), Just(u32::MAX), Just(0x7fff_ffff), Just(0)]
        )
            .prop_map(|(a, w)| Mutation::Word(a, w)),
        (
            0.0..0.05f64,
            prop_oneof![
                any::<u64>(),
                Just(999_999_999),
                Just(0),
                Just(65_536),
                1..100u64
            ]
        )
            .prop_map(|(a, n)| Mutation::Number(a, n)),
    ]
}

fn apply(bytes: &mut Vec<u8>, m: &Mutation) {
    let at = |f: f64, n: usize| ((f * n as f64) as usize).min(n.saturating_sub(1));
    match *m {
        Mutation::Flip(f, b) if !bytes.is_empty() => {
            let i = at(f, bytes.len());
            bytes[i] ^= b.max(1);
        }
        Mutation::Insert(f, b) => {
            let i = at(f, bytes.len() + 1);
            bytes.insert(i.min(bytes.len()), b);
        }
        Mutation::Truncate(f) => bytes.truncate(at(f, bytes.len())),
        Mutation::Word(f, w) if bytes.len() >= 4 => {
            let i = at(f, bytes.len() - 3);
            bytes[i..i + 4].copy_from_slice(&w.to_be_bytes());
        }
        Mutation::Number(f, n) => {
            let start = at(f, bytes.len());
            let Some(d) = bytes[start..].iter().position(u8::is_ascii_digit) else {
                return;
            };
            let d = start + d;
            let end = bytes[d..]
                .iter()
                .position(|b| !b.is_ascii_digit())
                .map_or(bytes.len(), |e| d + e);
            bytes.splice(d..end, n.to_string().into_bytes());
        }
        _ => {}
    }
}

/// Decodes `bytes` as a map's image, then as a whole map, and traces its
/// walls: never a panic, never an allocation past [`allowance`].
fn decode_all(bytes: &[u8]) {
    let (r, largest) = largest::measure(|| {
        let img = image::decode(bytes);
        let map = from_image(Path::new("map.yaml"), meta(), bytes);
        if let Ok(m) = &map {
            // Small images only: tracing is linear in the cells.
            if m.width * m.height <= 1 << 16 {
                let _ = m.walls(crate::types::UnknownCells::Occupied);
            }
        }
        (img.is_ok(), map.is_ok())
    });
    assert_eq!(r.0, r.1, "the image decodes exactly when the map does");
    assert!(
        largest <= allowance(bytes.len()),
        "{} bytes of input asked for {largest} bytes at once",
        bytes.len()
    );
}

/// The first bytes of each image format, and none.
const MAGICS: &[&[u8]] = &[b"P5", b"P2", b"\x89PNG\r\n\x1a\n", b""];

/// Bits of YAML put into a valid map description.
const YAML_BITS: &[&str] = &[
    "",
    ":",
    "- ",
    "[",
    "]",
    "{",
    "}",
    "\"",
    "'",
    "!!binary ",
    "&a ",
    "*a ",
    "\n  ",
    "1e999",
    "-",
    ".inf",
    ".nan",
    "~",
    "\u{feff}",
    "#",
    "? ",
    "|\n",
    "0x10",
    "\t",
];

proptest! {
    #![proptest_config(ProptestConfig { cases: 1000, ..ProptestConfig::default() })]

    #[test]
    fn mutated_map_images_never_panic_nor_allocate_past_their_size(
        which in 0..7usize,
        muts in prop::collection::vec(mutation(), 1..5),
    ) {
        let mut bytes = valid_images().swap_remove(which);
        for m in &muts {
            apply(&mut bytes, m);
        }
        decode_all(&bytes);
    }

    #[test]
    fn random_bytes_as_a_map_image_never_panic(
        magic in prop::sample::select(MAGICS),
        rest in prop::collection::vec(any::<u8>(), 0..256),
    ) {
        let bytes = [magic, &rest[..]].concat();
        decode_all(&bytes);
    }

    #[test]
    fn mutated_map_yaml_never_panics(
        cut in 0..200usize,
        insert in prop::sample::select(YAML_BITS),
        at in 0..200usize,
    ) {
        let yaml = "image: office.pgm\nmode: trinary\nresolution: 0.05\norigin: [-12, -7, 0]\n\
                    negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
        let mut text: String = yaml.chars().take(yaml.len() - cut.min(yaml.len())).collect();
        let i = text.char_indices().map(|(i, _)| i).nth(at).unwrap_or(text.len());
        text.insert_str(i, insert);
        let (r, largest) = largest::measure(|| parse_meta(&text, Path::new("map.yaml")));
        if let Err(e) = r {
            prop_assert!(e.to_string().starts_with("map.yaml: "), "{e}");
        }
        prop_assert!(largest <= allowance(text.len()));
    }
}

#[test]
fn a_valid_image_of_each_kind_decodes() {
    for (i, bytes) in valid_images().iter().enumerate() {
        assert!(image::decode(bytes).is_ok(), "image {i}");
    }
}

/// The CRC-32 of PNG chunks (ISO 3309), for a forged header.
fn crc32(bytes: &[u8]) -> u32 {
    let mut c = !0u32;
    for &b in bytes {
        c ^= u32::from(b);
        for _ in 0..8 {
            c = if c & 1 == 1 {
                0xedb8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    !c
}

#[test]
fn a_pgm_header_claiming_more_pixels_than_its_file_holds_is_refused_without_allocating_them() {
    // Found by the mutation target: office.pgm cut short, its width made
    // large; 30,000 x 30,000 samples were reserved (1.8 GB) before the
    // raster was found short.
    for bytes in [
        &b"P5 30000 30000 255\n\x00\x01\x02"[..],
        b"P2 30000 30000 255\n0 1 2\n",
        b"P5 999999999 999999999 65535\n\x00",
    ] {
        let (r, largest) = largest::measure(|| image::decode(bytes));
        let e = r.expect_err("refused");
        assert!(e.contains("too short") || e.contains("too large"), "{e}");
        assert!(largest <= allowance(bytes.len()), "{largest} bytes at once");
    }
}

#[test]
fn a_png_header_claiming_a_huge_image_is_refused_before_its_buffer_is_made() {
    // Found by the mutation target: a PNG's width word changed; the
    // decoder's output buffer was made at the header's size.
    let mut bytes = png_of(png::ColorType::Rgba, png::BitDepth::Sixteen);
    // IHDR: length at 8, type at 12, width at 16, height at 20, CRC at 29.
    bytes[16..20].copy_from_slice(&40_000u32.to_be_bytes());
    bytes[20..24].copy_from_slice(&40_000u32.to_be_bytes());
    let crc = crc32(&bytes[12..29]);
    bytes[29..33].copy_from_slice(&crc.to_be_bytes());
    let (r, largest) = largest::measure(|| image::decode(&bytes));
    let e = r.expect_err("refused");
    assert!(e.contains("40000 x 40000 pixels"), "{e}");
    assert!(e.contains("more than its"), "{e}");
    assert!(largest <= allowance(bytes.len()), "{largest} bytes at once");
}
