//! `taskstack live`: a human streamed in, one frame a line, imitated as each frame arrives;
//! the robot's commands out as they come, the run's files at the end.

use std::fmt::Write as _;
use std::io::{self, LineWriter, Write};
use std::net::{TcpStream, UdpSocket};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Args;
use serde_json::json;
use taskstack::imitation::metrics::ImitationMetrics;
use taskstack::imitation::reference::support::SupportConfig;
use taskstack::live::transport::{Arrival, Input, Received};
use taskstack::live::{LiveConfig, LiveCounts, LiveSource};

use crate::Report;
use crate::imitate::print_summary;
use crate::live_view::LiveView;
use crate::options::{ImitationOptions, UsageError};
use crate::run::{Progress, Run, Settings, Staged, output_files, staged_run};

/// Imitate a human streamed in as it moves: one frame a line, live.
///
/// Reads human frames from standard input (the default), a TCP connection (--listen: as a
/// server; --connect: as a client) or UDP datagrams (--udp), one frame a line, and imitates
/// each as it arrives. The formats are the clip files': a BVH header (HIERARCHY … Frame
/// Time:) first on the stream, or from --bvh-header, then one motion line a frame; or Kinect
/// v2 CSV lines. `taskstack stream CLIP --to ADDR` plays a clip file into a socket.
///
/// The robot's joint commands go out as `joints.csv` lines as they come (--print: standard
/// output; --send udp:HOST:PORT or tcp:HOST:PORT), a header line first, each line with the
/// frame's time. When the stream ends (standard input's end; with --once the TCP source
/// leaving; --end-after seconds without a frame; Ctrl-C) the robot holds the human's last pose
/// as `taskstack imitate --hold` says, and the run's files are written whole into the output
/// folder, as `taskstack imitate` writes them: joints.csv, metrics.json (with `live`: the
/// stream's counts), view.html and the plots, for the judge and the viewer.
///
/// Faults are counted and bridged: a malformed or out-of-range line is skipped; a gap of
/// 0.1 s holds the last pose, one of 2 s brings the robot back onto both feet (the human's
/// last pose on both); a TCP source that leaves is waited for (a server accepts the next, a
/// client reconnects every 0.5 s); a line that waited more than 0.25 s is dropped as stale.
/// See the `taskstack::live` module docs.
#[derive(Debug, Args)]
#[command(verbatim_doc_comment)]
pub(crate) struct LiveArgs {
    /// Listen for a TCP source at HOST:PORT (one at a time).
    #[arg(long, value_name = "HOST:PORT", group = "input")]
    listen: Option<String>,
    /// Connect to a TCP source at HOST:PORT (and reconnect when it leaves).
    #[arg(long, value_name = "HOST:PORT", group = "input")]
    connect: Option<String>,
    /// Receive UDP datagrams of lines at HOST:PORT.
    #[arg(long, value_name = "HOST:PORT", group = "input")]
    udp: Option<String>,
    /// BVH motion lines of the skeleton of this BVH file's header, when the stream does not
    /// send the header itself (CMU conventions).
    #[arg(long, value_name = "FILE.bvh")]
    bvh_header: Option<PathBuf>,
    /// End the session when the first TCP source leaves, instead of waiting for the next.
    #[arg(long)]
    once: bool,
    /// End the session after this long without a frame (s, > 0). Default: only at the
    /// input's end or Ctrl-C.
    #[arg(long, value_name = "SECONDS", value_parser = crate::options::positive,
          allow_negative_numbers = true)]
    end_after: Option<f64>,
    /// Write each command line to standard output as it comes (no summary then).
    #[arg(long)]
    print: bool,
    /// Send each command line to udp:HOST:PORT (one datagram a line) or tcp:HOST:PORT.
    #[arg(long, value_name = "udp:HOST:PORT|tcp:HOST:PORT")]
    send: Option<String>,
    /// Serve a live view at HOST:PORT: open http://HOST:PORT/ in a browser to watch the robot
    /// and the human as the frames arrive (the view.html page, fed over a WebSocket; a page
    /// opened late first gets the last 30 s).
    #[arg(long, value_name = "HOST:PORT")]
    view: Option<String>,
    /// Output folder (created if needed). Default: taskstack-out/live.
    #[arg(long, short, value_name = "DIR")]
    out: Option<PathBuf>,
    #[command(flatten)]
    options: ImitationOptions,
}

