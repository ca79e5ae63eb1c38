//! What the integration tests share: simulators on pseudo-terminals and the app in an
//! egui_kittest harness.
#![allow(dead_code)] // not every helper is used by every module

pub mod gui;
pub mod servo;
