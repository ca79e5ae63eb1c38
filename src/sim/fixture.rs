//! A simulated fixture for the line station: a built-in device on a slot, which plays the
//! operator's hands where a step needs them (covering the corner switches in turn) and, after
//! each verdict, is swapped for a fresh unit (a new serial number or seed, factory settings, a
//! fresh servo at id 0), so that a demo station runs unit after unit with no hardware.

use super::servo_bus::{ServoBus, SimServo, builtin_servo_profile};
use super::solar_cleanbot::SolarCleanbot;
use super::tuya_mcu::TuyaMcu;
use super::window_cleaner::WindowCleaner;
use super::{Faults, SharedDevice, SimKind, SimOptions, SimTransport, VanishHandle};
use crate::link::Opener;
use crate::ops::station::runner::EMPTY_SILENCE;
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// How long each corner switch is held, and released, when the fixture's hands cover them.
const CORNER_HOLD: Duration = Duration::from_millis(250);

/// The device on a simulated fixture, kept so that it can be acted on and swapped.
#[derive(Clone)]
enum Unit {
    WindowCleaner(Arc<Mutex<WindowCleaner>>),
    Solar(Arc<Mutex<SolarCleanbot>>),
    Servos(Arc<Mutex<ServoBus>>),
    Tuya(Arc<Mutex<TuyaMcu>>),
}

/// A slot's simulated device: [`SimFixture::opener`] serves it to the slot's link; as
/// [`crate::ops::station::Hands`] it acts prompts out and presents the next unit.
#[derive(Clone)]
pub struct SimFixture {
    kind: SimKind,
    unit: Unit,
    /// Units presented so far (1 for the first).
    units: u32,
    /// The fixture's adapter pulled: every port opened on it vanishes, for good.
    unplugged: VanishHandle,
}

impl SimFixture {
    /// The first unit of `kind` (a servo bus holds one fresh servo at id 0). Errors: a
    /// simulator that cannot be built (its built-in profile).
    pub fn new(kind: SimKind) -> Result<Self, String> {
        Ok(Self {
            kind,
            unit: unit(kind, 1)?,
            units: 1,
            unplugged: VanishHandle::default(),
        })
    }

    /// The device as the simulated wire serves it.
    fn shared(&self) -> SharedDevice {
        match &self.unit {
            Unit::WindowCleaner(d) => d.clone(),
            Unit::Solar(d) => d.clone(),
            Unit::Servos(d) => d.clone(),
            Unit::Tuya(d) => d.clone(),
        }
    }

    /// Opens the fixture's device at a baud rate: what [`crate::link::PortOpener::with_port`]
    /// takes for the slot's simulated port name.
    pub fn opener(&self) -> impl Fn(u32) -> Opener + Send + Sync + 'static {
        let device = self.shared();
        let kind = self.kind;
        let unplugged = self.unplugged.clone();
        move |baud| {
            let device = device.clone();
            let unplugged = unplugged.clone();
            Box::new(move || {
                let t = SimTransport::new(device.clone(), baud, Faults::default(), kind.describe())
                    .with_vanish(unplugged.clone());
                Ok(Box::new(t) as Box<dyn crate::link::Transport>)
            })
        }
    }

    /// Pulls the fixture's adapter when its `vanish` is called (from any thread): the slot's
    /// port fails at its next call (link lost), and so does every later open, for good.
    pub fn unplug_handle(&self) -> VanishHandle {
        self.unplugged.clone()
    }

    /// Units presented so far.
    pub fn units(&self) -> u32 {
        self.units
    }
}

