//! The merger's flags (`mrslam merge`, two maps or more): the algorithm, its settings, the pipeline around it.

use super::args::one_of;
use clap::Args;
use mrslam_merge::{Algorithm, BoundaryWalls, Contact, Encoding, FusionRule, MergeParams, MergerConfig, Model};
use nalgebra::Point2;

/// The merger and the pipeline around it, as flags.
#[derive(Args)]
pub struct MergerArgs {
    /// Merge algorithm: `sift` (the paper's, Alg. 3), `rmap` (Park's R-map baseline, Alg. 1), `correlative`
    /// (global correlative search by branch and bound) or `cascade` (`sift`, `sift` with every map's boundary as
    /// walls, then `correlative`: the first answer the gate accepts; the default, chosen by measurement on
    /// generated plans, cuts of a real map and two robots' SLAM maps: benchmarks/runs/2026-12-02-merge-cascade.md).
    #[arg(long, default_value = "cascade", value_parser = one_of::<Algorithm>(Algorithm::ALL.map(Algorithm::name)))]
    pub algorithm: Algorithm,
    /// Transform model: rigid, similarity or homography (the paper's; its rigid part is used).
    #[arg(long, default_value = "rigid", value_parser = one_of::<Model>(Model::ALL.map(Model::name)))]
    pub model: Model,
    /// Lowe's ratio for descriptor matching, in (0, 1].
    #[arg(long, default_value_t = 0.75, value_parser = ratio)]
    pub ratio: f32,
    /// Keep only mutual nearest-neighbour matches.
    #[arg(long)]
    pub mutual: bool,
    /// Candidates per feature: 1 = nearest neighbour with the ratio test (the paper); k > 1 = the k nearest.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=16))]
    pub candidates: u32,
    /// Transforms handed to verification, strongest first (sequential RANSAC); 1 = the paper's single answer.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=16))]
    pub hypotheses: u32,
    /// Grow occupied cells by this many cells before SIFT (0 = the map as it is).
    #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u32).range(0..=4))]
    pub wall_dilation: u32,
    /// SIFT starts its pyramid at the map's own cells instead of the map doubled (OpenCV's `firstOctave = 0`
    /// rather than -1): for SLAM maps, whose finest scale is the walls' jitter; about half the SIFT time.
    #[arg(long)]
    pub no_upscale: bool,
    /// The verification gate's wall tolerance: a wall of map b meets a wall of map a within this many cells
    /// (1: the 3x3 neighbourhood; 2 lets the walls of two robots' SLAM runs meet).
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(0..=4))]
    pub wall_tolerance: u32,
    /// Which maps get walls where their free space meets unknown: `unmarked` (maps with almost no occupied
    /// cells: map_server's light-grey walls, glass), `always` (every map, its own walls kept) or `off` (the maps
    /// as they are: the paper's merger has no such step; a cascade then skips its `sift+boundary` stage).
    #[arg(
        long,
        default_value = "unmarked",
        value_parser = one_of::<BoundaryWalls>(BoundaryWalls::ALL.map(BoundaryWalls::name))
    )]
    pub boundary_walls: BoundaryWalls,
    /// The correlative merger's significance test: its best pose must score this share above every pose clearly
    /// apart from it (Lowe's ratio test), else the merge is refused as ambiguous, naming the rival; 0 turns the
    /// test off.
    #[arg(long, value_parser = margin, default_value_t = MergerConfig::default().min_margin)]
    pub min_margin: f64,
    /// The correlative merger's answer is not checked by the same search the other way round (the other map's
    /// walls on this one's); the check refuses answers that are ambiguous that way.
    #[arg(long)]
    pub one_way: bool,
    /// Map-to-image encoding: `walls` (free and unknown alike) or `paper` (unknown grey).
    #[arg(long, default_value = "walls", value_parser = one_of::<Encoding>(Encoding::ALL.map(Encoding::name)))]
    pub encoding: Encoding,
    /// How aligned cells combine: log-odds-sum or occupied-free-unknown.
    #[arg(long, default_value = "log-odds-sum", value_parser = one_of::<FusionRule>(FusionRule::ALL.map(FusionRule::name)))]
    pub fusion: FusionRule,
    /// Skip the verification gate and accept whatever the algorithm answers.
    #[arg(long)]
    pub no_verify: bool,
    /// Seed of the merger's random draws (the robust estimator's, the R-map's).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Two robots that met, `XA,YA,XB,YB,WITHIN`: robot a at (XA, YA) in map a's frame and robot b at (XB, YB)
    /// in map b's, at most WITHIN metres apart (a radio's range, plus their pose error). The gate refuses any
    /// transform that puts them farther apart, as it does for the online merges of robots in contact (two maps
    /// only).
    #[arg(long, value_name = "XA,YA,XB,YB,WITHIN", value_parser = contact, allow_hyphen_values = true)]
    pub contact: Option<Contact>,
}

