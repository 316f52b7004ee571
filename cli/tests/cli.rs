//! The `taskstack` command as a user meets it: help texts, the happy paths, and every kind of
//! bad input with its exit status and a message naming the culprit.

mod common;

use common::{KINECT, WALK, clip, imitated_kinect, s, taskstack, taskstack_with_input, temp_dir};
use serde_json::Value;

#[test]
fn every_subcommand_explains_its_options_and_outputs() {
    let top = taskstack(&["--help"]);
    assert_eq!(top.code, Some(0), "{}", top.stderr);
    for command in [
        "imitate", "batch", "check", "contacts", "fk", "live", "solve", "stream", "view", "walk",
    ] {
        assert!(
            top.stdout.contains(command),
            "top-level help lists {command}"
        );
    }
    let imitate = taskstack(&["imitate", "--help"]);
    assert_eq!(imitate.code, Some(0));
    for needle in [
        "joints.csv",
        "motion.npz",
        "metrics.json",
        "view.html",
        "effectors.svg",
        "com.svg",
        "phases.svg",
        "joints.svg",
        "--export",
        "--fps",
        "unitree-csv",
        "--hold",
        "[default: auto]",
        "--velocity-fraction",
        "m/s",
        "--robot",
        "--walk",
        "--out",
        "--skeleton",
        "--quiet",
        "--json",
        "--offline",
        "--lift-lead",
        "--landing-lead",
    ] {
        assert!(
            imitate.stdout.contains(needle),
            "imitate --help mentions {needle}:\n{}",
            imitate.stdout
        );
    }
    for (command, needles) in [
        (
            "batch",
            &["--jobs", "--out", "metrics.json", "exit status"][..],
        ),
        ("fk", &["metres", "radians", "--root", "--urdf"][..]),
        (
            "solve",
            &["PROBLEM.json", "--frames", "--repeats", "µs"][..],
        ),
        ("view", &["OUT_DIR", "--no-open"][..]),
        ("contacts", &["--scene", "--knees", "seconds", "metres"][..]),
        (
            "live",
            &[
                "--listen",
                "--connect",
                "--udp",
                "--bvh-header",
                "--print",
                "--send",
                "Ctrl-C",
            ][..],
        ),
        (
            "stream",
            &["--to", "--udp", "--speed", "--malformed", "--pause"][..],
        ),
    ] {
        let help = taskstack(&[command, "--help"]);
        assert_eq!(help.code, Some(0), "{command} --help");
        for needle in needles {
            assert!(
                help.stdout.contains(needle),
                "{command} --help mentions {needle}:\n{}",
                help.stdout
            );
        }
    }
    // One line per command in the overview (a long first doc paragraph would wrap).
    for line in top
        .stdout
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
    {
        if line.trim().is_empty() {
            break;
        }
        assert!(line.starts_with("  ") && line.len() <= 100, "{line}");
        assert!(
            !line.starts_with("           "),
            "a wrapped command line: {line}"
        );
    }
    // -h is help, not a clip path.
    assert_eq!(taskstack(&["imitate", "-h"]).code, Some(0));
}

