//! Decoding a map's image: PGM (`P5` binary, `P2` plain) and PNG (any
//! colour type and depth: palettes and depths below 8 bits expanded to 8
//! bits a sample, 16 bits kept, as map_server's image library keeps them),
//! told apart by their first bytes as map_server's image library does, not
//! by the file's name.

/// A decoded image: samples row by row from the top row, `channels` a pixel
/// (1 gray, 2 gray + alpha, 3 RGB, 4 RGBA), each in `0..=max`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Pixels {
    pub width: usize,
    pub height: usize,
    pub channels: usize,
    pub max: u16,
    pub samples: Vec<u16>,
}

impl Pixels {
    /// Does the image carry an alpha channel?
    pub fn has_alpha(&self) -> bool {
        self.channels == 2 || self.channels == 4
    }

    /// The samples of the pixel at column `x`, row `y` (row 0 the top).
    pub fn pixel(&self, x: usize, y: usize) -> &[u16] {
        let at = (y * self.width + x) * self.channels;
        &self.samples[at..at + self.channels]
    }
}

/// Decodes an image file's bytes; the error is the reason, without the
/// file's name.
pub(crate) fn decode(bytes: &[u8]) -> Result<Pixels, String> {
    match bytes {
        [0x89, b'P', b'N', b'G', ..] => png(bytes),
        [b'P', b'5', ..] => pgm(bytes, true),
        [b'P', b'2', ..] => pgm(bytes, false),
        [] => Err("the image file is empty".into()),
        _ => Err(
            "not a PGM (P5 or P2) or PNG image (mrsim reads those two, the formats \
             map_server's map_saver writes)"
                .into(),
        ),
    }
}

/// The most pixel bytes a PNG's bytes can decode to: deflate's largest
/// ratio (about 1032:1), with room for the filter bytes.
const PNG_MAX_RATIO: usize = 1100;

fn png(bytes: &[u8]) -> Result<Pixels, String> {
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().map_err(|e| format!("bad PNG: {e}"))?;
    let size = reader
        .output_buffer_size()
        .ok_or("bad PNG: the image is too large")?;
    // Deflate expands at most about 1032 times: an image whose pixels
    // could not come out of the file's bytes is refused before its buffer
    // is made, rather than allocated on the header's word.
    if size > bytes.len().saturating_mul(PNG_MAX_RATIO) {
        let info = reader.info();
        return Err(format!(
            "bad PNG: its header says {} x {} pixels ({size} bytes), more than its {} bytes \
             can hold",
            info.width,
            info.height,
            bytes.len()
        ));
    }
    let mut buf = vec![0u8; size];
    let frame = reader
        .next_frame(&mut buf)
        .map_err(|e| format!("bad PNG: {e}"))?;
    let channels = match frame.color_type {
        png::ColorType::Grayscale => 1,
        png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        png::ColorType::Indexed => return Err("bad PNG: palette not expanded".into()),
    };
    let wide = match frame.bit_depth {
        png::BitDepth::Eight => false,
        png::BitDepth::Sixteen => true,
        other => return Err(format!("bad PNG: {other:?} bits a sample not expanded")),
    };
    let (width, height) = (frame.width as usize, frame.height as usize);
    let row = width * channels * if wide { 2 } else { 1 };
    let mut samples = Vec::with_capacity(width * channels * height);
    for y in 0..height {
        let start = y * frame.line_size;
        let line = buf
            .get(start..start + row)
            .ok_or("bad PNG: short image data")?;
        if wide {
            samples.extend(
                line.chunks_exact(2)
                    .map(|c| u16::from_be_bytes([c[0], c[1]])),
            );
        } else {
            samples.extend(line.iter().map(|&b| u16::from(b)));
        }
    }
    Ok(Pixels {
        width,
        height,
        channels,
        max: if wide { u16::MAX } else { 255 },
        samples,
    })
}

/// Netpbm's gray map: magic, width, height, maxval as decimal numbers
/// separated by whitespace (a `#` starts a comment to the end of the line),
/// one whitespace character, then the raster: one or two bytes a sample
/// (big-endian when maxval > 255) for `P5`, decimal numbers for `P2`.
fn pgm(bytes: &[u8], binary: bool) -> Result<Pixels, String> {
    let mut at = 2;
    let mut header = [0usize; 3];
    for (k, name) in ["width", "height", "maxval"].iter().enumerate() {
        header[k] = header_number(bytes, &mut at).ok_or_else(|| {
            format!("bad PGM header: no {name} (a PGM starts `P5 WIDTH HEIGHT MAXVAL`)")
        })?;
    }
    let [width, height, max] = header;
    if width == 0 || height == 0 {
        return Err(format!(
            "bad PGM header: the image is {width} x {height} pixels (it needs at least one)"
        ));
    }
    if !(1..=65535).contains(&max) {
        return Err(format!(
            "bad PGM header: maxval must be in 1..=65535, got {max}"
        ));
    }
    let count = width
        .checked_mul(height)
        .ok_or("bad PGM header: the image is too large")?;
    // Room only for what the file can hold: at least one byte a sample in
    // P5, two (a digit and a space) in P2; a header claiming more than that
    // is caught below without allocating for its claim.
    let mut samples = Vec::with_capacity(count.min(bytes.len()));
    if binary {
        // Exactly one whitespace character ends the header.
        if !bytes.get(at).is_some_and(u8::is_ascii_whitespace) {
            return Err("bad PGM header: no whitespace after maxval".into());
        }
        let raster = &bytes[at + 1..];
        let wide = max > 255;
        let need = count
            .checked_mul(if wide { 2 } else { 1 })
            .ok_or("bad PGM header: the image is too large")?;
        if raster.len() < need {
            return Err(format!(
                "the PGM's pixel data is too short: {width} x {height} pixels need {need} bytes, \
                 the file has {}",
                raster.len()
            ));
        }
        if wide {
            samples.extend(
                raster[..need]
                    .chunks_exact(2)
                    .map(|c| u16::from_be_bytes([c[0], c[1]])),
            );
        } else {
            samples.extend(raster[..need].iter().map(|&b| u16::from(b)));
        }
    } else {
        for k in 0..count {
            let v = header_number(bytes, &mut at).ok_or_else(|| {
                format!(
                    "the PGM's pixel data is too short or not numbers: {width} x {height} pixels, \
                     pixel {k} missing"
                )
            })?;
            samples.push(u16::try_from(v).unwrap_or(u16::MAX));
        }
    }
    if let Some(v) = samples.iter().find(|&&v| usize::from(v) > max) {
        return Err(format!(
            "the PGM has a pixel value {v} above its maxval {max}"
        ));
    }
    Ok(Pixels {
        width,
        height,
        channels: 1,
        max: max as u16,
        samples,
    })
}

/// The next decimal number from `at`, skipping whitespace and comments;
/// `at` is left just past its last digit. None if there is none (or it is
/// absurdly long).
fn header_number(bytes: &[u8], at: &mut usize) -> Option<usize> {
    loop {
        match bytes.get(*at)? {
            b'#' => {
                while bytes.get(*at).is_some_and(|&b| b != b'\n' && b != b'\r') {
                    *at += 1;
                }
            }
            b if b.is_ascii_whitespace() => *at += 1,
            _ => break,
        }
    }
    let start = *at;
    while bytes.get(*at).is_some_and(u8::is_ascii_digit) {
        *at += 1;
    }
    if *at == start || *at - start > 9 {
        return None;
    }
    std::str::from_utf8(&bytes[start..*at]).ok()?.parse().ok()
}
