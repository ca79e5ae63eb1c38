pub mod cli;
pub mod link;
pub mod ops;
pub mod packet;
pub mod profile;
pub mod protocol;
pub mod series;
pub mod sim;
