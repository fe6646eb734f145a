//! Filter parameters, named and defaulted as GMapping's (ROS `slam_gmapping` / OpenSLAM `gfs`).

pub use crate::scan_matcher::MatcherKind;

/// All parameters of the filter. [`Default`] gives GMapping's defaults; [`SlamParams::hokuyo`] and
/// [`SlamParams::rplidar`] are presets for the two robots of the paper.
///
/// Why the presets differ from GMapping's defaults: GMapping's defaults were tuned for 80 m SICK
/// scanners on large robots (update every 1 m or 0.5 rad, 80 m usable range). With a 4 m or 6 m lidar a
/// 1 m gap between filter updates leaves too little overlap between consecutive scans for the matcher,
/// and a small indoor robot's rooms are only a few metres across; so the presets use the sensor's own
/// range and update every 0.25-0.3 m / 0.25 rad. They also use the likelihood-field matcher
/// ([`SlamParams::matcher`] `field`, with `sigma`, `iterations`, `refine_iterations`, `heading_search`,
/// `motion_prior`, `lskip` and `seen_band` set to go with it; see [`SlamParams::hokuyo`]): on the synthetic
/// office loop it is 3.5 (RpLidar) and 1.5 (Hokuyo) times as accurate as GMapping's matcher, at about half
/// its cost per update.
#[derive(Debug, Clone, PartialEq)]
pub struct SlamParams {
    /// `particles`: number of particles (GMapping 30).
    pub particles: usize,
    /// `delta`: grid resolution, metres per cell (GMapping 0.05).
    pub delta: f64,
    /// `maxRange`: beams at or beyond this range (metres) are max-range readings: never hits; they clear
    /// free space up to `max_urange` when `clear_max_range` is set (GMapping 80).
    pub max_range: f64,
    /// `maxUrange`: usable range, metres: longer beams are not matched and are clipped here when mapping
    /// free space (GMapping 80).
    pub max_urange: f64,
    /// Whether no-return beams (at or beyond the sensor's / `max_range`) clear free space up to `max_urange`
    /// in the output map. Off by default, as GMapping ignores readings beyond maxRange: on real logs
    /// no-return beams (glass, black surfaces, open doors) would spray free space outside the building.
    /// Beams between `max_urange` and `max_range` always clear up to `max_urange`.
    pub clear_max_range: bool,
    /// `linearUpdate`: process a scan after the robot translated this far, metres (GMapping 1.0).
    pub linear_update: f64,
    /// `angularUpdate`: process a scan after the robot turned this much, radians (GMapping 0.5).
    pub angular_update: f64,
    /// `temporalUpdate`: process a scan when this many seconds passed since the last one; negative
    /// disables it (GMapping -1).
    pub temporal_update: f64,
    /// `resampleThreshold`: resample when Neff < threshold × particles (GMapping 0.5).
    pub resample_threshold: f64,
    /// `sigma`: the scan matcher's endpoint-match sigma: score += exp(-d²/sigma), d in metres (GMapping 0.05).
    pub sigma: f64,
    /// `lsigma`: the likelihood's sigma: log-likelihood += -d²/lsigma per beam (GMapping 0.075).
    pub lsigma: f64,
    /// `ogain`: gain smoothing the likelihood: weights are exp((l - l_max) / (ogain × particles)) (GMapping 3).
    pub ogain: f64,
    /// `kernelSize`: half-width in cells of the window searched for an occupied cell around each beam
    /// end point (GMapping 1, i.e. 3×3).
    pub kernel_size: i32,
    /// `lstep`: initial linear step of the hill-climbing optimiser, metres (GMapping 0.05).
    pub lstep: f64,
    /// `astep`: initial angular step of the hill-climbing optimiser, radians (GMapping 0.05).
    pub astep: f64,
    /// `iterations`: number of step halvings of the optimiser (GMapping 5).
    pub iterations: u32,
    /// `lskip`: the matcher uses every (lskip+1)-th beam (GMapping 0: all beams).
    pub lskip: usize,
    /// `minimumScore`: the matched pose replaces the motion-model pose only when the match score exceeds
    /// this (GMapping 0).
    pub minimum_score: f64,
    /// `srr`: odometry translation error from translation (GMapping 0.1).
    pub srr: f64,
    /// `srt`: odometry rotation error from translation, rad/m (GMapping 0.2).
    pub srt: f64,
    /// `str`: odometry translation error from rotation, m/rad (GMapping 0.1).
    pub str: f64,
    /// `stt`: odometry rotation error from rotation (GMapping 0.2).
    pub stt: f64,
    /// `occ_thresh`: a cell of the output map is occupied when hits/visits exceeds this (GMapping 0.25).
    pub occ_thresh: f64,
    /// Not GMapping: match only the beams whose end point finds an occupied cell at the motion-model pose
    /// (the "frontier guard"; see [`crate::scan_matcher::ScanMatcher::beams_in_map`]). Off by default.
    pub frontier_guard: bool,
    /// Not GMapping: metres of each beam before its end point, and as far behind it, marked as seen
    /// ("known") in every particle's map; 0 (the default) keeps GMapping's hits-only matching.
    /// When positive, a beam whose window finds no occupied cell and whose end point lies in never-seen
    /// space scores `unknown_score` and costs no likelihood, instead of scoring 0 and costing
    /// `nullLikelihood`: GMapping's score otherwise rewards poses that pull beams ending beyond the mapped
    /// region back onto it, which drags the pose backwards whenever the robot drives into new space.
    pub seen_band: f64,
    /// Score of a beam ending in never-seen space when `seen_band` is on, as a fraction of a perfect match.
    pub unknown_score: f64,
    /// Not GMapping: `matcher`, the scan matcher: `gmapping` (the default: GMapping's kernel search per beam
    /// and pose) or `field` (a likelihood field of surface segments built once per particle and update, one
    /// table read per beam, then Gauss-Newton refinement; see `field`).
    pub matcher: MatcherKind,
    /// Not GMapping: `field_reach`, cells: how far from a surface the `field` matcher still finds it (a beam
    /// ending farther from every surface is unmatched). GMapping's kernel reaches `kernel_size` + ½ cell.
    pub field_reach: i32,
    /// Not GMapping: `field_lines`: the `field` matcher measures a beam's distance to the line through the
    /// cell means around the nearest occupied cell (a segment one cell long), where they lie on a line;
    /// off: to the nearest cell mean, as GMapping.
    pub field_lines: bool,
    /// Not GMapping: `refine_iterations`: Gauss-Newton iterations refining the `field` matcher's hill-climbed
    /// pose (0: none).
    pub refine_iterations: u32,
    /// Not GMapping: `weight_all_beams`: the likelihood that weighs particles uses every beam within the
    /// usable range; off: the matched beams only (every `lskip`+1-th), as GMapping.
    pub weight_all_beams: bool,
    /// Not GMapping: `heading_search`, radians: before hill climbing, the `field` matcher tries the
    /// motion-model pose turned by every multiple of `heading_step` within ±this and climbs from the best
    /// (0: off). The narrow kernel of the presets has a narrow basin: a heading error of 0.05 rad (one
    /// sigma of GMapping's `srt` over 0.25 m) moves end points 4 m away by 20 cm, beyond the field's reach.
    pub heading_search: f64,
    /// Not GMapping: `heading_step`, radians: the heading search's step.
    pub heading_step: f64,
    /// Not GMapping: `motion_prior`: the `field` matcher maximises the scan score plus the log of the
    /// motion model's density around the particle's sample (GMapping's noise model, `srr`..`stt`, over the
    /// odometry since the last processed scan), scaled by this weight; 0: the scan score alone, as
    /// GMapping. Without it, a direction the scan does not observe (along a corridor whose walls have no
    /// features within range) is free to drift with the matcher's small model errors.
    pub motion_prior: f64,
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
    /// Not GMapping: `scan_odometry`: match every scan against a local map of the scans before it and move
    /// the particles by the matched increments instead of the raw odometry's (see `scan_odometry`).
    /// Off (the default): raw odometry, as GMapping.
    pub scan_odometry: bool,
    /// Not GMapping: `scan_odometry_submap`: scans per submap of the scan odometry's local map (it matches
    /// against the last `scan_odometry_submap` to 2 × `scan_odometry_submap` scans).
    pub scan_odometry_submap: usize,
    /// Not GMapping: `scan_odometry_range`, metres: beams longer than this (or than `max_urange`) are not
    /// used by the scan odometry.
    pub scan_odometry_range: f64,
    /// Not GMapping: `scan_odometry_sigma`: the scan odometry matcher's score sigma (as `sigma`, m²).
    pub scan_odometry_sigma: f64,
    /// Not GMapping: `scan_odometry_heading_search`, radians: the scan odometry matcher tries headings within
    /// ± this of the odometry's before it climbs (0: off).
    pub scan_odometry_heading_search: f64,
    /// Not GMapping: `scan_odometry_reach`, cells: the scan odometry's field reach (as `field_reach`). Its
    /// increments are centimetres, so a short reach suffices, and its field is built for every scan.
    pub scan_odometry_reach: i32,
    /// Not GMapping: `wall_hits`: in the output map a beam's free-space trace stops at the first cell on its
    /// way that at least this many beams ended in (see `map_build`); 0: traces run to the end
    /// point, as GMapping's.
    pub wall_hits: u32,
    /// Not GMapping: `kernel_likelihood`: with the `field` matcher, weigh each particle by GMapping's kernel
    /// likelihood (`kernel_size`, `lsigma`) at its matched pose rather than by the field's distances: the
    /// field finds the pose, GMapping's likelihood tells the particles apart.
    pub kernel_likelihood: bool,
    /// Not GMapping: `loop_closure`: when the log ends, smooth the best particle's trajectory with a pose
    /// graph whose loop edges match each processed scan against the scans around the place it passed a loop
    /// ago (see `loop_closure`), and map from the smoothed poses. Off (the default): the filter's
    /// trajectory, as GMapping.
    pub loop_closure: bool,
    /// Not GMapping: `loop_min_travel`, metres driven: a place is a loop ago when the robot drove at least this
    /// far since it passed there.
    pub loop_min_travel: f64,
    /// Not GMapping: `loop_search_radius`, metres: a scan is matched against the place passed a loop ago
    /// nearest to it, when nearer than this.
    pub loop_search_radius: f64,
    /// Not GMapping: `loop_submap_nodes`: the local map of a place is the processed scans within this many of
    /// it, before and after.
    pub loop_submap_nodes: usize,
    /// Not GMapping: `loop_window`, metres: the loop match searches translations within ± this of where the
    /// filter put the scan.
    pub loop_window: f64,
    /// Not GMapping: `loop_heading_window`, radians: the loop match searches headings within ± this.
    pub loop_heading_window: f64,
    /// Not GMapping: `loop_min_matched`: a loop match is kept when at least this fraction of the scan's beams
    /// found a surface of the local map.
    pub loop_min_matched: f64,
    /// Not GMapping: `loop_chain_sigma`, metres: the standard deviation of the filter's own increment between
    /// two processed scans (each axis), as the pose graph's chain trusts it.
    pub loop_chain_sigma: f64,
    /// Not GMapping: `loop_chain_heading_sigma`, radians: the same for the increment's heading.
    pub loop_chain_heading_sigma: f64,
    /// Not GMapping: `loop_sigma`, metres: added (in quadrature, each axis) to a loop match's standard
    /// deviation from the matcher's information, which counts every beam as independent.
    pub loop_sigma: f64,
    /// Not GMapping: `loop_heading_sigma`, radians: the same for the loop match's heading.
    pub loop_heading_sigma: f64,
    /// Not GMapping: `loop_range`, metres: beams longer than this (or than `max_urange`) are not used by the
    /// loop matches.
    pub loop_range: f64,
}