#[test]
fn imitate_writes_every_output_and_reports_clip_and_hold_apart() {
    let dir = temp_dir("imitate");
    let out = dir.join("run");
    let clip = clip(KINECT);
    let run = taskstack(&["imitate", s(&clip), "--out", s(&out), "--hold", "0.5"]);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    for file in [
        "joints.csv",
        "motion.npz",
        "metrics.json",
        "view.html",
        "effectors.svg",
        "com.svg",
        "phases.svg",
        "joints.svg",
    ] {
        let len = std::fs::metadata(out.join(file))
            .map(|m| m.len())
            .unwrap_or(0);
        assert!(len > 100, "{file} written ({len} bytes)");
    }
    let metrics: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("metrics.json")).unwrap()).unwrap();
    let frames = metrics["frames"].as_u64().unwrap();
    let clip_frames = metrics["clip_frames"].as_u64().unwrap();
    // The hold: 0.5 s of frames 1/120 s apart after the clip.
    assert_eq!(frames - clip_frames, 60);
    let lines = std::fs::read_to_string(out.join("joints.csv"))
        .unwrap()
        .lines()
        .count() as u64;
    assert_eq!(lines, frames + 1, "a header and one line per frame");
    assert!(
        run.stdout.contains(&format!("{clip_frames} frames")),
        "{}",
        run.stdout
    );
    assert!(
        run.stdout
            .contains("60 frames (0.50 s) holding its last pose"),
        "{}",
        run.stdout
    );
    // The summary's split of each hand's error is metrics.json's.
    let reach = &metrics["hand_reach"];
    let cm = |v: &Value| format!("{:.1}", v.as_f64().unwrap() * 100.0);
    for hand in ["l_hand", "r_hand"] {
        let told = format!(
            "{hand} {} cm, {} cm of it ({} frames over 1 cm)",
            cm(&reach[hand]["error_m"]),
            cm(&reach[hand]["least_error_m"]["mean"]),
            reach[hand]["posture_unreachable_frames"]
        );
        assert!(run.stdout.contains(&told), "{told}\n{}", run.stdout);
    }
    // The hands' timing: metrics.json's lag, the errors without and with it removed (the
    // pooled clip errors of `tracking_error_clip` can only be larger), told in the summary.
    let timing = &metrics["hand_timing"];
    assert_eq!(timing["lag_s"], metrics["hand_lag_s"]);
    let (error, removed) = (&timing["error_m"], &timing["lag_removed_error_m"]);
    assert!(
        removed.as_f64().unwrap() <= error.as_f64().unwrap(),
        "{timing}"
    );
    let told = format!(
        "best aligned {:.2} s later, which takes their mean error from {} to {} cm",
        timing["lag_s"].as_f64().unwrap(),
        cm(error),
        cm(removed)
    );
    assert!(run.stdout.contains(&told), "{told}\n{}", run.stdout);
    // effectors.svg draws, beside each hand's distance, the part no arm posture removes: one
    // dashed path per hand besides the legend's swatch.
    let plot = std::fs::read_to_string(out.join("effectors.svg")).unwrap();
    assert!(plot.contains("no arm posture removes"));
    let dashed = plot.matches("stroke-dasharray").count();
    assert_eq!(dashed, 3, "legend swatch and two hands");
}

#[test]
fn imitate_json_is_one_document_for_scripts_and_quiet_prints_nothing() {
    let dir = temp_dir("json");
    let clip = clip(KINECT);
    let json = taskstack(&[
        "--json",
        "imitate",
        s(&clip),
        "--out",
        s(&dir.join("a")),
        "--hold",
        "0",
    ]);
    assert_eq!(json.code, Some(0), "{}", json.stderr);
    let value: Value = serde_json::from_str(&json.stdout).expect("stdout is one JSON document");
    assert!(value["metrics"]["hand_lag_s"].is_number());
    assert_eq!(value["files"].as_array().map(Vec::len), Some(8));
    assert!(
        value["files"]
            .as_array()
            .unwrap()
            .iter()
            .any(|f| f == "motion.npz")
    );
    let quiet = taskstack(&[
        "-q",
        "imitate",
        s(&clip),
        "--out",
        s(&dir.join("b")),
        "--hold",
        "0",
    ]);
    assert_eq!(quiet.code, Some(0), "{}", quiet.stderr);
    assert_eq!(quiet.stdout, "");
    assert_eq!(quiet.stderr, "");
}

/// `--offline` reads the clip first and reports the foot lags in metrics.json; its leads are
/// checked, and need `--offline`.
#[test]
fn imitate_offline_reports_foot_lags_and_checks_its_leads() {
    let dir = temp_dir("offline");
    let clip = clip(WALK);
    let out = dir.join("run");
    let args = [
        "--json",
        "imitate",
        s(&clip),
        "--offline",
        "--out",
        s(&out),
        "--hold",
        "1",
    ];
    let run = taskstack(&args);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let value: Value = serde_json::from_str(&run.stdout).expect("stdout is one JSON document");
    let lags = &value["metrics"]["foot_lag_s"];
    assert!(
        lags["human_lifts"].as_u64().is_some_and(|n| n > 0),
        "{lags}"
    );
    assert!(lags["lift"]["count"].is_u64() && lags["landing"]["median"].is_number());
    // `batch` prepares its clips as `imitate` does: the same offline run, byte for byte.
    let batch_out = dir.join("batch");
    let args = [
        "batch",
        s(&clip),
        "--offline",
        "--out",
        s(&batch_out),
        "--hold",
        "1",
    ];
    let run = taskstack(&args);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let stem = clip.file_stem().unwrap();
    let batch_joints = std::fs::read(batch_out.join(stem).join("joints.csv")).unwrap();
    let online_out = dir.join("online");
    let run = taskstack(&["imitate", s(&clip), "--out", s(&online_out), "--hold", "1"]);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let online_joints = std::fs::read(online_out.join("joints.csv")).unwrap();
    assert_eq!(batch_joints, std::fs::read(out.join("joints.csv")).unwrap());
    assert_ne!(batch_joints, online_joints, "--offline changes the run");
    let bad = [
        "imitate",
        s(&clip),
        "--offline",
        "--lift-lead",
        "-1",
        "--out",
        s(&out),
    ];
    fails(&bad, 1, &["look_ahead.lift_lead"]);
    let online = ["imitate", s(&clip), "--landing-lead", "1", "--out", s(&out)];
    fails(&online, 2, &["--offline"]);
}

