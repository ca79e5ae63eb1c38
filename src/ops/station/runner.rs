//! The slot runner: one named thread per slot owns the slot's link, waits for its port and for
//! a unit (Start, a scanned serial, or a new unit answering), runs the line plan step by step,
//! keeps one record per unit run (`RunKind::Station`, the bundle's hash in it) before it says
//! the verdict, and stops at once on its cancel flag (STOP for the slot, STOP ALL for all).
//!
//! The engineer view borrows an idle slot ([`Command::Lend`]): a port has one owner, so the
//! runner closes its link, says [`What::Lent`] with the port's path, and waits; the engineer's
//! window opens that port with the ordinary panels; [`Command::Return`] (the view closed) has
//! the runner open it again and wait for the next unit, as after a replug.

use super::StartMode;
use super::event::{Answer, Command, Event, What};
use super::load::Slot;
use super::plan::LinePlan;
use super::reason::Reason;
use super::steps::{Desk, UnitRun, run_step};
use crate::i18n::Text;
use crate::link::{Client, Link, LinkOptions, PortOpener};
use crate::ops::records::record::{Record, RunKind, Unit, Verdict};
use crate::ops::records::{Recorder, SerialSource};
use crate::ops::{Cancel, Device};
use crossbeam_channel::{Receiver, Sender};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// How often an idle fixture's identity is read to see a new unit, and a missing port looked
/// for (the earlier line tool's 0.5 s).
pub const IDLE_POLL: Duration = Duration::from_millis(500);

/// What the station's slots share: its id, the bundle's hash, who operates it, the records.
#[derive(Clone)]
pub struct StationContext {
    /// The station's id.
    pub id: String,
    /// The bundle's hash (into every record).
    pub bundle_sha256: String,
    /// The operator's name, when known.
    pub operator: Option<String>,
    /// Where every slot's records go (one recorder, taken in turn).
    pub recorder: Arc<Mutex<Recorder>>,
}

impl StationContext {
    /// The context of `bundle`'s slots: its id and hash in every record, `operator` when known,
    /// and `recorder` shared by the slots.
    pub fn new(bundle: &super::load::Bundle, operator: Option<String>, recorder: Recorder) -> Self {
        Self {
            id: bundle.id.clone(),
            bundle_sha256: bundle.sha256.clone(),
            operator,
            recorder: Arc::new(Mutex::new(recorder)),
        }
    }
}

/// A fixture's hands: what a simulated fixture does where the operator's would (the corner
/// switches), and its next unit after a verdict. A real fixture's do nothing.
pub trait Hands: Send {
    /// The operator is asked to do `text` (a self-test's Operator step); a simulated fixture
    /// acts it out. `false` aborts the step.
    fn prompt(&mut self, text: &str) -> bool;
    /// The unit's verdict is out: a simulated fixture swaps in a fresh unit and says `true`
    /// (it is there now); a real one says `false` (the next unit is seen when it answers).
    fn next_unit(&mut self) -> bool;
}

/// A real fixture: the operator's hands do what prompts say.
pub struct OperatorHands;

impl Hands for OperatorHands {
    fn prompt(&mut self, _text: &str) -> bool {
        true
    }
    fn next_unit(&mut self) -> bool {
        false
    }
}

/// A running slot: where its commands go, its STOP, its thread.
pub struct SlotHandle {
    /// The slot's name.
    pub name: String,
    /// Start and answers.
    pub commands: Sender<Command>,
    /// STOP for this slot.
    pub cancel: Cancel,
    /// How the slot's port is opened (a simulated slot's device served under its name): the
    /// engineer view opens the lent port with it.
    pub opener: PortOpener,
    /// The slot's thread (ends after STOP, or after one unit with `once`).
    pub thread: std::thread::JoinHandle<()>,
}

