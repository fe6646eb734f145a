//! Mergers tried in turn, each answer through the verification gate: the fast answer first, the slow search only
//! for the pairs it could not settle.
//!
//! ```text
//! sift            the paper's merger on the maps (walls from the boundary of a map that marks none)
//! sift+boundary   the same with every map's free/unknown boundary as walls (maps that mark only some walls)
//! correlative     the global search (two robots' maps: doubled walls, doors, people; few shared features);
//!                 refused when a map does not mark its walls (`Merger::needs_marked_walls`)
//! ```
//!
//! The first answer the gate accepts is the merge; a pair every stage refuses is refused with each stage's reason.
//! With [`Cascade::side_by_side`], `sift+boundary` runs on another thread beside `sift` (the answer of `sift` still
//! comes first), so a pair both refuse costs one SIFT stage's wall time.
//! Each stage is a second chance for a wrong pose too, so the order and the stages were chosen by measuring false
//! merges on non-overlapping pairs alongside the successes (benchmarks/runs/2026-12-02-merge-cascade.md).

use crate::alignment::{Alignment, NoAlignment};
use crate::boundary_walls::{Boundary, BoundaryWalls};
use crate::contact::Contact;
use crate::correlative::{CorrelativeMerger, CorrelativeParams};
use crate::merge_params::MergeParams;
use crate::merger::{Merger, merge_bounded};
use crate::report::{MergeOutcome, refused};
use crate::sift_merger::{SiftMerger, SiftMergerParams};
use crate::timing::ms;
use mrslam_core::OccupancyGrid;
use std::collections::BTreeMap;
use std::time::Instant;

/// One stage of a [`Cascade`].
pub struct Stage {
    /// Its name in reports and timings (`sift`, `sift+boundary`, `correlative`).
    pub name: &'static str,
    /// The algorithm.
    pub merger: Box<dyn Merger>,
    /// Walls from the maps' boundaries for this stage instead of [`MergeParams::boundary_walls`]; such a stage
    /// runs only when the pipeline's mode is the default ([`BoundaryWalls::Unmarked`]): `Off` asks for the maps as
    /// they are, and `Always` already gave the first stage those walls. With `Always`, it is also skipped when
    /// neither map marks its walls: the first stage saw the same walls.
    pub boundary_walls: Option<BoundaryWalls>,
    /// Run on another thread at the same time as the stage before it, whose answer still comes first: for a stage
    /// about as cheap as that one (`sift+boundary` beside `sift`), so a pair both refuse costs one stage's wall time.
    pub beside_previous: bool,
}

/// Mergers tried in turn through the gate; the first accepted answer is the merge (`--algorithm cascade`).
pub struct Cascade {
    /// The stages, in the order they are tried.
    pub stages: Vec<Stage>,
}

impl Cascade {
    /// `sift`, `sift+boundary`, `correlative`, with these parameters.
    pub fn new(sift: SiftMergerParams, correlative: CorrelativeParams) -> Self {
        Cascade {
            stages: vec![
                Stage {
                    name: "sift",
                    merger: Box::new(SiftMerger::new(sift.clone())),
                    boundary_walls: None,
                    beside_previous: false,
                },
                Stage {
                    name: "sift+boundary",
                    merger: Box::new(SiftMerger::new(sift)),
                    boundary_walls: Some(BoundaryWalls::Always),
                    beside_previous: false,
                },
                Stage {
                    name: "correlative",
                    merger: Box::new(CorrelativeMerger::new(correlative)),
                    boundary_walls: None,
                    beside_previous: false,
                },
            ],
        }
    }

    /// The same cascade with each stage that gives the maps walls from their boundaries run beside the stage
    /// before it (`sift+boundary` beside `sift`): for maps `sift` rarely settles (robots' maps), where a refused
    /// pair then costs one SIFT stage's wall time; when `sift` does settle a pair, the answer waits for the stage
    /// beside it (a cut of a real map: 330 ms -> 0.8 s).
    pub fn side_by_side(mut self) -> Self {
        for s in &mut self.stages {
            s.beside_previous |= s.boundary_walls.is_some();
        }
        self
    }

    /// The stages that run under the pipeline's parameters, each with the parameters it runs with;
    /// `some_marked`: one of the maps marks its walls (else a stage with the boundary as walls sees what the first
    /// stage saw).
    fn active(&self, p: &MergeParams, some_marked: bool) -> impl Iterator<Item = (&Stage, MergeParams)> {
        self.stages.iter().filter_map(move |s| match s.boundary_walls {
            None => Some((s, *p)),
            Some(BoundaryWalls::Always) if !some_marked => None,
            Some(mode) if p.boundary_walls == BoundaryWalls::Unmarked => {
                Some((s, MergeParams { boundary_walls: mode, ..*p }))
            }
            Some(_) => None,
        })
    }
}

