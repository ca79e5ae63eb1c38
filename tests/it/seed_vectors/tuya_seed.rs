//! The Tuya seed (003): every printed frame, the function table and data point examples.

use super::*;

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
