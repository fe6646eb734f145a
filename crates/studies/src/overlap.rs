//! Map-level studies: cut ground-truth maps into pairs of chosen overlap, merge each pair with every
//! algorithm through the verification gate, score against the pair's true transform.

use super::algorithms::check_algorithms;
use super::results::{TrialRow, sort_rows};
use super::shard::Shard;
use super::trial::{TrialSpec, mix, trials};
use super::{Progress, StudyError};
use mrslam_core::{CellState, OccupancyGrid};
use mrslam_merge::floorplan::{FloorplanParams, generate};
use mrslam_merge::pairs::{PairSpec, cut_pair};
use mrslam_merge::{Algorithm, Encoding, MergeParams, MergerConfig, merge};
use mrslam_testbed::eval::transform_error;
use rayon::prelude::*;

/// Where a study's ground-truth maps come from.
#[derive(Debug, Clone)]
pub enum MapSource {
    /// `count` procedurally generated floor plans; repetition `rep` of every overlap uses plan `rep % count`.
    Floorplans {
        /// How many distinct plans.
        count: usize,
        /// Their shape.
        params: FloorplanParams,
    },
    /// One map for every trial: a world's true map, or a real map.
    Map(OccupancyGrid),
}

/// A map-level study.
#[derive(Debug, Clone)]
pub struct OverlapStudy {
    /// Ground-truth maps.
    pub source: MapSource,
    /// Target overlaps (Jaccard of the halves' known cells).
    pub overlaps: Vec<f64>,
    /// Trials per overlap.
    pub trials: usize,
    /// Algorithms, in the order rows are written.
    pub algorithms: Vec<Algorithm>,
    /// Study seed.
    pub seed: u64,
    /// Success: rotation error at most this, degrees.
    pub max_rotation_deg: f64,
    /// Success: translation error at most this many cells of the map.
    pub max_translation_cells: f64,
    /// Largest shift of the moved half, metres.
    pub max_shift_m: f64,
    /// Which trials this process runs.
    pub shard: Shard,
    /// How the pair's maps store their walls.
    pub style: MapStyle,
    /// The SIFT merger's map-to-image encoding.
    pub encoding: Encoding,
}

/// How a pair's maps store their walls.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MapStyle {
    /// As cut: walls are occupied cells.
    #[default]
    Walls,
    /// Walls dropped to unknown in both maps, as map_server reads a map whose walls were stored light grey (between
    /// its thresholds) or as glass leaves them: the structure is only the boundary between free and unknown.
    Boundary,
}

impl MapStyle {
    /// The style's name on the command line and in study.json.
    pub fn name(self) -> &'static str {
        match self {
            MapStyle::Walls => "walls",
            MapStyle::Boundary => "boundary",
        }
    }

    /// Puts `grid` in this style (in place).
    pub fn apply(self, grid: &mut OccupancyGrid) {
        if self == MapStyle::Boundary {
            for y in 0..grid.height() {
                for x in 0..grid.width() {
                    if grid.state(x, y) == CellState::Occupied {
                        grid.set(x, y, 0.0);
                    }
                }
            }
        }
    }
}

/// The most trials per overlap a study takes (a million trials of a study take days).
pub const MAX_TRIALS: usize = 100_000;

/// The most trials a study takes in all, overlaps times trials.
pub const MAX_STUDY_TRIALS: usize = 1_000_000;

/// The most generated floor plans a study takes.
pub const MAX_FLOORPLANS: usize = 10_000;

