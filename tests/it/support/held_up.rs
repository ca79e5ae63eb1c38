//! A computer too loaded to run the link's thread on time (issue 25, item 4e): a port whose
//! reads that find nothing return 30 ms after their deadline, as a thread scheduled late does,
//! the port behind it a simulator's served in lockstep (exact about when the device heard what).

use super::Port;
use botbench::link::{LinkError, Opener, PortOpener, Transport};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// How late a held-up read returns past its deadline: past [`botbench::link::HELD_UP`].
const LATE: Duration = Duration::from_millis(30);

/// `port`, with each of its reads that find nothing, as many as `late_reads` holds, returning
/// [`LATE`] after its deadline.
pub struct HeldUp {
    port: Box<dyn Transport>,
    late_reads: Arc<AtomicUsize>,
}

impl Transport for HeldUp {
    fn write(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        self.port.write(bytes)
    }
    fn read(&mut self, buf: &mut [u8], deadline: Instant) -> Result<usize, LinkError> {
        let n = self.port.read(buf, deadline)?;
        let late = n == 0
            && self
                .late_reads
                .fetch_update(Ordering::SeqCst, Ordering::SeqCst, |k| k.checked_sub(1))
                .is_ok();
        if late {
            std::thread::sleep((deadline + LATE).saturating_duration_since(Instant::now()));
        }
        Ok(n)
    }
    fn set_baud(&mut self, baud: u32) -> Result<(), LinkError> {
        self.port.set_baud(baud)
    }
    fn baud(&self) -> u32 {
        self.port.baud()
    }
    fn clear_input(&mut self) -> Result<(), LinkError> {
        self.port.clear_input()
    }
    fn describe(&self) -> String {
        self.port.describe()
    }
    fn arrived_at(&self) -> Option<Instant> {
        self.port.arrived_at()
    }
    fn written_at(&self) -> Option<Instant> {
        self.port.written_at()
    }
}

/// `open` with what it opens behind [`HeldUp`], sharing `late_reads`.
fn held_up_opener(mut open: Opener, late_reads: Arc<AtomicUsize>) -> Opener {
    Box::new(move || {
        Ok(Box::new(HeldUp {
            port: open()?,
            late_reads: late_reads.clone(),
        }) as Box<dyn Transport>)
    })
}

/// `ports`, with `path` opened behind [`HeldUp`]: its first `late_reads` reads that find
/// nothing late (`usize::MAX`: every one), counted over every open.
pub fn held_up(ports: PortOpener, path: &str, late_reads: usize) -> PortOpener {
    let late = Arc::new(AtomicUsize::new(late_reads));
    let (served, at) = (ports.clone(), path.to_string());
    ports.with_port(path, move |baud| {
        held_up_opener(served.open(&at, baud), late.clone())
    })
}

/// A served port on a computer held up at every read that finds nothing, for the window.
pub struct HeldUpPort<'a, P: Port>(pub &'a P);

impl<P: Port> Port for HeldUpPort<'_, P> {
    fn path(&self) -> &str {
        self.0.path()
    }
    fn opener(&self, baud: u32) -> Opener {
        held_up_opener(self.0.opener(baud), Arc::new(AtomicUsize::new(usize::MAX)))
    }
    fn ports(&self) -> PortOpener {
        held_up(self.0.ports(), self.0.path(), usize::MAX)
    }
}
