//! The Tuya MCU simulator: the seed's basic frames, working mode, queries and data point
//! commands, reports, battery drain and MCU requests.

use super::*;

// ---------------------------------------------------------------- Tuya

#[test]
fn seed_heartbeat_and_restart() {
    let now = Instant::now();
    let mut mcu = TuyaMcu::default();
    let hb = [0x55, 0xaa, 0x00, 0x00, 0x00, 0x00, 0xff];
    let first = mcu.receive(&hb, 9600, now);
    assert_eq!(
        first,
        vec![Outgoing::new(
            tuya_mcu::DEFAULT_LATENCY,
            vec![0x55, 0xaa, 0x03, 0x00, 0x00, 0x01, 0x00, 0x03]
        )]
    );
    for _ in 0..3 {
        let later = mcu.receive(&hb, 9600, now);
        assert_eq!(
            later[0].bytes,
            [0x55, 0xaa, 0x03, 0x00, 0x00, 0x01, 0x01, 0x04]
        );
    }
    mcu.restart();
    assert_eq!(mcu.receive(&hb, 9600, now)[0].bytes[6], 0x00);
    assert_eq!(mcu.receive(&hb, 9600, now)[0].bytes[6], 0x01);
}

#[test]
fn seed_product_info() {
    let now = Instant::now();
    let mut mcu = TuyaMcu::new(TuyaConfig {
        pid: "RN2FVAgXG6WfAktU".into(),
        ..TuyaConfig::default()
    });
    let out = mcu.receive(&[0x55, 0xaa, 0x00, 0x01, 0x00, 0x00, 0x00], 9600, now);
    let expected: [u8; 49] = [
        0x55, 0xaa, 0x03, 0x01, 0x00, 0x2a, 0x7b, 0x22, 0x70, 0x22, 0x3a, 0x22, 0x52, 0x4e, 0x32,
        0x46, 0x56, 0x41, 0x67, 0x58, 0x47, 0x36, 0x57, 0x66, 0x41, 0x6b, 0x74, 0x55, 0x22, 0x2c,
        0x22, 0x76, 0x22, 0x3a, 0x22, 0x31, 0x2e, 0x30, 0x2e, 0x30, 0x22, 0x2c, 0x22, 0x6d, 0x22,
        0x3a, 0x30, 0x7d, 0x0c,
    ];
    assert_eq!(out.len(), 1);
    assert_eq!(out[0].bytes, expected);

    // The default product, and a malformed answer on request.
    let mut mcu = TuyaMcu::default();
    let f = &tuya_frames(&mcu.receive(&module(tcmd::PRODUCT_INFO, &[]), 9600, now))[0];
    let json: serde_json::Value = serde_json::from_slice(&f.data).expect("JSON");
    assert_eq!(json["p"], "lgldgnmt4ifc.jzex");
    assert_eq!(json["v"], "1.0.0");
    assert_eq!(json["m"], 0);
    mcu.config_mut().product_info_raw = Some(tuya_mcu::MALFORMED_PRODUCT_INFO.to_vec());
    let f = &tuya_frames(&mcu.receive(&module(tcmd::PRODUCT_INFO, &[]), 9600, now))[0];
    assert!(serde_json::from_slice::<serde_json::Value>(&f.data).is_err());
}

#[test]
fn working_mode_and_wifi_state() {
    let now = Instant::now();
    let mut mcu = TuyaMcu::default();
    let f = tuya_frames(&mcu.receive(&module(tcmd::WORK_MODE, &[]), 9600, now));
    assert_eq!(
        (f[0].command, f[0].data.as_slice()),
        (tcmd::WORK_MODE, &[][..])
    );
    mcu.config_mut().work_mode = Some([14, 0]);
    let f = tuya_frames(&mcu.receive(&module(tcmd::WORK_MODE, &[]), 9600, now));
    assert_eq!(f[0].data, [14, 0]);

    let f = tuya_frames(&mcu.receive(&module(tcmd::WIFI_STATE, &[4]), 9600, now));
    assert_eq!((f[0].command, f[0].data.len()), (tcmd::WIFI_STATE, 0));
    assert_eq!(mcu.wifi_state(), Some(4));
}

