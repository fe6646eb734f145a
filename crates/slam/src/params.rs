//! Filter parameters, named and defaulted as GMapping's (ROS `slam_gmapping` / OpenSLAM `gfs`): one struct of
//! sub-structs, each defined beside the component it configures, reachable by dotted names
//! (`matcher.sigma`) and by GMapping's flat names (`sigma`, `srr`, `linearUpdate`'s `linear_update`).

use crate::loop_closure::LoopClosureParams;
use crate::map_build::MapParams;
use crate::motion::MotionModel;
use crate::scan_matcher::{MatcherKind, MatcherParams};
use crate::scan_odometry::ScanOdometryParams;
use serde::{Deserialize, Serialize};

/// Why a parameter was not set or is out of its domain.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ParamError {
    /// No parameter has this name (dotted or flat).
    #[error("unknown SLAM parameter '{0}'")]
    Unknown(String),
    /// The text does not read as the parameter's type.
    #[error("{name}: {message} ('{value}')")]
    Value {
        /// The parameter as named.
        name: String,
        /// The text given.
        value: String,
        /// What is wrong with it.
        message: String,
    },
    /// The value is outside the parameter's domain.
    #[error("{name} {message}")]
    Invalid {
        /// The parameter's dotted name.
        name: String,
        /// What is wrong, as a predicate ("must be ...").
        message: String,
    },
}

/// The particle filter's own settings: how many particles, when a scan is processed, how particles are weighed
/// and resampled, and the online odometry calibration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FilterParams {
    /// `particles`: number of particles (GMapping 30).
    pub particles: usize,
    /// `linearUpdate`: process a scan after the robot translated this far, metres (GMapping 1.0).
    pub linear_update: f64,
    /// `angularUpdate`: process a scan after the robot turned this much, radians (GMapping 0.5).
    pub angular_update: f64,
    /// `temporalUpdate`: process a scan when this many seconds passed since the last one; negative
    /// disables it (GMapping -1).
    pub temporal_update: f64,
    /// `resampleThreshold`: resample when Neff < threshold × particles (GMapping 0.5).
    pub resample_threshold: f64,
    /// `ogain`: gain smoothing the likelihood: weights are exp((l - l_max) / (ogain × particles)) (GMapping 3).
    pub ogain: f64,
    /// Not GMapping: `odometry_calibration`, metres: when positive, the filter estimates the odometry's
    /// systematic errors online (a distance scale and a heading drift per metre driven; see
    /// [`crate::Rbpf::odometry_calibration`]) and corrects every odometry increment before the motion
    /// model samples from it and the `motion_prior` centres on it; the estimate forgets what it learnt
    /// over about this many metres driven. 0 (the default): raw odometry, as GMapping. `field` matcher
    /// only (it needs the scan's information matrix). Why: the motion prior pulls each match towards the
    /// odometry by the prior's share of the pose's information; where the scan observes a direction only
    /// weakly (along a corridor) a biased odometry's error leaks into every update and accumulates (see
    /// the `calibration` module). Measured with 20 m: on the synthetic office loop (3 % scale
    /// error) the Hokuyo preset with 0.1 m updates goes from 0.049 to 0.020 m RMS; in the simulated
    /// corridor, whose odometry has no scale error, it did not help, so no preset turns it on.
    pub odometry_calibration: f64,
}

impl Default for FilterParams {
    fn default() -> Self {
        FilterParams {
            particles: 30,
            linear_update: 1.0,
            angular_update: 0.5,
            temporal_update: -1.0,
            resample_threshold: 0.5,
            ogain: 3.0,
            odometry_calibration: 0.0,
        }
    }
}

