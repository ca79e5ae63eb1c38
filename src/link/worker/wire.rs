//! The wire: the port (and how to reopen it after a loss), the decoder of what the device sends,
//! the port's rate, when the bytes written so far have crossed the line, and the counters of
//! what crossed it. Nothing here decides what a frame means: that is the exchange's and the
//! session's.

use crate::link::decoder::AnyDecoder;
use crate::link::{LinkError, LinkState, LinkStats, Opener, Transport, wire_time};
use crate::packet::Packet;
use crate::profile::Protocol;
use crate::protocol::FrameError;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// How often an idle worker checks that the port is still there.
const PORT_CHECK: Duration = Duration::from_millis(500);
/// The most bytes one read takes.
const READ_CHUNK: usize = 4096;

/// The port of one link and the bytes on it.
pub(super) struct Wire {
    /// The port; `None` while it is lost.
    transport: Option<Box<dyn Transport>>,
    /// Reopens the port after a loss.
    opener: Opener,
    decoder: AnyDecoder,
    /// The port's rate, in baud.
    baud: u32,
    /// When the bytes written so far have crossed the wire (at the rate they were sent at).
    sent_until: Instant,
    /// When the idle worker last checked that the port is there.
    checked_at: Instant,
    /// Frames sent and received, errors, timeouts, margins: what the status bar shows.
    pub(super) stats: LinkStats,
    /// Why the port was lost, while it is: what a request made since is told.
    lost_because: Option<String>,
    /// The port's count of bytes taken by another reader ([`Transport::taken`]) when last
    /// looked at, and when it last grew.
    taken: (u64, Option<Instant>),
    /// When the bytes of the last read that brought any had arrived ([`Transport::arrived_at`],
    /// else when it returned).
    arrived: Instant,
    /// Bytes read from the port since the link opened, of any kind (answers, late answers,
    /// junk), shared with the link's clients ([`crate::link::Client::bytes_heard`]).
    heard: Arc<AtomicU64>,
}

/// How long after the port last said bytes had been taken by another reader an unanswered
/// request is put down to that reader.
const TAKEN_RECENTLY: Duration = Duration::from_secs(5);

impl Wire {
    /// The wire over `transport`, opened by `opener`, carrying `protocol`.
    pub(super) fn new(transport: Box<dyn Transport>, opener: Opener, protocol: Protocol) -> Self {
        let now = Instant::now();
        Self {
            baud: transport.baud(),
            transport: Some(transport),
            opener,
            decoder: AnyDecoder::new(protocol),
            sent_until: now,
            checked_at: now,
            stats: LinkStats::default(),
            lost_because: None,
            taken: (0, None),
            arrived: now,
            heard: Arc::default(),
        }
    }

    /// The count of bytes read from the port since the link opened, as its clients see it.
    pub(super) fn heard(&self) -> Arc<AtomicU64> {
        self.heard.clone()
    }

    /// Who is taking this port's bytes, when someone is: the other programs that have it open,
    /// or, when the OS names none this user may see, that it said bytes had arrived which were
    /// gone when read within the last [`TAKEN_RECENTLY`]. `None` while the port is not shared.
    pub(super) fn taken_by(&mut self) -> Option<(String, String)> {
        let t = self.transport.as_mut()?;
        let count = t.taken();
        if count > self.taken.0 {
            self.stats.taken_reads += count - self.taken.0;
            self.taken = (count, Some(Instant::now()));
        }
        let recently = self.taken.1.is_some_and(|at| at.elapsed() < TAKEN_RECENTLY);
        let others = t.others_reading();
        let port = t.describe();
        if !others.is_empty() {
            let mut by = crate::system::Holder::list(&others);
            if recently {
                by.push_str("; answers vanished after the port said they had come");
            }
            return Some((port, by));
        }
        recently.then(|| {
            (
                port,
                "a program this user cannot see: answers vanished after the port said they had \
                 come; `sudo fuser -v PORT` names it"
                    .replace("PORT", &t.describe()),
            )
        })
    }

    /// Whether the port is open (not lost).
    pub(super) fn is_open(&self) -> bool {
        self.transport.is_some()
    }

    /// The port's rate, in baud.
    pub(super) fn baud(&self) -> u32 {
        self.baud
    }

    /// When the bytes written so far have crossed the wire.
    pub(super) fn sent_until(&self) -> Instant {
        self.sent_until
    }

    /// When the last write's bytes started on the wire, where the port knows it
    /// ([`crate::link::Transport::written_at`]).
    pub(super) fn written_at(&self) -> Option<Instant> {
        self.transport.as_ref().and_then(|t| t.written_at())
    }

    /// The USB adapter's latency timer, where the port knows it.
    pub(super) fn latency_timer(&self) -> Option<Duration> {
        self.transport.as_ref().and_then(|t| t.latency_timer())
    }

    /// [`LinkState::Connected`] with the port's description and rate, while it is open.
    pub(super) fn connected_state(&self) -> Option<LinkState> {
        self.transport.as_ref().map(|t| LinkState::Connected {
            port: t.describe(),
            baud: t.baud(),
        })
    }