#[test]
fn frames_of_another_version_are_dropped() {
    let now = Instant::now();
    let mut mcu = TuyaMcu::default();
    let from_mcu = |c: u8, d: &[u8]| tuya::Frame::from_mcu(c, d.to_vec()).encode().expect("ok");
    assert!(
        mcu.receive(&from_mcu(tcmd::HEARTBEAT, &[]), 9600, now)
            .is_empty()
    );
    assert!(
        mcu.receive(&from_mcu(tcmd::QUERY_STATUS, &[]), 9600, now)
            .is_empty()
    );
    assert!(
        mcu.receive(&from_mcu(tcmd::DP_COMMAND, &[1, 1, 0, 1, 0]), 9600, now)
            .is_empty()
    );
    assert_eq!(mcu.dp(dpid::POWER), Some(&DpValue::Bool(true)));
    // The dropped heartbeat did not count: the first real one still answers 00.
    assert_eq!(mcu.receive(&module(0, &[]), 9600, now)[0].bytes[6], 0);
}

#[test]
fn the_mcu_hears_only_its_own_baud() {
    let now = Instant::now();
    let mut mcu = TuyaMcu::default();
    assert!(mcu.receive(&module(0, &[]), 115_200, now).is_empty());
    assert_eq!(mcu.receive(&module(0, &[]), 9600, now).len(), 1);
    let mut any = TuyaMcu::new(TuyaConfig {
        baud: None,
        ..TuyaConfig::default()
    });
    assert_eq!(any.receive(&module(0, &[]), 115_200, now).len(), 1);
}

#[test]
fn query_gives_19_reports() {
    let now = Instant::now();
    let mut mcu = TuyaMcu::default();
    let got = reports(&mcu.receive(&module(tcmd::QUERY_STATUS, &[]), 9600, now));
    assert_eq!(got.len(), 19);
    let ids: Vec<u8> = got.iter().map(|p| p.id).collect();
    assert_eq!(ids, (1..=19).collect::<Vec<u8>>());
    let profile = builtin_vacuum_profile();
    for p in &got {
        let def = profile.data_point(p.id).expect("a profile DP");
        assert_eq!(p.value.dp_type(), def.dp_type, "dp {}", p.id);
    }
    assert_eq!(got[5].value, DpValue::Value(80));
    assert_eq!(got[6].value, DpValue::Value(90));
    assert_eq!(got[7].value, DpValue::Value(85));
    assert_eq!(got[8].value, DpValue::Value(70));
    assert_eq!(got[4].value, DpValue::Enum(0));
    assert_eq!(got[17].value, DpValue::Bitmap { bits: 0, width: 1 });
    assert_eq!(got[18].value, DpValue::Raw(vec![0, 0, 0xff]));
}