/// All parameters of the filter. [`Default`] gives GMapping's defaults; [`SlamParams::hokuyo`] and
/// [`SlamParams::rplidar`] are presets for the two robots of the paper.
///
/// Why the presets differ from GMapping's defaults: GMapping's defaults were tuned for 80 m SICK
/// scanners on large robots (update every 1 m or 0.5 rad, 80 m usable range). With a 4 m or 6 m lidar a
/// 1 m gap between filter updates leaves too little overlap between consecutive scans for the matcher,
/// and a small indoor robot's rooms are only a few metres across; so the presets use the sensor's own
/// range and update every 0.25-0.3 m / 0.25 rad. They also use the likelihood-field matcher
/// ([`MatcherParams::kind`] `field`, with `sigma`, `iterations`, `refine_iterations`, `heading_search`,
/// `motion_prior`, `lskip` and `seen_band` set to go with it; see [`SlamParams::hokuyo`]): on the synthetic
/// office loop it is 3.5 (RpLidar) and 1.5 (Hokuyo) times as accurate as GMapping's matcher, at about half
/// its cost per update.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SlamParams {
    /// The filter: particles, update triggers, weighting, resampling, odometry calibration.
    pub filter: FilterParams,
    /// The output map and the ranges used.
    pub map: MapParams,
    /// The odometry motion model.
    pub motion: MotionModel,
    /// The scan matcher.
    pub matcher: MatcherParams,
    /// Scan-matched odometry.
    pub scan_odometry: ScanOdometryParams,
    /// Loop closure at the end of a log.
    pub loop_closure: LoopClosureParams,
}

/// Every flat name a parameter had before the parameters were nested (GMapping's names in snake case), and
/// its dotted name now.
pub const FLAT_NAMES: &[(&str, &str)] = &[
    ("particles", "filter.particles"),
    ("linear_update", "filter.linear_update"),
    ("angular_update", "filter.angular_update"),
    ("temporal_update", "filter.temporal_update"),
    ("resample_threshold", "filter.resample_threshold"),
    ("ogain", "filter.ogain"),
    ("odometry_calibration", "filter.odometry_calibration"),
    ("delta", "map.delta"),
    ("max_range", "map.max_range"),
    ("max_urange", "map.max_urange"),
    ("clear_max_range", "map.clear_max_range"),
    ("occ_thresh", "map.occ_thresh"),
    ("wall_hits", "map.wall_hits"),
    ("srr", "motion.srr"),
    ("srt", "motion.srt"),
    ("str", "motion.trans_from_rot"),
    ("stt", "motion.stt"),
    ("matcher", "matcher.kind"),
    ("sigma", "matcher.sigma"),
    ("lsigma", "matcher.lsigma"),
    ("kernel_size", "matcher.kernel_size"),
    ("lstep", "matcher.lstep"),
    ("astep", "matcher.astep"),
    ("iterations", "matcher.iterations"),
    ("lskip", "matcher.lskip"),
    ("minimum_score", "matcher.minimum_score"),
    ("frontier_guard", "matcher.frontier_guard"),
    ("seen_band", "matcher.seen_band"),
    ("unknown_score", "matcher.unknown_score"),
    ("field_reach", "matcher.field_reach"),
    ("field_lines", "matcher.field_lines"),
    ("refine_iterations", "matcher.refine_iterations"),
    ("weight_all_beams", "matcher.weight_all_beams"),
    ("heading_search", "matcher.heading_search"),
    ("heading_step", "matcher.heading_step"),
    ("motion_prior", "matcher.motion_prior"),
    ("kernel_likelihood", "matcher.kernel_likelihood"),
    ("scan_odometry", "scan_odometry.enabled"),
    ("scan_odometry_submap", "scan_odometry.submap"),
    ("scan_odometry_range", "scan_odometry.range"),
    ("scan_odometry_sigma", "scan_odometry.sigma"),
    ("scan_odometry_heading_search", "scan_odometry.heading_search"),
    ("scan_odometry_reach", "scan_odometry.reach"),
    ("scan_odometry_turn_round", "scan_odometry.turn_round"),
    ("scan_odometry_line_lag", "scan_odometry.line_lag"),
    ("scan_odometry_line_lag_s", "scan_odometry.line_lag_s"),
    ("scan_odometry_prior", "scan_odometry.prior"),
    ("loop_closure", "loop_closure.enabled"),
    ("loop_min_travel", "loop_closure.min_travel"),
    ("loop_search_radius", "loop_closure.search_radius"),
    ("loop_submap_nodes", "loop_closure.submap_nodes"),
    ("loop_window", "loop_closure.window"),
    ("loop_heading_window", "loop_closure.heading_window"),
    ("loop_min_matched", "loop_closure.min_matched"),
    ("loop_chain_sigma", "loop_closure.chain_sigma"),
    ("loop_chain_heading_sigma", "loop_closure.chain_heading_sigma"),
    ("loop_sigma", "loop_closure.sigma"),
    ("loop_heading_sigma", "loop_closure.heading_sigma"),
    ("loop_range", "loop_closure.range"),
    ("loop_online", "loop_closure.online"),
    ("loop_submap_scans", "loop_closure.submap_scans"),
    ("loop_window_per_metre", "loop_closure.window_per_metre"),
    ("loop_heading_window_per_metre", "loop_closure.heading_window_per_metre"),
    ("loop_max_window", "loop_closure.max_window"),
    ("loop_max_heading_window", "loop_closure.max_heading_window"),
    ("loop_min_score", "loop_closure.min_score"),
    ("loop_max_rival", "loop_closure.max_rival"),
    ("loop_max_searches", "loop_closure.max_searches"),
    ("loop_optimize_every", "loop_closure.optimize_every"),
    ("loop_max_residual", "loop_closure.max_residual"),
    ("loop_open_travel", "loop_closure.open_loop_travel"),
    ("loop_relocalise", "loop_closure.relocalise"),
];

