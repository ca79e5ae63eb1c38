//! How long to wait for an answer, learned while connected, and the answers still owed.
//!
//! The deadlines of an exchange (see the README, "Deadlines from the wire"):
//! - the first byte of an answer is awaited for the request's wire time, one byte and the
//!   **margin**: the request's, else the link's `--margin-ms`, else the automatic margin: the
//!   device's own (the protocol's default) plus the adapter's latency timer where the OS gives
//!   it, or the answer latency measured on this connection with headroom, whichever is more;
//! - once a frame has started, the rest is awaited for its wire time plus the **frame gap**: an
//!   adapter hands a frame over in bursts, one latency tick apart, so the gap is never less than
//!   the margin, the adapter's latency timer, or [`FRAME_GAP_MIN`];
//! - after the last attempt, an exchange still listens for the **grace** period for an answer
//!   that comes late: [`GRACE_MIN`] while nothing has been measured on the connection (a slow
//!   adapter not known yet, a loaded host), then less as answers are measured, down to
//!   [`GRACE_MARGINS`] automatic margins, at least the frame gap;
//! - an attempt that went unanswered is **owed**: its answer may still come. An owed answer is
//!   taken for its own request when it comes (counted, its latency learned), never for a later
//!   request, and it is forgotten when an answer to a later request comes first (the devices
//!   answer in order) or after [`LATE_LIMIT_MIN`] (or ten margins).

use crate::link::request::{Match, Request};
use crate::link::wire_time;
use crate::packet::Packet;
use log::debug;
use std::collections::VecDeque;
use std::time::{Duration, Instant};

/// The least time allowed for the rest of a frame that has started: a USB adapter's default
/// latency timer (16 ms) with slack.
pub(crate) const FRAME_GAP_MIN: Duration = Duration::from_millis(20);
/// How long an exchange keeps listening after its last attempt, for a late answer, before any
/// answer latency has been measured on the connection: a loaded host can see an answer 100 ms
/// or more after it came (a default 16 ms latency timer, and a scheduler that wakes the reader
/// late, twice an exchange: measured up to 50 ms each on a loaded 2-core machine). Only an
/// exchange left unanswered pays it.
pub(crate) const GRACE_MIN: Duration = Duration::from_millis(150);
/// Once answers have been measured, the grace is this many automatic margins (the latest
/// answer latencies at their worst, with headroom; a loaded host's delays are in them), at least
/// the frame gap. A few answers show a connection only roughly (on the simulated slow host that
/// delays each answer by up to 25 ms at random, one answer in six comes within 4 ms), so with `n`
/// answers measured the grace stays at least [`GRACE_MIN`] × 2 / (n + 2): 100 ms after one,
/// 50 ms after four, and the frame gap's 20 ms from about the thirteenth on. An answer later than
/// the grace is still taken for its own request when it comes (it is owed), and widens the
/// margin.
pub(crate) const GRACE_MARGINS: u32 = 4;
/// The longest automatic margin (beyond it a device is taken for silent).
const MARGIN_CAP: Duration = Duration::from_millis(250);
/// How long an owed answer is waited for at least.
pub(crate) const LATE_LIMIT_MIN: Duration = Duration::from_millis(500);
/// How many answer latencies the automatic margin looks back on.
const RECENT: usize = 32;
/// How many owed answers are kept at most.
const OWED_CAP: usize = 64;

/// The answer timing of one link: the margin given (`--margin-ms`) or the device's own, what has
/// been measured on this connection, and the answers still owed to unanswered attempts.
#[derive(Debug)]
pub(super) struct Timing {
    /// `--margin-ms`: the margin of every request that names none, instead of the automatic one.
    fixed: Option<Duration>,
    /// The protocol's own margin (see [`crate::link::default_margin`]).
    device: Duration,
    /// What has been measured on this connection.
    pub(super) learned: AnswerTiming,
    /// Answers still owed to attempts that went unanswered.
    pub(super) owed: OwedAnswers,
}

impl Timing {
    /// The timing of a new link: `fixed` (`--margin-ms`) or the automatic margin from `device`
    /// (the protocol's own) and the adapter's `latency_timer`.
    pub(super) fn new(
        fixed: Option<Duration>,
        device: Duration,
        latency_timer: Option<Duration>,
    ) -> Self {
        Self {
            fixed,
            device,
            learned: AnswerTiming::new(latency_timer),
            owed: OwedAnswers::default(),
        }
    }

    /// A new connection (a reconnect): nothing measured, nothing owed.
    pub(super) fn connected(&mut self, latency_timer: Option<Duration>) {
        self.learned = AnswerTiming::new(latency_timer);
        self.owed.clear();
    }

    /// How long the device may take to start answering `req`, beyond the wire time: the
    /// request's own margin, else the link's ([`Self::auto_margin`]).
    pub(super) fn margin(&self, req: &Request) -> Duration {
        req.margin.unwrap_or_else(|| self.auto_margin())
    }

    /// The link's margin: `--margin-ms`, else the automatic one (the protocol's own, the
    /// adapter's latency timer, the answer latency measured on this connection).
    pub(super) fn auto_margin(&self) -> Duration {
        self.fixed
            .unwrap_or_else(|| self.learned.margin(self.device))
    }