/// Starts slot `slot` on a thread of its own (`slot-NAME`): its port opened with `opener`,
/// events to `events`; with `once`, it ends after one unit's verdict. Errors: the thread
/// could not be started.
pub fn spawn(
    slot: Slot,
    station: StationContext,
    opener: PortOpener,
    hands: Box<dyn Hands>,
    events: Sender<Event>,
    once: bool,
) -> std::io::Result<SlotHandle> {
    let (tx, rx) = crossbeam_channel::bounded(64);
    let cancel = Cancel::new();
    let name = slot.name.clone();
    let runner = SlotRunner {
        slot,
        station,
        opener: opener.clone(),
        hands,
        events,
        commands: rx,
        cancel: cancel.clone(),
        once,
        last_identity: None,
    };
    let thread = std::thread::Builder::new()
        .name(format!("slot-{name}"))
        .spawn(move || runner.serve())?;
    Ok(SlotHandle {
        name,
        commands: tx,
        cancel,
        opener,
        thread,
    })
}

struct SlotRunner {
    slot: Slot,
    station: StationContext,
    opener: PortOpener,
    hands: Box<dyn Hands>,
    events: Sender<Event>,
    commands: Receiver<Command>,
    cancel: Cancel,
    once: bool,
    /// The identity of the unit last tested here, read after its verdict (Auto start).
    last_identity: Option<String>,
}

impl SlotRunner {
    fn tell(&self, what: What) {
        let _ = self.events.send(Event {
            slot: self.slot.name.clone(),
            what,
        });
    }

    /// Waits `d` or until cancelled; `false` when cancelled.
    fn pause(&self, d: Duration) -> bool {
        let end = Instant::now() + d;
        while Instant::now() < end {
            if self.cancel.is_cancelled() {
                return false;
            }
            std::thread::sleep(Duration::from_millis(20).min(end - Instant::now()));
        }
        !self.cancel.is_cancelled()
    }

    fn serve(mut self) {
        let why = self.serve_units();
        self.tell(What::Stopped { why });
    }

    /// Opens the port (waiting for it while it is missing) and runs units until stopped.
    fn serve_units(&mut self) -> String {
        let mut ready = true;
        loop {
            let Some((link, path)) = self.open() else {
                return "stopped".into();
            };
            let client = link.client();
            loop {
                let serial = match self.wait_start(&client, ready) {
                    Start::Go(serial) => serial,
                    Start::Stopped => return "stopped".into(),
                    Start::Lost => break,
                    Start::Lend => {
                        drop(client);
                        drop(link);
                        if !self.lend(path) {
                            return "stopped".into();
                        }
                        // The unit the engineer had is not a new one.
                        ready = false;
                        break;
                    }
                };
                let record = self.unit(&client, serial);
                // Who is on the fixture now (a firmware update may have changed it): the next
                // unit is one that answers after a silence, or with another identity.
                if self.slot.plan.start == StartMode::Auto {
                    let servo = self.slot.profile.protocol == crate::profile::Protocol::Servo;
                    self.last_identity = match self.probe(&client) {
                        Probe::Present(id) => id,
                        // A servo provisioned away from the factory id: the fresh servo that
                        // answers there next is another unit by its serial number.
                        _ if servo => record.unit.serial.as_deref().map(servo_identity),
                        _ => None,
                    };
                }
                let lost = record
                    .reason
                    .as_deref()
                    .is_some_and(|r| r.starts_with("link lost"));
                if self.once {
                    return "one unit run (--once)".into();
                }
                if lost {
                    break;
                }
                ready = self.hands.next_unit();
            }
        }
    }

    /// The port closed (its link dropped): says [`What::Lent`] and waits for
    /// [`Command::Return`]; `false` when stopped first.
    fn lend(&self, port: String) -> bool {
        self.tell(What::Lent { port });
        loop {
            if self.cancel.is_cancelled() {
                return false;
            }
            match self.commands.recv_timeout(Duration::from_millis(100)) {
                Ok(Command::Return) => return true,
                Ok(_) | Err(crossbeam_channel::RecvTimeoutError::Timeout) => {}
                Err(crossbeam_channel::RecvTimeoutError::Disconnected) => return false,
            }
        }
    }

