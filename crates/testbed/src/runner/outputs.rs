//! A run's files: maps, the truth, merged maps with their pictures, and the report.

use super::options::{RunError, RunOutput};
use crate::scenario::Scenario;
use mrslam_core::Pose2;
use mrslam_core::map_io::{self, MapIoError};
use mrslam_merge::Algorithm;
use std::path::{Path, PathBuf};

/// The picture of a merge: the true map in grey, the host robot's map (blue) at its true frame, the other's
/// (orange) placed by the merge's estimate `t_a_b` from there, each with its SLAM path: where the estimate is
/// right, both robots' walls lie on the truth's.
///
/// A run without a merge pair (a team of one robot) shows the truth alone.
pub fn merge_overlay(out: &RunOutput, t_a_b: &Pose2) -> image::RgbImage {
    let Some([host, other]) = &out.report.merge_pair else { return map_io::overlay(&out.truth, &[]) };
    let frame = out.frames.get(host).copied().unwrap_or_else(Pose2::identity);
    let layer = |name: &String, placement: Pose2, colour: [u8; 3]| {
        out.maps.get(name).map(|map| map_io::OverlayLayer {
            map,
            placement,
            path: out.paths.get(name).map_or(&[][..], Vec::as_slice),
            colour,
        })
    };
    let layers: Vec<map_io::OverlayLayer> =
        [layer(host, frame, [30, 90, 220]), layer(other, frame * t_a_b, [235, 120, 20])]
            .into_iter()
            .flatten()
            .collect();
    map_io::overlay(&out.truth, &layers)
}

/// The files [`write_outputs`] may write into `dir` for `scenario` merged by `algorithms` (`None`: the
/// scenario's): each robot's map, the truth, each algorithm's merged map (each map's YAML, then its PGM and PNG
/// preview) and overlay picture, `report.json` last. A caller checks them against its inputs before a run.
pub fn output_files(scenario: &Scenario, algorithms: Option<&[Algorithm]>, dir: &Path) -> Vec<PathBuf> {
    let algorithms = algorithms.unwrap_or(&scenario.merge.algorithms);
    let maps = scenario
        .robots
        .iter()
        .map(|r| r.name.clone())
        .chain(["truth".to_string()])
        .chain(algorithms.iter().map(|a| format!("merged_{a}")));
    let mut files = Vec::new();
    for name in maps {
        let yaml = dir.join(format!("{name}.yaml"));
        files.extend([yaml.clone(), yaml.with_extension("pgm"), map_io::preview_path(&yaml)]);
    }
    files.extend(algorithms.iter().map(|a| dir.join(format!("overlay_{a}.png"))));
    files.push(dir.join("report.json"));
    files
}

/// Writes a run's maps (YAML+PGM, each with a PNG preview), the true map, merged maps with a picture of each
/// accepted merge over the truth (`overlay_<algorithm>.png`, see [`merge_overlay`]) and `report.json` (last)
/// into `dir`.
pub fn write_outputs(out: &RunOutput, dir: &Path) -> Result<(), RunError> {
    std::fs::create_dir_all(dir).map_err(|cause| MapIoError::Io { path: dir.to_path_buf(), cause })?;
    for (name, map) in &out.maps {
        map_io::write_ros_map_with_preview(map, &dir.join(format!("{name}.yaml")))?;
    }
    map_io::write_ros_map_with_preview(&out.truth, &dir.join("truth.yaml"))?;
    for m in &out.merges {
        let path = dir.join(format!("merged_{}.yaml", m.report.algorithm));
        let picture = dir.join(format!("overlay_{}.png", m.report.algorithm));
        match &m.merged {
            Some(g) => {
                map_io::write_ros_map_with_preview(g, &path)?;
                if let Some(t) = m.report.transform {
                    map_io::write_rgb_png(&merge_overlay(out, &t.to_pose()), &picture)?;
                }
            }
            None => {
                // A rejected merge leaves no map, not even a stale one from an earlier run.
                let _ = std::fs::remove_file(&path);
                let _ = std::fs::remove_file(path.with_extension("pgm"));
                let _ = std::fs::remove_file(map_io::preview_path(&path));
                let _ = std::fs::remove_file(&picture);
            }
        }
    }
    let json = serde_json::to_vec_pretty(&out.report).expect("reports serialise");
    mrslam_core::output::write_file_atomic(&dir.join("report.json"), &json).map_err(MapIoError::from)?;
    Ok(())
}
