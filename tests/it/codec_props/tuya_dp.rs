//! Tuya header errors (length cap, version byte) and the data point codec.

use super::*;

// ---------------------------------------------------------------------------------------------
// Tuya header errors
// ---------------------------------------------------------------------------------------------

fn tuya_small_proto() -> Proto<tuya::TuyaFraming> {
    Proto {
        new: || TuyaDecoder::with_max_data(SMALL_CAP),
        max_frame: SMALL_CAP + 7,
        ..tuya_proto()
    }
}

const SMALL_CAP: usize = 100;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn tuya_length_over_the_cap_is_too_long(
        small in any::<bool>(),
        version in prop_oneof![Just(0x00u8), Just(0x03)],
        command in tuya_safe(),
        over in 1usize..=65535,
        next in tuya_frame(tuya_safe(), 40),
        chunks in chunks(),
    ) {
        let (proto, cap) = if small {
            (tuya_small_proto(), SMALL_CAP)
        } else {
            (tuya_proto(), botbench::protocol::tuya::DEFAULT_MAX_DATA)
        };
        let len = cap + over;
        prop_assume!(len <= 65535);
        let len_bytes = (len as u16).to_be_bytes();
        prop_assume!(!len_bytes.contains(&0x55));
        let header = vec![0x55, 0xAA, version, command, len_bytes[0], len_bytes[1]];
        let stream = [header.clone(), next.encode().unwrap()].concat();
        let items = run(&proto, &stream, &chunks);
        check_accounting(&proto, &stream, &items);
        prop_assert_eq!(items.len(), 2);
        prop_assert_eq!(&items[0].res, &Err(FrameError::TooLong { len, cap, bytes: header }));
        prop_assert_eq!(items[0].start, 0);
        prop_assert_eq!(items[1].res.as_ref().ok(), Some(&next));
        prop_assert_eq!(items[1].start, 6);
    }

    #[test]
    fn tuya_frames_of_any_version_byte_are_read(
        version in any::<u8>(),
        frame in tuya_frame(any_byte(), 40),
        next in tuya_frame(any_byte(), 40),
        chunks in chunks(),
    ) {
        // MCUs send 0x03, 0x01 (MCU SDK v2.3) or 0x00 (PROTOCOL_NOTES §4): the version is
        // kept, never a reason to drop the frame.
        let frame = tuya::Frame { version, ..frame };
        let stream = [frame.encode().unwrap(), next.encode().unwrap()].concat();
        let items = run(&tuya_proto(), &stream, &chunks);
        check_accounting(&tuya_proto(), &stream, &items);
        prop_assert_eq!(items.len(), 2);
        prop_assert_eq!(items[0].res.as_ref().ok(), Some(&frame));
        prop_assert_eq!(items[1].res.as_ref().ok(), Some(&next));
    }

}

#[test]
fn tuya_cap_boundary() {
    let at_cap = tuya::Frame::from_mcu(0x0b, vec![0x01; SMALL_CAP]);
    let mut dec = TuyaDecoder::with_max_data(SMALL_CAP);
    dec.push(&at_cap.encode().unwrap());
    assert_eq!(dec.next(), Some(Ok(at_cap)));

    let over = tuya::Frame::from_mcu(0x0b, vec![0x01; SMALL_CAP + 1]);
    dec.push(&over.encode().unwrap());
    match dec.next() {
        Some(Err(FrameError::TooLong { len, cap, .. })) => {
            assert_eq!((len, cap), (SMALL_CAP + 1, SMALL_CAP));
        }
        other => panic!("{other:?}"),
    }
    // A 1024-byte OTA packet fits the default cap.
    let ota = tuya::Frame::from_module(0x0b, vec![0xAB; 4 + 1024]);
    let mut dec = TuyaDecoder::new();
    dec.push(&ota.encode().unwrap());
    assert_eq!(dec.next(), Some(Ok(ota)));
}

// ---------------------------------------------------------------------------------------------
// Tuya data points
// ---------------------------------------------------------------------------------------------

