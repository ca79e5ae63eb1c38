//! The commented bundle `botbench station new` writes: the demo station (three simulated
//! slots, one per device kind) with every option shown, so that it runs as written on any PC
//! and a line engineer edits it into the line's own.

/// The example bundle's text: `presets/demo-station.ron`.
pub const EXAMPLE: &str = include_str!("../../../presets/demo-station.ron");