impl SlamParams {
    /// Preset for Experia's Hokuyo URG-04LX class lidar: 4 m range, 240°, 667 beams.
    ///
    /// Usable range = sensor range; update every 0.25 m / 0.25 rad (short range: keep scan overlap high).
    /// The `field` matcher (see [`MatcherParams::kind`]) with a narrow kernel (`sigma` 0.001: exp(-d²/sigma)
    /// halves at 2.6 cm, where GMapping's 0.05 is still 0.99), a ±0.2 rad heading search, a short climb
    /// (`iterations` 2) finished by Gauss-Newton (`refine_iterations` 10) and the motion-model prior
    /// (`motion_prior` 1); `lskip` 1 (every 2nd beam, 0.72°) for matching, all beams for mapping;
    /// `seen_band` 0.3 m (`unknown_score` 0.5). On long-range real data (the Freiburg log, 1 m updates, 15 m
    /// usable range) `unknown_score` 0 and `sigma` 0.003 worked instead (see BENCHMARKS.md).
    pub fn hokuyo() -> Self {
        let p = SlamParams::field_matcher();
        SlamParams {
            map: MapParams { max_range: 4.0, max_urange: 4.0, ..p.map },
            filter: FilterParams { linear_update: 0.25, angular_update: 0.25, ..p.filter },
            ..p
        }
    }

    /// Preset for Prawn's RpLidar A1 class lidar: 6 m range, 360°, 1° resolution, 5 Hz.
    ///
    /// Usable range = sensor range; update every 0.3 m / 0.25 rad; the matcher as in [`SlamParams::hokuyo`].
    pub fn rplidar() -> Self {
        let p = SlamParams::field_matcher();
        SlamParams {
            map: MapParams { max_range: 6.0, max_urange: 6.0, ..p.map },
            filter: FilterParams { linear_update: 0.3, angular_update: 0.25, ..p.filter },
            ..p
        }
    }

    /// Preset for real robots' logs: GMapping's filter moved by scan-matched odometry, with the field matcher.
    ///
    /// GMapping's parameters except:
    /// - `scan_odometry` on: every scan is matched against a local map of the scans before it and the
    ///   particles move by the matched increments (see `scan_odometry`); the motion noise is halved
    ///   (`srr` 0.05, `srt` 0.1, `str` 0.05, `stt` 0.1), as those increments are better than the wheels'.
    /// - The `field` matcher with the motion prior (`motion_prior` 1): a ±0.05 rad heading search, a short
    ///   climb (`iterations` 2) and Gauss-Newton (`refine_iterations` 10) to the optimum of the score
    ///   exp(-d²/`sigma`) over a field reaching 6 cells (30 cm, `field_reach`). `sigma` 0.01 (exp(-d²/sigma)
    ///   halves at 8 cm; the robot presets' 0.001 at 2.6 cm): where a particle comes back to walls it mapped a
    ///   loop ago 20 cm off, the narrow kernel gives them no weight and the particle does not snap onto
    ///   them (on ACES the narrow kernel lost its final loop on two seeds of two).
    /// - Sharper weights (`lsigma` 0.03 instead of 0.075): the field's distances are smaller than GMapping's
    ///   kernel distances, and with 0.075 the particles that kept a loop together were not told apart from
    ///   those that did not.
    /// - `wall_hits` 2: beams through glass and past wall edges do not carve free space behind walls.
    /// - `loop_closure` on, online: a pose graph over the processed scans, each searched by branch and bound
    ///   against the submaps passed a loop ago and optimised as loops are found, the filter re-anchored on it
    ///   (see [`LoopClosureParams::enabled`]): on ACES every particle descended from one ancestor before its
    ///   long loops, and relations across them were 0.2-0.4 m off on every seed; on Intel a loop that drifted
    ///   beyond the filter's reach drew rooms over each other (1.49 m on seed 0) until the search window grew
    ///   with the driving. Its settings were chosen on Intel and confirmed on ACES and FR079.
    ///
    /// Measured on the raw ACES and Freiburg 079 benchmark logs (BENCHMARKS.md, "Real benchmark logs").
    pub fn matched() -> Self {
        let p = SlamParams::default();
        SlamParams {
            scan_odometry: ScanOdometryParams { enabled: true, ..p.scan_odometry },
            motion: MotionModel { srr: 0.05, srt: 0.1, trans_from_rot: 0.05, stt: 0.1 },
            matcher: MatcherParams {
                kind: MatcherKind::Field,
                sigma: 0.01,
                lsigma: 0.03,
                iterations: 2,
                refine_iterations: 10,
                heading_search: 0.05,
                heading_step: 0.01,
                motion_prior: 1.0,
                field_reach: 6,
                ..p.matcher
            },
            map: MapParams { wall_hits: 2, ..p.map },
            loop_closure: LoopClosureParams { enabled: true, ..p.loop_closure },
            ..p
        }
    }