/// Expects exit status `code` and every one of `needles` in stderr.
fn fails(args: &[&str], code: i32, needles: &[&str]) {
    let run = taskstack(args);
    assert_eq!(run.code, Some(code), "{args:?}: {}", run.stderr);
    for needle in needles {
        assert!(
            run.stderr.contains(needle),
            "{args:?}: stderr names {needle}:\n{}",
            run.stderr
        );
    }
}

#[test]
fn imitate_exports_unitree_csv_rows_at_the_asked_rate() {
    let dir = temp_dir("unitree");
    let out = dir.join("run");
    let kinect = clip(KINECT);
    let args = ["imitate", s(&kinect), "--out", s(&out), "--hold", "0.5"];
    let run = taskstack(&[&args[..], &["--export", "unitree-csv", "--fps", "10"]].concat());
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let joints = std::fs::read_to_string(out.join("joints.csv")).unwrap();
    let header = joints.lines().next().unwrap().split(',').count();
    let times: Vec<f64> = (joints.lines().skip(1))
        .map(|l| l.split(',').next().unwrap().parse().unwrap())
        .collect();
    let span = times[times.len() - 1] - times[0];
    let csv = std::fs::read_to_string(out.join("motion_unitree.csv")).unwrap();
    let rows: Vec<Vec<f64>> = (csv.lines())
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    // No header; a row every 0.1 s from the first frame to the last.
    assert_eq!(rows.len(), (span * 10.0 + 1e-9).floor() as usize + 1);
    for row in &rows {
        // x y z, qx qy qz qw, then the joints (joints.csv's columns less its time).
        assert_eq!(row.len(), 7 + header - 1);
        let norm: f64 = row[3..7].iter().map(|v| v * v).sum();
        assert!((norm - 1.0).abs() < 1e-9, "unit quaternion");
        assert!(
            (0.25..0.40).contains(&row[2]),
            "the NAO's torso height {}",
            row[2]
        );
    }
    // The first row is the first frame: its joints are joints.csv's (6 decimals there).
    let first: Vec<f64> = (joints.lines().nth(1).unwrap().split(',').skip(1))
        .map(|v| v.parse().unwrap())
        .collect();
    for (a, b) in rows[0][7..].iter().zip(&first) {
        assert!((a - b).abs() <= 5e-7, "{a} vs {b}");
    }
    // Run again without the export: the folder describes the new run only.
    let run = taskstack(&args);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    assert!(!out.join("motion_unitree.csv").exists());
}

