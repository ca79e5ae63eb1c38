//! The link worker against the MSP simulators through real pseudo-terminals.

use botbench::link::{
    ExchangeError, Link, LinkCommand, LinkEvent, LinkOptions, LinkState, Poll, Request,
};
use botbench::ops::Device;
use botbench::ops::OpError;
use botbench::ops::exchange as ops;
use botbench::profile::{Input, Profile, Value};
use botbench::sim::Faults;
use botbench::sim::window_cleaner::WindowCleaner;
use std::cell::Cell;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crate::support::{Port, Served, lossy, next_event, profile, serve_with};

fn window_cleaner(faults: Faults) -> Served<WindowCleaner> {
    serve_with(crate::support::window_cleaner(), faults)
}

fn open(port: &impl Port, profile: Arc<Profile>, options: LinkOptions) -> Link {
    crate::support::open_link(port, 115_200, profile, options)
}

#[test]
fn the_session_learns_the_device_and_reads_and_writes_parameters() {
    let p = profile("window-cleaner");
    let b = window_cleaner(Faults::default());
    let link = open(&b, p.clone(), LinkOptions::default());
    let info = next_event(&link, "identification", |ev| match ev {
        LinkEvent::Identified(r) => Some(r),
        _ => None,
    })
    .expect("CMD_VERSION answered");
    assert_eq!(info.hw, 0x03);
    assert_eq!(info.flags, Some(0x0f));

    let client = link.client();
    let set = p.command("MSP_SET_USE_FAN_OUTPUT_PID").unwrap();
    let inputs: Vec<(String, Input)> = [
        ("fanPwmvalueAtIdle", "55"),
        ("fanPwmvalueMin", "72"),
        ("fanPwmvalueMax", "99"),
        ("defaultTarget", "2.80"),
        ("maxTarget", "3.10"),
        ("minTarget", "2.40"),
    ]
    .iter()
    .map(|(k, v)| (k.to_string(), Input::from(*v)))
    .collect();
    let checks = ops::write_verified(Device::new(&client, &p), set, &inputs).unwrap();
    assert_eq!(checks.len(), 6);
    assert!(checks.iter().all(|c| c.ok()), "{checks:?}");
    let sim = b.sim();
    assert_eq!(sim.param("defaultTarget"), Some(280));
    assert_eq!(sim.param("minTarget"), Some(240));
}

#[test]
fn an_out_of_range_value_is_refused_before_anything_is_sent() {
    let p = profile("window-cleaner");
    let b = window_cleaner(Faults::default());
    let link = open(&b, p.clone(), LinkOptions::default());
    let before = b.sim().param("pwmValue");
    let set = p.command("MSP_SET_PWMVALUE").unwrap();
    let err = ops::write_verified(
        Device::new(&link.client(), &p),
        set,
        &[("pwmValue".into(), Input::from("101"))],
    )
    .unwrap_err();
    assert!(
        matches!(
            err,
            OpError::Value(botbench::profile::FieldError::OutOfRange { .. })
        ),
        "{err}"
    );
    assert_eq!(b.sim().param("pwmValue"), before);
}

/// Whether `e` is what a lossy line gives: no answer, a garbled one, or one to something else.
fn lost(e: &OpError) -> bool {
    matches!(
        e,
        OpError::Exchange(
            ExchangeError::Timeout { .. }
                | ExchangeError::Garbled { .. }
                | ExchangeError::Mismatch { .. }
        )
    )
}

#[test]
fn with_drops_and_corruption_a_thousand_operations_give_only_true_values_or_typed_errors() {
    let p = profile("window-cleaner");
    let b = window_cleaner(lossy(7));
    let link = open(&b, p.clone(), LinkOptions::default());
    let client = link.client();
    let get = p.command("MSP_GET_PWMVALUE").unwrap();
    let set = p.command("MSP_SET_PWMVALUE").unwrap();
    let mut rng = fastrand::Rng::with_seed(11);
    let (mut ok, mut errors) = (0, 0);
    for i in 0..1000 {
        if i % 2 == 0 {
            let v = rng.i64(0..=100);
            match ops::write_verified(
                Device::new(&client, &p),
                set,
                &[("pwmValue".into(), Input::Raw(Value::Int(v)))],
            ) {
                Ok(checks) => {
                    assert!(checks.iter().all(|c| c.ok()), "op {i}: {checks:?}");
                    assert_eq!(b.sim().param("pwmValue"), Some(v), "op {i}");
                    ok += 1;
                }
                Err(e) if lost(&e) => errors += 1,
                Err(e) => panic!("op {i}: untyped failure {e}"),
            }
        } else {
            match ops::read(Device::new(&client, &p), get, &[]) {
                Ok(values) => {
                    let held = b.sim().param("pwmValue").unwrap();
                    assert_eq!(
                        values,
                        [("pwmValue".to_string(), Value::Int(held))]
                            .into_iter()
                            .collect(),
                        "op {i}"
                    );
                    ok += 1;
                }
                Err(e) if lost(&e) => errors += 1,
                Err(e) => panic!("op {i}: untyped failure {e}"),
            }
        }
    }
    assert_eq!(ok + errors, 1000);
    assert!(
        ok > 950,
        "retries should hide most single faults: {ok} ok, {errors} errors"
    );
}

