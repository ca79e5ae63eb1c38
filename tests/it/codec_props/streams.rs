//! The stream properties, for any protocol and per protocol, and the deterministic edge cases
//! of the stream engine.

use super::*;

// ---------------------------------------------------------------------------------------------
// The properties, for any protocol
// ---------------------------------------------------------------------------------------------

fn prop_round_trip<P>(proto: &Proto<P>, frame: &P::Frame, wire_len: usize)
where
    P: Framing,
    P::Frame: Debug + PartialEq + Clone,
{
    let bytes = (proto.encode)(frame);
    assert_eq!(bytes.len(), wire_len);
    assert_eq!(
        bytes[bytes.len() - 1],
        (proto.checksum)(&bytes),
        "checksum byte"
    );
    assert!((proto.is_start)(bytes[0]));
    let mut dec = (proto.new)();
    dec.push(&bytes);
    let got: Vec<Result<P::Frame, FrameError>> = dec.by_ref().collect();
    assert_eq!(got, vec![Ok(frame.clone())]);
    assert_eq!(
        (dec.last_start(), dec.stream_offset()),
        (0, bytes.len() as u64)
    );
    assert_eq!(dec.finish(), None);
}

/// Frames among junk that cannot start a frame all come out, exactly, with exact junk counts.
fn prop_clean_stream<P>(
    proto: &Proto<P>,
    segments: &[(Vec<u8>, P::Frame)],
    tail: &[u8],
    chunks: &[usize],
) where
    P: Framing,
    P::Frame: Debug + PartialEq + Clone,
{
    let (stream, offsets, items) = decoded(proto, segments, tail, chunks);
    let items = merge_junk(items);

    let mut want: Vec<(u64, u64, Result<P::Frame, usize>)> = Vec::new();
    let mut junk_start = 0u64;
    for ((junk, frame), (start, end)) in segments.iter().zip(&offsets) {
        if !junk.is_empty() {
            want.push((junk_start, *start, Err(junk.len())));
        }
        want.push((*start, *end, Ok(frame.clone())));
        junk_start = *end;
    }
    if !tail.is_empty() {
        want.push((junk_start, stream.len() as u64, Err(tail.len())));
    }
    let got: Vec<(u64, u64, Result<P::Frame, usize>)> = items
        .into_iter()
        .map(|item| {
            let res = match item.res {
                Ok(f) => Ok(f),
                Err(FrameError::Junk { len, .. }) => Err(len),
                Err(other) => panic!("unexpected {other:?} at {}", item.start),
            };
            (item.start, item.after, res)
        })
        .collect();
    assert_eq!(got, want);
}

/// Frames among arbitrary junk: each frame comes out at its offset, unless the junk held a false
/// header that covers it. That can happen two ways, both inherent to length-framed protocols:
/// - the false header's frame checks out and runs into the real one (see
///   `false_header_with_a_good_checksum_swallows_the_next_frame`);
/// - the false header announces more bytes than the stream has left, so at the end `finish()`
///   reports everything from it on as one `Truncated` (see
///   `finish_does_not_rescan_behind_a_false_header`).
///
/// Anything else losing a frame is a decoder bug.
fn prop_arbitrary_junk<P>(
    proto: &Proto<P>,
    segments: &[(Vec<u8>, P::Frame)],
    tail: &[u8],
    chunks: &[usize],
) where
    P: Framing,
    P::Frame: Debug + PartialEq + Clone,
{
    let (_, offsets, items) = decoded(proto, segments, tail, chunks);
    let frames: Vec<(u64, u64, &P::Frame)> = items
        .iter()
        .filter_map(|i| i.res.as_ref().ok().map(|f| (i.start, i.after, f)))
        .collect();
    for ((_, frame), (start, end)) in segments.iter().zip(&offsets) {
        let found = frames.iter().find(|(s, _, _)| s == start);
        match found {
            Some((_, after, got)) => {
                assert_eq!(*got, frame);
                assert_eq!(after, end);
            }
            None => {
                let swallowed = frames.iter().any(|(s, e, _)| s < start && e > start);
                let truncated_tail = items.last().is_some_and(|last| {
                    matches!(last.res, Err(FrameError::Truncated { .. })) && last.start < *start
                });
                assert!(
                    swallowed || truncated_tail,
                    "frame at {start} lost, and no false header covers it: {items:?}"
                );
            }
        }
    }
}

