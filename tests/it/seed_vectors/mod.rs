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

mod msp_seed;
mod servo_seed;
mod tuya_seed;