#[test]
fn the_g1_plays_its_servo_commands_through_the_sway_shaper_unless_told_not_to() {
    let dir = temp_dir("sway");
    let kinect = clip(KINECT);
    let rows = |name: &str, extra: &[&str]| -> Vec<Vec<f64>> {
        let out = dir.join(name);
        let args = ["imitate", s(&kinect), "--robot", "g1", "--out", s(&out)];
        let run = taskstack(&[&args[..], &["--hold", "1"], extra].concat());
        assert_eq!(run.code, Some(0), "{}", run.stderr);
        let joints = std::fs::read_to_string(out.join("joints.csv")).unwrap();
        (joints.lines().skip(1))
            .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
            .collect()
    };
    let (shaped, planned) = (rows("shaped", &[]), rows("planned", &["--no-sway-shaping"]));
    assert_eq!(shaped.len(), planned.len());
    // ZVD at T = 1.1 s for a damping ratio of 0.03 (`robots::sway`'s docs): copies of the plan
    // delayed 0, T/2 and T, weighted 1, 2K, K² over (1 + K)², K = exp(−ζπ / √(1 − ζ²)).
    let (period, zeta) = (1.1, 0.03_f64);
    let k = (-zeta * std::f64::consts::PI / (1.0 - zeta * zeta).sqrt()).exp();
    let copies = [(0.0, 1.0), (period / 2.0, 2.0 * k), (period, k * k)];
    let planned_at = |t: f64, j: usize| -> f64 {
        let after = planned.partition_point(|r| r[0] <= t);
        match after {
            0 => planned[0][j],
            n if n == planned.len() => planned[n - 1][j],
            n => {
                let (a, b) = (&planned[n - 1], &planned[n]);
                a[j] + (t - a[0]) / (b[0] - a[0]) * (b[j] - a[j])
            }
        }
    };
    let mut largest_lag = 0.0_f64;
    for (row, plan) in shaped.iter().zip(&planned) {
        assert_eq!(row[0], plan[0], "the same times");
        for j in 1..row.len() {
            let expected: f64 = (copies.iter())
                .map(|(delay, weight)| weight * planned_at(row[0] - delay, j))
                .sum::<f64>()
                / (1.0 + k).powi(2);
            // Six decimals in joints.csv, on each of three copies' inputs and the output.
            assert!((row[j] - expected).abs() < 4e-6, "t {} column {j}", row[0]);
            largest_lag = largest_lag.max((row[j] - plan[j]).abs());
        }
    }
    assert!(
        largest_lag > 0.01,
        "the shaper changed nothing: {largest_lag} rad"
    );
}

#[test]
fn a_failed_run_leaves_the_folder_as_it_was() {
    let dir = temp_dir("whole");
    let out = dir.join("out");
    let good = taskstack(&["imitate", s(&clip(KINECT)), "--out", s(&out), "--hold", "0"]);
    assert_eq!(good.code, Some(0), "{}", good.stderr);
    let before: Vec<(String, Vec<u8>)> = files_in(&out);
    assert_eq!(
        before.len(),
        8,
        "{:?}",
        before.iter().map(|f| &f.0).collect::<Vec<_>>()
    );
    let text = std::fs::read_to_string(clip(WALK)).unwrap();
    let truncated = dir.join("truncated.bvh");
    std::fs::write(&truncated, &text[..text.len() * 2 / 3]).unwrap();
    let bad = taskstack(&["imitate", s(&truncated), "--out", s(&out), "--hold", "0"]);
    assert_eq!(bad.code, Some(1));
    assert!(
        files_in(&out) == before,
        "the earlier run's files, untouched, and nothing else"
    );
    // Into a new folder: nothing at all.
    let fresh = dir.join("fresh");
    let bad = taskstack(&["imitate", s(&truncated), "--out", s(&fresh), "--hold", "0"]);
    assert_eq!(bad.code, Some(1));
    assert!(files_in(&fresh).is_empty());
}

/// The files of `dir` (name, bytes), sorted by name.
fn files_in(dir: &std::path::Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .map(|e| e.unwrap().path())
                .map(|p| {
                    (
                        p.file_name().unwrap().to_string_lossy().into_owned(),
                        std::fs::read(&p).unwrap(),
                    )
                })
                .collect()
        })
        .unwrap_or_default();
    files.sort();
    files
}

#[test]
fn check_without_the_simulator_says_how_to_install_it() {
    use std::process::Command;
    let dir = temp_dir("check");
    let out = imitated_kinect(&dir, "0");
    let missing = Command::new(env!("CARGO_BIN_EXE_taskstack"))
        .args(["check", s(&out)])
        .env("TASKSTACK_PYTHON", dir.join("no-python"))
        .output()
        .unwrap();
    assert_eq!(missing.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&missing.stderr);
    assert!(stderr.contains("python[sim]"), "{stderr}");
    fails(&["check", s(&dir.join("nothing"))], 2, &["nothing"]);
    let help = taskstack(&["check", "--help"]);
    for needle in [
        "OUT_DIR",
        "5 mm",
        "99 %",
        "physics.svg",
        "Exit status",
        "--model",
    ] {
        assert!(
            help.stdout.contains(needle),
            "check --help mentions {needle}"
        );
    }
}