impl MergerArgs {
    /// The merger the flags describe.
    pub fn config(&self) -> MergerConfig {
        MergerConfig {
            algorithm: self.algorithm,
            model: self.model,
            encoding: self.encoding,
            ratio: self.ratio,
            candidates: self.candidates as usize,
            mutual: self.mutual,
            hypotheses: self.hypotheses as usize,
            wall_dilation: self.wall_dilation as usize,
            upscale: !self.no_upscale,
            // One merge has the machine to itself: the two maps' features on two threads (the studies, which run
            // merges side by side, keep one thread per merge).
            parallel: true,
            // `sift` settles most maps a user brings (a real map's cuts: 0.33 s alone, 0.8 s waiting for
            // `sift+boundary` beside it): the stages one after the other.
            side_by_side: false,
            min_margin: self.min_margin,
            cross_check: !self.one_way,
            seed: self.seed,
        }
    }

    /// The pipeline around the merger: the gate, the fusion, the boundary walls.
    pub fn params(&self) -> MergeParams {
        let mut mp = MergeParams {
            verify_enabled: !self.no_verify,
            fusion: self.fusion,
            boundary_walls: self.boundary_walls,
            ..MergeParams::default()
        };
        mp.verify.wall_tolerance_cells = self.wall_tolerance as usize;
        mp.contact = self.contact;
        mp
    }
}

/// Reads `--ratio`: a number in (0, 1] (a ratio above 1 accepts every match).
fn ratio(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(r) if r > 0.0 && r <= 1.0 => Ok(r),
        Ok(r) => Err(format!("{r} is outside (0, 1]")),
        Err(e) => Err(e.to_string()),
    }
}

/// Reads `--contact`: five finite numbers separated by commas, the last above 0.
fn contact(s: &str) -> Result<Contact, String> {
    let v: Vec<f64> =
        s.split(',').map(|x| x.trim().parse::<f64>().map_err(|e| format!("`{x}`: {e}"))).collect::<Result<_, _>>()?;
    match v[..] {
        [xa, ya, xb, yb, within] if v.iter().all(|x| x.is_finite() && x.abs() <= 1e6) && within > 0.0 => {
            Ok(Contact { a: Point2::new(xa, ya), b: Point2::new(xb, yb), within_m: within, search_within: false })
        }
        [_, _, _, _, within] if within <= 0.0 => Err(format!("WITHIN must be above 0 metres, got {within}")),
        [_, _, _, _, _] => Err("the numbers must be finite metres within ±1e6".into()),
        _ => Err(format!("expected XA,YA,XB,YB,WITHIN (five numbers), got {} number(s)", v.len())),
    }
}

/// Reads `--min-margin`: a number in [0, 1).
fn margin(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(m) if (0.0..1.0).contains(&m) => Ok(m),
        Ok(m) => Err(format!("{m} is outside [0, 1)")),
        Err(e) => Err(e.to_string()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        merger: MergerArgs,
    }

    #[test]
    fn the_default_flags_are_the_default_merger_on_two_threads() {
        let cli = Cli::try_parse_from(["x", "--seed", "4"]).unwrap();
        let expected = MergerConfig { parallel: true, ..MergerConfig::new(Algorithm::Cascade, 4) };
        assert_eq!(cli.merger.config(), expected);
        assert_eq!(cli.merger.params(), MergeParams::default());
    }

    #[test]
    fn a_contact_reads_as_five_numbers_and_nothing_else() {
        let cli = Cli::try_parse_from(["x", "--contact", "-1.5,2,3,-4e0,12"]).unwrap();
        let c = cli.merger.params().contact.unwrap();
        assert_eq!((c.a, c.b, c.within_m), (Point2::new(-1.5, 2.0), Point2::new(3.0, -4.0), 12.0));
        for (bad, says) in [
            ("1,2,3,4", "five numbers"),
            ("1,2,3,4,0", "above 0"),
            ("1,2,3,4,-2", "above 0"),
            ("1,2,nan,4,5", "finite"),
            ("1,2,3,4,1e300", "finite"),
            ("1,2,x,4,5", "`x`"),
        ] {
            let e = Cli::try_parse_from(["x", "--contact", bad]).err().unwrap().to_string();
            assert!(e.contains(says), "{bad}: {e}");
        }
    }
}
