//! How a [`Device`] meets a host: wire timing, faults, and the in-process [`SimTransport`].
//!
//! Timing model (8N1, 10 bits a byte, see [`wire_time`]):
//! - a chunk the host writes reaches the device when its last byte has crossed the wire, i.e.
//!   `max(write time, end of the previous chunk) + wire_time(len, baud)`;
//! - the device answers [`Outgoing::after`] later (plus [`Faults::extra_latency`]), once the
//!   device-to-host line is free;
//! - the host has the reply when its last byte has crossed the wire: `wire_time(reply len)` later.
//!   A reply is handed over whole at that instant.
//!
//! An [`Outgoing`] sent at another baud rate than the host's arrives as pseudo-random garbage of
//! about `len × host_baud / device_baud` bytes (at least one).

use super::line::{Line, Seen, garble_overlap};
use super::{Device, Outgoing};
use crate::link::{LinkError, Transport, wire_time};
use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// A device shared between a runner and whoever pokes at its state (tests, the GUI).
pub type SharedDevice = Arc<Mutex<dyn Device>>;

/// How often a runner calls [`Device::tick`].
pub const TICK: Duration = Duration::from_millis(3);
/// How far back [`Wire::pump`] catches up on the ticks of a device nobody pumped meanwhile.
const TICK_CATCH_UP: Duration = Duration::from_secs(10);

/// Faults applied to every frame the device sends. `Default` is no fault at all.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Faults {
    /// Probability (0..=1) that a frame is lost.
    pub drop: f64,
    /// Probability (0..=1) that a frame that is not lost has one bit flipped in its last byte.
    ///
    /// The last byte is the checksum in all three protocols, so the frame keeps its framing and
    /// fails its checksum, exactly as a host sees any single-bit error in the data or checksum.
    pub corrupt: f64,
    /// Added to the device's own answer latency.
    pub extra_latency: Duration,
    /// The device answers nothing (a dead device on a live port).
    pub silent: bool,
    /// The device boots for this long after each open of its port (a board whose USB adapter
    /// toggles DTR/RTS on open): it hears nothing and says nothing meanwhile. In process and
    /// in lockstep each open starts it again; on a plain pty, which sees no open, it runs from
    /// the simulator's start only.
    pub boot: Duration,
    /// Seed of the fault dice, for repeatable runs.
    pub seed: u64,
    /// How the line itself misbehaves: a USB adapter's latency timer, a split reply, a slow
    /// host, an echoing or half-duplex bus, a vanishing port ([`Line`]).
    pub line: Line,
}

impl Faults {
    /// Checks the probabilities are in 0..=1.
    pub fn check(&self) -> Result<(), String> {
        for (name, p) in [("drop", self.drop), ("corrupt", self.corrupt)] {
            if !(0.0..=1.0).contains(&p) {
                return Err(format!("{name} probability {p} is not between 0 and 1"));
            }
        }
        self.line.check()
    }
}

/// Locks a shared device, taking it over even if a previous holder panicked.
pub fn lock(device: &SharedDevice) -> MutexGuard<'_, dyn Device + 'static> {
    device.lock().unwrap_or_else(|e| e.into_inner())
}

struct Inbound {
    at: Instant,
    bytes: Vec<u8>,
    baud: u32,
}

/// A frame on its way to the host, byte by byte as a UART delivers it.
struct Delivery {
    /// When its first byte starts on the wire.
    start: Instant,
    /// One byte's time on the wire.
    byte: Duration,
    bytes: Vec<u8>,
    /// When the host sees each byte (the adapter, the host: [`Line`]).
    seen: Seen,
    /// The host's own request read back (a one-wire bus): not the device's frame.
    echo: bool,
}

impl Delivery {
    /// When its last byte has arrived.
    fn end(&self) -> Instant {
        self.start + self.byte * self.bytes.len() as u32
    }

    /// When byte `i` is seen by the host.
    fn seen_at(&self, i: usize) -> Instant {
        self.seen.at(i, self.start + self.byte * (i as u32 + 1))
    }

    /// When the host sees its last byte (`None` for an empty frame).
    fn last_seen(&self) -> Option<Instant> {
        let n = self.bytes.len();
        (n > 0).then(|| self.seen_at(n - 1))
    }

