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
//! been recorded. The bytes still travel through the real pty, both ways, but neither end
//! waits on it: the device hears the host's bytes from its stamped writes, and the host reads
//! the device's bytes from what the simulator recorded as written ([`State::to_host`]); the
//! copies that crossed the pty are drained by a thread at each side and compared with what was
//! sent ([`super::crossing`]). On Linux a read or poll of a pty waits for the kernel's worker
//! to hand over bytes in flight (`n_tty_read` and `n_tty_poll` call `tty_buffer_flush_work`),
//! and on a machine loaded with CPU-bound work that worker was seen to run up to 18 s late: a
//! host reading its port that way had no answer from a device that had answered at once (seen:
//! "read 631 of 10008 written", 18 s past the read's deadline, every test process at once). A
//! clear of the input is taken in step too ([`HostAction::Clear`]).
//!
//! The device's clock never runs ahead of the host's next stamp: between two calls of a host's
//! port, the host's next action can still be stamped as early as the last call's return (a
//! write is stamped so), so the simulator advances only to there ([`Lockstep::horizon`]); during
//! a call (a read waiting for an answer) it runs free. Otherwise a simulator thread that runs
//! while the host's thread is held up (a loaded machine; a whole process stopped for seconds)
//! would let the device speak on its own at a time after a request it has not yet heard, and
//! its answer would queue behind that (seen: a Tuya answer 6.2 s late under two CPU-bound
//! loops, the same after a `kill -STOP` of the test process for 6 s).
//!
//! Used by the tests: [`PtyServer::start_lockstep`](super::PtyServer::start_lockstep) serves a
//! device this way, and the server's own opener
//! ([`PtyServer::opener`](super::PtyServer::opener), or the
//! [`PortOpener`](crate::link::PortOpener) it gives the window and the command line) opens its
//! path through a [`LockstepPort`]. A client that opens the path any other way (another
//! process) sees a plain pty that never answers: the `sim` command and `botbench bench` use
//! plain servers.

use super::crossing::Way;
use crate::link::serial::SerialTransport;
use crate::link::{LinkError, Opener, Transport};
use std::collections::VecDeque;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// What the host did to its port.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum HostAction {
    /// Wrote these bytes. The device hears them from here, at the write's stamp, not from the
    /// pty: what it hears must not wait on the pty handing the host's bytes over to the
    /// simulator's side (seen under load: a write whose bytes the simulator's side had still
    /// not read 10 s later, the device waiting for them all that time).
    Wrote(Vec<u8>),
    /// Switched to this baud rate.
    Baud(u32),
    /// Opened the port: a device that boots on open ([`super::Faults::boot`]) starts again.
    Opened,
    /// Dropped what had arrived ([`Transport::clear_input`]): the device side drops what had
    /// reached the host by the stamp, and says how many bytes it had written by then
    /// ([`State::cleared`]), so that the host drops exactly those, however late either thread
    /// runs.
    Clear,
}

/// The most bytes the simulator's side holds for the host, sent and not yet read: what a pty
/// holds (its buffers' limit, 64 KiB). What a device sends beyond it, with nobody reading, is
/// lost, as it is on a real port whose buffer is full.
const TO_HOST_LIMIT: usize = 64 * 1024;

