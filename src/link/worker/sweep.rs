//! A sweep: requests sent one after another at the pace of the bus, not of the host. A USB
//! adapter delays only what the host receives (its latency timer), so a servo scan that waited
//! for each answer would cost 255 latency ticks; on the bus itself a ping and its answer fit in
//! about 2 ms. Each answer is taken for its request whenever it reaches the host (the answers
//! name their servo), a damaged frame is narrowed down to the requests it can have come from
//! (the devices answer in order), and what answers none of the sweep's requests is handed back.

use super::Worker;
use crate::link::request::{ExchangeError, ReplySpec, held_up_by};
use crate::link::{Damaged, Sweep, SweepAnswer, SweepReply, wire_time};
use crate::packet::Packet;
use crate::protocol::{Direction, FrameError};
use std::collections::VecDeque;
use std::time::{Duration, Instant};

/// How long before a paced request is due the sweep stops sleeping and polls the port instead:
/// waking from a sleep takes the OS 50-100 µs, which a 0-254 scan would otherwise pay 255 times
/// over (about 20 ms measured, most of what a scan takes beyond the bus's own time). Costs at
/// most this much CPU a request.
const PACE_SPIN: Duration = Duration::from_micros(250);
/// How many frames that answered nothing are kept for the next sweep, at most.
const UNCLAIMED_CAP: usize = 64;

/// Servo frames that answered no request, read between two sweeps (while the worker was idle,
/// or during an exchange they did not answer, late answers to earlier exchanges included), and
/// damaged ones: the next sweep hands them back with its strays and damaged frames, so that an answer that came after its sweep (or
/// its exchange) had ended still counts for its id however soon the worker read it, and however
/// many exchanges came in between (a scan asks ids again one by one).
#[derive(Debug, Default)]
pub(super) struct Unclaimed(VecDeque<Result<Packet, FrameError>>);

impl Unclaimed {
    /// Keeps a frame, or a damaged one (the latest [`UNCLAIMED_CAP`] only).
    pub(super) fn keep(&mut self, frame: Result<Packet, FrameError>) {
        if self.0.len() >= UNCLAIMED_CAP {
            self.0.pop_front();
        }
        self.0.push_back(frame);
    }

    /// All of them, oldest first.
    fn take(&mut self) -> Vec<Result<Packet, FrameError>> {
        self.0.drain(..).collect()
    }
}

/// What came, in the order it came: an answer to request `i`, or a damaged frame when request
/// `sent` was the last one sent (none: before the sweep's first).
enum Seen {
    Answer(usize),
    Damaged {
        error: FrameError,
        sent: Option<usize>,
    },
}

/// A sweep under way.
struct Run {
    /// When each request counts as sent, for its deadlines: when it was asked, or when its
    /// write returned if the host was held up in it ([`Worker::host_was_late_by`]).
    sent: Vec<Instant>,
    /// When each request was asked for (its write begun): its answer's latency is learned
    /// from here, as an exchange's round trip is, so that a write held up never makes the
    /// device seem quicker than it is.
    asked: Vec<Instant>,
    answers: Vec<Option<SweepAnswer>>,
    order: Vec<Seen>,
    strays: Vec<Packet>,
    on_wire: Vec<Duration>,
    margin: Duration,
    /// Whether it listens for what earlier requests still owe (see [`Sweep::listen`]).
    listen: bool,
}

impl Worker {
    /// Runs `sweep`: every request at the bus's pace, then the answers still on their way, until
    /// the line has been quiet for the margin after the last request's window (or every request
    /// has its answer); one that listens, not before the grace an exchange gives has passed
    /// since it began (the grace as its own answers leave it: they are measured too).
    /// The reply says how late the host ran, when it did ([`SweepReply::host_late`]).
    pub(super) fn run_sweep(&mut self, sweep: &Sweep) -> Result<SweepReply, ExchangeError> {
        let (result, late) = self.watching_late(|w| w.sweep_once(sweep));
        result.map(|reply| SweepReply {
            host_late: held_up_by(late),
            ..reply
        })
    }

