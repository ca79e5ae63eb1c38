//! What the two MSP simulators share: request decoding, device-code filtering, the core commands
//! (PING, VERSION, BUILD_INFO), and replies encoded with the profile's own field codec, so that a
//! reply is exactly what the profile says.

use super::Outgoing;
use crate::profile::{Command, Decoded, Input, Profile, Registry, Value};
use crate::protocol::Direction;
use crate::protocol::msp::{
    CMD_BUILD_INFO, CMD_PING, CMD_VERSION, DEVICE_CORE, Reply, ReplyKind, Request, RequestDecoder,
};
use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};

/// A device's default answer latency: how long after a request's last byte its reply starts.
pub const DEFAULT_LATENCY: Duration = Duration::from_micros(100);

/// A built-in profile by id, parsed once.
pub fn builtin_profile(id: &str) -> Result<Arc<Profile>, String> {
    static REGISTRY: OnceLock<Result<Registry, String>> = OnceLock::new();
    let reg = REGISTRY
        .get_or_init(|| Registry::builtin().map_err(|e| e.to_string()))
        .as_ref()
        .map_err(Clone::clone)?;
    reg.get(id).map_err(|e| e.to_string())
}

/// What CMD_VERSION and CMD_BUILD_INFO answer.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Identity {
    /// Firmware major, minor, patch.
    pub fw: (u8, u8, u8),
    /// API major, minor.
    pub api: (u8, u8),
    /// Build number.
    pub build: u8,
    /// Capability flags (the 8th byte); `None` answers 7 bytes, as older firmware does.
    pub flags: Option<u8>,
    /// Build date, 10 characters (`2024-05-17`).
    pub date: String,
    /// Build time, 8 characters (`14:03:52`).
    pub time: String,
}

impl Default for Identity {
    fn default() -> Self {
        Self {
            fw: (1, 4, 2),
            api: (1, 2),
            build: 37,
            flags: Some(0x0F),
            date: "2024-05-17".into(),
            time: "14:03:52".into(),
        }
    }
}

/// What a model answers a request with.
#[derive(Debug, Clone, PartialEq)]
pub enum Answer {
    /// A reply whose payload is built from these values by the profile's reply layout.
    Fields(Vec<(String, Input)>),
    /// A simple response (an ack with no data).
    Ack,
    /// No answer (unknown command, refused value).
    Nothing,
}

impl Answer {
    /// A reply from raw integers, by field ident.
    pub fn ints<'a>(pairs: impl IntoIterator<Item = (&'a str, i64)>) -> Self {
        Answer::Fields(
            pairs
                .into_iter()
                .map(|(k, v)| (k.to_string(), Input::Raw(Value::Int(v))))
                .collect(),
        )
    }

    /// A one-field reply of bytes.
    pub fn bytes(ident: &str, bytes: Vec<u8>) -> Self {
        Answer::Fields(vec![(ident.to_string(), Input::Raw(Value::Bytes(bytes)))])
    }
}

/// An unsolicited frame (kind 0xFE) a board pushes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AsyncFrame {
    /// Its command number.
    pub command: u8,
    /// Its payload.
    pub payload: Vec<u8>,
}

/// How an MSP board misbehaves in the field (PROTOCOL_NOTES §4). `Default`: as documented.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MspQuirks {
    /// Before each reply, an unsolicited frame of the same command with this payload (a board
    /// that reports a value on its own just as it is asked for it).
    pub async_before_reply: Option<Vec<u8>>,
    /// This frame, pushed on its own every period.
    pub async_every: Option<(Duration, AsyncFrame)>,
    /// Replies to these commands fail their checksum (a firmware bug, a noisy line).
    pub garble: Vec<u8>,
    /// The hardware code CMD_VERSION gives, which is also the device code the board answers,
    /// instead of the board's own: another board on the same framing (one no profile claims).
    pub hardware_code: Option<u8>,
}

impl MspQuirks {
    fn async_frame(command: u8, payload: Vec<u8>, after: Duration) -> Option<Outgoing> {
        let frame = Reply {
            kind: ReplyKind::Async,
            command,
            data: payload,
        };
        frame.encode().ok().map(|b| Outgoing::new(after, b))
    }
}

/// The MSP plumbing of one simulated device.
#[derive(Debug, Clone)]
pub struct MspCore {
    /// The profile whose layouts replies follow.
    pub profile: Arc<Profile>,
    /// The device code this device answers (besides 0x00, the core code).
    pub code: u8,
    /// The baud rate the device's UART runs at; bytes sent at another rate are garbage to it.
    pub baud: u32,
    /// The answer latency.
    pub latency: Duration,
    /// VERSION and BUILD_INFO contents.
    pub identity: Identity,
    /// The last reply the profile could not encode (a simulator bug): for tests.
    pub last_error: Option<String>,
    /// How it misbehaves.
    pub quirks: MspQuirks,
    /// When the next pushed frame is due.
    next_push: Option<Instant>,
    decoder: RequestDecoder,
}