impl OverlapStudy {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), StudyError> {
        let bad = |m: String| Err(StudyError::Invalid(m));
        if !(1..=MAX_TRIALS).contains(&self.trials) {
            return bad(format!("--trials {}: must be from 1 to {MAX_TRIALS}", self.trials));
        }
        if self.overlaps.is_empty() {
            return bad("no overlaps to study".into());
        }
        let total = self.overlaps.len().saturating_mul(self.trials);
        if total > MAX_STUDY_TRIALS {
            return bad(format!(
                "{} overlaps x {} trials = {total} trials; a study runs at most {MAX_STUDY_TRIALS} (shards included)",
                self.overlaps.len(),
                self.trials
            ));
        }
        check_algorithms(&self.algorithms)?;
        if let MapSource::Floorplans { count, .. } = self.source
            && !(1..=MAX_FLOORPLANS).contains(&count)
        {
            return bad(format!("--floorplans {count}: must be from 1 to {MAX_FLOORPLANS}"));
        }
        if !(self.max_rotation_deg >= 0.0 && self.max_translation_cells >= 0.0 && self.max_shift_m >= 0.0) {
            return bad("success thresholds and the shift must not be negative".into());
        }
        if self.max_shift_m > mrslam_merge::pairs::MAX_SHIFT_M {
            return bad(format!(
                "--max-shift {}: must be at most {} m",
                self.max_shift_m,
                mrslam_merge::pairs::MAX_SHIFT_M
            ));
        }
        Ok(())
    }

    /// The trials this shard runs, in index order.
    pub fn selected_trials(&self) -> Vec<TrialSpec> {
        trials(self.seed, &self.overlaps, self.trials).into_iter().filter(|t| self.shard.selects(t.trial)).collect()
    }
}

/// The true map of a world file at `resolution` metres per cell.
pub fn world_truth(path: &std::path::Path, resolution: f64) -> Result<OccupancyGrid, StudyError> {
    let spec = mrslam_sim::WorldSpec::from_toml_file(path).map_err(|e| StudyError::file(path, e))?;
    let world = mrslam_sim::World::from_spec(&spec).map_err(|e| StudyError::file(path, e))?;
    world.true_map(resolution).map_err(|e| StudyError::file(path, e))
}

/// The seed of floor plan `k` of a study seeded `seed`.
pub fn floorplan_seed(seed: u64, k: usize) -> u64 {
    mix(mix(seed ^ 0xf100_4b1a_0000_0000) ^ k as u64)
}

/// Runs the study's trials of this shard in parallel, calling `progress` after each; rows sorted by trial,
/// then algorithm in the study's order.
pub fn run_overlap_study(study: &OverlapStudy, progress: &dyn Progress) -> Result<Vec<TrialRow>, StudyError> {
    study.validate()?;
    let selected: Vec<TrialSpec> = study.selected_trials().into_iter().filter(|t| !progress.skip(t.trial)).collect();
    let plans: Vec<Option<OccupancyGrid>> = match &study.source {
        MapSource::Floorplans { count, params } => {
            // Only the plans this shard uses.
            let used: Vec<usize> = (0..*count).filter(|k| selected.iter().any(|t| t.rep % count == *k)).collect();
            let built: Vec<(usize, OccupancyGrid)> =
                used.par_iter().map(|&k| (k, generate(floorplan_seed(study.seed, k), params))).collect();
            let mut v = vec![None; *count];
            for (k, g) in built {
                v[k] = Some(g);
            }
            v
        }
        MapSource::Map(g) => vec![Some(g.clone())],
    };
    let rows: Vec<Vec<TrialRow>> = selected
        .par_iter()
        .map(|t| {
            // Every plan a selected trial uses was built above.
            let r = plans[t.rep % plans.len()].as_ref().map(|map| run_trial(study, map, t)).unwrap_or_default();
            progress.finished(&r)?;
            Ok(r)
        })
        .collect::<Result<_, StudyError>>()?;
    let mut rows: Vec<TrialRow> = rows.into_iter().flatten().collect();
    sort_rows(&mut rows, &study.algorithms);
    Ok(rows)
}

