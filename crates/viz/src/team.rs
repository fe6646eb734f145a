//! The team part of a run: the map each team shares, the merge attempts that join teams (each judged against the
//! truth), the counts of those merges, and how much of the building the robots have mapped.
//!
//! The simulation loop hands over plain data when something happens (an exchange of maps, an attempt, a coverage
//! sample); nothing here runs per step but the end of an attempt's display.

use crate::blueprint::{Layout, ViewKind, query};
use crate::convert::{GridStyle, Rgba, color, xy};
use crate::maps::{MATCH_BAD, MATCH_GOOD};
use crate::metrics::Level;
use crate::paths;
use crate::recorder::Recorder;
use crate::world::layer;
use mrslam_core::{OccupancyGrid, Pose2};
use nalgebra::Point2;
use rerun::components::{DrawOrder, Radius};
use rerun::{Clear, EntityPath, LineStrip2D, LineStrips2D};
use std::collections::BTreeSet;

/// Colour of a refused merge attempt (accepted ones are green when correct, red when false).
pub const ATTEMPT_REFUSED: Rgba = [150, 150, 150, 255];
/// An attempt's line stays drawn this long, simulated seconds.
pub const ATTEMPT_SHOW_S: f64 = 2.0;

/// How a merge attempt between two teams ended, judged against the truth.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AttemptOutcome {
    /// Accepted, and within the scenario's thresholds of the true transform.
    Correct,
    /// Accepted on a wrong transform: the teams joined on a false merge.
    False,
    /// Refused by the merger's gate.
    Refused,
}

impl AttemptOutcome {
    /// Its colour: green, red or grey.
    pub fn color(self) -> Rgba {
        match self {
            AttemptOutcome::Correct => MATCH_GOOD,
            AttemptOutcome::False => MATCH_BAD,
            AttemptOutcome::Refused => ATTEMPT_REFUSED,
        }
    }

    fn word(self) -> &'static str {
        match self {
            AttemptOutcome::Correct => "accepted",
            AttemptOutcome::False => "accepted FALSE",
            AttemptOutcome::Refused => "refused",
        }
    }

    fn level(self) -> Level {
        match self {
            AttemptOutcome::Correct => Level::Info,
            AttemptOutcome::False => Level::Error,
            AttemptOutcome::Refused => Level::Warn,
        }
    }
}