#[test]
fn dp_commands_are_answered_as_the_sdk_and_what_follows_is_reported_after() {
    // The MCU SDK answers each data point of a 0x06 with one report of the value received; what
    // the vacuum's own rules change follows from the next tick, in the order it changed.
    let now = Instant::now();
    let mut mcu = TuyaMcu::default();
    // Clean switch on: the mode (0 → 2) and the status (smart clean) follow.
    let got = reports(&mcu.receive(&dp_frame(&[point(2, DpValue::Bool(true))]), 9600, now));
    assert_eq!(got, [point(2, DpValue::Bool(true))]);
    assert_eq!(mcu.dp(dpid::STATUS), Some(&DpValue::Enum(1)));
    assert_eq!(
        reports(&mcu.tick(now)),
        [point(3, DpValue::Enum(2)), point(5, DpValue::Enum(1))]
    );
    // Power off: the clean switch, the status and the mode follow.
    let got = reports(&mcu.receive(&dp_frame(&[point(1, DpValue::Bool(false))]), 9600, now));
    assert_eq!(got, [point(1, DpValue::Bool(false))]);
    assert_eq!(
        reports(&mcu.tick(now)),
        [
            point(2, DpValue::Bool(false)),
            point(5, DpValue::Enum(0)),
            point(3, DpValue::Enum(0))
        ]
    );
    // Enum: wall-follow mode → edge cleaning, and the robot powers on.
    let got = reports(&mcu.receive(&dp_frame(&[point(3, DpValue::Enum(3))]), 9600, now));
    assert_eq!(got, [point(3, DpValue::Enum(3))]);
    assert_eq!(
        reports(&mcu.tick(now)),
        [
            point(5, DpValue::Enum(2)),
            point(2, DpValue::Bool(true)),
            point(1, DpValue::Bool(true))
        ]
    );
    // A consumable reset: life back to 100.
    let got = reports(&mcu.receive(&dp_frame(&[point(12, DpValue::Bool(true))]), 9600, now));
    assert_eq!(got, [point(12, DpValue::Bool(true))]);
    assert_eq!(reports(&mcu.tick(now)), [point(9, DpValue::Value(100))]);
    // Several DPs in one frame: each its own report, in order; nothing follows.
    let got = reports(&mcu.receive(
        &dp_frame(&[point(14, DpValue::Enum(0)), point(13, DpValue::Bool(true))]),
        9600,
        now,
    ));
    assert_eq!(
        got,
        [point(14, DpValue::Enum(0)), point(13, DpValue::Bool(true))]
    );
    assert!(mcu.tick(now).is_empty());
}

#[test]
fn every_dp_type_is_reported_back_when_writable() {
    // The vacuum's value, string, bitmap and raw DPs are report-only; make them writable.
    let mut profile = (*builtin_vacuum_profile()).clone();
    for d in &mut profile.data_points {
        d.access = Access::ReadWrite;
    }
    let now = Instant::now();
    let mut mcu = TuyaMcu::with_profile(Arc::new(profile), TuyaConfig::default());
    for p in [
        point(1, DpValue::Bool(false)),
        point(3, DpValue::Enum(11)),
        point(16, DpValue::Value(9999)),
        point(15, DpValue::String("20240501120003012000007".into())),
        point(
            18,
            DpValue::Bitmap {
                bits: 0x45,
                width: 1,
            },
        ),
        point(19, DpValue::Raw(vec![1, 0x80, 0x40])),
    ] {
        let got = reports(&mcu.receive(&dp_frame(std::slice::from_ref(&p)), 9600, now));
        assert_eq!(got.first(), Some(&p));
        assert_eq!(mcu.dp(p.id), Some(&p.value));
    }
    // Still range-checked.
    assert!(
        mcu.receive(&dp_frame(&[point(16, DpValue::Value(10_000))]), 9600, now)
            .is_empty()
    );
}

#[test]
fn bad_dps_get_no_answer() {
    let now = Instant::now();
    let mut mcu = TuyaMcu::default();
    let before = mcu.dps().clone();
    for points in [
        vec![point(1, DpValue::Enum(0))],     // power as an enum
        vec![point(3, DpValue::Bool(true))],  // mode as a bool
        vec![point(3, DpValue::Value(2))],    // mode as a value
        vec![point(3, DpValue::Enum(12))],    // no such mode
        vec![point(6, DpValue::Value(50))],   // battery: report only
        vec![point(5, DpValue::Enum(1))],     // status: report only
        vec![point(99, DpValue::Bool(true))], // unknown dpid
        vec![point(14, DpValue::String("x".into()))],
    ] {
        let out = mcu.receive(&dp_frame(&points), 9600, now);
        assert!(out.is_empty(), "{points:?} answered: {out:02x?}");
    }
    // A bool of the wrong length, a truncated list.
    assert!(
        mcu.receive(&module(tcmd::DP_COMMAND, &[1, 1, 0, 2, 0, 0]), 9600, now)
            .is_empty()
    );
    assert!(
        mcu.receive(&module(tcmd::DP_COMMAND, &[1, 1, 0, 1]), 9600, now)
            .is_empty()
    );
    assert_eq!(mcu.dps(), &before);
    // A good DP next to a bad one: only the good one is answered.
    let got = reports(&mcu.receive(
        &dp_frame(&[point(1, DpValue::Enum(0)), point(13, DpValue::Bool(true))]),
        9600,
        now,
    ));
    assert_eq!(got, [point(13, DpValue::Bool(true))]);
}