#[test]
fn bad_clips_are_errors_naming_the_clip() {
    let dir = temp_dir("bad-clips");
    let out = dir.join("out");
    let missing = dir.join("missing.bvh");
    fails(
        &["imitate", s(&missing), "--out", s(&out)],
        1,
        &["missing.bvh"],
    );
    let empty = dir.join("empty.bvh");
    std::fs::write(&empty, "").unwrap();
    fails(&["imitate", s(&empty), "--out", s(&out)], 1, &["empty.bvh"]);
    // A BVH cut in the middle of its motion: the first frames are fine, the last line is short.
    let text = std::fs::read_to_string(clip(WALK)).unwrap();
    let truncated = dir.join("truncated.bvh");
    std::fs::write(&truncated, &text[..text.len() * 2 / 3]).unwrap();
    fails(
        &["imitate", s(&truncated), "--out", s(&out), "--hold", "0"],
        1,
        &["truncated.bvh"],
    );
    // The cause is printed once, not once per error in the chain.
    let run = taskstack(&["imitate", s(&truncated), "--out", s(&out), "--hold", "0"]);
    assert_eq!(run.stderr.matches("frame has").count(), 1, "{}", run.stderr);
    let run = taskstack(&["imitate", s(&missing), "--out", s(&out)]);
    assert_eq!(
        run.stderr.matches("No such file").count(),
        1,
        "{}",
        run.stderr
    );
    // A header and no frame of motion.
    let header = text.split("Frame Time:").next().unwrap().replace(
        text.lines().find(|l| l.starts_with("Frames:")).unwrap(),
        "Frames: 0",
    );
    let frameless = dir.join("frameless.bvh");
    std::fs::write(&frameless, header + "Frame Time: 0.008333\n").unwrap();
    fails(
        &["imitate", s(&frameless), "--out", s(&out)],
        1,
        &["frameless.bvh", "no frame"],
    );
    let garbage = dir.join("notes.bvh");
    std::fs::write(&garbage, "these are my notes, not a clip\n").unwrap();
    fails(
        &["imitate", s(&garbage), "--out", s(&out)],
        1,
        &["notes.bvh"],
    );
    let kinect = dir.join("table.csv");
    std::fs::write(&kinect, "a,b,c\n1,2,3\n").unwrap();
    fails(
        &["imitate", s(&kinect), "--out", s(&out)],
        1,
        &["table.csv"],
    );
    fails(&["imitate", s(&dir), "--out", s(&out)], 1, &["is a folder"]);
}

#[test]
fn an_unwritable_output_folder_fails_before_any_work_naming_the_folder() {
    let dir = temp_dir("unwritable");
    let file = dir.join("a-file");
    std::fs::write(&file, "").unwrap();
    let out = file.join("out");
    let run = taskstack(&["imitate", s(&clip(WALK)), "--out", s(&out)]);
    assert_eq!(run.code, Some(1));
    assert!(
        run.stderr.contains("output folder") && run.stderr.contains("a-file/out"),
        "{}",
        run.stderr
    );
    assert!(
        !run.stderr.contains("slow_walk.bvh:"),
        "the clip is not blamed: {}",
        run.stderr
    );
}

#[test]
fn bad_options_are_usage_errors_naming_the_option() {
    let clip = clip(KINECT);
    let c = s(&clip);
    fails(&["imitate", c, "--frobnicate"], 2, &["--frobnicate"]);
    fails(&["imitate", c, "--hold", "abc"], 2, &["--hold", "abc"]);
    fails(&["imitate", c, "--hold", "1e12"], 2, &["--hold"]);
    fails(&["imitate", c, "--hold", "-1"], 2, &["--hold"]);
    // The arms follow the human only in the dynamic walk.
    fails(
        &["imitate", c, "--walking-arms"],
        2,
        &["--walking-arms", "--dynamic-walk"],
    );
    fails(
        &["imitate", c, "--velocity-fraction", "2"],
        2,
        &["--velocity-fraction"],
    );
    fails(&["imitate", c, "--task-speed", "0"], 2, &["--task-speed"]);
    fails(
        &["imitate", c, "--tracking-speed", "NaN"],
        2,
        &["--tracking-speed"],
    );
    fails(&["imitate", c, "--iterations", "0"], 2, &["--iterations"]);
    for option in [
        "--step-distance",
        "--step-heading",
        "--step-pivot",
        "--step-slide",
    ] {
        fails(&["imitate", c, "--walk", option, "-0.1"], 2, &[option]);
    }
    fails(
        &["imitate", c, "--robot", "no-such-robot.toml"],
        1,
        &["--robot", "no-such-robot.toml"],
    );
    fails(
        &["imitate", c, "--skeleton", "no-such-map.toml"],
        1,
        &["--skeleton", "no-such-map.toml"],
    );
    // An option of the other method is refused, not ignored: `--task-speed` clips every task
    // of Poubel's method; Koenemann's swing foot has `--swing-speed`.
    fails(
        &["imitate", c, "--method", "koenemann", "--task-speed", "0.3"],
        2,
        &["--task-speed", "--method koenemann"],
    );
    fails(
        &["imitate", c, "--method", "koenemann", "--walk"],
        2,
        &["--walk", "--method koenemann"],
    );
    fails(
        &["imitate", c, "--swing-speed", "0.3"],
        2,
        &["--swing-speed", "--method poubel"],
    );
    fails(&["batch", c], 2, &["--out"]);
    fails(&["frobnicate"], 2, &["frobnicate"]);
}

