//! Proof that a firmware update took (TUYA_FIELD_NOTES §5.3): after the last OTA packet the
//! MCU restarts, answers the heartbeat with `00`, and its product info (0x01) names the image's
//! version within 60 s of the end frame; only then is the update done. The ways it fails in the
//! field are each said as what they are: the MCU never comes back, it comes back with its old
//! version, or it never restarts at all.

use super::super::OpError;
use crate::link::session::tuya::parse_product_info;
use crate::link::{
    Client, ExchangeError, LinkCommand, ProductInfo, Request, TuyaEvent, Watch, Watched,
};
use crate::ops::Run;
use crate::protocol::tuya::cmd;
use std::time::{Duration, Instant};

/// How long the MCU has, from the end frame, to come back with the new version: one minute
/// (Tuya's pages "OTA 升级说明" and "MCU OTA 服务", TUYA_FIELD_NOTES §9).
pub const COME_BACK_LIMIT: Duration = Duration::from_secs(60);
/// How often a heartbeat asks whether the MCU is back: every second, as a module does before
/// the first answer (TUYA_FIELD_NOTES §9).
const POLL: Duration = Duration::from_secs(1);
/// How long one heartbeat waits for its answer.
const HEARTBEAT_WAIT: Duration = Duration::from_millis(500);

/// The MCU's product info, asked directly (0x01): `None` when it does not answer.
pub fn product_info(client: &Client) -> Option<ProductInfo> {
    let reply = client
        .request(Request::new(cmd::PRODUCT_INFO, Vec::new()).attempts(2))
        .ok()?;
    Some(parse_product_info(reply.payload().unwrap_or_default()))
}

/// What the MCU did after the end frame.
#[derive(Debug, Clone, PartialEq)]
pub struct CameBack {
    /// Seconds from the end frame to the product info that named its version.
    pub seconds: f64,
    /// The version it now reports.
    pub version: String,
}

/// How the wait for the restart stands.
#[derive(Debug, Default)]
struct Seen {
    /// A heartbeat went unanswered since the end frame (the MCU was restarting).
    silent: bool,
    /// The MCU restarted (a `00` heartbeat answer, to this wait or to the session), and when.
    restarted: Option<Instant>,
}

impl Seen {
    /// Takes what the link said: the session's own heartbeat may see the restart first and
    /// run the handshake, whose product info is then the answer.
    fn take(&mut self, item: Watched) -> Option<ProductInfo> {
        match item {
            Watched::Tuya(TuyaEvent::McuRestarted) => {
                self.restarted.get_or_insert_with(Instant::now);
                None
            }
            Watched::Tuya(TuyaEvent::ProductInfo(info)) if self.restarted.is_some() => Some(info),
            _ => None,
        }
    }
}

/// Waits, after the end frame sent at `ended` (`watch` started before it), until the MCU
/// restarted and its product info names `expected`, at most `limit` from `ended`. Once it
/// restarted, the handshake runs again (the MCU needs it to work, and the window shows the new
/// product info). Errors, as the field has them: never back (no heartbeat answer), never
/// restarted (it answered, never `00`), back with another version, cancelled, link lost.
pub fn await_new_version(
    client: &Client,
    watch: &Watch,
    expected: &str,
    ended: Instant,
    limit: Duration,
    run: &mut Run<'_>,
) -> Result<CameBack, OpError> {
    let deadline = ended + limit;
    let mut seen = Seen::default();
    let mut asked_handshake = false;
    while Instant::now() < deadline {
        run.go_on()?;
        let info = watch.take().into_iter().find_map(|w| seen.take(w));
        if let Some(info) = info {
            return judged(info, expected, ended);
        }
        if seen.restarted.is_none() {
            heartbeat(client, &mut seen)?;
        }
        if seen.restarted.is_some() && !asked_handshake {
            client.send(LinkCommand::Handshake);
            asked_handshake = true;
        }
        let wait = POLL.min(deadline.saturating_duration_since(Instant::now()));
        if let Some(item) = watch.next(wait)
            && let Some(info) = seen.take(item)
        {
            return judged(info, expected, ended);
        }
    }
    let secs = limit.as_secs_f64();
    Err(OpError::Verify(match (seen.restarted, seen.silent) {
        (Some(_), _) => format!(
            "the MCU restarted but gave no product info within {secs:.0} s of the last packet: the update is not proven"
        ),
        (None, true) => format!(
            "the MCU never came back: no heartbeat answer within {secs:.0} s of the last packet"
        ),
        (None, false) => format!(
            "the MCU did not restart within {secs:.0} s of the last packet (it kept answering heartbeats, never 00): the new image is not running"
        ),
    }))
}

/// One heartbeat: `00` is the restart (an answer of `01` after a silence is not: the
/// session's own heartbeat took the `00`, and said so, [`Seen::take`]).
fn heartbeat(client: &Client, seen: &mut Seen) -> Result<(), OpError> {
    let request = Request::new(cmd::HEARTBEAT, Vec::new())
        .margin(HEARTBEAT_WAIT)
        .attempts(1);
    match client.request(request) {
        Ok(r) if r.payload() == Some(&[0][..]) => {
            seen.restarted = Some(Instant::now());
        }
        Ok(_) => {}
        Err(ExchangeError::Disconnected(r)) => {
            return Err(OpError::Verify(format!(
                "link lost while waiting for the MCU to restart: {r}"
            )));
        }
        Err(_) => seen.silent = true,
    }
    Ok(())
}

/// The product info after the restart against the expected version.
fn judged(info: ProductInfo, expected: &str, ended: Instant) -> Result<CameBack, OpError> {
    let seconds = ended.elapsed().as_secs_f64();
    match info.version {
        Some(v) if v == expected => Ok(CameBack {
            seconds,
            version: v,
        }),
        Some(v) => Err(OpError::Verify(format!(
            "the MCU came back after {seconds:.1} s still running version {v}, not {expected}: the update did not take"
        ))),
        None => Err(OpError::Verify(format!(
            "the MCU came back after {seconds:.1} s but its product info names no version ({}): the update is not proven",
            info.raw
        ))),
    }
}
