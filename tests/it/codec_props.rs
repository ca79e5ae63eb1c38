//! Property tests of the three codecs and the shared streaming decoder.
//!
//! The oracles here are independent of the code under test: start bytes, header lengths and
//! checksums are restated from the protocol documents, and every decoded item is checked against
//! the very stream bytes it claims to cover.

use std::fmt::Debug;

use botbench::protocol::msp::{self, ReplyDecoder, ReplyKind, RequestDecoder};
use botbench::protocol::servo::{self, ServoDecoder};
use botbench::protocol::tuya::dp::{self, DataPoint, DpError, DpValue};
use botbench::protocol::tuya::{self, TuyaDecoder};
use botbench::protocol::{Decoder, Direction, FrameError, Framing, JUNK_SAMPLE};
use proptest::collection::vec;
use proptest::prelude::*;
use proptest::sample::{Index, select};

use crate::support::sum_mod_256;

// ---------------------------------------------------------------------------------------------
// The protocols, restated for the tests
// ---------------------------------------------------------------------------------------------

/// What the tests need to know about a protocol, independent of its decoder.
struct Proto<P: Framing> {
    new: fn() -> Decoder<P>,
    encode: fn(&P::Frame) -> Vec<u8>,
    /// Whether a byte may begin a frame.
    is_start: fn(u8) -> bool,
    /// The longest frame the decoder accepts.
    max_frame: usize,
    /// How many bytes of a frame it takes to know the frame's length.
    len_known_at: usize,
    /// The checksum of a frame's bytes, worked out by hand (the last byte excluded).
    checksum: fn(&[u8]) -> u8,
}

fn msp_request_proto() -> Proto<msp::RequestFraming> {
    Proto {
        new: RequestDecoder::new,
        encode: |f| f.encode().unwrap(),
        is_start: |b| b == 0xFF,
        max_frame: 255 + 6,
        len_known_at: 5,
        // device ^ command ^ size ^ data: everything after the option byte.
        checksum: |f| f[2..f.len() - 1].iter().fold(0, |a, b| a ^ b),
    }
}

fn msp_reply_proto() -> Proto<msp::ReplyFraming> {
    Proto {
        new: ReplyDecoder::new,
        encode: |f| f.encode().unwrap(),
        is_start: |b| b == 0xFF,
        max_frame: 255 + 5,
        len_known_at: 4,
        // command ^ size ^ data: everything after the kind byte.
        checksum: |f| f[2..f.len() - 1].iter().fold(0, |a, b| a ^ b),
    }
}

fn servo_proto() -> Proto<servo::ServoFraming> {
    Proto {
        new: ServoDecoder::new,
        encode: |f| f.encode().unwrap(),
        is_start: |b| b == 0x12 || b == 0x05,
        max_frame: 255 + 5,
        len_known_at: 4,
        checksum: |f| sum_mod_256(&f[..f.len() - 1]),
    }
}

fn tuya_proto() -> Proto<tuya::TuyaFraming> {
    Proto {
        new: TuyaDecoder::new,
        encode: |f| f.encode().unwrap(),
        is_start: |b| b == 0x55,
        max_frame: 2048 + 7,
        len_known_at: 6,
        checksum: |f| sum_mod_256(&f[..f.len() - 1]),
    }
}

// ---------------------------------------------------------------------------------------------
// Strategies
// ---------------------------------------------------------------------------------------------

fn msp_request(byte: BoxedStrategy<u8>, max: usize) -> BoxedStrategy<msp::Request> {
    (
        prop_oneof![Just(0xFF), Just(0xFE)],
        byte.clone(),
        byte.clone(),
        vec(byte, 0..=max),
    )
        .prop_map(|(option, device, command, data)| msp::Request {
            option,
            device,
            command,
            data,
        })
        .boxed()
}

fn msp_reply(byte: BoxedStrategy<u8>, max: usize) -> BoxedStrategy<msp::Reply> {
    (
        prop_oneof![Just(ReplyKind::Reply), Just(ReplyKind::Async)],
        byte.clone(),
        vec(byte, 0..=max),
    )
        .prop_map(|(kind, command, data)| msp::Reply {
            kind,
            command,
            data,
        })
        .boxed()
}

fn servo_frame(byte: BoxedStrategy<u8>, max: usize) -> BoxedStrategy<servo::Frame> {
    (
        prop_oneof![Just(Direction::HostToDevice), Just(Direction::DeviceToHost)],
        byte.clone(),
        vec(byte, 0..=max),
    )
        .prop_map(|(direction, command, content)| servo::Frame {
            direction,
            command,
            content,
        })
        .boxed()
}

