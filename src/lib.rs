pub mod cli;
pub mod link;
pub mod packet;
pub mod profile;
pub mod protocol;
pub mod sim;