pub(crate) fn run(args: LiveArgs, report: Report) -> Result<ExitCode> {
    let input = input_of(&args)?;
    let header = (args.bvh_header.as_ref())
        .map(|path| bvh_header(path).with_context(|| format!("--bvh-header {}", path.display())))
        .transpose()?;
    let settings = Settings {
        profile: args.options.profile()?,
        config: args.options.imitator_config()?,
        hold: args.options.hold,
        setup: Default::default(),
        exports: args.options.exports(),
    };
    let mut outputs = Outputs {
        commands: commands_output(args.print, args.send.as_deref())?,
        view: None,
    };
    let origin = input.origin();
    outputs.view = (args.view.as_deref())
        .map(|address| LiveView::serve(address, &settings.profile, &origin))
        .transpose()?;
    let (arrivals, sender) = (input.open(args.once)).with_context(|| origin.clone())?;
    stop_on_ctrl_c(sender);
    let config = LiveConfig {
        end_after: args.end_after,
        ..LiveConfig::default()
    };
    let mut source = LiveSource::start(arrivals, header.as_deref(), &origin, config)?;
    let name = PathBuf::from(&origin);
    let out = (args.out.clone()).unwrap_or_else(|| Path::new("taskstack-out").join("live"));
    let metrics = staged_run(&out, |staged| {
        imitate_session(&mut source, &name, &settings, &mut outputs, staged)
    })?;
    let counts = *source.counts();
    let mut text = String::new();
    if report.json {
        let value = json!({
            "input": origin,
            "out": out,
            "files": output_files(settings.exports),
            "live": counts.to_json(),
            "metrics": taskstack::batch::metrics_value(&metrics, &name),
        });
        let _ = writeln!(text, "{value}");
    } else if !report.quiet && !args.print {
        print_summary(&mut text, &metrics, &name, &out, &settings);
        print_counts(&mut text, &counts);
    }
    crate::output(&text)?;
    Ok(ExitCode::SUCCESS)
}

/// The input of the options (standard input by default).
fn input_of(args: &LiveArgs) -> Result<Input> {
    if args.options.skeleton.is_some() {
        let why = "it reads CMU-named BVH skeletons and Kinect lines";
        return Err(UsageError(format!(
            "--skeleton (a skeleton map) is not read by taskstack live: {why}"
        ))
        .into());
    }
    Ok(match (&args.listen, &args.connect, &args.udp) {
        (Some(a), _, _) => Input::TcpListen(a.clone()),
        (_, Some(a), _) => Input::TcpConnect(a.clone()),
        (_, _, Some(a)) => Input::Udp(a.clone()),
        _ => Input::Stdin,
    })
}

/// Where a session's frames go as they come, besides its files.
struct Outputs {
    commands: Option<Box<dyn Write>>,
    view: Option<LiveView>,
}

/// The session's run into `staged`, `metrics.json` with the stream's counts.
fn imitate_session(
    source: &mut LiveSource,
    name: &Path,
    settings: &Settings,
    outputs: &mut Outputs,
    staged: &mut Staged,
) -> Result<ImitationMetrics> {
    let config = taskstack::ImitatorConfig {
        support: SupportConfig::for_capture(source.capture()),
        ..settings.config.clone()
    };
    let view = &mut outputs.view;
    // A page that cannot be sent a frame does not stop the session.
    let mut show = |frame: &taskstack::RobotFrame| {
        if let Some(view) = view.as_mut() {
            let _ = view.frame(frame);
        }
    };
    let mut run = Run {
        name,
        config,
        settings,
        commands: (outputs.commands.as_mut()).map(|w| &mut **w as &mut dyn Write),
        on_frame: Some(&mut show),
    };
    let metrics = run.imitate(&mut *source, staged, &mut |_: Progress| {})?;
    let mut value = taskstack::batch::metrics_value(&metrics, name);
    value["live"] = source.counts().to_json();
    let text = serde_json::to_string_pretty(&value).unwrap_or_default() + "\n";
    staged.write("metrics.json", text)?;
    Ok(metrics)
}

