//! Grey images as maps are stored: PGM (P5, P2) read by our own parser and written, PNG through the `image`
//! crate.

use super::error::{MapIoError, io_err};
use crate::grid::MAX_CELLS;
use std::io::Read as _;
use std::path::Path;

/// A grey image with 8-bit pixels, row 0 at the top, as stored on disk.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GreyImage {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Pixels, row-major from the top row.
    pub pixels: Vec<u8>,
}

/// Most bytes read of a map's image: 1 GiB (a 16-bit PGM of [`MAX_CELLS`] pixels is 800 MB; a PNG is smaller).
pub const IMAGE_LIMIT: u64 = 1 << 30;

/// Bytes that tell an image's format: PGM's `P5`/`P2`, PNG's 8-byte signature, other formats' magic.
const MAGIC_BYTES: u64 = 16;

/// Reads a grey image: PGM (P5 binary or P2 ASCII, any maxval) by our own parser, anything else (PNG) with
/// the `image` crate. Colour images are averaged to grey as map_server does; dimensions are checked
/// against [`MAX_CELLS`] before pixels are allocated; at most [`IMAGE_LIMIT`] bytes are read
/// ([`read_grey_image_limited`]).
pub fn read_grey_image(path: &Path) -> Result<GreyImage, MapIoError> {
    read_grey_image_limited(path, IMAGE_LIMIT)
}

/// [`read_grey_image`] reading at most `limit` bytes. The file's first bytes must name an image format (a
/// device such as `/dev/zero` or a text file is refused having read 16 bytes) and a file whose size exceeds
/// `limit` is refused before it is read.
pub fn read_grey_image_limited(path: &Path, limit: u64) -> Result<GreyImage, MapIoError> {
    let file = std::fs::File::open(path).map_err(io_err(path))?;
    let len = file.metadata().map_err(io_err(path))?.len();
    let mut reader = file.take(limit.saturating_add(1));
    let mut bytes = Vec::new();
    (&mut reader).take(MAGIC_BYTES).read_to_end(&mut bytes).map_err(io_err(path))?;
    if bytes.first() != Some(&b'P') && image::guess_format(&bytes).is_err() {
        return Err(MapIoError::Image {
            path: path.to_path_buf(),
            message: "its first bytes are no PGM (P5, P2) or PNG header (a device, or not an image?)".into(),
        });
    }
    let too_large = || {
        io_err(path)(std::io::Error::new(
            std::io::ErrorKind::FileTooLarge,
            format!("larger than the {limit} bytes a map image may have"),
        ))
    };
    if len > limit {
        return Err(too_large());
    }
    bytes.reserve(len.saturating_sub(MAGIC_BYTES) as usize);
    reader.read_to_end(&mut bytes).map_err(io_err(path))?;
    if bytes.len() as u64 > limit {
        return Err(too_large());
    }
    decode_grey_image(&bytes, path)
}

/// Decodes a grey image from its bytes (see [`read_grey_image`]); `path` only names it in errors.
pub fn decode_grey_image(bytes: &[u8], path: &Path) -> Result<GreyImage, MapIoError> {
    if bytes.first() == Some(&b'P') {
        return parse_pgm(bytes, path);
    }
    let reader = image::ImageReader::new(std::io::Cursor::new(bytes)).with_guessed_format().map_err(io_err(path))?;
    let (w, h) =
        reader.into_dimensions().map_err(|e| MapIoError::Image { path: path.to_path_buf(), message: e.to_string() })?;
    let (w, h) = (w as usize, h as usize);
    if w.saturating_mul(h) > MAX_CELLS {
        return Err(MapIoError::TooLarge { path: path.to_path_buf(), width: w, height: h });
    }
    let img = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(io_err(path))?
        .decode()
        .map_err(|e| MapIoError::Image { path: path.to_path_buf(), message: e.to_string() })?;
    let rgb = img.to_rgb8();
    let pixels = rgb.pixels().map(|p| ((p[0] as u16 + p[1] as u16 + p[2] as u16) / 3) as u8).collect();
    Ok(GreyImage { width: w, height: h, pixels })
}

/// Parses a PGM file's bytes.
pub fn parse_pgm(bytes: &[u8], path: &Path) -> Result<GreyImage, MapIoError> {
    let err = |message: String| MapIoError::Pgm { path: path.to_path_buf(), message };
    let magic = bytes.get(..2).ok_or_else(|| err("file too short for a header".into()))?;
    let binary = match magic {
        b"P5" => true,
        b"P2" => false,
        _ => {
            return Err(err(format!(
                "magic number `{}` is not P5 (binary) or P2 (ASCII grey)",
                String::from_utf8_lossy(magic)
            )));
        }
    };
    let mut pos = 2;
    let mut header = [0usize; 3];
    for (k, name) in ["width", "height", "maxval"].iter().enumerate() {
        header[k] = next_number(bytes, &mut pos).ok_or_else(|| err(format!("missing or bad {name} in header")))?;
    }
    let [w, h, maxval] = header;
    if w == 0 || h == 0 {
        return Err(err(format!("empty image ({w}x{h})")));
    }
    if !(1..=65535).contains(&maxval) {
        return Err(err(format!("maxval {maxval} outside 1..65535")));
    }
    if w.saturating_mul(h) > MAX_CELLS {
        return Err(MapIoError::TooLarge { path: path.to_path_buf(), width: w, height: h });
    }
    let n = w * h;
    let scale = |v: usize| -> u8 { ((v.min(maxval) * 255 + maxval / 2) / maxval) as u8 };
    if binary {
        pos += 1; // exactly one whitespace byte after maxval
        let bpp = if maxval > 255 { 2 } else { 1 };
        let data = bytes.get(pos..).unwrap_or(&[]);
        // Checked before any allocation: a header may claim any size.
        if data.len() < n * bpp {
            return Err(err(format!("truncated: {} of {} pixel bytes present", data.len(), n * bpp)));
        }
        let mut pixels = Vec::with_capacity(n);
        if bpp == 1 {
            pixels.extend(data[..n].iter().map(|&v| scale(v as usize)));
        } else {
            pixels.extend(data[..2 * n].chunks_exact(2).map(|c| scale(((c[0] as usize) << 8) | c[1] as usize)));
        }
        Ok(GreyImage { width: w, height: h, pixels })
    } else {
        // Each ASCII pixel takes at least a digit and a separator: no more can be present than that allows.
        let mut pixels = Vec::with_capacity(n.min(bytes.len().saturating_sub(pos) / 2 + 1));
        for k in 0..n {
            let v = next_number(bytes, &mut pos)
                .ok_or_else(|| err(format!("truncated: pixel {k} of {n} missing or not a number")))?;
            pixels.push(scale(v));
        }
        Ok(GreyImage { width: w, height: h, pixels })
    }
}

