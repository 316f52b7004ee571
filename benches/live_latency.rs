//! Latency of a live session (`taskstack::live`), measured end to end on the loopback
//! interface: a sender streams CMU 05_02's BVH lines over TCP at 120 frames/s (the clip played
//! forward, then backward, and so on: continuous motion), the session imitates each frame as
//! it arrives and writes its command line to a second TCP connection, and a receiver matches
//! each command to the frame's send time. The latency reported (send → command received) holds
//! two loopback hops besides the session's arrival → command: an upper bound of it.
//!
//! Not a criterion benchmark: it measures a stream in real time, not a function in a loop.
//! Default 10 s; `TASKSTACK_LIVE_SECONDS=600` for ten minutes; `cargo bench -- --test` (CI's
//! check that benches run): 1 s. Prints the median, 99th percentile, maximum and the frames
//! dropped, and the imitation step's own median and 99th percentile.

use std::io::{BufRead, BufReader, Write};
use std::net::{TcpListener, TcpStream};
use std::path::Path;
use std::thread;
use std::time::{Duration, Instant};

use taskstack::batch::imitate_clip;
use taskstack::export::JointsWriter;
use taskstack::imitation::reference::support::SupportConfig;
use taskstack::live::transport::Input;
use taskstack::live::{LiveConfig, LiveCounts, LiveSource};
use taskstack::robots::nao;
use taskstack::{Imitator, ImitatorConfig};

const CLIP: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/data/mocap/cmu_05_02_stand_arm_gestures_turn_single_leg.bvh"
);
const RATE: f64 = 120.0;

fn main() {
    let test = std::env::args().any(|a| a == "--test");
    let seconds: f64 = match test {
        true => 1.0,
        false => (std::env::var("TASKSTACK_LIVE_SECONDS").ok())
            .and_then(|s| s.parse().ok())
            .unwrap_or(10.0),
    };
    let frames = (seconds * RATE) as usize;
    let text = std::fs::read_to_string(CLIP).expect("the bundled clip");
    let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    let header_end = lines
        .iter()
        .position(|l| l.starts_with("Frame Time"))
        .unwrap()
        + 1;
    let header = lines[..header_end].join("\n") + "\n";
    let motion: Vec<String> = lines[header_end..]
        .iter()
        .map(|l| format!("{l}\n"))
        .collect();

    // The commands come back on a connection of their own.
    let commands = TcpListener::bind("127.0.0.1:0").unwrap();
    let commands_address = commands.local_addr().unwrap();
    let frames_address = free_address();
    let listen = frames_address.clone();
    let session = thread::spawn(move || run_session(&listen, &commands_address));
    let (back, _) = commands.accept().unwrap();

    let mut stream = connect(&frames_address);
    stream.set_nodelay(true).unwrap();
    stream.write_all(header.as_bytes()).unwrap();
    let receiver = thread::spawn(move || receive(back));
    let start = Instant::now();
    let mut sent = Vec::with_capacity(frames + 1);
    // Frame k of the stream: the clip forward, then backward, ...; the T-pose line first.
    let period = motion.len() - 1;
    for k in 0..=frames {
        let due = start + Duration::from_secs_f64(k as f64 / RATE);
        while Instant::now() < due {
            thread::sleep(due - Instant::now());
        }
        let phase = k.saturating_sub(1) % (2 * period);
        let index = match k {
            0 => 0,
            _ if phase < period => 1 + phase,
            _ => 2 * period - phase,
        };
        sent.push(Instant::now());
        stream
            .write_all(motion[index.min(period)].as_bytes())
            .unwrap();
    }
    drop(stream);
    let received = receiver.join().unwrap();
    let step_us = session.join().unwrap();
    report(&sent, &received, &step_us, frames, seconds);
}

/// A loopback address free a moment ago.
fn free_address() -> String {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    listener.local_addr().unwrap().to_string()
}

fn connect(address: &str) -> TcpStream {
    for _ in 0..200 {
        if let Ok(stream) = TcpStream::connect(address) {
            return stream;
        }
        thread::sleep(Duration::from_millis(10));
    }
    panic!("the session does not listen at {address}");
}

/// The session: frames from a TCP listener, commands to `commands`; returns the imitation
/// step's median and 99th percentile (µs) the metrics recorded, and the session's counts.
fn run_session(frames: &str, commands: &std::net::SocketAddr) -> (f64, f64, LiveCounts) {
    let (arrivals, _) = Input::TcpListen(frames.to_owned()).open(true).unwrap();
    let back = TcpStream::connect(commands).unwrap();
    back.set_nodelay(true).unwrap();
    let mut source = LiveSource::start(arrivals, None, "bench", LiveConfig::default()).unwrap();
    let config = ImitatorConfig {
        support: SupportConfig::for_capture(source.capture()),
        ..ImitatorConfig::default()
    };
    let mut imitator = Imitator::new(nao::profile(), config).unwrap();
    let mut out = JointsWriter::new(back);
    let metrics = imitate_clip(
        Path::new("bench"),
        &mut source,
        &mut imitator,
        0.0,
        |frame| {
            out.frame(frame).unwrap();
            out.finish().unwrap();
        },
    )
    .unwrap();
    let counts = *source.counts();
    (
        metrics.solve_time_us.median,
        metrics.solve_time_us.p99,
        counts,
    )
}

/// Each command line's frame time and when it arrived.
fn receive(back: TcpStream) -> Vec<(f64, Instant)> {
    let mut received = Vec::new();
    for line in BufReader::new(back).lines() {
        let Ok(line) = line else { break };
        let at = Instant::now();
        if let Some(Ok(time)) = line.split(',').next().map(str::parse::<f64>) {
            received.push((time, at));
        }
    }
    received
}

fn report(
    sent: &[Instant],
    received: &[(f64, Instant)],
    step: &(f64, f64, LiveCounts),
    frames: usize,
    seconds: f64,
) {
    // The command of stream frame k (k ≥ 1: the T-pose line is skipped) has time k / 120 s.
    let mut latency_us: Vec<f64> = received
        .iter()
        .filter_map(|(time, at)| {
            let k = (time * RATE).round() as usize;
            let sent = sent.get(k)?;
            Some(at.saturating_duration_since(*sent).as_secs_f64() * 1e6)
        })
        .collect();
    latency_us.sort_by(f64::total_cmp);
    let at = |q: f64| latency_us[((latency_us.len() - 1) as f64 * q).round() as usize];
    println!(
        "live latency, {seconds:.0} s at {RATE:.0} frames/s over loopback TCP (send → command received): \
         median {:.0} µs, p99 {:.0} µs (p99/median {:.1}), max {:.0} µs; {} of {frames} frames answered, {} dropped",
        at(0.5),
        at(0.99),
        at(0.99) / at(0.5),
        at(1.0),
        latency_us.len(),
        frames.saturating_sub(latency_us.len()),
    );
    println!(
        "imitation step: median {:.0} µs, p99 {:.0} µs (p99/median {:.1}); session {:?}",
        step.0,
        step.1,
        step.1 / step.0,
        step.2
    );
}