/// The state a host and the simulator serving it share.
#[derive(Debug)]
pub struct Lockstep {
    state: Mutex<State>,
    /// Signalled when the host does something the simulator waits for (an action, a call
    /// begun, a port closed), with [`State::generation`] counting up.
    changed: Condvar,
    /// Signalled when the device side does something a host's read waits for (bytes written,
    /// a clear taken, a crossing found changed, serving ended), with
    /// [`State::device_generation`] counting up.
    device_changed: Condvar,
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
    /// Bytes the host has read (or cleared), in total.
    read_total: u64,
    /// The bytes the simulator has written that the host has not read yet: byte `read_total`
    /// first, at most [`TO_HOST_LIMIT`]. The host reads these, not the pty's copy.
    to_host: VecDeque<u8>,
    /// The earliest instant at which the device side may still send a byte: a chunk of the
    /// host's still crossing to the device, or the next byte of a frame on its way back.
    pub(crate) next_due: Option<Instant>,
    /// The simulator still serves.
    serving: bool,
    /// The server is gone (dropped): its pty's path may be another server's now.
    closed: bool,
    /// Clears the host has asked for, and the simulator has taken, in total.
    clears_asked: u64,
    clears_done: u64,
    /// The simulator's `written_total` when it took the last clear: the host drops every byte
    /// up to it.
    clear_mark: u64,
    /// The host's bytes that crossed the pty, compared with what it wrote.
    pub(crate) to_device: super::crossing::Crossing,
    /// The device's bytes that crossed the pty, compared with what the simulator wrote.
    pub(crate) to_host_crossing: super::crossing::Crossing,
    /// Each open host port between two calls, and when its last call returned: its next action
    /// is stamped no earlier (a port in a call, or none open, holds the simulator back nowhere).
    between_calls: Vec<(u64, Instant)>,
    /// The number the next host port opened gets.
    next_port: u64,
    /// Counts the changes [`Lockstep::changed`] signals.
    generation: u64,
    /// Counts the changes [`Lockstep::device_changed`] signals.
    device_generation: u64,
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
                to_host: VecDeque::new(),
                next_due: None,
                serving: true,
                closed: false,
                clears_asked: 0,
                clears_done: 0,
                clear_mark: 0,
                to_device: super::crossing::Crossing::new(Way::ToDevice),
                to_host_crossing: super::crossing::Crossing::new(Way::ToHost),
                between_calls: Vec::new(),
                next_port: 0,
                generation: 0,
                device_generation: 0,
            }),
            changed: Condvar::new(),
            device_changed: Condvar::new(),
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
    /// Returns the stamp given.
    fn host(&self, action: HostAction, at: Option<Instant>) -> Instant {
        let mut s = self.lock();
        let at = at.unwrap_or_else(Instant::now);
        let at = s.actions.back().map_or(at, |(last, _)| at.max(*last));
        s.actions.push_back((at, action));
        s.generation += 1;
        drop(s);
        self.changed.notify_all();
        at
    }

    /// How far the device's clock may run at `now`: to `now`, or to the earliest instant an
    /// open host port between two calls may still stamp its next action (see the module doc).
    pub(crate) fn horizon(s: &State, now: Instant) -> Instant {
        s.between_calls
            .iter()
            .map(|&(_, returned)| returned)
            .fold(now, Instant::min)
    }

    /// Host port `port` begins a call (`Some(returned)`: ended one at `returned`; `None`: is
    /// closed, or begins one). A call begun frees the simulator's clock, so it is signalled.
    fn host_call(&self, port: u64, returned: Option<Instant>) {
        let mut s = self.lock();
        s.between_calls.retain(|&(p, _)| p != port);
        if let Some(at) = returned {
            s.between_calls.push((port, at));
            return;
        }
        s.generation += 1;
        drop(s);
        self.changed.notify_all();
    }

    /// The simulator waits up to `timeout` for the host to change something after it saw
    /// `generation` (returns at once if it has already).
    pub(crate) fn wait_for_host(&self, generation: u64, timeout: Duration) {
        let s = self.lock();
        if s.generation != generation {
            return;
        }
        let _unused = self
            .changed
            .wait_timeout(s, timeout)
            .unwrap_or_else(|e| e.into_inner());
    }

    /// The device side changed something a host's read waits for: the reads waiting are woken.
    pub(crate) fn signal_host(&self) {
        self.lock().device_generation += 1;
        self.device_changed.notify_all();
    }

    /// A host's read waits until `until` at most for the device side to change something after
    /// it saw `generation` (returns at once if it has already).
    fn wait_for_device(&self, generation: u64, until: Instant) {
        let s = self.lock();
        let wait = until.saturating_duration_since(Instant::now());
        if s.device_generation != generation || wait.is_zero() {
            return;
        }
        let _unused = self
            .device_changed
            .wait_timeout(s, wait)
            .unwrap_or_else(|e| e.into_inner());
    }

    /// How many of the bytes after the first `taken` the host may read by `deadline`: those of
    /// the simulator's batches due by then (a batch whose first byte was due later is not yet
    /// there for a host that reads by `deadline`, however late the host's thread runs); and when
    /// the host saw the last of them (`None`: none).
    fn due_by(s: &State, taken: u64, deadline: Instant) -> (u64, Option<Instant>) {
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
            .any(|(at, a)| matches!(a, HostAction::Wrote(_) | HostAction::Clear) && *at <= deadline)
            || s.next_due.is_some_and(|t| t <= deadline)
            || s.written.iter().any(|(_, due)| *due <= deadline)
    }
}

