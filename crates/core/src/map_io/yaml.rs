//! The map_server YAML file: its fields, read with a YAML parser (errors name the line and the field, keys
//! map_server ignores are reported), and written.

use super::error::MapIoError;
use crate::grid::OccupancyGrid;
use crate::se2::Pose2;
use std::fmt::Write as _;
use std::path::Path;

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

/// The coarsest map resolution read, metres per pixel: a pixel larger than a building is a typo.
pub const MAX_RESOLUTION: f64 = 100.0;

/// The finest map resolution read, metres per pixel (0.1 mm): a finer pixel is a typo, and a map at it would
/// need billions of cells to be merged with a map of any robot's resolution.
pub const MIN_RESOLUTION: f64 = 1e-4;

/// The largest origin coordinate read, metres (ten thousand kilometres).
pub const MAX_COORDINATE: f64 = 1e7;

/// The keys map_server reads from a map YAML.
pub const MAP_YAML_KEYS: &[&str] =
    &["image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh", "mode"];

/// Parses the text of a map_server YAML file; `path` only names the file in errors.
pub fn parse_map_yaml(text: &str, path: &Path) -> Result<MapYaml, MapIoError> {
    parse_map_yaml_with(text, path, &mut |_| {})
}

/// The 1-based line where top-level `key` is written (`key:` at the start of a line, quoted or not; 0 when
/// not found, as in a one-line flow mapping).
pub(super) fn key_line(text: &str, key: &str) -> usize {
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
                if !(MIN_RESOLUTION..=MAX_RESOLUTION).contains(&r) {
                    return Err(bad(
                        "resolution",
                        format!(
                            "must be between {MIN_RESOLUTION} and {MAX_RESOLUTION} metres per pixel, found {}",
                            shown()
                        ),
                    ));
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
                    if slot.abs() > MAX_COORDINATE {
                        return Err(bad("origin", format!("{t}: further than {MAX_COORDINATE:e} m from 0")));
                    }
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

#[cfg(test)]
mod tests {
    use super::*;

    fn yaml(text: &str) -> Result<MapYaml, MapIoError> {
        parse_map_yaml(text, Path::new("m.yaml"))
    }

    #[test]
    fn absurd_scales_are_refused() {
        let e = yaml("image: m.pgm\nresolution: 1e300\norigin: [0, 0, 0]\n").unwrap_err().to_string();
        assert!(e.contains("m.yaml:2") && e.contains("and 100 metres per pixel, found 1e300"), "{e}");
        for tiny in ["1e-5", "1e-20", "0"] {
            let e = yaml(&format!("image: m.pgm\nresolution: {tiny}\norigin: [0, 0, 0]\n")).unwrap_err().to_string();
            assert!(e.contains("m.yaml:2") && e.contains("between 0.0001 and 100 metres per pixel"), "{e}");
        }
        assert!(yaml("image: m.pgm\nresolution: 1e-4\norigin: [0, 0, 0]\n").is_ok());
        let e = yaml("image: m.pgm\nresolution: 0.05\norigin: [1e300, 0, 0]\n").unwrap_err().to_string();
        assert!(e.contains("m.yaml:3") && e.contains("further than 1e7 m"), "{e}");
        assert!(yaml("image: m.pgm\nresolution: 100\norigin: [-1e7, 0, 0]\n").is_ok());
    }

    #[test]
    fn yaml_errors_name_line_and_field() {
        let e = yaml("image: m.pgm\norigin: [0, 0, 0]\n").unwrap_err().to_string();
        assert!(e.contains("m.yaml") && e.contains("missing required field `resolution`"), "{e}");
        let e = yaml("image: m.pgm\nresolution: -0.05\norigin: [0, 0, 0]\n").unwrap_err().to_string();
        assert!(e.contains("m.yaml:2") && e.contains("`resolution`") && e.contains("between 0.0001 and 100"), "{e}");
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
}