impl MspCore {
    /// Plumbing for `profile`, answering device `code` as `opts` ask: their baud rate (else the
    /// profile's), reply latency and the field's quirks.
    pub fn with_options(profile: Arc<Profile>, code: u8, opts: &super::SimOptions) -> Self {
        let baud = opts.baud.unwrap_or(profile.baud);
        let code = opts.msp.hardware_code.unwrap_or(code);
        let mut core = Self::new(profile, code, baud);
        if let Some(l) = opts.latency {
            core.latency = l;
        }
        core.quirks = opts.msp.clone();
        core
    }

    /// Plumbing for `profile`, answering device `code` at `baud`.
    pub fn new(profile: Arc<Profile>, code: u8, baud: u32) -> Self {
        Self {
            profile,
            code,
            baud,
            latency: DEFAULT_LATENCY,
            identity: Identity::default(),
            last_error: None,
            quirks: MspQuirks::default(),
            next_push: None,
            decoder: RequestDecoder::new(),
        }
    }

    /// The frames pushed on their own by `now` ([`MspQuirks::async_every`]); call from
    /// [`super::Device::tick`].
    pub fn pushes(&mut self, now: Instant) -> Vec<Outgoing> {
        let Some((period, frame)) = self.quirks.async_every.clone() else {
            return Vec::new();
        };
        let due = *self.next_push.get_or_insert(now + period);
        if now < due {
            return Vec::new();
        }
        self.next_push = Some(now + period.max(Duration::from_millis(1)));
        MspQuirks::async_frame(frame.command, frame.payload, Duration::ZERO)
            .into_iter()
            .collect()
    }

    /// The requests addressed to this device in `bytes` (received at `baud`). Bytes at another
    /// baud rate are noise to the UART: they are dropped, with any partial frame.
    pub fn requests(&mut self, bytes: &[u8], baud: u32) -> Vec<Request> {
        if baud != self.baud {
            self.decoder.clear();
            return Vec::new();
        }
        self.decoder.push(bytes);
        let mut out = Vec::new();
        for item in self.decoder.by_ref() {
            if let Ok(req) = item
                && (req.device == self.code || req.device == DEVICE_CORE)
            {
                out.push(req);
            }
        }
        out
    }

    /// The answer when the core settles `req`: a core command, or nothing for any other command
    /// sent to device 0x00. `None` when the device's own model must answer.
    pub fn core_answer(&self, req: &Request) -> Option<Answer> {
        let id = &self.identity;
        Some(match req.command {
            CMD_PING => Answer::Ack,
            CMD_VERSION => {
                let mut a = vec![
                    ("hw", i64::from(self.code)),
                    ("fwMajor", i64::from(id.fw.0)),
                    ("fwMinor", i64::from(id.fw.1)),
                    ("fwPatch", i64::from(id.fw.2)),
                    ("apiMajor", i64::from(id.api.0)),
                    ("apiMinor", i64::from(id.api.1)),
                    ("build", i64::from(id.build)),
                ];
                if let Some(flags) = id.flags {
                    a.push(("flags", i64::from(flags)));
                }
                Answer::ints(a)
            }
            CMD_BUILD_INFO => Answer::Fields(vec![
                ("date".into(), Input::Raw(Value::Text(fixed(&id.date, 10)))),
                ("time".into(), Input::Raw(Value::Text(fixed(&id.time, 8)))),
            ]),
            _ if req.device == DEVICE_CORE => Answer::Nothing,
            _ => return None,
        })
    }

    /// The command of the profile with this number.
    pub fn command(&self, id: u8) -> Option<&Command> {
        self.profile.command_by_id(id)
    }

    /// Decodes a request's payload by the profile (a Set's payload is its Get's reply layout).
    pub fn decode_request<'p>(&'p self, req: &Request) -> Option<Decoded<'p>> {
        let cmd = self.command(req.command)?;
        self.profile
            .decode(cmd, Direction::HostToDevice, &req.data)
            .ok()
    }

    /// Turns an answer into the frame to send, honouring option 0xFE (act, no answer).
    pub fn respond(&mut self, req: &Request, answer: Answer, out: &mut Vec<Outgoing>) {
        if !req.wants_answer() {
            return;
        }
        let data = match answer {
            Answer::Nothing => return,
            Answer::Ack => Vec::new(),
            Answer::Fields(inputs) => {
                let Some(cmd) = self.profile.command_by_id(req.command) else {
                    self.last_error =
                        Some(format!("command {} is not in the profile", req.command));
                    return;
                };
                match self.profile.encode(cmd, Direction::DeviceToHost, &inputs) {
                    Ok(data) => data,
                    Err(e) => {
                        self.last_error = Some(format!("{}: {e}", cmd.ident));
                        return;
                    }
                }
            }
        };
        if let Some(payload) = &self.quirks.async_before_reply {
            out.extend(MspQuirks::async_frame(
                req.command,
                payload.clone(),
                self.latency,
            ));
        }
        match Reply::new(req.command, data).encode() {
            Ok(mut bytes) => {
                if self.quirks.garble.contains(&req.command)
                    && let Some(crc) = bytes.last_mut()
                {
                    *crc ^= 0x01;
                }
                out.push(Outgoing::new(self.latency, bytes));
            }
            Err(e) => self.last_error = Some(e.to_string()),
        }
    }
}

