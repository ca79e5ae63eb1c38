//! The integration tests, in one binary: one module per area, and the helpers they share in
//! [`support`]. Tests run on parallel threads, so none of them sets process-wide state
//! (environment, current directory, fixed paths or ports): each gets its own temporary
//! directory and passes its configuration in.

// Tests and benchmarks stop at the first thing that is not as set up: a panic is their report.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

mod cancel_truth;
mod capture_faults;
mod capture_record;
mod cli_edges;
mod cli_explains;
mod cli_frame;
mod cli_in_process;
mod cli_ranges;
mod cli_records;
mod codec_props;
mod field_msp;
mod field_servo;
mod field_shared;
mod field_vanish;
mod firmware_variants;
mod gui;
mod gui_capture;
mod gui_files;
mod gui_first_run;
mod gui_hints;
mod gui_line_station;
mod gui_msp;
mod gui_servo;
mod gui_servo_setup;
mod gui_station_reasons;
mod gui_tuya;
mod gui_tuya_field;
mod gui_tuya_module;
mod gui_yield;
mod i18n;
mod install;
mod interop_fields;
mod layers;
mod link_identify;
mod link_msp;
mod link_servo;
mod link_tuya;
mod port_boot;
mod preset;
mod profile_codec;
mod profile_load;
mod provision;
mod readme;
mod records;
mod records_pg;
mod repaint;
mod sdk_driver;
mod sdk_vectors;
mod seed_vectors;
mod selftest;
mod series;
mod servo_multi_turn;
mod servo_sync;
mod sim_devices;
mod sim_msp;
mod station_bundle;
mod station_headless;
mod station_records;
mod station_runner;
mod stations;
mod tuya_conform;
mod tuya_field;
mod tuya_module;
mod tuya_schema;
mod tuya_sdk_vectors;
mod tuya_update;
mod window_chinese;
mod window_kinds;
mod window_language;
mod window_layout;
mod window_sizes;
mod window_truth;
mod window_truth_small;
