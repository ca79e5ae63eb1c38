//! The servo bus and Tuya MCU simulators, driven directly through `Device::receive` and `tick`.
//!
//! Seed examples are written out byte for byte; other requests are built with the protocol
//! encoders, and answers are read back with the protocol decoders.

use std::sync::Arc;
use std::time::{Duration, Instant};

use botbench::profile::Access;
use botbench::protocol::servo::{self, ServoDecoder, cmd as scmd};
use botbench::protocol::tuya::dp::{self, DataPoint, DpValue};
use botbench::protocol::tuya::{self, TuyaDecoder, cmd as tcmd};
use botbench::protocol::{Direction, FrameError};
use botbench::sim::servo_bus::{self, Motion, ServoBus, SimServo, ext, param};
use botbench::sim::tuya_mcu::{
    self, OtaPacketAnswer, OtaState, TuyaConfig, TuyaMcu, builtin_vacuum_profile, dpid,
};
use botbench::sim::{Device, Outgoing};

/// The seed's servo id and baud-option parameters (the frames below are its test vectors).
const SERVO_ID: u8 = 34;
const BAUDRATE: u8 = 36;

use crate::support::{image, ms};

const B: u32 = 115_200;

// ---------------------------------------------------------------- servo helpers

fn req(command: u8, content: &[u8]) -> Vec<u8> {
    servo::Frame::request(command, content.to_vec())
        .encode()
        .expect("a request encodes")
}

fn servo_items(bytes: &[u8]) -> Vec<Result<servo::Frame, FrameError>> {
    let mut d = ServoDecoder::new();
    d.push(bytes);
    let mut items: Vec<_> = d.by_ref().collect();
    items.extend(d.finish().map(Err));
    items
}

/// The one clean reply in `out`, at the request's baud.
fn one_reply(out: &[Outgoing]) -> servo::Frame {
    assert_eq!(out.len(), 1, "one frame expected: {out:02x?}");
    assert_eq!(out[0].baud, None);
    let items = servo_items(&out[0].bytes);
    match items.as_slice() {
        [Ok(f)] => {
            assert_eq!(f.direction, Direction::DeviceToHost);
            f.clone()
        }
        other => panic!("one clean frame expected, got {other:?}"),
    }
}

fn ask(bus: &mut ServoBus, command: u8, content: &[u8], baud: u32, now: Instant) -> Vec<Outgoing> {
    bus.receive(&req(command, content), baud, now)
}

fn read_angle(bus: &mut ServoBus, id: u8, now: Instant) -> i16 {
    let f = one_reply(&ask(bus, scmd::READ_ANGLE, &[id], B, now));
    assert_eq!(f.content[0], id);
    i16::from_le_bytes([f.content[1], f.content[2]])
}

fn write(bus: &mut ServoBus, id: u8, data_id: u8, data: &[u8], now: Instant) -> Vec<u8> {
    let mut c = vec![id, data_id];
    c.extend_from_slice(data);
    one_reply(&ask(bus, scmd::WRITE_DATA, &c, B, now)).content
}

fn angle_of(bus: &ServoBus, serial: u32, now: Instant) -> f64 {
    bus.servo_by_serial(serial).expect("servo").angle_at(now)
}

mod servo_sim;
mod tuya_ota;
mod tuya_sim;

// ---------------------------------------------------------------- Tuya helpers

fn module(command: u8, data: &[u8]) -> Vec<u8> {
    tuya::Frame::from_module(command, data.to_vec())
        .encode()
        .expect("encodes")
}

fn tuya_frames(out: &[Outgoing]) -> Vec<tuya::Frame> {
    out.iter()
        .map(|o| {
            let mut d = TuyaDecoder::new();
            d.push(&o.bytes);
            let items: Vec<_> = d.by_ref().collect();
            match items.as_slice() {
                [Ok(f)] => {
                    assert_eq!(f.version, tuya::VERSION_MCU);
                    f.clone()
                }
                other => panic!("one clean frame per Outgoing: {other:?}"),
            }
        })
        .collect()
}

fn dp_frame(points: &[DataPoint]) -> Vec<u8> {
    module(tcmd::DP_COMMAND, &dp::encode(points).expect("encodes"))
}

fn reports(out: &[Outgoing]) -> Vec<DataPoint> {
    tuya_frames(out)
        .into_iter()
        .flat_map(|f| {
            assert_eq!(f.command, tcmd::DP_REPORT);
            let dps = dp::decode(&f.data).expect("a DP list");
            assert_eq!(dps.len(), 1, "one DP per report");
            dps
        })
        .collect()
}

fn point(id: u8, value: DpValue) -> DataPoint {
    DataPoint { id, value }
}

// ---------------------------------------------------------------- robustness

#[test]
fn random_bytes_never_panic() {
    let mut rng = fastrand::Rng::with_seed(0xB0B);
    let t0 = Instant::now();
    let mut bus = ServoBus::new(vec![
        SimServo::fresh(1),
        SimServo::fresh(2),
        SimServo::fresh(3).with_id(3).with_param(33, 1),
        SimServo::fresh(4).with_id(3).with_extended(false),
    ]);
    let mut mcu = TuyaMcu::default();
    let bauds = [9_600, 115_200, 1_000_000];
    for i in 0..20_000u64 {
        let now = t0 + Duration::from_micros(i * 137);
        let len = rng.usize(0..40);
        let mut bytes: Vec<u8> = (0..len).map(|_| rng.u8(..)).collect();
        // Often a valid header and a plausible command, so the handlers see odd contents.
        match rng.u8(0..4) {
            0 => {
                let command = rng.u8(0..30);
                let mut content: Vec<u8> = (0..rng.usize(0..14)).map(|_| rng.u8(..)).collect();
                if !content.is_empty() && rng.bool() {
                    content[0] = rng.u8(0..5);
                }
                bytes = req(command, &content);
            }
            1 => {
                let command = rng.u8(0..0x30);
                bytes = module(command, &bytes);
            }
            _ => {}
        }
        let baud = bauds[rng.usize(0..bauds.len())];
        let _ = bus.receive(&bytes, baud, now);
        let _ = bus.tick(now);
        let _ = mcu.receive(&bytes, 9600, now);
        let _ = mcu.tick(now);
    }
    // The devices still work afterwards (a reboot empties the MCU's half-received frame).
    mcu.restart();
    let mut bus = ServoBus::new(vec![SimServo::fresh(9)]);
    assert_eq!(
        one_reply(&ask(&mut bus, scmd::PING, &[0], B, t0)).content,
        [0]
    );
    let out = mcu.receive(&[0x55, 0xaa, 0x00, 0x00, 0x00, 0x00, 0xff], 9600, t0);
    assert_eq!(tuya_frames(&out)[0].command, tcmd::HEARTBEAT);
}
