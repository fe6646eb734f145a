//! World files: TOML descriptions of walls, furniture, named points and an optional bitmap layer.
//!
//! ```toml
//! name = "example"
//! [[walls]]                      # a polyline of wall segments, `thickness` metres thick (default 0.1)
//! points = [[0, 0], [10, 0], [10, 5]]
//! thickness = 0.15
//! [[boxes]]                      # an oriented rectangle: centre, full size, angle (radians, default 0)
//! center = [2, 1]
//! size = [1.2, 0.6]
//! angle = 0.3
//! [[circles]]                    # a disc (pillar, bin, water cooler)
//! center = [5, 2]
//! radius = 0.2
//! [[polygons]]                   # a simple polygon, at least 3 points, non-zero area
//! points = [[7, 1], [8, 1], [7.5, 2]]
//! [named_points]                 # poses: x, y (metres), theta (radians, default 0)
//! start_experia = { x = 1, y = 1, theta = 0 }
//! [bitmap]                       # optional: a ROS map_server map; occupied cells become obstacles
//! map = "floor.yaml"             # relative to the world file
//! unknown = "free"               # the map's unknown cells: "free" (default) or "occupied" (a closed building)
//! min_obstacle_cells = 1         # occupied groups of fewer cells are freed (specks a SLAM map keeps); default 1
//! ```

use crate::error::SimError;
use crate::geometry::{polygon_self_intersects, signed_area};
use mrslam_core::{OccupancyGrid, Pose2, pose};
use nalgebra::Point2;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use toml::Spanned;

/// The largest coordinate or size a world file may hold, metres: the map reader's bound on a map's origin.
pub const MAX_WORLD_COORDINATE: f64 = mrslam_core::map_io::MAX_COORDINATE;

/// A polyline of wall segments with a thickness.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WallSpec {
    /// Vertices of the polyline (centre line of the wall), metres; at least 2.
    pub points: Vec<[f64; 2]>,
    /// Wall thickness, metres (default 0.1).
    #[serde(default = "default_thickness")]
    pub thickness: f64,
}

fn default_thickness() -> f64 {
    0.1
}

/// An oriented rectangular obstacle.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxSpec {
    /// Centre, metres.
    pub center: [f64; 2],
    /// Full size along the box's own x and y axes, metres.
    pub size: [f64; 2],
    /// Orientation, radians (default 0).
    #[serde(default)]
    pub angle: f64,
}

/// A disc obstacle.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CircleSpec {
    /// Centre, metres.
    pub center: [f64; 2],
    /// Radius, metres.
    pub radius: f64,
}

/// A simple polygon obstacle (convex or not).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PolygonSpec {
    /// Vertices, metres; at least 3, non-zero area, no self-intersection.
    pub points: Vec<[f64; 2]>,
}

/// A named pose: a start, the common end point, a waypoint.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NamedPoint {
    /// x, metres.
    pub x: f64,
    /// y, metres.
    pub y: f64,
    /// Heading, radians (default 0).
    #[serde(default)]
    pub theta: f64,
}

impl NamedPoint {
    /// The point as a pose.
    pub fn pose(&self) -> Pose2 {
        pose(self.x, self.y, self.theta)
    }
}

/// The bitmap layer as written in the file.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
struct BitmapSpec {
    map: String,
    unknown: Option<String>,
    min_obstacle_cells: Option<usize>,
}

/// A loaded bitmap layer: a ROS map whose occupied cells are obstacles.
#[derive(Debug, Clone, PartialEq)]
pub struct BitmapLayer {
    /// The map's YAML file.
    pub map: PathBuf,
    /// The map; cells in state Occupied become obstacles.
    pub grid: OccupancyGrid,
}

/// A parsed and validated world description.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct WorldSpec {
    /// Name of the world.
    pub name: String,
    /// Free-text description.
    pub description: String,
    /// Wall polylines.
    pub walls: Vec<WallSpec>,
    /// Rectangular obstacles.
    pub boxes: Vec<BoxSpec>,
    /// Disc obstacles.
    pub circles: Vec<CircleSpec>,
    /// Polygon obstacles.
    pub polygons: Vec<PolygonSpec>,
    /// Named poses (starts, the common end point, ...).
    pub named_points: BTreeMap<String, NamedPoint>,
    /// Optional bitmap layer.
    pub bitmap: Option<BitmapLayer>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawWorld {
    #[serde(default)]
    name: String,
    #[serde(default)]
    description: String,
    #[serde(default)]
    walls: Vec<Spanned<WallSpec>>,
    #[serde(default)]
    boxes: Vec<Spanned<BoxSpec>>,
    #[serde(default)]
    circles: Vec<Spanned<CircleSpec>>,
    #[serde(default)]
    polygons: Vec<Spanned<PolygonSpec>>,
    #[serde(default)]
    named_points: BTreeMap<String, Spanned<NamedPoint>>,
    bitmap: Option<Spanned<BitmapSpec>>,
}