    /// The link to the slot's port and the path opened, once it is there; `None` when stopped
    /// first.
    fn open(&self) -> Option<(Link, String)> {
        let mut said = None;
        loop {
            if self.cancel.is_cancelled() {
                return None;
            }
            let ports = if super::port::needs_port_list(&self.slot.port) {
                crate::system::list_ports()
            } else {
                Vec::new()
            };
            let found = super::port::resolve(&self.slot.port, &self.slot.name, &ports);
            let opened = found.and_then(|path| {
                let profile = self.slot.profile.clone();
                let options = LinkOptions {
                    reconnect: false,
                    setup: self.slot.setup,
                    ..LinkOptions::default()
                };
                Link::open(
                    self.opener.open(&path, profile.baud),
                    profile,
                    options,
                    None,
                )
                .map(|l| (l, path))
                .map_err(|e| e.to_string())
            });
            match opened {
                Ok((link, path)) => {
                    self.tell(What::Port {
                        present: true,
                        detail: path.clone(),
                    });
                    return Some((link, path));
                }
                Err(why) => {
                    if said.as_ref() != Some(&why) {
                        self.tell(What::Port {
                            present: false,
                            detail: why.clone(),
                        });
                        said = Some(why);
                    }
                    if !self.pause(IDLE_POLL) {
                        return None;
                    }
                }
            }
        }
    }
}

/// How waiting for a unit ended.
enum Start {
    /// Go, with the serial scanned to start it.
    Go(Option<String>),
    /// STOP.
    Stopped,
    /// The port went away.
    Lost,
    /// The engineer view asks for the slot ([`Command::Lend`]).
    Lend,
}

impl SlotRunner {
    /// Waits for the next unit as the plan says: the Start button, a scanned serial, or a new
    /// unit answering: at once when `ready` (the first unit, or a simulated fixture has just
    /// presented a fresh one), else after the fixture was seen empty.
    fn wait_start(&self, client: &Client, ready: bool) -> Start {
        let plan = &self.slot.plan;
        let how = match plan.start {
            StartMode::Button => "button",
            StartMode::Scan => "scan",
            StartMode::Auto => "auto",
        };
        self.tell(What::Waiting { how });
        let mut watch = FixtureWatch::new(ready);
        loop {
            if self.cancel.is_cancelled() {
                return Start::Stopped;
            }
            match self.commands.recv_timeout(IDLE_POLL) {
                // Start works in every mode: the operator may always start a unit by hand.
                Ok(Command::Start) => return Start::Go(None),
                Ok(Command::Answer(Answer::Text(code))) if plan.start == StartMode::Scan => {
                    return Start::Go(Some(code));
                }
                Ok(Command::Lend) => return Start::Lend,
                Ok(_) => continue,
                Err(crossbeam_channel::RecvTimeoutError::Disconnected) => return Start::Stopped,
                Err(crossbeam_channel::RecvTimeoutError::Timeout) => {}
            }
            if plan.start == StartMode::Auto {
                let heard = client.bytes_heard();
                if !watch.before_poll(heard, Instant::now()) {
                    // An unanswered poll's silence is still being listened to.
                    continue;
                }
                match self.probe(client) {
                    Probe::Present(id) => {
                        // Another unit answering without a silence between (swapped quickly):
                        // its identity differs from the one last tested here.
                        let other =
                            matches!((&id, &self.last_identity), (Some(id), Some(l)) if id != l);
                        if watch.empty_seen() || other {
                            return Start::Go(None);
                        }
                    }
                    Probe::Absent => watch.unanswered(heard, Instant::now()),
                    Probe::Lost => return Start::Lost,
                }
            }
        }
    }

    /// Whether a unit answers on the port now, read afresh (never a cached identity, which
    /// would hide a fixture left empty), and who it says it is: its identity (MSP: CMD_VERSION
    /// and CMD_BUILD_INFO), a fresh servo (at the factory id, by its serial number),
    /// the MCU's product info (Tuya).
    fn probe(&self, client: &Client) -> Probe {
        use crate::profile::Protocol;
        let profile = &self.slot.profile;
        let dev = Device::new(client, profile);
        let answered: Result<Option<Option<String>>, crate::ops::OpError> = match profile.protocol {
            Protocol::Msp => client
                .identify()
                .map(|info| Some(Some(crate::ops::device::description(&info))))
                .map_err(crate::ops::OpError::from),
            Protocol::Servo => {
                crate::ops::servo::provision::find_fresh(dev, &profile.servo_bauds()).map(|found| {
                    found
                        .iter()
                        .find(|(_, p)| *p == crate::ops::servo::Presence::Present)
                        .map(|&(baud, _)| fresh_servo_serial(dev, baud).map(|s| servo_identity(&s)))
                })
            }
            Protocol::Tuya => Ok(crate::ops::tuya::product_info(client)
                .map(|info| Some(format!("{:?} {:?}", info.pid, info.version)))),
        };
        match answered {
            Ok(Some(identity)) => Probe::Present(identity),
            Ok(None) => Probe::Absent,
            Err(e) if e.lost_port().is_some() => Probe::Lost,
            Err(_) => Probe::Absent,
        }
    }
}