#[test]
fn battery_drains_while_cleaning_and_is_reported() {
    let t0 = Instant::now();
    let mut mcu = TuyaMcu::new(TuyaConfig {
        battery_drain_every: Duration::from_secs(1),
        seed: 7,
        ..TuyaConfig::default()
    });
    assert!(
        mcu.tick(t0 + ms(5_000)).is_empty(),
        "not cleaning: no drain"
    );
    mcu.receive(&dp_frame(&[point(2, DpValue::Bool(true))]), 9600, t0);
    // What starting to clean changed (the mode, the status) is reported first.
    assert!(!mcu.tick(t0).is_empty());
    let mut seen = Vec::new();
    for s in 1..=60 {
        for p in reports(&mcu.tick(t0 + ms(s * 1000))) {
            assert_eq!(p.id, dpid::BATTERY);
            seen.push(p.value);
        }
    }
    assert!(seen.len() >= 40, "{} reports", seen.len());
    assert_eq!(seen.last(), mcu.dp(dpid::BATTERY));
    assert!(matches!(mcu.dp(dpid::BATTERY), Some(DpValue::Value(v)) if *v < 40));
    // Stop cleaning: no more.
    mcu.receive(
        &dp_frame(&[point(2, DpValue::Bool(false))]),
        9600,
        t0 + ms(60_000),
    );
    // The status (standby) follows; then nothing more.
    assert_eq!(
        reports(&mcu.tick(t0 + ms(60_000))),
        [point(5, DpValue::Enum(0))]
    );
    assert!(mcu.tick(t0 + ms(120_000)).is_empty());
    // A change the robot makes itself is reported from the next tick.
    assert!(mcu.set_dp(
        dpid::FAULT,
        DpValue::Bitmap {
            bits: 0x04,
            width: 1
        }
    ));
    assert_eq!(
        reports(&mcu.tick(t0 + ms(120_001))),
        [point(
            18,
            DpValue::Bitmap {
                bits: 0x04,
                width: 1
            }
        )]
    );
}

#[test]
fn mcu_requests_are_sent_and_answers_recorded() {
    let now = Instant::now();
    let mut mcu = TuyaMcu::default();
    assert!(mcu.tick(now).is_empty());
    mcu.request_local_time();
    mcu.request_wifi_test();
    mcu.reset_wifi();
    mcu.reset_wifi_mode(1);
    mcu.request_net_status();
    mcu.request_mac();
    let sent = tuya_frames(&mcu.tick(now));
    let cmds: Vec<(u8, Vec<u8>)> = sent.into_iter().map(|f| (f.command, f.data)).collect();
    assert_eq!(
        cmds,
        [
            (0x1c, vec![]),
            (0x0e, vec![]),
            (0x04, vec![]),
            (0x05, vec![1]),
            (0x2b, vec![]),
            (0x2d, vec![]),
        ]
    );
    assert!(mcu.tick(now).is_empty(), "each sent once");
    let time = [1, 24, 5, 1, 12, 30, 0, 3];
    assert!(mcu.receive(&module(0x1c, &time), 9600, now).is_empty());
    assert!(mcu.receive(&module(0x0e, &[1, 80]), 9600, now).is_empty());
    assert!(mcu.receive(&module(0x04, &[]), 9600, now).is_empty());
    assert_eq!(
        mcu.answers(),
        [(0x1c, time.to_vec()), (0x0e, vec![1, 80]), (0x04, vec![])]
    );
    assert_eq!(mcu.take_answers().len(), 3);
    assert!(mcu.answers().is_empty());
}