    /// How many of its bytes the host has seen by `now`.
    fn arrived(&self, now: Instant) -> usize {
        // Seen times rise with the byte index.
        (0..self.bytes.len())
            .find(|&i| self.seen_at(i) > now)
            .unwrap_or(self.bytes.len())
    }
}

/// After a frame's first byte (delivered at once, so that a host sees an answer start), the rest
/// arrives in chunks of at most this long, as from a USB adapter.
const DELIVERY_CHUNK: Duration = Duration::from_millis(1);

/// The two directions of a simulated wire with a device at the far end. Shared by
/// [`SimTransport`] and [`super::pty::PtyServer`]; it never sleeps.
pub(crate) struct Wire {
    device: SharedDevice,
    faults: Faults,
    rng: fastrand::Rng,
    baud: u32,
    inbound: VecDeque<Inbound>,
    outbound: VecDeque<Delivery>,
    /// Bytes of the front delivery already handed to the host.
    taken: usize,
    rx_free: Instant,
    /// The device's transmissions not yet over, as (start, end) in wire order: a frame goes out
    /// in the first gap long enough for it, as a UART sends whenever its line is idle (see
    /// [`Self::tx_slot`]).
    tx_busy: VecDeque<(Instant, Instant)>,
    next_tick: Instant,
    /// The adapter's clock starts with the wire.
    epoch: Instant,
    /// Bytes the host has sent.
    host_bytes: u64,
    /// The port has vanished ([`Line::vanish_after_bytes`]).
    vanished: bool,
    /// When the host saw the last byte [`Self::take_due`] handed over (behind an adapter's latency
    /// timer, later than it crossed the wire).
    last_seen: Option<Instant>,
    /// The host's writes are stamped with when the host made them (in process, in lockstep),
    /// rather than with when the simulator read them (a plain pty): only then is a request known
    /// to overlap a reply on a half-duplex line (see [`Wire::host_times_uncertain`]).
    host_times_exact: bool,
    /// When the device boots ([`Faults::boot`]), from the last open to the end of its boot:
    /// what reaches it then is lost and it says nothing. Only that window: what the host wrote
    /// before the open was heard before it, however late the simulator takes the two (seen
    /// under two CPU-bound loops: a broadcast write taken together with the next run's open
    /// was dropped as if heard while booting, though the boot took 0 ms).
    booting: (Instant, Instant),
}

impl Wire {
    pub(crate) fn new(device: SharedDevice, baud: u32, faults: Faults) -> Self {
        let now = Instant::now();
        let booting = (now, now + faults.boot);
        Self {
            device,
            rng: fastrand::Rng::with_seed(faults.seed),
            faults,
            baud: baud.max(1),
            inbound: VecDeque::new(),
            outbound: VecDeque::new(),
            taken: 0,
            rx_free: now,
            tx_busy: VecDeque::new(),
            next_tick: now,
            epoch: now,
            host_bytes: 0,
            vanished: false,
            last_seen: None,
            host_times_exact: true,
            booting,
        }
    }

    /// Whether the device is booting at `at` (see [`Self::booting`]).
    fn is_booting(&self, at: Instant) -> bool {
        let (from, until) = self.booting;
        at >= from && at < until
    }

    /// The host opened the port at `at`: a device that boots on open starts again.
    pub(crate) fn opened(&mut self, at: Instant) {
        self.booting = (at, at + self.faults.boot);
    }

    /// The host's writes are known only when the simulator reads them (a plain pty served to
    /// another process): the operating system hands them over up to a scheduling delay late, a
    /// millisecond and more on a loaded machine, longer than a servo's reply takes on the wire.
    /// A request and a reply are then not said to collide on a half-duplex line: a request that
    /// merely reached the simulator late would garble a reply it never met (a host retrying
    /// 2 ms after a ping whose reply had ended at 1.6 ms). Collisions between devices (two
    /// servos on one id) are the simulator's own timing and stay.
    pub(crate) fn host_times_uncertain(&mut self) {
        self.host_times_exact = false;
    }

