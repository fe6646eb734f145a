//! A scenario's team settings: who can talk to whom, what they exchange, which merger joins their maps while
//! they drive, and whether a joined team splits the frontiers.

use super::error::{Ctx, ScenarioError};
use super::file::TeamFile;
use mrslam_merge::Algorithm;

/// How the robots of a team choose where to explore.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Coordination {
    /// Every robot drives to the nearest frontier of its own map, joined or not (m-explore's behaviour).
    None,
    /// A joined team assigns the frontiers of its merged map over its robots (Burgard et al. 2005); a robot
    /// alone explores alone.
    Frontiers,
}

impl Coordination {
    /// Every mode, as files and the command line name them.
    pub const ALL: [Coordination; 2] = [Coordination::None, Coordination::Frontiers];

    /// The name: `none` or `frontiers`.
    pub const fn name(self) -> &'static str {
        match self {
            Coordination::None => "none",
            Coordination::Frontiers => "frontiers",
        }
    }
}

impl std::str::FromStr for Coordination {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Coordination::ALL
            .into_iter()
            .find(|c| c.name() == s)
            .ok_or_else(|| format!("unknown coordination `{s}` (expected none or frontiers)"))
    }
}

impl std::fmt::Display for Coordination {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The `[team]` table resolved: robots that merge their maps as they meet and may then explore together.
#[derive(Debug, Clone, PartialEq)]
pub struct TeamSetup {
    /// Communication range, metres: robots of different teams farther apart never try to merge (0: never).
    pub range: f64,
    /// Whether a wall between two robots cuts their link (the world's true walls decide).
    pub line_of_sight: bool,
    /// Two robots in contact exchange their maps (and try to merge them) at most this often, seconds; a team's
    /// robots send their maps to the team as often.
    pub exchange_period: f64,
    /// How a joined team explores.
    pub coordination: Coordination,
    /// The merger of the online merges (the default merger of `mrslam merge`: the cascade).
    pub merger: Algorithm,
    /// Coverage of the true free area is sampled this often, seconds.
    pub coverage_period: f64,
    /// Weight of travel cost against information gain in the frontier assignment (Burgard et al.'s beta).
    pub beta: f64,
    /// Robots in contact exchange maps and try to merge them only once both teams' maps know this much area,
    /// m² (0: from the first scan). Maps of a scan or two match a corridor's other doors as well as the right
    /// ones; the correlative stage asks for 100 m² of shared known space for the same reason.
    pub min_known_m2: f64,
    /// Whether an online merge's correlative search looks only at the transforms that put the two robots in
    /// contact within the range of each other (each where its SLAM puts it on its team's map). The gate refuses
    /// the others either way. Off by default: about 10 % faster, but blind to the answers elsewhere that show a
    /// self-similar pair ambiguous (one false merge in the FR079 study with it on, none with it off).
    pub search_near_contact: bool,
}

impl Default for TeamSetup {
    fn default() -> Self {
        TeamSetup {
            range: 10.0,
            line_of_sight: true,
            exchange_period: 10.0,
            coordination: Coordination::Frontiers,
            merger: Algorithm::Cascade,
            coverage_period: 2.0,
            beta: 1.0,
            min_known_m2: 0.0,
            search_near_contact: false,
        }
    }
}

pub(super) fn resolve_team(cx: &Ctx, t: &TeamFile) -> Result<TeamSetup, ScenarioError> {
    let d = TeamSetup::default();
    let non_negative = |field: &str, v: Option<f64>, default: f64| match v {
        Some(x) if !(x.is_finite() && x >= 0.0) => {
            Err(cx.err(format!("team.{field}"), format!("must be a finite number >= 0, got {x}")))
        }
        v => Ok(v.unwrap_or(default)),
    };
    let positive = |field: &str, v: Option<f64>, default: f64| match v {
        Some(x) if !(x.is_finite() && x > 0.0) => {
            Err(cx.err(format!("team.{field}"), format!("must be a finite number > 0, got {x}")))
        }
        v => Ok(v.unwrap_or(default)),
    };
    let coordination = match &t.coordination {
        None => d.coordination,
        Some(s) => s.parse().map_err(|e: String| cx.err("team.coordination", e))?,
    };
    let merger = match &t.merger {
        None => d.merger,
        Some(s) => s.parse::<Algorithm>().map_err(|e| cx.err("team.merger", e.to_string()))?,
    };
    Ok(TeamSetup {
        range: non_negative("range", t.range, d.range)?,
        line_of_sight: t.line_of_sight.unwrap_or(d.line_of_sight),
        exchange_period: positive("exchange_period", t.exchange_period, d.exchange_period)?,
        coordination,
        merger,
        coverage_period: positive("coverage_period", t.coverage_period, d.coverage_period)?,
        beta: non_negative("beta", t.beta, d.beta)?,
        min_known_m2: non_negative("min_known_m2", t.min_known_m2, d.min_known_m2)?,
        search_near_contact: t.search_near_contact.unwrap_or(d.search_near_contact),
    })
}