/// Where each element of a world came from, so semantic errors can name a line.
#[derive(Default)]
struct Spans {
    text: String,
    walls: Vec<Range<usize>>,
    boxes: Vec<Range<usize>>,
    circles: Vec<Range<usize>>,
    polygons: Vec<Range<usize>>,
    named_points: BTreeMap<String, Range<usize>>,
}

impl Spans {
    /// 1-based line of `field` inside the element spanning `span` (0 when unknown).
    fn line(&self, span: Option<&Range<usize>>, field: &str) -> usize {
        let Some(span) = span else { return 0 };
        let start = span.start.min(self.text.len());
        // A `[[table]]` element's span may cover only its header: its body runs to the next header.
        let rest = self.text.get(start..).unwrap_or("");
        let first_nl = rest.find('\n').map_or(rest.len(), |i| i + 1);
        let mut end = start + first_nl;
        for l in rest[first_nl..].split_inclusive('\n') {
            if l.trim_start().starts_with('[') {
                break;
            }
            end += l.len();
        }
        let end = end.max(span.end.min(self.text.len()));
        let body = self.text.get(start..end).unwrap_or("");
        let off = find_key(body, field).unwrap_or(0);
        line_of(&self.text, start + off)
    }
}

/// Byte offset of `key` used as a key (followed by `=`) in `body`.
fn find_key(body: &str, key: &str) -> Option<usize> {
    let mut from = 0;
    while let Some(i) = body[from..].find(key) {
        let at = from + i;
        let before_ok =
            at == 0 || body[..at].chars().next_back().is_some_and(|c| c.is_whitespace() || c == '{' || c == ',');
        let after = body[at + key.len()..].trim_start();
        if before_ok && after.starts_with('=') {
            return Some(at);
        }
        from = at + key.len();
    }
    None
}

/// 1-based line number of byte `offset` in `text`.
fn line_of(text: &str, offset: usize) -> usize {
    let offset = offset.min(text.len());
    text.as_bytes()[..offset].iter().filter(|&&b| b == b'\n').count() + 1
}

/// The key named on a line (`key = value`), or the line itself trimmed (`[[boxes]]`).
fn key_on_line(text: &str, line: usize) -> String {
    let l = text.lines().nth(line.saturating_sub(1)).unwrap_or("").trim();
    match l.split_once('=') {
        Some((k, _)) if !l.starts_with('[') => k.trim().to_string(),
        _ => l.to_string(),
    }
}

impl WorldSpec {
    /// Reads, parses and validates a world file (and loads its bitmap layer).
    pub fn from_toml_file(path: impl AsRef<Path>) -> Result<WorldSpec, SimError> {
        let path = path.as_ref();
        let text = mrslam_core::input::read_text_limited(path, mrslam_core::input::CONFIG_LIMIT)
            .map_err(|cause| SimError::Io { path: path.to_path_buf(), cause })?;
        Self::from_toml_str(&text, path)
    }

