//! Helpers shared by the integration tests, one module per thing:
//!
//! * [`data`]: the shared data folder, relative to the crate; tests skip
//!   when it is absent, fail when `FLEXISO_REQUIRE_DATA=1`.
//! * [`gpu`]: a graphics adapter, or a skip; fail when
//!   `FLEXISO_REQUIRE_GPU=1`.
//! * [`harness`]: driving the explorer with egui_kittest (clicks, drags).
//! * [`bin`]: running the `flexiso` binary and reading what it printed.
//! * [`formats`]: volume files for the reader tests (encoders, writers).
//! * [`tree_oracle`]: the contour tree checked against brute force from the
//!   definitions (join/split trees, node degrees, level-set components).
//!
//! Each test binary compiles this module whole and uses a part of it.
#![allow(dead_code, unused_imports, clippy::unwrap_used)]

pub mod bin;
pub mod data;
pub mod formats;
pub mod gpu;
pub mod harness;
pub mod tree_oracle;

pub use bin::{Run, flexiso, flexiso_with_stdin, flexiso_without_display};
pub use data::{data_dir, dataset};
pub use gpu::gpu;