/// `--step-pivot` and `--step-slide` reach the footstep planner: at 0 the robot follows the
/// jitter of a standing human's footprints (Kinect ges01, where the human never steps) and
/// steps once; at their defaults it stands.
#[test]
fn step_pivot_and_slide_reach_the_footstep_planner() {
    let dir = temp_dir("step-options");
    let clip = clip(KINECT);
    let robot_steps = |name: &str, extra: &[&str]| {
        let out = dir.join(name);
        let mut args = vec![
            "imitate",
            s(&clip),
            "--walk",
            "--hold",
            "2",
            "--out",
            s(&out),
        ];
        args.extend_from_slice(extra);
        let run = taskstack(&args);
        assert_eq!(run.code, Some(0), "{}", run.stderr);
        let metrics: Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("metrics.json")).unwrap())
                .unwrap();
        metrics["steps"]["robot"].as_u64().unwrap()
    };
    assert_eq!(robot_steps("default", &[]), 0);
    let zero = ["--step-pivot", "0", "--step-slide", "0"];
    assert!(robot_steps("zero", &zero) > 0);
}

#[test]
fn batch_runs_every_clip_and_keeps_going_past_a_bad_one() {
    let dir = temp_dir("batch");
    let clips = dir.join("clips");
    std::fs::create_dir_all(&clips).unwrap();
    std::fs::copy(clip(KINECT), clips.join("wave.csv")).unwrap();
    std::fs::copy(
        clip("kinect2_labanotation_ges02_balancinghands.csv"),
        clips.join("balance.csv"),
    )
    .unwrap();
    let out = dir.join("out");
    let run = taskstack(&[
        "batch",
        s(&clips),
        "--out",
        s(&out),
        "--jobs",
        "2",
        "--hold",
        "0",
    ]);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    for name in ["wave", "balance"] {
        assert!(
            out.join(name).join("view.html").is_file(),
            "{name} has its outputs"
        );
        assert!(
            run.stdout.contains(&format!("{name}.csv")),
            "the table lists {name}: {}",
            run.stdout
        );
    }
    assert!(run.stdout.contains("2 of 2 clips"), "{}", run.stdout);

    std::fs::write(clips.join("broken.csv"), "not,a,kinect,file\n").unwrap();
    let run = taskstack(&[
        "--json",
        "batch",
        s(&clips),
        "--out",
        s(&out),
        "--hold",
        "0",
    ]);
    assert_eq!(run.code, Some(1), "a failed clip fails the batch");
    let value: Value = serde_json::from_str(&run.stdout).expect("one JSON document");
    let clips = value["clips"].as_array().unwrap();
    assert_eq!(clips.len(), 3);
    let broken = clips
        .iter()
        .find(|c| c["clip"].as_str().unwrap().ends_with("broken.csv"))
        .unwrap();
    assert_eq!(broken["ok"], false);
    assert!(broken["error"].as_str().unwrap().contains("broken.csv"));
    assert_eq!(clips.iter().filter(|c| c["ok"] == true).count(), 2);
    fails(
        &["batch", s(&dir.join("nowhere")), "--out", s(&out)],
        1,
        &["nowhere"],
    );
}