/// Reads the next whitespace-separated decimal number, skipping `#` comments.
fn next_number(bytes: &[u8], pos: &mut usize) -> Option<usize> {
    loop {
        match bytes.get(*pos)? {
            b'#' => {
                while *bytes.get(*pos)? != b'\n' {
                    *pos += 1;
                }
            }
            c if c.is_ascii_whitespace() => *pos += 1,
            _ => break,
        }
    }
    let start = *pos;
    while bytes.get(*pos).is_some_and(u8::is_ascii_digit) {
        *pos += 1;
    }
    if *pos == start || *pos - start > 12 {
        return None;
    }
    std::str::from_utf8(&bytes[start..*pos]).ok()?.parse().ok()
}

/// Encodes a grey image as binary PGM (P5).
pub fn encode_pgm(img: &GreyImage) -> Vec<u8> {
    let mut out = format!("P5\n# written by mrslam\n{} {}\n255\n", img.width, img.height).into_bytes();
    out.extend_from_slice(&img.pixels);
    out
}

/// Encodes a grey image as PNG.
pub fn encode_png(img: &GreyImage, path: &Path) -> Result<Vec<u8>, MapIoError> {
    let mut out = Vec::new();
    let buf = image::GrayImage::from_raw(img.width as u32, img.height as u32, img.pixels.clone())
        .ok_or_else(|| MapIoError::Image { path: path.to_path_buf(), message: "pixel count mismatch".into() })?;
    buf.write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png)
        .map_err(|e| MapIoError::Image { path: path.to_path_buf(), message: e.to_string() })?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    #[test]
    fn image_errors_name_the_file() {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), "bad.pgm", b"P6\n1 1\n255\n\0\0\0");
        let e = read_grey_image(&dir.path().join("bad.pgm")).unwrap_err().to_string();
        assert!(e.contains("bad.pgm") && e.contains("P6"), "{e}");
        write(dir.path(), "short.pgm", b"P5\n10 10\n255\n\0\0\0");
        let e = read_grey_image(&dir.path().join("short.pgm")).unwrap_err().to_string();
        assert!(e.contains("truncated: 3 of 100"), "{e}");
        write(dir.path(), "short2.pgm", b"P2\n2 2\n255\n1 2 3");
        let e = read_grey_image(&dir.path().join("short2.pgm")).unwrap_err().to_string();
        assert!(e.contains("truncated"), "{e}");
        // A header claiming 1e6 x 1e6 pixels is refused before any allocation.
        write(dir.path(), "huge.pgm", b"P5\n1000000 1000000\n255\n\0");
        let e = read_grey_image(&dir.path().join("huge.pgm")).unwrap_err();
        assert!(matches!(e, MapIoError::TooLarge { width: 1_000_000, .. }), "{e}");
    }

    #[test]
    fn a_device_or_an_oversized_image_is_refused_before_it_is_read() {
        // /dev/zero: its first bytes are no image header (before: 2 GiB read, then refused).
        let e = read_grey_image(Path::new("/dev/zero")).unwrap_err().to_string();
        assert!(e.starts_with("/dev/zero: cannot decode image: its first bytes are no PGM"), "{e}");
        // A text file is no image either.
        let dir = tempfile::tempdir().unwrap();
        let notes = write(dir.path(), "notes.png", b"some words about the map\n");
        assert!(read_grey_image(&notes).unwrap_err().to_string().contains("its first bytes are no PGM"));
        // A file larger than the bound is refused by its size; at the bound it is read.
        let img = [b"P5\n100 100\n255\n".as_slice(), &[0u8; 10_000]].concat();
        let big = write(dir.path(), "big.pgm", &img);
        let e = read_grey_image_limited(&big, 4096).unwrap_err().to_string();
        assert!(e.contains("big.pgm") && e.contains("larger than the 4096 bytes a map image may have"), "{e}");
        assert_eq!(read_grey_image_limited(&big, img.len() as u64).unwrap().pixels.len(), 10_000);
    }

    #[test]
    fn reads_png_maps() {
        let dir = tempfile::tempdir().unwrap();
        let img = GreyImage { width: 2, height: 2, pixels: vec![0, 254, 205, 254] };
        let p = dir.path().join("m.png");
        std::fs::write(&p, encode_png(&img, &p).unwrap()).unwrap();
        assert_eq!(read_grey_image(&p).unwrap(), img);
    }
}
