//! A capture's bytes decoded into frames, each stamped with the time its last byte arrived
//! (for `botbench frame decode --capture` and the packet monitor's offline view).

use super::format::CaptureFile;
use crate::packet::{Item, MspDirection, decode_all};
use crate::profile::Protocol;
use crate::protocol::Direction;

/// One frame (or frame error) found in a capture.
#[derive(Debug, Clone)]
pub struct CapturedFrame {
    /// When its last byte was written or read, in microseconds since the Unix epoch.
    pub at_us: u64,
    /// Which way it went.
    pub direction: Direction,
    /// The frame or what was wrong with the bytes; `offset` counts bytes in its direction's
    /// stream from the start of the capture.
    pub item: Item,
}

/// Every frame of both directions of `capture`, decoded as `protocol` frames (MSP: requests
/// out, replies in), in the order their last bytes crossed (outbound first at equal times).
/// Each direction is decoded as one stream, so a frame split over chunks (an adapter's latency
/// tick) is one frame.
pub fn frames(capture: &CaptureFile, protocol: Protocol) -> Vec<CapturedFrame> {
    let mut out = Vec::new();
    for (direction, msp_dir) in [
        (Direction::HostToDevice, MspDirection::Requests),
        (Direction::DeviceToHost, MspDirection::Replies),
    ] {
        let mut stream = Vec::new();
        // (end offset of the chunk in the stream, its time)
        let mut ends = Vec::new();
        for c in capture.chunks.iter().filter(|c| c.direction == direction) {
            stream.extend_from_slice(&c.bytes);
            ends.push((stream.len() as u64, c.at_us));
        }
        for item in decode_all(protocol, msp_dir, &stream) {
            let last = item.offset + item.len.max(1) as u64;
            let i = ends.partition_point(|(end, _)| *end < last);
            let at_us = ends.get(i).or(ends.last()).map_or(0, |(_, t)| *t);
            out.push(CapturedFrame {
                at_us,
                direction,
                item,
            });
        }
    }
    out.sort_by_key(|f| (f.at_us, f.direction == Direction::DeviceToHost));
    out
}
