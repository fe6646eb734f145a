//! Runs the correlative merger on two map files (optionally against a known `T_a_b`) or on generated pairs,
//! with parameter overrides, and prints each answer:
//! `cargo run --release -p mrslam-dev --bin correlative_probe -- A.yaml B.yaml [x y theta] [key=value ...]`
//! `cargo run --release -p mrslam-dev --bin correlative_probe -- gen [key=value ...]`.

use mrslam_core::map_io::read_ros_map;
use mrslam_core::{OccupancyGrid, Pose2, pose};
use mrslam_merge::floorplan::{FloorplanParams, generate};
use mrslam_merge::pairs::{PairSpec, cut_pair};
use mrslam_merge::{CorrelativeMerger, CorrelativeParams, MergeParams, Merger, SiftMerger, merge};

fn set(p: &mut CorrelativeParams, kv: &str) {
    let (k, v) = kv.split_once('=').expect("key=value");
    let f: f64 = v.parse().expect("number");
    match k {
        "res" => p.search.resolution = f,
        "screen" => p.search.screen_resolution = f,
        "cands" => p.search.screen_candidates = f as usize,
        "sigma" => p.search.sigma_cells = f,
        "fsigma" => p.fine.sigma_cells = f,
        "pen" => p.search.free_penalty = f,
        "fpen" => p.fine.free_penalty = f,
        "dense" => p.search.dense_free_share = f,
        "fbpen" => p.fallback.free_penalty = f,
        "fbarea" => p.fallback.min_overlap_m2 = f,
        "depth" => p.search.depth = f as usize,
        "astep" => p.search.angle_step_scale = f,
        "pts" => p.search.max_points = f as usize,
        "fpts" => p.fine.max_points = f as usize,
        "per" => p.search.per_rotation = f as usize,
        "min" => p.search.min_score = f,
        "keep" => p.search.keep_ratio = f,
        "hyp" => p.answer.hypotheses = f as usize,
        "fang" => p.fine.angles = f as usize,
        "acc" => p.answer.min_acceptance = f,
        "area" => p.answer.min_overlap_m2 = f,
        "par" => p.parallel = f != 0.0,
        "margin" => p.answer.min_margin = f,
        "rdist" => p.answer.rival_distinct_m = f,
        "rivals" => p.search.rivals = f as usize,
        "fbrivals" => p.fallback.rivals = f as usize,
        "fbalways" => p.fallback.always = f != 0.0,
        "cross" => p.answer.cross_check = f != 0.0,
        _ => panic!("unknown key {k}"),
    }
}

/// Share of b's walls over a's known cells with a wall of a within `k` cells (square), for k = 1..=4.
fn tolerant_walls(a: &OccupancyGrid, b: &OccupancyGrid, t: &Pose2) -> Vec<f64> {
    use mrslam_core::CellState;
    let walls = mrslam_merge::dev::wall_points(b);
    (1..=4i64)
        .map(|k| {
            let (mut n, mut hit) = (0usize, 0usize);
            for p in &walls {
                let (ix, iy) = a.world_to_cell_i(&(t * p));
                let Some(l) = a.get_checked(ix, iy) else { continue };
                if CellState::from_log_odds(l) == CellState::Unknown {
                    continue;
                }
                n += 1;
                let near = (-k..=k).any(|dy| {
                    (-k..=k).any(|dx| {
                        a.get_checked(ix + dx, iy + dy)
                            .is_some_and(|l| CellState::from_log_odds(l) == CellState::Occupied)
                    })
                });
                hit += usize::from(near);
            }
            hit as f64 / n.max(1) as f64
        })
        .collect()
}

/// b's walls in 20 m tiles (b's frame): per tile with 200+ walls over a's known cells, the wall agreement at
/// `t` and after ICP of that tile alone, as (walls, at t, after tile ICP, tile ICP shift m, rotation deg).
fn tiles(a: &OccupancyGrid, b: &OccupancyGrid, t: &Pose2) {
    let walls = mrslam_merge::dev::wall_points(b);
    let mut by_tile: std::collections::BTreeMap<(i64, i64), Vec<nalgebra::Point2<f64>>> = Default::default();
    for p in &walls {
        by_tile.entry(((p.x / 20.0).floor() as i64, (p.y / 20.0).floor() as i64)).or_default().push(*p);
    }
    for (k, pts) in by_tile {
        let (n, m) = mrslam_merge::dev::wall_hits(a, &pts, t);
        if n < 200 {
            continue;
        }
        let local = mrslam_merge::dev::refine(a, &pts, t, &mrslam_merge::RefineParams::default());
        let (_, m2) = mrslam_merge::dev::wall_hits(a, &pts, &local);
        let d = t.inverse() * local;
        println!(
            "  tile {k:?}: {n} walls, agreement {:.2} -> {:.2} after its own ICP (moved {:.2} m, {:.2} deg)",
            m as f64 / n as f64,
            m2 as f64 / n as f64,
            d.translation.vector.norm(),
            d.rotation.angle().to_degrees()
        );
    }
}

