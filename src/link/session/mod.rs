//! The protocol sessions the worker drives: what each protocol does on a connection beyond the
//! exchanges callers ask for. MSP identifies the device once per connection ([`msp`]); botbench
//! plays the Tuya Wi-Fi module, with its handshake, heartbeat and answers to the MCU ([`tuya`]).

pub mod msp;
pub mod tuya;

pub use msp::{DeviceInfo, build_date};
