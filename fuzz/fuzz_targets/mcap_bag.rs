//! An MCAP file's (a ROS 2 bag's) bytes, written to a file named `.mcap` and read as any log is, through `read_log`: the
//! format's reader, the decoding of its messages and the log's assembly all see them.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    // One file per fuzzing process, rewritten for each input.
    let path = std::env::temp_dir().join(format!("mrslam-fuzz-{}.mcap", std::process::id()));
    if std::fs::write(&path, data).is_ok() {
        let _ = mrslam_log::read_log(&path, &mrslam_log::ReadOptions::default());
    }
});
