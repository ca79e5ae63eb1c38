//! Waiting for an answer: frames are read until one answers the request (or a burst of them
//! ends) or the deadline passes. A frame that answers something else is never taken for it;
//! once a frame has started, its rest is awaited for the frame gap (an adapter's bursts), and at
//! the deadline what has arrived meanwhile is still read.

use super::Worker;
use crate::link::request::{ExchangeError, Match};
use crate::link::{LinkEvent, wire_time};
use crate::packet::{Header, Packet};
use crate::protocol::FrameError;
use std::time::{Duration, Instant};

/// Extra time allowed between the bytes of one frame (scheduler jitter on a loaded machine).
const INTER_BYTE_SLACK: Duration = Duration::from_millis(5);
/// The longest one read blocks while waiting (commands are looked at between reads).
const READ_SLICE: Duration = Duration::from_millis(50);
/// How long a wait that is no burst of reports may last at most: in effect, unbounded.
const NO_CAP: Duration = Duration::from_secs(86_400);

/// What a wait for an answer saw.
pub(super) struct Waited {
    pub(super) outcome: Outcome,
    /// The last frame error.
    pub(super) frame_err: Option<FrameError>,
    /// The last frame that answered something else: its command, and its servo id.
    pub(super) mismatch: Option<(u8, Option<u8>)>,
}

/// Whether an answer came.
pub(super) enum Outcome {
    /// The answer (one frame, or the frames of a burst), and when its first and last frames
    /// were read.
    Answered {
        packets: Vec<Packet>,
        first: Instant,
        last: Instant,
    },
    /// Nothing that answers the request.
    Nothing,
}

/// How a burst of answering frames ends.
pub(super) enum BurstEnd {
    /// When the line has been quiet this long.
    Quiet(Duration),
    /// When each of these Tuya data points has been reported, or at `until` at the latest;
    /// while reports of data points not yet heard keep coming (a slow MCU that reports 100-150
    /// ms apart), each moves the end to `gap` after it, never past `hard`.
    Reported {
        ids: Vec<u8>,
        until: Instant,
        gap: Duration,
        hard: Instant,
    },
}

impl BurstEnd {
    /// Whether `got` completes the burst.
    fn complete(&self, got: &[Packet]) -> bool {
        match self {
            BurstEnd::Quiet(_) => false,
            BurstEnd::Reported { ids, .. } => {
                let reported = crate::link::session::tuya::reported_ids(got);
                ids.iter().all(|id| reported.contains(id))
            }
        }
    }

    /// Whether `p` reports an awaited data point that `got` has not.
    fn brings_news(&self, got: &[Packet], p: &Packet) -> bool {
        let BurstEnd::Reported { ids, .. } = self else {
            return false;
        };
        let before = crate::link::session::tuya::reported_ids(got);
        crate::link::session::tuya::reported_ids(std::slice::from_ref(p))
            .iter()
            .any(|id| ids.contains(id) && !before.contains(id))
    }
}

/// A wait under way.
struct Wait<'m> {
    /// What an answer looks like.
    each: &'m Match,
    /// How a burst ends, when the answer is one.
    burst: Option<BurstEnd>,
    /// The first deadline: the answer's first byte is due by then.
    first_deadline: Instant,
    /// The deadline now (later once bytes came).
    deadline: Instant,
    /// A burst of reports ends by this time whatever comes (a chatty MCU is never quiet).
    cap: Instant,
    /// The answering frames so far, and when the first and last were read.
    got: Vec<Packet>,
    first_at: Option<Instant>,
    last_at: Instant,
    frame_err: Option<FrameError>,
    mismatch: Option<(u8, Option<u8>)>,
    /// A partial frame was given up on since bytes last came.
    flushed: bool,
    /// How far the last read that found nothing looked.
    looked_to: Option<Instant>,
    /// How long the rest of a started frame may take (the frame gap, as the wait began).
    gap: Duration,
}

impl Wait<'_> {
    /// What the wait saw, as it ends now.
    fn end(self) -> Waited {
        let outcome = match self.first_at {
            None => Outcome::Nothing,
            Some(first) => Outcome::Answered {
                packets: self.got,
                first,
                last: self.last_at,
            },
        };
        Waited {
            outcome,
            frame_err: self.frame_err,
            mismatch: self.mismatch,
        }
    }
}

