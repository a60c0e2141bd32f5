//! A graphics adapter, or a skip: tests that render ask [`gpu`] and return
//! early on `None`; with `FLEXISO_REQUIRE_GPU=1` no adapter is a failure.

use flexiso::render::Gpu;

/// The adapter wgpu finds (Mesa's lavapipe on machines without a GPU), or
/// None (skip, with a note on stderr) when there is none and none is
/// required.
pub fn gpu() -> Option<Gpu> {
    match Gpu::new() {
        Ok(g) => {
            eprintln!("adapter: {}", g.describe());
            Some(g)
        }
        Err(e) => {
            assert!(
                std::env::var("FLEXISO_REQUIRE_GPU").as_deref() != Ok("1"),
                "FLEXISO_REQUIRE_GPU=1 but no adapter: {e}"
            );
            eprintln!("skipping what needs an adapter: {e}");
            None
        }
    }
}
