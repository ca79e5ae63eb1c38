//! The live values of several servos in one exchange: the vendor SDK's synchronous MONITOR
//! (command 25 with sub-command 22, tests/sdk/README.md). One request names every servo; each
//! answers with its own MONITOR reply, in the order asked. Servos that do not know command 25
//! (older firmware) stay silent.

use crate::link::{ExchangeError, Request, request::SYNC_QUIET};
use crate::ops::Device;
use crate::ops::OpError;
use crate::profile::{Input, Profile, Value};
use crate::protocol::Direction;
use crate::protocol::servo::cmd;
use serde::Serialize;

/// The most servos one synchronous MONITOR can name: the content (3 header bytes and one byte
/// a servo) fits the frame's one-byte length.
pub const MAX_SERVOS: usize = 252;

/// The raw MONITOR angle (0.1°) of the "no data" form: with turns 0, the servo has no reading
/// to give (the vendor SDK 1.3.12, `response_query_servo_monitor`, skips such an answer). Read
/// as an angle it would be -23592959.9°.
pub const NO_DATA_ANGLE: i32 = -235_929_599;

/// Whether a MONITOR answer's raw angle (0.1°) and turns are the "no data" form.
pub fn is_no_data(angle_raw: i64, turns: i64) -> bool {
    angle_raw == i64::from(NO_DATA_ANGLE) && turns == 0
}

/// One servo's MONITOR values, in the profile's display units.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Monitor {
    /// Supply voltage, mV.
    pub voltage_mv: i64,
    /// Current, mA.
    pub current_ma: i64,
    /// Power, mW.
    pub power_mw: i64,
    /// The temperature as the servo sent it (a thermistor reading, or °C: the profile says).
    pub temperature_raw: i64,
    /// The temperature, °C, after the profile's conversion; `None` where it is undefined.
    pub temperature_c: Option<f64>,
    /// The raw status byte (its bit order is published inconsistently).
    pub status: i64,
    /// The multi-turn angle, degrees.
    pub angle_deg: f64,
    /// Whole turns.
    pub turns: i64,
}

/// What a servo answered (JSON: `"answer": "values" | "misfit" | "no_data" | "no_answer"`).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "answer", rename_all = "snake_case")]
pub enum Reading {
    /// Its values.
    Values(Monitor),
    /// Its answer does not fit the profile's MONITOR layout.
    Misfit {
        /// The fault, the values read before it and the raw bytes.
        error: String,
    },
    /// It answered with the "no data" form ([`NO_DATA_ANGLE`], turns 0): no values.
    NoData,
    /// It did not answer.
    NoAnswer,
}

/// A servo asked, and what it answered.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MonitorRow {
    /// The servo id.
    pub id: u8,
    /// What it answered.
    #[serde(flatten)]
    pub reading: Reading,
}

/// The request for the live values of `ids`, in one frame.
pub fn sync_monitor_request(profile: &Profile, ids: &[u8]) -> Result<Request, OpError> {
    let sync = profile.command_by_id(cmd::SYNC_COMMAND).ok_or_else(|| {
        OpError::unknown_command(profile, format!("SYNC_COMMAND ({})", cmd::SYNC_COMMAND))
    })?;
    if ids.is_empty() || ids.len() > MAX_SERVOS {
        return Err(OpError::OutOfRange {
            what: "number of servos in a synchronous MONITOR",
            value: ids.len() as i64,
            min: 1,
            max: MAX_SERVOS as i64,
            note: String::new(),
        });
    }
    for &id in ids {
        super::addressed(id, "read live values")?;
    }
    let mut inputs = vec![(
        "sub_command".to_string(),
        Input::Raw(Value::Int(cmd::MONITOR.into())),
    )];
    for (i, id) in ids.iter().enumerate() {
        inputs.push((
            format!("servo_id[{i}]"),
            Input::Raw(Value::Int((*id).into())),
        ));
    }
    let payload = profile.encode(sync, Direction::HostToDevice, &inputs)?;
    // Each servo answers after the one before: give the first answer as long as the gap. A
    // second attempt only when nothing at all came back.
    Ok(Request::for_command(profile, sync, payload)
        .attempts(2)
        .margin(SYNC_QUIET))
}

/// Reads the live values of every servo in `ids` in one exchange (in frames of up to
/// [`MAX_SERVOS`]). A servo that does not answer has no reading; none answering is not an
/// error (older servos do not know command 25).
pub fn monitor_all(dev: Device<'_>, ids: &[u8]) -> Result<Vec<MonitorRow>, OpError> {
    let Device { client, profile } = dev;
    let mut rows: Vec<MonitorRow> = ids
        .iter()
        .map(|&id| MonitorRow {
            id,
            reading: Reading::NoAnswer,
        })
        .collect();
    for chunk in ids.chunks(MAX_SERVOS) {
        let req = sync_monitor_request(profile, chunk)?;
        let packets = match client.request(req) {
            Ok(reply) => reply.packets,
            Err(ExchangeError::Timeout { .. }) => Vec::new(),
            Err(e) => return Err(e.into()),
        };
        for p in packets {
            let Some(&id) = p.payload.first() else {
                continue;
            };
            if let Some(row) = rows
                .iter_mut()
                .find(|r| r.id == id && r.reading == Reading::NoAnswer)
            {
                row.reading = reading(profile, &p.payload);
            }
        }
    }
    Ok(rows)
}

/// One MONITOR answer as a [`Reading`]: its values, no data, or a misfit naming its bytes.
pub fn reading(profile: &Profile, payload: &[u8]) -> Reading {
    match decode(profile, payload) {
        Ok((_, angle_raw)) if is_no_data(angle_raw.0, angle_raw.1) => Reading::NoData,
        Ok((m, _)) => Reading::Values(m),
        Err(error) => Reading::Misfit { error },
    }
}

/// One MONITOR answer as values; a payload that does not fit is an error naming its bytes.
/// The "no data" form reads as an angle of -23592959.9°: [`reading`] tells it apart.
pub fn read_monitor(profile: &Profile, payload: &[u8]) -> Result<Monitor, String> {
    decode(profile, payload).map(|(m, _)| m)
}

/// The values and the raw (angle 0.1°, turns) of one MONITOR answer.
fn decode(profile: &Profile, payload: &[u8]) -> Result<(Monitor, (i64, i64)), String> {
    let monitor = profile
        .command_by_id(cmd::MONITOR)
        .ok_or_else(|| format!("the profile has no MONITOR ({})", cmd::MONITOR))?;
    let d = profile
        .decode(monitor, Direction::DeviceToHost, payload)
        .map_err(|e| e.to_string())?;
    let int = |ident: &str| {
        d.int(ident)
            .ok_or_else(|| format!("MONITOR has no field '{ident}'"))
    };
    let temperature = d
        .values
        .iter()
        .find(|v| v.ident == "temperature")
        .ok_or("MONITOR has no field 'temperature'")?;
    let angle = d
        .values
        .iter()
        .find(|v| v.ident == "angle")
        .ok_or("MONITOR has no field 'angle'")?;
    let temperature_raw = int("temperature")?;
    let raw = (int("angle")?, int("turns")?);
    let m = Monitor {
        voltage_mv: int("voltage")?,
        current_ma: int("current")?,
        power_mw: int("power")?,
        temperature_raw,
        temperature_c: temperature.field.display_number(temperature_raw),
        status: int("status")?,
        angle_deg: angle.field.display_number(int("angle")?).unwrap_or(0.0),
        turns: int("turns")?,
    };
    Ok((m, raw))
}
