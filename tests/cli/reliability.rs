//! Careless input, as a new user types it: outputs named like inputs, typo'd flags, odd output names,
//! maps with nothing in them. Nothing is overwritten, every error exits 1 and names what is wrong, and exit
//! code 2 means only a refused merge.

use crate::util::{fails_with, mrslam, p, plan, text};
use std::path::Path;

/// The bytes of every file in `dir`, by name.
fn snapshot(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .map(|p| (p.file_name().unwrap().to_string_lossy().into_owned(), std::fs::read(&p).unwrap()))
        .collect();
    files.sort();
    files
}

#[test]
fn an_output_never_overwrites_an_input() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let w = plan(d, "w", 21);
    let other = plan(d, "other", 22);
    let b = d.join("b.yaml");
    let before = snapshot(d);

    // map cut W.yaml W.yaml b.yaml: the first half would replace the map being cut.
    fails_with(&["map", "cut", p(&w), p(&w), p(&b)], &["w.yaml", "input"]);
    // features m.yaml --png m.pgm: the picture would replace the map's own image.
    fails_with(&["features", p(&w), "--png", p(&d.join("w.pgm"))], &["w.pgm"]);
    // The same with a map whose image is a PNG.
    std::fs::rename(d.join("w.pgm"), d.join("w.png")).unwrap();
    std::fs::write(&w, "image: w.png\nresolution: 0.05\norigin: [0, 0, 0]\n").unwrap();
    let before_png = snapshot(d);
    fails_with(&["features", p(&w), "--png", p(&d.join("w.png"))], &["w.png", "image of the input", "w.yaml"]);
    assert_eq!(snapshot(d), before_png, "nothing written");
    std::fs::rename(d.join("w.png"), d.join("w.pgm")).unwrap();
    std::fs::write(&w, before.iter().find(|(n, _)| n == "w.yaml").unwrap().1.clone()).unwrap();
    // merge a.yaml b.yaml -o a.yaml, and -o naming a yaml whose PGM is the input's image.
    fails_with(&["merge", p(&w), p(&other), "-o", p(&w)], &["w.yaml", "input"]);
    fails_with(&["merge", p(&w), p(&other), "-o", p(&d.join("w.yml"))], &["w.pgm", "image of the input"]);
    // Two outputs that are one file.
    fails_with(&["map", "cut", p(&w), p(&b), p(&d.join("b.yml"))], &["b.pgm", "both would write"]);
    // map convert onto itself, by another spelling of the path.
    fails_with(&["map", "convert", p(&w), &format!("{}/./w.pgm", p(d))], &["w.pgm", "input"]);
    assert_eq!(snapshot(d), before, "every input is as it was, nothing else was written");
}

#[test]
fn usage_errors_exit_1_and_only_a_refused_merge_exits_2() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let a = plan(d, "a", 21);
    let b = plan(d, "b", 22);
    fails_with(&["merge", p(&a), p(&b), "--ratoi", "0.7"], &["--ratoi"]);
    fails_with(&["merge", p(&a), p(&b), "--fusion", "foo"], &["foo"]);
    fails_with(&["merge", p(&a)], &["<B>"]);
    fails_with(&["frobnicate"], &["frobnicate"]);
    fails_with(&[], &["Usage"]);
    let o = mrslam(&["--help"]);
    assert_eq!(o.status.code(), Some(0));
    let help = text(&o.stdout);
    assert!(help.contains("Exit codes:") && help.contains("2  `mrslam merge` only"), "{help}");
    assert_eq!(mrslam(&["--version"]).status.code(), Some(0));
    assert_eq!(mrslam(&["merge", "--help"]).status.code(), Some(0));
    // Two unrelated plans: the merge is refused, exit 2.
    let o = mrslam(&["merge", p(&a), p(&b)]);
    assert_eq!(o.status.code(), Some(2), "{}{}", text(&o.stdout), text(&o.stderr));
}

#[test]
fn output_names_say_what_is_written_and_are_checked_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let w = plan(d, "w", 21);
    let other = plan(d, "other", 22);
    let before = snapshot(d);
    fails_with(&["merge", p(&w), p(&other), "-o", p(&d.join("m.png"))], &["m.png", ".png", "expected .yaml"]);
    fails_with(&["merge", p(&w), p(&other), "--report", p(&d.join("r.txt"))], &["r.txt", "expected .json"]);
    fails_with(&["features", p(&w), "--png", p(&d.join("out.jpg"))], &["out.jpg", "expected .png"]);
    fails_with(&["features", p(&w), "--json", p(&d.join("k.csv"))], &["k.csv", "expected .json"]);
    fails_with(&["map", "convert", p(&w), p(&d.join("willow"))], &["willow", "no file extension", ".yaml"]);
    fails_with(&["map", "cut", p(&w), p(&d.join("a.pgm")), p(&d.join("b.yaml"))], &["a.pgm", "expected .yaml"]);
    // A missing folder is named as such, before the work.
    let o = fails_with(&["map", "convert", p(&w), p(&d.join("conv/w.yaml"))], &["conv", "does not exist"]);
    assert!(!text(&o.stderr).contains("No such file"), "{}", text(&o.stderr));
    let o = fails_with(&["features", p(&w), "--json", p(&d.join("feat/k.json"))], &["feat", "does not exist"]);
    assert!(text(&o.stdout).is_empty(), "no work done, no success printed: {}", text(&o.stdout));
    assert_eq!(snapshot(d), before, "nothing written");
}