/// A servo's identity for telling units apart on an Auto slot: its serial number.
fn servo_identity(serial: &str) -> String {
    format!("servo serial {serial}")
}

/// The serial number of the fresh servo (at the factory id) answering at `baud`; `None` when
/// it could not be read (the servo is still a unit that answers, of unknown identity).
fn fresh_servo_serial(dev: Device<'_>, baud: u32) -> Option<String> {
    let fresh = crate::ops::servo::factory_location(dev.profile).id;
    let param = crate::ops::servo::serial_param(dev.profile).ok()?;
    crate::ops::servo::switch(dev.client, baud).ok()?;
    crate::ops::servo::read_param(dev, fresh, param)
        .ok()
        .map(|n| n.to_string())
}

/// How long the wire must stay silent after an identity poll went unanswered, from the poll's
/// start, for the fixture to count as empty: answers that come late (a device, a host or a line
/// running late) come within it, and a person's swap takes longer.
pub const EMPTY_SILENCE: Duration = Duration::from_secs(2);

/// What the idle fixture's identity polls have shown since its last unit. The fixture is empty
/// (a unit lifted off) after a poll left unanswered on a silent wire: nothing at all read for
/// [`EMPTY_SILENCE`] from the poll's start, and no poll sent meanwhile. A poll whose answers
/// came after its window or came garbled (a noisy line) is a unit still there: taking it for an
/// empty fixture tested the same unit twice (seen at load 14-19: a simulated device's process,
/// starved of CPU, answering one poll late).
#[derive(Debug, Clone, Copy)]
struct FixtureWatch {
    /// The fixture was seen empty, or its first unit is awaited: the next unit that answers is
    /// a new one.
    empty_seen: bool,
    /// The last poll went unanswered: the count of bytes heard ([`Client::bytes_heard`]) and
    /// the instant when it began.
    unanswered: Option<(u64, Instant)>,
}

impl FixtureWatch {
    /// `ready`: the next unit to answer is new without a silence (the fixture's first unit).
    fn new(ready: bool) -> Self {
        Self {
            empty_seen: ready,
            unanswered: None,
        }
    }

    /// Whether a poll may begin at `now`, `heard` bytes read so far: not while an unanswered
    /// poll's silence is being listened to (a poll's own answers would end it). The silence
    /// over, with nothing read since that poll began, the fixture was empty.
    fn before_poll(&mut self, heard: u64, now: Instant) -> bool {
        let Some((at_heard, began)) = self.unanswered else {
            return true;
        };
        if heard != at_heard {
            self.unanswered = None;
            return true;
        }
        if now.saturating_duration_since(began) < EMPTY_SILENCE {
            return false;
        }
        self.unanswered = None;
        self.empty_seen = true;
        true
    }

    /// The poll that began at `began`, `heard` bytes read by then, went unanswered.
    fn unanswered(&mut self, heard: u64, began: Instant) {
        self.unanswered = Some((heard, began));
    }

    /// Whether a unit answering now is a new one by the silence before it.
    fn empty_seen(&self) -> bool {
        self.empty_seen
    }
}

/// What a look at the idle fixture found.
enum Probe {
    /// A unit answers, with its identity where the device has one.
    Present(Option<String>),
    Absent,
    Lost,
}

