//! `mrslam study team`, as a user would: the two-rooms team scenario with one and two robots, both coordinations,
//! two seeds and a short duration; its files and what their rows must say; a resume; shards joined by `study
//! collect`; the trials listed by `--dry-run`; and bad input refused with exit code 1.

use crate::util::{fails_with, mrslam, p, root, text};
use std::path::Path;
use std::process::Output;

const COLUMNS: &str = "trial,n,range_m,coordination,merger,seed,time_to_50_s,time_to_90_s,time_to_95_s,\
final_coverage,redundancy,distance_m,first_correct_merge_s,merges_accepted,merges_refused,merges_false,\
bytes_exchanged,team_map_acceptance,wall_s,teams_at_end,reachable_m2,sim_s,coverage_step_s,coverage_curve";

/// Simulated seconds per trial: long enough for the two robots to meet and try a merge, short for the test.
const DURATION: &str = "40";

fn scenario() -> String {
    root().join("scenarios/team_two_rooms.toml").display().to_string()
}

fn team(out: &Path, extra: &[&str]) -> Output {
    let scenario = scenario();
    let mut args = vec!["study", "team", &scenario, "--out", p(out), "--quiet", "--duration", DURATION];
    args.extend_from_slice(extra);
    mrslam(&args)
}

fn ok(o: &Output) -> String {
    assert_eq!(o.status.code(), Some(0), "stdout: {}\nstderr: {}", text(&o.stdout), text(&o.stderr));
    text(&o.stdout)
}

/// A CSV file's header and its rows split at commas.
fn csv(path: &Path) -> (String, Vec<Vec<String>>) {
    let t = std::fs::read_to_string(path).unwrap();
    let mut lines = t.lines();
    let header = lines.next().unwrap().to_string();
    (header, lines.map(|l| l.split(',').map(str::to_string).collect()).collect())
}

/// Rows without their wall time (the one column that differs between identical runs).
fn without_wall(rows: &[Vec<String>]) -> Vec<Vec<String>> {
    let wall = COLUMNS.split(',').position(|c| c == "wall_s").unwrap();
    rows.iter().map(|r| r.iter().enumerate().filter(|(i, _)| *i != wall).map(|(_, c)| c.clone()).collect()).collect()
}