#[test]
fn nothing_doubtful_is_accepted_quietly() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let w = plan(d, "w", 21);
    let other = plan(d, "other", 22);
    // Maps with nothing to cut.
    std::fs::write(d.join("unknown.pgm"), [b"P5\n40 30\n255\n".as_slice(), &[205u8; 40 * 30]].concat()).unwrap();
    std::fs::write(d.join("unknown.yaml"), "image: unknown.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n").unwrap();
    std::fs::write(d.join("one.pgm"), b"P5\n1 1\n255\n\x00").unwrap();
    std::fs::write(d.join("one.yaml"), "image: one.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n").unwrap();
    for m in ["unknown.yaml", "one.yaml"] {
        let (a, b) = (d.join("a.yaml"), d.join("b.yaml"));
        fails_with(&["map", "cut", p(&d.join(m)), p(&a), p(&b)], &[m, "too few to cut"]);
        assert!(!a.exists() && !b.exists());
    }
    // A ratio above 1 accepts every match: refused.
    fails_with(&["merge", p(&w), p(&other), "--ratio", "1.5"], &["--ratio", "1.5", "outside (0, 1]"]);
    // A typo'd key in a map YAML is named (map_server ignores it, so the map still loads).
    let typo = d.join("typo.yaml");
    std::fs::write(&typo, "image: w.pgm\nresolution: 0.05\nresolutoin: 0.1\norigin: [0, 0, 0]\n").unwrap();
    let o = mrslam(&["map", "info", p(&typo)]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("typo.yaml:3: unknown key `resolutoin` ignored"), "{}", text(&o.stderr));
    // A missing image names the YAML that refers to it, and its line.
    let gone = d.join("gone.yaml");
    std::fs::write(&gone, "resolution: 0.05\nimage: nowhere.pgm\norigin: [0, 0, 0]\n").unwrap();
    fails_with(&["map", "info", p(&gone)], &["gone.yaml:2: field `image`", "nowhere.pgm"]);
    // A block-style origin, as map_server accepts it.
    let block = d.join("block.yaml");
    std::fs::write(&block, "image: w.pgm\nresolution: 0.05\norigin:\n  - -10.0\n  - -10.0\n  - 0.0\n").unwrap();
    let o = mrslam(&["map", "info", p(&block)]);
    assert!(text(&o.stdout).contains("x -10.000 m, y -10.000 m"), "{}{}", text(&o.stdout), text(&o.stderr));
    // A gzipped log cut off in the middle is refused, saying so.
    let mut log = String::new();
    for k in 0..300 {
        log += &format!("FLASER 3 1.0 2.0 3.0 0 0 0 0 0 0 {k}.0 h {k}.0\n");
    }
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    std::io::Write::write_all(&mut gz, log.as_bytes()).unwrap();
    let bytes = gz.finish().unwrap();
    std::fs::write(d.join("cut.clf.gz"), &bytes[..bytes.len() / 2]).unwrap();
    fails_with(&["log", "info", p(&d.join("cut.clf.gz"))], &["cut.clf.gz", "cut off"]);
}

#[cfg(unix)]
#[test]
fn output_into_a_closed_pipe_ends_quietly_without_a_panic() {
    use std::os::unix::process::ExitStatusExt;
    use std::process::{Command, Stdio};
    // `mrslam map info plan.yaml | head -0`: the reader is gone before mrslam prints (a reader that had read
    // the first line would leave the same EPIPE for the next one).
    let dir = tempfile::tempdir().unwrap();
    let map = plan(dir.path(), "plan", 4);
    let mut child = Command::new(env!("CARGO_BIN_EXE_mrslam"))
        .args(["map", "info", p(&map)])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let e = text(&out.stderr);
    assert!(!e.contains("panicked"), "{e}");
    // Killed by SIGPIPE as other Unix tools are, or done before the reader closed: never a panic's exit 101.
    assert!(out.status.signal() == Some(libc::SIGPIPE) || out.status.success(), "{:?}: {e}", out.status);
}