/// One trial: cut the pair, merge it with every algorithm, score.
fn run_trial(study: &OverlapStudy, map: &OccupancyGrid, t: &TrialSpec) -> Vec<TrialRow> {
    let spec = PairSpec { overlap: t.overlap_target, max_shift_m: study.max_shift_m, rotate: true };
    let mut pair = cut_pair(map, &spec, t.seed);
    study.style.apply(&mut pair.a);
    study.style.apply(&mut pair.b);
    let max_translation_m = study.max_translation_cells * map.resolution();
    study
        .algorithms
        .iter()
        .map(|&algorithm| {
            // Every random draw of the merger follows the trial's seed.
            let merger = MergerConfig { encoding: study.encoding, ..MergerConfig::new(algorithm, t.seed) }.build();
            let out = merge(merger.as_ref(), &pair.a, &pair.b, &MergeParams::default());
            let err = out.report.transform.map(|x| transform_error(&x.to_pose(), &pair.t_a_b));
            let accepted = out.report.accepted;
            let success = accepted
                && err.is_some_and(|(r, d)| r.to_degrees() <= study.max_rotation_deg && d <= max_translation_m);
            TrialRow {
                trial: t.trial,
                overlap_target: Some(t.overlap_target),
                overlap: pair.overlap,
                seed: t.seed,
                algorithm: algorithm.to_string(),
                accepted,
                success,
                false_merge: accepted && !success,
                rotation_error_deg: err.map(|e| e.0.to_degrees()),
                translation_error_m: err.map(|e| e.1),
                time_ms: out.report.time_ms,
                rotation_error_at_end_deg: None,
                translation_error_at_end_m: None,
                stage: out.report.stage.clone().unwrap_or_default(),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_boundary_style_drops_the_walls_and_keeps_the_rest() {
        let plan = generate(5, &FloorplanParams { width_m: 10.0, height_m: 8.0, ..FloorplanParams::default() });
        let cells = |g: &OccupancyGrid, s: CellState| {
            (0..g.height())
                .flat_map(|y| (0..g.width()).map(move |x| (x, y)))
                .filter(|&(x, y)| g.state(x, y) == s)
                .count()
        };
        assert!(cells(&plan, CellState::Occupied) > 100);
        let mut b = plan.clone();
        MapStyle::Boundary.apply(&mut b);
        assert_eq!(cells(&b, CellState::Occupied), 0);
        assert_eq!(cells(&b, CellState::Free), cells(&plan, CellState::Free));
        let mut w = plan.clone();
        MapStyle::Walls.apply(&mut w);
        assert_eq!(w, plan);
    }

    fn small() -> OverlapStudy {
        OverlapStudy {
            source: MapSource::Floorplans {
                count: 2,
                params: FloorplanParams { width_m: 10.0, height_m: 8.0, ..FloorplanParams::default() },
            },
            overlaps: vec![0.3, 0.6],
            trials: 2,
            algorithms: vec![Algorithm::Sift],
            seed: 3,
            max_rotation_deg: 2.0,
            max_translation_cells: 2.0,
            max_shift_m: 3.0,
            shard: Shard::ALL,
            style: MapStyle::Walls,
            encoding: Encoding::default(),
        }
    }

    #[test]
    fn shards_compute_the_rows_of_the_whole() {
        let whole = run_overlap_study(&small(), &()).unwrap();
        assert_eq!(whole.len(), 4);
        let mut parts = Vec::new();
        for k in 0..2 {
            let s = OverlapStudy { shard: Shard::new(k, 2).unwrap(), ..small() };
            parts.extend(run_overlap_study(&s, &()).unwrap());
        }
        sort_rows(&mut parts, &[Algorithm::Sift]);
        let strip = |r: &TrialRow| TrialRow { time_ms: 0.0, ..r.clone() };
        assert_eq!(whole.iter().map(strip).collect::<Vec<_>>(), parts.iter().map(strip).collect::<Vec<_>>());
        for r in &whole {
            assert!((r.overlap - r.overlap_target.unwrap()).abs() < 0.02, "{r:?}");
            assert_eq!(r.false_merge, r.accepted && !r.success);
        }
    }

    #[test]
    fn bad_parameters_are_refused() {
        assert!(run_overlap_study(&OverlapStudy { trials: 0, ..small() }, &()).is_err());
        let e = run_overlap_study(&OverlapStudy { algorithms: vec![], ..small() }, &());
        assert!(e.unwrap_err().to_string().contains("no algorithms"));
        let twice = vec![Algorithm::Rmap, Algorithm::Rmap];
        let e = run_overlap_study(&OverlapStudy { algorithms: twice, ..small() }, &());
        assert!(e.unwrap_err().to_string().contains("given twice"));
    }
}