    /// Parses and validates world text; `path` names the file in errors and anchors the bitmap path.
    pub fn from_toml_str(text: &str, path: &Path) -> Result<WorldSpec, SimError> {
        let raw: RawWorld = toml::from_str(text).map_err(|e| {
            let line = e.span().map(|s| line_of(text, s.start)).unwrap_or(0);
            let field = if e.message().starts_with("unknown field") {
                e.span().and_then(|s| text.get(s)).map(|s| s.trim().to_string()).unwrap_or_default()
            } else {
                key_on_line(text, line)
            };
            SimError::WorldFile { path: path.to_path_buf(), line, field, message: e.message().trim().to_string() }
        })?;
        let mut spans = Spans { text: text.to_string(), ..Spans::default() };
        let walls = strip_vec(raw.walls, &mut spans.walls);
        let boxes = strip_vec(raw.boxes, &mut spans.boxes);
        let circles = strip_vec(raw.circles, &mut spans.circles);
        let polygons = strip_vec(raw.polygons, &mut spans.polygons);
        let named_points = raw
            .named_points
            .into_iter()
            .map(|(k, v)| {
                spans.named_points.insert(k.clone(), v.span());
                (k, v.into_inner())
            })
            .collect();
        let mut spec = WorldSpec {
            name: raw.name,
            description: raw.description,
            walls,
            boxes,
            circles,
            polygons,
            named_points,
            bitmap: None,
        };
        spec.check(path, &spans)?;
        if let Some(b) = raw.bitmap {
            let line = line_of(text, b.span().start);
            let b = b.into_inner();
            if b.map.trim().is_empty() {
                return Err(SimError::WorldFile {
                    path: path.to_path_buf(),
                    line,
                    field: "bitmap.map".into(),
                    message: "must name a map_server YAML file".into(),
                });
            }
            let closed = match b.unknown.as_deref() {
                None | Some("free") => false,
                Some("occupied") => true,
                Some(other) => {
                    return Err(SimError::WorldFile {
                        path: path.to_path_buf(),
                        line,
                        field: "bitmap.unknown".into(),
                        message: format!("expected \"free\" or \"occupied\", got \"{other}\""),
                    });
                }
            };
            let map = mrslam_core::map_io::resolve_image_path(path, &b.map);
            let mut grid = mrslam_core::map_io::read_ros_map(&map)
                .map_err(|cause| SimError::Bitmap { path: path.to_path_buf(), cause })?;
            if closed {
                // Unknown cells (log-odds 0) become walls: what the map's robot never saw is not driven into.
                grid.cells_mut()
                    .iter_mut()
                    .filter(|l| **l == 0.0)
                    .for_each(|l| *l = mrslam_core::map_io::ROS_LOGODDS_LIMIT);
            }
            // After closing: an unknown hole between beams, walled by the step above, is a speck too.
            if let Some(min) = b.min_obstacle_cells {
                crate::bitmap::drop_specks(&mut grid, min);
            }
            spec.bitmap = Some(BitmapLayer { map, grid });
        }
        Ok(spec)
    }

    /// Validates a world built in code (errors carry line 0 and the path `<spec>`).
    pub fn validate(&self) -> Result<(), SimError> {
        self.check(Path::new("<spec>"), &Spans::default())
    }

    /// The named pose `name`, if the world defines it.
    pub fn named_pose(&self, name: &str) -> Option<Pose2> {
        self.named_points.get(name).map(NamedPoint::pose)
    }

    fn check(&self, path: &Path, spans: &Spans) -> Result<(), SimError> {
        let err =
            |kind: &str, i: Option<usize>, span: Option<&Range<usize>>, field: &str, msg: String| SimError::WorldFile {
                path: path.to_path_buf(),
                line: spans.line(span, field),
                field: match i {
                    Some(i) => format!("{kind}[{i}].{field}"),
                    None => format!("{kind}.{field}"),
                },
                message: msg,
            };
        // Finite and within the bound: a coordinate or a size further out is a typo, and would overflow the grids
        // the simulator builds over the world.
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite() && x.abs() <= MAX_WORLD_COORDINATE);
        let far = |what: &str| format!("{what} must be finite and within {MAX_WORLD_COORDINATE:e} m of 0");
        for (i, w) in self.walls.iter().enumerate() {
            let s = spans.walls.get(i);
            if w.points.len() < 2 {
                return Err(err(
                    "walls",
                    Some(i),
                    s,
                    "points",
                    format!("a wall needs at least 2 points, got {}", w.points.len()),
                ));
            }
            if !w.points.iter().all(|p| finite(p)) {
                return Err(err("walls", Some(i), s, "points", far("coordinates")));
            }
            if let Some(k) = w.points.windows(2).position(|p| p[0] == p[1]) {
                return Err(err(
                    "walls",
                    Some(i),
                    s,
                    "points",
                    format!("points {k} and {} coincide (zero-length segment)", k + 1),
                ));
            }
            if !(finite(&[w.thickness]) && w.thickness > 0.0) {
                return Err(err(
                    "walls",
                    Some(i),
                    s,
                    "thickness",
                    format!("must be positive and at most {MAX_WORLD_COORDINATE:e} m, got {}", shown(w.thickness)),
                ));
            }
        }
        for (i, b) in self.boxes.iter().enumerate() {
            let s = spans.boxes.get(i);
            if !finite(&b.center) {
                return Err(err("boxes", Some(i), s, "center", far("the centre")));
            }
            if !(finite(&b.size) && b.size[0] > 0.0 && b.size[1] > 0.0) {
                return Err(err(
                    "boxes",
                    Some(i),
                    s,
                    "size",
                    format!(
                        "both sides must be positive and at most {MAX_WORLD_COORDINATE:e} m, got [{}, {}]",
                        shown(b.size[0]),
                        shown(b.size[1])
                    ),
                ));
            }
            if !b.angle.is_finite() {
                return Err(err("boxes", Some(i), s, "angle", "must be finite".into()));
            }
        }
        for (i, c) in self.circles.iter().enumerate() {
            let s = spans.circles.get(i);
            if !finite(&c.center) {
                return Err(err("circles", Some(i), s, "center", far("the centre")));
            }
            if !(finite(&[c.radius]) && c.radius > 0.0) {
                return Err(err(
                    "circles",
                    Some(i),
                    s,
                    "radius",
                    format!("must be positive and at most {MAX_WORLD_COORDINATE:e} m, got {}", shown(c.radius)),
                ));
            }
        }
        for (i, p) in self.polygons.iter().enumerate() {
            let s = spans.polygons.get(i);
            if p.points.len() < 3 {
                return Err(err(
                    "polygons",
                    Some(i),
                    s,
                    "points",
                    format!("a polygon needs at least 3 points, got {}", p.points.len()),
                ));
            }
            if !p.points.iter().all(|q| finite(q)) {
                return Err(err("polygons", Some(i), s, "points", far("coordinates")));
            }
            let pts = to_points(&p.points);
            if signed_area(&pts).abs() < 1e-9 {
                return Err(err("polygons", Some(i), s, "points", "degenerate polygon: zero area".into()));
            }
            if polygon_self_intersects(&pts) {
                return Err(err("polygons", Some(i), s, "points", "degenerate polygon: edges cross each other".into()));
            }
        }
        for (name, p) in &self.named_points {
            let s = spans.named_points.get(name);
            if !finite(&[p.x, p.y, p.theta]) {
                return Err(err("named_points", None, s, name, far("x, y and theta")));
            }
        }
        Ok(())
    }
}