fn dp_value() -> impl Strategy<Value = DpValue> {
    prop_oneof![
        vec(any::<u8>(), 0..40).prop_map(DpValue::Raw),
        any::<bool>().prop_map(DpValue::Bool),
        any::<i32>().prop_map(DpValue::Value),
        vec(any::<char>(), 0..12).prop_map(|c| DpValue::String(c.into_iter().collect())),
        any::<u8>().prop_map(DpValue::Enum),
        any::<u8>().prop_map(|b| DpValue::Bitmap {
            bits: b.into(),
            width: 1
        }),
        any::<u16>().prop_map(|b| DpValue::Bitmap {
            bits: b.into(),
            width: 2
        }),
        any::<u32>().prop_map(|bits| DpValue::Bitmap { bits, width: 4 }),
    ]
}

fn data_point() -> impl Strategy<Value = DataPoint> {
    (any::<u8>(), dp_value()).prop_map(|(id, value)| DataPoint { id, value })
}

/// A data point's bytes, by hand: `id, type, len u16 BE, value`.
fn dp_wire(point: &DataPoint) -> Vec<u8> {
    let (ty, value): (u8, Vec<u8>) = match &point.value {
        DpValue::Raw(b) => (0, b.clone()),
        DpValue::Bool(b) => (1, vec![*b as u8]),
        DpValue::Value(v) => (2, v.to_be_bytes().to_vec()),
        DpValue::String(s) => (3, s.as_bytes().to_vec()),
        DpValue::Enum(e) => (4, vec![*e]),
        DpValue::Bitmap { bits, width: 1 } => (5, vec![*bits as u8]),
        DpValue::Bitmap { bits, width: 2 } => (5, (*bits as u16).to_be_bytes().to_vec()),
        DpValue::Bitmap { bits, width: 4 } => (5, bits.to_be_bytes().to_vec()),
        DpValue::Bitmap { .. } => unreachable!(),
    };
    let mut out = vec![point.id, ty];
    out.extend_from_slice(&(value.len() as u16).to_be_bytes());
    out.extend_from_slice(&value);
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn dp_lists_round_trip(points in vec(data_point(), 0..8)) {
        let want: Vec<u8> = points.iter().flat_map(dp_wire).collect();
        let bytes = dp::encode(&points).unwrap();
        prop_assert_eq!(&bytes, &want);
        prop_assert_eq!(dp::decode(&bytes).unwrap(), points.clone());

        // And inside a DP report frame through the stream decoder.
        let frame = tuya::Frame::from_mcu(tuya::cmd::DP_REPORT, bytes);
        let mut dec = TuyaDecoder::new();
        dec.push(&frame.encode().unwrap());
        let got = dec.next().unwrap().unwrap();
        prop_assert_eq!(dp::decode(&got.data).unwrap(), points);
    }

    #[test]
    fn dp_arbitrary_bytes_never_panic(bytes in vec(biased(&[0, 1, 2, 3, 4, 5, 6]), 0..64)) {
        // Whatever decodes must re-encode to something that decodes to the same list.
        if let Ok(points) = dp::decode(&bytes) {
            let again = dp::encode(&points).unwrap();
            prop_assert_eq!(dp::decode(&again).unwrap(), points);
        }
    }

    #[test]
    fn dp_cut_inside_a_data_point_is_truncated(
        points in vec(data_point(), 1..6),
        cut in any::<Index>(),
    ) {
        let wires: Vec<Vec<u8>> = points.iter().map(dp_wire).collect();
        let bytes = wires.concat();
        let k = cut.index(bytes.len()); // 0..len: never the whole list
        // The data point the cut falls in, and where it starts.
        let mut offset = 0;
        let mut i = 0;
        while offset + wires[i].len() <= k {
            offset += wires[i].len();
            i += 1;
        }
        prop_assume!(k > offset); // a cut at a boundary is a shorter, valid list
        let have = k - offset;
        let need = if have < 4 { 4 } else { wires[i].len() };
        prop_assert_eq!(
            dp::decode(&bytes[..k]),
            Err(DpError::Truncated { offset, need, have })
        );
    }

    #[test]
    fn dp_unknown_type(id in any::<u8>(), ty in 6u8..=255, value in vec(any::<u8>(), 0..8)) {
        let mut bytes = vec![id, ty];
        bytes.extend_from_slice(&(value.len() as u16).to_be_bytes());
        bytes.extend_from_slice(&value);
        prop_assert_eq!(dp::decode(&bytes), Err(DpError::UnknownType { id, ty }));
    }

    #[test]
    fn dp_length_that_does_not_fit_the_type(
        id in any::<u8>(),
        ty in select(vec![1u8, 2, 4, 5]),
        len in 0usize..9,
    ) {
        let fits = match ty {
            1 | 4 => len == 1,
            2 => len == 4,
            5 => matches!(len, 1 | 2 | 4),
            _ => unreachable!(),
        };
        prop_assume!(!fits);
        let mut bytes = vec![id, ty, 0, len as u8];
        bytes.extend(std::iter::repeat_n(b'a', len));
        let name = ["raw", "bool", "value", "string", "enum", "bitmap"][ty as usize];
        match dp::decode(&bytes) {
            Err(DpError::BadLength { id: i, ty: t, len: l, .. }) => {
                prop_assert_eq!((i, t, l), (id, name, len));
            }
            other => prop_assert!(false, "{:?}", other),
        }
    }

    #[test]
    fn dp_bitmap_wider_than_its_width_is_refused(
        width in prop_oneof![Just(1u8), Just(2), Just(3), Just(4), Just(0), Just(8)],
        bits in any::<u32>(),
    ) {
        let fits = match width {
            1 => bits <= 0xFF,
            2 => bits <= 0xFFFF,
            4 => true,
            _ => false,
        };
        let point = DataPoint { id: 18, value: DpValue::Bitmap { bits, width } };
        let res = dp::encode(std::slice::from_ref(&point));
        if fits {
            prop_assert_eq!(res.unwrap(), dp_wire(&point));
        } else {
            let is_bad_length = matches!(res, Err(DpError::BadLength { id: 18, .. }));
            prop_assert!(is_bad_length, "{:?}", res);
        }
    }
}