    fn sweep_once(&mut self, sweep: &Sweep) -> Result<SweepReply, ExchangeError> {
        let started = Instant::now();
        let mut run = self.sweep_run(sweep);
        let answer_time = sweep.device_latency + wire_time(sweep.answer_bytes, self.wire.baud());
        let next = self.send_sweep(sweep, &mut run, answer_time)?;
        let window = match run.sent.last() {
            Some(&last) => {
                last + run.on_wire.last().copied().unwrap_or_default() + answer_time + run.margin
            }
            None => next,
        };
        let mut until = window.max(next);
        if run.listen {
            until = until.max(started + self.timing.learned.grace(run.margin));
        }
        self.sweep_read(sweep, &mut run, until, true)?;
        let unanswered = run.answers.iter().position(Option::is_none);
        if let (Some(i), Some((port, by))) = (unanswered, self.wire.taken_by()) {
            // What is missing may have been taken: no request of it can count as unanswered.
            return Err(ExchangeError::Taken {
                command: sweep.requests[i].command.into(),
                port,
                by,
            });
        }
        Ok(finish(run))
    }

    /// A sweep about to start: nothing sent yet, and what the last exchange left unclaimed
    /// (frames that may answer a request of the last sweep) taken as strays or damage.
    fn sweep_run(&mut self, sweep: &Sweep) -> Run {
        let n = sweep.requests.len();
        let mut run = Run {
            sent: Vec::with_capacity(n),
            asked: Vec::with_capacity(n),
            answers: vec![None; n],
            order: Vec::new(),
            strays: Vec::new(),
            on_wire: Vec::with_capacity(n),
            margin: self.timing.auto_margin(),
            listen: sweep.listen || n == 0,
        };
        for frame in self.unclaimed.take() {
            match frame {
                Ok(p) => run.strays.push(p),
                Err(error) => run.order.push(Seen::Damaged { error, sent: None }),
            }
        }
        run
    }

    /// Sends the sweep's requests one after another, each once the bus is free (the last
    /// answer can have ended, or has been read whole); returns when the last answer can have
    /// ended. A request that waits for no answer is refused before it is sent.
    fn send_sweep(
        &mut self,
        sweep: &Sweep,
        run: &mut Run,
        answer_time: Duration,
    ) -> Result<Instant, ExchangeError> {
        let baud = self.wire.baud();
        let mut next = Instant::now();
        for (i, req) in sweep.requests.iter().enumerate() {
            if !matches!(req.reply, ReplySpec::Required(_)) {
                return Err(ExchangeError::Encode(format!(
                    "a sweep's request {i} (command {}) waits for no answer",
                    req.command
                )));
            }
            let (bytes, packet) = self.session.encode(req)?;
            self.sweep_read(sweep, run, next, false)?;
            self.commands_during_exchange()?;
            let asked = Instant::now();
            self.write(&bytes, packet)?;
            let t = self.sent_at(asked, bytes.len());
            let on_wire = wire_time(bytes.len(), baud);
            run.sent.push(t);
            run.asked.push(asked);
            run.on_wire.push(on_wire);
            // The request's last byte leaves when the bytes written before it have (`sent_until`);
            // the device may then take its latency, and its answer the answer's wire time.
            next = self.wire.sent_until().max(t + on_wire) + answer_time;
        }
        Ok(next)
    }

    /// Reads and sorts what comes until `until`; when `settle`, also for as long as the line
    /// keeps talking (the frame gap after a frame's first bytes, the margin after a whole one).
    /// Returns early when nothing more is awaited: pacing (not `settle`), once the last request
    /// sent has its answer whole (the bus is free: its answer has ended); settling, once every
    /// request of a sweep that does not listen has its answer.
    fn sweep_read(
        &mut self,
        sweep: &Sweep,
        run: &mut Run,
        until: Instant,
        settle: bool,
    ) -> Result<(), ExchangeError> {
        let mut deadline = until;
        let gap = self.timing.learned.frame_gap();
        let mut flushed = false;
        loop {
            self.sweep_sort(sweep, run);
            if self.wire.buffered() == 0 && run.awaits_nothing(settle) {
                return Ok(());
            }
            let now = Instant::now();
            if now >= deadline {
                let n = self.read_some(deadline)?;
                if n > 0 {
                    flushed = false;
                    if settle {
                        deadline = self.settle_deadline(deadline, gap, run.margin);
                    }
                    continue;
                }
                if settle && self.wire.buffered() > 0 && !flushed {
                    self.wire.flush();
                    flushed = true;
                    continue;
                }
                return Ok(());
            }
            // Pacing, the last stretch before the request is due is polled, not slept.
            let wake = if settle {
                deadline
            } else {
                deadline.checked_sub(PACE_SPIN).unwrap_or(deadline)
            };
            let slice = if now < wake {
                wake.min(now + Duration::from_millis(50))
            } else {
                now
            };
            if self.read_some(slice)? == 0 {
                self.woke_after(slice);
            } else if settle {
                flushed = false;
                deadline = self.settle_deadline(deadline, gap, run.margin);
            }
        }
    }

