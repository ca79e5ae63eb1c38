/// The build: `0.1.0 (1a2b3c4d5)`, the crate's version and the git commit it was built from
/// (`unknown` outside git; see `build.rs`). `botbench --version` prints it.
pub const VERSION: &str = concat!(
    env!("CARGO_PKG_VERSION"),
    " (",
    env!("BOTBENCH_COMMIT"),
    ")"
);

pub mod bench;
pub mod cli;
pub mod document;
pub mod i18n;
pub mod link;
pub mod ops;
pub mod packet;
pub mod preset;
pub mod profile;
pub mod protocol;
pub mod series;
pub mod sim;
pub mod system;
pub mod ui;
