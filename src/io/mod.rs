//! Readers of human motion (the `io` layer, above `human`): BVH motion capture ([`bvh`]) and Microsoft
//! Kinect v2 skeleton CSV ([`kinect`]). Both stream: a reader parses its header once and then
//! yields one [`crate::human::HumanFrame`] at a time, so a live source and a file feed
//! the same pipeline. Both cap what a file may ask for (line length, joint count) so that hostile
//! input is refused with a typed error instead of exhausting memory.

pub mod bvh;
pub mod clip;
pub mod kinect;
pub mod skeleton_map;

use std::io::{self, BufRead, Read};

use crate::human::HumanFrame;

/// A source of human frames, one at a time, in time order: a clip file ([`clip::Clip`]) or a
/// live stream ([`crate::live::LiveSource`]). The imitation's clip loop
/// ([`crate::batch::imitate_clip`]) reads either.
pub trait FrameSource {
    /// Reads the next frame into `out`; `Ok(false)` at the end.
    ///
    /// # Errors
    /// The source's read error, naming where.
    fn read_frame(&mut self, out: &mut HumanFrame) -> Result<bool, clip::ClipError>;
}

/// A source lent to the clip loop stays the caller's, to be asked afterwards (a live
/// session's counts).
impl<S: FrameSource + ?Sized> FrameSource for &mut S {
    fn read_frame(&mut self, out: &mut HumanFrame) -> Result<bool, clip::ClipError> {
        (**self).read_frame(out)
    }
}

/// The iterator item of a reader with `read_frame(&mut HumanFrame) -> Result<bool, E>`: the next
/// frame, `None` at the end, or the error.
fn next_frame<E>(
    read: impl FnOnce(&mut HumanFrame) -> Result<bool, E>,
) -> Option<Result<HumanFrame, E>> {
    let mut frame = HumanFrame::new(0.0);
    match read(&mut frame) {
        Ok(true) => Some(Ok(frame)),
        Ok(false) => None,
        Err(e) => Some(Err(e)),
    }
}

/// Reads one line (without its `\n` / `\r\n`) into `buf`, reading at most `max_bytes` bytes.
/// Returns `Ok(None)` at end of input and `Ok(Some(true))` if the line was longer than
/// `max_bytes` (the rest of it is left unread). Invalid UTF-8 is an `InvalidData` error.
pub(crate) fn read_line_capped<R: BufRead>(
    reader: &mut R,
    buf: &mut String,
    max_bytes: usize,
) -> io::Result<Option<bool>> {
    buf.clear();
    let limit = u64::try_from(max_bytes).unwrap_or(u64::MAX);
    let n = reader.by_ref().take(limit).read_line(buf)?;
    if n == 0 {
        return Ok(None);
    }
    let complete = buf.ends_with('\n');
    if complete {
        buf.pop();
        if buf.ends_with('\r') {
            buf.pop();
        }
    }
    Ok(Some(!complete && n >= max_bytes))
}