/// A frame with a corrupted checksum gives `Checksum` with both values right, and the next frame
/// still decodes; the rest of the bad frame is not reported again as junk.
fn prop_checksum<P>(
    proto: &Proto<P>,
    bad: &P::Frame,
    delta: u8,
    next: &P::Frame,
    chunks: &[usize],
) -> Result<(), TestCaseError>
where
    P: Framing,
    P::Frame: Debug + PartialEq + Clone,
{
    let mut bad_bytes = (proto.encode)(bad);
    let last = bad_bytes.len() - 1;
    let good_sum = (proto.checksum)(&bad_bytes);
    let wrong = good_sum.wrapping_add(delta);
    prop_assume!(!(proto.is_start)(wrong));
    bad_bytes[last] = wrong;
    let next_bytes = (proto.encode)(next);
    let stream = [bad_bytes.clone(), next_bytes.clone()].concat();

    let items = run(proto, &stream, chunks);
    check_accounting(proto, &stream, &items);
    assert_eq!(items.len(), 2, "{items:?}");
    assert_eq!(
        items[0].res,
        Err(FrameError::Checksum {
            expected: good_sum,
            actual: wrong,
            bytes: bad_bytes.clone(),
        })
    );
    assert_eq!(items[0].start, 0);
    assert_eq!(items[1].res.as_ref().ok(), Some(next));
    assert_eq!(items[1].start, bad_bytes.len() as u64);
    assert_eq!(items[1].after, stream.len() as u64);
    Ok(())
}

/// `finish()` reports a partial frame as `Truncated`, with the length once the header has it.
fn prop_truncated<P>(
    proto: &Proto<P>,
    before: &[P::Frame],
    frame: &P::Frame,
    cut: Index,
    chunks: &[usize],
) where
    P: Framing,
    P::Frame: Debug + PartialEq + Clone,
{
    let whole = (proto.encode)(frame);
    let k = 1 + cut.index(whole.len() - 1); // 1..len: a strict prefix
    let mut stream: Vec<u8> = before.iter().flat_map(|f| (proto.encode)(f)).collect();
    let at = stream.len() as u64;
    stream.extend_from_slice(&whole[..k]);

    let items = run(proto, &stream, chunks);
    check_accounting(proto, &stream, &items);
    let (last, frames) = items.split_last().expect("a Truncated report");
    let got: Vec<&P::Frame> = frames.iter().map(|i| i.res.as_ref().unwrap()).collect();
    assert_eq!(got, before.iter().collect::<Vec<_>>());
    let need = (k >= proto.len_known_at).then_some(whole.len());
    assert_eq!(
        last.res,
        Err(FrameError::Truncated {
            have: k,
            need,
            bytes: whole[..k].to_vec(),
        })
    );
    assert_eq!(last.start, at);
}

// ---------------------------------------------------------------------------------------------
// The properties, per protocol
// ---------------------------------------------------------------------------------------------

macro_rules! protocol_props {
    ($name:ident, $proto:expr, $frame:expr, $safe:expr, $junk:expr, $headers:expr) => {
        mod $name {
            use super::*;

            proptest! {
                #![proptest_config(ProptestConfig::with_cases(96))]

                #[test]
                fn round_trip(frame in $frame(any_byte(), 255)) {
                    let wire_len = frame.wire_len();
                    prop_round_trip(&$proto, &frame, wire_len);
                }

                #[test]
                fn frames_among_non_start_junk_all_come_out_exactly(
                    segments in vec((vec($junk, 0..20), $frame(any_byte(), 40)), 0..10),
                    tail in vec($junk, 0..20),
                    chunks in chunks(),
                ) {
                    prop_clean_stream(&$proto, &segments, &tail, &chunks);
                }

                #[test]
                fn frames_among_arbitrary_junk_are_never_lost(
                    segments in vec((vec(biased($headers), 0..24), $frame(any_byte(), 40)), 0..10),
                    tail in vec(biased($headers), 0..24),
                    chunks in chunks(),
                ) {
                    prop_arbitrary_junk(&$proto, &segments, &tail, &chunks);
                }

                #[test]
                fn arbitrary_bytes_in_arbitrary_chunks(
                    stream in vec(biased($headers), 0..3000),
                    chunks in chunks(),
                ) {
                    let items = run(&$proto, &stream, &chunks);
                    check_accounting(&$proto, &stream, &items);
                }

                #[test]
                fn bad_checksum_is_reported_and_the_next_frame_decodes(
                    bad in $frame($safe, 40),
                    delta in 1u8..=255,
                    next in $frame($safe, 40),
                    chunks in chunks(),
                ) {
                    prop_checksum(&$proto, &bad, delta, &next, &chunks)?;
                }

                #[test]
                fn finish_reports_a_partial_frame_as_truncated(
                    before in vec($frame(any_byte(), 40), 0..4),
                    frame in $frame(any_byte(), 60),
                    cut in any::<Index>(),
                    chunks in chunks(),
                ) {
                    prop_truncated(&$proto, &before, &frame, cut, &chunks);
                }
            }
        }
    };
}

