//! `taskstack stream`: plays a clip file into a socket, one frame a line, at the clip's own
//! frame rate: a source for `taskstack live` without a capture system.

use std::fmt::Write as _;
use std::io::{BufRead, BufReader, Write};
use std::net::{TcpStream, UdpSocket};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::thread;
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use clap::Args;

use crate::Report;

/// How long a TCP stream keeps trying to reach `taskstack live` (s).
const CONNECT_WAIT: f64 = 10.0;

/// Play a clip file into a socket, one frame a line, at its own frame rate.
///
/// Sends a BVH file's header and then its motion lines, or a Kinect v2 CSV file's lines, to
/// `taskstack live` (or any reader of the line protocol) over TCP (the default: it connects,
/// retrying for 10 s) or UDP (--udp: the header in one datagram, then a datagram a line). Each
/// frame leaves at its time in the clip (BVH: its index × Frame Time; Kinect: its time stamp)
/// divided by --speed. For tests and demos, it can also put faults in the stream: malformed
/// lines, a pause, a disconnect.
#[derive(Debug, Args)]
#[command(verbatim_doc_comment)]
pub(crate) struct StreamArgs {
    /// The clip: a .bvh file or a Kinect v2 .csv.
    #[arg(value_name = "CLIP")]
    clip: PathBuf,
    /// Where to send it: HOST:PORT.
    #[arg(long, value_name = "HOST:PORT")]
    to: String,
    /// Send UDP datagrams instead of a TCP stream.
    #[arg(long)]
    udp: bool,
    /// Play this many times faster than the clip's own rate (> 0); 0: as fast as the socket
    /// takes the lines.
    #[arg(long, value_name = "FACTOR", default_value_t = 1.0, value_parser = non_negative,
          allow_negative_numbers = true)]
    speed: f64,
    /// Faults: this many malformed lines, spread evenly between the frames.
    #[arg(long, value_name = "N", default_value_t = 0)]
    malformed: u64,
    /// Faults: stop sending for --pause seconds at this clip time (s).
    #[arg(long, value_name = "SECONDS", requires = "pause", value_parser = non_negative,
          allow_negative_numbers = true)]
    pause_at: Option<f64>,
    /// Faults: how long the pause of --pause-at lasts (s); with --reconnect the connection is
    /// closed for it and opened again (the header sent again).
    #[arg(long, value_name = "SECONDS", requires = "pause_at", value_parser = non_negative,
          allow_negative_numbers = true)]
    pause: Option<f64>,
    /// Faults: close the TCP connection during the pause and connect again after it.
    #[arg(long, requires = "pause_at", conflicts_with = "udp")]
    reconnect: bool,
}

fn non_negative(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!("`{text}`: expected a finite number ≥ 0")),
    }
}

/// A clip's lines: the header (BVH; empty for Kinect), then each frame's line and its time (s).
struct Lines {
    header: String,
    frames: Vec<(f64, String)>,
}

/// Reads `path`'s lines and their times.
fn read_lines(path: &Path) -> Result<Lines> {
    let file = std::fs::File::open(path)?;
    let kinect = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    let mut header = String::new();
    let mut frames = Vec::new();
    let (mut in_header, mut frame_time, mut first) = (!kinect, 0.0, None);
    for line in BufReader::new(file).lines() {
        let line = line?;
        if line.trim().is_empty() {
            continue;
        }
        if in_header {
            let mut words = line.split_whitespace();
            if words.next() == Some("Frame") {
                frame_time = words.last().and_then(|w| w.parse().ok()).unwrap_or(0.0);
                in_header = false;
            }
            header.push_str(&line);
            header.push('\n');
            continue;
        }
        let time = if kinect {
            let stamp: f64 = line
                .split(',')
                .next()
                .and_then(|s| s.trim().parse().ok())
                .unwrap_or(0.0);
            (stamp - *first.get_or_insert(stamp)) * 1e-7
        } else {
            frames.len() as f64 * frame_time
        };
        frames.push((time, line));
    }
    if in_header {
        bail!("no `Frame Time:` line: not a BVH file");
    }
    Ok(Lines { header, frames })
}

/// Where the lines go.
enum Sink {
    Tcp(TcpStream),
    Udp(UdpSocket),
}

impl Sink {
    fn open(to: &str, udp: bool) -> Result<Self> {
        if udp {
            let socket = UdpSocket::bind("0.0.0.0:0")?;
            socket.connect(to)?;
            return Ok(Sink::Udp(socket));
        }
        let start = Instant::now();
        loop {
            match TcpStream::connect(to) {
                Ok(stream) => {
                    let _ = stream.set_nodelay(true);
                    return Ok(Sink::Tcp(stream));
                }
                Err(err) if start.elapsed().as_secs_f64() > CONNECT_WAIT => return Err(err.into()),
                Err(_) => thread::sleep(Duration::from_millis(50)),
            }
        }
    }

    /// Sends `text` (one or more whole lines).
    fn send(&mut self, text: &str) -> Result<()> {
        match self {
            Sink::Tcp(stream) => stream.write_all(text.as_bytes())?,
            Sink::Udp(socket) => {
                socket.send(text.as_bytes())?;
            }
        }
        Ok(())
    }
}

pub(crate) fn run(args: StreamArgs, report: Report) -> Result<ExitCode> {
    let clip = &args.clip;
    let lines = read_lines(clip).with_context(|| format!("clip {}", clip.display()))?;
    let open = || Sink::open(&args.to, args.udp).with_context(|| format!("--to {}", args.to));
    let mut sink = open()?;
    if !lines.header.is_empty() {
        sink.send(&lines.header)?;
    }
    let n = lines.frames.len() as u64;
    let (mut sent_malformed, mut paused) = (0, false);
    let start = Instant::now();
    let mut delay = 0.0;
    for (k, (time, line)) in lines.frames.iter().enumerate() {
        if !paused && args.pause_at.is_some_and(|at| *time >= at) {
            paused = true;
            let pause = args.pause.unwrap_or(0.0);
            if args.reconnect {
                drop(sink);
                thread::sleep(Duration::from_secs_f64(pause));
                sink = open()?;
                sink.send(&lines.header)?;
            } else {
                thread::sleep(Duration::from_secs_f64(pause));
            }
            delay += pause;
        }
        if args.speed > 0.0 {
            let due = delay + time / args.speed;
            let now = start.elapsed().as_secs_f64();
            if due > now {
                thread::sleep(Duration::from_secs_f64(due - now));
            }
        }
        sink.send(&format!("{line}\n"))?;
        // The malformed lines after frame k: spread evenly, all of them by the last frame.
        let k = k as u64;
        let burst = ((k + 1) * args.malformed) / n - (k * args.malformed) / n;
        for _ in 0..burst {
            sink.send("not a frame\n")?;
        }
        sent_malformed += burst;
    }
    if report.human() {
        let mut text = String::new();
        let _ = writeln!(
            text,
            "sent {} frames of {} to {} in {:.2} s ({} malformed lines)",
            n,
            clip.display(),
            args.to,
            start.elapsed().as_secs_f64(),
            sent_malformed
        );
        eprint!("{text}");
    }
    Ok(ExitCode::SUCCESS)
}