impl Default for Cascade {
    fn default() -> Self {
        Cascade::new(SiftMergerParams::default(), CorrelativeParams::default())
    }
}

impl Merger for Cascade {
    fn name(&self) -> &'static str {
        crate::Algorithm::Cascade.name()
    }

    /// Without the gate there is nothing to decide between stages: the first stage's answer that has one.
    fn align(&self, a: &OccupancyGrid, b: &OccupancyGrid) -> Result<Alignment, Box<NoAlignment>> {
        self.align_near(a, b, None)
    }

    fn align_near(
        &self,
        a: &OccupancyGrid,
        b: &OccupancyGrid,
        contact: Option<&Contact>,
    ) -> Result<Alignment, Box<NoAlignment>> {
        let mut last = None;
        for stage in &self.stages {
            match stage.merger.align_near(a, b, contact) {
                Ok(al) => return Ok(al),
                Err(no) => last = Some(no),
            }
        }
        Err(last.unwrap_or_else(|| {
            Box::new(NoAlignment {
                reason: NO_STAGES.into(),
                matches: 0,
                timings_ms: BTreeMap::new(),
                evidence: Default::default(),
            })
        }))
    }

    /// Each stage through the pipeline in turn, the first the gate accepts is the merge.
    fn merge(&self, a: &OccupancyGrid, b: &OccupancyGrid, p: &MergeParams) -> MergeOutcome {
        merge_cascade(self, a, b, p)
    }
}

/// Runs the cascade's stages in turn through the pipeline; the first accepted outcome, else the last refusal
/// with every stage's reason. Timings are prefixed by the stage (`correlative/search`), the report's `stage`
/// names the stage that decided.
pub(crate) fn merge_cascade(c: &Cascade, a: &OccupancyGrid, b: &OccupancyGrid, p: &MergeParams) -> MergeOutcome {
    let start = Instant::now();
    let mut timings = BTreeMap::new();
    let mut reasons = Vec::new();
    let mut last: Option<MergeOutcome> = None;
    // Each map's boundary found once for every stage (its walls, whether it marks them).
    let (ba, bb) = (Boundary::of(a), Boundary::of(b));
    let run = |(stage, params): &(&Stage, MergeParams)| {
        merge_bounded(stage.merger.as_ref(), (a, b), Some((&ba, &bb)), params, Instant::now())
    };
    let active: Vec<(&Stage, MergeParams)> = c.active(p, ba.marks_its_walls() || bb.marks_its_walls()).collect();
    let mut next = 0;
    'stages: while next < active.len() {
        // A stage and those that run beside it, their outcomes in the cascade's order.
        let group = 1 + active[next + 1..].iter().take_while(|(s, _)| s.beside_previous).count();
        let outcomes = match &active[next..next + group] {
            [one] => vec![run(one)],
            [first, rest @ ..] => {
                let (first, rest) = rayon::join(|| run(first), || rest.iter().map(run).collect::<Vec<_>>());
                std::iter::once(first).chain(rest).collect()
            }
            [] => Vec::new(),
        };
        for ((stage, _), mut out) in active[next..next + group].iter().zip(outcomes) {
            for (k, v) in std::mem::take(&mut out.report.timings_ms) {
                timings.insert(format!("{}/{k}", stage.name), v);
            }
            timings.insert(stage.name.to_string(), out.report.time_ms);
            out.report.stage = Some(stage.name.to_string());
            if out.report.accepted {
                last = Some(out);
                break 'stages;
            }
            reasons.push(format!("{}: {}", stage.name, out.report.reason.as_deref().unwrap_or("refused")));
            last = Some(out);
        }
        next += group;
    }
    let Some(mut out) = last else {
        return refused(c.name(), NO_STAGES.into(), 0, BTreeMap::new(), start);
    };
    if !out.report.accepted {
        out.report.reason = Some(reasons.join("; "));
    }
    out.report.algorithm = c.name().to_string();
    out.report.timings_ms = timings;
    out.report.time_ms = ms(start);
    out
}

/// Why an empty cascade finds nothing.
const NO_STAGES: &str = "a cascade without stages";

#[cfg(test)]
mod tests {
    use super::*;
    use crate::boundary_walls::marks_its_walls;
    use crate::merger::tests::{Fixed, room};
    use mrslam_core::{Pose2, pose};