impl SlotRunner {
    /// Runs one unit through the plan and keeps its record; says the verdict after.
    fn unit(&mut self, client: &Client, serial: Option<String>) -> Record {
        let slot = self.slot.clone();
        let plan: &LinePlan = &slot.plan;
        self.tell(What::Unit {
            serial: serial.clone(),
        });
        let mut record = Record::start(
            RunKind::Station,
            &plan.name,
            Some(self.station.bundle_sha256.clone()),
            &slot.profile.id,
        );
        record.context.station = Some(self.station.id.clone());
        record.context.slot = Some(slot.name.clone());
        record.context.fixture = Some(slot.fixture.clone());
        record.context.operator.clone_from(&self.station.operator);
        record.context.bundle_sha256 = Some(self.station.bundle_sha256.clone());
        let mut u = UnitRun {
            dev: Device::new(client, &slot.profile),
            cancel: &self.cancel.clone(),
            unit: Unit {
                serial_source: serial.as_ref().map(|_| SerialSource::Scanned),
                serial,
                ..Unit::default()
            },
            pass_so_far: true,
            provision: Default::default(),
        };
        let failed = self.steps(plan, &mut u, &mut record);
        let mut why = None;
        record.unit = u.unit.clone();
        record.finish(None);
        match failed {
            None => {
                record.verdict = Verdict::Pass;
                record.failed_step = None;
                record.reason = None;
            }
            Some((step, reason)) => {
                record.verdict = Verdict::Fail;
                record.failed_step = Some(step);
                record.reason = Some(reason.to_string());
                why = Some(reason);
            }
        }
        self.keep(&mut record, why);
        record
    }

    /// Runs the plan's steps; the first step that failed (after its retry) and why. After a
    /// failure only WriteResult steps still run (the device is told it failed); a link lost
    /// or STOP ends the run at once.
    fn steps(
        &mut self,
        plan: &LinePlan,
        u: &mut UnitRun<'_>,
        record: &mut Record,
    ) -> Option<(String, Reason)> {
        let mut failed: Option<(String, Reason)> = None;
        let of = plan.steps.len();
        for (i, step) in plan.steps.iter().enumerate() {
            if failed.is_some() && !matches!(step.op, super::Op::WriteResult) {
                continue;
            }
            let mut attempt = 1;
            loop {
                if self.cancel.is_cancelled() {
                    return failed.or(Some((step.name.clone(), Reason::Cancelled)));
                }
                self.tell(What::Step {
                    index: i + 1,
                    of,
                    name: step.name.clone(),
                    name_zh: step.name_zh.clone(),
                    attempt,
                });
                let done = run_step(u, &step.name, &step.op, &mut SlotDesk { runner: self });
                let seen = done
                    .records
                    .last()
                    .map(|r| r.detail.clone())
                    .unwrap_or_default();
                self.tell(What::StepDone {
                    name: step.name.clone(),
                    name_zh: step.name_zh.clone(),
                    pass: done.failure.is_none(),
                    detail: match &done.failure {
                        Some(reason) if seen.is_empty() || seen == reason.to_string() => {
                            reason.to_string()
                        }
                        Some(reason) => format!("{reason}: {seen}"),
                        None => seen,
                    },
                });
                record.steps.extend(done.records);
                let Some(reason) = done.failure else { break };
                if reason.link_lost() {
                    return failed.or(Some((
                        step.name.clone(),
                        Reason::LinkLostDuring {
                            step: step.name.clone(),
                            step_zh: step.name_zh.clone(),
                        },
                    )));
                }
                if plan.retry_once
                    && attempt == 1
                    && !self.cancel.is_cancelled()
                    && self.retry(step, &reason)
                {
                    attempt = 2;
                    continue;
                }
                u.pass_so_far = false;
                if failed.is_none() {
                    failed = Some((step.name.clone(), reason));
                }
                break;
            }
        }
        failed
    }

    /// Asks the operator whether to retry `step`, which failed for `reason` (the window says
    /// the question in 中文 from the typed reason).
    fn retry(&mut self, step: &super::LineStep, reason: &Reason) -> bool {
        let q = Text::new(
            format!("{} failed: {reason}. Retry once?", step.name),
            format!("{} 失败:{reason}。重试一次?", step.name_zh),
        );
        let mut desk = SlotDesk { runner: self };
        matches!(
            desk.ask_why("retry", &q, Duration::from_secs(120), Some(reason.clone())),
            Some(Answer::Yes)
        )
    }

