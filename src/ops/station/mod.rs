//! The line station: several fixtures on one PC, each slot running a line plan on its own
//! worker. A station is data first: a bundle file ([`doc`]) checked whole ([`load`]) into a
//! [`Bundle`] whose hash goes into every record; the slot runner ([`runner`]) runs each
//! slot's [`LinePlan`] over the operations botbench already has, sends [`Event`]s and keeps one
//! record per unit. The command line and the window are thin over it.
//!
//! - [`doc`]: the RON shapes; [`example`]: the commented bundle `botbench station new` writes.
//! - [`load`]: read, hash, check; [`plan`]: a plan's steps with their files parsed.
//! - [`forward`]: the records waiting in a spool, counted and forwarded while the station runs.
//! - [`access`]: the engineer's unlocks, refused passwords, locks and lent slots, recorded.
//! - [`reason`]: why a step failed, typed (English for the records, 中文 in the window).
//! - [`port`]: finding a slot's port by what stays true when its adapter is replugged.

pub mod doc;
pub mod example;
pub mod load;
pub mod plan;
pub mod port;

pub use doc::{PortLocator, StartMode};
pub use load::{Bundle, HashedFile, LoadContext, Slot, bundle_sha256, load};
pub use plan::{LinePlan, LineStep, Op};
pub mod access;
pub mod event;
pub mod forward;
pub mod reason;
pub mod runner;
pub mod steps;

pub use access::Access;
pub use event::{Answer, Command, Event, What};
pub use forward::Forwarder;
pub use reason::Reason;
pub use runner::{Hands, OperatorHands, SlotHandle, StationContext, spawn};