    /// GMapping's defaults with the `field` matcher settings both robot presets share.
    fn field_matcher() -> Self {
        let p = SlamParams::default();
        SlamParams {
            matcher: MatcherParams {
                kind: MatcherKind::Field,
                sigma: 0.001,
                lskip: 1,
                seen_band: 0.3,
                iterations: 2,
                refine_iterations: 10,
                heading_search: 0.2,
                heading_step: 0.02,
                motion_prior: 1.0,
                ..p.matcher
            },
            ..p
        }
    }

    /// Sets the parameter called `name` from its text `value`; for command lines and scenario files. `name` is
    /// a dotted name (`matcher.sigma`, `filter.particles`) or a flat one of [`FLAT_NAMES`] (`sigma`,
    /// `particles`). The value is read as the parameter's type (number, integer, `true`/`false`, or a name such
    /// as `field`); nothing else changes. Errors name the parameter and what is wrong.
    pub fn set(&mut self, name: &str, value: &str) -> Result<(), ParamError> {
        let path = FLAT_NAMES.iter().find(|(flat, _)| *flat == name).map_or(name, |(_, dotted)| dotted);
        let bad = |message: String| ParamError::Value { name: name.to_string(), value: value.to_string(), message };
        let unknown = || ParamError::Unknown(name.to_string());
        let mut tree = toml::Value::try_from(&*self).map_err(|e| bad(e.to_string()))?;
        let slot = path.split('.').try_fold(&mut tree, |v, key| v.get_mut(key)).ok_or_else(unknown)?;
        let text = value.trim();
        *slot = match slot {
            toml::Value::Float(_) => toml::Value::Float(text.parse().map_err(|e| bad(format!("{e}")))?),
            toml::Value::Integer(_) => toml::Value::Integer(text.parse().map_err(|e| bad(format!("{e}")))?),
            toml::Value::Boolean(_) => toml::Value::Boolean(text.parse().map_err(|e| bad(format!("{e}")))?),
            toml::Value::String(_) => toml::Value::String(text.to_string()),
            _ => return Err(unknown()),
        };
        *self = tree.try_into().map_err(|e: toml::de::Error| bad(e.message().to_string()))?;
        Ok(())
    }

