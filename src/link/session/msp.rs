//! The MSP session: identifies the device once per connection (CMD_VERSION to the core device
//! code, then CMD_BUILD_INFO), learns the device code later requests go to where the profile
//! says `Auto`, and keeps the result for whoever asks ([`crate::link::Client::device_info`]).

use crate::i18n::Text;
use crate::link::LinkEvent;
use crate::link::request::{ExchangeError, Reply, Request};
use crate::profile::{DeviceCode, Profile};
use crate::protocol::{Direction, msp};
use crossbeam_channel::Sender;
use serde::Serialize;
use std::sync::Arc;

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
    /// Capability flags, named by the profile's CMD_VERSION `flags` field ([`Capability`]);
    /// `None` from older firmware that sends 7 bytes.
    pub flags: Option<u8>,
    /// Build date and time from CMD_BUILD_INFO, where the device answers it.
    pub build_date: Option<String>,
    /// Bytes past the profile's CMD_VERSION layout (newer firmware), as hex: the device is
    /// identified by the fields it has, and the extra bytes are shown, never dropped silently.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub extra: Option<String>,
}

impl DeviceInfo {
    /// Reads a CMD_VERSION answer with the profile's layout (at least 7 fields: hardware code,
    /// firmware major, minor and patch, API major and minor, build; then optional flags).
    ///
    /// Errors: the profile has no CMD_VERSION, the payload does not decode with its layout, or
    /// it has fewer than 7 fields.
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

/// One capability bit of a CMD_VERSION `flags` byte.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Capability {
    /// The bit, 0-7.
    pub bit: u8,
    /// Its name from the profile (`bit N` / `第 N 位` for a set bit the profile does not name).
    pub name: Text,
    /// Whether the device reports it set.
    pub set: bool,
}

/// The capability bits of `flags` as the profile's CMD_VERSION `flags` field names them: each
/// named bit, and each set bit it does not name, in bit order.
pub fn capabilities(profile: &Profile, flags: u8) -> Vec<Capability> {
    let set = |bit: u8| flags >> bit & 1 == 1;
    let named: Vec<Capability> = profile
        .command_by_id(msp::CMD_VERSION)
        .and_then(|c| c.reply.iter().find(|f| f.ident == "flags"))
        .map(|f| {
            f.bits
                .iter()
                .filter(|b| b.bit < 8)
                .map(|b| Capability {
                    bit: b.bit,
                    name: b.name.clone(),
                    set: set(b.bit),
                })
                .collect()
        })
        .unwrap_or_default();
    let mut out = named.clone();
    for bit in (0..8u8).filter(|&b| set(b) && !named.iter().any(|c| c.bit == b)) {
        out.push(Capability {
            bit,
            name: Text {
                en: format!("bit {bit}"),
                zh: format!("第 {bit} 位"),
            },
            set: true,
        });
    }
    out.sort_by_key(|c| c.bit);
    out
}

/// Reads a CMD_BUILD_INFO answer: 10 date characters, then 8 time characters (such as
/// `2024-05-0112:30:00`), as `date time`; `None` when the payload is shorter or not UTF-8.
pub fn build_date(payload: &[u8]) -> Option<String> {
    let text = std::str::from_utf8(payload).ok()?;
    if text.len() < 18 || !text.is_char_boundary(10) || !text.is_char_boundary(18) {
        return None;
    }
    Some(format!("{} {}", &text[..10], &text[10..18]))
}

/// A caller of [`crate::link::Client::device_info`], waiting for this connection's
/// identification.
pub(crate) type InfoWaiter = Sender<Result<DeviceInfo, ExchangeError>>;

/// The MSP session of one link: where the identification of the current connection stands.
#[derive(Debug)]
pub(crate) struct MspSession {
    profile: Arc<Profile>,
    /// The device code requests go to when they name none: the profile's, or, where the
    /// profile says `Auto`, the hardware code CMD_VERSION answered.
    device_code: u8,
    /// Identify on every new connection ([`crate::link::LinkOptions::start_session`]).
    identify_on_connect: bool,
    state: Identify,
    /// Callers waiting for the identification under way.
    waiters: Vec<InfoWaiter>,
    /// The device on this connection identified as hardware this profile is not for (its `hw`
    /// code): nothing but identification is sent to it ([`Self::refuses`]).
    misfit: Option<u8>,
}

/// Where the identification of the current connection stands.
#[derive(Debug)]
enum Identify {
    /// Not asked on this connection.
    NotAsked,
    /// `Ask` is to be sent before the next caller's request.
    Due(Ask),
    /// `Ask` is sent; its answer is awaited.
    Asked(Ask),
    /// Finished for this connection: kept, and given to whoever asks.
    Done(Result<DeviceInfo, ExchangeError>),
}

/// A request of the identification.
#[derive(Debug)]
enum Ask {
    /// CMD_VERSION, to the core device code.
    Version,
    /// CMD_BUILD_INFO, after CMD_VERSION answered this.
    BuildInfo(DeviceInfo),
}

impl MspSession {
    /// A session for `profile`; identifies the device at once when `identify_on_connect`.
    pub(crate) fn new(profile: Arc<Profile>, identify_on_connect: bool) -> Self {
        let device_code = profile
            .device_code
            .map_or(msp::DEVICE_CORE, DeviceCode::initial);
        let mut session = Self {
            profile,
            device_code,
            identify_on_connect,
            state: Identify::NotAsked,
            waiters: Vec::new(),
            misfit: None,
        };
        session.connected();
        session
    }

