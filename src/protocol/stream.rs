//! The streaming frame engine that the three codecs share.
//!
//! A protocol describes its framing with [`Framing::scan`]; [`Decoder`] does the rest: buffering
//! bytes that arrive in any chunking, skipping junk, re-synchronising one byte after a false
//! header or a bad frame, and reporting every skipped byte exactly once.

use super::FrameError;

/// How much junk is kept, as bytes, in one [`FrameError::Junk`] report (the count is exact).
pub const JUNK_SAMPLE: usize = 64;

/// What a protocol finds at a candidate frame start.
#[derive(Debug)]
pub enum Scan<F> {
    /// These bytes cannot start a frame: skip one.
    NoHeader,
    /// A valid prefix of a frame.
    NeedMore {
        /// The whole frame's length in bytes, once the length field has arrived.
        need: Option<usize>,
    },
    /// A whole, valid frame of `len` bytes.
    Frame(F, usize),
    /// A header followed by a bad frame: report it, then search again from the next byte.
    Bad(FrameError),
}

/// A protocol's framing rules.
pub trait Framing {
    /// The frame type this framing yields.
    type Frame;
    /// Whether `byte` may be the first byte of a frame (a fast pre-filter).
    fn is_start(&self, byte: u8) -> bool;
    /// Looks at `buf`, which starts with a byte for which `is_start` holds.
    fn scan(&self, buf: &[u8]) -> Scan<Self::Frame>;
}

/// A streaming decoder: push bytes in any chunking, then iterate frames and errors.
///
/// The iterator is not fused: it yields `None` when it needs more bytes and resumes after the next
/// [`push`](Decoder::push). Memory is bounded by the largest chunk pushed plus one frame.
#[derive(Debug, Clone)]
pub struct Decoder<P: Framing> {
    framing: P,
    buf: Vec<u8>,
    pos: usize,
    /// Stream offset of `buf[0]`.
    base: u64,
    /// Skipped bytes up to this stream offset belong to a bad frame already reported.
    shadow_end: u64,
    junk_len: usize,
    junk_start: u64,
    junk_sample: Vec<u8>,
    last_start: u64,
    /// The line went quiet: a partial frame at the head will not complete.
    stale: bool,
}

impl<P: Framing> Decoder<P> {
    /// A decoder with the given framing rules.
    pub fn with_framing(framing: P) -> Self {
        Self {
            framing,
            buf: Vec::new(),
            pos: 0,
            base: 0,
            shadow_end: 0,
            junk_len: 0,
            junk_start: 0,
            junk_sample: Vec::new(),
            last_start: 0,
            stale: false,
        }
    }

    /// Appends received bytes.
    pub fn push(&mut self, bytes: &[u8]) {
        if !bytes.is_empty() {
            self.stale = false;
        }
        if self.pos == self.buf.len() {
            self.base += self.pos as u64;
            self.buf.clear();
            self.pos = 0;
        } else if self.pos > 0 {
            self.base += self.pos as u64;
            self.buf.drain(..self.pos);
            self.pos = 0;
        }
        self.buf.extend_from_slice(bytes);
    }

    /// Says that the line has gone quiet (no byte for longer than a frame's bytes are ever
    /// apart), so a partial frame at the head will not complete. The iterator then treats it as
    /// a false header: it searches the buffered bytes behind it for a frame, reports the bytes
    /// before that frame as junk, and reports a partial frame with nothing behind it as
    /// [`FrameError::Truncated`]. Without this, junk that looks like a header announcing a long
    /// length would hold back a real reply until more bytes arrive.
    pub fn flush(&mut self) {
        self.stale = true;
    }

    /// The stream offset where decoding resumes: just past the last frame returned, or one byte
    /// past the start of the last bad frame (the decoder re-synchronises from there).
    pub fn stream_offset(&self) -> u64 {
        self.base + self.pos as u64
    }

    /// The stream offset where the item last returned (frame or error) begins.
    pub fn last_start(&self) -> u64 {
        self.last_start
    }

    /// Bytes received but not yet consumed (a partial frame, at most one frame long).
    pub fn buffered(&self) -> usize {
        self.buf.len() - self.pos
    }

    /// Drops everything buffered, as after a port reopen or a baud change.
    pub fn clear(&mut self) {
        self.base += self.buf.len() as u64;
        self.buf.clear();
        self.pos = 0;
        self.junk_len = 0;
        self.junk_sample.clear();
    }