    /// Takes one answer latency; a change of the automatic margin is logged.
    pub(super) fn observe(&mut self, latency: Duration) {
        let before = self.auto_margin();
        self.learned.observe(latency);
        let after = self.auto_margin();
        if after != before {
            debug!(
                "margin {:.1} ms -> {:.1} ms (answer latency {:.1} ms)",
                ms(before),
                ms(after),
                ms(latency)
            );
        }
    }

    /// The latency of an answer that arrived at `arrived` to a request whose last byte was on
    /// the wire at `sent`: the time between, less the answer's own wire time (`answer_bytes` at
    /// `baud`).
    pub(super) fn latency_of(
        arrived: Instant,
        sent: Instant,
        answer_bytes: usize,
        baud: u32,
    ) -> Duration {
        arrived
            .saturating_duration_since(sent)
            .saturating_sub(wire_time(answer_bytes, baud))
    }

    /// Owes `answer` to an attempt whose last byte was on the wire at `sent`, for as long as
    /// the late limit of `margin` from now.
    pub(super) fn owe(&mut self, answer: &Match, sent: Instant, margin: Duration) {
        let expires = Instant::now() + self.learned.late_limit(margin);
        self.owed.push(Owed {
            answer: answer.clone(),
            sent,
            expires,
        });
    }
}

/// `d` in milliseconds, for the log.
fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// What the link has measured of how late answers come on this connection: the device's own
/// latency, the adapter's bursts and the host's scheduling all in one figure.
#[derive(Debug, Clone, Default)]
pub(crate) struct AnswerTiming {
    /// The adapter's latency timer, where the OS told it.
    pub(crate) latency_timer: Option<Duration>,
    /// The latest answer latencies, from the request's last byte on the wire to the answer's
    /// first byte read.
    recent: VecDeque<Duration>,
}

impl AnswerTiming {
    /// A new connection: nothing measured yet.
    pub(crate) fn new(latency_timer: Option<Duration>) -> Self {
        Self {
            latency_timer,
            recent: VecDeque::new(),
        }
    }

    /// Takes one answer latency.
    pub(crate) fn observe(&mut self, latency: Duration) {
        if self.recent.len() >= RECENT {
            self.recent.pop_front();
        }
        self.recent.push_back(latency);
    }

    /// The largest recent answer latency, if any answer came.
    pub(crate) fn measured(&self) -> Option<Duration> {
        self.recent.iter().max().copied()
    }

    /// The automatic margin for a device whose own margin is `device`: that plus the adapter's
    /// latency timer, or the measured latency with a quarter and a millisecond of headroom,
    /// whichever is more (at most [`MARGIN_CAP`], unless the device's own is more).
    pub(crate) fn margin(&self, device: Duration) -> Duration {
        let known = device + self.latency_timer.unwrap_or_default();
        let measured = self
            .measured()
            .map_or(Duration::ZERO, |m| m + m / 4 + Duration::from_millis(1));
        known.max(measured).min(MARGIN_CAP.max(device))
    }

    /// How long the rest of a started frame may take, beyond its wire time: a burst the adapter
    /// holds back (its latency timer, or the latency measured), at least [`FRAME_GAP_MIN`].
    pub(crate) fn frame_gap(&self) -> Duration {
        FRAME_GAP_MIN
            .max(self.latency_timer.unwrap_or_default() + Duration::from_millis(4))
            .max(self.margin(Duration::ZERO))
    }

    /// How long an exchange keeps listening after its last attempt's window, whose margin was
    /// `margin`: [`GRACE_MARGINS`] automatic margins, at least the frame gap, once answers have
    /// been measured; never less than [`GRACE_MIN`] × 2 / (answers measured + 2) (all of it
    /// before any answer), nor than half of `margin`; never more than [`GRACE_MIN`] or one
    /// automatic margin, whichever is more (a connection whose answers once took 200 ms waits
    /// no longer than that).
    pub(crate) fn grace(&self, margin: Duration) -> Duration {
        let n = self.recent.len() as u32;
        let doubt = GRACE_MIN * 2 / (n + 2);
        let learned = if n == 0 {
            Duration::ZERO
        } else {
            let auto = self.margin(Duration::ZERO);
            self.frame_gap()
                .max(auto * GRACE_MARGINS)
                .min(GRACE_MIN.max(auto))
        };
        doubt.max(learned).max(margin / 2)
    }

    /// How long an owed answer is waited for.
    pub(crate) fn late_limit(&self, margin: Duration) -> Duration {
        LATE_LIMIT_MIN.max(margin * 10)
    }
}

/// An answer still owed to an attempt that went unanswered.
#[derive(Debug, Clone)]
pub(crate) struct Owed {
    /// What the answer looks like.
    pub(crate) answer: Match,
    /// When the request's last byte was on the wire.
    pub(crate) sent: Instant,
    /// When it is given up.
    pub(crate) expires: Instant,
}

/// The answers owed, oldest first.
#[derive(Debug, Default)]
pub(crate) struct OwedAnswers(VecDeque<Owed>);

