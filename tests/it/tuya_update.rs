//! A firmware update that is proven (issue 26, item 6): after the last OTA packet botbench
//! waits for the MCU to restart and name the image's version in its product info (0x01), and
//! says the version before and after and how long the MCU took to come back; each way an
//! update fails in the field (a refused packet, never back, back with the old version) is said
//! as what it is. Through pseudo-terminals against the simulated MCU.

use botbench::link::session::tuya::TuyaEvent;
use botbench::link::{Link, LinkEvent, LinkOptions};
use botbench::ops::tuya as ops;
use botbench::ops::{OpError, Run};
use botbench::sim::Faults;
use botbench::sim::tuya_mcu::{OtaFault, TuyaConfig, TuyaMcu};
use std::time::Duration;

use crate::support::cli::run;
use crate::support::{Served, next_event, open_link, profile, serve, serve_plain};

const BAUD: u32 = 115_200;

/// A 4 KiB image whose MCU_VER string is `1.2.3`, as an SDK build holds it.
fn image() -> Vec<u8> {
    let mut image: Vec<u8> = (0..4096u32).map(|i| (i * 13 % 251) as u8 | 0x80).collect();
    image[100..106].copy_from_slice(b"1.2.3\0");
    image
}

fn config(fault: Option<OtaFault>) -> TuyaConfig {
    TuyaConfig {
        baud: Some(BAUD),
        ota_fault: fault,
        ota_restart: Duration::from_millis(300),
        ..TuyaConfig::default()
    }
}

/// The MCU in lockstep with the link of this process.
fn mcu(fault: Option<OtaFault>) -> Served<TuyaMcu> {
    serve(TuyaMcu::new(config(fault)))
}

fn link(mcu: &Served<TuyaMcu>) -> Link {
    let link = open_link(mcu, BAUD, profile("tuya-vacuum"), LinkOptions::default());
    next_event(&link, "the handshake", |e| {
        matches!(e, LinkEvent::Tuya(TuyaEvent::HandshakeDone)).then_some(())
    });
    link
}

/// Quick acks for the tests: 300 ms, one resend.
fn timing() -> ops::OtaTiming {
    ops::OtaTiming {
        ack_wait: Duration::from_millis(300),
        retries: 1,
    }
}

fn update(link: &Link, limit: Duration) -> Result<ops::OtaReport, OpError> {
    let expect = ops::Expect {
        version: "1.2.3".into(),
        limit,
    };
    let c = link.client();
    ops::update(
        &c,
        &image(),
        512 * 1024,
        &expect,
        timing(),
        &mut Run::new(&Default::default(), |_| {}),
    )
}

#[test]
fn an_update_is_done_when_the_mcu_comes_back_naming_the_images_version() {
    assert_eq!(ops::image_version(&image()).as_deref(), Some("1.2.3"));
    let mcu = mcu(None);
    let link = link(&mcu);
    let report = update(&link, ops::COME_BACK_LIMIT).expect("proven");
    assert_eq!(report.before_version.as_deref(), Some("1.0.0"));
    assert_eq!(report.after_version.as_deref(), Some("1.2.3"));
    let back = report.back_seconds.expect("timed");
    assert!(back >= 0.3, "the MCU was away 300 ms at least: {back}");
    assert_eq!(mcu.sim().version(), "1.2.3");
    assert_eq!(mcu.sim().ota_image(), image().as_slice());
}

#[test]
fn an_mcu_that_comes_back_with_its_old_version_fails_the_update() {
    let mcu = mcu(Some(OtaFault::OldVersion));
    let link = link(&mcu);
    let e = update(&link, ops::COME_BACK_LIMIT).expect_err("not proven");
    let said = e.to_string();
    assert!(
        said.contains("still running version 1.0.0, not 1.2.3: the update did not take"),
        "{said}"
    );
}

#[test]
fn an_mcu_that_never_comes_back_fails_the_update_at_the_limit() {
    let mcu = mcu(Some(OtaFault::NeverBack));
    let link = link(&mcu);
    let e = update(&link, Duration::from_secs(3)).expect_err("not proven");
    let said = e.to_string();
    assert!(
        said.contains("the MCU never came back: no heartbeat answer within 3 s"),
        "{said}"
    );
}

#[test]
fn an_mcu_that_refuses_a_packet_fails_the_update_at_its_offset() {
    let mcu = mcu(Some(OtaFault::RefusePacket(1024)));
    let link = link(&mcu);
    let e = update(&link, ops::COME_BACK_LIMIT).expect_err("not proven");
    let said = e.to_string();
    assert!(said.contains("stopped acking at offset 1024"), "{said}");
}

#[test]
fn tuya_ota_says_the_versions_and_refuses_an_image_without_one() {
    let dir = tempfile::tempdir().unwrap();
    let fw = dir.path().join("fw.bin");
    std::fs::write(&fw, image()).unwrap();
    // A pty another process opens.
    let mcu = serve_plain(TuyaMcu::new(config(None)), Faults::default());
    let fw_path = fw.display().to_string();
    let ota = |extra: &[&str]| {
        let mut all = vec!["tuya", "--port", mcu.path(), "--baud", "115200", "ota"];
        all.extend_from_slice(extra);
        run(&all)
    };
    // No version in the image, none given: refused before anything is sent.
    let blank = dir.path().join("blank.bin");
    std::fs::write(&blank, vec![0x5a; 2048]).unwrap();
    let o = ota(&[blank.to_str().unwrap()]);
    assert_eq!(o.code, 2, "{}", o.text());
    assert!(o.err.contains("--expect-version"), "{}", o.text());
    assert_eq!(format!("{:?}", mcu.sim().ota_state()), "Idle");
    // The image's own version, proven.
    let o = ota(&[&fw_path]);
    assert_eq!(o.code, 0, "{}", o.text());
    assert!(
        o.out
            .contains("update done: version 1.0.0 before, 1.2.3 now; the MCU came back"),
        "{}",
        o.text()
    );
    assert_eq!(mcu.sim().version(), "1.2.3");
    // Another version than the one it comes back with: exit 1, said.
    let o = ota(&["--expect-version", "2.0.0", "--restart-wait", "5", &fw_path]);
    assert_eq!(o.code, 1, "{}", o.text());
    assert!(
        o.err.contains("not 2.0.0: the update did not take"),
        "{}",
        o.text()
    );
}
