pub mod cli;
pub mod packet;
pub mod profile;
pub mod protocol;
