pub mod profile;
pub mod protocol;
