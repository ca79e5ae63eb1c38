//! The link: one named worker thread per open port owns the transport and a protocol session.

pub mod transport;

pub use transport::{LinkError, Transport, wire_time};
