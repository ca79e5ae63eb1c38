//! Finding a slot's port when the station starts and after its adapter was unplugged: by the
//! USB socket (`/dev/serial/by-path/...`), by the adapter's serial number, or by a plain path.
//! A simulated slot's "port" is a name its caller serves ([`simulated_path`]).

use super::doc::PortLocator;
use crate::system::PortInfo;
use std::path::Path;

/// The name under which the caller serves slot `slot`'s simulated device of `kind`
/// (`simulated:window-cleaner:1`); no file of that name exists.
pub fn simulated_path(kind: &str, slot: &str) -> String {
    format!("simulated:{kind}:{slot}")
}

/// The path to open for `locator` now, given the system's serial ports (`ports`, from
/// [`crate::system::list_ports`]); for a simulated device, [`simulated_path`] of `slot`.
/// Errors: why no port is there, in the words the slot's tile shows (`no adapter at
/// /dev/serial/by-path/...: unplugged?`).
pub fn resolve(locator: &PortLocator, slot: &str, ports: &[PortInfo]) -> Result<String, String> {
    match locator {
        PortLocator::Simulated(kind) => Ok(simulated_path(kind, slot)),
        PortLocator::UsbPath(p) => {
            if Path::new(p).exists() {
                Ok(p.clone())
            } else {
                Err(format!("no adapter at {p}: unplugged?"))
            }
        }
        PortLocator::AdapterSerial(sn) => ports
            .iter()
            .find(|i| i.serial_number.as_deref() == Some(sn.as_str()))
            .map(|i| i.path.clone())
            .ok_or_else(|| format!("no adapter with serial number {sn}: unplugged?")),
        PortLocator::Path(p) => {
            if Path::new(p).exists() || ports.iter().any(|i| &i.path == p) {
                Ok(p.clone())
            } else {
                Err(format!("no port {p}"))
            }
        }
    }
}

/// Whether `locator` needs the system's port list to be found (an adapter's serial number).
pub fn needs_port_list(locator: &PortLocator) -> bool {
    matches!(locator, PortLocator::AdapterSerial(_))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_locator_is_found_or_said_missing() {
        let sim = PortLocator::Simulated("servo-bus".into());
        assert_eq!(resolve(&sim, "2", &[]).unwrap(), "simulated:servo-bus:2");
        let gone = PortLocator::UsbPath("/dev/serial/by-path/no-such-socket".into());
        let e = resolve(&gone, "1", &[]).unwrap_err();
        assert!(e.contains("unplugged"), "{e}");
        let by_sn = PortLocator::AdapterSerial("A10K3X7Q".into());
        assert!(resolve(&by_sn, "1", &[]).is_err());
        let here = tempfile::NamedTempFile::new().unwrap();
        let path = here.path().display().to_string();
        assert_eq!(
            resolve(&PortLocator::Path(path.clone()), "1", &[]).unwrap(),
            path
        );
    }
}
