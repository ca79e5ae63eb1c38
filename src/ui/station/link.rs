//! The link as the window sees it: what it is connected to, its state and counters as the worker
//! last reported them, how it was opened, and the serial ports there are.

use crate::link::{DeviceEvent, Link, LinkOptions, LinkState, LinkStats, PortOpener};
use crate::sim::tuya_mcu::TuyaMcu;
use crate::system::{self, PortInfo};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// What to connect to.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Target {
    /// A simulator inside botbench.
    Demo(String),
    /// A serial port (or pseudo-terminal) by path.
    Port(String),
}

impl Target {
    /// A label for the port picker and the title.
    pub fn label(&self) -> String {
        match self {
            Target::Demo(kind) => format!("built-in simulated {kind}"),
            Target::Port(p) => p.clone(),
        }
    }

    /// [`Self::label`] in `lang`: a built-in demo device by its Chinese name in 中文
    /// (`内置模拟擦窗机器人`), by its simulator's name when it is none botbench has.
    pub fn label_in(&self, lang: crate::i18n::Lang) -> String {
        match (self, lang) {
            (Target::Demo(kind), crate::i18n::Lang::Zh) => {
                match kind.parse::<crate::sim::SimKind>() {
                    Ok(k) => format!("内置{}", k.described().zh),
                    Err(_) => format!("内置模拟设备 {kind}"),
                }
            }
            _ => self.label(),
        }
    }

    /// What the link calls the port it opened (`LinkState::Connected`'s `port`), in both
    /// languages: a built-in demo device's description is translated, a path is a path.
    pub fn port_said(&self, port: &str) -> crate::i18n::Text {
        match self {
            Target::Demo(name) => match name.parse::<crate::sim::SimKind>() {
                Ok(kind) if kind.describe() == port => kind.described(),
                _ => crate::i18n::Text::same(port),
            },
            Target::Port(_) => crate::i18n::Text::same(port),
        }
    }
}

/// Whether the device answers, as the link reports it ([`DeviceEvent`]): an open port says
/// nothing of the device behind it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Answering {
    /// Nothing answered yet on this connection, and fewer than [`SILENT_AFTER`] requests went
    /// unanswered.
    #[default]
    NotYet,
    /// The device answered, and fewer than [`SILENT_AFTER`] requests went unanswered since.
    Yes,
    /// This many requests in a row went unanswered (at least [`SILENT_AFTER`]).
    No(u64),
}

pub use crate::link::SILENT_AFTER;

/// When the device last answered: for comparisons and for people.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LastAnswer {
    /// When the window heard of it (monotonic).
    pub at: Instant,
    /// The wall-clock time.
    pub clock: chrono::DateTime<chrono::Local>,
}

impl LastAnswer {
    fn now() -> Self {
        Self {
            at: Instant::now(),
            clock: chrono::Local::now(),
        }
    }
}

/// An open link and what it talks to.
pub struct Connection {
    /// The worker.
    pub link: Link,
    /// What it talks to.
    pub target: Target,
    /// The built-in simulated Tuya MCU, when that is the target: the window can ask it to
    /// send its own requests.
    pub demo_tuya: Option<Arc<Mutex<TuyaMcu>>>,
}

/// The link's status.
#[derive(Default)]
pub struct LinkStatus {
    /// The open link, if any.
    pub connection: Option<Connection>,
    /// The link's state as last reported (`None`: not connected, or not reported yet).
    pub state: Option<LinkState>,
    /// The link's counters.
    pub stats: LinkStats,
    /// How links are opened (answer margin, reconnect), as `--margin-ms` on the command line.
    pub options: LinkOptions,
    /// Telemetry polling is paused.
    pub polling_paused: bool,
    /// When polling was paused: a following plot stops there instead of scrolling the paused
    /// data out of view.
    pub paused_at: Option<Instant>,
    /// The link has just come up (first connect or a reconnect): the app reads the device.
    pub just_connected: bool,
    /// The device answered again after being silent (or answered for the first time after
    /// silence): possibly another unit on the same port. The app forgets what the last unit
    /// showed, identifies and reads the device again.
    pub device_back: bool,
    /// Whether the device answers, as the link last reported it on this connection.
    answering: Answering,
    /// How far this computer was held up during the last unanswered attempt, when it was
    /// ([`crate::link::NoAnswer::host_late`]); cleared by an answer.
    silent_held_up: Option<std::time::Duration>,
    /// When the device last answered anything on this link (a poll, a job's request, a frame
    /// of its own), as far as the window has heard: `None` before its first answer.
    last_answer: Option<LastAnswer>,
    /// Serial ports, refreshed every second.
    pub ports: Vec<PortInfo>,
    ports_at: Option<Instant>,
    /// Where the ports are listed from.
    pub port_lister: PortLister,
    /// How a port named by its path is opened: the system's serial ports, or what a test
    /// serves ([`crate::ui::App::new`] is handed it).
    pub port_opener: PortOpener,
    /// The last reply id given out ([`Self::reply_id`]).
    next_reply_id: std::sync::atomic::AtomicU64,
}

/// Where the serial ports come from: the system's ([`system::list_ports`]), unless a test lists
/// its own (an FTDI adapter with a latency timer, on a machine that has none).
#[derive(Clone)]
pub struct PortLister(pub Arc<dyn Fn() -> Vec<PortInfo> + Send + Sync>);

