//! This connection's identification through the whole link: a pseudo-terminal, the worker, and
//! the simulators ([`Client::device_info`], [`Client::identify`]).

use botbench::link::{
    ExchangeError, Link, LinkEvent, LinkOptions, LinkState, LogEntry, Opener, Request, serial,
};
use botbench::profile::{Protocol, Registry};
use botbench::protocol::{Direction, msp};
use botbench::sim::{Faults, PtyServer, SimKind, SimOptions};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Long enough on a loaded machine; only a failing test waits this long.
const PATIENCE: Duration = Duration::from_secs(10);

/// The link's options, with an answer margin that a loaded machine cannot overrun: a retried
/// CMD_VERSION would count twice.
fn options() -> LinkOptions {
    LinkOptions {
        margin: Some(Duration::from_secs(1)),
        ..LinkOptions::default()
    }
}

fn serve(kind: SimKind) -> PtyServer {
    let device = botbench::sim::build(kind, &SimOptions::default()).unwrap();
    PtyServer::start(device, Faults::default()).unwrap()
}

/// A link to the pty at the path in `path`, which a test may change to stand in for a
/// re-plugged adapter.
fn open(path: &Arc<Mutex<String>>, kind: SimKind, profile: &str, options: LinkOptions) -> Link {
    let profile = Registry::builtin().unwrap().get(profile).unwrap();
    let path = path.clone();
    let baud = kind.default_baud();
    let opener: Opener = Box::new(move || {
        let p = path.lock().unwrap().clone();
        serial::opener(&p, baud)()
    });
    Link::open(opener, profile, options, None).unwrap()
}

/// How many CMD_VERSION requests were written since the last count: a ping goes out after
/// everything asked before it, so every frame written before it has been logged when it returns.
fn versions_sent(link: &Link) -> usize {
    link.client()
        .request(Request::new(msp::CMD_PING, Vec::new()))
        .expect("the device answers a ping");
    link.events()
        .try_iter()
        .filter(|ev| {
            matches!(ev, LinkEvent::Frame(LogEntry {
                direction: Direction::HostToDevice,
                frame: Ok(p),
                ..
            }) if p.command == msp::CMD_VERSION)
        })
        .count()
}

/// Waits for a state change that `pick` accepts.
fn wait_state(link: &Link, pick: impl Fn(&LinkState) -> bool) {
    let deadline = Instant::now() + PATIENCE;
    while let Ok(ev) = link
        .events()
        .recv_timeout(deadline.saturating_duration_since(Instant::now()))
    {
        if let LinkEvent::State(s) = ev
            && pick(&s)
        {
            return;
        }
    }
    panic!("the link never reached the state");
}

#[test]
fn device_info_gives_this_connections_identification_without_asking_the_device_again() {
    let server = serve(SimKind::WindowCleaner);
    let path = Arc::new(Mutex::new(server.path().to_string()));
    let link = open(&path, SimKind::WindowCleaner, "window-cleaner", options());
    let client = link.client();
    let info = client.device_info().expect("identified");
    assert_eq!(info.hw, 0x03);
    assert!(info.build_date.is_some(), "{info:?}");
    for _ in 0..3 {
        assert_eq!(client.device_info(), Ok(info.clone()));
    }
    assert_eq!(
        versions_sent(&link),
        1,
        "CMD_VERSION asked once, on connect"
    );

    // Asked to identify again, the link asks the device again, once.
    assert_eq!(client.identify(), Ok(info.clone()));
    assert_eq!(client.device_info(), Ok(info));
    assert_eq!(versions_sent(&link), 1);
}

#[test]
fn a_link_that_identifies_on_demand_asks_the_device_when_first_asked() {
    let server = serve(SimKind::WindowCleaner);
    let path = Arc::new(Mutex::new(server.path().to_string()));
    let options = LinkOptions {
        start_session: false,
        ..options()
    };
    let link = open(&path, SimKind::WindowCleaner, "window-cleaner", options);
    assert_eq!(versions_sent(&link), 0);
    let info = link.client().device_info().expect("identified on demand");
    assert_eq!(info.hw, 0x03);
    assert_eq!(link.client().device_info(), Ok(info));
    assert_eq!(versions_sent(&link), 1);
}

#[test]
fn a_lost_port_has_no_identification_and_the_next_connection_is_identified_afresh() {
    let mut server = serve(SimKind::WindowCleaner);
    let path = Arc::new(Mutex::new(server.path().to_string()));
    let link = open(&path, SimKind::WindowCleaner, "window-cleaner", options());
    let client = link.client();
    client.device_info().expect("identified");
    assert_eq!(versions_sent(&link), 1);

    server.vanish();
    wait_state(&link, |s| matches!(s, LinkState::Lost { .. }));
    assert!(
        matches!(client.device_info(), Err(ExchangeError::Disconnected(_))),
        "no identification without a port"
    );

    // Another device is plugged in (a new pty stands in for the adapter): the new connection is
    // identified before device_info answers, so the answer is the new device's.
    let server2 = serve(SimKind::SolarCleanbot);
    *path.lock().unwrap() = server2.path().to_string();
    wait_state(&link, |s| matches!(s, LinkState::Connected { .. }));
    assert_eq!(client.device_info().map(|i| i.hw), Ok(0x04));
    assert_eq!(
        versions_sent(&link),
        1,
        "CMD_VERSION asked on the new connection"
    );
}

#[test]
fn a_servo_link_has_no_device_identification() {
    let server = serve(SimKind::ServoBus);
    let path = Arc::new(Mutex::new(server.path().to_string()));
    let link = open(&path, SimKind::ServoBus, "servo", options());
    assert!(matches!(
        link.client().device_info(),
        Err(ExchangeError::NotInProtocol {
            protocol: Protocol::Servo,
            ..
        })
    ));
}
