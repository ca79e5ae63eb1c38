//! The Tuya MCU's misbehaviours as MCUs in the field have them (issue 26, TUYA_FIELD_NOTES):
//! a slow MCU whose reports to a status query come 100-150 ms apart, data points the product's
//! profile does not have, values the profile does not allow, reports sent as 0x22 that wait
//! for the module's 0x23, a firmware that takes writes of report-only data points, answers a
//! frame with a bad checksum or a command it does not know, and an update that fails as
//! updates in the field do ([`OtaFault`]). Each is a [`super::TuyaConfig`] option, and
//! `botbench sim tuya-vacuum` takes each as an option.

use super::TuyaMcu;
use crate::protocol::tuya::cmd;
use crate::protocol::tuya::dp::DpValue;
use std::str::FromStr;
use std::time::{Duration, Instant};

/// How a firmware update fails, as in the field.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OtaFault {
    /// The MCU restarts after the last packet but still runs (and reports) its old version.
    OldVersion,
    /// The MCU never comes back after the last packet: no heartbeat, no product info.
    NeverBack,
    /// The MCU refuses the packet at this offset and every later one (no ack, as the SDK does
    /// with a packet it cannot take).
    RefusePacket(u32),
}

impl FromStr for OtaFault {
    type Err = String;

    /// `old-version`, `never-back`, `refuse-packet:OFFSET`.
    fn from_str(text: &str) -> Result<Self, String> {
        let t = text.trim();
        match t {
            "old-version" => Ok(OtaFault::OldVersion),
            "never-back" => Ok(OtaFault::NeverBack),
            _ => t
                .strip_prefix("refuse-packet:")
                .and_then(|o| o.trim().parse().ok())
                .map(OtaFault::RefusePacket)
                .ok_or_else(|| {
                    format!(
                        "'{t}': expected old-version, never-back or refuse-packet:OFFSET (bytes)"
                    )
                }),
        }
    }
}

/// A value a misbehaving firmware reports, typed as `ID=VALUE` on the command line: a number
/// (for a bool, value, enum or bitmap: its raw value), or `len:N` for a string or raw value of
/// N bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RawValue {
    /// A raw number.
    Int(i64),
    /// A string or raw value of this many bytes.
    Len(usize),
}

/// Reads `ID=VALUE` (`6=150`, `15=len:300`) for `--report-out-of-range`.
pub fn parse_id_value(text: &str) -> Result<(u8, RawValue), String> {
    let bad = || format!("'{text}': expected ID=VALUE such as 6=150, or ID=len:N for a string");
    let (id, value) = text.trim().split_once('=').ok_or_else(bad)?;
    let id = u8::from_str(id.trim()).map_err(|_| bad())?;
    let value = match value.trim().strip_prefix("len:") {
        Some(n) => RawValue::Len(n.trim().parse().map_err(|_| bad())?),
        None => RawValue::Int(value.trim().parse().map_err(|_| bad())?),
    };
    Ok((id, value))
}

/// Reads `ID:TYPE:VALUE` (`101:value:50`, `102:bool:1`, `103:string:abc`) for
/// `--report-unknown-dp`: a data point the product's profile does not have.
pub fn parse_unknown_dp(text: &str) -> Result<(u8, DpValue), String> {
    let bad = || format!("'{text}': expected ID:TYPE:VALUE such as 101:value:50");
    let mut parts = text.trim().splitn(3, ':');
    let (Some(id), Some(ty), Some(v)) = (parts.next(), parts.next(), parts.next()) else {
        return Err(bad());
    };
    let id = u8::from_str(id.trim()).map_err(|_| bad())?;
    let int = || i64::from_str(v.trim()).map_err(|_| bad());
    let value = match ty.trim() {
        "bool" => DpValue::Bool(int()? != 0),
        "value" => DpValue::Value(i32::try_from(int()?).map_err(|_| bad())?),
        "enum" => DpValue::Enum(u8::try_from(int()?).map_err(|_| bad())?),
        "bitmap" => DpValue::Bitmap {
            bits: u32::try_from(int()?).map_err(|_| bad())?,
            width: 4,
        },
        "string" => DpValue::String(v.to_string()),
        "raw" => DpValue::Raw(crate::protocol::hex::parse(v).map_err(|_| bad())?),
        other => {
            return Err(format!(
                "'{text}': type '{other}' is none of bool, value, enum, bitmap, string, raw"
            ));
        }
    };
    Ok((id, value))
}

/// Reads `MIN-MAX` or `MS` milliseconds (`100-150`) for `--report-gap-ms`.
pub fn parse_gap(text: &str) -> Result<(Duration, Duration), String> {
    let bad =
        || format!("'{text}': expected MS or MIN-MAX milliseconds, 1 to 10000, such as 100-150");
    let (a, b) = text
        .trim()
        .split_once('-')
        .unwrap_or((text.trim(), text.trim()));
    let ms = |t: &str| {
        u64::from_str(t.trim())
            .ok()
            .filter(|m| (1..=10_000).contains(m))
            .ok_or_else(bad)
    };
    let (a, b) = (ms(a)?, ms(b)?);
    if a > b {
        return Err(bad());
    }
    Ok((Duration::from_millis(a), Duration::from_millis(b)))
}