/// Unit `n` of `kind`, factory fresh: seed `n`; a servo's serial number 1000 + n.
fn unit(kind: SimKind, n: u32) -> Result<Unit, String> {
    let opts = SimOptions {
        seed: u64::from(n),
        ..SimOptions::default()
    };
    Ok(match kind {
        SimKind::WindowCleaner => {
            Unit::WindowCleaner(Arc::new(Mutex::new(WindowCleaner::new(&opts)?)))
        }
        SimKind::SolarCleanbot => Unit::Solar(Arc::new(Mutex::new(SolarCleanbot::new(&opts)?))),
        SimKind::ServoBus => {
            let profile = builtin_servo_profile();
            let servo = SimServo::fresh_with(&profile, 1000 + n)
                .with_id(0)
                .with_baud(kind.default_baud());
            Unit::Servos(Arc::new(Mutex::new(
                ServoBus::with_profile(profile, vec![servo]).with_seed(u64::from(n)),
            )))
        }
        SimKind::TuyaVacuum => Unit::Tuya(Arc::new(Mutex::new(super::tuya_mcu(&opts)))),
    })
}

impl crate::ops::station::Hands for SimFixture {
    /// Covers each corner switch in turn and releases it (a window cleaner's Corner switches
    /// step), on a thread of its own while the step watches.
    fn prompt(&mut self, _text: &str) -> bool {
        if let Unit::WindowCleaner(d) = &self.unit {
            let d = d.clone();
            let _ = std::thread::Builder::new()
                .name("sim-fixture-hands".into())
                .spawn(move || {
                    for bit in [1u8, 2, 4, 8] {
                        for bits in [bit, 0] {
                            std::thread::sleep(CORNER_HOLD);
                            d.lock()
                                .unwrap_or_else(|e| e.into_inner())
                                .set_corners(bits);
                        }
                    }
                });
        }
        true
    }

    /// Swaps the device for a fresh one: the same wire, a new unit on it.
    fn next_unit(&mut self) -> bool {
        let n = self.units + 1;
        let Ok(fresh) = unit(self.kind, n) else {
            return false;
        };
        match (&self.unit, fresh) {
            (Unit::WindowCleaner(d), Unit::WindowCleaner(f)) => swap(d, &f),
            (Unit::Solar(d), Unit::Solar(f)) => swap(d, &f),
            (Unit::Servos(d), Unit::Servos(f)) => swap(d, &f),
            (Unit::Tuya(d), Unit::Tuya(f)) => swap(d, &f),
            _ => return false,
        }
        self.units = n;
        true
    }
}

/// Puts `fresh`'s device in `d`'s place.
fn swap<T>(d: &Arc<Mutex<T>>, fresh: &Arc<Mutex<T>>) {
    let mut f = fresh.lock().unwrap_or_else(|e| e.into_inner());
    let mut d = d.lock().unwrap_or_else(|e| e.into_inner());
    std::mem::swap(&mut *d, &mut *f);
}

/// Starts `slot` ([`crate::ops::station::spawn`]): a simulated slot on a [`SimFixture`] of its
/// own (served under [`crate::ops::station::port::simulated_path`]), any other on `ports` with
/// the operator's hands. Errors: an unknown simulated kind, a simulator that cannot be built,
/// a thread that cannot be started.
pub fn start_slot(
    slot: &crate::ops::station::Slot,
    context: crate::ops::station::StationContext,
    ports: &crate::link::PortOpener,
    events: crossbeam_channel::Sender<crate::ops::station::Event>,
    once: bool,
) -> Result<crate::ops::station::SlotHandle, String> {
    use crate::ops::station::{self, PortLocator};
    let (opener, hands): (crate::link::PortOpener, Box<dyn station::Hands>) = match &slot.port {
        PortLocator::Simulated(kind) => {
            let kind: SimKind = kind.parse()?;
            let fixture = SimFixture::new(kind)?;
            let path = station::port::simulated_path(kind.name(), &slot.name);
            (
                ports.clone().with_port(path, fixture.opener()),
                Box::new(fixture),
            )
        }
        _ => (ports.clone(), Box::new(station::OperatorHands)),
    };
    station::spawn(slot.clone(), context, opener, hands, events, once)
        .map_err(|e| format!("slot {}: cannot start its thread: {e}", slot.name))
}

