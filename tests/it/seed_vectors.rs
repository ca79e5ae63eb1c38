//! Every frame printed in the three protocol seeds, as a test vector.
//!
//! Each expected byte string is written out literally (copied from the seed, or for MSP, which
//! prints no hex, worked out by hand from the documented layout). Nothing expected is computed by
//! the code under test: encoding must give exactly these bytes, and decoding them must give the
//! frame back, with its fields read by hand.

use std::fmt::Debug;

use botbench::protocol::msp::{self, ReplyDecoder, ReplyKind, RequestDecoder};
use botbench::protocol::servo::{self, ServoDecoder, cmd as scmd};
use botbench::protocol::tuya::dp::{self, DataPoint, DpValue};
use botbench::protocol::tuya::{self, TuyaDecoder, cmd as tcmd};
use botbench::protocol::{Decoder, Direction, Framing, hex};

use crate::support::sum_mod_256;

/// Decodes `bytes` pushed in one go and in single bytes; both must give exactly one frame that
/// spans the whole input, with nothing left over.
fn decode_one<P>(make: impl Fn() -> Decoder<P>, bytes: &[u8]) -> P::Frame
where
    P: Framing,
    P::Frame: Debug + PartialEq,
{
    let mut whole = make();
    whole.push(bytes);
    let items: Vec<_> = whole.by_ref().collect();
    assert_eq!(
        items.len(),
        1,
        "one item expected from {bytes:02x?}: {items:?}"
    );
    assert_eq!(whole.last_start(), 0);
    assert_eq!(whole.stream_offset(), bytes.len() as u64);
    assert_eq!(whole.buffered(), 0);
    assert_eq!(whole.finish(), None);
    let frame = items.into_iter().next().unwrap().expect("a valid frame");

    let mut bytewise = make();
    let mut got = Vec::new();
    for (i, b) in bytes.iter().enumerate() {
        bytewise.push(std::slice::from_ref(b));
        for item in bytewise.by_ref() {
            got.push((i, item));
        }
    }
    assert_eq!(bytewise.finish(), None);
    assert_eq!(got.len(), 1, "byte-wise: {got:?}");
    let (at, item) = got.pop().unwrap();
    assert_eq!(
        at,
        bytes.len() - 1,
        "the frame must come out at its last byte"
    );
    assert_eq!(item.as_ref().ok(), Some(&frame));
    frame
}

fn le16(b: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([b[at], b[at + 1]])
}

