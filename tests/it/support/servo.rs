//! A simulated servo bus on a pseudo-terminal with a link open to it, for the servo tests.

use botbench::link::{Client, Link, LinkOptions, serial};
use botbench::profile::{Profile, Registry};
use botbench::sim::servo_bus::{ServoBus, SimServo};
use botbench::sim::{Faults, PtyServer, SharedDevice};
use std::sync::{Arc, Mutex};

/// The bus, the pty serving it, and a link to it.
pub struct Bench {
    _server: PtyServer,
    /// The simulated bus, to inspect and change.
    pub bus: Arc<Mutex<ServoBus>>,
    /// The link.
    pub link: Link,
    /// The built-in servo profile.
    pub profile: Arc<Profile>,
}

impl Bench {
    /// A bus of `servos`, served at 115200 baud.
    pub fn new(servos: Vec<SimServo>) -> Self {
        Self::with_margin(servos, std::time::Duration::from_millis(5))
    }

    /// The same, the link giving a servo `margin` beyond the wire time to answer (more for a
    /// test whose outcome must not depend on the machine's load).
    pub fn with_margin(servos: Vec<SimServo>, margin: std::time::Duration) -> Self {
        let profile = Registry::builtin().unwrap().get("servo").unwrap();
        let bus = Arc::new(Mutex::new(ServoBus::new(servos)));
        let shared: SharedDevice = bus.clone();
        let server = PtyServer::start(shared, Faults::default()).unwrap();
        let options = LinkOptions {
            // Generous for a loaded test machine; the benchmark uses the default.
            margin: Some(margin),
            ..LinkOptions::default()
        };
        let link = Link::open(
            serial::opener(server.path(), 115_200),
            profile.clone(),
            options,
            None,
        )
        .unwrap();
        Self {
            _server: server,
            bus,
            link,
            profile,
        }
    }

    /// A blocking client of the link.
    pub fn client(&self) -> Client {
        self.link.client()
    }
}