/// A station started: its slots, their events (on one channel), and the forwarder of the
/// records that wait in a spool.
pub struct StartedStation {
    /// The slots' handles, in the bundle's order.
    pub slots: Vec<crate::ops::station::SlotHandle>,
    /// Every slot's events, and the forwarder's.
    pub events: crossbeam_channel::Receiver<crate::ops::station::Event>,
    /// Sends the records that wait on to their store; stops when dropped.
    pub forwarder: crate::ops::station::Forwarder,
    /// What the slots share (the station's id, bundle hash, recorder): the window records
    /// the engineer's unlocks through it.
    pub context: crate::ops::station::StationContext,
}

/// Starts every slot of `bundle` ([`start_slot`]: simulated slots on fixtures of their own,
/// the others on `ports`), recording through `recorder` (its store, its context), and the
/// forwarder of waiting records. With `once`, each slot ends after one unit. Errors: a slot
/// that cannot be started (said with its name), the forwarder's thread.
pub fn start_station(
    bundle: &crate::ops::station::Bundle,
    recorder: crate::ops::records::Recorder,
    operator: Option<String>,
    ports: &crate::link::PortOpener,
    once: bool,
) -> Result<StartedStation, String> {
    use crate::ops::station::{Event, Forwarder, StationContext};
    let context = StationContext::new(bundle, operator, recorder);
    let (tx, rx) = crossbeam_channel::bounded::<Event>(1024);
    let mut slots = Vec::new();
    for slot in &bundle.slots {
        match start_slot(slot, context.clone(), ports, tx.clone(), once) {
            Ok(handle) => slots.push(handle),
            Err(e) => {
                // The slots already running stop: a station starts whole or not at all.
                slots.iter().for_each(|s| s.cancel.cancel());
                return Err(e);
            }
        }
    }
    let forwarder = Forwarder::spawn(&context, tx)
        .map_err(|e| format!("the station's records forwarder cannot start: {e}"))?;
    Ok(StartedStation {
        slots,
        events: rx,
        forwarder,
        context,
    })
}

/// How long a unit is off the fixture when `botbench sim ... next` swaps it: silent, as a real
/// fixture is between one unit lifted off and the next placed (three of a station's 0.5 s
/// identity polls).
pub const SWAP_GAP: Duration = Duration::from_millis(1500);

/// A lifted fixture: silent until `until`, and until the station has listened to its silence:
/// a request left unanswered, then another that came [`EMPTY_SILENCE`] or more after it (the
/// station's rule for an empty fixture).
///
/// A gap measured only in the fixture's time is missed by a station whose thread ran late for
/// longer than it (seen under two CPU-bound loops: the next window cleaner never tested), and a
/// count of requests is used up by one look of a station that sends several (seen under load: a
/// servo slot's search for a fresh servo pings the factory id at every baud rate, so the fresh
/// servo answered within the look that found the fixture empty, and the slot never started).
#[derive(Debug, Clone, Copy)]
struct Lifted {
    until: std::time::Instant,
    /// When the first request came while lifted.
    first_ignored: Option<std::time::Instant>,
}

impl Lifted {
    /// Whether the unit is still off the fixture at `now`; `heard`: a request came.
    fn still(&mut self, now: std::time::Instant, heard: bool) -> bool {
        let listened = self
            .first_ignored
            .is_some_and(|first| now.saturating_duration_since(first) >= EMPTY_SILENCE);
        if now >= self.until && listened {
            return false;
        }
        if heard && self.first_ignored.is_none() {
            self.first_ignored = Some(now);
        }
        true
    }
}

/// A fixture's device that can be lifted off: while lifted it hears nothing and says nothing
/// (the wire stays, as the fixture's cable does). `botbench sim` serves its device through
/// one, so that `next` on its stdin presents a fresh unit after a silence.
pub struct Lift {
    device: SharedDevice,
    lifted_until: Arc<Mutex<Option<Lifted>>>,
}

/// Lifts a [`Lift`]'s device off for a while.
#[derive(Clone)]
pub struct LiftHandle {
    lifted_until: Arc<Mutex<Option<Lifted>>>,
}

