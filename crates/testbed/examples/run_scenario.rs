//! Runs a scenario and prints its summary: `cargo run --release -p mrslam-testbed --example run_scenario -- FILE`.

fn main() {
    let path = std::env::args().nth(1).expect("scenario file");
    let sc = mrslam_testbed::scenario::Scenario::from_file(std::path::Path::new(&path)).unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(1)
    });
    let out = mrslam_testbed::runner::run(&sc, Default::default()).unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(1)
    });
    print!("{}", out.report.summary());
    mrslam_testbed::runner::write_outputs(&out, std::path::Path::new("/tmp/run_out")).unwrap();
}