/// b's walls placed by `t` on a's free cells with no wall of a within 0.4 m: how many, and the 2 m tiles (a's
/// frame) holding most of them.
fn contradictions(a: &OccupancyGrid, b: &OccupancyGrid, t: &Pose2) {
    use mrslam_core::CellState;
    let walls = mrslam_merge::dev::wall_points(b);
    let k = (0.4 / a.resolution()).round() as i64;
    let state = |ix: i64, iy: i64| a.get_checked(ix, iy).map(CellState::from_log_odds);
    let (mut known, mut bad) = (0usize, 0usize);
    let mut tiles: std::collections::BTreeMap<(i64, i64), usize> = Default::default();
    for p in &walls {
        let q = t * p;
        let (ix, iy) = a.world_to_cell_i(&q);
        match state(ix, iy) {
            Some(CellState::Unknown) | None => continue,
            _ => known += 1,
        }
        if state(ix, iy) != Some(CellState::Free) {
            continue;
        }
        let near = (-k..=k).any(|dy| (-k..=k).any(|dx| state(ix + dx, iy + dy) == Some(CellState::Occupied)));
        if !near {
            bad += 1;
            *tiles.entry(((q.x / 2.0).floor() as i64 * 2, (q.y / 2.0).floor() as i64 * 2)).or_default() += 1;
        }
    }
    let mut v: Vec<_> = tiles.into_iter().collect();
    v.sort_by_key(|t| std::cmp::Reverse(t.1));
    println!(
        "contradictions: {bad} of {known} walls of b over a's known cells lie on free space 0.4 m from any wall of a; top 2 m tiles (x, y): {:?}",
        &v[..v.len().min(12)]
    );
}

fn error(t: &Pose2, truth: &Pose2) -> (f64, f64) {
    let d = truth.inverse() * t;
    (d.translation.vector.norm(), d.rotation.angle().to_degrees().abs())
}