/// One try at merging the maps of two robots' teams, as plain data.
#[derive(Debug, Clone, Copy)]
pub struct AttemptView<'a> {
    /// The two robots in contact, host first.
    pub robots: [&'a str; 2],
    /// Their true positions in the world.
    pub at: [Point2<f64>; 2],
    /// The robots of the host's team and of the other's before the try, each root first; when accepted, the
    /// second team joins the first.
    pub teams: [&'a [String]; 2],
    /// How it ended.
    pub outcome: AttemptOutcome,
    /// The cascade's deciding stage.
    pub stage: Option<&'a str>,
    /// Why the gate refused.
    pub reason: Option<&'a str>,
    /// Error of the merger's transform against the truth (rotation degrees, translation metres), when it gave one.
    pub error: Option<(f64, f64)>,
}

/// What a recording keeps of the team part: the team maps drawn, the merge counts, and the lines now drawn.
#[derive(Debug, Default)]
pub(crate) struct TeamTrack {
    /// Roots whose team map is drawn.
    drawn: BTreeSet<String>,
    /// Merges accepted, refused and accepted falsely so far.
    counts: Counts,
    /// The attempt lines drawn now, and when they were made.
    lines: Vec<(Point2<f64>, Point2<f64>, Rgba, String)>,
    lines_at: f64,
}

#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
struct Counts {
    accepted: usize,
    refused: usize,
    wrong: usize,
}

impl Counts {
    const SERIES: [(&'static str, &'static str, Rgba); 3] = [
        ("accepted", "accepted", MATCH_GOOD),
        ("refused", "refused", ATTEMPT_REFUSED),
        ("false", "accepted falsely", MATCH_BAD),
    ];

    fn values(self) -> [usize; 3] {
        [self.accepted, self.refused, self.wrong]
    }
}

impl TeamTrack {
    /// Names and colours the team's time series and starts the merge counts at zero.
    pub(crate) fn begin(&mut self, rec: &mut Recorder) {
        rec.log_series_style(
            &paths::metric("coverage", &["mapped"]),
            "mapped (share of reachable free area)",
            [40, 120, 200, 255],
        );
        rec.log_series_style(
            &paths::metric("coverage", &["redundancy"]),
            "seen by two or more robots",
            [200, 120, 40, 255],
        );
        for (leaf, name, c) in Counts::SERIES {
            rec.log_series_style(&paths::metric("merges", &[leaf]), name, c);
        }
        self.log_counts(rec, None);
    }

    /// Removes the attempt lines once they have been shown long enough.
    pub(crate) fn tick(&mut self, rec: &mut Recorder) {
        if !self.lines.is_empty() && rec.sim_time() >= self.lines_at + ATTEMPT_SHOW_S - 1e-9 {
            self.lines.clear();
            rec.log(&paths::team(&["attempts"]), &Clear::flat());
        }
    }

    /// Logs an attempt: a line between the two robots in its outcome's colour (with the other attempts of this
    /// moment), a text entry saying why, and the counts; a second team joined into the first loses its own map.
    pub(crate) fn attempt(&mut self, rec: &mut Recorder, a: &AttemptView<'_>) {
        let now = rec.sim_time();
        if self.lines.is_empty() || now > self.lines_at + 1e-9 {
            self.lines.clear();
            self.lines_at = now;
        }
        let [host, other] = a.robots;
        let label = format!("{host} + {other}: {}", a.outcome.word());
        self.lines.push((a.at[0], a.at[1], a.outcome.color(), label));
        let arch = LineStrips2D::new(self.lines.iter().map(|(p, q, ..)| LineStrip2D::from_iter([xy(p), xy(q)])))
            .with_colors(self.lines.iter().map(|l| color(l.2)))
            .with_labels(self.lines.iter().map(|l| l.3.clone()))
            .with_radii([Radius::new_ui_points(3.0)])
            .with_draw_order(DrawOrder::from(layer::MATCHES));
        rec.log(&paths::team(&["attempts"]), &arch);
        rec.log_text(&paths::team(&["events"]), a.outcome.level(), &attempt_text(a));
        let before = self.counts;
        match a.outcome {
            AttemptOutcome::Correct => self.counts.accepted += 1,
            AttemptOutcome::False => {
                self.counts.accepted += 1;
                self.counts.wrong += 1;
            }
            AttemptOutcome::Refused => self.counts.refused += 1,
        }
        self.log_counts(rec, Some(before));
        if a.outcome != AttemptOutcome::Refused
            && let Some(root) = a.teams[1].first()
            && self.drawn.remove(root)
        {
            rec.log(&paths::team_map(root), &Clear::flat());
        }
    }

    /// Logs the merge counts; with the counts `before` an attempt, those that changed first at their old value,
    /// so that the plot steps.
    fn log_counts(&self, rec: &mut Recorder, before: Option<Counts>) {
        let now = self.counts.values();
        let old = before.map(Counts::values);
        for (k, (leaf, ..)) in Counts::SERIES.iter().enumerate() {
            let entity = paths::metric("merges", &[leaf]);
            if let Some(old) = old.filter(|o| o[k] != now[k]) {
                rec.log_scalar(&entity, old[k] as f64);
            }
            rec.log_scalar(&entity, now[k] as f64);
        }
    }

    /// Logs the map of `root`'s team (the root's SLAM frame), placed at `frame` in the world, in the root's
    /// colour `c`.
    pub(crate) fn map(&mut self, rec: &mut Recorder, root: &str, grid: &OccupancyGrid, frame: &Pose2, c: Rgba) {
        self.drawn.insert(root.to_string());
        rec.log_grid(&paths::team_map(root), grid, frame, &GridStyle::tinted(c), layer::MAP, false);
    }

    /// Logs a coverage sample: the share of the reachable free area mapped, and the share of what was seen that
    /// more than one robot saw; with them the merge counts, so that their plot runs on.
    pub(crate) fn coverage(&mut self, rec: &mut Recorder, mapped: f64, redundancy: f64) {
        rec.log_scalar(&paths::metric("coverage", &["mapped"]), mapped);
        rec.log_scalar(&paths::metric("coverage", &["redundancy"]), redundancy);
        self.log_counts(rec, None);
    }
}

/// An attempt in words: who, the teams, the verdict and why, the error against the truth.
fn attempt_text(a: &AttemptView<'_>) -> String {
    let [host, other] = a.robots;
    let team = |t: &[String]| format!("[{}]", t.join(", "));
    let mut s =
        format!("team merge {host} + {other} ({} with {}): {}", team(a.teams[0]), team(a.teams[1]), a.outcome.word());
    if let Some(stage) = a.stage {
        s += &format!(" by {stage}");
    }
    if let Some(r) = a.reason {
        s += &format!(": {r}");
    }
    if let Some((rot, tr)) = a.error {
        s += &format!(" (error vs truth {rot:.2} deg, {tr:.3} m)");
    }
    if a.outcome != AttemptOutcome::Refused
        && let Some(root) = a.teams[0].first()
    {
        s += &format!("; one team, its map in {root}'s frame");
    }
    s
}

/// The team's views: the world as the teams see it (their maps over the true walls, the robots' true poses and
/// goals, the attempts), and the coverage and merge counts as time series.
pub(crate) fn team_views(robots: &[String]) -> (Layout, Vec<Layout>) {
    let mut contents = vec![query('+', &paths::walls(), false), query('+', &paths::team(&[]), true)];
    for r in robots {
        contents.push(query('+', &paths::robot(r, &["truth"]), false));
        contents.push(query('+', &paths::robot(r, &["slam", "goal"]), true));
    }
    let world =
        Layout::view(ViewKind::Spatial2D, "team (team maps, merge attempts, goals)", EntityPath::root(), &contents);
    let series = |group: &str, title: &str| {
        let origin = paths::metric(group, &[]);
        Layout::view(ViewKind::TimeSeries, title, origin.clone(), &[query('+', &origin, true)])
    };
    (world, vec![series("coverage", "coverage (share)"), series("merges", "online merges (count)")])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_attempt_reads_as_who_what_and_why() {
        let (a, b) = (["experia".to_string()], ["prawn".to_string(), "scout".to_string()]);
        let mut v = AttemptView {
            robots: ["experia", "prawn"],
            at: [Point2::origin(), Point2::new(1.0, 0.0)],
            teams: [&a, &b],
            outcome: AttemptOutcome::Refused,
            stage: None,
            reason: Some("too few inliers"),
            error: None,
        };
        assert_eq!(
            attempt_text(&v),
            "team merge experia + prawn ([experia] with [prawn, scout]): refused: too few inliers"
        );
        (v.outcome, v.stage, v.reason, v.error) = (AttemptOutcome::False, Some("sift"), None, Some((12.0, 1.5)));
        assert_eq!(
            attempt_text(&v),
            "team merge experia + prawn ([experia] with [prawn, scout]): accepted FALSE by sift (error vs truth \
             12.00 deg, 1.500 m); one team, its map in experia's frame"
        );
        assert_ne!(AttemptOutcome::Correct.color(), AttemptOutcome::False.color());
        assert_ne!(AttemptOutcome::Refused.color(), AttemptOutcome::Correct.color());
    }
}
