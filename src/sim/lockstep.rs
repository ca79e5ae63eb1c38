//! A pseudo-terminal served in lockstep with a host in the same process, so that what a test
//! sees does not depend on how fast threads are scheduled.
//!
//! Through a plain [`PtyServer`](super::PtyServer) the simulator learns of the host's bytes and
//! baud switches when its thread gets to read them: on a loaded machine that is late, so answers
//! miss the host's deadlines, and a baud switch made right after a write can reach the simulator
//! first (the write is then heard at the new rate). In lockstep the host's port, a
//! [`LockstepPort`] around the real [`SerialTransport`], stamps each write and baud switch with
//! the instant it was made, in order, and the simulator takes them with those stamps, as the
//! in-process [`SimTransport`](super::SimTransport) does; and a read whose deadline has passed
//! waits until the simulator has caught up with that deadline and every byte due by then has
//! crossed the pty. The bytes still travel through the real pty and serial port code.
//!
//! Used by the tests: [`PtyServer::start_lockstep`](super::PtyServer::start_lockstep) serves a
//! device this way, and the server's own opener
//! ([`PtyServer::opener`](super::PtyServer::opener), or the
//! [`PortOpener`](crate::link::PortOpener) it gives the window and the command line) opens its
//! path through a [`LockstepPort`]. A client that opens the path any other way (another
//! process) sees a plain pty that never answers: the `sim` command and `botbench bench` use
//! plain servers.

use crate::link::serial::SerialTransport;
use crate::link::{LinkError, Opener, Transport};
use std::collections::VecDeque;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// What the host did to its port.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum HostAction {
    /// Wrote this many bytes.
    Wrote(usize),
    /// Switched to this baud rate.
    Baud(u32),
}

/// The state a host and the simulator serving it share.
#[derive(Debug)]
pub struct Lockstep {
    state: Mutex<State>,
}

#[derive(Debug)]
pub(crate) struct State {
    /// What the host did, stamped and in order, not yet taken by the simulator.
    pub(crate) actions: VecDeque<(Instant, HostAction)>,
    /// Batches of bytes the simulator has written to the pty: the running total after each, and
    /// when the batch's first byte was due at the host.
    written: VecDeque<(u64, Instant)>,
    /// When the host saw the last byte of each batch in `written` (behind an adapter's latency
    /// timer, later than it crossed), in the same order.
    seen: VecDeque<Instant>,
    written_total: u64,
    /// Bytes the host has read (or cleared) from the pty, in total.
    read_total: u64,
    /// The earliest instant at which the device side may still send a byte: a chunk of the
    /// host's still crossing to the device, or the next byte of a frame on its way back.
    pub(crate) next_due: Option<Instant>,
    /// The simulator still serves.
    serving: bool,
    /// The server is gone (dropped): its pty's path may be another server's now.
    closed: bool,
}

impl Lockstep {
    pub(crate) fn new() -> Arc<Self> {
        Arc::new(Self {
            state: Mutex::new(State {
                actions: VecDeque::new(),
                written: VecDeque::new(),
                seen: VecDeque::new(),
                written_total: 0,
                read_total: 0,
                next_due: None,
                serving: true,
                closed: false,
            }),
        })
    }

