//! Recording: a [`Capture`] owns a named writer thread (`botbench-capture`) fed through a
//! bounded channel; [`Capture::wrap`] puts a recording tap around every transport an opener
//! opens, so the link's worker is unchanged and every byte it writes or reads is recorded as the
//! call sent or returned it.
//!
//! Memory is bounded: at most [`QUEUE_CHUNKS`] chunks wait for the disk (each at most one read
//! buffer, 4 KiB). When the disk stalls and the queue is full, a chunk is dropped and counted:
//! the next chunk written carries the count (`epb_dropcount`), and [`Capture::dropped`] tells
//! the total. The writer flushes whenever the queue is empty, so a crash loses at most what
//! was queued.

use super::CaptureError;
use super::format::{self, CaptureInfo};
use crate::link::{LinkError, Opener, Transport};
use crate::protocol::Direction;
use crossbeam_channel::{Receiver, Sender, TrySendError};
use std::io::Write;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Instant, SystemTime, UNIX_EPOCH};

/// How many chunks may wait for the disk.
pub const QUEUE_CHUNKS: usize = 4096;

enum Record {
    Chunk {
        at_us: u64,
        direction: Direction,
        bytes: Vec<u8>,
        dropped_before: u64,
    },
    Baud(u32),
    Stop,
}

/// Counters of a capture, readable while it records.
#[derive(Debug, Default)]
struct Counters {
    /// Bytes in the file so far.
    file_bytes: AtomicU64,
    /// Chunks written.
    chunks: AtomicU64,
    /// Chunks dropped because the queue was full.
    dropped: AtomicU64,
    /// Drops not yet reported in a written chunk.
    pending_drops: AtomicU64,
    /// The longest the queue has been.
    peak_queue: AtomicUsize,
}

struct Inner {
    tx: Sender<Record>,
    counters: Arc<Counters>,
    stopped: AtomicBool,
    thread: Mutex<Option<JoinHandle<Result<(), CaptureError>>>>,
    result: Mutex<Option<Result<(), CaptureError>>>,
    /// The clock: microseconds since the epoch at `base`, then monotonic.
    base_us: u64,
    base: Instant,
    path: String,
}

impl Drop for Inner {
    fn drop(&mut self) {
        // A failure is kept for `stop`; when the last handle goes, nobody is left to tell.
        let _ = self.finish();
    }
}

impl Inner {
    fn finish(&self) -> Result<(), CaptureError> {
        if !self.stopped.swap(true, Ordering::SeqCst) {
            // Waits for room: everything queued before is written first.
            let _ = self.tx.send(Record::Stop);
        }
        let thread = self.thread.lock().unwrap_or_else(|e| e.into_inner()).take();
        let mut result = self.result.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(t) = thread {
            *result = Some(
                t.join()
                    .unwrap_or_else(|_| Err(CaptureError::Write("the writer panicked".into()))),
            );
        }
        result.clone().unwrap_or(Ok(()))
    }
}

/// A capture being recorded to a pcapng file (see [`super::format`]). Cheap to clone; the file
/// is complete when [`Capture::stop`] returns, or when the last clone is dropped.
#[derive(Clone)]
pub struct Capture(Arc<Inner>);

impl std::fmt::Debug for Capture {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Capture")
            .field("path", &self.0.path)
            .field("file_bytes", &self.file_bytes())
            .finish_non_exhaustive()
    }
}

/// What a finished capture holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CaptureSummary {
    /// Chunks written.
    pub chunks: u64,
    /// Chunks lost because the disk could not keep up.
    pub dropped: u64,
    /// The file's size in bytes.
    pub file_bytes: u64,
}

impl Capture {
    /// Creates (or truncates) the file at `path` and writes its header now, so that a path
    /// that cannot be written is an immediate error.
    /// A path that exists and is not a regular file (a named pipe, whose opening would wait for
    /// a reader; a device; a folder) is refused before it is opened.
    pub fn create(path: &std::path::Path, info: CaptureInfo) -> Result<Self, CaptureError> {
        super::format::regular_or_absent(path)?;
        let file = std::fs::File::create(path).map_err(|e| CaptureError::Open {
            path: path.display().to_string(),
            reason: e.to_string(),
        })?;
        Self::to_writer(file, info, path.display().to_string())
    }

    /// Records into any writer (a benchmark's sink, a test's stalled disk), through a 64 KiB
    /// buffer flushed whenever the queue runs empty; `name` is for messages.
    pub fn to_writer(
        out: impl Write + Send + 'static,
        info: CaptureInfo,
        name: String,
    ) -> Result<Self, CaptureError> {
        let counting = Counting {
            inner: std::io::BufWriter::with_capacity(64 * 1024, out),
            count: 0,
        };
        let mut w = format::start(counting, &info)?;
        format::write_interface(&mut w, &info, info.baud)?;
        w.get_mut().flush().map_err(CaptureError::write)?;
        let counters = Arc::new(Counters::default());
        counters
            .file_bytes
            .store(w.get_ref().count, Ordering::Relaxed);
        let (tx, rx) = crossbeam_channel::bounded(QUEUE_CHUNKS);
        let thread_counters = counters.clone();
        let thread = std::thread::Builder::new()
            .name("botbench-capture".into())
            .spawn(move || write_loop(w, &info, &rx, &thread_counters))
            .map_err(|e| CaptureError::Write(format!("cannot start the writer thread: {e}")))?;
        let now = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map(|d| d.as_micros() as u64)
            .unwrap_or(0);
        Ok(Self(Arc::new(Inner {
            tx,
            counters,
            stopped: AtomicBool::new(false),
            thread: Mutex::new(Some(thread)),
            result: Mutex::new(None),
            base_us: now,
            base: Instant::now(),
            path: name,
        })))
    }

