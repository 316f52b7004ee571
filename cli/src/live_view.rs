//! The live view of `taskstack live --view HOST:PORT`: the viewer page (`view.html`'s) served
//! over HTTP, its frames pushed to each open page over a WebSocket as the session runs; a page
//! opened late first gets the frames of the last [`BACKLOG`] seconds.

use std::collections::VecDeque;
use std::io::Write;
use std::net::{TcpListener, TcpStream};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread;

use anyhow::{Context, Result};
use taskstack::RobotFrame;
use taskstack::robots::BipedProfile;
use tungstenite::{Message, WebSocket};

use crate::view::{VIEW_RATE, ViewWriter};

/// How much of the session a page opened late is sent first (s).
pub(crate) const BACKLOG: f64 = 30.0;

/// The open pages and the frames a new one is sent first.
#[derive(Default)]
struct Pages {
    sockets: Vec<WebSocket<TcpStream>>,
    backlog: VecDeque<String>,
}

/// The live view: the page, and its frames sent as they come.
pub(crate) struct LiveView {
    view: ViewWriter<Vec<u8>>,
    pages: Arc<Mutex<Pages>>,
}

impl LiveView {
    /// Serves the view of a session of `profile`'s robot at `address` (`HOST:PORT`).
    pub(crate) fn serve(address: &str, profile: &BipedProfile, title: &str) -> Result<Self> {
        let listener = TcpListener::bind(address).with_context(|| format!("--view {address}"))?;
        let mut view = ViewWriter::new(Vec::new(), profile, title)?;
        let head = String::from_utf8_lossy(&view.take_written()).into_owned();
        let page = Arc::new(ViewWriter::<Vec<u8>>::live_page(&head)?);
        let pages = Arc::new(Mutex::new(Pages::default()));
        let shared = Arc::clone(&pages);
        thread::spawn(move || {
            for stream in listener.incoming().flatten() {
                let (page, pages) = (Arc::clone(&page), Arc::clone(&shared));
                thread::spawn(move || answer(stream, &page, &pages));
            }
        });
        Ok(Self { view, pages })
    }

    /// Sends robot frame `r` to every open page if it is due at the view's rate; a page that
    /// has gone is forgotten.
    pub(crate) fn frame(&mut self, r: &RobotFrame) -> Result<()> {
        self.view.frame(r)?;
        let written = self.view.take_written();
        let line = String::from_utf8_lossy(&written);
        let line = line.trim_end().trim_end_matches(',');
        if line.is_empty() {
            return Ok(());
        }
        let mut pages = self.pages.lock().unwrap_or_else(PoisonError::into_inner);
        pages.backlog.push_back(line.to_owned());
        if pages.backlog.len() as f64 > BACKLOG * VIEW_RATE {
            pages.backlog.pop_front();
        }
        pages
            .sockets
            .retain_mut(|socket| socket.send(Message::text(line)).is_ok());
        Ok(())
    }
}

/// Answers one connection: a WebSocket (the page's frames: the backlog, then each new one) or
/// any other request (the page).
fn answer(mut stream: TcpStream, page: &str, pages: &Mutex<Pages>) {
    let mut head = [0u8; 2048];
    let n = stream.peek(&mut head).unwrap_or(0);
    let request = String::from_utf8_lossy(&head[..n]).to_ascii_lowercase();
    if !request.contains("upgrade: websocket") {
        let _ = write!(
            stream,
            "HTTP/1.1 200 OK\r\nContent-Type: text/html; charset=utf-8\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{page}",
            page.len()
        );
        return;
    }
    let _ = stream.set_nodelay(true);
    let Ok(mut socket) = tungstenite::accept(stream) else {
        return;
    };
    let mut pages = pages.lock().unwrap_or_else(PoisonError::into_inner);
    let backlog: Vec<String> = pages.backlog.iter().cloned().collect();
    if backlog
        .into_iter()
        .all(|line| socket.send(Message::text(line)).is_ok())
    {
        pages.sockets.push(socket);
    }
}