#[test]
fn polled_telemetry_arrives_as_events() {
    let p = profile("window-cleaner");
    let b = window_cleaner(Faults::default());
    let link = open(&b, p.clone(), LinkOptions::default());
    let attitude = p.command("MSP_ATTITUDE").unwrap();
    link.send(LinkCommand::SetPolls(vec![Poll {
        request: Request::for_command(&p, attitude, Vec::new()).attempts(1),
        interval: None,
    }]));
    let mut answers = 0;
    next_event(&link, "50 attitude answers", |ev| {
        if let LinkEvent::Telemetry {
            command,
            result: Ok(packet),
            ..
        } = ev
        {
            assert_eq!(command, attitude.id);
            assert_eq!(packet.payload.len(), 6);
            answers += 1;
        }
        (answers >= 50).then_some(())
    });
}

#[test]
fn pipelined_polls_under_faults_never_mix_answers_with_each_other_or_with_writes() {
    let p = profile("window-cleaner");
    let b = window_cleaner(lossy(3));
    let options = LinkOptions {
        poll_pipeline: 2,
        ..LinkOptions::default()
    };
    let link = open(&b, p.clone(), options);
    let attitude = p.command("MSP_ATTITUDE").unwrap();
    let get = p.command("MSP_GET_PWMVALUE").unwrap();
    let set = p.command("MSP_SET_PWMVALUE").unwrap();
    let poll = |cmd| Poll {
        request: Request::for_command(&p, cmd, Vec::new()).attempts(1),
        interval: None,
    };
    link.send(LinkCommand::SetPolls(vec![poll(attitude), poll(get)]));
    let client = link.client();
    let mut written = vec![b.sim().param("pwmValue").unwrap()];
    let (attitudes, pwms) = (Cell::new(0), Cell::new(0));
    let check = |ev: LinkEvent, written: &[i64]| {
        if let LinkEvent::Telemetry {
            command,
            result: Ok(packet),
            ..
        } = ev
        {
            assert_eq!(packet.command, command, "an answer reported as another's");
            if command == attitude.id {
                assert_eq!(packet.payload.len(), 6);
                attitudes.set(attitudes.get() + 1);
            } else {
                assert_eq!(command, get.id);
                let v = i64::from(packet.payload[0]);
                assert!(written.contains(&v), "polled {v}, never written");
                pwms.set(pwms.get() + 1);
            }
        }
    };
    for i in 0..40 {
        let v = (i * 7 % 101) as i64;
        if let Ok(checks) = ops::write_verified(
            Device::new(&client, &p),
            set,
            &[("pwmValue".into(), Input::Raw(Value::Int(v)))],
        ) {
            assert!(checks.iter().all(|c| c.ok()), "write {i}: {checks:?}");
            assert_eq!(b.sim().param("pwmValue"), Some(v));
        }
        written.push(v);
        while let Ok(ev) = link.events().try_recv() {
            check(ev, &written);
        }
    }
    // Polling goes on: every answer from here on is checked too, until each command has been
    // answered more than 100 times.
    next_event(&link, "more than 100 answers to each poll", |ev| {
        check(ev, &written);
        (attitudes.get() > 100 && pwms.get() > 100).then_some(())
    });
}

#[test]
fn a_vanished_port_gives_disconnected_and_the_link_reconnects_when_it_returns() {
    let p = profile("window-cleaner");
    let mut b = window_cleaner(Faults::default());
    // The port by its path, as the system opens it: the pty now at `path`, served in lockstep.
    let path = Arc::new(Mutex::new(b.path().to_string()));
    let ports = Arc::new(Mutex::new(b.ports()));
    let (opener_path, opener_ports) = (path.clone(), ports.clone());
    let opener: botbench::link::Opener = Box::new(move || {
        let p = opener_path.lock().unwrap().clone();
        let ports = opener_ports.lock().unwrap().clone();
        ports.open(&p, 115_200)()
    });
    let link = Link::open(opener, p.clone(), LinkOptions::default(), None).unwrap();
    let client = link.client();
    let ping = || client.request(Request::new(1, Vec::new()));
    assert!(ping().is_ok());

    b.server.vanish();
    // The next exchange (or the idle check) notices.
    let _ = ping();
    next_event(&link, "Lost", |ev| match ev {
        LinkEvent::State(LinkState::Lost { reason }) => Some(reason),
        _ => None,
    });
    assert!(matches!(ping(), Err(ExchangeError::Disconnected(_))));

    // The device comes back (a new pty stands in for the re-plugged adapter).
    let b2 = window_cleaner(Faults::default());
    *ports.lock().unwrap() = b2.ports();
    *path.lock().unwrap() = b2.path().to_string();
    let back = next_event(&link, "the reconnection", |ev| match ev {
        LinkEvent::State(LinkState::Connected { port, .. }) => Some(port),
        _ => None,
    });
    assert_eq!(back, b2.path());
    assert!(ping().is_ok());
}

#[test]
fn a_silent_device_gives_a_typed_timeout_after_bounded_attempts() {
    let p = profile("window-cleaner");
    let b = window_cleaner(Faults {
        silent: true,
        ..Faults::default()
    });
    let link = open(
        &b,
        p,
        LinkOptions {
            start_session: false,
            ..LinkOptions::default()
        },
    );
    let t0 = Instant::now();
    let err = link
        .client()
        .request(Request::new(130, Vec::new()).attempts(3))
        .unwrap_err();
    assert!(
        matches!(
            err,
            ExchangeError::Timeout {
                command: botbench::link::CommandName { id: 130, .. },
                attempts: 3,
                ..
            }
        ),
        "{err}"
    );
    assert!(
        err.to_string()
            .starts_with("no answer to MSP_GET_PWMVALUE (130) after 3 attempt(s)"),
        "named by the profile: {err}"
    );
    assert!(
        t0.elapsed() >= Duration::from_millis(60),
        "three attempts of at least 20 ms"
    );
}