fn tuya_frame(byte: BoxedStrategy<u8>, max: usize) -> BoxedStrategy<tuya::Frame> {
    (
        prop_oneof![Just(0x00), Just(0x03)],
        byte.clone(),
        vec(byte, 0..=max),
    )
        .prop_map(|(version, command, data)| tuya::Frame {
            version,
            command,
            data,
        })
        .boxed()
}

fn any_byte() -> BoxedStrategy<u8> {
    any::<u8>().boxed()
}

/// Bytes that cannot start a frame nor, inside a frame, start a false header that would reach
/// past the frame (used where the expected output must be exact).
fn msp_safe() -> BoxedStrategy<u8> {
    (0u8..0xFE).boxed()
}
fn servo_safe() -> BoxedStrategy<u8> {
    any::<u8>()
        .prop_filter("no header byte", |b| ![0x12, 0x4C, 0x05, 0x1C].contains(b))
        .boxed()
}
fn tuya_safe() -> BoxedStrategy<u8> {
    any::<u8>().prop_filter("no 0x55", |&b| b != 0x55).boxed()
}

/// Bytes weighted towards header bytes, so that false and partial headers are common.
fn biased(headers: &'static [u8]) -> BoxedStrategy<u8> {
    prop_oneof![3 => any::<u8>(), 2 => select(headers)].boxed()
}

/// Chunk sizes, used in turn to cut the stream.
fn chunks() -> impl Strategy<Value = Vec<usize>> {
    vec(prop_oneof![1usize..8, 1usize..300, 1usize..5000], 1..12)
}

// ---------------------------------------------------------------------------------------------
// Running a decoder, and checking what it reports
// ---------------------------------------------------------------------------------------------

#[derive(Debug)]
struct Item<F> {
    /// `last_start()` after the item.
    start: u64,
    /// `stream_offset()` after the item.
    after: u64,
    res: Result<F, FrameError>,
}

/// Pushes `stream` cut by `chunks` (used in turn), drains the decoder after every push, then
/// finishes it. Checks the memory bound and termination on the way.
fn run<P>(proto: &Proto<P>, stream: &[u8], chunks: &[usize]) -> Vec<Item<P::Frame>>
where
    P: Framing,
{
    let mut dec = (proto.new)();
    let mut items = Vec::new();
    // Every item covers at least one new byte, apart from junk reports, which are disjoint: a
    // decoder that yields more than this is looping.
    let limit = 2 * stream.len() + 2;
    let mut at = 0;
    let mut turn = 0;
    while at < stream.len() {
        let n = chunks[turn % chunks.len()].min(stream.len() - at);
        turn += 1;
        dec.push(&stream[at..at + n]);
        at += n;
        assert!(
            dec.buffered() <= proto.max_frame + n,
            "buffered {} after a chunk of {n}",
            dec.buffered()
        );
        while let Some(res) = dec.next() {
            items.push(Item {
                start: dec.last_start(),
                after: dec.stream_offset(),
                res,
            });
            assert!(items.len() <= limit, "the decoder does not terminate");
        }
        assert!(
            dec.buffered() < proto.max_frame,
            "a drained decoder holds {} bytes",
            dec.buffered()
        );
        assert_eq!(dec.stream_offset() + dec.buffered() as u64, at as u64);
    }
    if let Some(err) = dec.finish() {
        items.push(Item {
            start: dec.last_start(),
            after: dec.stream_offset(),
            res: Err(err),
        });
    }
    assert_eq!(dec.finish(), None, "finish() twice");
    assert_eq!(dec.buffered(), 0);
    assert_eq!(dec.stream_offset(), stream.len() as u64);
    items
}

/// The range of stream bytes an item covers.
fn range<P: Framing>(proto: &Proto<P>, item: &Item<P::Frame>) -> (u64, u64) {
    match &item.res {
        Ok(frame) => (item.start, item.start + (proto.encode)(frame).len() as u64),
        Err(err) => (item.start, item.start + err.span() as u64),
    }
}