    /// Checks that every parameter is in its domain; the error names the first that is not.
    pub fn validate(&self) -> Result<(), ParamError> {
        let invalid = |name: &str, message: String| Err(ParamError::Invalid { name: name.to_string(), message });
        let pos = |name: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                invalid(name, format!("must be a positive finite number, got {v}"))
            }
        };
        let nonneg = |name: &str, v: f64| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                invalid(name, format!("must be a non-negative finite number, got {v}"))
            }
        };
        let (f, m, mo, k, so, lc) =
            (&self.filter, &self.map, &self.motion, &self.matcher, &self.scan_odometry, &self.loop_closure);
        if f.particles == 0 || f.particles > 100_000 {
            return invalid("filter.particles", format!("must be in 1..=100000, got {}", f.particles));
        }
        pos("map.delta", m.delta)?;
        pos("map.max_range", m.max_range)?;
        pos("map.max_urange", m.max_urange)?;
        nonneg("filter.linear_update", f.linear_update)?;
        nonneg("filter.angular_update", f.angular_update)?;
        if f.temporal_update.is_nan() {
            return invalid("filter.temporal_update", "must not be NaN".into());
        }
        nonneg("filter.resample_threshold", f.resample_threshold)?;
        pos("matcher.sigma", k.sigma)?;
        pos("matcher.lsigma", k.lsigma)?;
        pos("filter.ogain", f.ogain)?;
        if !(0..=8).contains(&k.kernel_size) {
            return invalid("matcher.kernel_size", format!("must be in 0..=8, got {}", k.kernel_size));
        }
        pos("matcher.lstep", k.lstep)?;
        pos("matcher.astep", k.astep)?;
        if k.iterations > 30 {
            return invalid("matcher.iterations", format!("must be at most 30, got {}", k.iterations));
        }
        if !k.minimum_score.is_finite() {
            return invalid("matcher.minimum_score", "must be finite".into());
        }
        for (n, v) in [
            ("motion.srr", mo.srr),
            ("motion.srt", mo.srt),
            ("motion.trans_from_rot", mo.trans_from_rot),
            ("motion.stt", mo.stt),
        ] {
            nonneg(n, v)?;
        }
        nonneg("matcher.seen_band", k.seen_band)?;
        nonneg("matcher.unknown_score", k.unknown_score)?;
        if !(1..=16).contains(&k.field_reach) {
            return invalid("matcher.field_reach", format!("must be in 1..=16, got {}", k.field_reach));
        }
        if !(1..=16).contains(&so.reach) {
            return invalid("scan_odometry.reach", format!("must be in 1..=16, got {}", so.reach));
        }
        nonneg("matcher.heading_search", k.heading_search)?;
        nonneg("matcher.motion_prior", k.motion_prior)?;
        nonneg("filter.odometry_calibration", f.odometry_calibration)?;
        if f.odometry_calibration > 0.0 && k.kind != MatcherKind::Field {
            return invalid(
                "filter.odometry_calibration",
                "needs matcher = field (it learns from the field matcher's information)".into(),
            );
        }
        pos("matcher.heading_step", k.heading_step)?;
        if !(1..=100_000).contains(&so.submap) {
            return invalid("scan_odometry.submap", format!("must be in 1..=100000, got {}", so.submap));
        }
        pos("scan_odometry.range", so.range)?;
        pos("scan_odometry.sigma", so.sigma)?;
        nonneg("scan_odometry.heading_search", so.heading_search)?;
        pos("scan_odometry.prior", so.prior)?;
        if so.line_lag_s.is_nan() || so.line_lag_s.abs() > 1.0 {
            return invalid("scan_odometry.line_lag_s", format!("must be within ±1 s, got {}", so.line_lag_s));
        }
        if so.heading_search / 0.01 > 1000.0 {
            return invalid("scan_odometry.heading_search", "must be at most 10 rad".into());
        }
        if k.heading_search / k.heading_step > 1000.0 {
            return invalid("matcher.heading_search", "/ matcher.heading_step must be at most 1000".into());
        }
        if k.refine_iterations > 100 {
            return invalid("matcher.refine_iterations", format!("must be at most 100, got {}", k.refine_iterations));
        }
        nonneg("loop_closure.min_travel", lc.min_travel)?;
        nonneg("loop_closure.search_radius", lc.search_radius)?;
        if lc.submap_nodes > 10_000 {
            return invalid("loop_closure.submap_nodes", format!("must be at most 10000, got {}", lc.submap_nodes));
        }
        nonneg("loop_closure.window", lc.window)?;
        if lc.window / m.delta > 200.0 {
            return invalid("loop_closure.window", "/ map.delta must be at most 200 cells".into());
        }
        nonneg("loop_closure.heading_window", lc.heading_window)?;
        if lc.heading_window / 0.01 > 1000.0 {
            return invalid("loop_closure.heading_window", "must be at most 10 rad".into());
        }
        if !(lc.min_matched.is_finite() && (0.0..=1.0).contains(&lc.min_matched)) {
            return invalid("loop_closure.min_matched", format!("must be in [0, 1], got {}", lc.min_matched));
        }
        pos("loop_closure.range", lc.range)?;
        pos("loop_closure.chain_sigma", lc.chain_sigma)?;
        pos("loop_closure.chain_heading_sigma", lc.chain_heading_sigma)?;
        pos("loop_closure.sigma", lc.sigma)?;
        pos("loop_closure.heading_sigma", lc.heading_sigma)?;
        if !(1..=10_000).contains(&lc.submap_scans) {
            return invalid("loop_closure.submap_scans", format!("must be in 1..=10000, got {}", lc.submap_scans));
        }
        nonneg("loop_closure.window_per_metre", lc.window_per_metre)?;
        nonneg("loop_closure.heading_window_per_metre", lc.heading_window_per_metre)?;
        nonneg("loop_closure.max_window", lc.max_window)?;
        if lc.max_window / m.delta > 4000.0 {
            return invalid("loop_closure.max_window", "/ map.delta must be at most 4000 cells".into());
        }
        nonneg("loop_closure.max_heading_window", lc.max_heading_window)?;
        if lc.max_heading_window > std::f64::consts::PI {
            return invalid("loop_closure.max_heading_window", "must be at most pi".into());
        }
        if !(lc.min_score.is_finite() && lc.min_score > 0.0 && lc.min_score <= 1.0) {
            return invalid("loop_closure.min_score", format!("must be in (0, 1], got {}", lc.min_score));
        }
        if !(lc.max_rival.is_finite() && lc.max_rival > 0.0) {
            return invalid("loop_closure.max_rival", format!("must be a positive number, got {}", lc.max_rival));
        }
        if lc.max_searches > 100 {
            return invalid("loop_closure.max_searches", format!("must be at most 100, got {}", lc.max_searches));
        }
        pos("loop_closure.max_residual", lc.max_residual)?;
        nonneg("loop_closure.open_loop_travel", lc.open_loop_travel)?;
        if !(m.occ_thresh.is_finite() && (0.0..1.0).contains(&m.occ_thresh)) {
            return invalid("map.occ_thresh", format!("must be in [0, 1), got {}", m.occ_thresh));
        }
        Ok(())
    }
}

