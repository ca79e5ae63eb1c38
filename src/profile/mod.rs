//! Device command sets as data: RON profiles under `assets/profiles/`, embedded in the binary,
//! overridable by a user's file of the same name.

pub mod model;

pub use model::*;
pub mod codec;
pub mod convert;
pub mod data_point;
pub mod encode;
pub mod fault;
pub mod registry;
pub mod relation;
pub mod roles;
pub mod stop;
pub mod tuya_schema;
pub mod validate;
pub mod value;

pub use codec::{Decoded, FieldValue, Input};
pub use data_point::DpLimit;
pub use registry::{ProfileError, Registry, Source};
pub use roles::{CommandRole, ParamRole};
pub use value::{FieldError, Misfit, Value};
