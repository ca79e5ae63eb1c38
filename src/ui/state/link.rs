//! The link as the window sees it: what it is connected to, its state and counters as the worker
//! last reported them, how it was opened, and the serial ports there are.

use crate::link::serial::{self, PortInfo};
use crate::link::{Link, LinkOptions, LinkState, LinkStats};
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
}

/// An open link and what it talks to.
pub struct Connection {
    /// The worker.
    pub link: Link,
    /// What it talks to.
    pub target: Target,
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
    /// The link has just come up (first connect or a reconnect): the app reads the device.
    pub just_connected: bool,
    /// Serial ports, refreshed every second.
    pub ports: Vec<PortInfo>,
    ports_at: Option<Instant>,
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
            self.ports = serial::list_ports();
            self.ports_at = Some(Instant::now());
        }
    }

    /// Re-lists the serial ports now (after a port's setting changed).
    pub fn refresh_ports_now(&mut self) {
        self.ports_at = None;
        self.refresh_ports();
    }

    /// The USB adapter of the port the link is open on, as last listed.
    pub fn adapter(&self) -> Option<(&str, &crate::link::adapter::Adapter)> {
        let Some(Target::Port(path)) = self.target() else {
            return None;
        };
        self.ports
            .iter()
            .find(|p| &p.path == path)
            .map(|p| (p.path.as_str(), &p.adapter))
    }

    /// A fresh id for a request whose result comes back as a `LinkEvent::Reply` (kept in
    /// [`super::DeviceModel::replies`]).
    pub fn reply_id(&self) -> u64 {
        static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
        NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
    }
}
