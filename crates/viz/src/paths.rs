//! The entity paths of a recording (ARCHITECTURE.md, "Recordings"), built from parts so that any robot or
//! algorithm name is one path part whatever characters it holds.

use rerun::EntityPath;
use rerun::external::re_log_types::EntityPathPart;

/// Roots drawn in the world's frame; each carries the display flip (see the private `world` module).
pub const SPATIAL_ROOTS: [&str; 5] = ["world", "robots", "maps", "merge", "team"];

fn path(parts: &[&str]) -> EntityPath {
    EntityPath::new(parts.iter().map(|p| EntityPathPart::new(*p)).collect())
}

/// A root entity, e.g. `world`.
pub fn root(name: &str) -> EntityPath {
    path(&[name])
}

/// `world/walls`: the world's obstacles as outlines (static).
pub fn walls() -> EntityPath {
    path(&["world", "walls"])
}

/// `world/truth_map`: the true occupancy map (static).
pub fn truth_map() -> EntityPath {
    path(&["world", "truth_map"])
}

/// `robots/<name>/<leaf...>`, e.g. `robots/experia/slam/pose`.
pub fn robot(name: &str, leaf: &[&str]) -> EntityPath {
    let mut parts = vec!["robots", name];
    parts.extend_from_slice(leaf);
    path(&parts)
}

/// `maps/<name>`: a robot's SLAM map.
pub fn map(name: &str) -> EntityPath {
    path(&["maps", name])
}

/// `merge/<algorithm>/<leaf...>`, e.g. `merge/sift/keypoints/prawn`, `merge/sift/matches`, `merge/sift/merged`.
pub fn merge(algorithm: &str, leaf: &[&str]) -> EntityPath {
    let mut parts = vec!["merge", algorithm];
    parts.extend_from_slice(leaf);
    path(&parts)
}

/// `metrics/<group>/<series...>`, e.g. `metrics/neff/experia`, `metrics/error/experia/slam`.
pub fn metric(group: &str, series: &[&str]) -> EntityPath {
    let mut parts = vec!["metrics", group];
    parts.extend_from_slice(series);
    path(&parts)
}

/// `team/<leaf...>`: the team part of a run, e.g. `team/attempts` (the merge attempts as lines between the robots),
/// `team/events` (the attempts as text).
pub fn team(leaf: &[&str]) -> EntityPath {
    let mut parts = vec!["team"];
    parts.extend_from_slice(leaf);
    path(&parts)
}

/// `team/maps/<root>`: the map of the team whose root (the frame of its map) is robot `root`.
pub fn team_map(root: &str) -> EntityPath {
    path(&["team", "maps", root])
}

/// `events`: what happened, as text (resampling, collisions, merges accepted or rejected and why).
pub fn events() -> EntityPath {
    path(&["events"])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_print_as_designed() {
        assert_eq!(walls().to_string(), "/world/walls");
        assert_eq!(robot("experia", &["slam", "particles"]).to_string(), "/robots/experia/slam/particles");
        assert_eq!(merge("sift", &["keypoints", "prawn"]).to_string(), "/merge/sift/keypoints/prawn");
        assert_eq!(team_map("experia").to_string(), "/team/maps/experia");
        assert_eq!(team(&["attempts"]).to_string(), "/team/attempts");
        // A name with a slash stays one part.
        assert_eq!(map("a/b").len(), 2);
    }
}