    /// Ends the stream: reports a trailing partial frame or junk, and empties the buffer.
    ///
    /// Drain the iterator first: complete frames still buffered would be reported as junk. To
    /// rescue frames hidden behind a false header at the end of input, call [`flush`](Self::flush)
    /// and drain the iterator again before this.
    pub fn finish(&mut self) -> Option<FrameError> {
        if let Some(junk) = self.take_junk() {
            return Some(junk);
        }
        let rest = &self.buf[self.pos..];
        if rest.is_empty() {
            return None;
        }
        self.last_start = self.stream_offset();
        let err = if self.framing.is_start(rest[0]) {
            match self.framing.scan(rest) {
                Scan::NeedMore { need } => FrameError::Truncated {
                    have: rest.len(),
                    need,
                    bytes: rest.to_vec(),
                },
                _ => junk_error(rest),
            }
        } else {
            junk_error(rest)
        };
        self.clear();
        Some(err)
    }

    fn skip(&mut self, n: usize) {
        let start = self.stream_offset();
        let end = start + n as u64;
        if end > self.shadow_end {
            let from = self.shadow_end.max(start);
            let skip_from = self.pos + (from - start) as usize;
            let counted = (end - from) as usize;
            if self.junk_len == 0 {
                self.junk_start = from;
            }
            self.junk_len += counted;
            let room = JUNK_SAMPLE.saturating_sub(self.junk_sample.len());
            let take = room.min(counted);
            self.junk_sample
                .extend_from_slice(&self.buf[skip_from..skip_from + take]);
        }
        self.pos += n;
    }

    fn take_junk(&mut self) -> Option<FrameError> {
        if self.junk_len == 0 {
            return None;
        }
        let len = std::mem::take(&mut self.junk_len);
        self.last_start = self.junk_start;
        Some(FrameError::Junk {
            len,
            sample: std::mem::take(&mut self.junk_sample),
        })
    }
}

fn junk_error(bytes: &[u8]) -> FrameError {
    FrameError::Junk {
        len: bytes.len(),
        sample: bytes[..bytes.len().min(JUNK_SAMPLE)].to_vec(),
    }
}

impl<P: Framing> Iterator for Decoder<P> {
    type Item = Result<P::Frame, FrameError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            let rest = &self.buf[self.pos..];
            if rest.is_empty() {
                return self.take_junk().map(Err);
            }
            if !self.framing.is_start(rest[0]) {
                let framing = &self.framing;
                let run = rest
                    .iter()
                    .position(|&b| framing.is_start(b))
                    .unwrap_or(rest.len());
                self.skip(run);
                continue;
            }
            match self.framing.scan(rest) {
                Scan::NoHeader => self.skip(1),
                Scan::NeedMore { need } if self.stale => {
                    let framing = &self.framing;
                    let behind = (1..rest.len()).find(|&i| {
                        framing.is_start(rest[i])
                            && matches!(framing.scan(&rest[i..]), Scan::Frame(..) | Scan::Bad(_))
                    });
                    match behind {
                        Some(i) => self.skip(i),
                        None => {
                            let err = FrameError::Truncated {
                                have: rest.len(),
                                need,
                                bytes: rest.to_vec(),
                            };
                            if let Some(junk) = self.take_junk() {
                                return Some(Err(junk));
                            }
                            self.last_start = self.stream_offset();
                            self.pos = self.buf.len();
                            self.shadow_end = self.shadow_end.max(self.stream_offset());
                            self.stale = false;
                            return Some(Err(err));
                        }
                    }
                }
                Scan::NeedMore { .. } => return self.take_junk().map(Err),
                Scan::Frame(frame, len) => {
                    if let Some(junk) = self.take_junk() {
                        return Some(Err(junk));
                    }
                    self.last_start = self.stream_offset();
                    self.pos += len;
                    self.shadow_end = self.shadow_end.max(self.stream_offset());
                    return Some(Ok(frame));
                }
                Scan::Bad(err) => {
                    if let Some(junk) = self.take_junk() {
                        return Some(Err(junk));
                    }
                    self.last_start = self.stream_offset();
                    let end = self.last_start + err.span() as u64;
                    self.pos += 1;
                    self.shadow_end = self.shadow_end.max(end);
                    return Some(Err(err));
                }
            }
        }
    }
}