    /// Why `command` is not sent: the device identified as hardware the profile is not for, and
    /// the request is not one of the identification's (ping, version, build information).
    pub(crate) fn refuses(&self, command: u8) -> Option<ExchangeError> {
        let hw = self.misfit?;
        if matches!(
            command,
            msp::CMD_PING | msp::CMD_VERSION | msp::CMD_BUILD_INFO
        ) {
            return None;
        }
        Some(ExchangeError::NotThisDevice {
            command: command.into(),
            hw,
            claimed: self.profile.device_code.map_or(0, DeviceCode::initial),
            profile: self.profile.id.clone(),
        })
    }

    /// The device code of requests that name none.
    pub(crate) fn device_code(&self) -> u8 {
        self.device_code
    }

    /// A new connection (the first, or after a reconnect): its device is identified afresh.
    pub(crate) fn connected(&mut self) {
        self.misfit = None;
        self.state = if self.identify_on_connect {
            Identify::Due(Ask::Version)
        } else {
            Identify::NotAsked
        };
    }

    /// The port went away: callers waiting are told `err`. An identification under way
    /// finishes with the error of its exchange.
    pub(crate) fn lost(&mut self, err: &ExchangeError) {
        self.answer_waiters(&Err(err.clone()));
        if !matches!(self.state, Identify::Asked(_)) {
            self.state = Identify::NotAsked;
        }
    }

    /// The link closes: callers waiting are told `err`.
    pub(crate) fn closed(&mut self, err: &ExchangeError) {
        self.answer_waiters(&Err(err.clone()));
    }

    /// A caller wants this connection's identification: it gets it at once when it is known,
    /// else when the identification under way (or started now) ends. A failed identification is
    /// tried again rather than handed out.
    pub(crate) fn want_device_info(&mut self, waiter: InfoWaiter) {
        match &self.state {
            Identify::Done(Ok(info)) => {
                let _ = waiter.send(Ok(info.clone()));
                return;
            }
            Identify::Done(Err(_)) | Identify::NotAsked => self.state = Identify::Due(Ask::Version),
            Identify::Due(_) | Identify::Asked(_) => {}
        }
        self.waiters.push(waiter);
    }

    fn answer_waiters(&mut self, result: &Result<DeviceInfo, ExchangeError>) {
        for waiter in self.waiters.drain(..) {
            let _ = waiter.send(result.clone());
        }
    }

    /// [`crate::link::LinkCommand::Identify`]: identify again before the next request.
    pub(crate) fn identify_again(&mut self) {
        self.state = Identify::Due(Ask::Version);
    }

    /// Whether a request of the identification is to be sent.
    pub(crate) fn due(&self) -> bool {
        matches!(self.state, Identify::Due(_))
    }

    /// The identification's next request, if one is due; its answer is then awaited.
    pub(crate) fn next_request(&mut self) -> Option<Request> {
        let request = match &self.state {
            Identify::Due(Ask::Version) => Request::new(msp::CMD_VERSION, Vec::new())
                .device(msp::DEVICE_CORE)
                .attempts(2),
            Identify::Due(Ask::BuildInfo(_)) => {
                Request::new(msp::CMD_BUILD_INFO, Vec::new()).attempts(1)
            }
            _ => return None,
        };
        if let Identify::Due(ask) = std::mem::replace(&mut self.state, Identify::NotAsked) {
            self.state = Identify::Asked(ask);
        }
        Some(request)
    }

    /// The result of the request [`Self::next_request`] gave. Returns whether another request
    /// follows at once; `events` gets [`LinkEvent::Identified`] when the identification ends.
    /// A CMD_BUILD_INFO the device does not answer leaves the build date out.
    pub(crate) fn on_answer(
        &mut self,
        result: Result<Reply, ExchangeError>,
        events: &mut Vec<LinkEvent>,
    ) -> bool {
        let Identify::Asked(ask) = std::mem::replace(&mut self.state, Identify::NotAsked) else {
            return false;
        };
        match ask {
            Ask::Version => {
                let info = result.and_then(|r| {
                    DeviceInfo::from_version(&self.profile, r.payload().unwrap_or_default())
                        .map_err(|reason| ExchangeError::Unreadable {
                            command: msp::CMD_VERSION.into(),
                            reason,
                        })
                });
                match info {
                    Ok(info) => {
                        if let Some(DeviceCode::Auto(claimed)) = self.profile.device_code {
                            // An `Auto` code names the hardware the profile is for; another
                            // kind of device gets nothing written (PROTOCOL_NOTES §1: 0x03 the
                            // window cleaner, 0x04 the solar cleanbot).
                            self.misfit = (info.hw != claimed).then_some(info.hw);
                            // Its core requests (ping) go to the code it gave.
                            self.device_code = info.hw;
                        }
                        self.state = Identify::Due(Ask::BuildInfo(info));
                        true
                    }
                    Err(e) => {
                        self.finish(Err(e), events);
                        false
                    }
                }
            }
            Ask::BuildInfo(mut info) => {
                if let Ok(r) = result {
                    info.build_date = build_date(r.payload().unwrap_or_default());
                }
                self.finish(Ok(info), events);
                false
            }
        }
    }

    fn finish(&mut self, result: Result<DeviceInfo, ExchangeError>, events: &mut Vec<LinkEvent>) {
        let result = result.map_err(|e| e.named(&self.profile));
        self.answer_waiters(&result);
        events.push(LinkEvent::Identified(result.clone()));
        self.state = Identify::Done(result);
    }
}
