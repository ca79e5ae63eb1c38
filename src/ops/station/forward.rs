//! The station's records that wait: a line server away or a full disk leaves records in a
//! spool on this PC (see [`crate::ops::records::Recorder`]); the station says how many wait
//! ([`What::Records`]) and a [`Forwarder`] thread sends them on when their store is back, so
//! that they do not wait for the next unit's record to be forwarded.

use super::event::{Event, What};
use super::runner::StationContext;
use crate::ops::Cancel;
use crate::ops::records::{Kept, Recorder};
use crossbeam_channel::Sender;
use std::time::{Duration, Instant};

/// How often the forwarder tries to send what waits: the line store's own pause after a
/// failure ([`crate::ops::records::line::RETRY_AFTER`], 10 s).
pub const FORWARD_EVERY: Duration = crate::ops::records::line::RETRY_AFTER;

/// How often the forwarder looks at its stop flag and at the count.
const LOOK_EVERY: Duration = Duration::from_millis(250);

/// The [`What::Records`] of `recorder` after a save that ended as `kept`: how many records
/// wait, in which store, and why (the save's own reason when it was not stored, else the
/// store's last error while any wait).
pub fn waiting(recorder: &mut Recorder, kept: &Kept) -> What {
    let waiting = recorder.waiting();
    let why = match kept {
        Kept::Spooled { why, .. } | Kept::InMemory { why, .. } => Some(why.to_string()),
        Kept::Stored { .. } if waiting > 0 => recorder.last_error().map(|e| e.to_string()),
        Kept::Stored { .. } => None,
    };
    What::Records {
        waiting,
        store: recorder.place(),
        why,
    }
}

/// The station's forwarder thread (`station-records`): says at start how many records wait
/// (some may be left from an earlier day), then every [`FORWARD_EVERY`] while any wait sends
/// them to their store, oldest first, saying the count whenever it changes. Stops when
/// dropped or [`Forwarder::stop`]ped (within [`LOOK_EVERY`], or after a connection attempt
/// under way: the line store's own 3 s timeout).
pub struct Forwarder {
    cancel: Cancel,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Forwarder {
    /// Starts the forwarder of `station`'s recorder, its events (slot `""`) to `events`.
    /// Errors: the thread could not be started.
    pub fn spawn(station: &StationContext, events: Sender<Event>) -> std::io::Result<Forwarder> {
        let cancel = Cancel::new();
        let stop = cancel.clone();
        let recorder = station.recorder.clone();
        let thread = std::thread::Builder::new()
            .name("station-records".into())
            .spawn(move || serve(&recorder, &events, &stop))?;
        Ok(Forwarder {
            cancel,
            thread: Some(thread),
        })
    }

    /// Stops the thread and waits for it to end.
    pub fn stop(mut self) {
        self.cancel.cancel();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for Forwarder {
    fn drop(&mut self) {
        self.cancel.cancel();
    }
}

/// The forwarder's loop.
fn serve(recorder: &std::sync::Mutex<Recorder>, events: &Sender<Event>, cancel: &Cancel) {
    let lock = || recorder.lock().unwrap_or_else(|e| e.into_inner());
    let mut said: Option<(u64, Option<String>)> = None;
    let mut next_try = Instant::now();
    while !cancel.is_cancelled() {
        let now = Instant::now();
        let (waiting, why, store) = {
            let mut r = lock();
            let mut why = None;
            if now >= next_try && r.waiting() > 0 {
                next_try = now + FORWARD_EVERY;
                if let Err(e) = r.forward_waiting() {
                    why = Some(e.to_string());
                }
            }
            let waiting = r.waiting();
            if waiting > 0 && why.is_none() {
                why = r.last_error().map(|e| e.to_string());
            }
            (waiting, if waiting > 0 { why } else { None }, r.place())
        };
        // The count and its reason, said when either changed (a reason's text may carry a
        // changing detail: only its presence and the count decide).
        let key = (waiting, why.as_ref().map(|_| String::new()));
        if said.as_ref() != Some(&key) {
            said = Some(key);
            let ev = Event {
                slot: String::new(),
                what: What::Records {
                    waiting,
                    store,
                    why,
                },
            };
            if events.send(ev).is_err() {
                return;
            }
        }
        std::thread::sleep(LOOK_EVERY);
    }
}