    fn settle_deadline(&self, deadline: Instant, gap: Duration, margin: Duration) -> Instant {
        let rest = if self.wire.buffered() > 0 {
            gap
        } else {
            margin
        };
        deadline.max(Instant::now() + wire_time(8, self.wire.baud()) + rest)
    }

    /// Sorts the decoded frames: an answer to the earliest request sent that it answers and that
    /// has none yet, a late answer owed to an earlier exchange, an echo, or a stray.
    fn sweep_sort(&mut self, sweep: &Sweep, run: &mut Run) {
        while let Some(item) = self.wire.next_frame() {
            self.count(&item);
            match item {
                Ok(p) => {
                    if p.direction != Direction::DeviceToHost {
                        self.events.tap_in(Ok(p), None);
                        continue;
                    }
                    let found = (0..run.sent.len()).find(|&i| {
                        run.answers[i].is_none()
                            && matches!(&sweep.requests[i].reply, ReplySpec::Required(m) if m.accepts(&p))
                    });
                    match found {
                        Some(i) => {
                            let arrived = self.wire.arrived();
                            let answer_wire = wire_time(p.wire.len(), self.wire.baud());
                            let since = |t: Instant| {
                                arrived
                                    .saturating_duration_since(t + run.on_wire[i])
                                    .saturating_sub(answer_wire)
                            };
                            self.timing.observe(since(run.asked[i]));
                            let late = since(run.sent[i]) > run.margin;
                            if late {
                                self.wire.stats.late_answers += 1;
                            }
                            self.events.tap_in(Ok(p.clone()), None);
                            run.answers[i] = Some(SweepAnswer { packet: p, late });
                            run.order.push(Seen::Answer(i));
                        }
                        // Counted for its own earlier request; a stray all the same.
                        None if self.late_answer(&p) => run.strays.push(p),
                        None => {
                            self.events.tap_in(
                                Ok(p.clone()),
                                Some("answers no request of this sweep".into()),
                            );
                            run.strays.push(p);
                        }
                    }
                }
                Err(error) => {
                    self.events.tap_in(Err(error.clone()), None);
                    run.order.push(Seen::Damaged {
                        error,
                        sent: run.sent.len().checked_sub(1),
                    });
                }
            }
        }
    }
}

impl Run {
    /// Whether nothing more is awaited: settling, a sweep that does not listen has every
    /// answer (one that listens settles as the line goes quiet, its answers late ones included);
    /// pacing, the last request sent has its answer.
    fn awaits_nothing(&self, settle: bool) -> bool {
        if settle {
            !self.listen && self.answers.iter().all(Option::is_some)
        } else {
            self.sent
                .len()
                .checked_sub(1)
                .is_some_and(|last| self.answers[last].is_some())
        }
    }
}

/// The sweep's result: each damaged frame with the requests it can have come from or
/// destroyed, those without an answer sent after the last clean answer before it and before it
/// came (and, when no clean answer came before it, maybe an earlier request). The devices
/// answer in order, so it answers one of those before the first clean answer after it; and on a
/// half-duplex bus an answer that collides with a request garbles both: the
/// request went out after the answer's own, before the damaged frame was read, and its device,
/// having heard garbage, stays silent (nothing else would show it was there).
fn finish(run: Run) -> SweepReply {
    let mut garbled = Vec::new();
    for (k, seen) in run.order.iter().enumerate() {
        let Seen::Damaged { error, sent } = seen else {
            continue;
        };
        let after = run.order[..k].iter().rev().find_map(|s| match s {
            Seen::Answer(i) => Some(*i + 1),
            Seen::Damaged { .. } => None,
        });
        let candidates: Vec<usize> = match sent {
            Some(sent) => (after.unwrap_or(0)..=*sent)
                .filter(|&i| i < run.answers.len() && run.answers[i].is_none())
                .collect(),
            None => Vec::new(),
        };
        garbled.push(Damaged {
            error: error.clone(),
            candidates,
            maybe_earlier: after.is_none(),
        });
    }
    SweepReply {
        answers: run.answers,
        garbled,
        strays: run.strays,
        margin: run.margin,
        host_late: None,
    }
}