impl Default for SlamParams {
    fn default() -> Self {
        SlamParams {
            particles: 30,
            delta: 0.05,
            max_range: 80.0,
            max_urange: 80.0,
            clear_max_range: false,
            linear_update: 1.0,
            angular_update: 0.5,
            temporal_update: -1.0,
            resample_threshold: 0.5,
            sigma: 0.05,
            lsigma: 0.075,
            ogain: 3.0,
            kernel_size: 1,
            lstep: 0.05,
            astep: 0.05,
            iterations: 5,
            lskip: 0,
            minimum_score: 0.0,
            srr: 0.1,
            srt: 0.2,
            str: 0.1,
            stt: 0.2,
            occ_thresh: 0.25,
            frontier_guard: false,
            seen_band: 0.0,
            unknown_score: 0.5,
            matcher: MatcherKind::Gmapping,
            field_reach: 3,
            field_lines: true,
            refine_iterations: 0,
            weight_all_beams: false,
            heading_search: 0.0,
            heading_step: 0.01,
            motion_prior: 0.0,
            odometry_calibration: 0.0,
            scan_odometry: false,
            scan_odometry_submap: 60,
            scan_odometry_range: 30.0,
            scan_odometry_sigma: 0.001,
            scan_odometry_heading_search: 0.1,
            scan_odometry_reach: 3,
            wall_hits: 0,
            kernel_likelihood: false,
            loop_closure: false,
            loop_min_travel: 20.0,
            loop_search_radius: 3.0,
            loop_submap_nodes: 10,
            loop_window: 0.4,
            loop_heading_window: 0.05,
            loop_min_matched: 0.6,
            loop_chain_sigma: 0.01,
            loop_chain_heading_sigma: 0.003,
            loop_sigma: 0.02,
            loop_heading_sigma: 0.005,
            loop_range: 30.0,
        }
    }
}

