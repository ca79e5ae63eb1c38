//! Telemetry behind a bad USB adapter (issue 25, item 8): a 16 ms latency timer, 5 % of frames
//! lost and 5 % corrupted. The window must poll at least 80 % of what `msp watch` achieves on
//! the same simulator: both are measured here through the link as each drives it (the same
//! worker, sessions and polls), each on a fresh simulator with the same fault dice.

use super::{Figure, open, profile};
use crate::link::{Link, LinkCommand, LinkEvent, LinkOptions, Poll, wire_time};
use crate::sim::window_cleaner::WindowCleaner;
use crate::sim::{Faults, Line, PtyServer, SharedDevice, SimOptions};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The adapter the issue measured on: a 16 ms latency timer, 5 % drops, 5 % corruption.
fn bad_adapter() -> Faults {
    Faults {
        drop: 0.05,
        corrupt: 0.05,
        seed: 25,
        line: Line {
            latency_timer: Some(Duration::from_millis(16)),
            ..Line::default()
        },
        ..Faults::default()
    }
}

/// Who polls: `msp watch MSP_ATTITUDE` (its defaults: as fast as the wire allows, no
/// reconnect), or the window's Telemetry panel (its defaults: the profile's plotted commands at
/// 50 Hz and the other telemetry at 1 Hz, reconnecting).
#[derive(Clone, Copy, PartialEq)]
enum Poller {
    Watch,
    Window,
}

/// What one poller achieved: answers (checked, whole) and failed polls over `seconds`.
struct Achieved {
    answers: u64,
    failed: u64,
    seconds: f64,
}

impl Achieved {
    fn hz(&self) -> f64 {
        self.answers as f64 / self.seconds.max(1e-9)
    }
}

/// The polls and link options `poller` uses (the CLI's and the window's own defaults).
fn setup(poller: Poller) -> Result<(Vec<Poll>, LinkOptions), String> {
    let p = profile("window-cleaner")?;
    Ok(match poller {
        Poller::Watch => {
            let attitude = p.command("MSP_ATTITUDE").ok_or("no MSP_ATTITUDE")?;
            let poll = crate::ops::telemetry::poll(&p, attitude, None);
            let opts = LinkOptions {
                reconnect: false,
                ..LinkOptions::default()
            };
            (vec![poll], opts)
        }
        Poller::Window => (
            crate::ops::telemetry::polls(&p, Some(50.0)),
            LinkOptions::default(),
        ),
    })
}

/// Polls for `secs` after the first answer and counts what came back.
fn achieved(poller: Poller, secs: f64) -> Result<Achieved, String> {
    let p = profile("window-cleaner")?;
    let wc: SharedDevice = Arc::new(Mutex::new(WindowCleaner::new(&SimOptions::default())?));
    let server = PtyServer::start(wc, bad_adapter()).map_err(|e| e.to_string())?;
    let (polls, opts) = setup(poller)?;
    let link = open(&server, p, 115_200, opts)?;
    link.send(LinkCommand::SetPolls(polls));
    count(&link, secs)
}

/// Counts the telemetry answers and failures on `link` for `secs` from the first answer
/// (bounded: no answer within 10 s is an error).
fn count(link: &Link, secs: f64) -> Result<Achieved, String> {
    let give_up = Instant::now() + Duration::from_secs(10);
    let mut first = None;
    let (mut answers, mut failed) = (0u64, 0u64);
    loop {
        let now = Instant::now();
        if first.is_none_or(|f: Instant| now.duration_since(f).as_secs_f64() < secs) {
            if first.is_none() && now > give_up {
                return Err("no telemetry answer within 10 s".into());
            }
        } else {
            break;
        }
        let Ok(LinkEvent::Telemetry { result, at, .. }) =
            link.events().recv_timeout(Duration::from_millis(100))
        else {
            continue;
        };
        match (first, result) {
            (None, Ok(_)) => first = Some(at),
            (None, Err(_)) => {}
            (Some(_), Ok(_)) => answers += 1,
            (Some(_), Err(_)) => failed += 1,
        }
    }
    Ok(Achieved {
        answers,
        failed,
        seconds: secs,
    })
}

/// The window's poll rate against `msp watch`'s on the same bad adapter, each polled for
/// `secs`: one figure each, the window's held to at least 0.80 of the watch's.
pub fn bad_adapter_polling(secs: f64) -> Result<Vec<Figure>, String> {
    let watch = achieved(Poller::Watch, secs)?;
    let window = achieved(Poller::Window, secs)?;
    // A poll's bytes: request 6, attitude reply 11 (the wire limit of one poll).
    let per_poll = wire_time(6 + 11, 115_200).as_secs_f64();
    let adapter = "115200 baud, 16 ms latency timer, 5 % drops, 5 % corruption";
    let said = |a: &Achieved| {
        format!(
            "{} answers, {} failed polls, {:.1} Hz",
            a.answers,
            a.failed,
            a.hz()
        )
    };
    let watch_fig = Figure::new(
        &format!("msp watch MSP_ATTITUDE behind a bad adapter ({adapter})"),
        watch.seconds,
        watch.answers as f64 * per_poll,
        said(&watch),
    );
    let ratio = window.hz() / watch.hz().max(1e-9);
    let window_fig = Figure::new(
        &format!("the window's telemetry polls behind a bad adapter ({adapter})"),
        window.seconds,
        window.answers as f64 * per_poll,
        format!(
            "{}: {ratio:.2} of msp watch's {:.1} Hz (the window polls its two plotted \
             commands at 50 Hz and the other telemetry at 1 Hz; every answer counts)",
            said(&window),
            watch.hz()
        ),
    )
    .judged("target ≥ 0.80 of msp watch".into(), ratio >= 0.80);
    Ok(vec![watch_fig, window_fig])
}
