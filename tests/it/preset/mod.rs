//! Presets against the built-in profiles and the simulated window cleaner on a pty.

use botbench::document::{DocumentError, ErrorKind};
use botbench::ops::OpError;
use botbench::ops::{self, Cancel, Progress};
use botbench::preset::{self, Preset};
use botbench::profile::{Field, FieldType, Input, Len, Profile, Registry, Value};
use botbench::sim::Faults;
use botbench::sim::window_cleaner::WindowCleaner;
use std::path::Path;

use crate::support::cli::{self, Sim};
use crate::support::{Served, connect, profile, serve, serve_plain, temp_dir};

const FACTORY: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/presets/window-cleaner-factory.ron"
);

fn factory_text() -> String {
    std::fs::read_to_string(FACTORY).unwrap()
}

fn window_cleaner() -> Served<WindowCleaner> {
    serve(crate::support::window_cleaner())
}

fn parse_err(text: &str, p: &Profile) -> DocumentError {
    Preset::parse("test.ron", text, p).expect_err("refused")
}

fn raw(inputs: &[(String, Input)], field: &str) -> Option<i64> {
    inputs.iter().find_map(|(k, v)| match v {
        Input::Raw(Value::Int(i)) if k == field => Some(*i),
        _ => None,
    })
}

mod command_line;
mod document;
