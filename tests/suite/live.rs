//! Live sessions (`taskstack::live`) fed through a channel, as the transports feed them: a
//! stream of a clip's lines gives the file's frames; each fault of the module's table is
//! counted and bridged as documented.

use std::sync::mpsc::{Sender, channel};
use std::thread;
use std::time::{Duration, Instant};

use taskstack::batch::{HOLD_STEP, imitate_clip};
use taskstack::human::{CaptureSystem, HumanFrame};
use taskstack::imitation::reference::support::{HumanSupport, SupportConfig, SupportDetector};
use taskstack::io::FrameSource;
use taskstack::io::clip::Clip;
use taskstack::live::transport::{Arrival, Received};
use taskstack::live::{LiveConfig, LiveError, LiveSource};
use taskstack::robots::nao;
use taskstack::{Imitator, ImitatorConfig};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/mocap/");
/// CMU MotionBuilder skeleton (its motion begins with a synthetic T-pose), 120 Hz.
const BVH: &str = "cmu_05_02_stand_arm_gestures_turn_single_leg.bvh";
/// Kinect v2, 30 Hz, two dropped frames.
const KINECT: &str = "kinect2_labanotation_ges01_wavehand.csv";

/// The clip file's non-blank lines.
fn lines(name: &str) -> Vec<String> {
    let text = std::fs::read_to_string(format!("{DATA}{name}")).unwrap();
    text.lines()
        .filter(|l| !l.trim().is_empty())
        .map(str::to_owned)
        .collect()
}

/// The index of the first motion line of a BVH clip's `lines` (0 for a Kinect clip).
fn header_end(lines: &[String]) -> usize {
    (lines.iter())
        .position(|l| l.starts_with("Frame Time"))
        .map_or(0, |i| i + 1)
}

/// The clip file's frames, read by the clip reader.
fn clip_frames(name: &str) -> Vec<HumanFrame> {
    Clip::open(format!("{DATA}{name}"))
        .unwrap()
        .map(Result::unwrap)
        .collect()
}

fn send(tx: &Sender<Arrival>, text: &str) {
    tx.send(Arrival::now(Received::Line(text.to_owned())))
        .unwrap();
}

/// Every frame `source` gives until its end.
fn drain(source: &mut LiveSource) -> Vec<HumanFrame> {
    let mut frame = HumanFrame::new(0.0);
    let mut frames = Vec::new();
    while source.read_frame(&mut frame).unwrap() {
        frames.push(frame);
    }
    frames
}

/// `lines` sent in a burst, the end after them, read back.
fn streamed(lines: &[String], config: LiveConfig) -> (Vec<HumanFrame>, LiveSource) {
    let (tx, rx) = channel();
    for line in lines {
        send(&tx, line);
    }
    tx.send(Arrival::now(Received::End)).unwrap();
    let mut source = LiveSource::start(rx, None, "test", config).unwrap();
    (drain(&mut source), source)
}

#[test]
fn a_streamed_clip_gives_the_files_frames() {
    for name in [BVH, KINECT] {
        let (frames, source) = streamed(&lines(name), LiveConfig::default());
        let file = clip_frames(name);
        assert_eq!(frames, file, "{name}");
        let counts = source.counts();
        assert_eq!(counts.frames, file.len() as u64, "{name}");
        assert_eq!(
            (counts.malformed, counts.stale, counts.gaps),
            (0, 0, 0),
            "{name}"
        );
    }
}

/// 10⁴ malformed lines of five kinds between the frames: each counted, none changes a frame
/// (a BVH frame's time is its index among the frames, which a malformed line does not take).
#[test]
fn malformed_lines_are_counted_and_skipped() {
    for name in [BVH, KINECT] {
        let lines = lines(name);
        let header = header_end(&lines);
        let bad = ["garbage", "1 2 3", "NaN,1,2", "1e999 0 0", "\u{fffd}"];
        let mut mixed: Vec<String> = lines[..header].to_vec();
        let per_frame = 10_000 / (lines.len() - header) + 1;
        let mut sent = 0;
        for line in &lines[header..] {
            for _ in 0..per_frame.min(10_000 - sent) {
                mixed.push(bad[sent % bad.len()].to_owned());
                sent += 1;
            }
            mixed.push(line.clone());
        }
        assert_eq!(sent, 10_000);
        let (frames, source) = streamed(&mixed, LiveConfig::default());
        assert_eq!(frames, clip_frames(name), "{name}");
        assert_eq!(source.counts().malformed, 10_000, "{name}");
    }
}