impl OwedAnswers {
    /// Adds one.
    pub(crate) fn push(&mut self, owed: Owed) {
        if self.0.len() >= OWED_CAP {
            self.0.pop_front();
        }
        self.0.push_back(owed);
    }

    /// Forgets those given up by `now`.
    pub(crate) fn expire(&mut self, now: Instant) {
        self.0.retain(|o| o.expires > now);
    }

    /// Whether an owed answer could be taken for an answer `answer` matches.
    pub(crate) fn overlaps(&self, answer: &Match) -> Option<&Owed> {
        self.0.iter().find(|o| o.answer.overlaps(answer))
    }

    /// If `p` is an owed answer, takes it: the oldest owed answer that `p` is; the ones owed
    /// before it are forgotten (they would have come first). Returns its request's send time.
    pub(crate) fn take(&mut self, p: &Packet) -> Option<Instant> {
        let i = self.0.iter().position(|o| o.answer.accepts(p))?;
        let owed = self.0.drain(..=i).next_back()?;
        Some(owed.sent)
    }

    /// An answer to a later request came: nothing owed before it will come.
    pub(crate) fn clear(&mut self) {
        self.0.clear();
    }

    /// Whether nothing is owed.
    #[cfg(test)]
    pub(crate) fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::servo;

    fn ms(n: u64) -> Duration {
        Duration::from_millis(n)
    }

    #[test]
    fn the_margin_follows_the_adapter_and_the_measured_latency() {
        let mut t = AnswerTiming::new(None);
        let device = Duration::from_micros(1500);
        assert_eq!(t.margin(device), device);
        t.observe(ms(16));
        assert_eq!(t.margin(device), ms(21));
        // A long stall widens it up to the cap only.
        t.observe(ms(2000));
        assert_eq!(t.margin(device), MARGIN_CAP);
        let known = AnswerTiming::new(Some(ms(16)));
        assert_eq!(known.margin(device), device + ms(16));
        assert!(known.frame_gap() >= ms(20));
        // Old latencies roll out.
        for _ in 0..RECENT {
            t.observe(ms(1));
        }
        assert_eq!(t.measured(), Some(ms(1)));
    }

    #[test]
    fn the_grace_is_long_until_answers_are_measured_then_follows_them() {
        let servo = Duration::from_micros(1500);
        let mut t = AnswerTiming::new(None);
        assert_eq!(t.grace(servo), GRACE_MIN);
        // One quick answer does not show that every answer is quick.
        t.observe(Duration::from_micros(400));
        assert_eq!(t.grace(servo), ms(100));
        for _ in 0..3 {
            t.observe(Duration::from_micros(400));
        }
        assert_eq!(t.grace(servo), ms(50));
        // Many do: the frame gap is the floor.
        for _ in 0..20 {
            t.observe(Duration::from_micros(400));
        }
        assert_eq!(t.grace(servo), FRAME_GAP_MIN);
        // A slow host's answers: a few margins.
        t.observe(ms(20));
        let margin = t.margin(Duration::ZERO);
        assert!(margin > ms(20), "{margin:?}");
        assert_eq!(t.grace(servo), margin * GRACE_MARGINS);
        // A long margin given by hand keeps at least half of it.
        assert_eq!(t.grace(ms(600)), ms(300));
        // Answers that once took far longer: never longer than that, or than before any answer.
        t.observe(ms(2000));
        assert_eq!(t.grace(servo), MARGIN_CAP);
        let mut slowish = AnswerTiming::new(None);
        for _ in 0..30 {
            slowish.observe(ms(60));
        }
        assert_eq!(slowish.grace(servo), GRACE_MIN);
        // Behind a known 16 ms adapter: the margins it needs.
        let mut adapter = AnswerTiming::new(Some(ms(16)));
        assert_eq!(adapter.grace(servo), GRACE_MIN);
        for _ in 0..30 {
            adapter.observe(ms(1));
        }
        assert_eq!(adapter.grace(servo), ms(16) * GRACE_MARGINS);
    }

    #[test]
    fn an_owed_answer_is_taken_once_and_earlier_ones_are_forgotten() {
        let now = Instant::now();
        let ping = |id: u8| Match::servo(servo::cmd::PING, &[id]);
        let answer = |id: u8| Packet::servo(servo::Frame::reply(servo::cmd::PING, vec![id]));
        let mut owed = OwedAnswers::default();
        for id in [3, 5, 5] {
            owed.push(Owed {
                answer: ping(id),
                sent: now,
                expires: now + ms(500),
            });
        }
        assert!(owed.overlaps(&ping(5)).is_some());
        assert!(owed.overlaps(&ping(4)).is_none());
        assert_eq!(owed.take(&answer(5)), Some(now));
        // 3 was owed before 5's answer came: it is forgotten.
        assert_eq!(owed.take(&answer(3)), None);
        assert!(owed.take(&answer(5)).is_some());
        assert!(owed.is_empty());
        owed.push(Owed {
            answer: ping(7),
            sent: now,
            expires: now + ms(1),
        });
        owed.expire(now + ms(2));
        assert!(owed.is_empty());
    }
}
