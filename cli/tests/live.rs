//! `taskstack live` fed by `taskstack stream` over the loopback interface, and by standard
//! input: the same joints as `taskstack imitate` on the file when nothing is lost, the faults
//! counted in the summary and metrics.json.

mod common;

use std::net::TcpListener;
use std::path::Path;
use std::process::{Command, Stdio};

use common::{KINECT, clip, s, taskstack, taskstack_with_input, temp_dir};
use serde_json::Value;

/// A loopback port free a moment ago.
fn free_port() -> u16 {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    listener.local_addr().unwrap().port()
}

/// `taskstack live ARGS` started in the background.
fn live(args: &[&str]) -> std::process::Child {
    Command::new(env!("CARGO_BIN_EXE_taskstack"))
        .arg("live")
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("taskstack live starts")
}

fn metrics(out: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("metrics.json")).unwrap()).unwrap()
}

#[test]
fn every_bundled_clip_streamed_over_tcp_gives_the_files_joints() {
    let dir = temp_dir("live-tcp");
    let mocap = clip("");
    let mut names: Vec<String> = std::fs::read_dir(&mocap)
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".bvh") || n.ends_with(".csv"))
        .collect();
    names.sort();
    assert_eq!(names.len(), 8, "{names:?}");
    for name in &names {
        let (file_out, live_out) = (
            dir.join(format!("{name}-file")),
            dir.join(format!("{name}-live")),
        );
        let path = clip(name);
        let run = taskstack(&[
            "-q",
            "imitate",
            s(&path),
            "--hold",
            "0.5",
            "--out",
            s(&file_out),
        ]);
        assert_eq!(run.code, Some(0), "{}", run.stderr);
        let address = format!("127.0.0.1:{}", free_port());
        let session = live(&[
            "-q",
            "--listen",
            &address,
            "--once",
            "--hold",
            "0.5",
            "--out",
            s(&live_out),
        ]);
        let sent = taskstack(&["-q", "stream", s(&path), "--to", &address, "--speed", "0"]);
        assert_eq!(sent.code, Some(0), "{name}: {}", sent.stderr);
        let session = session.wait_with_output().unwrap();
        assert!(
            session.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&session.stderr)
        );
        let joints = |out: &Path| std::fs::read_to_string(out.join("joints.csv")).unwrap();
        assert!(
            joints(&live_out) == joints(&file_out),
            "{name}: joints.csv differs"
        );
        let counts = &metrics(&live_out)["live"];
        assert_eq!(
            counts["frames"],
            metrics(&file_out)["clip_frames"],
            "{name}"
        );
        for fault in ["malformed", "out_of_range", "stale", "gaps"] {
            assert_eq!(counts[fault], 0, "{name}: {fault}");
        }
    }
}

#[test]
fn standard_input_is_imitated_and_print_sends_each_command_line() {
    let dir = temp_dir("live-stdin");
    let path = clip(KINECT);
    let text = std::fs::read_to_string(&path).unwrap();
    let out = dir.join("live");
    let run = taskstack_with_input(&["live", "--print", "--hold", "0", "--out", s(&out)], &text);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let written = std::fs::read_to_string(out.join("joints.csv")).unwrap();
    assert_eq!(run.stdout, written, "the printed commands are joints.csv");
    assert_eq!(written.lines().count(), 1 + 154);
}

/// 100 malformed lines and a 2.5 s pause: counted, the robot held, then back on both feet.
#[test]
fn faults_are_counted_in_the_summary_and_the_metrics() {
    let dir = temp_dir("live-faults");
    let path = clip(KINECT);
    let out = dir.join("live");
    let address = format!("127.0.0.1:{}", free_port());
    let session = live(&[
        "--listen",
        &address,
        "--once",
        "--hold",
        "0.5",
        "--out",
        s(&out),
    ]);
    let sent = taskstack(&[
        "-q",
        "stream",
        s(&path),
        "--to",
        &address,
        "--speed",
        "4",
        "--malformed",
        "100",
        "--pause-at",
        "2",
        "--pause",
        "2.5",
    ]);
    assert_eq!(sent.code, Some(0), "{}", sent.stderr);
    let session = session.wait_with_output().unwrap();
    let summary = String::from_utf8_lossy(&session.stdout);
    assert!(
        session.status.success(),
        "{}",
        String::from_utf8_lossy(&session.stderr)
    );
    assert!(
        summary.contains("154 frames; skipped 100 malformed"),
        "{summary}"
    );
    assert!(
        summary.contains("1 gaps") && summary.contains("1 back to standing"),
        "{summary}"
    );
    let counts = &metrics(&out)["live"];
    assert_eq!(
        (counts["malformed"].as_u64(), counts["stands"].as_u64()),
        (Some(100), Some(1))
    );
    assert!(counts["held_frames"].as_u64().unwrap() > 100, "{counts}");
}

#[test]
fn bad_live_options_are_usage_errors() {
    for (args, needle) in [
        (
            &["live", "--send", "carrier-pigeon"][..],
            "--send carrier-pigeon",
        ),
        (&["live", "--skeleton", "map.toml"][..], "--skeleton"),
        (&["live", "--listen", "a:1", "--udp", "b:2"][..], "--udp"),
    ] {
        let run = taskstack(args);
        assert_eq!(run.code, Some(2), "{args:?}: {}", run.stderr);
        assert!(run.stderr.contains(needle), "{args:?}: {}", run.stderr);
    }
    let run = taskstack(&[
        "stream",
        &clip(KINECT).display().to_string(),
        "--to",
        "127.0.0.1:1",
        "--udp",
        "--speed",
        "-1",
    ]);
    assert_eq!(run.code, Some(2), "{}", run.stderr);
}