    /// A cascade of fixed answers: (stage name, its answer, its boundary-walls override).
    fn cascade(stages: &[(&'static str, Pose2, Option<BoundaryWalls>)]) -> Cascade {
        let stage = |&(name, t, boundary_walls): &(&'static str, Pose2, Option<BoundaryWalls>)| Stage {
            name,
            merger: Box::new(Fixed(vec![t])),
            boundary_walls,
            beside_previous: false,
        };
        Cascade { stages: stages.iter().map(stage).collect() }
    }

    /// The room with its walls dropped to unknown: a map that does not mark its walls.
    fn bare_room() -> OccupancyGrid {
        let mut g = room(true);
        for y in 0..g.height() {
            for x in 0..g.width() {
                if g.state(x, y) == mrslam_core::CellState::Occupied {
                    g.set(x, y, 0.0);
                }
            }
        }
        g
    }

    #[test]
    fn a_stage_that_would_see_nothing_new_is_skipped_one_that_needs_marked_walls_refused() {
        let (g, bare) = (room(true), bare_room());
        assert!(marks_its_walls(&g) && !marks_its_walls(&bare));
        let off = pose(1.0, 0.0, 0.0);
        let mut c = cascade(&[("first", off, None), ("boundary", off, Some(BoundaryWalls::Always))]);
        c.stages.push(Stage {
            name: "marked",
            merger: Box::new(NeedsWalls(Fixed(vec![off]))),
            boundary_walls: None,
            beside_previous: false,
        });
        let ran = |a: &OccupancyGrid, b: &OccupancyGrid| -> Vec<&str> {
            let reason = crate::merge(&c, a, b, &MergeParams::default()).report.reason.unwrap();
            ["first", "boundary", "marked"].into_iter().filter(|n| reason.contains(&format!("{n}: "))).collect()
        };
        assert_eq!(ran(&g, &g), ["first", "boundary", "marked"]);
        // Neither map marks its walls: the first stage already had them from the boundary; the stage that needs
        // marked walls is refused.
        assert_eq!(ran(&bare, &bare), ["first", "marked"]);
        // One does: its boundary adds walls the first stage did not see; the correlative-like stage is refused.
        assert_eq!(ran(&g, &bare), ["first", "boundary", "marked"]);
        let reason = crate::merge(&c, &g, &bare, &MergeParams::default()).report.reason.unwrap();
        assert!(reason.contains("marked: map b does not mark its walls"), "{reason}");
    }

    /// A fixed answer from an algorithm that needs marked walls.
    struct NeedsWalls(Fixed);

    impl Merger for NeedsWalls {
        fn name(&self) -> &'static str {
            "needs-walls"
        }
        fn align(&self, a: &OccupancyGrid, b: &OccupancyGrid) -> Result<Alignment, Box<NoAlignment>> {
            self.0.align(a, b)
        }
        fn needs_marked_walls(&self) -> bool {
            true
        }
    }

    #[test]
    fn the_first_stage_the_gate_accepts_is_the_merge() {
        let g = room(true);
        let off = pose(1.0, 0.0, 0.0);
        let c = cascade(&[("first", off, None), ("second", Pose2::identity(), None), ("third", off, None)]);
        let unchecked = MergeParams { verify_enabled: false, ..MergeParams::default() };
        assert_eq!(crate::merge(&c, &g, &g, &unchecked).report.stage.as_deref(), Some("first"), "no gate: the first");
        let out = crate::merge(&c, &g, &g, &MergeParams::default());
        assert!(out.report.accepted, "{:?}", out.report.reason);
        assert_eq!(out.report.algorithm, "cascade");
        assert_eq!(out.report.stage.as_deref(), Some("second"));
        let t = out.report.transform.unwrap();
        assert!(t.x.abs() < 0.05 && t.y.abs() < 0.05, "{t:?}");
        assert!(out.merged.is_some());
        // Each stage run is timed under its name; the third never ran.
        assert!(out.report.timings_ms.contains_key("first") && out.report.timings_ms.contains_key("second"));
        assert!(out.report.timings_ms.keys().any(|k| k.starts_with("second/")));
        assert!(!out.report.timings_ms.contains_key("third"));
    }

    #[test]
    fn side_by_side_runs_the_boundary_stage_beside_sift_and_nothing_else() {
        let beside = |c: &Cascade| c.stages.iter().map(|s| (s.name, s.beside_previous)).collect::<Vec<_>>();
        assert_eq!(beside(&Cascade::default()), [("sift", false), ("sift+boundary", false), ("correlative", false)]);
        let side = Cascade::default().side_by_side();
        assert_eq!(beside(&side), [("sift", false), ("sift+boundary", true), ("correlative", false)]);
    }

    #[test]
    fn a_stage_run_beside_the_one_before_it_decides_only_when_that_one_refuses() {
        let g = room(true);
        let off = pose(1.0, 0.0, 0.0);
        let beside = |stages: &[(&'static str, Pose2)]| {
            let mut c = cascade(&stages.iter().map(|&(n, t)| (n, t, None)).collect::<Vec<_>>());
            c.stages[1].beside_previous = true;
            crate::merge(&c, &g, &g, &MergeParams::default()).report
        };
        // Both right: the first's answer, the second's unused (not timed).
        let r = beside(&[("first", Pose2::identity()), ("second", Pose2::identity()), ("third", off)]);
        assert_eq!(r.stage.as_deref(), Some("first"));
        assert!(!r.timings_ms.contains_key("second") && !r.timings_ms.contains_key("third"));
        // The first refused: the second's, as if run after it; the third never ran.
        let r = beside(&[("first", off), ("second", Pose2::identity()), ("third", off)]);
        assert!(r.accepted, "{:?}", r.reason);
        assert_eq!(r.stage.as_deref(), Some("second"));
        assert!(r.timings_ms.contains_key("first") && !r.timings_ms.contains_key("third"));
        // Both refused: the third decides, every reason in order.
        let r = beside(&[("first", off), ("second", off), ("third", Pose2::identity())]);
        assert_eq!(r.stage.as_deref(), Some("third"));
        let r = beside(&[("first", off), ("second", off), ("third", off)]);
        let reason = r.reason.unwrap();
        let at = |n: &str| reason.find(&format!("{n}: ")).unwrap();
        assert!(at("first") < at("second") && at("second") < at("third"), "{reason}");
    }

    #[test]
    fn a_pair_every_stage_refuses_is_refused_with_each_reason() {
        let g = room(true);
        let (x, y) = (pose(1.0, 0.0, 0.0), pose(0.0, 1.0, 0.0));
        let c = cascade(&[("first", x, None), ("second", y, Some(BoundaryWalls::Always))]);
        let out = crate::merge(&c, &g, &g, &MergeParams::default());
        assert!(!out.report.accepted && out.merged.is_none());
        let reason = out.report.reason.unwrap();
        assert!(reason.starts_with("first: ") && reason.contains("; second: "), "{reason}");
        assert_eq!(out.report.stage.as_deref(), Some("second"), "the last refusal is reported");
        // With the maps taken as they are, a stage that would give them walls does not run.
        let as_they_are = MergeParams { boundary_walls: BoundaryWalls::Off, ..MergeParams::default() };
        let reason = crate::merge(&c, &g, &g, &as_they_are).report.reason.unwrap();
        assert!(reason.starts_with("first: ") && !reason.contains("second"), "{reason}");
    }

    #[test]
    fn pairs_the_papers_merger_refuses_are_merged_by_the_correlative_stage() {
        use crate::floorplan::{FloorplanParams, generate};
        use crate::pairs::{PairSpec, cut_pair};
        for seed in [1, 3, 7] {
            let plan = generate(seed, &FloorplanParams { width_m: 18.0, height_m: 14.0, ..FloorplanParams::default() });
            let pair = cut_pair(&plan, &PairSpec { overlap: 0.15, max_shift_m: 3.0, rotate: true }, seed);
            let paper = crate::merge(&crate::SiftMerger::default(), &pair.a, &pair.b, &MergeParams::default());
            assert!(!paper.report.accepted, "seed {seed}: sift merges it");
            let out = crate::merge(&Cascade::default(), &pair.a, &pair.b, &MergeParams::default());
            assert!(out.report.accepted, "seed {seed}: {:?}", out.report.reason);
            assert_eq!(out.report.stage.as_deref(), Some("correlative"));
            let err = out.report.transform.unwrap().to_pose().inverse() * pair.t_a_b;
            assert!(
                err.translation.vector.norm() < 0.05 && err.rotation.angle().abs() < 0.2f64.to_radians(),
                "{err:?}"
            );
        }
    }

    #[test]
    fn the_default_cascade_tries_sift_then_boundary_walls_then_the_correlative_search() {
        use crate::floorplan::{FloorplanParams, generate};
        use crate::pairs::{PairSpec, cut_pair};
        // A pair the paper's merger takes is merged by the first stage.
        let plan = generate(1, &FloorplanParams::default());
        let pair = cut_pair(&plan, &PairSpec { overlap: 0.4, ..Default::default() }, 3);
        let out = crate::merge(&Cascade::default(), &pair.a, &pair.b, &MergeParams::default());
        assert!(out.report.accepted, "{:?}", out.report.reason);
        assert_eq!(out.report.stage.as_deref(), Some("sift"));
        // A pair nothing can merge (the room and a small patch of free space) is refused by every stage, in order.
        let mut patch = OccupancyGrid::new(20, 20, 0.05, pose(0.0, 0.0, 0.0)).unwrap();
        patch.cells_mut().fill(-2.0);
        let reason =
            crate::merge(&Cascade::default(), &room(true), &patch, &MergeParams::default()).report.reason.unwrap();
        let at = |stage: &str| reason.find(&format!("{stage}: ")).unwrap_or_else(|| panic!("{stage}: {reason}"));
        assert!(at("sift") < at("sift+boundary") && at("sift+boundary") < at("correlative"), "{reason}");
    }
}
