//! `view.html` in a real browser: a headless Chromium (or Chrome) loads the page of an imitation
//! run with `#selftest`, which steps the playback and reports, per drawn frame, how many canvas
//! pixels differ from the background, and every script error. Without a browser the test says
//! so and passes, unless `TASKSTACK_REQUIRE_BROWSER` is set (CI sets it and installs Chromium).

mod common;

use std::path::PathBuf;
use std::process::Command;

use common::{imitated_kinect, s, taskstack, temp_dir};
use serde_json::Value;

/// [`browser`], or `None` after saying the test is skipped; with `TASKSTACK_REQUIRE_BROWSER`
/// set (CI) a missing browser fails the test instead.
fn browser_or_skip() -> Option<PathBuf> {
    let found = browser();
    if found.is_none() {
        assert!(
            std::env::var_os("TASKSTACK_REQUIRE_BROWSER").is_none(),
            "TASKSTACK_REQUIRE_BROWSER is set but no Chromium or Chrome was found"
        );
        eprintln!("viewer test skipped: no chromium, chromium-browser or google-chrome on PATH");
    }
    found
}

/// The first browser found: `TASKSTACK_BROWSER`, else chromium, chromium-browser, google-chrome.
fn browser() -> Option<PathBuf> {
    let candidates = std::env::var_os("TASKSTACK_BROWSER")
        .map(PathBuf::from)
        .into_iter()
        .chain(
            [
                "chromium",
                "chromium-browser",
                "google-chrome",
                "google-chrome-stable",
            ]
            .map(PathBuf::from),
        );
    candidates.into_iter().find(|b| {
        Command::new(b)
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success())
    })
}

/// `taskstack live --view`: the page served over HTTP draws the frames the session pushes over
/// its WebSocket (a page opened after the frames first gets the session's backlog).
#[test]
fn the_live_view_follows_a_session_in_a_headless_browser() {
    let Some(browser) = browser_or_skip() else {
        return;
    };
    let dir = temp_dir("live-view");
    let port = |_| {
        let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        listener.local_addr().unwrap().to_string()
    };
    let (frames, view) = (port(0), port(1));
    let out = dir.join("live");
    let mut session = Command::new(env!("CARGO_BIN_EXE_taskstack"))
        .args([
            "-q",
            "live",
            "--listen",
            &frames,
            "--view",
            &view,
            // Long enough for a busy machine to start the browser after the frames.
            "--end-after",
            "30",
        ])
        .args(["--hold", "0", "--out", s(&out)])
        .spawn()
        .expect("taskstack live starts");
    let clip = common::clip(common::KINECT);
    let sent = taskstack(&["-q", "stream", s(&clip), "--to", &frames, "--speed", "0"]);
    assert_eq!(sent.code, Some(0), "{}", sent.stderr);
    let report = selftest_at(&browser, &format!("http://{view}/#selftest=30"));
    // The page has what it needs: the session need not wait out its end.
    let _ = session.kill();
    let _ = session.wait();
    assert_eq!(report["errors"], Value::Array(vec![]), "{report}");
    assert_eq!(report["frames"], 30, "{report}");
    let pixels = report["pixels"].as_f64().unwrap();
    for drawn in report["drawn"].as_array().unwrap() {
        assert!(drawn.as_f64().unwrap() > 0.01 * pixels, "{report}");
    }
}