    /// Writes `bytes` whole; counts a frame sent. An error means the port is gone: the caller
    /// loses it ([`Self::lose`]).
    pub(super) fn write(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        let Some(t) = self.transport.as_mut() else {
            return Err(LinkError::Disconnected(self.why_lost()));
        };
        t.write(bytes)?;
        let now = Instant::now();
        self.sent_until = self.sent_until.max(now) + wire_time(bytes.len(), self.baud);
        self.stats.sent += 1;
        Ok(())
    }

    /// Reads what arrives before `deadline` into the decoder; returns how many bytes. An error
    /// means the port is gone: the caller loses it.
    pub(super) fn read_some(&mut self, deadline: Instant) -> Result<usize, LinkError> {
        let Some(t) = self.transport.as_mut() else {
            return Err(LinkError::Disconnected(self.why_lost()));
        };
        let mut buf = [0u8; READ_CHUNK];
        let n = t.read(&mut buf, deadline)?;
        if n > 0 {
            self.arrived = t.arrived_at().unwrap_or_else(Instant::now);
            self.heard.fetch_add(n as u64, Ordering::Relaxed);
        }
        self.decoder.push(&buf[..n]);
        Ok(n)
    }

    /// When the bytes last read had arrived: the instant an answer decoded now is measured to
    /// (its latency, its round trip), never later than now.
    pub(super) fn arrived(&self) -> Instant {
        self.arrived.min(Instant::now())
    }

    /// The next frame (or frame error) decoded, as the decoder read it.
    pub(super) fn next_frame(&mut self) -> Option<Result<Packet, FrameError>> {
        self.decoder.next_packet()
    }

    /// Bytes held that are not a frame yet.
    pub(super) fn buffered(&self) -> usize {
        self.decoder.buffered()
    }

    /// The line went quiet: a partial frame held will not complete.
    pub(super) fn flush(&mut self) {
        self.decoder.flush();
    }

    /// Switches the port to `baud` once the bytes written have crossed the wire at the old rate
    /// (a frame still crossing would be cut); what was received is dropped. An error means the
    /// port refused or is gone.
    pub(super) fn set_baud(&mut self, baud: u32) -> Result<(), LinkError> {
        let now = Instant::now();
        if self.sent_until > now {
            std::thread::sleep(self.sent_until - now);
        }
        self.baud = baud;
        let why = self.why_lost();
        let t = self
            .transport
            .as_mut()
            .ok_or(LinkError::Disconnected(why))?;
        if let Err(refused) = t.set_baud(baud) {
            // A port that went refuses its settings too (EIO): said as lost when flushing it
            // says so, else as the setting refused.
            return Err(match t.clear_input() {
                Err(lost @ LinkError::Disconnected(_)) => lost,
                _ => refused,
            });
        }
        let _ = t.clear_input();
        self.decoder.clear();
        Ok(())
    }

    /// Drops what was received and not yet taken, and what was half decoded (a booting board's
    /// banner). An error means the port is gone.
    pub(super) fn clear_input(&mut self) -> Result<(), LinkError> {
        if let Some(t) = self.transport.as_mut() {
            t.clear_input()?;
        }
        self.decoder.clear();
        Ok(())
    }

    /// The port went away (`reason`): closed, and what was half decoded dropped.
    pub(super) fn lose(&mut self, reason: &str) {
        self.transport = None;
        self.decoder.clear();
        self.lost_because = Some(reason.to_string());
        // The last round trip was the lost connection's: none is measured until an answer.
        self.stats.rtt = None;
    }

    /// Why the port is lost, for a request made since it was: `port lost: ` and the reason it
    /// went (the same words whenever the request came).
    pub(super) fn why_lost(&self) -> String {
        match &self.lost_because {
            Some(reason) => format!("port lost: {reason}"),
            None => "port lost".into(),
        }
    }

    /// Reopens a lost port at the rate it had.
    pub(super) fn reopen(&mut self) -> Result<(), LinkError> {
        let mut t = (self.opener)()?;
        if t.baud() != self.baud {
            let _ = t.set_baud(self.baud);
        }
        self.transport = Some(t);
        self.decoder.clear();
        self.lost_because = None;
        Ok(())
    }

    /// While idle, every [`PORT_CHECK`]: whether the port is still there (a USB adapter
    /// unplugged). An error means it is gone.
    pub(super) fn check(&mut self, now: Instant) -> Result<(), LinkError> {
        if now.duration_since(self.checked_at) < PORT_CHECK {
            return Ok(());
        }
        self.check_now(now)
    }

    /// [`Self::check`] at once, however recently the port was looked at.
    pub(super) fn check_now(&mut self, now: Instant) -> Result<(), LinkError> {
        self.checked_at = now;
        match self.transport.as_mut() {
            Some(t) => t.check(),
            None => Ok(()),
        }
    }
}