#[test]
fn fk_answers_json_lines_and_names_the_bad_line() {
    let run = taskstack_with_input(
        &["fk"],
        "{\"q\": {\"LShoulderPitch\": 0.5}}\n\n{\"q\": {}}\n",
    );
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let lines: Vec<Value> = run
        .stdout
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 2, "one line per non-blank input line");
    // At the standing zero posture of the NAO rooted at the right sole, the left sole is 100 mm
    // to the left (hip offsets ±50 mm) on the floor: the URDF's HipOffsetY.
    let l_sole = &lines[1]["frames"]["l_sole"];
    assert!((l_sole[1].as_f64().unwrap() - 0.1).abs() < 1e-9, "{l_sole}");
    assert!(l_sole[2].as_f64().unwrap().abs() < 1e-9);
    // The coupled hip: RHipYawPitch drives the same motor as LHipYawPitch.
    let run = taskstack_with_input(
        &["fk"],
        "{\"q\": {\"LHipYawPitch\": 0.1, \"RHipYawPitch\": 0.2}}\n",
    );
    assert_eq!(run.code, Some(1));
    assert!(
        run.stderr.contains("input line 1") && run.stderr.contains("one motor"),
        "{}",
        run.stderr
    );
    let run = taskstack_with_input(&["fk"], "{\"q\": {}}\n{\"q\": {\"Elbow\": 1}}\n");
    assert_eq!(run.code, Some(1));
    assert!(
        run.stderr.contains("input line 2") && run.stderr.contains("Elbow"),
        "{}",
        run.stderr
    );
    assert_eq!(
        run.stdout.lines().count(),
        1,
        "the good line before it was answered"
    );
    // --quiet and --json mean nothing to fk: refused as a usage error, not ignored.
    fails(&["fk", "--quiet"], 2, &["--quiet"]);
    fails(&["--json", "fk"], 2, &["--json"]);
}

#[test]
fn contacts_lists_the_hands_landing_on_the_stool() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/contact");
    let clip = dir.join("cmu_23_19_lean_hands_on_stool.bvh");
    let scene = dir.join("stool_23_19.toml");
    let run = taskstack(&["--json", "contacts", s(&clip), "--scene", s(&scene)]);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let value: Value = serde_json::from_str(&run.stdout).unwrap();
    let events = value["events"].as_array().unwrap();
    let on_stool: Vec<_> = events
        .iter()
        .filter(|e| e["surface"] == "stool" && e["change"] == "enter")
        .map(|e| e["link"].as_str().unwrap())
        .collect();
    assert_eq!(on_stool, ["right_hand", "left_hand"], "{}", run.stdout);
    let table = taskstack(&["contacts", s(&clip), "--scene", s(&scene)]);
    assert!(
        table.stdout.contains("right_hand  stool"),
        "{}",
        table.stdout
    );
    let dir = temp_dir("contacts");
    let bad = dir.join("bad.toml");
    std::fs::write(
        &bad,
        "[[surface]]\nname = \"t\"\nheight = 0.7\nsize = [0.5, -1.0]\n",
    )
    .unwrap();
    fails(
        &["contacts", s(&clip), "--scene", s(&bad)],
        1,
        &["surface \"t\"", "size"],
    );
}

#[test]
fn solve_runs_a_benchmark_problem() {
    let problem = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data/bench/problem_rs.json");
    let run = taskstack(&["--json", "solve", s(&problem), "--frames", "3"]);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let value: Value = serde_json::from_str(&run.stdout).unwrap();
    assert_eq!(value["frames"].as_array().map(Vec::len), Some(3));
    assert_eq!(value["summary"]["limit_violations"], 0);
    let run = taskstack(&["solve", s(&problem), "--frames", "2"]);
    assert!(
        run.stdout.contains("worst error per task"),
        "{}",
        run.stdout
    );
    let dir = temp_dir("solve");
    let bad = dir.join("bad.json");
    std::fs::write(&bad, "{\"schema\": 1}").unwrap();
    fails(&["solve", s(&bad)], 1, &["bad.json"]);
    fails(&["solve", s(&problem), "--frames", "0"], 2, &["--frames"]);
}

#[test]
fn view_prints_the_page_of_an_output_folder() {
    let dir = temp_dir("view");
    let out = imitated_kinect(&dir, "0");
    let view = taskstack(&["view", s(&out), "--no-open"]);
    assert_eq!(view.code, Some(0), "{}", view.stderr);
    assert!(
        view.stdout.trim_end().ends_with("view.html"),
        "{}",
        view.stdout
    );
    // A batch folder: the clip folders holding the viewers are listed.
    fails(
        &["view", s(&dir), "--no-open"],
        1,
        &["holds a batch", s(&out)],
    );
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    fails(&["view", s(&empty), "--no-open"], 1, &["no view.html"]);
    fails(
        &["view", s(&dir.join("none")), "--no-open"],
        1,
        &["not a folder"],
    );
}