    /// Whether the port has vanished after the bytes [`Line::vanish_after_bytes`] allowed.
    pub(crate) fn vanished(&self) -> bool {
        self.vanished
    }

    fn line(&self) -> &Line {
        &self.faults.line
    }

    /// Queues a frame for the host in order of its start on the wire, and draws when the host
    /// sees its bytes: never before the frame before it, nor after the frames behind it (frames
    /// are never seen out of order, also when one goes out in a gap before frames scheduled
    /// earlier, see [`Self::tx_slot`]).
    fn deliver(&mut self, start: Instant, byte: Duration, bytes: Vec<u8>, echo: bool) {
        let at = self
            .outbound
            .iter()
            .rposition(|o| o.start <= start)
            .map_or(0, |i| i + 1);
        // The front may be partly handed over already: nothing goes before it then.
        let at = if self.taken > 0 { at.max(1) } else { at };
        let seen = if self.faults.line.delays() {
            let before = match at.checked_sub(1) {
                Some(i) => self.outbound[i].last_seen(),
                None => self.last_seen,
            };
            let not_before = before.unwrap_or(self.epoch);
            self.faults.line.seen(self.epoch, not_before, &mut self.rng)
        } else {
            Seen::at_once()
        };
        let d = Delivery {
            start,
            byte,
            bytes,
            seen,
            echo,
        };
        if let Some(last) = d.last_seen() {
            for behind in self.outbound.iter_mut().skip(at) {
                behind.seen.raise_not_before(last);
            }
        }
        self.outbound.insert(at, d);
    }

    pub(crate) fn baud(&self) -> u32 {
        self.baud
    }

    /// The host switches its port to `baud` at `now`. Bytes still crossing the wire are cut
    /// off, as a UART's would be: what has not arrived goes out at the new rate.
    pub(crate) fn set_baud(&mut self, baud: u32, now: Instant) {
        self.baud = baud.max(1);
        for chunk in self.inbound.iter_mut().filter(|c| c.at > now) {
            chunk.baud = self.baud;
        }
        // The host's UART reads at the new rate from now on: what the device still sends at
        // another rate arrives as garbage (what has crossed already is the adapter's).
        let byte = wire_time(1, self.baud);
        for d in self
            .outbound
            .iter_mut()
            .filter(|d| !d.echo && d.byte != byte)
        {
            for (i, b) in d.bytes.iter_mut().enumerate() {
                if d.start + d.byte * (i as u32 + 1) > now {
                    *b = self.rng.u8(..);
                }
            }
        }
    }

    pub(crate) fn device(&self) -> SharedDevice {
        self.device.clone()
    }

    /// The host has written `bytes` at `now`.
    pub(crate) fn host_wrote(&mut self, bytes: &[u8], now: Instant) {
        if bytes.is_empty() {
            return;
        }
        self.host_bytes += bytes.len() as u64;
        if self
            .line()
            .vanish_after_bytes
            .is_some_and(|n| self.host_bytes >= n)
        {
            self.vanished = true;
        }
        let start = now.max(self.rx_free);
        let at = start + wire_time(bytes.len(), self.baud);
        self.rx_free = at;
        let mut bytes = bytes.to_vec();
        if self.line().half_duplex && self.host_times_exact {
            // A reply still on the wire and this request garble each other.
            let byte = wire_time(1, self.baud);
            let rng = &mut self.rng;
            for d in self.outbound.iter_mut().filter(|d| !d.echo) {
                if garble_overlap(&mut d.bytes, d.start, d.byte, (start, at), rng) {
                    garble_overlap(&mut bytes, start, byte, (d.start, d.end()), rng);
                }
            }
        }
        if self.line().echo {
            self.deliver(start, wire_time(1, self.baud), bytes.clone(), true);
        }
        self.inbound.push_back(Inbound {
            at,
            bytes,
            baud: self.baud,
        });
    }