protocol_props!(
    msp_request_props,
    msp_request_proto(),
    msp_request,
    msp_safe(),
    0u8..0xFF,
    &[0xFF, 0xFE]
);
protocol_props!(
    msp_reply_props,
    msp_reply_proto(),
    msp_reply,
    msp_safe(),
    0u8..0xFF,
    &[0xFF, 0xFE]
);
protocol_props!(
    servo_props,
    servo_proto(),
    servo_frame,
    servo_safe(),
    any::<u8>().prop_filter("not a start byte", |b| *b != 0x12 && *b != 0x05),
    &[0x12, 0x4C, 0x05, 0x1C]
);
protocol_props!(
    tuya_props,
    tuya_proto(),
    tuya_frame,
    tuya_safe(),
    any::<u8>().prop_filter("not a start byte", |b| *b != 0x55),
    &[0x55, 0xAA, 0x00, 0x03]
);

// ---------------------------------------------------------------------------------------------
// Deterministic edge cases of the stream engine
// ---------------------------------------------------------------------------------------------

#[test]
fn false_header_with_a_good_checksum_swallows_the_next_frame() {
    // Servo junk `12 4c b4 00` announces an empty frame whose checksum byte is the next frame's
    // first byte: 0x12 + 0x4c + 0xb4 + 0x00 = 0x112, i.e. 0x12. The protocol cannot tell this
    // from a real frame; the real frame's header is eaten and its remaining bytes become junk.
    let real = servo::Frame::request(1, vec![3]).encode().unwrap();
    let stream = [vec![0x12, 0x4c, 0xb4, 0x00], real.clone()].concat();
    let items = run(&servo_proto(), &stream, &[stream.len()]);
    check_accounting(&servo_proto(), &stream, &items);
    assert_eq!(
        items[0].res.as_ref().ok(),
        Some(&servo::Frame::request(0xb4, vec![]))
    );
    assert!(
        items
            .iter()
            .all(|i| i.res.as_ref().ok() != Some(&servo::Frame::request(1, vec![3])))
    );
}

#[test]
fn finish_does_not_rescan_behind_a_false_header() {
    // Junk `55 aa 00 00 00 40` announces 64 data bytes; a real heartbeat follows and then the
    // stream ends. The decoder waits for the false frame to complete, and `finish()` reports
    // everything from the false header on as one truncated frame: the heartbeat is not decoded.
    // (On a live port the wait ends only when more bytes arrive; see the report of this branch.)
    let heartbeat = tuya::Frame::from_module(0, vec![]).encode().unwrap();
    let stream = [vec![0x55, 0xaa, 0x00, 0x00, 0x00, 0x40], heartbeat].concat();
    let items = run(&tuya_proto(), &stream, &[stream.len()]);
    check_accounting(&tuya_proto(), &stream, &items);
    assert_eq!(items.len(), 1);
    assert_eq!(
        items[0].res,
        Err(FrameError::Truncated {
            have: 13,
            need: Some(71),
            bytes: stream.clone(),
        })
    );
}

#[test]
fn msp_option_byte_that_is_no_option_is_not_a_header() {
    // `FF 00 ...` is junk to the request decoder, and a request is junk to the reply decoder
    // only where its option byte is neither 0xFF nor 0xFE.
    let mut dec = RequestDecoder::new();
    let frame = msp::Request::new(3, 130, vec![]);
    dec.push(&[[0xFF, 0x00, 0x01].as_slice(), &frame.encode().unwrap()].concat());
    let got: Vec<_> = dec.by_ref().collect();
    assert_eq!(
        got,
        vec![
            Err(FrameError::Junk {
                len: 3,
                sample: vec![0xFF, 0x00, 0x01]
            }),
            Ok(frame)
        ]
    );
}

#[test]
fn junk_sample_is_capped_but_the_count_is_exact() {
    let junk = vec![0x11u8; 1000];
    let frame = tuya::Frame::from_module(0, vec![]);
    let stream = [junk.clone(), frame.encode().unwrap()].concat();
    let mut dec = TuyaDecoder::new();
    dec.push(&stream);
    match dec.next() {
        Some(Err(FrameError::Junk { len, sample })) => {
            assert_eq!(len, 1000);
            assert_eq!(sample, vec![0x11; JUNK_SAMPLE]);
        }
        other => panic!("{other:?}"),
    }
    assert_eq!((dec.last_start(), dec.stream_offset()), (0, 1000));
    assert_eq!(dec.next(), Some(Ok(frame)));
    assert_eq!((dec.last_start(), dec.stream_offset()), (1000, 1007));
}

#[test]
fn clear_drops_a_partial_frame_and_keeps_offsets_running() {
    let frame = servo::Frame::request(1, vec![3]).encode().unwrap();
    let mut dec = ServoDecoder::new();
    dec.push(&frame[..3]);
    assert_eq!(dec.next(), None);
    assert_eq!(dec.buffered(), 3);
    dec.clear();
    assert_eq!(dec.buffered(), 0);
    assert_eq!(dec.finish(), None);
    dec.push(&frame);
    assert!(matches!(dec.next(), Some(Ok(_))));
    assert_eq!(
        (dec.last_start(), dec.stream_offset()),
        (3, 3 + frame.len() as u64)
    );
}
