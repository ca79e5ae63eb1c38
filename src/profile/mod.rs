//! Device command sets as data: RON profiles under `assets/profiles/`, embedded in the binary,
//! overridable by a user's file of the same name.

pub mod model;

pub use model::*;