    /// Feeds the device what has arrived by `now`, and ticks it at each of its ticks due by
    /// then, in time order with what it hears: a device has a processor of its own, so what it
    /// does on its own happens at its own ticks, never when the simulator's thread got to run
    /// (a thread run late ticked once, at the late instant, and a report the device queued for
    /// its next tick went out that late: a Tuya MCU's re-report of a data point it was sent,
    /// seen 6 s late after the test process was stopped for 6 s).
    pub(crate) fn pump(&mut self, now: Instant) {
        // A host that did not call in for ages (an idle in-process simulator) is not owed every
        // tick since; ten seconds of them, at most.
        self.next_tick = self
            .next_tick
            .max(now.checked_sub(TICK_CATCH_UP).unwrap_or(now));
        loop {
            let input_at = self.inbound.front().map(|i| i.at).filter(|&at| at <= now);
            let tick_at = (self.next_tick <= now).then_some(self.next_tick);
            let input_first = match (input_at, tick_at) {
                (None, None) => break,
                (Some(a), Some(t)) => a <= t,
                (a, _) => a.is_some(),
            };
            if input_first {
                let Some(input) = self.inbound.pop_front() else {
                    break;
                };
                if self.is_booting(input.at) {
                    continue;
                }
                let out = lock(&self.device).receive(&input.bytes, input.baud, input.at);
                self.schedule(out, input.at);
            } else {
                let at = self.next_tick;
                let out = lock(&self.device).tick(at);
                self.schedule(out, at);
                self.next_tick = at + TICK;
            }
        }
    }

    fn schedule(&mut self, out: Vec<Outgoing>, cause: Instant) {
        for o in out {
            if self.faults.silent || o.bytes.is_empty() || self.is_booting(cause) {
                continue;
            }
            if self.faults.drop > 0.0 && self.rng.f64() < self.faults.drop {
                continue;
            }
            let sent_baud = o.baud.unwrap_or(self.baud).max(1);
            let duration = wire_time(o.bytes.len(), sent_baud);
            let mut bytes = if sent_baud == self.baud {
                o.bytes
            } else {
                let n = (o.bytes.len() as u64 * u64::from(self.baud) / u64::from(sent_baud)).max(1)
                    as usize;
                (0..n).map(|_| self.rng.u8(..)).collect()
            };
            if self.faults.corrupt > 0.0
                && self.rng.f64() < self.faults.corrupt
                && let Some(last) = bytes.last_mut()
            {
                *last ^= 1 << self.rng.u8(0..8);
            }
            let start = self.tx_slot(cause, cause + o.after + self.faults.extra_latency, duration);
            let byte = duration / bytes.len().max(1) as u32;
            if self.faults.line.half_duplex && self.host_times_exact {
                // A request the host has already started on the wire collides with this reply.
                let rng = &mut self.rng;
                for i in self.inbound.iter_mut() {
                    let from = i.at - wire_time(i.bytes.len(), i.baud);
                    if garble_overlap(&mut bytes, start, byte, (from, i.at), rng) {
                        let i_byte = wire_time(1, i.baud);
                        garble_overlap(&mut i.bytes, from, i_byte, (start, start + duration), rng);
                    }
                }
            }
            self.deliver(start, byte, bytes, false);
        }
    }

    /// When a frame of `duration` that the device decided to send at `cause`, not before
    /// `earliest`, starts on the wire: the first gap from `earliest` between the transmissions
    /// already scheduled that holds it, not after the last of them. A frame the firmware sends
    /// later (a slow MCU's next report, a servo's answer once its move is done) does not hold the
    /// line before its time: an answer due now goes out in the gap before it (before, a
    /// heartbeat's answer waited 6.6 s behind reports scheduled 100-150 ms apart).
    fn tx_slot(&mut self, cause: Instant, earliest: Instant, duration: Duration) -> Instant {
        // The device decides in time order: what ended before this decision is history.
        while self.tx_busy.front().is_some_and(|&(_, end)| end <= cause) {
            self.tx_busy.pop_front();
        }
        let mut start = earliest;
        let mut at = self.tx_busy.len();
        for (i, &(from, until)) in self.tx_busy.iter().enumerate() {
            if start + duration <= from {
                at = i;
                break;
            }
            start = start.max(until);
        }
        self.tx_busy.insert(at, (start, start + duration));
        start
    }