/// A Kinect line whose right hand is 50 m out, and one whose pelvis leaps 2 m in a frame.
#[test]
fn out_of_range_frames_are_skipped() {
    let mut lines = lines(KINECT);
    let shifted = |line: &str, fields: &[usize], by: f64| {
        let mut values: Vec<String> = line.split(',').map(str::to_owned).collect();
        for &k in fields {
            let v: f64 = values[k].trim().parse().unwrap();
            values[k] = (v + by).to_string();
        }
        values.join(",")
    };
    // Field 1 + 4k is joint k's X: HandRight is joint 11; every joint's X for the leap.
    lines[40] = shifted(&lines[40], &[1 + 4 * 11], 50.0);
    let all: Vec<usize> = (0..25).map(|k| 1 + 4 * k).collect();
    lines[80] = shifted(&lines[80], &all, 2.0);
    let (frames, source) = streamed(&lines, LiveConfig::default());
    assert_eq!(source.counts().out_of_range, 2);
    let file = clip_frames(KINECT);
    let kept: Vec<HumanFrame> = (file.iter().enumerate())
        .filter(|(k, _)| *k != 40 && *k != 80)
        .map(|(_, f)| *f)
        .collect();
    assert_eq!(frames, kept);
}

/// A gap holds the last frame, one every hold step in real time; past `stand_after` the
/// human's last pose on both feet.
#[test]
fn a_gap_holds_the_last_frame_then_the_standing_pose() {
    let config = LiveConfig {
        hold_after: 0.05,
        stand_after: 0.3,
        ..LiveConfig::default()
    };
    let lines = lines(BVH);
    let header = header_end(&lines);
    // The gap comes a quarter second into the human's stance on one leg.
    let mut detector =
        SupportDetector::new(SupportConfig::for_capture(CaptureSystem::Optical)).unwrap();
    let mut on_one_leg = 0;
    let single = clip_frames(BVH).iter().position(|f| {
        on_one_leg = match detector.update(f) {
            HumanSupport::Double | HumanSupport::Airborne => 0,
            _ => on_one_leg + 1,
        };
        on_one_leg == 30
    });
    let streamed = single.expect("CMU 05_02's human stands on one leg") + 1;
    let cut = header + 1 + streamed; // the T-pose line is skipped
    let (tx, rx) = channel();
    for line in &lines[..cut] {
        send(&tx, line);
    }
    let mut source = LiveSource::start(rx, None, "test", config).unwrap();
    let mut frame = HumanFrame::new(0.0);
    let mut given = Vec::new();
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs_f64(0.6) {
        assert!(source.read_frame(&mut frame).unwrap());
        given.push((start.elapsed().as_secs_f64(), frame));
    }
    drop(tx);
    let (last_time, last) = (given[streamed - 1].1.time, given[streamed - 1].1);
    let held = &given[streamed..];
    assert!(!held.is_empty());
    for (k, (_, f)) in held.iter().enumerate() {
        let expected = last_time + (k + 1) as f64 * HOLD_STEP;
        assert!(
            (f.time - expected).abs() < 1e-9,
            "held frame {k} at {}",
            f.time
        );
    }
    // Paced in real time: at most one a hold step over the ~0.55 s of the gap (fewer on a
    // busy machine).
    assert!(
        held.len() >= 10 && held.len() <= 70,
        "{} held frames",
        held.len()
    );
    let same = |a: &HumanFrame, b: &HumanFrame| a.joints().eq(b.joints());
    let (early, late): (Vec<_>, Vec<_>) = held.iter().partition(|(t, _)| *t < 0.3);
    assert!(early.iter().all(|(_, f)| same(f, &last)));
    let stand = late.last().unwrap().1;
    assert!(
        !same(&stand, &last),
        "the standing pose is not the last frame"
    );
    assert!(
        given[..streamed].iter().any(|(_, f)| same(f, &stand)),
        "the standing pose is a frame the human stood in"
    );
    let counts = source.counts();
    assert_eq!((counts.gaps, counts.stands), (1, 1));
    assert_eq!(counts.held_frames, held.len() as u64);
}

/// A source that leaves and comes back with a new stream (its header again, its frames from
/// the start): the frames go on in time after the last, the new stream's time shifted.
#[test]
fn a_source_that_comes_back_goes_on_in_time() {
    let lines = lines(KINECT);
    let (tx, rx) = channel();
    tx.send(Arrival::now(Received::Connected("a".into())))
        .unwrap();
    for line in &lines[..100] {
        send(&tx, line);
    }
    tx.send(Arrival::now(Received::Disconnected)).unwrap();
    tx.send(Arrival::now(Received::Connected("b".into())))
        .unwrap();
    for line in &lines {
        send(&tx, line);
    }
    tx.send(Arrival::now(Received::End)).unwrap();
    let mut source = LiveSource::start(rx, None, "test", LiveConfig::default()).unwrap();
    let frames = drain(&mut source);
    assert_eq!(frames.len(), 100 + lines.len());
    assert!(frames.windows(2).all(|w| w[1].time > w[0].time));
    let step = frames[100].time - frames[99].time;
    assert!((step - HOLD_STEP).abs() < 1e-9, "{step}");
    let counts = source.counts();
    assert_eq!(
        (counts.connections, counts.disconnects, counts.time_shifts),
        (2, 1, 1)
    );
}

