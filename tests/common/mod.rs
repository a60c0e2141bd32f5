//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

/// The shared data folder (../shared/data next to the repository), or None
/// when it is absent. With `FLEXISO_REQUIRE_DATA=1` (as in CI) an absent
/// folder is a failure, not a skip.
pub fn data_dir() -> Option<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data");
    if dir.join("MANIFEST.tsv").is_file() {
        return Some(dir);
    }
    assert!(
        std::env::var("FLEXISO_REQUIRE_DATA").as_deref() != Ok("1"),
        "FLEXISO_REQUIRE_DATA=1 but {} is missing",
        dir.display()
    );
    eprintln!("skipping: {} is absent", dir.display());
    None
}

/// One dataset from the shared folder, or None (skip) when absent.
pub fn dataset(name: &str) -> Option<PathBuf> {
    let p = data_dir()?.join(name);
    assert!(
        p.is_file(),
        "{} is missing from the data folder",
        p.display()
    );
    Some(p)
}