impl TuyaMcu {
    /// The delays of a burst of `n` reports: at once (after the latency) from a quick MCU;
    /// `report_gap` apart (each drawn between its bounds) from a slow one.
    pub(super) fn burst_delays(&mut self, n: usize) -> Vec<Duration> {
        let latency = self.config.latency;
        let Some((lo, hi)) = self.config.report_gap else {
            return vec![latency; n];
        };
        let mut at = latency;
        (0..n)
            .map(|i| {
                if i > 0 {
                    let span = (hi - lo).as_micros() as u64;
                    at += lo + Duration::from_micros(self.rng.u64(0..=span));
                }
                at
            })
            .collect()
    }

    /// One data point's report data (`dpid, type, len, value`): the value it holds, or the
    /// firmware's impossible one when it has one (`report_out_of_range`: a bool byte other than
    /// 0 and 1 included), in the misreporting firmware's form when it has one.
    pub(super) fn report_data_of(&self, id: u8) -> Option<Vec<u8>> {
        if let (Some(DpValue::Bool(_)), Some(RawValue::Int(v))) =
            (self.dps.get(&id), self.config.report_out_of_range.get(&id))
        {
            return Some(vec![id, 1, 0, 1, *v as u8]);
        }
        let value = self.reported_value(id)?;
        Some(super::sdk::report_data(id, &value, &self.config.misreport))
    }

    /// The value reported for data point `id`: the firmware's impossible one when it has one
    /// (`report_out_of_range`), else the one it holds.
    fn reported_value(&self, id: u8) -> Option<DpValue> {
        let held = self.dps.get(&id)?;
        let Some(raw) = self.config.report_out_of_range.get(&id) else {
            return Some(held.clone());
        };
        Some(match (held, raw) {
            (DpValue::Value(_), RawValue::Int(v)) => DpValue::Value(*v as i32),
            (DpValue::Enum(_), RawValue::Int(v)) => DpValue::Enum(*v as u8),
            (DpValue::Bitmap { .. }, RawValue::Int(v)) => DpValue::Bitmap {
                bits: *v as u32,
                width: 4,
            },
            (DpValue::String(_), RawValue::Len(n)) => DpValue::String("x".repeat(*n)),
            (DpValue::Raw(_), RawValue::Len(n)) => DpValue::Raw(vec![0xA5; *n]),
            (held, _) => held.clone(),
        })
    }

    /// The report frames of the data points the profile lacks (`report_unknown_dp`).
    pub(super) fn unknown_reports(&self) -> Vec<Vec<u8>> {
        self.config
            .report_unknown_dp
            .iter()
            .filter_map(|(id, v)| {
                let mut data = Vec::new();
                crate::protocol::tuya::dp::encode_one(
                    &crate::protocol::tuya::dp::DataPoint {
                        id: *id,
                        value: v.clone(),
                    },
                    &mut data,
                )
                .ok()?;
                self.encode(cmd::DP_REPORT, data)
            })
            .collect()
    }

    /// A report the MCU sends on its own: as 0x07, or, with `sync_reports`, as 0x22 queued
    /// behind the one awaiting the module's 0x23 (the MCU sends the next only after it).
    pub(super) fn own_report(&mut self, id: u8) {
        if !self.config.sync_reports {
            if let Some(f) = self.report(id) {
                self.outbox.push_back(f);
            }
            return;
        }
        if let Some(data) = self.report_data_of(id) {
            self.sync.queue.push_back(data);
        }
    }

    /// The next synchronous report, when none awaits its answer; one whose answer did not
    /// come within 5 s is sent again (TUYA_FIELD_NOTES §2: the MCU waits more than 5 s).
    pub(super) fn next_sync(&mut self, now: Instant) -> Option<Vec<u8>> {
        match self.sync.awaiting {
            Some((_, since)) if now.saturating_duration_since(since) < SYNC_WAIT => None,
            Some((ref data, _)) => {
                let data = data.clone();
                self.sync.awaiting = Some((data.clone(), now));
                self.encode(cmd::DP_REPORT_SYNC, data)
            }
            None => {
                let data = self.sync.queue.pop_front()?;
                self.sync.awaiting = Some((data.clone(), now));
                self.encode(cmd::DP_REPORT_SYNC, data)
            }
        }
    }

    /// The module's 0x23: the synchronous report awaiting it is done (whatever the result: a
    /// failure is recorded, and the next report follows).
    pub(super) fn sync_result(&mut self, data: &[u8]) {
        if self.sync.awaiting.take().is_some() {
            self.sync.results.push(data.first().copied().unwrap_or(0));
        }
    }

    /// The results (0x23 data bytes: 1 success, 0 failure) the module gave the MCU's
    /// synchronous reports, oldest first.
    pub fn sync_results(&self) -> &[u8] {
        &self.sync.results
    }
}

/// How long the MCU waits for the module's 0x23 before it sends its 0x22 again.
const SYNC_WAIT: Duration = Duration::from_secs(5);

/// The MCU's synchronous reports (0x22): those waiting to be sent, the one awaiting the
/// module's answer (its data, when it was sent), and the module's results.
#[derive(Debug, Default)]
pub(super) struct Sync {
    queue: std::collections::VecDeque<Vec<u8>>,
    awaiting: Option<(Vec<u8>, Instant)>,
    results: Vec<u8>,
}
