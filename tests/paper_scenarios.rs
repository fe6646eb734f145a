//! The paper's two experiments, end to end in simulation, checked against ground truth.

use mrslam_testbed::report::RunReport;
use mrslam_testbed::runner::{RunOptions, run, write_outputs};
use mrslam_testbed::scenario::Scenario;
use std::path::Path;

fn run_paper(name: &str) -> RunReport {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios").join(format!("{name}.toml"));
    let scenario = Scenario::from_file(&path).expect("the shipped scenario loads");
    let out = run(&scenario, RunOptions::default()).expect("the scenario runs");
    let dir = tempfile::tempdir().unwrap();
    write_outputs(&out, dir.path()).unwrap();
    for f in ["experia.yaml", "experia.pgm", "prawn.yaml", "truth.yaml", "report.json"] {
        assert!(dir.path().join(f).exists(), "{f} not written");
    }
    eprint!("{}", out.report.summary());
    out.report
}

/// What holds today on every paper scenario: the robots drive their routes without touching anything, the
/// run writes its outputs, and a merge is never accepted unless it is right (a rejected merge is an honest
/// answer; a wrong accepted one is the failure this testbed exists to catch).
fn check_common(r: &RunReport) {
    for (name, robot) in &r.robots {
        assert!(robot.finished, "{name} did not finish its route");
        assert_eq!(robot.contact_steps, 0, "{name} touched an obstacle");
        assert!(robot.slam_rmse_m < robot.odom_rmse_m, "{name}: SLAM is no better than odometry");
    }
    for m in &r.merges {
        assert!(!m.accepted || m.success, "{} accepted a wrong merge: {m:?}", m.algorithm);
    }
}

#[test]
fn paper_corridor_maps_well_and_never_merges_wrongly() {
    let r = run_paper("paper_corridor");
    check_common(&r);
    for (name, robot) in &r.robots {
        assert!(
            robot.slam_rmse_m < 0.1 * robot.odom_rmse_m,
            "{name}: SLAM error {:.3} m is not well below odometry's {:.3} m",
            robot.slam_rmse_m,
            robot.odom_rmse_m
        );
        assert!(robot.map_acceptance > 0.95, "{name}: map acceptance {:.3}", robot.map_acceptance);
    }
    // Not yet: the SIFT merge of the two corridor halves. The halves overlap over ~8 m of a corridor whose
    // door recesses repeat, and the merger finds 3-6 consistent matches; the gate rejects it (see the run's
    // report). The paper's claim is that it succeeds; issue [testbed] stays open until it does here.
}

#[test]
fn paper_two_rooms_runs_and_never_merges_wrongly() {
    let r = run_paper("paper_two_rooms");
    check_common(&r);
    let experia = &r.robots["experia"];
    assert!(experia.slam_rmse_m < 0.5 * experia.odom_rmse_m, "{experia:?}");
}