    /// Keeps `record` (before the verdict is said) and says the verdict with the unit's
    /// earlier runs.
    fn keep(&mut self, record: &mut Record, why: Option<Reason>) {
        let (kept, earlier, waiting) = {
            let mut recorder = self
                .station
                .recorder
                .lock()
                .unwrap_or_else(|e| e.into_inner());
            let earlier = record.unit.serial.as_ref().and_then(|serial| {
                let mut found = None;
                let _ = recorder.store().read(&mut |db| {
                    found = crate::ops::records::query::history(db, &record.profile, serial)?;
                    Ok(())
                });
                found.map(|h| h.runs as i64)
            });
            let kept = recorder.save(record);
            if !kept.stored() {
                log::warn!("slot {}: {}", self.slot.name, kept.line());
            }
            let waiting = super::forward::waiting(&mut recorder, &kept);
            (kept, earlier, waiting)
        };
        self.tell(What::Verdict {
            pass: record.verdict == Verdict::Pass,
            serial: record.unit.serial.clone(),
            failed_step: record.failed_step.clone(),
            failed_step_zh: record.failed_step.as_ref().and_then(|f| {
                self.slot
                    .plan
                    .steps
                    .iter()
                    .find(|s| &s.name == f)
                    .map(|s| s.name_zh.clone())
            }),
            reason: why,
            earlier_runs: earlier,
            record: record.uuid.clone(),
            kept: kept.line(),
            stored: kept.stored(),
        });
        self.tell(waiting);
    }
}

/// The operator's side of a running slot.
struct SlotDesk<'r> {
    runner: &'r mut SlotRunner,
}

impl SlotDesk<'_> {
    /// [`Desk::ask`], with the cause of a retry question.
    fn ask_why(
        &mut self,
        kind: &'static str,
        text: &Text,
        timeout: Duration,
        why: Option<Reason>,
    ) -> Option<Answer> {
        let r = &self.runner;
        r.tell(What::Ask {
            kind,
            text: text.en.clone(),
            text_zh: text.zh.clone(),
            why,
        });
        let end = Instant::now() + timeout;
        loop {
            if r.cancel.is_cancelled() {
                return None;
            }
            let left = end.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return None;
            }
            match r
                .commands
                .recv_timeout(left.min(Duration::from_millis(100)))
            {
                Ok(Command::Answer(a)) => return Some(a),
                // Start, and the engineer view's Lend and Return, mean nothing while a unit runs.
                Ok(Command::Start | Command::Lend | Command::Return)
                | Err(crossbeam_channel::RecvTimeoutError::Timeout) => {}
                Err(crossbeam_channel::RecvTimeoutError::Disconnected) => return None,
            }
        }
    }
}

impl Desk for SlotDesk<'_> {
    fn ask(&mut self, kind: &'static str, text: &Text, timeout: Duration) -> Option<Answer> {
        self.ask_why(kind, text, timeout, None)
    }

    fn prompt(&mut self, text: &Text) -> bool {
        self.runner.tell(What::Ask {
            kind: "prompt",
            text: text.en.clone(),
            text_zh: text.zh.clone(),
            why: None,
        });
        self.runner.hands.prompt(&text.en)
    }

    fn tell(&mut self, what: What) {
        self.runner.tell(what);
    }
}

#[cfg(test)]
mod fixture_watch_tests {
    use super::{EMPTY_SILENCE, FixtureWatch};
    use std::time::{Duration, Instant};

    #[test]
    fn an_unanswered_poll_shows_an_empty_fixture_only_after_a_silent_wire() {
        let t0 = Instant::now();
        let ms = |n| t0 + Duration::from_millis(n);
        let mut w = FixtureWatch::new(false);
        assert!(!w.empty_seen(), "the unit just tested");
        // A poll whose answers came after its window, even after the next poll was due.
        assert!(w.before_poll(100, ms(0)));
        w.unanswered(100, ms(0));
        assert!(!w.before_poll(100, ms(600)), "polled during the silence");
        assert!(w.before_poll(112, ms(1200)), "bytes came: poll again");
        assert!(!w.empty_seen(), "a late answer took the fixture for empty");
        // A unit lifted off: a poll unanswered, nothing read for the whole silence.
        w.unanswered(112, ms(1500));
        assert!(!w.before_poll(112, ms(1500) + EMPTY_SILENCE - Duration::from_millis(1)));
        assert!(!w.empty_seen());
        assert!(w.before_poll(112, ms(1500) + EMPTY_SILENCE));
        assert!(w.empty_seen(), "a silent wire is an empty fixture");
        // The first unit of a fixture is awaited without a silence.
        assert!(FixtureWatch::new(true).empty_seen());
    }
}