    /// Copies bytes that have reached the host by `now` into `buf`.
    pub(crate) fn take_due(&mut self, now: Instant, buf: &mut [u8]) -> usize {
        self.take_due_upto(now, buf, usize::MAX)
    }

    /// [`Self::take_due`], from the front frame alone: a batch of bytes that were due together
    /// (a simulator catching up after a stall must not hand over frames due seconds apart as
    /// one batch, due when its first byte was).
    pub(crate) fn take_frame_due(&mut self, now: Instant, buf: &mut [u8]) -> usize {
        self.take_due_upto(now, buf, 1)
    }

    /// Copies bytes that have reached the host by `now` into `buf`, from at most `frames`
    /// frames (the front one counts, however much of it was taken before).
    fn take_due_upto(&mut self, now: Instant, buf: &mut [u8], frames: usize) -> usize {
        let mut n = 0;
        let mut left = frames;
        while n < buf.len() && left > 0 {
            let Some(front) = self.outbound.front() else {
                break;
            };
            let due = front.arrived(now);
            if due <= self.taken {
                break;
            }
            let k = (due - self.taken).min(buf.len() - n);
            buf[n..n + k].copy_from_slice(&front.bytes[self.taken..self.taken + k]);
            self.last_seen = Some(front.seen_at(self.taken + k - 1));
            n += k;
            self.taken += k;
            if self.taken == front.bytes.len() {
                self.outbound.pop_front();
                self.taken = 0;
                left -= 1;
            }
        }
        n
    }

    /// When the host saw the last byte [`Self::take_due`] handed over (`None` before any).
    pub(crate) fn last_seen(&self) -> Option<Instant> {
        self.last_seen
    }

    /// Drops the bytes that have reached the host and not been read.
    pub(crate) fn clear_arrived(&mut self, now: Instant) {
        while let Some(front) = self.outbound.front() {
            let due = front.arrived(now);
            if due == front.bytes.len() {
                self.outbound.pop_front();
                self.taken = 0;
            } else {
                self.taken = self.taken.max(due);
                break;
            }
        }
    }

    /// When the next byte on its way to the host arrives there.
    pub(crate) fn next_byte_due(&self) -> Option<Instant> {
        self.outbound
            .front()
            .map(|d| d.start + d.byte * (self.taken as u32 + 1))
    }

    /// The earliest instant the device side may still send the host a byte: when the host's next
    /// chunk has reached the device (its answer comes later), or the next byte on its way back.
    pub(crate) fn next_due(&self) -> Option<Instant> {
        let inbound = self.inbound.front().map(|i| i.at);
        match (inbound, self.next_byte_due()) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    /// When something happens next: a chunk reaches the device, a frame reaches the host, or
    /// the device is due a tick.
    pub(crate) fn next_event(&self) -> Instant {
        let mut t = self.next_tick;
        if let Some(i) = self.inbound.front() {
            t = t.min(i.at);
        }
        if let Some(d) = self.outbound.front() {
            // The next chunk of bytes: the first byte alone, then up to DELIVERY_CHUNK's worth;
            // behind an adapter or a late host, whatever is seen next.
            let per_chunk = if self.taken == 0 || self.line().delays() {
                1
            } else {
                (DELIVERY_CHUNK.as_nanos() / d.byte.as_nanos().max(1)).max(1) as usize
            };
            let upto = (self.taken + per_chunk).min(d.bytes.len());
            t = t.min(d.seen_at(upto.max(1) - 1));
        }
        t
    }
}

/// Sleeps until `t`: a plain sleep for most of it, then a short spin for the last ~100 µs.
pub(crate) fn sleep_until(t: Instant) {
    const SPIN: Duration = Duration::from_micros(100);
    let now = Instant::now();
    if t <= now {
        return;
    }
    let left = t - now;
    if left > SPIN {
        std::thread::sleep(left - SPIN);
    }
    while Instant::now() < t {
        std::hint::spin_loop();
    }
}

/// Makes a simulated port vanish (as an unplugged adapter) from another thread.
#[derive(Debug, Clone, Default)]
pub struct VanishHandle(Arc<AtomicBool>);

impl VanishHandle {
    /// Every later call on the port fails with [`LinkError::Disconnected`].
    pub fn vanish(&self) {
        self.0.store(true, Ordering::SeqCst);
    }