#[test]
fn the_viewer_draws_and_plays_in_a_headless_browser() {
    let Some(browser) = browser_or_skip() else {
        return;
    };
    let dir = temp_dir("viewer");
    let out = imitated_kinect(&dir, "1");
    let page = out.join("view.html").canonicalize().unwrap();
    let size = std::fs::metadata(&page).unwrap().len();
    let report = selftest(&browser, &page);
    assert_eq!(
        report["errors"],
        Value::Array(vec![]),
        "script errors: {report}"
    );
    let frames = report["frames"].as_u64().unwrap();
    // Up to 30 frames per second of the 3.4 s clip (30 Hz, with dropped frames) and the 1 s hold.
    assert!((100..=135).contains(&frames), "{report}");
    let pixels = report["pixels"].as_f64().unwrap();
    for drawn in report["drawn"].as_array().unwrap() {
        // The floor grid, the robot, the human and the feet cover a few percent of the canvas.
        let share = drawn.as_f64().unwrap() / pixels;
        assert!(share > 0.01 && share < 0.9, "drawn share {share}: {report}");
    }
    let played = report["played_to"].as_u64().unwrap();
    assert!(
        (15..=31).contains(&played),
        "one second of playback moves up to 30 frames: {report}"
    );
    assert!(size < 2_000_000, "view.html is {size} bytes");

    // With a simulated robot spliced in as `taskstack check` does (python/taskstack/sim/view.py),
    // the page still runs clean and draws more: the gray robot beside the plan.
    let text = std::fs::read_to_string(&page).unwrap();
    let sim = r#"const SIM = {"t0":0,"rate":30,"frames":[[0,300,0,0,300,300],[0,300,0,0,300,280]],"segments":[[0,1]],"model":"nominal","verdict":"PASS"};"#;
    std::fs::write(
        &page,
        text.replacen("\nconst TAIL = ", &format!("\n{sim}\nconst TAIL = "), 1),
    )
    .unwrap();
    let with_sim = selftest(&browser, &page);
    assert_eq!(
        with_sim["errors"],
        Value::Array(vec![]),
        "script errors: {with_sim}"
    );
    let first = |r: &Value| r["drawn"][0].as_f64().unwrap();
    assert!(first(&with_sim) > first(&report), "{with_sim} vs {report}");
}

/// A walk's page draws the walk's plan too: its frames carry the planned ZMP and the soles of
/// the steps not yet landed, and the page runs clean and draws more than with the plan taken
/// out of its frames.
#[test]
fn the_viewer_draws_the_walk_plan() {
    let Some(browser) = browser_or_skip() else {
        return;
    };
    let dir = temp_dir("viewer-walk");
    let out = dir.join("walk");
    let run = taskstack(&["-q", "walk", "--forward", "0.1", "--out", s(&out)]);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let page = out.join("view.html").canonicalize().unwrap();
    let text = std::fs::read_to_string(&page).unwrap();
    // A frame with a step queued: `[…, grounded, [zmp x, zmp y], [[side, x, y, …]], [], null]`
    // (no hand supports, no robot hands: a walk has no human).
    let planned = (text.lines().filter_map(frame))
        .filter(|f| f[9].is_array() && f[10].as_array().is_some_and(|s| !s.is_empty()))
        .count();
    assert!(planned > 50, "{planned} frames with a footstep");
    // The same frames without the plan (every frame's ZMP and footsteps emptied).
    draws_more_than_stripped(&browser, &page, 0, |l| {
        let mut f = frame(l)?;
        (f[9], f[10]) = (Value::Null, Value::Array(vec![]));
        Some(format!("{f},"))
    });
}

/// A run with hands on a stool draws the surface each hand rests on and the contact points: the
/// frames carry them, and the page's last frame (both hands held) draws more than with them
/// taken out.
#[test]
fn the_viewer_draws_the_surfaces_the_hands_rest_on() {
    let Some(browser) = browser_or_skip() else {
        return;
    };
    let dir = temp_dir("viewer-stool");
    let out = dir.join("stool");
    let data = concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/data/contact");
    let clip = format!("{data}/cmu_23_19_lean_hands_on_stool.bvh");
    let scene = format!("{data}/stool_23_19.toml");
    let args = ["-q", "imitate", &clip, "--scene", &scene, "--out", s(&out)];
    let run = taskstack(&args);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let page = out.join("view.html").canonicalize().unwrap();
    let text = std::fs::read_to_string(&page).unwrap();
    // A frame with a hand support: `[…, [footsteps], [[side, holding, x, y, z, height,
    // corners…]], [robot hands]]`.
    let supported = |f: &Value| f[11].as_array().is_some_and(|h| !h.is_empty());
    let held = text.lines().filter_map(frame).filter(supported).count();
    assert!(held > 20, "{held} frames with a hand support");
    draws_more_than_stripped(&browser, &page, 3, |l| {
        let mut f = frame(l).filter(supported)?;
        f[11] = Value::Array(vec![]);
        Some(format!("{f},"))
    });
}