/// A number as an error shows it: as written when ordinary, in scientific notation when huge (not 300 digits).
fn shown(v: f64) -> String {
    if v.abs() < 1e7 { v.to_string() } else { format!("{v:e}") }
}

fn strip_vec<T>(v: Vec<Spanned<T>>, spans: &mut Vec<Range<usize>>) -> Vec<T> {
    v.into_iter()
        .map(|x| {
            spans.push(x.span());
            x.into_inner()
        })
        .collect()
}

/// Converts `[x, y]` pairs to points.
pub(crate) fn to_points(v: &[[f64; 2]]) -> Vec<Point2<f64>> {
    v.iter().map(|p| Point2::new(p[0], p[1])).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<WorldSpec, SimError> {
        WorldSpec::from_toml_str(text, Path::new("test.toml"))
    }

    fn expect_err(text: &str, line: usize, field: &str) -> String {
        match parse(text) {
            Err(SimError::WorldFile { line: l, field: f, message, path }) => {
                assert_eq!(path, Path::new("test.toml"));
                assert_eq!((l, f.as_str()), (line, field), "message: {message}");
                message
            }
            other => panic!("expected a world-file error, got {other:?}"),
        }
    }

    const GOOD: &str = r#"
name = "t"
[[walls]]
points = [[0, 0], [4, 0], [4, 3]]
thickness = 0.2
[[boxes]]
center = [1, 1]
size = [0.5, 0.4]
[[circles]]
center = [3, 2]
radius = 0.1
[[polygons]]
points = [[2, 2], [3, 2], [2.5, 2.8]]
[named_points]
start = { x = 1, y = 2, theta = 0.5 }
end = { x = 3, y = 1 }
"#;

    #[test]
    fn parses_a_good_world() {
        let w = parse(GOOD).unwrap();
        assert_eq!(w.name, "t");
        assert_eq!(w.walls[0].points.len(), 3);
        assert_eq!(w.walls[0].thickness, 0.2);
        assert_eq!(w.boxes[0].angle, 0.0);
        assert_eq!(w.circles[0].radius, 0.1);
        assert_eq!(w.named_points["end"].theta, 0.0);
        assert!((w.named_pose("start").unwrap().rotation.angle() - 0.5).abs() < 1e-12);
        assert!(w.validate().is_ok());
    }

    #[test]
    fn unknown_key_names_line_and_field() {
        let t = GOOD.replace("radius = 0.1", "radius = 0.1\ncolour = \"red\"");
        let m = expect_err(&t, 12, "colour");
        assert!(m.contains("unknown field"), "{m}");
        let t = format!("gravity = 9.8\n{GOOD}");
        expect_err(&t, 1, "gravity");
    }

    #[test]
    fn wrong_type_names_line_and_field() {
        let t = GOOD.replace("size = [0.5, 0.4]", "size = \"big\"");
        expect_err(&t, 8, "size");
    }

    #[test]
    fn negative_and_zero_sizes_are_rejected() {
        expect_err(&GOOD.replace("size = [0.5, 0.4]", "size = [-0.5, 0.4]"), 8, "boxes[0].size");
        expect_err(&GOOD.replace("radius = 0.1", "radius = 0"), 11, "circles[0].radius");
        expect_err(&GOOD.replace("thickness = 0.2", "thickness = -1"), 5, "walls[0].thickness");
    }

    #[test]
    fn degenerate_polygons_are_rejected() {
        let m = expect_err(&GOOD.replace("[[2, 2], [3, 2], [2.5, 2.8]]", "[[2, 2], [3, 2]]"), 13, "polygons[0].points");
        assert!(m.contains("at least 3"));
        let m = expect_err(
            &GOOD.replace("[[2, 2], [3, 2], [2.5, 2.8]]", "[[2, 2], [3, 2], [4, 2]]"),
            13,
            "polygons[0].points",
        );
        assert!(m.contains("zero area"));
        let m = expect_err(
            &GOOD.replace("[[2, 2], [3, 2], [2.5, 2.8]]", "[[0, 0], [2, 2], [2, 0], [0, 1]]"),
            13,
            "polygons[0].points",
        );
        assert!(m.contains("cross"));
    }

    #[test]
    fn coordinates_and_sizes_past_the_bound_are_rejected() {
        for far in ["1e300", "1e100", "-2e7"] {
            let m = expect_err(
                &GOOD.replace("[[0, 0], [4, 0], [4, 3]]", &format!("[[0, 0], [{far}, 0]]")),
                4,
                "walls[0].points",
            );
            assert!(m.contains("within 1e7 m of 0"), "{m}");
            expect_err(&GOOD.replace("center = [3, 2]", &format!("center = [3, {far}]")), 10, "circles[0].center");
            expect_err(&GOOD.replace("center = [1, 1]", &format!("center = [{far}, 1]")), 7, "boxes[0].center");
            expect_err(
                &GOOD.replace("end = { x = 3, y = 1 }", &format!("end = {{ x = {far}, y = 1 }}")),
                16,
                "named_points.end",
            );
        }
        let m = expect_err(&GOOD.replace("radius = 0.1", "radius = 1e300"), 11, "circles[0].radius");
        assert!(m.ends_with("got 1e300"), "{m}");
        expect_err(&GOOD.replace("thickness = 0.2", "thickness = 1e300"), 5, "walls[0].thickness");
        expect_err(&GOOD.replace("size = [0.5, 0.4]", "size = [1e300, 0.4]"), 8, "boxes[0].size");
        assert!(parse(&GOOD.replace("[[0, 0], [4, 0], [4, 3]]", "[[0, 0], [1e7, 0]]")).is_ok());
    }

    #[test]
    fn degenerate_walls_are_rejected() {
        expect_err(&GOOD.replace("[[0, 0], [4, 0], [4, 3]]", "[[0, 0]]"), 4, "walls[0].points");
        expect_err(&GOOD.replace("[[0, 0], [4, 0], [4, 3]]", "[[0, 0], [0, 0]]"), 4, "walls[0].points");
    }

    #[test]
    fn bad_named_point_is_rejected() {
        expect_err(&GOOD.replace("end = { x = 3, y = 1 }", "end = { x = 3 }"), 16, "end");
        expect_err(&GOOD.replace("end = { x = 3, y = 1 }", "end = { x = 3, y = nan }"), 16, "named_points.end");
    }

    #[test]
    fn syntax_error_names_line() {
        let t = GOOD.replace("radius = 0.1", "radius = ");
        match parse(&t) {
            Err(SimError::WorldFile { line, .. }) => assert_eq!(line, 11),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn missing_bitmap_file_is_an_error() {
        let t = format!("{GOOD}\n[bitmap]\nmap = \"does_not_exist.yaml\"\n");
        assert!(matches!(parse(&t), Err(SimError::Bitmap { .. })));
    }

    #[test]
    fn display_names_file_line_and_field() {
        let e = parse(&GOOD.replace("radius = 0.1", "radius = -2")).unwrap_err();
        let s = e.to_string();
        assert!(s.starts_with("test.toml:11: field `circles[0].radius`"), "{s}");
    }
}
