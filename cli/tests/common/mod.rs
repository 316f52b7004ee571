//! Helpers of the command-line tests: run the built `taskstack` binary, fresh temporary folders,
//! the bundled clips.

#![allow(dead_code)] // each test file uses a part of the helpers

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};

/// The output of one run of the binary.
pub struct Run {
    pub code: Option<i32>,
    pub stdout: String,
    pub stderr: String,
}

fn finish(output: Output) -> Run {
    Run {
        code: output.status.code(),
        stdout: String::from_utf8_lossy(&output.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&output.stderr).into_owned(),
    }
}

/// Runs `taskstack ARGS` with empty stdin.
pub fn taskstack(args: &[&str]) -> Run {
    taskstack_with_input(args, "")
}

/// Runs `taskstack ARGS` with `input` on stdin.
pub fn taskstack_with_input(args: &[&str], input: &str) -> Run {
    use std::io::Write;
    let mut child = Command::new(env!("CARGO_BIN_EXE_taskstack"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the taskstack binary starts");
    let mut stdin = child.stdin.take().expect("stdin is piped");
    stdin
        .write_all(input.as_bytes())
        .expect("stdin takes the input");
    drop(stdin);
    finish(child.wait_with_output().expect("taskstack finishes"))
}

/// A new empty folder under the system's temporary folder, removed with everything in it when
/// the guard is dropped (tests clean up what they write, pass or fail).
pub fn temp_dir(name: &str) -> TempDir {
    static COUNT: AtomicUsize = AtomicUsize::new(0);
    let n = COUNT.fetch_add(1, Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("taskstack-cli-{}-{name}-{n}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temporary folder");
    TempDir(dir)
}

/// See [`temp_dir`].
pub struct TempDir(PathBuf);

impl std::ops::Deref for TempDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A bundled clip of the crate (`tests/data/mocap/NAME`).
pub fn clip(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data/mocap")
        .join(name)
}

/// The short Kinect clip used for happy paths (3.4 s at 30 Hz).
pub const KINECT: &str = "kinect2_labanotation_ges01_wavehand.csv";
/// A short BVH clip.
pub const WALK: &str = "cmu_07_04_slow_walk.bvh";

pub fn s(path: &Path) -> &str {
    path.to_str().expect("temporary paths are UTF-8")
}

/// `taskstack -q imitate KINECT --out DIR/run --hold HOLD`, asserted to succeed: the output
/// folder of a short run (the bundled Kinect clip), for tests of what reads one.
pub fn imitated_kinect(dir: &Path, hold: &str) -> PathBuf {
    let out = dir.join("run");
    let kinect = clip(KINECT);
    let run = taskstack(&[
        "-q",
        "imitate",
        s(&kinect),
        "--out",
        s(&out),
        "--hold",
        hold,
    ]);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    out
}