    /// The simulator serves until the returned guard is dropped.
    pub(crate) fn serving(&self) -> Serving<'_> {
        Serving(self)
    }

    pub(crate) fn lock(&self) -> MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The host does `action` at `at` (now when `None`, taken under the lock so that the
    /// simulator, which takes its own time under the lock too, cannot have gone past it). Stamps
    /// never go back.
    fn host(&self, action: HostAction, at: Option<Instant>) {
        let mut s = self.lock();
        let at = at.unwrap_or_else(Instant::now);
        let at = s.actions.back().map_or(at, |(last, _)| at.max(*last));
        s.actions.push_back((at, action));
    }

    /// How many of the bytes after the first `taken` the host may read by `deadline`: those of
    /// the simulator's batches due by then (a batch whose first byte was due later is not yet
    /// there for a host that reads by `deadline`, however late the host's thread runs); and when
    /// the host saw the last of them (`None`: none).
    fn due_by(&self, taken: u64, deadline: Instant) -> (u64, Option<Instant>) {
        let s = self.lock();
        let (mut upto, mut last) = (taken, None);
        for (&(total, due), &seen) in s.written.iter().zip(&s.seen) {
            if total <= taken {
                continue;
            }
            if due > deadline {
                break;
            }
            last = Some(seen);
            upto = total;
        }
        (upto - taken, last)
    }

    /// Whether the device side still owes the host a byte due by `deadline`: the simulator has not
    /// caught up with it yet, or has written such a byte that the host has not read.
    fn owes(&self, deadline: Instant) -> bool {
        let mut s = self.lock();
        if !s.serving {
            return false;
        }
        let read = s.read_total;
        while s.written.front().is_some_and(|(total, _)| *total <= read) {
            s.written.pop_front();
            s.seen.pop_front();
        }
        s.actions
            .iter()
            .any(|(at, a)| matches!(a, HostAction::Wrote(_)) && *at <= deadline)
            || s.next_due.is_some_and(|t| t <= deadline)
            || s.written.iter().any(|(_, due)| *due <= deadline)
    }
}

impl State {
    /// The simulator has written `n` bytes, the first of them due at `due`, the last seen by the
    /// host at `seen`.
    pub(crate) fn wrote(&mut self, n: usize, due: Instant, seen: Instant) {
        if n > 0 {
            self.written_total += n as u64;
            self.written.push_back((self.written_total, due));
            self.seen.push_back(seen);
        }
    }

    /// Of the bytes last recorded as written, `n` were dropped (nobody made room for them).
    pub(crate) fn dropped(&mut self, n: usize) {
        self.written_total = self.written_total.saturating_sub(n as u64);
        if let Some(last) = self.written.back_mut() {
            last.0 = self.written_total;
        }
    }
}

/// Held by the simulator while it serves: dropped (also by a panic), the host stops waiting.
pub(crate) struct Serving<'a>(&'a Lockstep);

impl Drop for Serving<'_> {
    fn drop(&mut self) {
        self.0.lock().serving = false;
    }
}

impl Lockstep {
    /// The server is gone: its path is no longer reopened through it.
    pub(crate) fn close(&self) {
        self.lock().closed = true;
    }
}

/// An opener for `path` at `baud` through a [`LockstepPort`] in step with `lockstep`, the
/// simulator serving `path`.
///
/// Reopening (after a loss) fails once that simulator's server is gone: the system gives a freed
/// pty's path to the next one opened, and a link that outlived its simulator must not reach
/// another test's.
pub(crate) fn opener(lockstep: Arc<Lockstep>, path: String, baud: u32) -> Opener {
    Box::new(move || {
        if lockstep.lock().closed {
            return Err(LinkError::Open {
                path: path.clone(),
                reason: "the simulator that served it has stopped".into(),
            });
        }
        let port = SerialTransport::open(&path, baud)?;
        lockstep.host(HostAction::Baud(baud), None);
        Ok(Box::new(LockstepPort {
            port,
            lockstep: lockstep.clone(),
            last_return: Instant::now(),
            held: VecDeque::new(),
            arrived: None,
        }) as Box<dyn Transport>)
    })
}

/// How long a read that waits for the simulator blocks before it looks again.
const CATCH_UP_POLL: Duration = Duration::from_millis(1);
/// How long past its deadline a read waits at most for the simulator to catch up: far beyond a
/// loaded machine's scheduling delays (the simulator's thread only has to run), so that a
/// read never blocks for ever (seen: `tuya init`'s link, closing, read for over 5 minutes).
const CATCH_UP_LIMIT: Duration = Duration::from_secs(10);

