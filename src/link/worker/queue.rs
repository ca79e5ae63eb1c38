//! Callers' work, in the order it came: exchanges, baud changes and sweeps queued, and the
//! commands that came while an exchange was under way, taken after it.

use crate::link::request::{ExchangeError, Request};
use crate::link::{LinkCommand, LinkError, ReplyTo, Sweep, SweepReply};
use crossbeam_channel::Sender;
use std::collections::VecDeque;

/// Work done in order.
pub(super) enum Queued {
    /// One exchange, and where its result goes.
    Exchange(Request, ReplyTo),
    /// A baud change, and who is told when it is done.
    Baud(u32, Option<Sender<Result<(), LinkError>>>),
    /// A sweep, and who gets what it brought.
    Sweep(Sweep, Sender<Result<SweepReply, ExchangeError>>),
}

/// The queue of one link.
#[derive(Default)]
pub(super) struct Queue {
    /// Callers' exchanges, baud changes and sweeps, in order.
    items: VecDeque<Queued>,
    /// Commands that came during an exchange, taken after it.
    deferred: VecDeque<LinkCommand>,
}

impl Queue {
    /// Queues `item` after the others.
    pub(super) fn push(&mut self, item: Queued) {
        self.items.push_back(item);
    }

    /// The oldest item, if any.
    pub(super) fn pop(&mut self) -> Option<Queued> {
        self.items.pop_front()
    }

    /// Keeps `cmd`, which came during an exchange, for after it.
    pub(super) fn defer(&mut self, cmd: LinkCommand) {
        self.deferred.push_back(cmd);
    }

    /// The oldest command kept for after an exchange, if any.
    pub(super) fn next_deferred(&mut self) -> Option<LinkCommand> {
        self.deferred.pop_front()
    }

    /// Every item still queued, for failing them (the port lost, the link closing).
    pub(super) fn take_all(&mut self) -> VecDeque<Queued> {
        std::mem::take(&mut self.items)
    }
}