/// The header of the BVH file at `path`.
fn bvh_header(path: &Path) -> Result<String> {
    let text = std::fs::read_to_string(path)?;
    taskstack::live::bvh_header(&text).context("no `Frame Time:` line: not a BVH file")
}

/// Where the command lines go: standard output, a socket, both or neither.
fn commands_output(print: bool, send: Option<&str>) -> Result<Option<Box<dyn Write>>> {
    let sent: Option<Box<dyn Write>> = match send {
        None => None,
        Some(spec) => Some(match spec.split_once(':') {
            Some(("udp", address)) => {
                let socket = UdpSocket::bind("0.0.0.0:0").context("--send: a UDP socket")?;
                socket
                    .connect(address)
                    .with_context(|| format!("--send {spec}"))?;
                Box::new(Datagrams {
                    socket,
                    line: Vec::new(),
                })
            }
            Some(("tcp", address)) => {
                let stream =
                    TcpStream::connect(address).with_context(|| format!("--send {spec}"))?;
                let _ = stream.set_nodelay(true);
                Box::new(LineWriter::new(stream))
            }
            _ => {
                return Err(UsageError(format!(
                    "--send {spec}: expected udp:HOST:PORT or tcp:HOST:PORT"
                ))
                .into());
            }
        }),
    };
    let printed: Option<Box<dyn Write>> =
        print.then(|| Box::new(LineWriter::new(io::stdout())) as Box<dyn Write>);
    Ok(match (printed, sent) {
        (Some(a), Some(b)) => Some(Box::new(Both(a, b))),
        (a, b) => a.or(b),
    })
}

/// Each line written, sent as one UDP datagram.
struct Datagrams {
    socket: UdpSocket,
    line: Vec<u8>,
}

impl Write for Datagrams {
    fn write(&mut self, bytes: &[u8]) -> io::Result<usize> {
        for &byte in bytes {
            self.line.push(byte);
            if byte == b'\n' {
                // A consumer not listening yet loses the line, as UDP does.
                let _ = self.socket.send(&self.line);
                self.line.clear();
            }
        }
        Ok(bytes.len())
    }

    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

/// Writes to both.
struct Both(Box<dyn Write>, Box<dyn Write>);

impl Write for Both {
    fn write(&mut self, bytes: &[u8]) -> io::Result<usize> {
        self.0.write_all(bytes)?;
        self.1.write_all(bytes)?;
        Ok(bytes.len())
    }

    fn flush(&mut self) -> io::Result<()> {
        self.0.flush()?;
        self.1.flush()
    }
}

/// Ctrl-C ends the session (its files are written); a second one ends the program at once.
fn stop_on_ctrl_c(sender: std::sync::mpsc::Sender<Arrival>) {
    let mut stopping = false;
    let _ = ctrlc::set_handler(move || {
        if stopping {
            std::process::exit(130);
        }
        stopping = true;
        let _ = sender.send(Arrival::now(Received::End));
    });
}

/// The stream's counts, one line.
fn print_counts(text: &mut String, c: &LiveCounts) {
    let _ = writeln!(
        text,
        "live: {} frames; skipped {} malformed, {} out of range, {} stale; {} gaps ({} held frames, {} back to standing); {} connections, {} disconnects",
        c.frames,
        c.malformed,
        c.out_of_range,
        c.stale,
        c.gaps,
        c.held_frames,
        c.stands,
        c.connections,
        c.disconnects
    );
}
