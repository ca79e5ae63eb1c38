//! The bus servo seed (002): every printed frame.

use super::*;

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
