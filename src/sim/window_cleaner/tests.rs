//! Unit tests of the simulated window cleaner.

use super::*;
use crate::protocol::msp::Reply;
use std::time::Duration;

fn ask(d: &mut WindowCleaner, command: u8, data: Vec<u8>, now: Instant) -> Option<Reply> {
    msp_device::ask(d, DEVICE_CODE, command, data, now)
}

#[test]
fn every_telemetry_and_get_command_answers_by_its_profile_layout() {
    let mut d = WindowCleaner::new(&SimOptions::default()).unwrap();
    let now = Instant::now();
    let profile = d.core().profile.clone();
    for cmd in &profile.commands {
        if !matches!(cmd.kind, CommandKind::Get | CommandKind::Telemetry) {
            continue;
        }
        let r = ask(&mut d, cmd.id, vec![], now);
        let r = r.unwrap_or_else(|| panic!("{} did not answer", cmd.ident));
        let decoded = profile
            .decode(cmd, crate::protocol::Direction::DeviceToHost, &r.data)
            .unwrap();
        assert!(decoded.trailing.is_empty(), "{}", cmd.ident);
    }
    assert_eq!(d.core().last_error, None);
}

#[test]
fn out_of_range_set_is_refused_silently() {
    let mut d = WindowCleaner::new(&SimOptions::default()).unwrap();
    let now = Instant::now();
    assert!(ask(&mut d, 220, vec![101], now).is_none());
    assert_eq!(d.param("pwmValue"), Some(85));
    assert!(ask(&mut d, 220, vec![60, 1], now).is_none());
    let ack = ask(&mut d, 220, vec![60], now).unwrap();
    assert!(ack.data.is_empty());
    assert_eq!(d.param("pwmvalue"), Some(60));
    assert_eq!(ask(&mut d, 130, vec![], now).unwrap().data, vec![60]);
}

#[test]
fn fan_and_motor_move_the_adcs_and_faults_hold_them() {
    let mut d = WindowCleaner::new(&SimOptions::default()).unwrap();
    let t0 = Instant::now();
    assert!(ask(&mut d, 211, vec![80], t0).is_some());
    assert!(ask(&mut d, 214, vec![1], t0).is_some());
    assert!(
        ask(&mut d, 214, vec![3], t0).is_none(),
        "3 is not a motor label"
    );
    let later = t0 + Duration::from_secs(2);
    let a = ask(&mut d, 110, vec![], later).unwrap().data;
    let left = u16::from_le_bytes([a[0], a[1]]);
    let fan = u16::from_le_bytes([a[4], a[5]]);
    assert!(left > 400, "{left}");
    assert!(fan > 1500, "{fan}");

    let mut f = WindowCleaner::new(&SimOptions::default()).unwrap();
    f.inject_named("fan-current-stuck").unwrap();
    f.inject(Fault::WheelCurrentStuck);
    assert!(ask(&mut f, 211, vec![80], t0).is_some());
    assert!(ask(&mut f, 214, vec![1], t0).is_some());
    let a = ask(&mut f, 110, vec![], later).unwrap().data;
    assert!(u16::from_le_bytes([a[0], a[1]]) < 50);
    assert!(u16::from_le_bytes([a[4], a[5]]) < 50);
    assert!("fan".parse::<Fault>().is_err());
}

#[test]
fn corners_triggers_and_version_flags() {
    let mut d = WindowCleaner::new(&SimOptions::default()).unwrap();
    let now = Instant::now();
    d.set_corners(0b1011);
    assert_eq!(ask(&mut d, 112, vec![], now).unwrap().data, vec![0b1011]);
    d.inject(Fault::CornerStuck);
    assert_eq!(ask(&mut d, 112, vec![], now).unwrap().data, vec![0b1010]);
    let echo = ask(&mut d, 216, vec![1, 0, 2, 0, 3, 0, 0xFF, 0xFF], now).unwrap();
    assert_eq!(echo.data, vec![1, 0, 2, 0, 3, 0, 0xFF, 0xFF]);
    d.set_flags(None);
    assert_eq!(ask(&mut d, 2, vec![], now).unwrap().data.len(), 7);
}