    /// Records one chunk, now. Never blocks: when the queue is full the chunk is dropped and
    /// counted. Nothing is recorded after [`Self::stop`].
    pub fn record(&self, direction: Direction, bytes: &[u8]) {
        self.record_at(direction, bytes, Instant::now());
    }

    /// Records one chunk that crossed at `at` (bytes read: when they arrived, where the port
    /// knows it, [`Transport::arrived_at`]; an instant before the capture began counts as its
    /// beginning). As [`Self::record`] otherwise. Chunks stay in the order they were recorded
    /// (an answer read after its request was written is after it in the file, whatever its
    /// stamp).
    pub fn record_at(&self, direction: Direction, bytes: &[u8], at: Instant) {
        let inner = &*self.0;
        if bytes.is_empty() || inner.stopped.load(Ordering::Relaxed) {
            return;
        }
        let since = at.saturating_duration_since(inner.base);
        let at_us = inner.base_us + since.as_micros() as u64;
        let c = &inner.counters;
        let dropped_before = c.pending_drops.swap(0, Ordering::Relaxed);
        let rec = Record::Chunk {
            at_us,
            direction,
            bytes: bytes.to_vec(),
            dropped_before,
        };
        match inner.tx.try_send(rec) {
            Ok(()) => {
                c.peak_queue.fetch_max(inner.tx.len(), Ordering::Relaxed);
            }
            Err(TrySendError::Full(_)) => {
                c.pending_drops
                    .fetch_add(dropped_before + 1, Ordering::Relaxed);
                c.dropped.fetch_add(1, Ordering::Relaxed);
            }
            Err(TrySendError::Disconnected(_)) => {}
        }
    }

    /// Records that the port switched to `baud` (a new interface block).
    pub fn baud_changed(&self, baud: u32) {
        if !self.0.stopped.load(Ordering::Relaxed) {
            // A setting is rare and must not be lost: wait for room.
            let _ = self.0.tx.send(Record::Baud(baud));
        }
    }

    /// Stops recording, waits until the file is complete, and says what it holds, or why
    /// writing failed (the disk full, the file gone). Later calls return the same.
    pub fn stop(&self) -> Result<CaptureSummary, CaptureError> {
        self.0.finish()?;
        Ok(self.summary())
    }

    /// The counters so far.
    pub fn summary(&self) -> CaptureSummary {
        let c = &self.0.counters;
        CaptureSummary {
            chunks: c.chunks.load(Ordering::Relaxed),
            dropped: c.dropped.load(Ordering::Relaxed),
            file_bytes: c.file_bytes.load(Ordering::Relaxed),
        }
    }

    /// The file's size so far, in bytes (what the window shows growing).
    pub fn file_bytes(&self) -> u64 {
        self.0.counters.file_bytes.load(Ordering::Relaxed)
    }

    /// Chunks dropped so far because the disk could not keep up.
    pub fn dropped(&self) -> u64 {
        self.0.counters.dropped.load(Ordering::Relaxed)
    }

    /// Chunks waiting for the disk now.
    pub fn queued(&self) -> usize {
        self.0.tx.len()
    }

    /// The most chunks that have waited for the disk at once.
    pub fn peak_queue(&self) -> usize {
        self.0.counters.peak_queue.load(Ordering::Relaxed)
    }

    /// Whether recording has stopped (asked to, or the writer failed).
    pub fn is_stopped(&self) -> bool {
        self.0.stopped.load(Ordering::Relaxed)
            || self
                .0
                .thread
                .lock()
                .map(|t| t.as_ref().is_none_or(|t| t.is_finished()))
                .unwrap_or(true)
    }

    /// The file's path (or the writer's name).
    pub fn path(&self) -> &str {
        &self.0.path
    }

    /// An opener that opens what `opener` opens, with every transport recorded here (a port
    /// reopened after a loss goes on being recorded into the same file).
    pub fn wrap(&self, opener: Opener) -> Opener {
        let tap = Tap::default();
        tap.start(self.clone());
        tap.wrap(opener)
    }
}

/// Where a link's bytes go when recording is switched on and off while connected (the window's
/// Record button): every transport opened through [`Tap::wrap`] records into the capture
/// [`Tap::start`] set, until [`Tap::stop`].
#[derive(Clone, Default)]
pub struct Tap(Arc<Mutex<Option<Capture>>>);

