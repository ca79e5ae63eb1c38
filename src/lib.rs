pub mod cli;
pub mod i18n;
pub mod link;
pub mod ops;
pub mod packet;
pub mod profile;
pub mod protocol;
pub mod sim;
