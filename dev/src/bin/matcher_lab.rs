//! Development aid: scan-matcher accuracy on maps built from the true poses, the way the filter builds them
//! (every 5th scan, 0.25 m apart, hits plus the seen band), matching the next processed scan from perturbed
//! starting poses. Isolates the matcher's error (and bias) from the filter's dynamics.
//! `cargo run --release -p mrslam-dev --bin matcher_lab -- [hokuyo|rplidar] [name=value ...]`
#![allow(clippy::unwrap_used, reason = "a development aid / test: a failed unwrap names the problem")]

use mrslam_core::Xyt;
use mrslam_core::pose;
use mrslam_slam::SlamParams;
use mrslam_slam::dev::TileMap;
use mrslam_slam::synthetic::{self, Drift, Lidar};
use mrslam_slam::{
    MatcherKind, MatcherParams,
    dev::{PreparedScan, ScanMatcher},
};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let which = args.first().map(String::as_str).unwrap_or("hokuyo");
    let noise: f64 = std::env::var("NOISE").ok().and_then(|v| v.parse().ok()).unwrap_or(0.01);
    let map = synthetic::office_map();
    let (run, mut params, every) = match which {
        "rplidar" => {
            let path = synthetic::waypoint_path(&synthetic::office_loop(), 0.1, 0.2);
            let run = synthetic::simulate(
                &map,
                &path,
                0.2,
                &Lidar { sigma: noise, ..Lidar::rplidar() },
                pose(0.0, 0.0, 0.0),
                &Drift::none(),
                3,
            );
            (run, SlamParams::rplidar(), 3)
        }
        _ => {
            let path = synthetic::waypoint_path(&synthetic::office_loop(), 0.05, 0.1);
            let run = synthetic::simulate(
                &map,
                &path,
                0.1,
                &Lidar { sigma: noise, ..Lidar::hokuyo() },
                pose(0.1, 0.0, 0.0),
                &Drift::none(),
                env_f("SIMSEED") as u64 + 11,
            );
            (run, SlamParams::hokuyo(), 5)
        }
    };
    let mut lin = 0.03;
    let mut ang = 0.03;
    for a in args.iter().skip(1) {
        let (k, v) = a.split_once('=').expect("name=value");
        match k {
            "lin" => lin = v.parse().unwrap(),
            "ang" => ang = v.parse().unwrap(),
            _ => params.set(k, v).unwrap(),
        }
    }
    let laser = Xyt::from_pose(&run.laser_offset);
    let matcher = ScanMatcher::new(
        MatcherParams { minimum_score: f64::NEG_INFINITY, ..params.matcher },
        laser,
        params.filter.odometry_calibration > 0.0,
    );
    let mut tm = TileMap::new(params.map.delta);
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let (nl, na) = (Normal::new(0.0, lin).unwrap(), Normal::new(0.0, ang).unwrap());
    let (mut sx, mut sy, mut st, mut ax, mut ay, mut at, mut n) = (0.0f64, 0.0, 0.0, 0.0f64, 0.0f64, 0.0f64, 0.0);
    let (mut better_than_truth, mut worse) = (0, 0);
    let mut max_err: f64 = 0.0;
    let mut scratch = mrslam_slam::dev::Scratch::default();
    let t0 = std::time::Instant::now();
    let mut est: Option<Xyt> = None;
    let mut prev_truth: Option<Xyt> = None;
    for k in (0..run.scans.len()).step_by(every) {
        let truth = Xyt::from_pose(&run.truth[k].1);
        let ps = PreparedScan::new(&run.scans[k], params.map.max_range, params.map.max_urange, params.matcher.lskip);
        let pe: usize = std::env::var("PROFILE").ok().and_then(|v| v.parse().ok()).unwrap_or(0);
        if pe > 0
            && k >= 4 * every
            && (k / every) % pe == 0
            && k <= std::env::var("KMAX").ok().and_then(|v| v.parse().ok()).unwrap_or(usize::MAX)
        {
            matcher.build_field(&tm, &truth, &ps, &mut scratch.field);
            let mut line = format!("k {k:4} at ({:5.1},{:5.1}) score(dθ mrad):", truth.x, truth.y);
            let mut best = (f64::MIN, 0.0);
            for i in -30..=30 {
                let q = Xyt { theta: truth.theta + i as f64 * 1e-4, ..truth };
                let e = matcher.field_eval(&scratch.field, &q, &ps.matched);
                if e.score > best.0 {
                    best = (e.score, i as f64 * 0.1);
                }
                if i % 5 == 0 {
                    line += &format!(" {:.1}", e.score);
                }
            }
            if std::env::var("XPROF").is_ok() {
                let mut l2 = String::from("   score(dx cm):");
                for i in -6..=6 {
                    let q = Xyt {
                        x: truth.x + i as f64 * 0.01 * truth.theta.cos(),
                        y: truth.y + i as f64 * 0.01 * truth.theta.sin(),
                        ..truth
                    };
                    let e = matcher.field_eval(&scratch.field, &q, &ps.matched);
                    l2 += &format!(" {:.1}", e.score);
                }
                println!("{l2}");
            }
            let r = matcher.refine(&scratch.field, &truth, &ps.matched, None);
            println!(
                "{line} | argmax {:+.1} mrad; GN from truth: dx {:+.4} dy {:+.4} dθ {:+.5}",
                best.1,
                r.x - truth.x,
                r.y - truth.y,
                r.theta - truth.theta
            );
        }
        if std::env::var("DUMP").ok().and_then(|v| v.parse::<usize>().ok()) == Some(k) {
            matcher.build_field(&tm, &truth, &ps, &mut scratch.field);
            let f = &scratch.field;
            let lp = matcher.laser_pose(&truth);
            let (s, c) = lp.theta.sin_cos();
            let (ox, oy) = f.origin();
            if let Ok(ddx) = std::env::var("DDX") {
                let ddx: f64 = ddx.parse().unwrap();
                let q = Xyt { x: truth.x + ddx * truth.theta.cos(), y: truth.y + ddx * truth.theta.sin(), ..truth };
                let lq = matcher.laser_pose(&q);
                let mut v = Vec::new();
                for (i, b) in ps.matched.iter().enumerate() {
                    let val = |l: &Xyt| {
                        let u = l.x - ox + c * b.x - s * b.y;
                        let w = l.y - oy + s * b.x + c * b.y;
                        match f.lookup(u, w, c * b.c - s * b.s, s * b.c + c * b.s) {
                            mrslam_slam::dev::Lookup::Hit(d2) => {
                                ((-d2 / params.matcher.sigma).exp(), format!("hit {:.4}", d2.sqrt()))
                            }
                            other => (0.0, format!("{other:?}")),
                        }
                    };
                    let (a, sa) = val(&lp);
                    let (bb, sb) = val(&lq);
                    v.push((bb - a, i, sa, sb, lp.x + c * b.x - s * b.y, lp.y + s * b.x + c * b.y));
                }
                v.sort_by(|a, b| b.0.abs().total_cmp(&a.0.abs()));
                for x in v.iter().take(25) {
                    println!("beam {:4} gain {:+.3} at ({:.3},{:.3}) {} -> {}", x.1, x.0, x.4, x.5, x.2, x.3);
                }
            }
            for (i, b) in ps.matched.iter().enumerate() {
                let u = lp.x - ox + c * b.x - s * b.y;
                let v = lp.y - oy + s * b.x + c * b.y;
                match f.nearest(u, v, c * b.c - s * b.s, s * b.c + c * b.s).map(|x| x.0) {
                    Some(sf) => {
                        let (ex, ey) = (u - sf.mx as f64, v - sf.my as f64);
                        let (snx, sny) = sf.normal();
                        let perp = snx * ex + sny * ey;
                        let d = f.nearest(u, v, c * b.c - s * b.s, s * b.c + c * b.s).map_or(0.0, |x| x.1.sqrt());
                        let w = (-d * d / params.matcher.sigma).exp();
                        let (tx, ty) = (-(v + oy - truth.y), u + ox - truth.x);
                        let torque =
                            if std::env::var("FX").is_ok() { w * perp * snx } else { w * perp * (snx * tx + sny * ty) };
                        println!(
                            "{i:4} a {:+.3} r {:.3} end ({:.3},{:.3}) perp {perp:+.4} d {d:.4} n ({:+.2},{:+.2}) kind {} torque {torque:+.6}",
                            b.s.atan2(b.c),
                            b.r,
                            u + ox,
                            v + oy,
                            snx,
                            sny,
                            sf.kind
                        );
                    }
                    None => println!(
                        "{i:4} a {:+.3} r {:.3} end ({:.3},{:.3}) {:?}",
                        b.s.atan2(b.c),
                        b.r,
                        u + ox,
                        v + oy,
                        f.lookup(u, v, c * b.c - s * b.s, s * b.c + c * b.s)
                    ),
                }
            }
        }
        let kmax = std::env::var("KMAX").ok().and_then(|v| v.parse().ok()).unwrap_or(usize::MAX);
        let every_test = std::env::var("TEST_EVERY").ok().and_then(|v| v.parse().ok()).unwrap_or(3);
        if k >= 4 * every && k <= kmax && (k / every) % every_test == 0 {
            for _ in 0..8 {
                let (fa, fl) = (env_f("FIXA"), env_f("FIXL"));
                let init = Xyt {
                    x: truth.x + nl.sample(&mut rng) + fl * truth.theta.cos(),
                    y: truth.y + nl.sample(&mut rng) + fl * truth.theta.sin(),
                    theta: truth.theta + na.sample(&mut rng) + fa,
                };
                let r = matcher.match_scan(&tm, &init, &ps, None, &mut scratch);
                let (p, s) = (r.pose, r.score);
                let st_truth = match matcher.params.kind {
                    MatcherKind::Gmapping => matcher.score(&tm, &truth, &ps.matched),
                    MatcherKind::Field => matcher.field_eval(&scratch.field, &truth, &ps.matched).score,
                };
                if s > st_truth + 1e-9 {
                    better_than_truth += 1;
                } else {
                    worse += 1;
                }
                // error in the robot frame of the truth
                let (c, s_) = (truth.theta.cos(), truth.theta.sin());
                let (dx, dy) = (p.x - truth.x, p.y - truth.y);
                let (ex, ey) = (c * dx + s_ * dy, -s_ * dx + c * dy);
                let et = p.theta - truth.theta;
                sx += ex;
                sy += ey;
                st += et;
                ax += ex * ex;
                ay += ey * ey;
                at += et * et;
                n += 1.0;
                max_err = max_err.max(ex.hypot(ey));
            }
        }
        // map the scan from the true pose (FEEDBACK: from the matched pose, as the filter does)
        let mut map_pose = truth;
        if std::env::var("FEEDBACK").is_ok() {
            let next = match (est, prev_truth) {
                (Some(e), Some(pt)) => {
                    let pt: Xyt = pt;
                    // true increment in the previous robot frame, drifted like the synthetic odometry
                    let (c0, s0) = (pt.theta.cos(), pt.theta.sin());
                    let (dx, dy) = (truth.x - pt.x, truth.y - pt.y);
                    let (ix, iy) = (c0 * dx + s0 * dy, -s0 * dx + c0 * dy);
                    let d = ix.hypot(iy);
                    let (ix, iy, it) = (ix * 1.03, iy * 1.03, truth.theta - pt.theta + 0.01 * d);
                    let e: Xyt = e;
                    let (c1, s1) = (e.theta.cos(), e.theta.sin());
                    let init = Xyt { x: e.x + c1 * ix - s1 * iy, y: e.y + s1 * ix + c1 * iy, theta: e.theta + it };
                    let r = matcher.match_scan(&tm, &init, &ps, None, &mut scratch);
                    let (c, s_) = (truth.theta.cos(), truth.theta.sin());
                    let (ex, ey) = (r.pose.x - truth.x, r.pose.y - truth.y);
                    if k <= std::env::var("KMAX").ok().and_then(|v| v.parse().ok()).unwrap_or(usize::MAX) {
                        println!(
                            "k {k:4} ({:5.1},{:5.1}) init dθ {:+.5} -> matched along {:+.4} lateral {:+.4} dθ {:+.5} (step {:+.5})",
                            truth.x,
                            truth.y,
                            init.theta - truth.theta,
                            c * ex + s_ * ey,
                            -s_ * ex + c * ey,
                            r.pose.theta - truth.theta,
                            r.pose.theta - init.theta
                        );
                    }
                    r.pose
                }
                _ => truth,
            };
            est = Some(next);
            prev_truth = Some(truth);
            map_pose = next;
        }
        let lp = matcher.laser_pose(&map_pose);
        let (s, c) = lp.theta.sin_cos();
        for b in &ps.hits {
            let (dx, dy) = (c * b.c - s * b.s, s * b.c + c * b.s);
            let (ex, ey) = (lp.x + b.r * dx, lp.y + b.r * dy);
            if params.matcher.seen_band > 0.0 {
                let r0 = (b.r - params.matcher.seen_band).max(0.0);
                let band = params.matcher.seen_band;
                tm.mark_seen(lp.x + r0 * dx, lp.y + r0 * dy, ex + band * dx, ey + band * dy).unwrap();
            }
            tm.add_beam_hit(ex, ey, dx, dy).unwrap();
        }
    }
    println!(
        "{which}: {n} matches in {:.2} s; bias along {:+.4} lateral {:+.4} heading {:+.5}; rms along {:.4} lateral {:.4} heading {:.5}; max {:.3}; optimum beats truth {better_than_truth}/{}",
        t0.elapsed().as_secs_f64(),
        sx / n,
        sy / n,
        st / n,
        (ax / n).sqrt(),
        (ay / n).sqrt(),
        (at / n).sqrt(),
        max_err,
        better_than_truth + worse
    );
}

fn env_f(k: &str) -> f64 {
    std::env::var(k).ok().and_then(|v| v.parse().ok()).unwrap_or(0.0)
}