impl Lockstep {
    /// What the host is owed by `deadline`, for a diagnosis.
    fn explain(&self, deadline: Instant) -> String {
        let s = self.lock();
        let now = Instant::now();
        let rel = |t: Instant| {
            if t >= now {
                format!("+{:?}", t - now)
            } else {
                format!("-{:?}", now - t)
            }
        };
        format!(
            "deadline {}, read {} of {} written, batches {:?}, actions {:?}, next due {:?}, \
             serving {}",
            rel(deadline),
            s.read_total,
            s.written_total,
            s.written
                .iter()
                .map(|(t, d)| (*t, rel(*d)))
                .collect::<Vec<_>>(),
            s.actions
                .iter()
                .map(|(t, a)| (rel(*t), a))
                .collect::<Vec<_>>(),
            s.next_due.map(rel),
            s.serving
        )
    }
}

impl State {
    /// What the host has changed so far: see [`Lockstep::wait_for_host`].
    pub(crate) fn generation(&self) -> u64 {
        self.generation
    }

    /// The simulator writes `bytes` (one frame), the first of them due at `due`, the last seen
    /// by the host at `seen`. Returns how many of them the host's side holds: those beyond
    /// [`TO_HOST_LIMIT`] unread bytes are lost (nobody reads them), and only the ones held go
    /// across the pty.
    pub(crate) fn wrote(&mut self, bytes: &[u8], due: Instant, seen: Instant) -> usize {
        let n = bytes
            .len()
            .min(TO_HOST_LIMIT.saturating_sub(self.to_host.len()));
        if n > 0 {
            self.to_host.extend(&bytes[..n]);
            self.written_total += n as u64;
            self.written.push_back((self.written_total, due));
            self.seen.push_back(seen);
        }
        n
    }

    /// The first change the pty made to bytes on their way, either way, in words.
    pub(crate) fn crossing_changed(&self) -> Option<&str> {
        self.to_device
            .changed()
            .or_else(|| self.to_host_crossing.changed())
    }

    /// The host reads (or drops) `n` of the bytes held for it, at most as many as there are.
    fn take_to_host(&mut self, n: usize) -> std::collections::vec_deque::Drain<'_, u8> {
        let n = n.min(self.to_host.len());
        self.read_total += n as u64;
        self.to_host.drain(..n)
    }

    /// The simulator has taken the host's clear: every byte it has written so far is the host's
    /// to drop (those that had not reached the host by the clear's stamp it has dropped itself).
    pub(crate) fn cleared(&mut self) {
        self.clears_done += 1;
        self.clear_mark = self.written_total;
    }
}

/// Held by the simulator while it serves: dropped (also by a panic), the host stops waiting.
pub(crate) struct Serving<'a>(&'a Lockstep);

impl Drop for Serving<'_> {
    fn drop(&mut self) {
        self.0.lock().serving = false;
        self.0.signal_host();
    }
}

impl Lockstep {
    /// The server is gone: its path is no longer reopened through it.
    pub(crate) fn close(&self) {
        self.lock().closed = true;
        self.changed.notify_all();
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
        lockstep.host(HostAction::Opened, None);
        lockstep.host(HostAction::Baud(baud), None);
        let id = {
            let mut s = lockstep.lock();
            s.next_port += 1;
            s.next_port
        };
        let last_return = Instant::now();
        lockstep.host_call(id, Some(last_return));
        Ok(Box::new(LockstepPort {
            port,
            id,
            lockstep: lockstep.clone(),
            last_return,
            arrived: None,
            written: None,
            clearing: None,
            discard: 0,
        }) as Box<dyn Transport>)
    })
}

/// How long a read past its deadline that waits for the simulator blocks before it looks
/// again.
const CATCH_UP_POLL: Duration = Duration::from_millis(1);
/// How long past its deadline a read waits at most for the simulator to catch up: far beyond a
/// loaded machine's scheduling delays (the simulator's thread only has to run), so that a
/// read never blocks for ever (seen: `tuya init`'s link, closing, read for over 5 minutes).
const CATCH_UP_LIMIT: Duration = Duration::from_secs(10);

/// The host's side of a pty served in lockstep: the real serial port, with each write and baud
/// switch stamped for the simulator, and reads that take the device's bytes from what the
/// simulator recorded ([`State::to_host`]; the pty's copy is drained and compared), that time
/// out only once nothing more is due, and that hand the host only what was due by their
/// deadline. A host thread that runs late (a loaded machine) finds bytes that came after the
/// deadline it reads by; they are left for its next read, so that it sees what a punctual host
/// would: the timing a test is about is the simulator's, never the scheduler's. Once the
/// simulator has stopped (its side of the pty closed), reads go to the port itself, which
/// says it is gone.
///
/// A write is stamped with the instant the port's previous call returned: a host takes the time
/// its answer deadline starts from after that call and before the write, so the device never
/// hears the request later than the host reckons (a host thread preempted in between would
/// otherwise make the device late). A baud switch is stamped when it is made.
#[derive(Debug)]
pub struct LockstepPort {
    port: SerialTransport,
    /// This port among those opened on the same pty ([`State::between_calls`]).
    id: u64,
    lockstep: Arc<Lockstep>,
    last_return: Instant,
    /// When the last byte the last read handed over had arrived ([`Transport::arrived_at`]).
    arrived: Option<Instant>,
    /// The stamp of the last write: when the device hears it from ([`Transport::written_at`]).
    written: Option<Instant>,
    /// The clear asked for (its number) that the simulator has not taken yet: nothing is
    /// handed over until it has said which bytes the clear drops.
    clearing: Option<u64>,
    /// Bytes the last clear drops that have not been dropped yet.
    discard: u64,
}

