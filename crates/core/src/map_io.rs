//! ROS map_server maps: YAML metadata plus a PGM (P5 or P2) or PNG image, read and written.
//!
//! Reading follows map_server's `loadMapFromFile`: a pixel's occupancy is `p = (255 - v) / 255`
//! (`v / 255` when `negate` is set); `trinary` mode makes `p > occupied_thresh` occupied,
//! `p < free_thresh` free and the rest unknown; `scale` keeps the in-between values; `raw` takes the
//! pixel value itself as the ROS occupancy (0..100, anything else unknown). Occupancies become log-odds
//! clamped to ±[`ROS_LOGODDS_LIMIT`], so a map read back from disk holds exactly −2, 0 or +2 per cell.
//!
//! The YAML is read with a YAML parser, so everything map_server accepts is accepted (block or flow lists,
//! quoted values, comments); keys map_server ignores are reported as warnings. Errors name the file, the line
//! and the field.

use crate::grid::{CellState, GridError, MAX_CELLS, OccupancyGrid};
use crate::se2::{Pose2, pose};
use nalgebra::Point2;
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

/// Log-odds given to a definitely occupied (+) or free (−) cell read from a ROS map: p ≈ 0.88 / 0.12.
pub const ROS_LOGODDS_LIMIT: f32 = 2.0;

/// PGM value written for occupied cells.
pub const PGM_OCCUPIED: u8 = 0;
/// PGM value written for free cells.
pub const PGM_FREE: u8 = 254;
/// PGM value written for unknown cells.
pub const PGM_UNKNOWN: u8 = 205;

/// How map_server interprets pixel values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MapMode {
    /// Occupied, free or unknown by the two thresholds.
    Trinary,
    /// Like trinary, with in-between values kept as a graded occupancy.
    Scale,
    /// The pixel value is the occupancy 0..100; others are unknown.
    Raw,
}

/// The metadata of a map_server YAML file.
#[derive(Debug, Clone, PartialEq)]
pub struct MapYaml {
    /// Image path as written in the file (relative paths are relative to the YAML file).
    pub image: String,
    /// Metres per pixel.
    pub resolution: f64,
    /// Pose of the lower-left pixel's outer corner: x, y, yaw.
    pub origin: [f64; 3],
    /// Whether white means occupied.
    pub negate: bool,
    /// Occupancy above which a pixel is occupied.
    pub occupied_thresh: f64,
    /// Occupancy below which a pixel is free.
    pub free_thresh: f64,
    /// Interpretation of pixel values.
    pub mode: MapMode,
}

