//! Looking for one servo id across baud rates (a fresh servo at any rate, a servo lost after a
//! baud change), without paying a silent rate's full grace before the connection is known.
//!
//! A ping that goes unanswered is listened to for the link's grace before the port may change
//! rate: an answer still on its way would otherwise be read at the next rate, and taken for the
//! answer there. Until answers have been measured on the connection that grace is long (150 ms),
//! so a search that began at the wrong rates paid it at each. A search here goes in three steps:
//!
//! 1. a **hint pass**: one ping at each rate at the bus's pace ([`ping_sweep`], no grace) until
//!    one hears something (when none does, the grace once, at the last rate, for the answers
//!    still on their way). What it hears is only a hint: an answer that came late is heard at a
//!    later rate;
//! 2. the **search** itself, each rate pinged as an exchange with its grace, as before, but the
//!    rate where the hint pass heard something first (the port still at it: the only answer
//!    that can still be on its way is that rate's own), then the rate pinged just before it
//!    (where a late answer came from), then the others;
//! 3. once the servo has answered, its answer latency is **measured** with a few more pings at
//!    the bus's pace, listened to for the grace at the end (their answers all read at this
//!    rate): the link's grace then fits the connection (down to the frame gap with no
//!    adapter latency; a few latency ticks behind a USB adapter), and the silent rates still to
//!    ask, and what follows, cost that instead of the grace for an unknown connection.
//!
//! Only step 2 decides where the servo is, with the same exchanges and grace as a search rate by
//! rate: an answer is still taken for its own request only, and never read at another rate.

use super::scan::{ping_sweep, pinged};
use super::{Presence, ping, switch};
use crate::link::{Client, SweepReply};
use crate::ops::OpError;

/// Pings at the bus's pace that measure the answer latency once the servo has answered: enough
/// for the link's grace to fit what it measured (it doubts fewer answers, see the link's
/// timing), about 40 ms at 57600 baud.
const MEASURE_PINGS: usize = 12;

/// Where `id` answers among `bauds`: each rate where something answered, and how, in the order
/// of `bauds`. With `first`, the search stops at the first rate where `id` answers cleanly, and
/// the port is left there; otherwise every rate is asked and the port is left at the last one
/// asked.
pub(super) fn search(
    client: &Client,
    id: u8,
    bauds: &[u32],
    first: bool,
) -> Result<Vec<(u32, Presence)>, OpError> {
    let order = hinted_order(client, id, bauds)?;
    let mut found = Vec::new();
    let mut measured = false;
    for b in order {
        switch(client, b)?;
        let presence = ping(client, id, 2)?;
        if presence == Presence::Absent {
            continue;
        }
        let clean = presence == Presence::Present;
        found.push((b, presence));
        if clean && first {
            break;
        }
        if clean && !measured {
            measured = true;
            // It listens for the answers still on their way before the port changes rate:
            // behind an adapter's latency timer the last ones come after the last ping's window,
            // and one of them would be read at the next rate as the answer there.
            let mut measure = ping_sweep(&[id; MEASURE_PINGS]);
            measure.listen = true;
            client.sweep(measure)?;
        }
    }
    found.sort_by_key(|(b, _)| bauds.iter().position(|x| x == b));
    Ok(found)
}

/// The order to search `bauds` in: one ping each, at the bus's pace, until one hears
/// something; that rate first (the port is still there: nothing from another rate is still on
/// its way but what was heard), then the rate pinged before it (where a late answer came from),
/// then the others in their order. When none hears anything, the line is listened to for the
/// grace an exchange gives, at the last rate, before the search begins at another.
fn hinted_order(client: &Client, id: u8, bauds: &[u32]) -> Result<Vec<u32>, OpError> {
    let mut heard = None;
    for (i, &b) in bauds.iter().enumerate() {
        switch(client, b)?;
        if hears(&client.sweep(ping_sweep(&[id]))?, id) {
            heard = Some(i);
            break;
        }
    }
    if heard.is_none()
        && let Some(last) = bauds.len().checked_sub(1)
        && hears(&client.sweep(ping_sweep(&[]))?, id)
    {
        heard = Some(last);
    }
    Ok(order(bauds, heard))
}

/// `bauds` with the one at `heard` (an index) first and the one before it second.
fn order(bauds: &[u32], heard: Option<usize>) -> Vec<u32> {
    let mut order: Vec<u32> = Vec::with_capacity(bauds.len());
    let hinted = heard
        .into_iter()
        .flat_map(|i| [Some(i), i.checked_sub(1)])
        .flatten()
        .filter_map(|i| bauds.get(i).copied());
    for b in hinted.chain(bauds.iter().copied()) {
        if !order.contains(&b) {
            order.push(b);
        }
    }
    order
}

/// Whether a sweep heard `id`: its answer, a damaged frame, or a late answer to a ping of it.
fn hears(reply: &SweepReply, id: u8) -> bool {
    reply.answers.iter().any(Option::is_some)
        || !reply.garbled.is_empty()
        || pinged(&reply.strays).any(|p| p == id)
}

#[cfg(test)]
mod tests {
    use super::order;

    #[test]
    fn the_rate_heard_comes_first_then_the_one_pinged_before_it_then_the_rest() {
        let bauds = [500_000, 9600, 19_200, 38_400, 57_600, 115_200];
        assert_eq!(
            order(&bauds, Some(5)),
            [115_200, 57_600, 500_000, 9600, 19_200, 38_400]
        );
        assert_eq!(
            order(&bauds, Some(0)),
            [500_000, 9600, 19_200, 38_400, 57_600, 115_200]
        );
        assert_eq!(order(&bauds, None), bauds);
        assert_eq!(order(&bauds, Some(9)), bauds);
        assert!(order(&[], Some(0)).is_empty());
    }
}
