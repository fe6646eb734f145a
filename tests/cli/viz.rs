//! `mrslam run ... --rrd` and `mrslam merge ... --rrd`, as a user would: the recording is read back with rerun's
//! own decoder (through `mrslam_viz::inspect`), and must hold the designed entity paths and timelines with
//! plausible counts, an RRD footer with a manifest per store, the same content on a second run; bad destinations
//! must fail before any work, and an interrupted run must leave nothing under the recording's name.

use crate::util::{mrslam, p, root, text};
use mrslam_core::map_io::write_ros_map;
use mrslam_merge::floorplan::{FloorplanParams, generate};
use mrslam_viz::inspect::{first_difference, summarize};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The two-rooms scenario cut to `seconds` of simulated time and the SIFT merge only, written into `dir`.
fn short_scenario(dir: &Path, seconds: f64) -> PathBuf {
    let text = std::fs::read_to_string(root().join("scenarios/paper_two_rooms.toml")).unwrap();
    let world = root().join("worlds/two_rooms.toml");
    for needle in ["duration = 180.0", "algorithms = [\"sift\", \"rmap\"]", "\"../worlds/two_rooms.toml\""] {
        assert!(text.contains(needle), "the shipped scenario no longer contains `{needle}`");
    }
    let text = text
        .replace("duration = 180.0", &format!("duration = {seconds:.1}"))
        .replace("algorithms = [\"sift\", \"rmap\"]", "algorithms = [\"sift\"]")
        .replace("\"../worlds/two_rooms.toml\"", &format!("{:?}", world.display().to_string()));
    let path = dir.join("short.toml");
    std::fs::write(&path, text).unwrap();
    path
}

fn run_with_rrd(scenario: &Path, out: &Path, rrd: &Path) -> Output {
    mrslam(&["run", p(scenario), "--quiet", "--out", p(out), "--rrd", p(rrd)])
}

#[test]
fn run_records_the_designed_entities_and_timelines_reproducibly() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let seconds = 6.0;
    let scenario = short_scenario(d, seconds);
    let rrd = d.join("run.rrd");
    let o = run_with_rrd(&scenario, &d.join("out"), &rrd);
    assert!(o.status.success(), "{}{}", text(&o.stdout), text(&o.stderr));
    assert!(text(&o.stdout).contains("rerun:"), "{}", text(&o.stdout));

    let s = summarize(&rrd).unwrap();
    assert_eq!(s.recordings, ["paper_two_rooms-seed11"]);
    assert_eq!(s.blueprints.len(), 1, "{s:?}");
    assert_eq!(s.activations, 1);
    assert!(s.blueprint_entities.contains("/viewport"), "{:?}", s.blueprint_entities);
    // Only the simulation's timelines: no wall-clock log_time, no log_tick.
    assert_eq!(s.timelines.iter().map(String::as_str).collect::<Vec<_>>(), ["sim_time", "step"]);

    for e in ["/world/walls", "/world/truth_map"] {
        assert_eq!(s.static_rows.get(e), Some(&1), "{e}: {:?}", s.rows);
    }
    // Scans: Experia's Hokuyo at 10 Hz, Prawn's RpLidar at 5 Hz.
    for (robot, hz) in [("experia", 10.0), ("prawn", 5.0)] {
        let expect = seconds * hz;
        // Rows logged over time (static rows, such as the odometry frame's placement, left out).
        let at = |leaf: &str| {
            let e = format!("/robots/{robot}/{leaf}");
            s.rows_at(&e) - s.static_rows.get(&e).copied().unwrap_or(0)
        };
        let scans = at("scan") as f64;
        assert!((scans - expect).abs() <= 2.0, "{robot}: {scans} scans in {seconds} s at {hz} Hz");
        assert_eq!(at("truth"), at("scan"), "{robot}: one true pose per scan");
        assert_eq!(at("odom"), at("scan"), "{robot}: one odometry pose per scan");
        for leaf in ["slam/pose", "slam/particles"] {
            let n = at(leaf);
            assert!(n >= 1 && n <= at("scan"), "{robot} {leaf}: {n}");
        }
        // Paths at most every 0.5 s (plus the final one), maps at most once a second (plus the final one).
        for (leaf, most) in [
            ("truth/path", seconds / 0.5 + 2.0),
            ("odom/path", seconds / 0.5 + 2.0),
            ("slam/path", seconds / 0.5 + 2.0),
        ] {
            let n = at(leaf) as f64;
            assert!(n >= 2.0 && n <= most, "{robot} {leaf}: {n} rows");
        }
        let maps = s.rows_at(&format!("/maps/{robot}")) as f64;
        assert!((2.0..=seconds + 2.0).contains(&maps), "{robot}: {maps} maps");
        assert_eq!(s.rows_at(&format!("/merge/sift/keypoints/{robot}")), 1, "{robot}");
        for group in ["neff", "slip"] {
            assert!(s.rows_at(&format!("/metrics/{group}/{robot}")) >= 2, "{robot} {group}: {:?}", s.rows);
        }
        assert!(s.rows_at(&format!("/metrics/error/{robot}/odom")) >= 2);
    }
    assert_eq!(s.rows_at("/merge/sift/matches"), 1);
    assert!(s.rows_at("/events") >= 2, "run start and the merge verdict: {:?}", s.rows);

    // A standard recording: the footer has a manifest for the recording and for its blueprint.
    let stores: Vec<&str> = s.recordings.iter().chain(&s.blueprints).map(String::as_str).collect();
    assert_eq!(s.footer_manifests.iter().map(String::as_str).collect::<Vec<_>>(), sorted(&stores), "{s:?}");

    // Reproducible: a second run of the same scenario records the same messages (the footer's bytes may differ).
    let again = d.join("again.rrd");
    let o = run_with_rrd(&scenario, &d.join("out2"), &again);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_eq!(first_difference(&rrd, &again).unwrap(), None, "two runs of one scenario differ");
    // And the comparison sees a difference where there is one: another seed.
    let other = d.join("other.rrd");
    let o = mrslam(&["run", p(&scenario), "--quiet", "--out", p(&d.join("out3")), "--rrd", p(&other), "--seed", "12"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let diff = first_difference(&rrd, &other).unwrap().expect("two seeds must not record the same run");
    assert!(diff.contains("message"), "{diff}");
}

fn sorted<'a>(xs: &[&'a str]) -> Vec<&'a str> {
    let mut v = xs.to_vec();
    v.sort_unstable();
    v
}