/// `text` cut or space-padded to exactly `n` bytes (ASCII expected).
fn fixed(text: &str, n: usize) -> String {
    let mut s: String = text.chars().filter(char::is_ascii).take(n).collect();
    while s.len() < n {
        s.push(' ');
    }
    s
}

/// An MSP robot built on an [`MspCore`]: its own state moves on with time, and it answers what
/// the core does not (the core answers CMD_VERSION and the commands every device shares).
pub trait MspRobot {
    /// The core.
    fn msp_core(&mut self) -> &mut MspCore;
    /// Moves its state on to `now`.
    fn advance(&mut self, now: Instant);
    /// Its answer to `req`, a command of its own.
    fn answer(&mut self, req: &Request, now: Instant) -> Answer;
}

/// [`super::Device::receive`] for an MSP robot: the bytes that arrived at `now`, at `baud`, and
/// the replies they bring.
pub fn receive<R: MspRobot>(robot: &mut R, bytes: &[u8], baud: u32, now: Instant) -> Vec<Outgoing> {
    robot.advance(now);
    let mut out = Vec::new();
    for req in robot.msp_core().requests(bytes, baud) {
        let answer = match robot.msp_core().core_answer(&req) {
            Some(a) => a,
            None => robot.answer(&req, now),
        };
        robot.msp_core().respond(&req, answer, &mut out);
    }
    out
}

/// Tests: asks `device` (code `code`) `command` with `data` at `now`; its first reply.
#[cfg(test)]
pub(crate) fn ask(
    device: &mut dyn super::Device,
    code: u8,
    command: u8,
    data: Vec<u8>,
    now: Instant,
) -> Option<crate::protocol::msp::Reply> {
    let bytes = Request::new(code, command, data).encode().ok()?;
    let out = device.receive(&bytes, 115_200, now);
    let mut dec = crate::protocol::msp::ReplyDecoder::new();
    dec.push(&out.first()?.bytes);
    dec.next()?.ok()
}

/// The raw default of every field of `cmd`'s reply, by ident (`fallback` where none is given).
pub fn reply_defaults(cmd: &Command, fallback: i64) -> Vec<(String, i64)> {
    cmd.reply
        .iter()
        .map(|f| (f.ident.clone(), f.default.unwrap_or(fallback)))
        .collect()
}

/// Clamps a float to a field's integer type range and rounds it.
pub fn clamp_i(x: f64, lo: i64, hi: i64) -> i64 {
    if x.is_nan() {
        return lo.max(0).min(hi);
    }
    (x.round() as i64).clamp(lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::msp::{OPTION_SILENT, ReplyDecoder};

    fn core() -> MspCore {
        MspCore::new(builtin_profile("window-cleaner").unwrap(), 3, 115200)
    }

    fn answer(core: &mut MspCore, req: Request) -> Vec<Outgoing> {
        let bytes = req.encode().unwrap();
        let mut out = Vec::new();
        for r in core.requests(&bytes, 115200) {
            let a = core.core_answer(&r).unwrap_or(Answer::Nothing);
            core.respond(&r, a, &mut out);
        }
        out
    }

    fn reply(out: &[Outgoing]) -> Reply {
        let mut d = ReplyDecoder::new();
        d.push(&out[0].bytes);
        d.next().unwrap().unwrap()
    }

    #[test]
    fn version_to_the_core_code_names_the_device_code() {
        let mut c = core();
        let out = answer(&mut c, Request::new(0, CMD_VERSION, vec![]));
        assert_eq!(out.len(), 1);
        let r = reply(&out);
        assert_eq!(r.command, CMD_VERSION);
        assert_eq!(r.data, vec![3, 1, 4, 2, 1, 2, 37, 0x0F]);
        assert_eq!(c.last_error, None);
    }

    #[test]
    fn build_info_is_ten_and_eight_characters() {
        let mut c = core();
        c.identity.date = "2024-1-2".into();
        let out = answer(&mut c, Request::new(3, CMD_BUILD_INFO, vec![]));
        let r = reply(&out);
        assert_eq!(r.data.len(), 18);
        assert_eq!(&r.data[..10], b"2024-1-2  ");
    }

    #[test]
    fn other_devices_wrong_baud_and_silent_option_get_nothing() {
        let mut c = core();
        assert!(answer(&mut c, Request::new(4, CMD_PING, vec![])).is_empty());
        let silent = Request {
            option: OPTION_SILENT,
            ..Request::new(3, CMD_PING, vec![])
        };
        assert!(answer(&mut c, silent).is_empty());
        let bytes = Request::new(3, CMD_PING, vec![]).encode().unwrap();
        assert!(c.requests(&bytes, 9600).is_empty());
        let ping = answer(&mut c, Request::new(3, CMD_PING, vec![]));
        assert_eq!(reply(&ping).data, Vec::<u8>::new());
    }
}