impl Drop for LockstepPort {
    fn drop(&mut self) {
        // Bytes not read stay for the next port opened, as they stay in the pty.
        self.lockstep.host_call(self.id, None);
    }
}

impl LockstepPort {
    fn returns<T>(&mut self, result: T) -> T {
        self.last_return = Instant::now();
        self.lockstep.host_call(self.id, Some(self.last_return));
        result
    }

    /// A call that may wait for the simulator begins: its clock runs free until it returns.
    fn begins(&self) {
        self.lockstep.host_call(self.id, None);
    }

    fn read_in_step(&mut self, buf: &mut [u8], deadline: Instant) -> Result<usize, LinkError> {
        loop {
            let (generation, serving) = {
                let s = self.lockstep.lock();
                if let Some(changed) = s.crossing_changed() {
                    return Err(LinkError::Disconnected(changed.to_string()));
                }
                (s.device_generation, s.serving)
            };
            self.drop_cleared();
            let clearing = self.is_clearing();
            let n = if clearing {
                0
            } else {
                self.hand_over(buf, deadline)
            };
            if n > 0 || buf.is_empty() {
                return Ok(n);
            }
            if !serving {
                // The simulator's side of the pty is closed: the port says so (a vanished
                // port's read fails), or has nothing more.
                return self.port.read(buf, deadline);
            }
            let now = Instant::now();
            let until = if now < deadline {
                deadline
            } else {
                // Past CATCH_UP_LIMIT the host reads as from a real port: nothing came in
                // time. A simulator that never catches up (or bytes the accounting lost) must
                // not hold the host's thread for ever (a link whose read never returned could
                // not be closed).
                let owed = clearing || self.lockstep.owes(deadline);
                if owed && now >= deadline + CATCH_UP_LIMIT {
                    // A simulator that never caught up: what the accounting held, to find why.
                    eprintln!(
                        "lockstep: a read still owed bytes {CATCH_UP_LIMIT:?} past its deadline \
                         (clearing {:?}, discard {}): {}",
                        self.clearing,
                        self.discard,
                        self.lockstep.explain(deadline)
                    );
                }
                if !owed || now >= deadline + CATCH_UP_LIMIT {
                    return Ok(0);
                }
                now + CATCH_UP_POLL
            };
            self.lockstep.wait_for_device(generation, until);
        }
    }

    /// Whether a clear still has bytes to drop, or has not been taken by the simulator yet.
    fn is_clearing(&self) -> bool {
        self.clearing.is_some() || self.discard > 0
    }

    /// Drops the bytes the last clear drops, once the simulator has said which; when the
    /// simulator no longer serves, everything held (nothing more comes).
    fn drop_cleared(&mut self) {
        let mut s = self.lockstep.lock();
        if let Some(asked) = self.clearing {
            if !s.serving {
                self.clearing = None;
                self.discard = 0;
                let all = s.to_host.len();
                s.take_to_host(all);
                return;
            }
            if s.clears_done < asked {
                return;
            }
            self.clearing = None;
            self.discard = s.clear_mark.saturating_sub(s.read_total);
        }
        let k = usize::try_from(self.discard).unwrap_or(usize::MAX);
        let dropped = s.take_to_host(k).len();
        self.discard -= dropped as u64;
    }

    /// Hands the host the bytes held for it that were due by `deadline` (as many as `buf`
    /// takes).
    fn hand_over(&mut self, buf: &mut [u8], deadline: Instant) -> usize {
        let mut s = self.lockstep.lock();
        if s.to_host.is_empty() {
            return 0;
        }
        let (due, last_seen) = Lockstep::due_by(&s, s.read_total, deadline);
        let n = usize::try_from(due).unwrap_or(usize::MAX).min(buf.len());
        let mut n_taken = 0;
        for (slot, byte) in buf.iter_mut().zip(s.take_to_host(n)) {
            *slot = byte;
            n_taken += 1;
        }
        if n_taken > 0 {
            self.arrived = last_seen;
        }
        n_taken
    }
}