/// The host's side of a pty served in lockstep: the real serial port, with each write and baud
/// switch stamped for the simulator, and reads that time out only once nothing more is due, and
/// that hand the host only what was due by their deadline. A host thread that runs late (a
/// loaded machine) finds in the pty bytes that came after the deadline it reads by; they are
/// held for its next read, so that it sees what a punctual host would: the timing a test is
/// about is the simulator's, never the scheduler's.
///
/// A write is stamped with the instant the port's previous call returned: a host takes the time
/// its answer deadline starts from after that call and before the write, so the device never
/// hears the request later than the host reckons (a host thread preempted in between would
/// otherwise make the device late). A baud switch is stamped when it is made.
#[derive(Debug)]
pub struct LockstepPort {
    port: SerialTransport,
    lockstep: Arc<Lockstep>,
    last_return: Instant,
    /// Bytes read from the pty that were due after the deadline of the read that found them.
    held: VecDeque<u8>,
    /// When the last byte the last read handed over had arrived ([`Transport::arrived_at`]).
    arrived: Option<Instant>,
}

impl LockstepPort {
    fn returns<T>(&mut self, result: T) -> T {
        self.last_return = Instant::now();
        result
    }

    fn read_in_step(&mut self, buf: &mut [u8], deadline: Instant) -> Result<usize, LinkError> {
        let mut until = deadline;
        let mut chunk = [0u8; 4096];
        loop {
            let n = self.hand_over(buf, deadline);
            if n > 0 || buf.is_empty() {
                return Ok(n);
            }
            let got = self.port.read(&mut chunk, until)?;
            if got > 0 {
                self.held.extend(&chunk[..got]);
                continue;
            }
            let now = Instant::now();
            if now < deadline {
                continue;
            }
            // Past CATCH_UP_LIMIT the host reads as from a real port: nothing came in time. A
            // simulator that never catches up (or bytes the accounting lost) must not hold the
            // host's thread for ever (a link whose read never returned could not be closed).
            if !self.lockstep.owes(deadline) || now >= deadline + CATCH_UP_LIMIT {
                return Ok(0);
            }
            until = now + CATCH_UP_POLL;
        }
    }

    /// Hands the host the held bytes that were due by `deadline` (as many as `buf` takes).
    fn hand_over(&mut self, buf: &mut [u8], deadline: Instant) -> usize {
        if self.held.is_empty() {
            return 0;
        }
        let taken = self.lockstep.lock().read_total;
        let (due, last_seen) = self.lockstep.due_by(taken, deadline);
        let due = usize::try_from(due).unwrap_or(usize::MAX);
        let n = due.min(self.held.len()).min(buf.len());
        self.arrived = last_seen;
        for (slot, byte) in buf.iter_mut().zip(self.held.drain(..n)) {
            *slot = byte;
        }
        self.lockstep.lock().read_total += n as u64;
        n
    }
}

impl Transport for LockstepPort {
    fn write(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        if !bytes.is_empty() {
            self.lockstep
                .host(HostAction::Wrote(bytes.len()), Some(self.last_return));
        }
        let result = self.port.write(bytes);
        self.returns(result)
    }

    fn read(&mut self, buf: &mut [u8], deadline: Instant) -> Result<usize, LinkError> {
        let result = self.read_in_step(buf, deadline);
        self.returns(result)
    }

    fn set_baud(&mut self, baud: u32) -> Result<(), LinkError> {
        self.lockstep.host(HostAction::Baud(baud), None);
        let result = self.port.set_baud(baud);
        self.returns(result)
    }

    fn baud(&self) -> u32 {
        self.port.baud()
    }

    fn clear_input(&mut self) -> Result<(), LinkError> {
        self.held.clear();
        let result = self.port.clear_input();
        {
            let mut s = self.lockstep.lock();
            s.read_total = s.written_total;
        }
        self.returns(result)
    }

    fn describe(&self) -> String {
        self.port.describe()
    }

    fn taken(&self) -> u64 {
        self.port.taken()
    }

    fn others_reading(&mut self) -> Vec<crate::system::Holder> {
        self.port.others_reading()
    }

    fn check(&mut self) -> Result<(), LinkError> {
        let result = self.port.check();
        self.returns(result)
    }

    fn arrived_at(&self) -> Option<Instant> {
        self.arrived
    }
}