impl std::fmt::Debug for Tap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_tuple("Tap").field(&self.current()).finish()
    }
}

impl Tap {
    fn slot(&self) -> std::sync::MutexGuard<'_, Option<Capture>> {
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Records into `capture` from now on (replacing any other, which is returned).
    pub fn start(&self, capture: Capture) -> Option<Capture> {
        self.slot().replace(capture)
    }

    /// Stops recording here; returns the capture to [`Capture::stop`].
    pub fn stop(&self) -> Option<Capture> {
        self.slot().take()
    }

    /// The capture being recorded, if any.
    pub fn current(&self) -> Option<Capture> {
        self.slot().clone()
    }

    /// An opener that opens what `opener` opens, its transports recorded while this tap has a
    /// capture.
    pub fn wrap(&self, mut opener: Opener) -> Opener {
        let tap = self.clone();
        Box::new(move || {
            let inner = opener()?;
            Ok(Box::new(RecordingTransport {
                inner,
                tap: tap.clone(),
            }) as Box<dyn Transport>)
        })
    }

    fn record(&self, direction: Direction, bytes: &[u8], at: Instant) {
        if let Some(c) = self.slot().as_ref() {
            c.record_at(direction, bytes, at);
        }
    }
}

/// A transport whose writes and reads are recorded as they are made.
struct RecordingTransport {
    inner: Box<dyn Transport>,
    tap: Tap,
}

impl Transport for RecordingTransport {
    fn write(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        self.tap
            .record(Direction::HostToDevice, bytes, Instant::now());
        self.inner.write(bytes)
    }

    fn read(&mut self, buf: &mut [u8], deadline: Instant) -> Result<usize, LinkError> {
        let n = self.inner.read(buf, deadline)?;
        if n > 0
            && let Some(got) = buf.get(..n)
        {
            // When the bytes arrived, not when this thread got to read them (a loaded host
            // would otherwise record its own delay as the device's, and a replay answer late).
            let at = self.inner.arrived_at().unwrap_or_else(Instant::now);
            self.tap.record(Direction::DeviceToHost, got, at);
        }
        Ok(n)
    }

    fn set_baud(&mut self, baud: u32) -> Result<(), LinkError> {
        self.inner.set_baud(baud)?;
        if let Some(c) = self.tap.current() {
            c.baud_changed(baud);
        }
        Ok(())
    }

    fn baud(&self) -> u32 {
        self.inner.baud()
    }

    fn clear_input(&mut self) -> Result<(), LinkError> {
        self.inner.clear_input()
    }

    fn describe(&self) -> String {
        self.inner.describe()
    }

    fn latency_timer(&self) -> Option<std::time::Duration> {
        self.inner.latency_timer()
    }

    fn set_lines(&mut self, dtr: Option<bool>, rts: Option<bool>) -> Result<(), LinkError> {
        self.inner.set_lines(dtr, rts)
    }

    fn taken(&self) -> u64 {
        self.inner.taken()
    }

    fn others_reading(&mut self) -> Vec<crate::system::Holder> {
        self.inner.others_reading()
    }

    fn check(&mut self) -> Result<(), LinkError> {
        self.inner.check()
    }

    fn arrived_at(&self) -> Option<Instant> {
        self.inner.arrived_at()
    }
}

/// Counts the bytes written through it (the file's size without asking the OS).
struct Counting<W> {
    inner: W,
    count: u64,
}

impl<W: Write> Write for Counting<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.count += n as u64;
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// The writer thread: writes until [`Record::Stop`] (or every sender is gone), flushing when
/// the queue runs empty. On a write error it stops recording and keeps the error.
fn write_loop<W: Write>(
    mut w: pcap_file::pcapng::PcapNgWriter<Counting<std::io::BufWriter<W>>>,
    info: &CaptureInfo,
    rx: &Receiver<Record>,
    counters: &Counters,
) -> Result<(), CaptureError> {
    let mut interface = 0u32;
    let mut baud = info.baud;
    loop {
        let rec = match rx.try_recv() {
            Ok(r) => r,
            Err(_) => {
                w.get_mut().flush().map_err(CaptureError::write)?;
                counters
                    .file_bytes
                    .store(w.get_ref().count, Ordering::Relaxed);
                match rx.recv() {
                    Ok(r) => r,
                    Err(_) => return Ok(()),
                }
            }
        };
        match rec {
            Record::Chunk {
                at_us,
                direction,
                bytes,
                dropped_before,
            } => {
                format::write_chunk(&mut w, interface, at_us, direction, &bytes, dropped_before)?;
                counters.chunks.fetch_add(1, Ordering::Relaxed);
            }
            Record::Baud(b) if b != baud => {
                baud = b;
                format::write_interface(&mut w, info, b)?;
                interface += 1;
            }
            Record::Baud(_) => {}
            Record::Stop => {
                w.get_mut().flush().map_err(CaptureError::write)?;
                counters
                    .file_bytes
                    .store(w.get_ref().count, Ordering::Relaxed);
                return Ok(());
            }
        }
        counters
            .file_bytes
            .store(w.get_ref().count, Ordering::Relaxed);
    }
}