/// A named set of parameters: what `--preset` and scenario files choose by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Preset {
    /// GMapping's filter on scan-matched odometry ([`SlamParams::matched`]): the default for real logs.
    #[default]
    Matched,
    /// GMapping's defaults ([`SlamParams::default`]): the reference.
    Gmapping,
    /// Experia's Hokuyo URG-04LX class lidar ([`SlamParams::hokuyo`]).
    Hokuyo,
    /// Prawn's RpLidar A1 class lidar ([`SlamParams::rplidar`]).
    Rplidar,
}

impl Preset {
    /// Every preset, in the order help texts list them.
    pub const ALL: [Preset; 4] = [Preset::Matched, Preset::Gmapping, Preset::Hokuyo, Preset::Rplidar];

    /// The preset's parameters.
    pub fn params(self) -> SlamParams {
        match self {
            Preset::Matched => SlamParams::matched(),
            Preset::Gmapping => SlamParams::default(),
            Preset::Hokuyo => SlamParams::hokuyo(),
            Preset::Rplidar => SlamParams::rplidar(),
        }
    }

    /// The preset's name, as `FromStr` reads it.
    pub fn name(self) -> &'static str {
        match self {
            Preset::Matched => "matched",
            Preset::Gmapping => "gmapping",
            Preset::Hokuyo => "hokuyo",
            Preset::Rplidar => "rplidar",
        }
    }
}

