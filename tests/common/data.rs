//! The shared data folder: `../shared/data` beside the crate, found from
//! `CARGO_MANIFEST_DIR` so the tests run from any clone. Absent, the tests
//! that need it skip (with a note on stderr); with `FLEXISO_REQUIRE_DATA=1`
//! (as in CI) an absent folder or file is a failure instead.

use std::path::PathBuf;

/// Whether `FLEXISO_REQUIRE_DATA=1` is set.
fn required() -> bool {
    std::env::var("FLEXISO_REQUIRE_DATA").as_deref() == Ok("1")
}

/// The data folder, present or not.
pub fn data_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data")
}

/// The shared data folder, or None (skip) when it is absent. With
/// `FLEXISO_REQUIRE_DATA=1` an absent folder is a failure, not a skip.
pub fn data_dir() -> Option<PathBuf> {
    let dir = data_path();
    if dir.join("MANIFEST.tsv").is_file() {
        return Some(dir);
    }
    assert!(
        !required(),
        "FLEXISO_REQUIRE_DATA=1 but {} is missing",
        dir.display()
    );
    eprintln!("skipping: {} is absent", dir.display());
    None
}

/// A file of the data folder (`name` relative to it, e.g.
/// `"formats/colin27_ch2.nii.gz"`), or None (skip) when the folder is
/// absent. A folder without the file is a failure: the folder is not what
/// the tests expect.
pub fn dataset(name: &str) -> Option<PathBuf> {
    let p = data_dir()?.join(name);
    assert!(
        p.exists(),
        "{} is missing from the data folder",
        p.display()
    );
    Some(p)
}