#[cfg(unix)]
#[test]
fn a_run_interrupted_by_sigint_leaves_no_recording_under_its_name() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scenario = short_scenario(d, 170.0);
    let rrd = d.join("run.rrd");
    let mut child = Command::new(env!("CARGO_BIN_EXE_mrslam"))
        .args(["run", p(&scenario), "--quiet", "--out", p(&d.join("out")), "--rrd", p(&rrd)])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // Interrupt once the recording has started (its partial file holds data), as a user's Ctrl-C would.
    let partial = mrslam_viz::partial_path(&rrd);
    let start = std::time::Instant::now();
    while partial.metadata().map_or(0, |m| m.len()) < 4096 && start.elapsed().as_secs() < 60 {
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    std::thread::sleep(std::time::Duration::from_millis(500));
    let killed = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(killed.success());
    let status = child.wait().unwrap();
    assert!(!status.success(), "the run finished before the interrupt: make the scenario longer");
    assert!(!rrd.exists(), "an interrupted run left a recording under the final name");
    assert!(partial.metadata().unwrap().len() > 0, "what was recorded is kept under the partial name");
    assert!(!d.join("out/report.json").exists(), "an interrupted run left a report");
    // What is kept is readable up to where the run stopped, and is not mistaken for a finished recording:
    // it has no footer.
    let s = summarize(&partial).unwrap();
    assert!(s.rows_at("/world/walls") == 1 && s.footer_manifests.is_empty(), "{s:?}");
}