fn be32(b: &[u8], at: usize) -> u32 {
    u32::from_be_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

// ---------------------------------------------------------------------------------------------
// Bus servo (seed 002)
// ---------------------------------------------------------------------------------------------

fn servo_vector(frame: &servo::Frame, bytes: &[u8]) {
    assert_eq!(frame.encode().unwrap(), bytes, "encoding {frame:?}");
    assert_eq!(frame.wire_len(), bytes.len());
    let got = decode_one(ServoDecoder::new, bytes);
    assert_eq!(&got, frame);
}

#[test]
fn servo_ping_request_and_reply() {
    // "ping一下3号舵机": 0x12 0x4c 0x01 0x01 0x03 0x63
    let req = servo::Frame::request(scmd::PING, vec![0x03]);
    servo_vector(&req, &[0x12, 0x4c, 0x01, 0x01, 0x03, 0x63]);
    assert_eq!(req.servo_id(), Some(3));
    assert_eq!(req.direction, Direction::HostToDevice);

    // The reply: 0x05 0x1c 0x01 0x01 0x03 0x26 (the seed's bullet list says 0x38, its own sum
    // says 38 decimal = 0x26; the printed frame is right).
    let reply = servo::Frame::reply(scmd::PING, vec![0x03]);
    servo_vector(&reply, &[0x05, 0x1c, 0x01, 0x01, 0x03, 0x26]);
    assert_eq!(reply.servo_id(), Some(3));
    assert_eq!(reply.direction, Direction::DeviceToHost);
}

#[test]
fn servo_rotate_servo_2_to_90_degrees_in_500_ms() {
    let bytes = [
        0x12, 0x4c, 0x08, 0x07, 0x02, 0x84, 0x03, 0xf4, 0x01, 0x00, 0x00, 0xeb,
    ];
    let frame = servo::Frame::request(scmd::ROTATE, vec![0x02, 0x84, 0x03, 0xf4, 0x01, 0x00, 0x00]);
    servo_vector(&frame, &bytes);
    let got = decode_one(ServoDecoder::new, &bytes);
    assert_eq!(got.command, 8);
    assert_eq!(got.servo_id(), Some(2));
    assert_eq!(le16(&got.content, 1) as i16, 900, "angle in 0.1 degrees");
    assert_eq!(le16(&got.content, 3), 500, "interval in ms");
    assert_eq!(le16(&got.content, 5), 0, "power");
}

#[test]
fn servo_read_angle_request_and_reply() {
    let req = [0x12, 0x4c, 0x0a, 0x01, 0x00, 0x69];
    servo_vector(&servo::Frame::request(scmd::READ_ANGLE, vec![0x00]), &req);

    let reply = [0x05, 0x1c, 0x0a, 0x03, 0x00, 0x86, 0x03, 0xb7];
    servo_vector(
        &servo::Frame::reply(scmd::READ_ANGLE, vec![0x00, 0x86, 0x03]),
        &reply,
    );
    let got = decode_one(ServoDecoder::new, &reply);
    assert_eq!(got.direction, Direction::DeviceToHost);
    assert_eq!(got.command, 10);
    assert_eq!(got.servo_id(), Some(0));
    let raw = le16(&got.content, 1) as i16;
    assert_eq!(raw, 902);
    assert_eq!(f64::from(raw) / 10.0, 90.2);
}

#[test]
fn servo_the_four_spin_examples() {
    // (method, speed, value, printed bytes)
    let cases: [(u8, u16, u16, [u8; 11]); 4] = [
        // 持续旋转: counter-clockwise, continuous, 100 deg/s
        (
            0x01,
            100,
            0,
            [
                0x12, 0x4c, 0x07, 0x06, 0x00, 0x01, 0x64, 0x00, 0x00, 0x00, 0xd0,
            ],
        ),
        // 停止转动
        (
            0x00,
            100,
            0,
            [
                0x12, 0x4c, 0x07, 0x06, 0x00, 0x00, 0x64, 0x00, 0x00, 0x00, 0xcf,
            ],
        ),
        // 定圈转动: clockwise (bit 7), 5 turns
        (
            0x82,
            100,
            5,
            [
                0x12, 0x4c, 0x07, 0x06, 0x00, 0x82, 0x64, 0x00, 0x05, 0x00, 0x56,
            ],
        ),
        // 定时运动: clockwise, 1000 ms
        (
            0x83,
            100,
            1000,
            [
                0x12, 0x4c, 0x07, 0x06, 0x00, 0x83, 0x64, 0x00, 0xe8, 0x03, 0x3d,
            ],
        ),
    ];
    for (method, speed, value, bytes) in cases {
        let mut content = vec![0x00, method];
        content.extend_from_slice(&speed.to_le_bytes());
        content.extend_from_slice(&value.to_le_bytes());
        servo_vector(&servo::Frame::request(scmd::SPIN, content), &bytes);

        let got = decode_one(ServoDecoder::new, &bytes);
        assert_eq!(got.command, 7);
        assert_eq!(got.servo_id(), Some(0));
        assert_eq!(got.content[1], method);
        assert_eq!(le16(&got.content, 2), speed);
        assert_eq!(le16(&got.content, 4), value);
    }
    // Direction and mode bits of the 5-turn example, read by hand.
    let five_turns = decode_one(
        ServoDecoder::new,
        &[
            0x12, 0x4c, 0x07, 0x06, 0x00, 0x82, 0x64, 0x00, 0x05, 0x00, 0x56,
        ],
    );
    assert_eq!(five_turns.content[1] & 0x80, 0x80, "clockwise");
    assert_eq!(five_turns.content[1] & 0x03, 0x02, "fixed number of turns");
}

#[test]
fn servo_damping_with_the_seeds_x12_typo() {
    let printed = "x12 0x4c 0x09 0x03 0x00 0xf4 0x01 0x5f";
    let bytes = [0x12, 0x4c, 0x09, 0x03, 0x00, 0xf4, 0x01, 0x5f];
    // The seed drops the 0 of 0x12; the hex reader used for pasted frames must accept it.
    assert_eq!(hex::parse(printed).unwrap(), bytes);
    servo_vector(
        &servo::Frame::request(scmd::DAMPING, vec![0x00, 0xf4, 0x01]),
        &bytes,
    );
    let got = decode_one(ServoDecoder::new, &bytes);
    assert_eq!(got.command, 9);
    assert_eq!(got.servo_id(), Some(0));
    assert_eq!(le16(&got.content, 1), 500, "power in mW");
}

#[test]
fn servo_seed_examples_back_to_back_in_one_stream() {
    let frames: [&[u8]; 5] = [
        &[0x12, 0x4c, 0x01, 0x01, 0x03, 0x63],
        &[0x05, 0x1c, 0x01, 0x01, 0x03, 0x26],
        &[0x12, 0x4c, 0x0a, 0x01, 0x00, 0x69],
        &[0x05, 0x1c, 0x0a, 0x03, 0x00, 0x86, 0x03, 0xb7],
        &[0x12, 0x4c, 0x09, 0x03, 0x00, 0xf4, 0x01, 0x5f],
    ];
    let mut dec = ServoDecoder::new();
    dec.push(&frames.concat());
    let mut offset = 0u64;
    for bytes in frames {
        let frame = dec.next().expect("a frame").expect("valid");
        assert_eq!(dec.last_start(), offset);
        offset += bytes.len() as u64;
        assert_eq!(dec.stream_offset(), offset);
        assert_eq!(frame.encode().unwrap(), bytes);
    }
    assert!(dec.next().is_none());
}

// ---------------------------------------------------------------------------------------------
// Tuya (seed 003)
// ---------------------------------------------------------------------------------------------

fn tuya_vector(frame: &tuya::Frame, bytes: &[u8]) {
    assert_eq!(frame.encode().unwrap(), bytes, "encoding {frame:?}");
    assert_eq!(frame.wire_len(), bytes.len());
    let got = decode_one(TuyaDecoder::new, bytes);
    assert_eq!(&got, frame);
}

#[test]
fn tuya_basic_module_frames_with_printed_checksums() {
    // (command, printed bytes)
    let cases: [(u8, [u8; 7]); 5] = [
        (tcmd::HEARTBEAT, [0x55, 0xaa, 0x00, 0x00, 0x00, 0x00, 0xff]),
        (
            tcmd::PRODUCT_INFO,
            [0x55, 0xaa, 0x00, 0x01, 0x00, 0x00, 0x00],
        ),
        (tcmd::WORK_MODE, [0x55, 0xaa, 0x00, 0x02, 0x00, 0x00, 0x01]),
        // Reset Wi-Fi ack and reset-with-mode ack, from the module.
        (tcmd::RESET_WIFI, [0x55, 0xaa, 0x00, 0x04, 0x00, 0x00, 0x03]),
        (
            tcmd::RESET_WIFI_MODE,
            [0x55, 0xaa, 0x00, 0x05, 0x00, 0x00, 0x04],
        ),
    ];
    for (command, bytes) in cases {
        let frame = tuya::Frame::from_module(command, vec![]);
        tuya_vector(&frame, &bytes);
        assert_eq!(frame.direction(), Direction::HostToDevice);
    }
    // The seed's hex text form parses to the same heartbeat.
    assert_eq!(
        hex::parse("55 aa 00 00 00 00 ff").unwrap(),
        [0x55, 0xaa, 0x00, 0x00, 0x00, 0x00, 0xff]
    );
}

#[test]
fn tuya_layout_only_frames_of_the_basic_table() {
    // The seed prints these with "校验和" in place of the checksum: the checksums below are
    // worked out by hand from the header and data.
    let cases: [(tuya::Frame, &[u8]); 6] = [
        // Heartbeat answers: 0x00 on the first after a reboot, then 0x01.
        (
            tuya::Frame::from_mcu(tcmd::HEARTBEAT, vec![0x00]),
            &[0x55, 0xaa, 0x03, 0x00, 0x00, 0x01, 0x00, 0x03],
        ),
        (
            tuya::Frame::from_mcu(tcmd::HEARTBEAT, vec![0x01]),
            &[0x55, 0xaa, 0x03, 0x00, 0x00, 0x01, 0x01, 0x04],
        ),
        (
            tuya::Frame::from_module(tcmd::QUERY_STATUS, vec![]),
            &[0x55, 0xaa, 0x00, 0x08, 0x00, 0x00, 0x07],
        ),
        // The MCU asks for a reset, and for a reset into AP mode.
        (
            tuya::Frame::from_mcu(tcmd::RESET_WIFI, vec![]),
            &[0x55, 0xaa, 0x03, 0x04, 0x00, 0x00, 0x06],
        ),
        (
            tuya::Frame::from_mcu(tcmd::RESET_WIFI_MODE, vec![0x01]),
            &[0x55, 0xaa, 0x03, 0x05, 0x00, 0x01, 0x01, 0x09],
        ),
        // Module-self-processing work-mode answer: two GPIO numbers.
        (
            tuya::Frame::from_mcu(tcmd::WORK_MODE, vec![0x0e, 0x00]),
            &[0x55, 0xaa, 0x03, 0x02, 0x00, 0x02, 0x0e, 0x00, 0x14],
        ),
    ];
    for (frame, bytes) in cases {
        tuya_vector(&frame, bytes);
        let want = if bytes[2] == 0x03 {
            Direction::DeviceToHost
        } else {
            Direction::HostToDevice
        };
        assert_eq!(frame.direction(), want);
    }
}

#[test]
fn tuya_product_info_reply_exactly_as_printed() {
    // The seed's byte table, row by row.
    let bytes: [u8; 49] = [
        0x55, 0xaa, 0x03, 0x01, 0x00, 0x2a, 0x7b, 0x22, 0x70, 0x22, 0x3a, 0x22, 0x52, 0x4e, 0x32,
        0x46, //
        0x56, 0x41, 0x67, 0x58, 0x47, 0x36, 0x57, 0x66, 0x41, 0x6b, 0x74, 0x55, 0x22, 0x2c, 0x22,
        0x76, //
        0x22, 0x3a, 0x22, 0x31, 0x2e, 0x30, 0x2e, 0x30, 0x22, 0x2c, 0x22, 0x6d, 0x22, 0x3a, 0x30,
        0x7d, //
        0x0c,
    ];
    let json = r#"{"p":"RN2FVAgXG6WfAktU","v":"1.0.0","m":0}"#;
    assert_eq!(json.len(), 0x2a);
    assert_eq!(
        sum_mod_256(&bytes[..48]),
        0x0c,
        "the printed checksum is right"
    );

    let frame = tuya::Frame::from_mcu(tcmd::PRODUCT_INFO, json.as_bytes().to_vec());
    tuya_vector(&frame, &bytes);

    let got = decode_one(TuyaDecoder::new, &bytes);
    assert_eq!(got.version, 0x03);
    assert_eq!(got.direction(), Direction::DeviceToHost);
    assert_eq!(got.command, 0x01);
    let info: serde_json::Value = serde_json::from_slice(&got.data).unwrap();
    assert_eq!(info["p"], "RN2FVAgXG6WfAktU");
    assert_eq!(info["v"], "1.0.0");
    assert_eq!(info["m"], 0);
}

#[test]
fn tuya_ota_packets_of_the_530_byte_example() {
    let image: Vec<u8> = (0..530u32).map(|i| (i * 7 + 3) as u8).collect();

    // OTA start: image size 530 as u32 BE.
    tuya_vector(
        &tuya::Frame::from_module(tcmd::OTA_START, 530u32.to_be_bytes().to_vec()),
        &[
            0x55, 0xaa, 0x00, 0x0a, 0x00, 0x04, 0x00, 0x00, 0x02, 0x12, 0x21,
        ],
    );

    // (printed header: version..offset, packet data range)
    let packets: [([u8; 10], std::ops::Range<usize>); 4] = [
        (
            [0x55, 0xaa, 0x00, 0x0b, 0x01, 0x04, 0x00, 0x00, 0x00, 0x00],
            0..256,
        ),
        (
            [0x55, 0xaa, 0x00, 0x0b, 0x01, 0x04, 0x00, 0x00, 0x01, 0x00],
            256..512,
        ),
        (
            [0x55, 0xaa, 0x00, 0x0b, 0x00, 0x16, 0x00, 0x00, 0x02, 0x00],
            512..530,
        ),
        (
            [0x55, 0xaa, 0x00, 0x0b, 0x00, 0x04, 0x00, 0x00, 0x02, 0x12],
            530..530,
        ),
    ];
    for (header, range) in packets {
        let mut data = (range.start as u32).to_be_bytes().to_vec();
        data.extend_from_slice(&image[range.clone()]);
        let frame = tuya::Frame::from_module(tcmd::OTA_PACKET, data);

        let mut want = header.to_vec();
        want.extend_from_slice(&image[range.clone()]);
        want.push(sum_mod_256(&want));
        tuya_vector(&frame, &want);

        let got = decode_one(TuyaDecoder::new, &want);
        assert_eq!(got.command, 0x0b);
        assert_eq!(
            usize::from(u16::from_be_bytes([want[4], want[5]])),
            4 + range.len()
        );
        assert_eq!(be32(&got.data, 0) as usize, range.start, "packet offset");
        assert_eq!(&got.data[4..], &image[range]);
    }
    // The last packet: offset == size, no data, fully printed.
    tuya_vector(
        &tuya::Frame::from_module(tcmd::OTA_PACKET, 530u32.to_be_bytes().to_vec()),
        &[
            0x55, 0xaa, 0x00, 0x0b, 0x00, 0x04, 0x00, 0x00, 0x02, 0x12, 0x22,
        ],
    );
    // The MCU's empty ack.
    tuya_vector(
        &tuya::Frame::from_mcu(tcmd::OTA_PACKET, vec![]),
        &[0x55, 0xaa, 0x03, 0x0b, 0x00, 0x00, 0x0d],
    );
}

/// One data point in a frame, checked three ways: the DP bytes, the frame bytes, and decoding.
fn dp_vector(from_module: bool, dp_point: DataPoint, frame_bytes: &[u8]) {
    let data = dp::encode(std::slice::from_ref(&dp_point)).unwrap();
    assert_eq!(data, frame_bytes[6..frame_bytes.len() - 1], "DP bytes");
    let frame = if from_module {
        tuya::Frame::from_module(tcmd::DP_COMMAND, data)
    } else {
        tuya::Frame::from_mcu(tcmd::DP_REPORT, data)
    };
    tuya_vector(&frame, frame_bytes);
    let got = decode_one(TuyaDecoder::new, frame_bytes);
    assert_eq!(dp::decode(&got.data).unwrap(), vec![dp_point]);
}

#[test]
fn tuya_dp_examples_written_out() {
    // DP 1 power on, module command: 55 aa 00 06 00 05 01 01 00 01 01 <sum>
    dp_vector(
        true,
        DataPoint {
            id: 1,
            value: DpValue::Bool(true),
        },
        &[
            0x55, 0xaa, 0x00, 0x06, 0x00, 0x05, 0x01, 0x01, 0x00, 0x01, 0x01, 0x0e,
        ],
    );
    // DP 1 power off, MCU report.
    dp_vector(
        false,
        DataPoint {
            id: 1,
            value: DpValue::Bool(false),
        },
        &[
            0x55, 0xaa, 0x03, 0x07, 0x00, 0x05, 0x01, 0x01, 0x00, 0x01, 0x00, 0x11,
        ],
    );
    // DP 6 battery 75 %, value type, 4 bytes BE.
    dp_vector(
        false,
        DataPoint {
            id: 6,
            value: DpValue::Value(75),
        },
        &[
            0x55, 0xaa, 0x03, 0x07, 0x00, 0x08, 0x06, 0x02, 0x00, 0x04, 0x00, 0x00, 0x00, 0x4b,
            0x68,
        ],
    );
    // DP 18 fault bitmap, 1 byte: edge sweep (bit 0), left wheel (bit 2), collision (bit 6).
    dp_vector(
        false,
        DataPoint {
            id: 18,
            value: DpValue::Bitmap {
                bits: 0b0100_0101,
                width: 1,
            },
        },
        &[
            0x55, 0xaa, 0x03, 0x07, 0x00, 0x05, 0x12, 0x05, 0x00, 0x01, 0x45, 0x6b,
        ],
    );
    // DP 3 mode "smart" (2), module command; and the MCU reporting "chargego" (0x0b).
    dp_vector(
        true,
        DataPoint {
            id: 3,
            value: DpValue::Enum(2),
        },
        &[
            0x55, 0xaa, 0x00, 0x06, 0x00, 0x05, 0x03, 0x04, 0x00, 0x01, 0x02, 0x14,
        ],
    );
    dp_vector(
        false,
        DataPoint {
            id: 3,
            value: DpValue::Enum(0x0b),
        },
        &[
            0x55, 0xaa, 0x03, 0x07, 0x00, 0x05, 0x03, 0x04, 0x00, 0x01, 0x0b, 0x21,
        ],
    );
    // DP 15 clean record, the seed's example string (23 bytes).
    let record = "20180411051102008000020";
    let mut bytes = vec![0x55, 0xaa, 0x03, 0x07, 0x00, 0x1b, 0x0f, 0x03, 0x00, 0x17];
    bytes.extend_from_slice(record.as_bytes());
    bytes.push(0xc1);
    dp_vector(
        false,
        DataPoint {
            id: 15,
            value: DpValue::String(record.to_string()),
        },
        &bytes,
    );
    // DP 19 map parameters, raw: the seed's example 0x0000ff (origin top left, 255 max).
    dp_vector(
        false,
        DataPoint {
            id: 19,
            value: DpValue::Raw(vec![0x00, 0x00, 0xff]),
        },
        &[
            0x55, 0xaa, 0x03, 0x07, 0x00, 0x07, 0x13, 0x00, 0x00, 0x03, 0x00, 0x00, 0xff, 0x25,
        ],
    );
}

/// The seed's function table: (dpid, type byte, value length, sent by the module too).
const FUNCTION_TABLE: [(u8, u8, usize, bool); 19] = [
    (1, 0x01, 1, true),
    (2, 0x01, 1, true),
    (3, 0x04, 1, true),
    (4, 0x04, 1, true),
    (5, 0x04, 1, false),
    (6, 0x02, 4, false),
    (7, 0x02, 4, false),
    (8, 0x02, 4, false),
    (9, 0x02, 4, false),
    (10, 0x01, 1, true),
    (11, 0x01, 1, true),
    (12, 0x01, 1, true),
    (13, 0x01, 1, true),
    (14, 0x04, 1, true),
    (15, 0x03, 5, false),
    (16, 0x02, 4, false),
    (17, 0x02, 4, false),
    (18, 0x05, 1, false),
    (19, 0x00, 3, false),
];

#[test]
fn tuya_function_table_layouts() {
    for (id, ty, len, module_sends) in FUNCTION_TABLE {
        // A sample value of the right type and length, with its bytes written out by hand.
        let (value, value_bytes): (DpValue, Vec<u8>) = match ty {
            0x00 => (DpValue::Raw(vec![0x01, 0x20, 0x30]), vec![0x01, 0x20, 0x30]),
            0x01 => (DpValue::Bool(true), vec![0x01]),
            0x02 => (DpValue::Value(999), vec![0x00, 0x00, 0x03, 0xe7]),
            0x03 => (DpValue::String("hello".into()), b"hello".to_vec()),
            0x04 => (DpValue::Enum(4), vec![0x04]),
            0x05 => (
                DpValue::Bitmap {
                    bits: 0x7f,
                    width: 1,
                },
                vec![0x7f],
            ),
            _ => unreachable!(),
        };
        assert_eq!(value_bytes.len(), len);
        assert_eq!(value.dp_type().byte(), ty);
        let point = DataPoint { id, value };

        let mut directions = vec![(0x03u8, 0x07u8)];
        if module_sends {
            directions.push((0x00, 0x06));
        }
        for (version, command) in directions {
            // 55 aa ver cmd 00 (4+len) | dpid type 00 len | value | sum
            let mut want = vec![0x55, 0xaa, version, command, 0x00, (4 + len) as u8];
            want.extend_from_slice(&[id, ty, 0x00, len as u8]);
            want.extend_from_slice(&value_bytes);
            want.push(sum_mod_256(&want));
            dp_vector(version == 0x00, point.clone(), &want);
        }
    }
}

#[test]
fn tuya_query_answer_burst_of_reports() {
    // Query status (0x08) is answered with one 0x07 per data point, back to back.
    let reports: Vec<Vec<u8>> = FUNCTION_TABLE
        .iter()
        .filter(|(_, ty, _, _)| *ty == 0x01)
        .map(|&(id, ..)| {
            let mut f = vec![
                0x55, 0xaa, 0x03, 0x07, 0x00, 0x05, id, 0x01, 0x00, 0x01, 0x00,
            ];
            f.push(sum_mod_256(&f));
            f
        })
        .collect();
    let mut dec = TuyaDecoder::new();
    dec.push(&reports.concat());
    let ids: Vec<u8> = dec
        .by_ref()
        .map(|item| {
            let frame = item.unwrap();
            let dps = dp::decode(&frame.data).unwrap();
            assert_eq!(dps.len(), 1);
            assert_eq!(dps[0].value, DpValue::Bool(false));
            dps[0].id
        })
        .collect();
    assert_eq!(ids, vec![1, 2, 10, 11, 12, 13]);
    assert_eq!(dec.finish(), None);
}

// ---------------------------------------------------------------------------------------------
// MSP (seed 000): no hex is printed, so the bytes below are worked out from the layouts:
// request FF opt dev cmd size data crc, crc = dev^cmd^size^data; reply FF kind cmd size data crc,
// crc = cmd^size^data (PROTOCOL_NOTES section 1). Multi-byte fields are little-endian.
// ---------------------------------------------------------------------------------------------

fn msp_request_vector(req: &msp::Request, bytes: &[u8]) {
    assert_eq!(req.encode().unwrap(), bytes, "encoding {req:?}");
    assert_eq!(req.wire_len(), bytes.len());
    assert_eq!(&decode_one(RequestDecoder::new, bytes), req);
}

fn msp_reply_vector(reply: &msp::Reply, bytes: &[u8]) {
    assert_eq!(reply.encode().unwrap(), bytes, "encoding {reply:?}");
    assert_eq!(reply.wire_len(), bytes.len());
    assert_eq!(&decode_one(ReplyDecoder::new, bytes), reply);
}

#[test]
fn msp_requests_from_the_layouts() {
    // GET_PWMVALUE 130 (0x82) to device 0x03: crc = 03 ^ 82 ^ 00 = 81.
    msp_request_vector(
        &msp::Request::new(0x03, 130, vec![]),
        &[0xff, 0xff, 0x03, 0x82, 0x00, 0x81],
    );
    // CMD_VERSION to the core device 0x00: crc = 00 ^ 02 ^ 00 = 02.
    msp_request_vector(
        &msp::Request::new(msp::DEVICE_CORE, msp::CMD_VERSION, vec![]),
        &[0xff, 0xff, 0x00, 0x02, 0x00, 0x02],
    );
    // SET_PWMVALUE 220 (0xdc), pwmValue 85 (0x55): crc = 03 ^ dc ^ 01 ^ 55 = 8b.
    msp_request_vector(
        &msp::Request::new(0x03, 220, vec![85]),
        &[0xff, 0xff, 0x03, 0xdc, 0x01, 0x55, 0x8b],
    );
    // SET_GYRO_THRESHOLD 226 (0xe2) 140/100/100/45: crc = 03^e2^04^8c^64^64^2d = 44.
    msp_request_vector(
        &msp::Request::new(0x03, 226, vec![140, 100, 100, 45]),
        &[0xff, 0xff, 0x03, 0xe2, 0x04, 0x8c, 0x64, 0x64, 0x2d, 0x44],
    );
    // SET_SPRAY_VALUE 225 (0xe1): pump 1, duration 150 ms (u16 LE 96 00), angle 30, count 2.
    let spray = [
        0xff, 0xff, 0x03, 0xe1, 0x05, 0x01, 0x96, 0x00, 0x1e, 0x02, 0x6c,
    ];
    msp_request_vector(
        &msp::Request::new(0x03, 225, vec![0x01, 0x96, 0x00, 30, 2]),
        &spray,
    );
    let got = decode_one(RequestDecoder::new, &spray);
    assert_eq!(le16(&got.data, 1), 150);
    // SET_USE_FAN_OUTPUT_PID 222 (0xde), size 9: crc = 6d.
    msp_request_vector(
        &msp::Request::new(
            0x03,
            222,
            vec![85, 77, 100, 0x13, 0x01, 0x2c, 0x01, 0xfa, 0x00],
        ),
        &[
            0xff, 0xff, 0x03, 0xde, 0x09, 0x55, 0x4d, 0x64, 0x13, 0x01, 0x2c, 0x01, 0xfa, 0x00,
            0x6d,
        ],
    );
    // A silent ping (option 0xfe: act, do not answer): crc = 03 ^ 01 ^ 00 = 02.
    let silent = msp::Request {
        option: msp::OPTION_SILENT,
        device: 0x03,
        command: msp::CMD_PING,
        data: vec![],
    };
    assert!(!silent.wants_answer());
    assert!(msp::Request::new(3, 1, vec![]).wants_answer());
    msp_request_vector(&silent, &[0xff, 0xfe, 0x03, 0x01, 0x00, 0x02]);
}

#[test]
fn msp_replies_from_the_layouts() {
    // GET_USE_FAN_OUTPUT_PID 132 (0x84), size 9: idle 85, min 77, max 100, targets 275/300/250
    // as u16 LE; crc = 84 ^ 09 ^ data = 34.
    let bytes = [
        0xff, 0xff, 0x84, 0x09, 0x55, 0x4d, 0x64, 0x13, 0x01, 0x2c, 0x01, 0xfa, 0x00, 0x34,
    ];
    msp_reply_vector(
        &msp::Reply::new(
            132,
            vec![0x55, 0x4d, 0x64, 0x13, 0x01, 0x2c, 0x01, 0xfa, 0x00],
        ),
        &bytes,
    );
    let got = decode_one(ReplyDecoder::new, &bytes);
    assert_eq!(got.kind, ReplyKind::Reply);
    assert_eq!(got.command, 132);
    assert_eq!(&got.data[..3], &[85, 77, 100]);
    let targets = [le16(&got.data, 3), le16(&got.data, 5), le16(&got.data, 7)];
    assert_eq!(targets, [275, 300, 250]);
    assert_eq!(f64::from(targets[0]) / 100.0, 2.75);

    // The simple response (ack) to SET_PWMVALUE 220: size 0, crc = dc ^ 00 = dc.
    msp_reply_vector(
        &msp::Reply::new(220, vec![]),
        &[0xff, 0xff, 0xdc, 0x00, 0xdc],
    );

    // Solar BATTERY_STATE 130: 12.34 V = 1234 (d2 04), state 1 (warning); crc = 56.
    let battery = [0xff, 0xff, 0x82, 0x03, 0xd2, 0x04, 0x01, 0x56];
    msp_reply_vector(&msp::Reply::new(130, vec![0xd2, 0x04, 0x01]), &battery);
    let got = decode_one(ReplyDecoder::new, &battery);
    assert_eq!(le16(&got.data, 0), 1234);
    assert_eq!(got.data[2], 1);

    // An async (0xfe) ATTITUDE 108 (0x6c), 4 x i16 LE: 16, -10, 5, 270; crc = 77.
    let attitude = [
        0xff, 0xfe, 0x6c, 0x08, 0x10, 0x00, 0xf6, 0xff, 0x05, 0x00, 0x0e, 0x01, 0x77,
    ];
    let frame = msp::Reply {
        kind: ReplyKind::Async,
        command: 108,
        data: vec![0x10, 0x00, 0xf6, 0xff, 0x05, 0x00, 0x0e, 0x01],
    };
    msp_reply_vector(&frame, &attitude);
    let got = decode_one(ReplyDecoder::new, &attitude);
    assert_eq!(got.kind, ReplyKind::Async);
    let angles: Vec<i16> = (0..4).map(|i| le16(&got.data, 2 * i) as i16).collect();
    assert_eq!(angles, [16, -10, 5, 270]);
}

#[test]
fn msp_reply_crc_has_no_device_byte() {
    // The seed's reply crc row names <device>; PROTOCOL_NOTES says that is a copy error. A reply
    // carrying the crc computed with the device byte (03 ^ 84 ^ 09 ^ data = 37) is a bad frame.
    let with_device_crc = [
        0xff, 0xff, 0x84, 0x09, 0x55, 0x4d, 0x64, 0x13, 0x01, 0x2c, 0x01, 0xfa, 0x00, 0x37,
    ];
    let mut dec = ReplyDecoder::new();
    dec.push(&with_device_crc);
    match dec.next() {
        Some(Err(botbench::protocol::FrameError::Checksum {
            expected, actual, ..
        })) => {
            assert_eq!(expected, 0x34);
            assert_eq!(actual, 0x37);
        }
        other => panic!("expected a checksum error, got {other:?}"),
    }
}