fn run(m: &dyn Merger, a: &OccupancyGrid, b: &OccupancyGrid, truth: Option<&Pose2>) -> (bool, Option<(f64, f64)>, f64) {
    let verify = std::env::var("NOVERIFY").is_err();
    let out = merge(m, a, b, &MergeParams { verify_enabled: verify, ..MergeParams::default() });
    let r = &out.report;
    let t = r.transform.map(|t| pose(t.x, t.y, t.theta));
    let err = t.as_ref().zip(truth).map(|(t, tr)| error(t, tr));
    println!(
        "{}: accepted {} t {:?} err {:?} inl {}/{} conf {:.2} omega {:?} walls {:?} amb {:?} reason {:?} time {:.0} ms {:?}",
        m.name(),
        r.accepted,
        r.transform.map(|t| (t.x, t.y, t.theta)),
        err,
        r.inliers,
        r.matches,
        r.confidence,
        r.acceptance_index,
        r.wall_agreement,
        r.ambiguity,
        r.reason,
        r.time_ms,
        r.timings_ms.iter().map(|(k, v)| format!("{k} {v:.0}")).collect::<Vec<_>>()
    );
    if let Some(t) = &t {
        println!("  wall agreement at 1..4 cells: {:?}", tolerant_walls(a, b, t));
        if std::env::var("TILES").is_ok() {
            tiles(a, b, t);
        }
    }
    (r.accepted, err, r.time_ms)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut p = CorrelativeParams::default();
    if args.first().is_some_and(|s| s == "gen") {
        for kv in &args[1..] {
            set(&mut p, kv);
        }
        let cor = CorrelativeMerger::new(p);
        let sift = SiftMerger::default();
        let mut stats = [[0usize; 3]; 2]; // per algorithm: ok, false, refused
        for seed in 0..8u64 {
            let map = generate(seed, &FloorplanParams { width_m: 29.0, height_m: 29.0, ..FloorplanParams::default() });
            for overlap in [-0.1, 0.1, 0.3, 0.5] {
                let pair = cut_pair(&map, &PairSpec { overlap, max_shift_m: 5.0, rotate: true }, seed);
                println!("seed {seed} overlap {overlap} truth {:?}", pair.t_a_b);
                for (k, m) in [&sift as &dyn Merger, &cor].into_iter().enumerate() {
                    let (acc, err, _) = run(m, &pair.a, &pair.b, Some(&pair.t_a_b));
                    let good = err.is_some_and(|(d, a)| d < 0.3 && a < 2.0) && overlap > 0.0;
                    stats[k][if !acc {
                        2
                    } else if good {
                        0
                    } else {
                        1
                    }] += 1;
                }
            }
        }
        println!("sift ok/false/refused {:?}, correlative {:?}", stats[0], stats[1]);
        return;
    }
    if args.first().is_some_and(|s| s == "trial") {
        // One trial of `mrslam study overlap --floorplans 8 --floorplan-size WxH` (study seed 1): `trial W H
        // OVERLAP REP SEED [key=value ...]`, SEED as results.csv has it.
        let v: Vec<f64> = args[1..4].iter().map(|s| s.parse().expect("number")).collect();
        let rep: u64 = args[4].parse().expect("rep");
        let seed: u64 = args[5].parse().expect("seed");
        for kv in &args[6..] {
            set(&mut p, kv);
        }
        let mix = |mut x: u64| {
            x = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
            x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            x ^ (x >> 31)
        };
        let plan_seed = mix(mix(1 ^ 0xf100_4b1a_0000_0000) ^ (rep % 8));
        let map = generate(plan_seed, &FloorplanParams { width_m: v[0], height_m: v[1], ..FloorplanParams::default() });
        let mut pair = cut_pair(&map, &PairSpec { overlap: v[2], max_shift_m: 5.0, rotate: true }, seed);
        if std::env::var_os("BOUNDARY").is_some() {
            // `--map-style boundary`: every occupied cell dropped to unknown after the cut.
            for g in [&mut pair.a, &mut pair.b] {
                for y in 0..g.height() {
                    for x in 0..g.width() {
                        if g.state(x, y) == mrslam_core::CellState::Occupied {
                            g.set(x, y, 0.0);
                        }
                    }
                }
                // The walls the merge pipeline gives such a map, so the probe sees what the merger sees.
                if let Some(walled) = mrslam_merge::boundary_walls::walls_from_boundary(g) {
                    *g = walled;
                }
            }
        }
        if let Ok(dir) = std::env::var("WRITE") {
            // The pair as map files, and its truth, for the file mode.
            let dir = std::path::Path::new(&dir);
            mrslam_core::map_io::write_ros_map(&pair.a, &dir.join("a.yaml")).expect("write a");
            mrslam_core::map_io::write_ros_map(&pair.b, &dir.join("b.yaml")).expect("write b");
            let t = &pair.t_a_b;
            println!("truth {} {} {}", t.translation.x, t.translation.y, t.rotation.angle());
        }
        let cor = CorrelativeMerger::new(p);
        if let Some(sig) = mrslam_merge::dev::significance(&cor, &pair.a, &pair.b) {
            println!(
                "best {:?} score {} rival {:?} score {} margin {:.3}",
                xyt(&sig.best),
                sig.best_score,
                sig.rival.as_ref().map(xyt),
                sig.rival_score,
                sig.margin()
            );
        }
        run(&cor, &pair.a, &pair.b, Some(&pair.t_a_b));
        return;
    }
    if args.first().is_some_and(|s| s == "gap") {
        // Gap pairs (nothing shared) and low-overlap pairs of generated plans: what separates a coincidence
        // from a true answer? Prints one line per pair: kind, size, seed, accepted (tolerance 1 / 2), error,
        // the best answer's matched walls and the runner-up's.
        for kv in &args[1..] {
            set(&mut p, kv);
        }
        // The whole merger as set (the significance test decides when the fallback search runs); the margin of
        // its answer is printed beside.
        let cor = CorrelativeMerger::new(p);
        for (w, h) in [(18.0, 14.0), (24.0, 18.0)] {
            for seed in 0..60u64 {
                let map =
                    generate(seed % 8, &FloorplanParams { width_m: w, height_m: h, ..FloorplanParams::default() });
                for overlap in [0.0, 0.1, 0.2] {
                    let pair = cut_pair(&map, &PairSpec { overlap, max_shift_m: 5.0, rotate: true }, 1000 + seed);
                    let Ok(al) = cor.align(&pair.a, &pair.b) else {
                        println!("{overlap} {w}x{h} {seed} none");
                        continue;
                    };
                    let out = merge(&cor, &pair.a, &pair.b, &MergeParams::default());
                    let acc = out.report.accepted;
                    let out_err = out.report.transform.map(|t| error(&pose(t.x, t.y, t.theta), &pair.t_a_b));
                    let (d, deg) = error(&al.transform, &pair.t_a_b);
                    let margin =
                        mrslam_merge::dev::significance(&cor, &pair.a, &pair.b).map_or(f64::NAN, |s| s.margin());
                    let second = al.alternatives.first().map_or(0, |h| h.inliers);
                    let agr = mrslam_merge::agreement_within(&pair.a, &pair.b, &al.transform, 2);
                    println!(
                        "{overlap} {w}x{h} {seed} acc {acc} merr {out_err:?} err {d:.3} {deg:.2} margin {margin:.3} inl {} second {second} matches {} common {} walls2 {:.3} omega {:.3}",
                        al.inliers,
                        al.matches,
                        agr.common(),
                        agr.wall_agreement(),
                        agr.acceptance_index()
                    );
                }
            }
        }
        return;
    }
    let a = read_ros_map(args[0].as_ref()).expect("map a");
    let b = read_ros_map(args[1].as_ref()).expect("map b");
    let mut rest = &args[2..];
    let truth = if rest.len() >= 3 && !rest[0].contains('=') {
        let v: Vec<f64> = rest[..3].iter().map(|s| s.parse().expect("number")).collect();
        rest = &rest[3..];
        Some(pose(v[0], v[1], v[2]))
    } else {
        None
    };
    for kv in rest {
        set(&mut p, kv);
    }
    println!("a {}x{} b {}x{}", a.width(), a.height(), b.width(), b.height());
    if let Some(t) = &truth {
        let walls = mrslam_merge::dev::wall_points(&b);
        let refined = mrslam_merge::dev::refine(&a, &walls, t, &mrslam_merge::RefineParams::default());
        if std::env::var("CONTRA").is_ok() {
            contradictions(&a, &b, &refined);
        }
        for (name, t) in [("truth", *t), ("truth+icp", refined)] {
            let agr = mrslam_merge::agreement(&a, &b, &t);
            println!("  wall agreement at 1..4 cells: {:?}", tolerant_walls(&a, &b, &t));
            println!(
                "{name}: {:?} omega {:.3} walls {:.3} ({} of {}) common {}",
                (t.translation.x, t.translation.y, t.rotation.angle()),
                agr.acceptance_index(),
                agr.wall_agreement(),
                agr.walls_matched,
                agr.walls,
                agr.common()
            );
            if std::env::var("TILES").is_ok() {
                tiles(&a, &b, &t);
            }
        }
    }
    let cor = CorrelativeMerger::new(p);
    if let Some(sig) = mrslam_merge::dev::significance(&cor, &a, &b) {
        let (s, c, _) = mrslam_merge::dev::score_near(&cor, &a, &b, &sig.best);
        println!(
            "global best {:?} score {} (wall/free/other points {c:?}, rescored {s}), rival {:?} score {}, margin {:.3}",
            xyt(&sig.best),
            sig.best_score,
            sig.rival.as_ref().map(xyt),
            sig.rival_score,
            sig.margin()
        );
        if let Some(t) = &truth {
            let (s, c, at) = mrslam_merge::dev::score_near(&cor, &a, &b, t);
            println!("global score near the truth {s} at {:?} (wall/free/other points {c:?})", xyt(&at));
        }
        if std::env::var("REVERSE").is_ok() {
            // a's walls on b's field: the same poses seen from the other map.
            for (name, t) in [("best", Some(sig.best)), ("truth", truth)] {
                let Some(t) = t else { continue };
                let (s, c, _) = mrslam_merge::dev::score_near(&cor, &b, &a, &t.inverse());
                println!("reverse score at the {name}: {s} (wall/free/other points of a {c:?})");
            }
        }
    }
    run(&cor, &a, &b, truth.as_ref());
}

fn xyt(t: &Pose2) -> (f64, f64, f64) {
    (t.translation.x, t.translation.y, t.rotation.angle().to_degrees())
}
