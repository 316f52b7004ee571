//! Where a live session's lines come from: standard input, a TCP connection (as server or
//! client) or UDP datagrams, each read on its own thread into a channel, every line stamped
//! with its arrival.

use std::io::{self, BufRead, BufReader};
use std::net::{TcpListener, TcpStream, ToSocketAddrs, UdpSocket};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::thread;
use std::time::{Duration, Instant};

use crate::io::read_line_capped;

/// The longest line a stream may send (bytes): a Kinect frame line is about 2.5 KB, a BVH
/// motion line of a 31-joint CMU skeleton about 1 KB. A longer line is cut there and its parts
/// count as malformed.
pub const MAX_LINE_BYTES: usize = 64 * 1024;

/// How long a TCP client waits between attempts to connect (s).
pub const RECONNECT_PERIOD: f64 = 0.5;

/// What arrived from the source.
#[derive(Debug)]
pub enum Received {
    /// One line (without its end of line).
    Line(String),
    /// A source connected (its address).
    Connected(String),
    /// The source went away; a TCP server waits for the next, a client reconnects.
    Disconnected,
    /// The session is over: standard input ended, the first source left a session that
    /// serves one (`once` of [`Input::open`]), or the user stopped it.
    End,
    /// The input failed and cannot go on (a port that cannot be bound, standard input
    /// unreadable).
    Failed(io::Error),
}

/// A [`Received`] and when it arrived.
#[derive(Debug)]
pub struct Arrival {
    /// What arrived.
    pub received: Received,
    /// When.
    pub at: Instant,
}

impl Arrival {
    /// `received`, arriving now.
    pub fn now(received: Received) -> Self {
        Self {
            received,
            at: Instant::now(),
        }
    }
}

/// The stream a live session reads.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Input {
    /// Standard input; it ending ends the session.
    Stdin,
    /// A TCP server at this address (`HOST:PORT`): one source at a time; after one leaves, the
    /// next is accepted.
    TcpListen(String),
    /// A TCP client of this address: it connects, and reconnects every [`RECONNECT_PERIOD`]
    /// after a disconnect or a refused connection.
    TcpConnect(String),
    /// UDP datagrams to this local address, each holding one or more lines.
    Udp(String),
}

impl Input {
    /// The input's name in errors and the report (`stdin`, `tcp://ADDR`, `udp://ADDR`).
    pub fn origin(&self) -> String {
        match self {
            Input::Stdin => "stdin".to_owned(),
            Input::TcpListen(a) | Input::TcpConnect(a) => format!("tcp://{a}"),
            Input::Udp(a) => format!("udp://{a}"),
        }
    }

    /// Starts reading on a thread of its own; `once`: the session ends when the first TCP
    /// source leaves (standard input always ends at its end; UDP has no end but the user's,
    /// or the session's own idle end). Returns the channel of arrivals and its sender, for
    /// the caller's own [`Received::End`] (a Ctrl-C handler, say).
    ///
    /// # Errors
    /// A TCP server's or a UDP socket's address that cannot be bound, at once.
    pub fn open(&self, once: bool) -> io::Result<(Receiver<Arrival>, Sender<Arrival>)> {
        let (tx, rx) = channel();
        let sender = tx.clone();
        match self.clone() {
            Input::Stdin => spawn(move || {
                read_lines(io::stdin().lock(), &tx, true);
            }),
            Input::TcpListen(address) => {
                let listener = TcpListener::bind(&address)?;
                spawn(move || serve(&listener, once, &tx));
            }
            Input::TcpConnect(address) => spawn(move || connect(&address, once, &tx)),
            Input::Udp(address) => {
                let socket = UdpSocket::bind(&address)?;
                spawn(move || receive(&socket, &tx));
            }
        }
        Ok((rx, sender))
    }
}

fn spawn(f: impl FnOnce() + Send + 'static) {
    thread::spawn(f);
}

/// Sends every line of `reader` (then [`Received::End`] when `last`, else
/// [`Received::Disconnected`]); `false` when the session is gone (the receiver dropped).
fn read_lines(mut reader: impl BufRead, tx: &Sender<Arrival>, last: bool) -> bool {
    let mut line = String::new();
    loop {
        match read_line_capped(&mut reader, &mut line, MAX_LINE_BYTES) {
            Ok(Some(_)) => {
                let text = std::mem::take(&mut line);
                if tx.send(Arrival::now(Received::Line(text))).is_err() {
                    return false;
                }
            }
            Ok(None) => break,
            // A broken connection is a disconnect; unreadable standard input ends the session.
            Err(err) if last => return tx.send(Arrival::now(Received::Failed(err))).is_ok(),
            Err(_) => break,
        }
    }
    let end = if last {
        Received::End
    } else {
        Received::Disconnected
    };
    tx.send(Arrival::now(end)).is_ok()
}

/// A TCP server: one source at a time, until the session ends.
fn serve(listener: &TcpListener, once: bool, tx: &Sender<Arrival>) {
    for stream in listener.incoming() {
        let Ok(stream) = stream else { continue };
        if !stream_lines(stream, once, tx) || once {
            return;
        }
    }
}

/// A TCP client: connects and reconnects until the session ends.
fn connect(address: &str, once: bool, tx: &Sender<Arrival>) {
    loop {
        let stream = address
            .to_socket_addrs()
            .ok()
            .and_then(|mut addresses| addresses.find_map(|a| TcpStream::connect(a).ok()));
        match stream {
            Some(stream) => {
                if !stream_lines(stream, once, tx) || once {
                    return;
                }
            }
            None => thread::sleep(Duration::from_secs_f64(RECONNECT_PERIOD)),
        }
    }
}

/// Announces `stream`, sends its lines, then its end; `false` when the session is gone.
fn stream_lines(stream: TcpStream, once: bool, tx: &Sender<Arrival>) -> bool {
    let peer = stream
        .peer_addr()
        .map_or_else(|_| "?".to_owned(), |a| a.to_string());
    let _ = stream.set_nodelay(true);
    if tx.send(Arrival::now(Received::Connected(peer))).is_err() {
        return false;
    }
    read_lines(BufReader::new(stream), tx, once)
}

/// UDP datagrams, split into lines, until the session ends.
fn receive(socket: &UdpSocket, tx: &Sender<Arrival>) {
    let mut buffer = vec![0u8; MAX_LINE_BYTES];
    loop {
        let received = socket.recv(&mut buffer);
        let Ok(n) = received else {
            continue;
        };
        let mut lines = BufReader::new(&buffer[..n]);
        let mut text = String::new();
        while let Ok(Some(_)) = read_line_capped(&mut lines, &mut text, MAX_LINE_BYTES) {
            if tx
                .send(Arrival::now(Received::Line(std::mem::take(&mut text))))
                .is_err()
            {
                return;
            }
        }
        // A datagram that is not UTF-8: one malformed line.
        if std::str::from_utf8(&buffer[..n]).is_err()
            && tx
                .send(Arrival::now(Received::Line("\u{fffd}".to_owned())))
                .is_err()
        {
            return;
        }
    }
}