#[test]
fn bad_destinations_fail_before_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A long scenario: if the destination were checked after the run, this test would take minutes.
    let scenario = short_scenario(d, 170.0);
    let out = d.join("out");
    let rrd = d.join("no/such/folder/run.rrd");
    let start = std::time::Instant::now();
    let o = run_with_rrd(&scenario, &out, &rrd);
    let e = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains(p(&rrd)) && e.contains("does not exist"), "{e}");
    assert!(!e.contains("panicked"), "{e}");
    assert!(!out.join("report.json").exists(), "the run went ahead");
    assert!(start.elapsed().as_secs() < 20, "refused only after {:?}", start.elapsed());

    // A folder in the way.
    let o = run_with_rrd(&scenario, &out, d);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stderr).contains("it is a folder"), "{}", text(&o.stderr));

    // --spawn with no viewer on PATH says how to get one.
    let empty = d.join("empty-path");
    std::fs::create_dir_all(&empty).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_mrslam"))
        .args(["run", p(&scenario), "--quiet", "--out", p(&out), "--spawn"])
        .env("PATH", &empty)
        .output()
        .unwrap();
    let e = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("pip install rerun-sdk==0.36.3"), "{e}");

    // --spawn with a viewer on PATH that cannot show a window: refused before the run, saying why.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let fake = d.join("fake-viewer");
        std::fs::create_dir_all(&fake).unwrap();
        let exe = fake.join("rerun");
        std::fs::write(&exe, "#!/bin/sh\nexit 0\n").unwrap();
        std::fs::set_permissions(&exe, std::fs::Permissions::from_mode(0o755)).unwrap();
        let spawn = |display: Option<&str>| {
            let mut c = Command::new(env!("CARGO_BIN_EXE_mrslam"));
            c.args(["run", p(&scenario), "--quiet", "--out", p(&out), "--spawn"]).env("PATH", &fake);
            c.env_remove("DISPLAY").env_remove("WAYLAND_DISPLAY");
            if let Some(v) = display {
                c.env("DISPLAY", v);
            }
            c.output().unwrap()
        };
        if cfg!(target_os = "linux") {
            let o = spawn(None);
            let e = text(&o.stderr);
            assert_eq!(o.status.code(), Some(1), "{e}");
            assert!(e.contains("no display") && e.contains("--rrd FILE"), "{e}");
            assert!(!out.join("report.json").exists(), "the run went ahead");
        }
        // A display, but the viewer exits at once (as one that cannot open it does): refused once it is plain
        // that nothing listens, not after the run.
        let start = std::time::Instant::now();
        let o = spawn(Some(":99"));
        let e = text(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{e}");
        assert!(e.contains("--spawn"), "{e}");
        assert!(!e.contains("panicked"), "{e}");
        assert!(!out.join("report.json").exists(), "the run went ahead");
        assert!(start.elapsed().as_secs() < 60, "refused only after {:?}", start.elapsed());
    }

    // --connect where no viewer listens (a port just freed) fails at once instead of waiting for one.
    let port = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let addr = format!("127.0.0.1:{port}");
    let start = std::time::Instant::now();
    let o = mrslam(&["run", p(&scenario), "--quiet", "--out", p(&out), "--connect", &addr]);
    let e = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains(&addr) && e.contains("no rerun viewer answers there"), "{e}");
    assert!(start.elapsed().as_secs() < 20, "refused only after {:?}", start.elapsed());
    assert!(!out.join("report.json").exists(), "the run went ahead");

    // --connect with something that is no address.
    let o = mrslam(&["run", p(&scenario), "--quiet", "--out", p(&out), "--connect", "no such host at all"]);
    let e = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("--connect no such host at all"), "{e}");
}

#[test]
fn merge_records_both_maps_keypoints_matches_and_the_merged_map() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_ros_map(&generate(21, &FloorplanParams::default()), &d.join("plan.yaml")).unwrap();
    let o = mrslam(&[
        "map",
        "cut",
        p(&d.join("plan.yaml")),
        p(&d.join("left.yaml")),
        p(&d.join("right.yaml")),
        "--seed",
        "3",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let rrd = d.join("merge.rrd");
    let o = mrslam(&["merge", p(&d.join("left.yaml")), p(&d.join("right.yaml")), "--rrd", p(&rrd)]);
    assert_eq!(o.status.code(), Some(0), "{}{}", text(&o.stdout), text(&o.stderr));
    let s = summarize(&rrd).unwrap();
    assert_eq!(s.recordings, ["merge-left-right-cascade-seed0"]);
    for e in ["/maps/left", "/maps/right", "/merge/cascade/keypoints/left", "/merge/cascade/keypoints/right"] {
        assert_eq!(s.rows_at(e), 1, "{e}: {:?}", s.rows);
    }
    assert_eq!(s.rows_at("/merge/cascade/matches"), 1);
    assert_eq!(s.rows_at("/merge/cascade/merged"), 1, "the pair merges, so the merged map is there");
    assert!(s.rows_at("/events") >= 1);
    assert_eq!(s.activations, 1);
    assert_eq!(s.footer_manifests.len(), 2, "a manifest for the recording and one for its blueprint: {s:?}");

    // An unwritable --rrd fails before the merge, with the path named.
    let bad = d.join("missing/merge.rrd");
    let o = mrslam(&["merge", p(&d.join("left.yaml")), p(&d.join("right.yaml")), "--rrd", p(&bad)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stderr).contains(p(&bad)), "{}", text(&o.stderr));
    assert!(!text(&o.stdout).contains("ACCEPTED"), "the merge ran: {}", text(&o.stdout));
}

#[test]
fn a_rerun_into_the_same_folder_leaves_no_stale_recording() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scenario = short_scenario(d, 2.0);
    let out = d.join("out");
    let o = run_with_rrd(&scenario, &out, &out.join("run.rrd"));
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(out.join("run.rrd").exists());
    // The same again, recorded again: the recording is kept.
    let o = run_with_rrd(&scenario, &out, &out.join("run.rrd"));
    assert!(o.status.success() && out.join("run.rrd").exists(), "{}", text(&o.stderr));
    // Without --rrd, the folder's recording would show the earlier run beside this run's report: removed.
    let o = mrslam(&["run", p(&scenario), "--quiet", "--out", p(&out)]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(!out.join("run.rrd").exists(), "stale recording kept");
    assert!(text(&o.stdout).contains("removed:") && text(&o.stdout).contains("run.rrd"), "{}", text(&o.stdout));
}