/// An imitation's page draws each hand's target (the scaled human's hand as the robot is asked
/// to reach it) and the hand's error to it: its frames carry the robot's hands, 0.5–50 cm from
/// the targets in the human points at `RUN.hand_joints`, and the page draws more than with the
/// hands taken out.
#[test]
fn the_viewer_draws_the_hand_targets() {
    let Some(browser) = browser_or_skip() else {
        return;
    };
    let dir = temp_dir("viewer-hands");
    let out = imitated_kinect(&dir, "1");
    let page = out.join("view.html").canonicalize().unwrap();
    let text = std::fs::read_to_string(&page).unwrap();
    let joints = ["LHand", "RHand"].map(|name| {
        let names = text
            .split("\"human_joints\":[")
            .nth(1)
            .unwrap()
            .split(']')
            .next()
            .unwrap();
        (names.split(','))
            .position(|n| n == format!("\"{name}\""))
            .unwrap()
    });
    let frames: Vec<Value> = text.lines().filter_map(frame).collect();
    let errors: Vec<f64> = (frames.iter())
        .flat_map(|f| {
            (0..2).map(move |s| {
                let at = |v: &Value, k: usize| v[k].as_f64().unwrap();
                let (hand, human) = (&f[12], &f[4]);
                let d = (0..3).map(|a| at(hand, 3 * s + a) - at(human, 3 * joints[s] + a));
                d.map(|x| x * x).sum::<f64>().sqrt()
            })
        })
        .collect();
    assert_eq!(errors.len(), 2 * frames.len());
    assert!(errors.iter().all(|&e| e < 500.0), "{errors:?} mm");
    assert!(errors.iter().any(|&e| e > 5.0), "{errors:?} mm");
    draws_more_than_stripped(&browser, &page, 1, |l| {
        let mut f = frame(l)?;
        f[12] = Value::Null;
        Some(format!("{f},"))
    });
}

/// A frame line of a page (`[…],`) as JSON; `None` for any other line.
fn frame(line: &str) -> Option<Value> {
    let json = line.strip_prefix('[')?.strip_suffix("],")?;
    serde_json::from_str(&format!("[{json}]")).ok()
}

/// The page runs clean, runs clean again with `strip` applied to its frame lines (`None` keeps
/// a line), and its self-test step `step` draws more pixels before than after.
fn draws_more_than_stripped(
    browser: &PathBuf,
    page: &std::path::Path,
    step: usize,
    strip: impl Fn(&str) -> Option<String>,
) {
    let text = std::fs::read_to_string(page).unwrap();
    let report = selftest(browser, page);
    assert_eq!(report["errors"], Value::Array(vec![]), "{report}");
    let stripped: String = (text.lines())
        .map(|l| {
            let frame = l.starts_with('[').then(|| strip(l)).flatten();
            format!("{}\n", frame.as_deref().unwrap_or(l))
        })
        .collect();
    std::fs::write(page, stripped).unwrap();
    let without = selftest(browser, page);
    assert_eq!(without["errors"], Value::Array(vec![]), "{without}");
    let drawn = |r: &Value| r["drawn"][step].as_f64().unwrap();
    assert!(drawn(&report) > drawn(&without), "{report} vs {without}");
}

/// Loads `page` with `#selftest` in the headless `browser` and returns the page's report; the
/// browser's log must hold no uncaught error.
fn selftest(browser: &PathBuf, page: &std::path::Path) -> Value {
    selftest_at(browser, &format!("file://{}#selftest", s(page)))
}

/// [`selftest`] of the page at `url`.
fn selftest_at(browser: &PathBuf, url: &str) -> Value {
    let profile = temp_dir("viewer-profile");
    let output = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--no-first-run",
            "--window-size=900,600",
            "--virtual-time-budget=5000",
            "--enable-logging=stderr",
            "--v=0",
        ])
        .arg(format!("--user-data-dir={}", s(&profile)))
        .arg("--dump-dom")
        .arg(url)
        .output()
        .expect("the browser runs");
    let dom = String::from_utf8_lossy(&output.stdout);
    let log = String::from_utf8_lossy(&output.stderr);
    let report = dom
        .split("<pre id=\"selftest\">")
        .nth(1)
        .and_then(|rest| rest.split("</pre>").next())
        .unwrap_or_else(|| panic!("no self-test report in the page; browser log:\n{log}"));
    assert!(!log.contains("Uncaught"), "console errors:\n{log}");
    serde_json::from_str(&report.replace("&quot;", "\"")).expect("the report is JSON")
}