#[test]
fn a_reader_that_closes_the_pipe_is_not_an_error() {
    use std::process::{Command, Stdio};
    let problem = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data/bench/problem_ds.json");
    // `taskstack --json solve … | head -c 0`: the reader is gone before the output is written.
    let mut child = Command::new(env!("CARGO_BIN_EXE_taskstack"))
        .args(["--json", "solve", s(&problem)])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let output = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(0), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn walk_writes_a_joint_trajectory_the_plan_and_a_summary() {
    let out = temp_dir("walk");
    let run = taskstack(&[
        "walk",
        "--forward",
        "0.2",
        "--left",
        "-0.05",
        "--hold",
        "0.5",
        "--json",
        "--out",
        s(&out),
    ]);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let summary: Value = serde_json::from_str(&run.stdout).unwrap();
    assert_eq!(summary["robot"], "nao");
    // 0.2 m forward and 0.05 m right from the midpoint between the feet.
    assert!((summary["travel_m"].as_f64().unwrap() - 0.2f64.hypot(0.05)).abs() < 1e-9);
    assert!(summary["steps"].as_u64().unwrap() >= 5);
    assert!(summary["zmp_margin_min_m"].as_f64().unwrap() >= 0.005);
    let joints = std::fs::read_to_string(out.join("joints.csv")).unwrap();
    let mut lines = joints.lines();
    let header = lines.next().unwrap();
    assert!(header.starts_with("time,HeadYaw"), "{header}");
    let rows: Vec<&str> = lines.collect();
    let last_time: f64 = rows
        .last()
        .unwrap()
        .split(',')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    let walk_time = summary["walk_time_s"].as_f64().unwrap();
    assert!(
        (last_time - walk_time - 0.5).abs() < 0.011,
        "the hold follows the walk"
    );
    assert_eq!(
        rows.len(),
        (last_time / 0.01).round() as usize + 1,
        "100 Hz from 0"
    );
    let view = std::fs::read_to_string(out.join("view.html")).unwrap();
    assert!(view.contains("const FRAMES") && view.contains("nao walking"));
    let plan = std::fs::read_to_string(out.join("plan.csv")).unwrap();
    assert!(
        plan.starts_with("time,com_x,com_y,zmp_x,zmp_y,left_z,right_z,body_zmp_x,body_zmp_y\n")
    );
    // The whole body's ZMP is known from the second tick to the one before the last.
    let rows: Vec<&str> = plan.lines().skip(1).collect();
    assert!(rows[0].ends_with(",,") && rows[rows.len() - 1].ends_with(",,"));
    assert!(rows[1..rows.len() - 1].iter().all(|r| !r.ends_with(',')));
    assert!(
        summary["body_zmp_margin_min_m"]
            .as_f64()
            .unwrap()
            .is_finite()
    );
    assert!(
        std::fs::read_to_string(out.join("walk.json"))
            .unwrap()
            .contains("mean_speed_m_s")
    );
    let help = taskstack(&["walk", "--help"]);
    for needle in [
        "--forward",
        "--left",
        "--turn",
        "--hold",
        "--step-length",
        "joints.csv",
        "plan.csv",
        "view.html",
        "walk.json",
        "(m",
        "rad",
    ] {
        assert!(
            help.stdout.contains(needle),
            "walk --help mentions {needle}"
        );
    }
    // A walk longer than the generator's queue (64 steps): 81 steps of at most 5 cm.
    let long = taskstack(&[
        "walk",
        "--forward",
        "4",
        "--hold",
        "0",
        "--json",
        "--out",
        s(&out),
    ]);
    assert_eq!(long.code, Some(0), "{}", long.stderr);
    let summary: Value = serde_json::from_str(&long.stdout).unwrap();
    assert!(summary["steps"].as_u64().unwrap() > 64);
    assert!((summary["travel_m"].as_f64().unwrap() - 4.0).abs() < 1e-9);
    fails(&["walk", "--forward", "nan"], 1, &["finite"]);
    fails(&["walk", "--robot", "nope"], 1, &["--robot nope"]);
}
