//! What each protocol's session does beyond exchanges: MSP learns the device from CMD_VERSION.

use crate::profile::Profile;
use crate::protocol::{Direction, msp};
use serde::Serialize;

/// What an MSP device says of itself (CMD_VERSION, CMD_BUILD_INFO).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct DeviceInfo {
    /// The hardware code, which is also the device code of later requests.
    pub hw: u8,
    /// Firmware version, `major.minor.patch`.
    pub firmware: String,
    /// API version, `major.minor`.
    pub api: String,
    /// Build number.
    pub build: u8,
    /// Capability flags (bit 0 config page, 1 PID tuning page, 2 discrete charging-module data,
    /// 3 collision-switch data); `None` from older firmware that sends 7 bytes.
    pub flags: Option<u8>,
    /// Build date and time from CMD_BUILD_INFO, where the device answers it.
    pub build_date: Option<String>,
    /// Bytes past the profile's CMD_VERSION layout (newer firmware), as hex: the device is
    /// identified by the fields it has, and the extra bytes are shown, never dropped silently.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub extra: Option<String>,
}

impl DeviceInfo {
    /// Reads a CMD_VERSION answer with the profile's layout.
    pub fn from_version(profile: &Profile, payload: &[u8]) -> Result<Self, String> {
        let cmd = profile
            .command_by_id(msp::CMD_VERSION)
            .ok_or("the profile has no CMD_VERSION")?;
        // Strict but for bytes past the layout: those are kept in `extra`.
        let d = profile.decode_lenient(cmd, Direction::DeviceToHost, payload);
        if let Some(e) = &d.error {
            return Err(format!(
                "CMD_VERSION answer does not fit the profile: {e}; raw [{}]",
                crate::protocol::hex::format(payload)
            ));
        }
        let v = |i: usize| -> i64 {
            d.values
                .get(i)
                .and_then(|v| match v.value {
                    crate::profile::Value::Int(x) => Some(x),
                    _ => None,
                })
                .unwrap_or(0)
        };
        if d.values.len() < 7 {
            return Err(format!(
                "CMD_VERSION answer too short: {} bytes",
                payload.len()
            ));
        }
        Ok(Self {
            hw: v(0) as u8,
            firmware: format!("{}.{}.{}", v(1), v(2), v(3)),
            api: format!("{}.{}", v(4), v(5)),
            build: v(6) as u8,
            flags: (d.values.len() > 7).then(|| v(7) as u8),
            build_date: None,
            extra: (!d.trailing.is_empty()).then(|| crate::protocol::hex::format(&d.trailing)),
        })
    }

    /// Whether capability bit `bit` is set; firmware without flags supports everything.
    pub fn supports(&self, bit: u8) -> bool {
        self.flags.is_none_or(|f| f >> bit & 1 == 1)
    }
}

/// Reads a CMD_BUILD_INFO answer: 10 date characters, then 8 time characters.
pub fn build_date(payload: &[u8]) -> Option<String> {
    let text = std::str::from_utf8(payload).ok()?;
    if text.len() < 18 || !text.is_char_boundary(10) || !text.is_char_boundary(18) {
        return None;
    }
    Some(format!("{} {}", &text[..10], &text[10..18]))
}