impl Transport for LockstepPort {
    fn write(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        if !bytes.is_empty() {
            let at = self
                .lockstep
                .host(HostAction::Wrote(bytes.to_vec()), Some(self.last_return));
            self.written = Some(at);
        }
        self.begins();
        let result = self.port.write(bytes);
        if result.is_ok() {
            self.lockstep.lock().to_device.sent(bytes);
        }
        self.returns(result)
    }

    fn read(&mut self, buf: &mut [u8], deadline: Instant) -> Result<usize, LinkError> {
        self.begins();
        let result = self.read_in_step(buf, deadline);
        self.returns(result)
    }

    fn set_baud(&mut self, baud: u32) -> Result<(), LinkError> {
        self.lockstep.host(HostAction::Baud(baud), None);
        self.begins();
        let result = self.port.set_baud(baud);
        self.returns(result)
    }

    fn baud(&self) -> u32 {
        self.port.baud()
    }

    fn set_lines(&mut self, dtr: Option<bool>, rts: Option<bool>) -> Result<(), LinkError> {
        self.port.set_lines(dtr, rts)
    }

    /// In step: what had reached the host by now is dropped, whether the simulator's thread
    /// has written it to the pty yet or not (a starved simulator writes it late), and nothing
    /// that reaches the host later is (the bytes stay in the pty, counted). The simulator takes
    /// the clear at its stamp and says how many of its bytes it covers; the reads that follow
    /// drop those first. With the simulator gone, the pty is flushed.
    fn clear_input(&mut self) -> Result<(), LinkError> {
        let serving = {
            let mut s = self.lockstep.lock();
            if s.serving {
                let at = Instant::now();
                let at = s.actions.back().map_or(at, |(last, _)| at.max(*last));
                s.actions.push_back((at, HostAction::Clear));
                s.clears_asked += 1;
                self.clearing = Some(s.clears_asked);
            }
            s.serving
        };
        // The clear is an action the simulator takes: signalled.
        self.begins();
        if serving {
            return self.returns(Ok(()));
        }
        self.clearing = None;
        self.discard = 0;
        let result = self.port.clear_input();
        {
            let mut s = self.lockstep.lock();
            let all = s.to_host.len();
            s.take_to_host(all);
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

    fn written_at(&self) -> Option<Instant> {
        self.written
    }
}

#[cfg(test)]
mod tests {
    use super::super::PtyServer;
    use super::super::runner::Faults;
    use super::super::tuya_mcu::{TuyaConfig, TuyaMcu, dpid};
    use std::sync::{Arc, Mutex};
    use std::time::{Duration, Instant};

    /// A host held up between two calls of its port (a loaded machine; a stopped process) while
    /// the simulator runs: a device that speaks on its own (a report every 20 ms) must not speak
    /// during that hold-up before the request the host makes when it runs again, or its answer
    /// queues behind reports the host could not have caused (before: the heartbeat's answer was
    /// due after the hold-up, as if the device had thought for 400 ms).
    #[test]
    fn a_device_does_not_run_ahead_of_a_host_held_up_between_two_calls() {
        let mcu = TuyaMcu::new(TuyaConfig {
            baud: Some(115_200),
            report_every: Some((dpid::BATTERY, Duration::from_millis(20))),
            ..TuyaConfig::default()
        });
        let server =
            PtyServer::start_lockstep(Arc::new(Mutex::new(mcu)), Faults::default()).expect("pty");
        let mut port = (server.opener(115_200))().expect("opens");
        let mut buf = [0u8; 4096];
        port.read(&mut buf, Instant::now()).expect("reads");
        let held_from = Instant::now();
        std::thread::sleep(Duration::from_millis(400));
        // The heartbeat, written once the host runs again: stamped at its last call's return.
        port.write(&[0x55, 0xAA, 0x00, 0x00, 0x00, 0x00, 0xFF])
            .expect("writes");
        // What a punctual host would have had 100 ms after the hold-up began.
        let by = held_from + Duration::from_millis(100);
        let mut got = Vec::new();
        loop {
            let n = port.read(&mut buf, by).expect("reads");
            if n == 0 {
                break;
            }
            got.extend_from_slice(&buf[..n]);
        }
        let answer = [0x55, 0xAA, 0x03, 0x00, 0x00, 0x01];
        assert!(
            got.windows(answer.len()).any(|w| w == answer),
            "no heartbeat answer due within 100 ms of the request's stamp: {got:02x?}"
        );
    }
}