#[test]
fn dp_string_that_is_not_utf8() {
    assert_eq!(
        dp::decode(&[15, 3, 0, 2, 0xC3, 0x28]),
        Err(DpError::NotUtf8 { id: 15 })
    );
}

#[test]
fn dp_value_is_signed_big_endian() {
    let points = dp::decode(&[16, 2, 0, 4, 0xFF, 0xFF, 0xFF, 0xFE]).unwrap();
    assert_eq!(points[0].value, DpValue::Value(-2));
}

#[test]
fn flush_rescues_a_frame_held_back_by_a_false_header() {
    // The same stream as above, on a line that then goes quiet: after `flush()` the false
    // header's bytes are junk and the heartbeat behind them comes out.
    let heartbeat = tuya::Frame::from_module(0, vec![]).encode().unwrap();
    let stream = [vec![0x55, 0xaa, 0x00, 0x00, 0x00, 0x40], heartbeat.clone()].concat();
    let mut dec = tuya::TuyaDecoder::new();
    dec.push(&stream);
    assert_eq!(dec.next(), None, "waits for the announced 64 bytes");
    dec.flush();
    assert_eq!(
        dec.next(),
        Some(Err(FrameError::Junk {
            len: 6,
            sample: stream[..6].to_vec()
        }))
    );
    assert_eq!(dec.next(), Some(Ok(tuya::Frame::from_module(0, vec![]))));
    assert_eq!(dec.next(), None);
    assert_eq!(dec.finish(), None);
}

#[test]
fn flush_reports_a_partial_frame_with_nothing_behind_it_as_truncated() {
    let mut dec = servo::ServoDecoder::new();
    dec.push(&[0x05, 0x1c, 0x01, 0x01]);
    assert_eq!(dec.next(), None);
    dec.flush();
    assert_eq!(
        dec.next(),
        Some(Err(FrameError::Truncated {
            have: 4,
            need: Some(6),
            bytes: vec![0x05, 0x1c, 0x01, 0x01]
        }))
    );
    assert_eq!(dec.buffered(), 0);
    // A reply that then arrives whole decodes as usual.
    dec.push(&[0x05, 0x1c, 0x01, 0x01, 0x03, 0x26]);
    assert!(matches!(dec.next(), Some(Ok(_))));
}