impl Worker {
    /// Reads until the answer (or the end of a burst) or the deadline. Returns what came, the
    /// last frame error and the last mismatching command seen (with the servo id it came from).
    pub(super) fn wait_for(
        &mut self,
        each: &Match,
        burst: Option<BurstEnd>,
        first_deadline: Instant,
    ) -> Result<Waited, ExchangeError> {
        let cap = match &burst {
            Some(BurstEnd::Reported { until, .. }) => *until,
            _ => first_deadline + NO_CAP,
        };
        let mut w = Wait {
            each,
            burst,
            first_deadline,
            deadline: first_deadline,
            cap,
            got: Vec::new(),
            first_at: None,
            last_at: first_deadline,
            frame_err: None,
            mismatch: None,
            flushed: false,
            looked_to: None,
            gap: self.timing.learned.frame_gap(),
        };
        loop {
            if self.sort_arrived(&mut w)? {
                return Ok(w.end());
            }
            let now = Instant::now();
            if now >= w.deadline {
                if self.look_again(&mut w)? {
                    continue;
                }
                return Ok(w.end());
            }
            self.commands_during_exchange()?;
            let slice = w.deadline.min(now + READ_SLICE);
            if self.read_some(slice)? > 0 {
                self.bytes_came(&mut w);
            } else {
                w.looked_to = Some(slice);
                self.woke_after(slice);
            }
        }
    }

    /// Sorts every frame decoded so far; returns whether the answer is complete.
    fn sort_arrived(&mut self, w: &mut Wait<'_>) -> Result<bool, ExchangeError> {
        while let Some(item) = self.next_frame() {
            self.count(&item);
            match item {
                Ok(p) => {
                    if self.late_answer(&p) {
                        self.keep_unclaimed(Ok(&p));
                    } else if w.each.accepts(&p) {
                        if self.took_answer(w, p) {
                            return Ok(true);
                        }
                    } else {
                        self.took_other(w, p)?;
                    }
                }
                Err(e) => {
                    self.keep_unclaimed(Err(&e));
                    self.events.tap_in(Err(e.clone()), None);
                    w.frame_err = Some(e);
                }
            }
        }
        Ok(false)
    }

    /// `p` answers the request: kept; returns whether the answer is complete (one frame, or the
    /// burst's last), else the deadline moves to the burst's.
    fn took_answer(&mut self, w: &mut Wait<'_>, p: Packet) -> bool {
        if self.session.in_order() {
            // Nothing owed before this answer will come now.
            self.timing.owed.clear();
        }
        self.events.tap_in(Ok(p.clone()), None);
        if self.session.answer_is_report(&p) {
            self.events.emit(LinkEvent::Report(p.clone()));
        }
        let now = Instant::now();
        let arrived = self.wire.arrived();
        w.first_at.get_or_insert(arrived);
        w.last_at = arrived;
        if let Some(end @ BurstEnd::Reported { gap, hard, .. }) = &w.burst
            && end.brings_news(&w.got, &p)
        {
            w.cap = w.cap.max((now + *gap).min(*hard));
        }
        w.got.push(p);
        match &w.burst {
            Some(BurstEnd::Quiet(quiet)) => w.deadline = now + *quiet,
            Some(end @ BurstEnd::Reported { .. }) if !end.complete(&w.got) => w.deadline = w.cap,
            _ => {
                // One frame, or the last report of the burst: no frame error or mismatch is
                // said of an answer that came.
                w.frame_err = None;
                w.mismatch = None;
                return true;
            }
        }
        false
    }

    /// `p` answers no request of this exchange: passed on as the session sorts it; an answer to
    /// something else is remembered, for a request that gets only such frames.
    fn took_other(&mut self, w: &mut Wait<'_>, p: Packet) -> Result<(), ExchangeError> {
        self.keep_unclaimed(Ok(&p));
        self.events.tap_in(Ok(p.clone()), None);
        let unasked = self.session.unasked(&p);
        if unasked.answers_other() {
            let from = matches!(p.header, Header::Servo)
                .then(|| p.payload.first().copied())
                .flatten();
            w.mismatch = Some((p.command, from));
        }
        self.take_unasked(p, unasked)
    }

    /// At the deadline: a thread held up past it (a loaded machine) looks once more before it
    /// gives up, since what arrived by the deadline is the answer however late it is read; a
    /// partial frame held is given up on. Returns whether to go on waiting.
    fn look_again(&mut self, w: &mut Wait<'_>) -> Result<bool, ExchangeError> {
        if w.looked_to.is_none_or(|t| t < w.deadline) {
            w.looked_to = Some(w.deadline);
            if self.read_some(w.deadline)? > 0 {
                self.bytes_came(w);
            }
            return Ok(true);
        }
        if self.wire.buffered() > 0 && !w.flushed {
            self.wire.flush();
            w.flushed = true;
            return Ok(true);
        }
        Ok(false)
    }

    /// Bytes came: a frame under way gets its rest, however the adapter splits it (the frame
    /// gap); a line that keeps talking, a little more; a burst of reports never past its cap.
    fn bytes_came(&mut self, w: &mut Wait<'_>) {
        w.flushed = false;
        let rest = if self.wire.buffered() > 0 {
            w.gap
        } else {
            INTER_BYTE_SLACK
        };
        let rest = w
            .deadline
            .max(Instant::now() + wire_time(8, self.wire.baud()) + rest);
        w.deadline = rest.min(w.cap.max(w.first_deadline));
    }
}
