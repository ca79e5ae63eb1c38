//! A simulated servo bus on a pseudo-terminal with a link open to it, for the servo tests.

use super::{Served, open_link, profile, serve};
use botbench::link::{Client, Link, LinkOptions};
use botbench::profile::Profile;
use botbench::sim::servo_bus::{ServoBus, SimServo};
use std::sync::{Arc, MutexGuard};

/// The bus, the pty serving it, and a link to it with the servo protocol's own answer margin.
/// The link closes first.
pub struct Bench {
    /// The link.
    pub link: Link,
    /// The simulated bus on its pty.
    pub served: Served<ServoBus>,
    /// The built-in servo profile.
    pub profile: Arc<Profile>,
}

impl Bench {
    /// A bus of `servos`, served at 115200 baud.
    pub fn new(servos: Vec<SimServo>) -> Self {
        let profile = profile("servo");
        let served = serve(ServoBus::new(servos));
        let link = open_link(&served, 115_200, profile.clone(), LinkOptions::default());
        Self {
            link,
            served,
            profile,
        }
    }

    /// A blocking client of the link.
    pub fn client(&self) -> Client {
        self.link.client()
    }

    /// The simulated bus, locked.
    pub fn bus(&self) -> MutexGuard<'_, ServoBus> {
        self.served.sim()
    }

    /// The servo with serial number `serial`, as it is now.
    pub fn servo(&self, serial: u32) -> SimServo {
        self.served.servo(serial)
    }
}

impl Served<ServoBus> {
    /// The servo with serial number `serial`, as it is now.
    pub fn servo(&self, serial: u32) -> SimServo {
        self.sim()
            .servo_by_serial(serial)
            .unwrap_or_else(|| panic!("no servo {serial} on the bus"))
            .clone()
    }
}