impl Lift {
    /// `device` on a fixture, and the handle that lifts it.
    pub fn new(device: SharedDevice) -> (Lift, LiftHandle) {
        let lifted_until = Arc::new(Mutex::new(None));
        let handle = LiftHandle {
            lifted_until: lifted_until.clone(),
        };
        (
            Lift {
                device,
                lifted_until,
            },
            handle,
        )
    }

    /// Whether the unit is off the fixture at `now`; `heard`: a request came (left unanswered
    /// while lifted).
    fn lifted(&self, now: std::time::Instant, heard: bool) -> bool {
        let mut lifted = self.lifted_until.lock().unwrap_or_else(|e| e.into_inner());
        let Some(l) = lifted.as_mut() else {
            return false;
        };
        if l.still(now, heard) {
            return true;
        }
        *lifted = None;
        false
    }
}

impl LiftHandle {
    /// Silent from now for `gap`, and until the station has listened to the silence
    /// ([`Lifted`]).
    pub fn lift_for(&self, gap: Duration) {
        *self.lifted_until.lock().unwrap_or_else(|e| e.into_inner()) = Some(Lifted {
            until: std::time::Instant::now() + gap,
            first_ignored: None,
        });
    }
}

impl super::Device for Lift {
    fn receive(
        &mut self,
        bytes: &[u8],
        baud: u32,
        now: std::time::Instant,
    ) -> Vec<super::Outgoing> {
        if self.lifted(now, true) {
            return Vec::new();
        }
        self.device
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .receive(bytes, baud, now)
    }

    fn tick(&mut self, now: std::time::Instant) -> Vec<super::Outgoing> {
        if self.lifted(now, false) {
            return Vec::new();
        }
        self.device
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .tick(now)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{Device, Outgoing};
    use std::time::Instant;

    /// Answers every request with one byte.
    struct Answers;

    impl Device for Answers {
        fn receive(&mut self, _bytes: &[u8], _baud: u32, _now: Instant) -> Vec<Outgoing> {
            vec![Outgoing::new(Duration::ZERO, vec![1])]
        }
    }

    /// A swap's gap that has passed before the station looked (its thread ran late) still
    /// leaves the station's look unanswered, however many requests it sends (a servo slot's
    /// search pings every baud rate), and the unit answers only once the station has listened to
    /// the silence for [`EMPTY_SILENCE`]: the empty fixture is seen whatever the load.
    #[test]
    fn a_lifted_fixture_stays_silent_until_the_station_could_see_it_empty() {
        let (mut lift, handle) = Lift::new(Arc::new(Mutex::new(Answers)));
        assert_eq!(lift.receive(&[0], 9600, Instant::now()).len(), 1);
        handle.lift_for(Duration::ZERO);
        let later = Instant::now() + Duration::from_secs(5);
        for n in 1..=12 {
            assert!(lift.tick(later).is_empty());
            assert!(
                lift.receive(&[0], 9600, later).is_empty(),
                "request {n} of the station's first look answered, the gap long past"
            );
        }
        let almost = later + EMPTY_SILENCE - Duration::from_millis(1);
        assert!(
            lift.receive(&[0], 9600, almost).is_empty(),
            "answered before the silence was listened to"
        );
        let listened = later + EMPTY_SILENCE;
        assert_eq!(lift.receive(&[0], 9600, listened).len(), 1, "placed again");
        assert_eq!(lift.receive(&[0], 9600, listened).len(), 1, "stays placed");
    }

    /// Ticks alone (no request) never start the silence the station listens to.
    #[test]
    fn a_lifted_fixture_nobody_asked_is_not_seen_empty() {
        let (mut lift, handle) = Lift::new(Arc::new(Mutex::new(Answers)));
        handle.lift_for(Duration::ZERO);
        let later = Instant::now() + Duration::from_secs(60);
        assert!(lift.tick(later).is_empty());
        assert!(lift.receive(&[0], 9600, later + EMPTY_SILENCE).is_empty());
    }
}