/// A burst of 1 000 frames is imitated in order, none stale; frames that waited in the queue
/// longer than `max_lag` behind the stream's real-time schedule are dropped and counted.
#[test]
fn a_burst_is_kept_and_late_frames_are_dropped() {
    let lines = lines(BVH);
    let header = header_end(&lines);
    let (frames, source) = streamed(&lines[..header + 1001], LiveConfig::default());
    assert_eq!((frames.len(), source.counts().stale), (1000, 0));

    // A second of frames (the T-pose and 119 more) that arrived at the stream's own rate
    // during the last second: the first 0.75 s of them (89 frames) are more than 0.25 s late
    // however soon they are read, later ones too when the reading is slow.
    let (tx, rx) = channel();
    let arrived = Instant::now() - Duration::from_secs(1);
    for (k, line) in lines[..header + 120].iter().enumerate() {
        let at = arrived + Duration::from_secs_f64(k.saturating_sub(header) as f64 / 120.0);
        tx.send(Arrival {
            received: Received::Line(line.clone()),
            at,
        })
        .unwrap();
    }
    tx.send(Arrival::now(Received::End)).unwrap();
    let mut source = LiveSource::start(rx, None, "test", LiveConfig::default()).unwrap();
    let frames = drain(&mut source);
    let stale = source.counts().stale;
    assert!(stale >= 85, "{stale} stale of 119");
    assert_eq!(frames.len() as u64 + stale, 119);
}

#[test]
fn a_stream_without_frames_or_with_a_bad_header_is_refused() {
    let (tx, rx) = channel();
    tx.send(Arrival::now(Received::End)).unwrap();
    let err = LiveSource::start(rx, None, "tcp://x", LiveConfig::default()).unwrap_err();
    assert!(matches!(err, LiveError::NoFrames(_)), "{err}");

    let (tx, rx) = channel();
    for line in ["HIERARCHY", "ROOT Hips", "{", "Frame Time: 0.1"] {
        send(&tx, line);
    }
    let err = LiveSource::start(rx, None, "tcp://x", LiveConfig::default()).unwrap_err();
    assert!(matches!(err, LiveError::Stream(_)), "{err}");

    let (_tx, rx) = channel::<Arrival>();
    let config = LiveConfig {
        max_lag: f64::NAN,
        ..LiveConfig::default()
    };
    let err = LiveSource::start(rx, Some(""), "x", config).unwrap_err();
    assert!(matches!(err, LiveError::Config("max_lag")), "{err}");
}

/// The imitation of a stream with every fault (malformed lines, an out-of-range frame, a gap
/// that brings the robot back onto both feet) stays within the joint limits, finite.
#[test]
fn a_faulty_stream_is_imitated_within_the_limits() {
    let lines = lines(BVH);
    let header = header_end(&lines);
    let (tx, rx) = channel();
    let sender = thread::spawn(move || {
        for (k, line) in lines.iter().enumerate() {
            send(&tx, line);
            if k > header && k % 50 == 0 {
                send(&tx, "1 2 3");
                // The root 90 000 BVH units (5 km) away: the pelvis leaps.
                let mut values: Vec<&str> = line.split_whitespace().collect();
                values[0] = "90000";
                send(&tx, &values.join(" "));
            }
            if k == header + 800 {
                thread::sleep(Duration::from_millis(1000));
            }
        }
        tx.send(Arrival::now(Received::End)).unwrap();
    });
    let config = LiveConfig {
        hold_after: 0.05,
        stand_after: 0.3,
        ..LiveConfig::default()
    };
    let mut source = LiveSource::start(rx, None, "test", config).unwrap();
    let profile = nao::profile();
    let config = ImitatorConfig {
        support: SupportConfig::for_capture(source.capture()),
        ..ImitatorConfig::default()
    };
    let mut imitator = Imitator::new(profile, config).unwrap();
    let bounds = imitator.bounds().clone();
    let mut worst = 0.0_f64;
    let path = std::path::Path::new("test");
    imitate_clip(path, &mut source, &mut imitator, 1.0, |frame| {
        for (k, q) in frame.q.iter().enumerate() {
            assert!(q.is_finite());
            worst = worst.max(bounds.lower()[k] - q).max(q - bounds.upper()[k]);
        }
    })
    .unwrap();
    sender.join().unwrap();
    assert!(worst <= 0.0, "a joint {worst} rad beyond its limit");
    let counts = source.counts();
    assert!(
        counts.malformed > 0 && counts.out_of_range > 0,
        "{counts:?}"
    );
    assert_eq!((counts.gaps, counts.stands), (1, 1), "{counts:?}");
}