impl Default for PortLister {
    fn default() -> Self {
        Self(Arc::new(system::list_ports))
    }
}

impl LinkStatus {
    /// Whether the link is up.
    pub fn connected(&self) -> bool {
        matches!(self.state, Some(LinkState::Connected { .. }))
    }

    /// The rate the port is at now, while connected.
    pub fn baud(&self) -> Option<u32> {
        match &self.state {
            Some(LinkState::Connected { baud, .. }) => Some(*baud),
            _ => None,
        }
    }

    /// The built-in simulated Tuya MCU the link talks to, if it does.
    pub fn demo_tuya(&self) -> Option<&Arc<Mutex<TuyaMcu>>> {
        self.connection.as_ref().and_then(|c| c.demo_tuya.as_ref())
    }

    /// Whether the device answers (see [`Answering`]).
    pub fn answering(&self) -> Answering {
        self.answering
    }

    /// How far this computer was held up during the last unanswered attempt, when it was
    /// [`crate::link::HELD_UP`] or more: a silent device's checklist leads with the loaded
    /// computer ([`crate::link::silent::SilentCheck::HostLate`]).
    pub fn silent_held_up(&self) -> Option<std::time::Duration> {
        self.silent_held_up
    }

    /// An attempt went unanswered ([`crate::link::LinkEvent::NoAnswer`]).
    pub fn on_no_answer(&mut self, n: &crate::link::NoAnswer) {
        self.silent_held_up = n.host_late;
    }

    /// When the device last answered on this link (see [`LastAnswer`]).
    pub fn last_answer(&self) -> Option<LastAnswer> {
        self.last_answer
    }

    /// The device answered something just now (a poll's answer, a reply, a frame of its own).
    pub fn heard(&mut self) {
        self.last_answer = Some(LastAnswer::now());
    }

    /// Takes the link's counters: valid frames received since the last ones mean the device
    /// answered ([`Self::last_answer`]).
    pub fn on_stats(&mut self, stats: LinkStats) {
        if stats.received != self.stats.received && stats.received > 0 {
            self.heard();
        }
        self.stats = stats;
    }

    /// Takes what the link reports of the device: it answers (after silence: raises
    /// [`Self::device_back`]), or it has been silent for this many attempts.
    pub fn on_device(&mut self, event: DeviceEvent) {
        match event {
            DeviceEvent::Answered { after_silence } => {
                self.device_back |= after_silence;
                self.answering = Answering::Yes;
                self.silent_held_up = None;
                self.heard();
            }
            DeviceEvent::Silent { unanswered } => self.answering = Answering::No(unanswered),
        }
    }

    /// The port closed or was lost: nothing is known of the device until it answers.
    pub fn forget_answers(&mut self) {
        self.answering = Answering::NotYet;
        self.silent_held_up = None;
        self.device_back = false;
        self.last_answer = None;
        // The round trip shown was the ended connection's.
        self.stats.rtt = None;
    }

    /// What the link talks to, while one is open.
    pub fn target(&self) -> Option<&Target> {
        self.connection.as_ref().map(|c| &c.target)
    }

    /// Re-lists the serial ports at most once a second.
    pub fn refresh_ports(&mut self) {
        if self
            .ports_at
            .is_none_or(|t| t.elapsed() >= Duration::from_secs(1))
        {
            self.ports = (self.port_lister.0)();
            self.ports_at = Some(Instant::now());
        }
    }

    /// Re-lists the serial ports now (after a port's setting changed).
    pub fn refresh_ports_now(&mut self) {
        self.ports_at = None;
        self.refresh_ports();
    }

    /// The USB adapter of the port the link is open on, as last listed.
    pub fn adapter(&self) -> Option<(&str, &crate::system::adapter::Adapter)> {
        let Some(Target::Port(path)) = self.target() else {
            return None;
        };
        self.ports
            .iter()
            .find(|p| &p.path == path)
            .map(|p| (p.path.as_str(), &p.adapter))
    }

    /// A fresh id for a request whose result comes back as a `LinkEvent::Reply` (kept in
    /// [`super::DeviceModel::replies`]): 1, 2, 3… on this station, never reused by it (its
    /// replies come on its own link, so another station's ids never meet them).
    pub fn reply_id(&self) -> u64 {
        self.next_reply_id
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed)
            + 1
    }
}

#[cfg(test)]
mod tests {
    use super::Target;
    use crate::i18n::Lang;
    use crate::sim::SimKind;

    #[test]
    fn a_demo_devices_name_is_said_in_chinese_and_a_path_stays_a_path() {
        for kind in SimKind::ALL {
            let t = Target::Demo(kind.name().to_string());
            let said = t.port_said(kind.describe());
            assert_eq!(said.en, kind.describe());
            assert!(said.zh.starts_with("模拟"), "{}", said.zh);
            assert!(!said.zh.contains("simulated"));
            let zh = t.label_in(Lang::Zh);
            assert!(zh.starts_with("内置模拟"), "{zh}");
            assert!(!zh.contains(kind.name()), "{zh}");
        }
        let port = Target::Port("/dev/ttyUSB0".into());
        assert_eq!(port.port_said("/dev/ttyUSB0").zh, "/dev/ttyUSB0");
        assert_eq!(port.label_in(Lang::Zh), "/dev/ttyUSB0");
    }
}