/// What must hold of any decoder output: each item is true to the bytes it covers, junk is
/// reported once and never overlaps anything else, frames do not overlap, and together the items
/// cover every byte of the stream.
fn check_accounting<P>(proto: &Proto<P>, stream: &[u8], items: &[Item<P::Frame>])
where
    P: Framing,
    P::Frame: Debug,
{
    let slice = |a: u64, b: u64| &stream[a as usize..b as usize];
    let mut covered = 0u64;
    let mut last_start = None;
    let mut last_exclusive_end = 0u64; // end of the last frame or junk
    for item in items {
        let (start, end) = range(proto, item);
        assert!(end <= stream.len() as u64, "{item:?} runs past the stream");
        assert!(
            last_start.is_none_or(|s| start > s),
            "items out of order at {item:?}"
        );
        last_start = Some(start);
        assert!(start <= covered, "bytes {covered}..{start} never reported");
        covered = covered.max(end);
        match &item.res {
            Ok(frame) => {
                assert_eq!((proto.encode)(frame), slice(start, end));
                assert_eq!(item.after, end, "stream_offset after a frame");
                assert!(start >= last_exclusive_end, "{item:?} overlaps");
                last_exclusive_end = end;
            }
            Err(FrameError::Junk { len, sample }) => {
                assert!(*len > 0);
                let n = (*len).min(JUNK_SAMPLE);
                assert_eq!(sample.as_slice(), slice(start, start + n as u64));
                assert_eq!(item.after, end, "stream_offset after junk");
                assert!(start >= last_exclusive_end, "{item:?} overlaps");
                last_exclusive_end = end;
            }
            Err(FrameError::Truncated { bytes, .. }) => {
                assert_eq!(bytes.as_slice(), slice(start, end));
                assert_eq!(end, stream.len() as u64, "only the end is truncated");
            }
            Err(err) => {
                assert_eq!(err.bytes(), slice(start, end));
                assert!((proto.is_start)(stream[start as usize]));
                // The decoder re-synchronises one byte into a bad frame.
                assert_eq!(item.after, start + 1, "stream_offset after {err:?}");
            }
        }
        // No junk is reported inside a bad frame or a frame already reported.
        if let Err(FrameError::Junk { .. }) = &item.res {
            for other in items {
                if std::ptr::eq(other, item) {
                    continue;
                }
                let (a, b) = range(proto, other);
                assert!(b <= start || a >= end, "junk {item:?} overlaps {other:?}");
            }
        }
    }
    assert_eq!(covered, stream.len() as u64, "the tail was never reported");
}

/// Merges junk reports that a chunk boundary split, checking they are contiguous.
fn merge_junk<F: Debug>(items: Vec<Item<F>>) -> Vec<Item<F>> {
    let mut out: Vec<Item<F>> = Vec::new();
    for item in items {
        if let (Some(prev), Err(FrameError::Junk { len, .. })) = (out.last_mut(), &item.res)
            && let Err(FrameError::Junk { len: prev_len, .. }) = &mut prev.res
        {
            assert_eq!(prev.after, item.start, "junk reports are not contiguous");
            *prev_len += len;
            prev.after = item.after;
            continue;
        }
        out.push(item);
    }
    out
}

/// Builds `junk0 frame0 junk1 frame1 ... tail`, returning the stream and each frame's offsets.
fn build<F>(
    proto_encode: fn(&F) -> Vec<u8>,
    segments: &[(Vec<u8>, F)],
    tail: &[u8],
) -> (Vec<u8>, Vec<(u64, u64)>) {
    let mut stream = Vec::new();
    let mut at = Vec::new();
    for (junk, frame) in segments {
        stream.extend_from_slice(junk);
        let start = stream.len() as u64;
        stream.extend_from_slice(&proto_encode(frame));
        at.push((start, stream.len() as u64));
    }
    stream.extend_from_slice(tail);
    (stream, at)
}

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
    let (stream, offsets) = build(proto.encode, segments, tail);
    let items = run(proto, &stream, chunks);
    check_accounting(proto, &stream, &items);
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
    let (stream, offsets) = build(proto.encode, segments, tail);
    let items = run(proto, &stream, chunks);
    check_accounting(proto, &stream, &items);
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
            (tuya_proto(), 2048)
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
    fn tuya_unknown_version_is_an_unknown_header(
        version in any::<u8>().prop_filter("not 0 or 3", |v| *v != 0 && *v != 3),
        next in tuya_frame(any_byte(), 40),
        chunks in chunks(),
    ) {
        let stream = [vec![0x55, 0xAA, version], next.encode().unwrap()].concat();
        let items = run(&tuya_proto(), &stream, &chunks);
        check_accounting(&tuya_proto(), &stream, &items);
        prop_assert_eq!(items.len(), 2);
        prop_assert_eq!(
            &items[0].res,
            &Err(FrameError::UnknownHeader { what: "version", value: version, bytes: vec![0x55, 0xAA, version] })
        );
        prop_assert_eq!(items[1].res.as_ref().ok(), Some(&next));
        prop_assert_eq!(items[1].start, 3);
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