    /// Whether the port has vanished.
    pub fn is_vanished(&self) -> bool {
        self.0.load(Ordering::SeqCst)
    }
}

/// A [`Transport`] to a simulated device in the same process: no port, no thread. The device
/// is fed and ticked (every [`TICK`]) while the host calls in, mostly while it waits in `read`;
/// its state catches up with the clock on the next call.
pub struct SimTransport {
    wire: Wire,
    name: String,
    vanished: VanishHandle,
}

impl SimTransport {
    /// A transport to `device`, starting at `baud`; `describe()` returns `description`
    /// (e.g. `simulated window cleaner`).
    pub fn new(
        device: SharedDevice,
        baud: u32,
        faults: Faults,
        description: impl Into<String>,
    ) -> Self {
        Self {
            wire: Wire::new(device, baud, faults),
            name: description.into(),
            vanished: VanishHandle::default(),
        }
    }

    /// A transport to a new simulator of `kind`, at its UART's baud rate, described as
    /// [`super::SimKind::describe`] says.
    pub fn of_kind(
        kind: super::SimKind,
        opts: &super::SimOptions,
        faults: Faults,
    ) -> Result<Self, String> {
        faults.check()?;
        // A servo bus is one half-duplex line.
        let mut faults = faults;
        faults.line.half_duplex |= kind == super::SimKind::ServoBus;
        let device = super::build(kind, opts)?;
        let baud = opts.baud.unwrap_or_else(|| kind.default_baud());
        Ok(Self::new(device, baud, faults, kind.describe()))
    }

    /// The simulated device, to read or change its state.
    pub fn device(&self) -> SharedDevice {
        self.wire.device()
    }

    /// The same transport, vanishing when `handle` says so (a fixture's adapter unplugged:
    /// every transport opened on it shares the handle).
    pub fn with_vanish(mut self, handle: VanishHandle) -> Self {
        self.vanished = handle;
        self
    }

    /// A handle that makes this port vanish, usable from another thread.
    pub fn vanish_handle(&self) -> VanishHandle {
        self.vanished.clone()
    }

    /// Makes the port vanish now.
    pub fn vanish(&self) {
        self.vanished.vanish();
    }

    fn alive(&self) -> Result<(), LinkError> {
        if self.wire.vanished() {
            self.vanished.vanish();
        }
        if self.vanished.is_vanished() {
            Err(LinkError::Disconnected(format!("{} vanished", self.name)))
        } else {
            Ok(())
        }
    }
}

impl std::fmt::Debug for SimTransport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SimTransport")
            .field("name", &self.name)
            .field("baud", &self.wire.baud())
            .finish_non_exhaustive()
    }
}

impl Transport for SimTransport {
    fn write(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        self.alive()?;
        let now = Instant::now();
        self.wire.pump(now);
        self.wire.host_wrote(bytes, now);
        Ok(())
    }

    fn read(&mut self, buf: &mut [u8], deadline: Instant) -> Result<usize, LinkError> {
        loop {
            self.alive()?;
            let now = Instant::now();
            self.wire.pump(now);
            let n = self.wire.take_due(now, buf);
            if n > 0 || buf.is_empty() || now >= deadline {
                return Ok(n);
            }
            sleep_until(self.wire.next_event().min(deadline));
        }
    }

    fn set_baud(&mut self, baud: u32) -> Result<(), LinkError> {
        self.alive()?;
        if baud == 0 {
            return Err(LinkError::Setting("baud rate 0".into()));
        }
        self.wire.set_baud(baud, Instant::now());
        Ok(())
    }

    fn baud(&self) -> u32 {
        self.wire.baud()
    }

    fn clear_input(&mut self) -> Result<(), LinkError> {
        self.alive()?;
        let now = Instant::now();
        self.wire.pump(now);
        self.wire.clear_arrived(now);
        Ok(())
    }

    fn describe(&self) -> String {
        self.name.clone()
    }

    fn arrived_at(&self) -> Option<Instant> {
        self.wire.last_seen()
    }
}

#[cfg(test)]
mod tests;