/// Everything that can go wrong reading or writing a map; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum MapIoError {
    /// The file could not be read or written.
    #[error("{path}: {cause}")]
    Io {
        /// File at fault.
        path: PathBuf,
        /// Underlying error.
        cause: std::io::Error,
    },
    /// A YAML line could not be understood.
    #[error("{}: {message}", at(path, *line))]
    Yaml {
        /// File at fault.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A field has a value that is not allowed.
    #[error("{}: field `{field}`: {message}", at(path, *line))]
    BadField {
        /// File at fault.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// Field name.
        field: &'static str,
        /// What is wrong.
        message: String,
    },
    /// A required field is absent.
    #[error("{path}: missing required field `{field}`")]
    MissingField {
        /// File at fault.
        path: PathBuf,
        /// Field name.
        field: &'static str,
    },
    /// The image is not a valid PGM.
    #[error("{path}: not a valid PGM image: {message}")]
    Pgm {
        /// File at fault.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The image could not be decoded.
    #[error("{path}: cannot decode image: {message}")]
    Image {
        /// File at fault.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The image is larger than this program accepts.
    #[error("{path}: image of {width}x{height} pixels exceeds the limit of {MAX_CELLS} cells")]
    TooLarge {
        /// File at fault.
        path: PathBuf,
        /// Width claimed.
        width: usize,
        /// Height claimed.
        height: usize,
    },
    /// The image a map YAML names could not be read.
    #[error("{}: field `image`: {cause}", at(yaml, *line))]
    ImageOf {
        /// The YAML naming the image.
        yaml: PathBuf,
        /// Line of its `image` field.
        line: usize,
        /// Why the image could not be read (names the image).
        cause: Box<MapIoError>,
    },
    /// The grid could not be built.
    #[error("{path}: {cause}")]
    Grid {
        /// File at fault.
        path: PathBuf,
        /// Underlying error.
        cause: GridError,
    },
}

/// `file:line`, or the file alone when the line is not known (0).
fn at(path: &Path, line: usize) -> String {
    if line == 0 { path.display().to_string() } else { format!("{}:{line}", path.display()) }
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> MapIoError + '_ {
    move |cause| MapIoError::Io { path: path.to_path_buf(), cause }
}

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

/// Reads a map_server YAML file and the image it names.
pub fn read_ros_map(yaml_path: &Path) -> Result<OccupancyGrid, MapIoError> {
    read_ros_map_with(yaml_path, &mut |_| {})
}

/// Reads a map_server YAML file and the image it names, calling `warn` for each key map_server ignores.
pub fn read_ros_map_with(yaml_path: &Path, warn: &mut dyn FnMut(String)) -> Result<OccupancyGrid, MapIoError> {
    let text = crate::input::read_text_limited(yaml_path, crate::input::CONFIG_LIMIT).map_err(io_err(yaml_path))?;
    let meta = parse_map_yaml_with(&text, yaml_path, warn)?;
    let image_path = resolve_image_path(yaml_path, &meta.image);
    let img = read_grey_image(&image_path).map_err(|cause| MapIoError::ImageOf {
        yaml: yaml_path.to_path_buf(),
        line: key_line(&text, "image"),
        cause: Box::new(cause),
    })?;
    grid_from_image(&img, &meta).map_err(|cause| MapIoError::Grid { path: yaml_path.to_path_buf(), cause })
}

/// Resolves the YAML's `image` field against the YAML file's folder.
pub fn resolve_image_path(yaml_path: &Path, image: &str) -> PathBuf {
    let p = Path::new(image);
    if p.is_absolute() { p.to_path_buf() } else { yaml_path.parent().unwrap_or(Path::new(".")).join(p) }
}

/// Builds a grid from an image and its metadata, as map_server does.
pub fn grid_from_image(img: &GreyImage, meta: &MapYaml) -> Result<OccupancyGrid, GridError> {
    let (w, h) = (img.width, img.height);
    let mut cells = vec![0.0f32; w * h];
    let (occ, free) = (meta.occupied_thresh, meta.free_thresh);
    for row in 0..h {
        let iy = h - 1 - row;
        for ix in 0..w {
            let v = img.pixels[row * w + ix];
            let ros: i32 = match meta.mode {
                MapMode::Raw => {
                    if v <= 100 {
                        v as i32
                    } else {
                        -1
                    }
                }
                MapMode::Trinary | MapMode::Scale => {
                    let p = if meta.negate { v as f64 / 255.0 } else { (255.0 - v as f64) / 255.0 };
                    if p > occ {
                        100
                    } else if p < free {
                        0
                    } else if meta.mode == MapMode::Scale {
                        (99.0 * (p - free) / (occ - free)) as i32
                    } else {
                        -1
                    }
                }
            };
            cells[iy * w + ix] = ros_to_log_odds(ros);
        }
    }
    OccupancyGrid::from_cells(w, h, meta.resolution, pose(meta.origin[0], meta.origin[1], meta.origin[2]), cells)
}

/// Log-odds of a ROS occupancy value (−1 unknown, 0..100).
pub fn ros_to_log_odds(v: i32) -> f32 {
    match v {
        v if !(0..=100).contains(&v) => 0.0,
        0 => -ROS_LOGODDS_LIMIT,
        100 => ROS_LOGODDS_LIMIT,
        v => {
            let p = v as f32 / 100.0;
            (p / (1.0 - p)).ln().clamp(-ROS_LOGODDS_LIMIT, ROS_LOGODDS_LIMIT)
        }
    }
}

/// The keys map_server reads from a map YAML.
pub const MAP_YAML_KEYS: &[&str] =
    &["image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh", "mode"];

/// Parses the text of a map_server YAML file; `path` only names the file in errors.
pub fn parse_map_yaml(text: &str, path: &Path) -> Result<MapYaml, MapIoError> {
    parse_map_yaml_with(text, path, &mut |_| {})
}

/// The 1-based line where top-level `key` is written (`key:` at the start of a line, quoted or not; 0 when
/// not found, as in a one-line flow mapping).
fn key_line(text: &str, key: &str) -> usize {
    key_lines(text, key).next().unwrap_or(0)
}

/// Every 1-based line where top-level `key` is written.
fn key_lines<'t>(text: &'t str, key: &'t str) -> impl Iterator<Item = usize> + 't {
    let spellings = [key.to_string(), format!("\"{key}\""), format!("'{key}'")];
    text.lines().enumerate().filter_map(move |(i, l)| {
        spellings
            .iter()
            .any(|k| l.strip_prefix(k.as_str()).is_some_and(|rest| rest.trim_start().starts_with(':')))
            .then_some(i + 1)
    })
}

/// A scalar as text: strings as they are, numbers and booleans as YAML writes them.
fn scalar_text(v: &serde_norway::Value) -> Option<String> {
    match v {
        serde_norway::Value::String(s) => Some(s.clone()),
        serde_norway::Value::Number(n) => Some(n.to_string()),
        serde_norway::Value::Bool(b) => Some(b.to_string()),
        _ => None,
    }
}

/// Parses a map YAML as map_server does (any YAML: block or flow lists, quoted scalars, comments), calling
/// `warn` with a message for each key map_server would ignore.
pub fn parse_map_yaml_with(text: &str, path: &Path, warn: &mut dyn FnMut(String)) -> Result<MapYaml, MapIoError> {
    let yaml_err = |line: usize, message: String| MapIoError::Yaml { path: path.to_path_buf(), line, message };
    let doc: serde_norway::Value = serde_norway::from_str(text).map_err(|e| {
        let message = e.to_string();
        // A key given twice: the line of its second appearance.
        let twice = message
            .strip_prefix("duplicate entry with key \"")
            .and_then(|rest| rest.split('"').next())
            .and_then(|key| key_lines(text, key).nth(1));
        let line = twice.or(e.location().map(|l| l.line())).unwrap_or(0);
        // serde_norway appends " at line L column C"; the line is already in front.
        let message = message.split(" at line ").next().unwrap_or(&message).to_string();
        yaml_err(line, message)
    })?;
    let map = match &doc {
        serde_norway::Value::Mapping(m) => m,
        serde_norway::Value::Null => return Err(MapIoError::MissingField { path: path.to_path_buf(), field: "image" }),
        _ => {
            let first = text.lines().position(|l| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
            return Err(yaml_err(first.map_or(1, |i| i + 1), "expected `key: value` lines (a mapping)".into()));
        }
    };
    let mut image: Option<String> = None;
    let mut resolution: Option<f64> = None;
    let mut origin: Option<[f64; 3]> = None;
    let mut negate = false;
    let mut occupied_thresh = 0.65;
    let mut free_thresh = 0.196;
    let mut mode = MapMode::Trinary;
    for (k, v) in map {
        let Some(key) = k.as_str() else {
            return Err(yaml_err(0, format!("key `{}` is not a name", scalar_text(k).unwrap_or_else(|| "?".into()))));
        };
        let line = key_line(text, key);
        let bad = |field: &'static str, message: String| MapIoError::BadField {
            path: path.to_path_buf(),
            line,
            field,
            message,
        };
        let shown = || scalar_text(v).unwrap_or_else(|| "a list or mapping".into());
        let number = |field: &'static str| -> Result<f64, MapIoError> {
            scalar_text(v)
                .and_then(|s| s.trim().parse::<f64>().ok())
                .filter(|v| v.is_finite())
                .ok_or_else(|| bad(field, format!("expected a finite number, found `{}`", shown())))
        };
        match key {
            "image" => {
                let s = scalar_text(v).ok_or_else(|| bad("image", "expected a file name".into()))?;
                if s.trim().is_empty() {
                    return Err(bad("image", "empty image path".into()));
                }
                image = Some(s);
            }
            "resolution" => {
                let r = number("resolution")?;
                if r <= 0.0 {
                    return Err(bad("resolution", format!("must be positive, found {r}")));
                }
                resolution = Some(r);
            }
            "origin" => {
                let serde_norway::Value::Sequence(items) = v else {
                    return Err(bad("origin", format!("expected `[x, y, yaw]`, found `{}`", shown())));
                };
                if items.len() != 3 {
                    return Err(bad("origin", format!("expected 3 numbers, found {}", items.len())));
                }
                let mut o = [0.0; 3];
                for (slot, item) in o.iter_mut().zip(items) {
                    let t = scalar_text(item).unwrap_or_else(|| "a list or mapping".into());
                    *slot = t
                        .trim()
                        .parse::<f64>()
                        .ok()
                        .filter(|v| v.is_finite())
                        .ok_or_else(|| bad("origin", format!("`{t}` is not a finite number")))?;
                }
                origin = Some(o);
            }
            "negate" => {
                negate = match scalar_text(v).as_deref() {
                    Some("0" | "false" | "False") => false,
                    Some("1" | "true" | "True") => true,
                    _ => return Err(bad("negate", format!("expected 0 or 1, found `{}`", shown()))),
                }
            }
            "occupied_thresh" => occupied_thresh = number("occupied_thresh")?,
            "free_thresh" => free_thresh = number("free_thresh")?,
            "mode" => {
                mode = match scalar_text(v).as_deref() {
                    Some("trinary") => MapMode::Trinary,
                    Some("scale") => MapMode::Scale,
                    Some("raw") => MapMode::Raw,
                    _ => return Err(bad("mode", format!("expected trinary, scale or raw, found `{}`", shown()))),
                }
            }
            other => {
                let at = if line == 0 { String::new() } else { format!(":{line}") };
                warn(format!(
                    "{}{at}: unknown key `{other}` ignored (map_server reads {})",
                    path.display(),
                    MAP_YAML_KEYS.join(", ")
                ));
            }
        }
    }
    if !(0.0..=1.0).contains(&free_thresh) || !(0.0..=1.0).contains(&occupied_thresh) || free_thresh >= occupied_thresh
    {
        return Err(MapIoError::BadField {
            path: path.to_path_buf(),
            line: key_line(text, "free_thresh").max(key_line(text, "occupied_thresh")),
            field: "free_thresh",
            message: format!("need 0 <= free_thresh < occupied_thresh <= 1, found {free_thresh} and {occupied_thresh}"),
        });
    }
    let missing = |field| MapIoError::MissingField { path: path.to_path_buf(), field };
    Ok(MapYaml {
        image: image.ok_or_else(|| missing("image"))?,
        resolution: resolution.ok_or_else(|| missing("resolution"))?,
        origin: origin.ok_or_else(|| missing("origin"))?,
        negate,
        occupied_thresh,
        free_thresh,
        mode,
    })
}

/// Reads a grey image: PGM (P5 binary or P2 ASCII, any maxval) by our own parser, anything else (PNG) with
/// the `image` crate. Colour images are averaged to grey as map_server does; dimensions are checked
/// against [`MAX_CELLS`] before pixels are allocated.
pub fn read_grey_image(path: &Path) -> Result<GreyImage, MapIoError> {
    let bytes = crate::input::read_limited(path, crate::input::DATA_LIMIT).map_err(io_err(path))?;
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

/// Renders a grid as a trinary grey image, top row first: occupied 0, free 254, unknown 205.
pub fn grid_to_image(grid: &OccupancyGrid) -> GreyImage {
    let (w, h) = (grid.width(), grid.height());
    let mut pixels = vec![PGM_UNKNOWN; w * h];
    for iy in 0..h {
        let row = h - 1 - iy;
        for ix in 0..w {
            pixels[row * w + ix] = match grid.state(ix, iy) {
                CellState::Occupied => PGM_OCCUPIED,
                CellState::Free => PGM_FREE,
                CellState::Unknown => PGM_UNKNOWN,
            };
        }
    }
    GreyImage { width: w, height: h, pixels }
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

/// Writes a grid as map_server files: `yaml_path` and a trinary PGM beside it with the same stem.
///
/// Both files are written to temporary names and renamed into place, the YAML last, so a reader never
/// sees a half-written map.
pub fn write_ros_map(grid: &OccupancyGrid, yaml_path: &Path) -> Result<(), MapIoError> {
    let pgm_path = yaml_path.with_extension("pgm");
    let image_name = pgm_path.file_name().and_then(|s| s.to_str()).unwrap_or("map.pgm").to_string();
    write_file_atomic(&pgm_path, &encode_pgm(&grid_to_image(grid)))?;
    write_file_atomic(yaml_path, map_yaml_text(grid, &image_name).as_bytes())
}

/// Cells of margin a preview keeps around the map's known cells.
const PREVIEW_MARGIN: usize = 10;

/// Where the preview of the map `yaml_path` goes: beside it, the same name with `.png`.
pub fn preview_path(yaml_path: &Path) -> PathBuf {
    yaml_path.with_extension("png")
}

/// The pixel box (x0, y0, x1, y1, inclusive, top row 0) of a grid's image that its preview keeps: the known cells
/// and a margin of 10 cells; the whole image when no cell is known.
fn preview_box(img: &GreyImage) -> (usize, usize, usize, usize) {
    let (w, h) = (img.width, img.height);
    let (mut x0, mut y0, mut x1, mut y1) = (w, h, 0, 0);
    for (i, &v) in img.pixels.iter().enumerate() {
        if v != PGM_UNKNOWN {
            let (x, y) = (i % w, i / w);
            x0 = x0.min(x);
            y0 = y0.min(y);
            x1 = x1.max(x);
            y1 = y1.max(y);
        }
    }
    if x0 > x1 {
        return (0, 0, w.saturating_sub(1), h.saturating_sub(1));
    }
    let (x0, y0) = (x0.saturating_sub(PREVIEW_MARGIN), y0.saturating_sub(PREVIEW_MARGIN));
    (x0, y0, (x1 + PREVIEW_MARGIN).min(w - 1), (y1 + PREVIEW_MARGIN).min(h - 1))
}

/// A picture of a grid for a person: its trinary image (occupied black, free white, unknown grey) cropped to the
/// known cells and a margin of 10 cells.
pub fn preview_image(grid: &OccupancyGrid) -> GreyImage {
    let full = grid_to_image(grid);
    if full.pixels.is_empty() {
        return full;
    }
    let (x0, y0, x1, y1) = preview_box(&full);
    let w = full.width;
    let pixels = (y0..=y1).flat_map(|y| full.pixels[y * w + x0..=y * w + x1].iter().copied()).collect();
    GreyImage { width: x1 - x0 + 1, height: y1 - y0 + 1, pixels }
}

/// [`preview_image`] in colour with a path drawn over it in red: `path` is a sequence of points in the map frame
/// (metres), joined by straight lines; points off the picture are clipped.
pub fn preview_with_path(grid: &OccupancyGrid, path: &[Point2<f64>]) -> image::RgbImage {
    let full = grid_to_image(grid);
    let mut out = image::RgbImage::new(1, 1);
    if full.pixels.is_empty() {
        return out;
    }
    let (x0, y0, x1, y1) = preview_box(&full);
    let (w, h) = (x1 - x0 + 1, y1 - y0 + 1);
    out = image::RgbImage::from_fn(w as u32, h as u32, |x, y| {
        let v = full.pixels[(y as usize + y0) * full.width + x as usize + x0];
        image::Rgb([v, v, v])
    });
    // a point's pixel (fractional), top row 0, in the cropped picture
    let pixel = |p: &Point2<f64>| {
        let (cx, cy) = grid.world_to_cell_f(p);
        (cx - x0 as f64, (full.height as f64 - cy) - y0 as f64)
    };
    for pair in path.windows(2) {
        segment(pixel(&pair[0]), pixel(&pair[1]), |x, y| {
            if x >= 0.0 && y >= 0.0 && (x as usize) < w && (y as usize) < h {
                out.put_pixel(x as u32, y as u32, image::Rgb([220, 30, 30]));
            }
        });
    }
    out
}

/// Visits the points of the straight line from pixel `a` to pixel `b` (fractional), at most one pixel apart.
fn segment(a: (f64, f64), b: (f64, f64), mut visit: impl FnMut(f64, f64)) {
    let steps = ((b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil() as usize).clamp(1, 100_000);
    for k in 0..=steps {
        let t = k as f64 / steps as f64;
        visit(a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1));
    }
}

/// One map laid over another in [`overlay`]: its occupied cells and a path, placed in the base map's frame.
#[derive(Debug, Clone, Copy)]
pub struct OverlayLayer<'a> {
    /// The map whose occupied cells are drawn.
    pub map: &'a OccupancyGrid,
    /// Where the map's frame lies in the base map's frame.
    pub placement: Pose2,
    /// A path in the map's frame, drawn as lines.
    pub path: &'a [Pose2],
    /// Colour of the occupied cells; the path is drawn in a darker shade of it.
    pub colour: [u8; 3],
}

/// A picture of maps laid over a base map (the truth, say): the base in light greys, each layer's occupied cells
/// in its colour at its placement, each layer's path in a darker shade; cropped as [`preview_image`] crops the
/// base. Where the placements are right, the layers' walls cover the base's.
pub fn overlay(base: &OccupancyGrid, layers: &[OverlayLayer]) -> image::RgbImage {
    let full = grid_to_image(base);
    if full.pixels.is_empty() {
        return image::RgbImage::new(1, 1);
    }
    let (x0, y0, x1, y1) = preview_box(&full);
    let (w, h) = (x1 - x0 + 1, y1 - y0 + 1);
    let mut out = image::RgbImage::from_fn(w as u32, h as u32, |x, y| {
        let v = match full.pixels[(y as usize + y0) * full.width + x as usize + x0] {
            PGM_OCCUPIED => 150,
            PGM_FREE => 245,
            _ => 215,
        };
        image::Rgb([v, v, v])
    });
    let pixel = |p: &Point2<f64>| {
        let (cx, cy) = base.world_to_cell_f(p);
        (cx - x0 as f64, (full.height as f64 - cy) - y0 as f64)
    };
    let mut put = |x: f64, y: f64, c: [u8; 3]| {
        if x >= 0.0 && y >= 0.0 && (x as usize) < w && (y as usize) < h {
            out.put_pixel(x as u32, y as u32, image::Rgb(c));
        }
    };
    for layer in layers {
        let m = layer.map;
        for iy in 0..m.height() {
            for ix in 0..m.width() {
                if m.state(ix, iy) == CellState::Occupied {
                    let (x, y) = pixel(&(layer.placement * m.cell_center(ix as i64, iy as i64)));
                    put(x, y, layer.colour);
                }
            }
        }
        let dark = layer.colour.map(|c| c / 2);
        for pair in layer.path.windows(2) {
            let a = pixel(&(layer.placement * Point2::from(pair[0].translation.vector)));
            let b = pixel(&(layer.placement * Point2::from(pair[1].translation.vector)));
            segment(a, b, |x, y| put(x, y, dark));
        }
    }
    out
}

/// Writes an RGB picture as a PNG at `png_path` (through a temporary name).
pub fn write_rgb_png(img: &image::RgbImage, png_path: &Path) -> Result<(), MapIoError> {
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)
        .map_err(|e| MapIoError::Image { path: png_path.to_path_buf(), message: e.to_string() })?;
    write_file_atomic(png_path, &bytes)
}

/// Writes [`preview_image`] of `grid` as a PNG at `png_path` (through a temporary name).
pub fn write_map_preview(grid: &OccupancyGrid, png_path: &Path) -> Result<(), MapIoError> {
    write_file_atomic(png_path, &encode_png(&preview_image(grid), png_path)?)
}

/// [`write_ros_map`], then the map's PNG preview beside it ([`preview_path`]): what the command line and the
/// testbed write for every map, so that a person can look at it without a viewer.
pub fn write_ros_map_with_preview(grid: &OccupancyGrid, yaml_path: &Path) -> Result<(), MapIoError> {
    write_ros_map(grid, yaml_path)?;
    write_map_preview(grid, &preview_path(yaml_path))
}

/// The YAML text map_server reads for `grid` stored in `image_name`.
pub fn map_yaml_text(grid: &OccupancyGrid, image_name: &str) -> String {
    let o: &Pose2 = grid.origin();
    let mut s = String::new();
    let _ = writeln!(s, "image: {image_name}");
    let _ = writeln!(s, "mode: trinary");
    let _ = writeln!(s, "resolution: {}", grid.resolution());
    let _ = writeln!(s, "origin: [{}, {}, {}]", o.translation.x, o.translation.y, o.rotation.angle());
    let _ = writeln!(s, "negate: 0");
    let _ = writeln!(s, "occupied_thresh: 0.65");
    let _ = writeln!(s, "free_thresh: 0.196");
    s
}

/// Writes `bytes` to `path` through a temporary file in the same folder and a rename.
pub fn write_file_atomic(path: &Path, bytes: &[u8]) -> Result<(), MapIoError> {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let name = path.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let tmp = dir.join(format!(".{name}.tmp{}", std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(cause) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(MapIoError::Io { path: path.to_path_buf(), cause });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::LogOddsParams;

    #[test]
    fn a_preview_is_the_map_cropped_to_its_known_cells() {
        let mut g = OccupancyGrid::new(100, 80, 0.05, crate::pose(0.0, 0.0, 0.0)).unwrap();
        for iy in 30..40 {
            for ix in 20..50 {
                g.set(ix, iy, if ix == 20 { 2.0 } else { -2.0 });
            }
        }
        let img = preview_image(&g);
        assert_eq!((img.width, img.height), (30 + 20, 10 + 20));
        // the wall column, 10 pixels in from the left, is black; the corner of the margin is unknown grey
        assert_eq!(img.pixels[15 * img.width + 10], PGM_OCCUPIED);
        assert_eq!(img.pixels[15 * img.width + 11], PGM_FREE);
        assert_eq!(img.pixels[0], PGM_UNKNOWN);
        let dir = tempfile::tempdir().unwrap();
        let yaml = dir.path().join("m.yaml");
        write_ros_map_with_preview(&g, &yaml).unwrap();
        let png = read_grey_image(&preview_path(&yaml)).unwrap();
        assert_eq!((png.width, png.height, png.pixels), (img.width, img.height, img.pixels));
        // an empty map's preview is the whole (unknown) image
        let empty = OccupancyGrid::new(7, 5, 0.05, crate::pose(0.0, 0.0, 0.0)).unwrap();
        assert_eq!((preview_image(&empty).width, preview_image(&empty).height), (7, 5));
        // A path along the free strip, from cell (25, 35) to (45, 35): red on that row, 11 px from the top.
        let path = [Point2::new(25.5 * 0.05, 35.5 * 0.05), Point2::new(45.5 * 0.05, 35.5 * 0.05)];
        let rgb = preview_with_path(&g, &path);
        assert_eq!((rgb.width() as usize, rgb.height() as usize), (img.width, img.height));
        let row = (80 - 35 - 1) - (80 - 40 - 10); // the cell row's pixel row in the crop
        assert_eq!(rgb.get_pixel(15, row as u32).0, [220, 30, 30]);
        assert_eq!(rgb.get_pixel(35, row as u32).0, [220, 30, 30]);
        assert_eq!(rgb.get_pixel(15, row as u32 + 2).0, [PGM_FREE; 3]);
        // The map laid over itself, placed right: its wall cells in the layer's colour where the base's are.
        let layer = OverlayLayer { map: &g, placement: Pose2::identity(), path: &[], colour: [0, 0, 255] };
        let over = overlay(&g, &[layer]);
        assert_eq!((over.width() as usize, over.height() as usize), (img.width, img.height));
        assert_eq!(over.get_pixel(10, 15).0, [0, 0, 255]);
        assert_eq!(over.get_pixel(11, 15).0, [245; 3]);
        // Placed one metre (20 cells) to the right: the wall is drawn there instead.
        let moved = OverlayLayer { placement: crate::pose(1.0, 0.0, 0.0), ..layer };
        let over = overlay(&g, &[moved]);
        assert_eq!(over.get_pixel(10, 15).0, [150; 3]);
        assert_eq!(over.get_pixel(30, 15).0, [0, 0, 255]);
    }

    fn yaml(text: &str) -> Result<MapYaml, MapIoError> {
        parse_map_yaml(text, Path::new("m.yaml"))
    }

    fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    fn sample_grid() -> OccupancyGrid {
        let mut g = OccupancyGrid::new(7, 5, 0.05, pose(-1.0, 2.5, 0.25)).unwrap();
        for iy in 0..5 {
            for ix in 0..7 {
                let l = match (ix + 2 * iy) % 3 {
                    0 => ROS_LOGODDS_LIMIT,
                    1 => -ROS_LOGODDS_LIMIT,
                    _ => 0.0,
                };
                g.set(ix, iy, l);
            }
        }
        g
    }

    #[test]
    fn write_then_read_gives_same_cells() {
        let dir = tempfile::tempdir().unwrap();
        let g = sample_grid();
        let p = dir.path().join("map.yaml");
        write_ros_map(&g, &p).unwrap();
        let back = read_ros_map(&p).unwrap();
        assert_eq!(back.cells(), g.cells());
        assert_eq!((back.width(), back.height()), (7, 5));
        let crate::se2::Xyt { x, y, theta: t } = crate::se2::Xyt::from_pose(back.origin());
        assert!((x + 1.0).abs() < 1e-12 && (y - 2.5).abs() < 1e-12 && (t - 0.25).abs() < 1e-12);
        assert!(dir.path().join("map.pgm").exists());
        // no temporary files left behind
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
    }

    #[test]
    fn scan_built_grid_survives_round_trip_by_state() {
        let mut g = OccupancyGrid::new(10, 10, 0.1, pose(0.0, 0.0, 0.0)).unwrap();
        let scan = crate::scan::LaserScan {
            stamp: 0.0,
            angle_min: -1.0,
            angle_increment: 0.05,
            range_min: 0.05,
            range_max: 3.0,
            ranges: vec![0.8; 40],
        };
        for _ in 0..3 {
            g.integrate_scan(&scan, &pose(0.5, 0.5, 0.3), &LogOddsParams::default()).unwrap();
        }
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.yaml");
        write_ros_map(&g, &p).unwrap();
        let back = read_ros_map(&p).unwrap();
        for iy in 0..g.height() {
            for ix in 0..g.width() {
                assert_eq!(back.state(ix, iy), g.state(ix, iy));
            }
        }
    }

    #[test]
    fn reads_both_pgm_kinds_with_negate_and_thresholds() {
        let dir = tempfile::tempdir().unwrap();
        // 4x1 pixels: black, dark grey 100, light grey 205, white. p = (255 - v)/255 = 1, .61, .196, 0
        let p5 = [b"P5\n4 1\n255\n".as_slice(), &[0u8, 100, 205, 255]].concat();
        write(dir.path(), "b.pgm", &p5);
        write(dir.path(), "a.pgm", b"P2\n# ascii\n4 1\n15\n0 6 12 15\n");
        let meta = "resolution: 0.1\norigin: [0, 0, 0]\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
        for (img, negate, expect) in [
            ("b.pgm", 0, [100, -1, -1, 0]),
            ("b.pgm", 1, [0, -1, 100, 100]),
            // maxval 15: 0 6 12 15 scale to 0 102 204 255, p = 1, .6, .2, 0
            ("a.pgm", 0, [100, -1, -1, 0]),
        ] {
            let y = write(dir.path(), "m.yaml", format!("image: {img}\nnegate: {negate}\n{meta}").as_bytes());
            let g = read_ros_map(&y).unwrap();
            let got: Vec<i8> = g
                .to_ros_int8()
                .iter()
                .map(|&v| {
                    if v == -1 {
                        -1
                    } else if v > 50 {
                        100
                    } else {
                        0
                    }
                })
                .collect();
            let expect: Vec<i8> = expect.iter().map(|&v| v as i8).collect();
            assert_eq!(got, expect, "{img} negate {negate}");
        }
    }

    #[test]
    fn scale_and_raw_modes() {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), "r.pgm", &[b"P5 3 1 255\n".as_slice(), &[0u8, 100, 255]].concat());
        let y = write(dir.path(), "r.yaml", b"image: r.pgm\nresolution: 1\norigin: [0,0,0]\nmode: raw\n");
        let g = read_ros_map(&y).unwrap();
        assert_eq!(g.to_ros_int8(), vec![0, 100, -1]);
        write(dir.path(), "s.pgm", &[b"P5 3 1 255\n".as_slice(), &[0u8, 110, 255]].concat());
        let y = write(dir.path(), "s.yaml", b"image: s.pgm\nresolution: 1\norigin: [0,0,0]\nmode: scale\n");
        let g = read_ros_map(&y).unwrap();
        let v = g.to_ros_int8();
        assert_eq!((v[0], v[2]), (100, 0));
        assert!(v[1] > 0 && v[1] < 100, "graded value kept: {}", v[1]);
    }

    #[test]
    fn yaml_errors_name_line_and_field() {
        let e = yaml("image: m.pgm\norigin: [0, 0, 0]\n").unwrap_err().to_string();
        assert!(e.contains("m.yaml") && e.contains("missing required field `resolution`"), "{e}");
        let e = yaml("image: m.pgm\nresolution: -0.05\norigin: [0, 0, 0]\n").unwrap_err().to_string();
        assert!(e.contains("m.yaml:2") && e.contains("`resolution`") && e.contains("positive"), "{e}");
        let e = yaml("image: m.pgm\nresolution: 0\norigin: [0, 0, 0]\n").unwrap_err().to_string();
        assert!(e.contains("m.yaml:2"), "{e}");
        let e = yaml("image: m.pgm\nresolution: 0.05\norigin: [0, 0]\n").unwrap_err().to_string();
        assert!(e.contains("m.yaml:3") && e.contains("`origin`"), "{e}");
        let e = yaml("image: m.pgm\nresolution: abc\n").unwrap_err().to_string();
        assert!(e.contains("m.yaml:2") && e.contains("finite number"), "{e}");
        let e = yaml("# c\nimage m.pgm\n").unwrap_err().to_string();
        assert!(e.contains("m.yaml:2") && e.contains("key: value"), "{e}");
        let ok =
            yaml("image: 'my map.pgm'  # the map\nresolution: 0.05\norigin: [1, 2, 0.5]\nmode: trinary\n").unwrap();
        assert_eq!(ok.image, "my map.pgm");
        assert_eq!(ok.origin, [1.0, 2.0, 0.5]);
    }

    #[test]
    fn any_yaml_map_server_reads_is_read_and_unknown_keys_are_reported() {
        let block = "image: \"m.pgm\"\nresolution: 0.05\norigin:\n  - -10.0\n  - -10.0\n  - 0.0\nnegate: 0\n";
        assert_eq!(yaml(block).unwrap().origin, [-10.0, -10.0, 0.0]);
        let flow = yaml("{image: m.pgm, resolution: '0.1', origin: [1, 2, 3], free_thresh: 0.2}").unwrap();
        assert_eq!((flow.resolution, flow.free_thresh), (0.1, 0.2));
        let mut warnings = Vec::new();
        let m = parse_map_yaml_with(
            "image: m.pgm\nresolutoin: 0.1\nresolution: 0.05\norigin: [0, 0, 0]\n",
            Path::new("m.yaml"),
            &mut |w| warnings.push(w),
        )
        .unwrap();
        assert_eq!(m.resolution, 0.05);
        assert_eq!(warnings.len(), 1);
        assert!(warnings[0].starts_with("m.yaml:2: unknown key `resolutoin` ignored"), "{warnings:?}");
        let e = yaml("image: m.pgm\nimage: n.pgm\n").unwrap_err().to_string();
        assert!(e.contains("m.yaml:2") && e.contains("duplicate"), "{e}");
        let e = yaml("image: [m.pgm\n").unwrap_err().to_string();
        assert!(e.starts_with("m.yaml:"), "{e}");
        assert!(yaml("").is_err() && yaml("- a\n- b\n").is_err());
    }

    #[test]
    fn image_errors_name_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let y = write(dir.path(), "m.yaml", b"image: gone.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n");
        let e = read_ros_map(&y).unwrap_err().to_string();
        assert!(e.contains("gone.pgm") && e.starts_with(&format!("{}:1: field `image`: ", y.display())), "{e}");
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
    fn reads_png_maps() {
        let dir = tempfile::tempdir().unwrap();
        let img = GreyImage { width: 2, height: 2, pixels: vec![0, 254, 205, 254] };
        let p = dir.path().join("m.png");
        std::fs::write(&p, encode_png(&img, &p).unwrap()).unwrap();
        assert_eq!(read_grey_image(&p).unwrap(), img);
    }
}