#[test]
fn a_small_team_study_writes_consistent_files_resumes_and_its_shards_collect() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("team");
    let axes = ["--robots", "1,2", "--coordination", "none,frontiers", "--seeds", "0:1"];

    // --dry-run lists the trials and the runs they share, and runs nothing.
    let listed = ok(&team(&out, &[&axes[..], &["--dry-run"]].concat()));
    assert!(listed.contains("8 trials (4 configurations x 2 seeds)"), "{listed}");
    assert!(listed.contains("trial 0: N=1, range 6 m, none, cascade, seed 0"), "{listed}");
    assert!(listed.contains("trial 3: N=1, range 6 m, frontiers, cascade, seed 1 (one robot: the run of trial 1)"));
    assert!(listed.contains("trial 7: N=2, range 6 m, frontiers, cascade, seed 1\n"), "{listed}");
    assert!(listed.contains("8 trials in this shard, 6 runs"), "{listed}");
    assert!(!out.exists(), "a dry run writes nothing");

    let stdout = ok(&team(&out, &axes));
    assert!(stdout.contains("8 trials in"), "{stdout}");
    for f in ["study.json", "results.csv", "summary.csv", "coverage.csv", "plot.png", "time90.png"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let (header, rows) = csv(&out.join("results.csv"));
    assert_eq!(header, COLUMNS);
    assert_eq!(rows.len(), 8);
    let col = |name: &str| COLUMNS.split(',').position(|c| c == name).unwrap();
    let num = |r: &Vec<String>, name: &str| r[col(name)].parse::<f64>().unwrap();
    let steps = (DURATION.parse::<f64>().unwrap() / 2.0) as usize + 1;
    for (t, r) in rows.iter().enumerate() {
        assert_eq!(r[col("trial")], t.to_string());
        assert_eq!(r[col("n")], if t < 4 { "1" } else { "2" });
        assert_eq!(r[col("coordination")], if t % 4 < 2 { "none" } else { "frontiers" });
        assert_eq!(r[col("seed")], (t % 2).to_string());
        let curve: Vec<f64> = r[col("coverage_curve")].split(' ').map(|c| c.parse().unwrap()).collect();
        assert_eq!(curve.len(), steps, "trial {t}: one point every 2 s from 0 to {DURATION} s");
        assert!(curve.iter().all(|c| (0.0..=1.0).contains(c)), "trial {t}: {curve:?}");
        let fin = num(r, "final_coverage");
        assert!(fin > 0.0 && fin <= 1.0 && (fin - curve[steps - 1]).abs() < 1e-3, "trial {t}: {fin} vs {curve:?}");
        assert!((0.0..=1.0).contains(&num(r, "redundancy")));
        assert!(num(r, "distance_m") > 0.0 && num(r, "sim_s") <= 40.0 + 1e-6 && num(r, "wall_s") > 0.0);
        let (accepted, fals) = (num(r, "merges_accepted"), num(r, "merges_false"));
        assert!(fals <= accepted);
        if t < 4 {
            // One robot: nobody to meet, nothing to merge or send, one team, nothing seen twice.
            for c in ["merges_accepted", "merges_refused", "merges_false", "bytes_exchanged", "redundancy"] {
                assert_eq!(num(r, c), 0.0, "trial {t}: {c}");
            }
            assert_eq!(r[col("first_correct_merge_s")], "");
            assert_eq!(r[col("teams_at_end")], "1");
        } else {
            // Two robots: an accepted merge (right or wrong) joins them into one team.
            let teams = if accepted > 0.0 { "1" } else { "2" };
            assert_eq!(r[col("teams_at_end")], teams, "trial {t}");
            let tried = accepted + num(r, "merges_refused");
            assert!(tried == 0.0 || num(r, "bytes_exchanged") > 0.0, "trial {t}: a merge without maps sent");
        }
    }
    // A lone robot's coordination changes nothing: its trials are one run per seed.
    let same = without_wall(&rows);
    for t in 0..2 {
        let (a, b) = (&same[t], &same[t + 2]);
        let differ: Vec<usize> = (0..a.len()).filter(|&i| a[i] != b[i]).collect();
        assert_eq!(differ, [0, 3], "trials {t} and {} differ only in trial and coordination", t + 2);
    }
    let (header, summary) = csv(&out.join("summary.csv"));
    assert!(header.starts_with("n,range_m,coordination,merger,trials,reached_90,"), "{header}");
    assert_eq!(summary.len(), 4);
    assert!(summary.iter().all(|r| r[4] == "2"), "two trials per configuration: {summary:?}");
    let (header, coverage) = csv(&out.join("coverage.csv"));
    assert_eq!(header, "n,range_m,coordination,merger,t_s,trials,mean,lo,hi,min,max");
    assert_eq!(coverage.len(), 4 * steps);
    let study = std::fs::read_to_string(out.join("study.json")).unwrap();
    assert!(study.contains("\"kind\": \"team\"") && study.contains("\"coordination\": \"none,frontiers\""));

    // Again into the same folder: refused; resumed: nothing left to run, the same rows.
    fails_with(&["study", "team", &scenario(), "--out", p(&out), "--duration", DURATION], &["--resume"]);
    let resumed = ok(&team(&out, &[&axes[..], &["--resume"]].concat()));
    assert!(resumed.contains("8 trials already done"), "{resumed}");
    let (_, again) = csv(&out.join("results.csv"));
    assert_eq!(again, rows);

    // Two shards of a smaller study, joined by `study collect`, give the rows the trials gave above.
    let small = ["--robots", "2", "--coordination", "frontiers", "--seeds", "0:1"];
    let (s0, s1, joined) = (dir.path().join("s0"), dir.path().join("s1"), dir.path().join("joined"));
    ok(&team(&s0, &[&small[..], &["--shard", "0/2"]].concat()));
    ok(&team(&s1, &[&small[..], &["--shard", "1/2"]].concat()));
    let collected = ok(&mrslam(&["study", "collect", p(&s1), p(&s0), "--out", p(&joined)]));
    assert!(collected.contains("collected 2 rows (2 trials)"), "{collected}");
    let (header, joined_rows) = csv(&joined.join("results.csv"));
    assert_eq!(header, COLUMNS);
    let expected: Vec<Vec<String>> = without_wall(&rows[6..8])
        .into_iter()
        .enumerate()
        .map(|(t, mut r)| {
            r[0] = t.to_string();
            r
        })
        .collect();
    assert_eq!(without_wall(&joined_rows), expected, "a shard's rows are the whole study's");
    assert!(joined.join("time90.png").is_file() && joined.join("coverage.csv").is_file());
}

#[test]
fn bad_input_is_refused_with_a_clear_message() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let s = scenario();
    let with = |extra: &[&'static str]| {
        let mut a = vec!["study", "team", s.as_str(), "--out", p(&out), "--quiet"];
        a.extend_from_slice(extra);
        a
    };
    fails_with(&with(&["--robots", "1,3"]), &["--robots 3", "scenario `team_two_rooms`", "has 2 robots"]);
    fails_with(&with(&["--robots", "0"]), &["--robots 0"]);
    fails_with(&with(&["--coordination", "none,swarm"]), &["--coordination", "unknown coordination `swarm`"]);
    fails_with(&with(&["--merger", "magic"]), &["--merger", "unknown algorithm `magic`"]);
    fails_with(&with(&["--seeds", "5:2"]), &["--seeds `5:2`: empty"]);
    fails_with(&with(&["--seeds", "1,1"]), &["--seeds `1,1`: 1 given twice"]);
    fails_with(&with(&["--range", "-2"]), &["--range `-2`: -2 is negative"]);
    fails_with(&with(&["--duration", "0"]), &["--duration 0"]);
    fails_with(&with(&["--shard", "2/2"]), &["shard"]);
    // A scenario without a [team] table.
    let paper = root().join("scenarios/paper_two_rooms.toml");
    fails_with(&["study", "team", p(&paper), "--out", p(&out)], &["has no [team] table"]);
    // --out on a file; nothing was written by any refusal.
    std::fs::write(dir.path().join("file"), "x").unwrap();
    fails_with(&["study", "team", &s, "--out", p(&dir.path().join("file")), "--seeds", "0"], &["is a file"]);
    assert!(!out.exists());
}