impl SlamParams {
    /// Preset for Experia's Hokuyo URG-04LX class lidar: 4 m range, 240°, 667 beams.
    ///
    /// Usable range = sensor range; update every 0.25 m / 0.25 rad (short range: keep scan overlap high).
    /// The `field` matcher (see [`SlamParams::matcher`]) with a narrow kernel (`sigma` 0.001: exp(-d²/sigma)
    /// halves at 2.6 cm, where GMapping's 0.05 is still 0.99), a ±0.2 rad heading search, a short climb
    /// (`iterations` 2) finished by Gauss-Newton (`refine_iterations` 10) and the motion-model prior
    /// (`motion_prior` 1); `lskip` 1 (every 2nd beam, 0.72°) for matching, all beams for mapping;
    /// `seen_band` 0.3 m (`unknown_score` 0.5). On long-range real data (the Freiburg log, 1 m updates, 15 m
    /// usable range) `unknown_score` 0 and `sigma` 0.003 worked instead (see BENCHMARKS.md).
    pub fn hokuyo() -> Self {
        SlamParams {
            max_range: 4.0,
            max_urange: 4.0,
            linear_update: 0.25,
            angular_update: 0.25,
            ..SlamParams::field_matcher()
        }
    }

    /// Preset for Prawn's RpLidar A1 class lidar: 6 m range, 360°, 1° resolution, 5 Hz.
    ///
    /// Usable range = sensor range; update every 0.3 m / 0.25 rad; the matcher as in [`SlamParams::hokuyo`].
    pub fn rplidar() -> Self {
        SlamParams {
            max_range: 6.0,
            max_urange: 6.0,
            linear_update: 0.3,
            angular_update: 0.25,
            ..SlamParams::field_matcher()
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
    /// - `loop_closure` on: at the end of the log the best particle's trajectory is smoothed by a pose graph
    ///   with loop edges (see [`SlamParams::loop_closure`]): on ACES every particle descended from one ancestor
    ///   before its long loops, and relations across them were 0.2-0.4 m off on every seed.
    ///
    /// Measured on the raw ACES and Freiburg 079 benchmark logs (BENCHMARKS.md, "Real benchmark logs").
    pub fn matched() -> Self {
        SlamParams {
            scan_odometry: true,
            srr: 0.05,
            srt: 0.1,
            str: 0.05,
            stt: 0.1,
            matcher: MatcherKind::Field,
            sigma: 0.01,
            lsigma: 0.03,
            iterations: 2,
            refine_iterations: 10,
            heading_search: 0.05,
            heading_step: 0.01,
            motion_prior: 1.0,
            field_reach: 6,
            wall_hits: 2,
            loop_closure: true,
            ..SlamParams::default()
        }
    }

    /// These parameters with the `field` matcher set up to match one scan on its own: every beam, no seen band,
    /// a short climb and Gauss-Newton, none of the filter's options (minimum score, frontier guard, calibration,
    /// all-beam or kernel weighting). What the scan odometry and the loop closure start from.
    pub(crate) fn field_matcher_alone(&self) -> Self {
        SlamParams {
            matcher: MatcherKind::Field,
            lskip: 0,
            seen_band: 0.0,
            iterations: 2,
            refine_iterations: 10,
            heading_step: 0.01,
            minimum_score: 0.0,
            frontier_guard: false,
            odometry_calibration: 0.0,
            weight_all_beams: false,
            kernel_likelihood: false,
            ..self.clone()
        }
    }

    /// GMapping's defaults with the `field` matcher settings both robot presets share.
    fn field_matcher() -> Self {
        SlamParams {
            matcher: MatcherKind::Field,
            sigma: 0.001,
            lskip: 1,
            seen_band: 0.3,
            iterations: 2,
            refine_iterations: 10,
            heading_search: 0.2,
            heading_step: 0.02,
            motion_prior: 1.0,
            ..SlamParams::default()
        }
    }

    /// Sets the parameter called `name` (the field's name) from its text `value`; for command lines and
    /// scenario files. Errors name the parameter and what is wrong.
    pub fn set(&mut self, name: &str, value: &str) -> Result<(), String> {
        let f = || value.trim().parse::<f64>().map_err(|e| format!("{name}: {e} ('{value}')"));
        let u = || value.trim().parse::<usize>().map_err(|e| format!("{name}: {e} ('{value}')"));
        let b = || value.trim().parse::<bool>().map_err(|e| format!("{name}: {e} ('{value}')"));
        match name {
            "particles" => self.particles = u()?,
            "delta" => self.delta = f()?,
            "max_range" => self.max_range = f()?,
            "max_urange" => self.max_urange = f()?,
            "clear_max_range" => self.clear_max_range = b()?,
            "linear_update" => self.linear_update = f()?,
            "angular_update" => self.angular_update = f()?,
            "temporal_update" => self.temporal_update = f()?,
            "resample_threshold" => self.resample_threshold = f()?,
            "sigma" => self.sigma = f()?,
            "lsigma" => self.lsigma = f()?,
            "ogain" => self.ogain = f()?,
            "kernel_size" => self.kernel_size = value.trim().parse().map_err(|e| format!("{name}: {e}"))?,
            "lstep" => self.lstep = f()?,
            "astep" => self.astep = f()?,
            "iterations" => self.iterations = value.trim().parse().map_err(|e| format!("{name}: {e}"))?,
            "lskip" => self.lskip = u()?,
            "minimum_score" => self.minimum_score = f()?,
            "srr" => self.srr = f()?,
            "srt" => self.srt = f()?,
            "str" => self.str = f()?,
            "stt" => self.stt = f()?,
            "occ_thresh" => self.occ_thresh = f()?,
            "frontier_guard" => self.frontier_guard = b()?,
            "seen_band" => self.seen_band = f()?,
            "unknown_score" => self.unknown_score = f()?,
            "matcher" => self.matcher = value.parse()?,
            "field_reach" => self.field_reach = value.trim().parse().map_err(|e| format!("{name}: {e}"))?,
            "field_lines" => self.field_lines = b()?,
            "refine_iterations" => self.refine_iterations = value.trim().parse().map_err(|e| format!("{name}: {e}"))?,
            "weight_all_beams" => self.weight_all_beams = b()?,
            "heading_search" => self.heading_search = f()?,
            "heading_step" => self.heading_step = f()?,
            "motion_prior" => self.motion_prior = f()?,
            "odometry_calibration" => self.odometry_calibration = f()?,
            "scan_odometry" => self.scan_odometry = b()?,
            "scan_odometry_submap" => self.scan_odometry_submap = u()?,
            "scan_odometry_range" => self.scan_odometry_range = f()?,
            "scan_odometry_sigma" => self.scan_odometry_sigma = f()?,
            "scan_odometry_heading_search" => self.scan_odometry_heading_search = f()?,
            "scan_odometry_reach" => {
                self.scan_odometry_reach = value.trim().parse().map_err(|e| format!("{name}: {e}"))?
            }
            "kernel_likelihood" => self.kernel_likelihood = b()?,
            "loop_closure" => self.loop_closure = b()?,
            "loop_min_travel" => self.loop_min_travel = f()?,
            "loop_search_radius" => self.loop_search_radius = f()?,
            "loop_submap_nodes" => self.loop_submap_nodes = u()?,
            "loop_window" => self.loop_window = f()?,
            "loop_heading_window" => self.loop_heading_window = f()?,
            "loop_min_matched" => self.loop_min_matched = f()?,
            "loop_chain_sigma" => self.loop_chain_sigma = f()?,
            "loop_chain_heading_sigma" => self.loop_chain_heading_sigma = f()?,
            "loop_sigma" => self.loop_sigma = f()?,
            "loop_heading_sigma" => self.loop_heading_sigma = f()?,
            "loop_range" => self.loop_range = f()?,
            "wall_hits" => self.wall_hits = value.trim().parse().map_err(|e| format!("{name}: {e} ('{value}')"))?,
            _ => return Err(format!("unknown SLAM parameter '{name}'")),
        }
        Ok(())
    }

    /// Checks that every parameter is in its domain; returns a description of the first that is not.
    pub fn validate(&self) -> Result<(), String> {
        let pos = |name: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(format!("{name} must be a positive finite number, got {v}"))
            }
        };
        let nonneg = |name: &str, v: f64| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(format!("{name} must be a non-negative finite number, got {v}"))
            }
        };
        if self.particles == 0 || self.particles > 100_000 {
            return Err(format!("particles must be in 1..=100000, got {}", self.particles));
        }
        pos("delta", self.delta)?;
        pos("max_range", self.max_range)?;
        pos("max_urange", self.max_urange)?;
        nonneg("linear_update", self.linear_update)?;
        nonneg("angular_update", self.angular_update)?;
        if self.temporal_update.is_nan() {
            return Err("temporal_update must not be NaN".into());
        }
        nonneg("resample_threshold", self.resample_threshold)?;
        pos("sigma", self.sigma)?;
        pos("lsigma", self.lsigma)?;
        pos("ogain", self.ogain)?;
        if !(0..=8).contains(&self.kernel_size) {
            return Err(format!("kernel_size must be in 0..=8, got {}", self.kernel_size));
        }
        pos("lstep", self.lstep)?;
        pos("astep", self.astep)?;
        if self.iterations > 30 {
            return Err(format!("iterations must be at most 30, got {}", self.iterations));
        }
        if !self.minimum_score.is_finite() {
            return Err("minimum_score must be finite".into());
        }
        for (n, v) in [("srr", self.srr), ("srt", self.srt), ("str", self.str), ("stt", self.stt)] {
            nonneg(n, v)?;
        }
        nonneg("seen_band", self.seen_band)?;
        nonneg("unknown_score", self.unknown_score)?;
        if !(1..=16).contains(&self.field_reach) {
            return Err(format!("field_reach must be in 1..=16, got {}", self.field_reach));
        }
        if !(1..=16).contains(&self.scan_odometry_reach) {
            return Err(format!("scan_odometry_reach must be in 1..=16, got {}", self.scan_odometry_reach));
        }
        nonneg("heading_search", self.heading_search)?;
        nonneg("motion_prior", self.motion_prior)?;
        nonneg("odometry_calibration", self.odometry_calibration)?;
        if self.odometry_calibration > 0.0 && self.matcher != MatcherKind::Field {
            return Err(
                "odometry_calibration needs matcher = field (it learns from the field matcher's information)".into()
            );
        }
        pos("heading_step", self.heading_step)?;
        if !(1..=100_000).contains(&self.scan_odometry_submap) {
            return Err(format!("scan_odometry_submap must be in 1..=100000, got {}", self.scan_odometry_submap));
        }
        pos("scan_odometry_range", self.scan_odometry_range)?;
        pos("scan_odometry_sigma", self.scan_odometry_sigma)?;
        nonneg("scan_odometry_heading_search", self.scan_odometry_heading_search)?;
        if self.scan_odometry_heading_search / 0.01 > 1000.0 {
            return Err("scan_odometry_heading_search must be at most 10 rad".into());
        }
        if self.heading_search / self.heading_step > 1000.0 {
            return Err("heading_search / heading_step must be at most 1000".into());
        }
        if self.refine_iterations > 100 {
            return Err(format!("refine_iterations must be at most 100, got {}", self.refine_iterations));
        }
        nonneg("loop_min_travel", self.loop_min_travel)?;
        nonneg("loop_search_radius", self.loop_search_radius)?;
        if self.loop_submap_nodes > 10_000 {
            return Err(format!("loop_submap_nodes must be at most 10000, got {}", self.loop_submap_nodes));
        }
        nonneg("loop_window", self.loop_window)?;
        if self.loop_window / self.delta > 200.0 {
            return Err("loop_window / delta must be at most 200 cells".into());
        }
        nonneg("loop_heading_window", self.loop_heading_window)?;
        if self.loop_heading_window / 0.01 > 1000.0 {
            return Err("loop_heading_window must be at most 10 rad".into());
        }
        if !(self.loop_min_matched.is_finite() && (0.0..=1.0).contains(&self.loop_min_matched)) {
            return Err(format!("loop_min_matched must be in [0, 1], got {}", self.loop_min_matched));
        }
        pos("loop_range", self.loop_range)?;
        pos("loop_chain_sigma", self.loop_chain_sigma)?;
        pos("loop_chain_heading_sigma", self.loop_chain_heading_sigma)?;
        pos("loop_sigma", self.loop_sigma)?;
        pos("loop_heading_sigma", self.loop_heading_sigma)?;
        if !(self.occ_thresh.is_finite() && (0.0..1.0).contains(&self.occ_thresh)) {
            return Err(format!("occ_thresh must be in [0, 1), got {}", self.occ_thresh));
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

    #[test]
    fn odometry_calibration_is_refused_without_the_field_matcher() {
        let p = SlamParams { odometry_calibration: 20.0, ..SlamParams::default() };
        assert!(p.validate().unwrap_err().contains("odometry_calibration needs matcher = field"));
        assert!(SlamParams { odometry_calibration: 20.0, ..SlamParams::hokuyo() }.validate().is_ok());
        assert!(SlamParams { odometry_calibration: -1.0, ..SlamParams::hokuyo() }.validate().is_err());
    }

    #[test]
    fn defaults_are_gmappings() {
        let p = SlamParams::default();
        assert_eq!(p.particles, 30);
        assert_eq!((p.srr, p.srt, p.str, p.stt), (0.1, 0.2, 0.1, 0.2));
        assert_eq!((p.linear_update, p.angular_update, p.temporal_update), (1.0, 0.5, -1.0));
        assert_eq!((p.sigma, p.lsigma, p.ogain, p.kernel_size), (0.05, 0.075, 3.0, 1));
        assert!(p.validate().is_ok());
        assert!(SlamParams::hokuyo().validate().is_ok());
        assert!(SlamParams::rplidar().validate().is_ok());
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
    fn validation_rejects_nonsense() {
        let p = SlamParams { delta: 0.0, ..SlamParams::default() };
        assert!(p.validate().unwrap_err().contains("delta"));
        let p = SlamParams { particles: 0, ..SlamParams::default() };
        assert!(p.validate().is_err());
        let p = SlamParams { sigma: f64::NAN, ..SlamParams::default() };
        assert!(p.validate().is_err());
    }
}
