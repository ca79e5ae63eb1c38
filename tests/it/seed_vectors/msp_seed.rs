//! The MSP seed (000): frames worked out from the documented layouts.

use super::*;

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
