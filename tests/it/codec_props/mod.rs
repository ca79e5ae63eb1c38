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

/// The stream `junk0 frame0 junk1 frame1 ... tail`, each frame's offsets in it, and what the
/// decoder made of it pushed in `chunks` ([`run`]), its accounting checked.
#[allow(clippy::type_complexity)]
fn decoded<P>(
    proto: &Proto<P>,
    segments: &[(Vec<u8>, P::Frame)],
    tail: &[u8],
    chunks: &[usize],
) -> (Vec<u8>, Vec<(u64, u64)>, Vec<Item<P::Frame>>)
where
    P: Framing,
    P::Frame: Debug,
{
    let (stream, offsets) = build(proto.encode, segments, tail);
    let items = run(proto, &stream, chunks);
    check_accounting(proto, &stream, &items);
    (stream, offsets, items)
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

mod streams;
mod tuya_dp;