impl std::fmt::Display for Preset {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Preset {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Preset::ALL.into_iter().find(|p| p.name() == s).ok_or_else(|| {
            let names: Vec<&str> = Preset::ALL.iter().map(|p| p.name()).collect();
            format!("unknown SLAM preset `{s}` (expected {})", names.join(", "))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The value at a dotted path of the parameters' tree.
    fn leaf(p: &SlamParams, path: &str) -> toml::Value {
        let tree = toml::Value::try_from(p).unwrap();
        path.split('.').try_fold(&tree, |v, k| v.get(k)).unwrap().clone()
    }

    #[test]
    fn odometry_calibration_is_refused_without_the_field_matcher() {
        let mut p = SlamParams::default();
        p.set("odometry_calibration", "20").unwrap();
        let e = p.validate().unwrap_err();
        assert!(e.to_string().contains("odometry_calibration needs matcher = field"), "{e}");
        let mut p = SlamParams::hokuyo();
        p.set("filter.odometry_calibration", "20").unwrap();
        assert!(p.validate().is_ok());
        p.set("odometry_calibration", "-1").unwrap();
        assert!(p.validate().is_err());
    }

    #[test]
    fn every_flat_name_sets_the_same_parameter_as_its_dotted_name() {
        for preset in Preset::ALL {
            let base = preset.params();
            for &(flat, dotted) in FLAT_NAMES {
                // A value other than the preset's, of the parameter's own type.
                let value = match leaf(&base, dotted) {
                    toml::Value::Float(x) => format!("{}", x + 0.25),
                    toml::Value::Integer(i) => format!("{}", i + 1),
                    toml::Value::Boolean(b) => format!("{}", !b),
                    toml::Value::String(k) => (if k == "field" { "gmapping" } else { "field" }).to_string(),
                    other => panic!("{dotted}: {other:?}"),
                };
                let (mut by_flat, mut by_dotted) = (base.clone(), base.clone());
                by_flat.set(flat, &value).unwrap();
                by_dotted.set(dotted, &value).unwrap();
                assert_eq!(by_flat, by_dotted, "{preset}: {flat} = {value}");
                assert_ne!(by_flat, base, "{preset}: {flat} = {value} changed nothing");
                assert_eq!(leaf(&by_flat, dotted).to_string().trim_matches('"'), value, "{flat}");
            }
        }
        // Every parameter has a flat name.
        let tree = toml::Value::try_from(SlamParams::default()).unwrap();
        let count: usize = tree.as_table().unwrap().values().map(|g| g.as_table().unwrap().len()).sum();
        assert_eq!(count, FLAT_NAMES.len());
    }

    #[test]
    fn a_set_value_is_the_text_read_as_the_parameters_type() {
        let mut p = SlamParams::default();
        p.set("matcher.sigma", " 0.1 ").unwrap();
        assert_eq!(p.matcher.sigma, 0.1);
        p.set("str", "0.3").unwrap();
        assert_eq!(p.motion.trans_from_rot, 0.3);
        p.set("matcher", "field").unwrap();
        assert_eq!(p.matcher.kind, MatcherKind::Field);
        p.set("temporal_update", "inf").unwrap();
        assert_eq!(p.filter.temporal_update, f64::INFINITY);
        p.set("particles", "12").unwrap();
        assert_eq!(p.filter.particles, 12);
        let before = p.clone();
        let unknown = |e: ParamError| e.to_string();
        assert_eq!(unknown(p.set("warp", "1").unwrap_err()), "unknown SLAM parameter 'warp'");
        assert_eq!(unknown(p.set("filter", "1").unwrap_err()), "unknown SLAM parameter 'filter'");
        assert_eq!(unknown(p.set("matcher.warp", "1").unwrap_err()), "unknown SLAM parameter 'matcher.warp'");
        let e = p.set("particles", "1.5").unwrap_err();
        assert!(matches!(&e, ParamError::Value { name, .. } if name == "particles"), "{e}");
        assert!(e.to_string().starts_with("particles: ") && e.to_string().ends_with("('1.5')"), "{e}");
        assert!(p.set("matcher", "hill").is_err());
        assert!(p.set("loop_closure", "yes").is_err());
        assert!(p.set("particles", "-3").is_err());
        assert_eq!(p, before, "a refused value changes nothing");
    }

    #[test]
    fn presets_round_trip_by_name() {
        for p in Preset::ALL {
            assert_eq!(p.name().parse::<Preset>(), Ok(p));
            assert!(p.params().validate().is_ok());
        }
        assert_eq!(
            "x".parse::<Preset>().unwrap_err(),
            "unknown SLAM preset `x` (expected matched, gmapping, hokuyo, rplidar)"
        );
    }

    #[test]
    fn validation_rejects_nonsense_and_names_the_parameter() {
        for (name, value, dotted) in
            [("delta", "0", "map.delta"), ("particles", "0", "filter.particles"), ("sigma", "NaN", "matcher.sigma")]
        {
            let mut p = SlamParams::default();
            p.set(name, value).unwrap();
            let e = p.validate().unwrap_err();
            assert!(matches!(&e, ParamError::Invalid { name, .. } if name == dotted), "{e}");
            assert!(e.to_string().starts_with(dotted), "{e}");
        }
    }
}
