//! File dialogs (rfd), each on its own thread: the portal's dialog can
//! stay open while the window keeps drawing. One [`DialogKind`] per
//! question the explorer asks; the answer comes back as a path.

use std::path::PathBuf;

use super::Job;

/// What a file dialog asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DialogKind {
    /// A volume to open.
    Open,
    /// Where to export the contours (PLY, OBJ, STL).
    ExportContours,
    /// Where to save the 3D view as PNG.
    Screenshot,
    /// Where to export the tree as JSON.
    TreeJson,
}

/// A dialog's answer: what it asked and the path chosen.
pub type Answer = (DialogKind, PathBuf);

/// The dialog job: `Ready(None)` when the user cancelled the dialog.
pub type DialogJob = Job<Option<Answer>>;

/// Opens a dialog for `kind` in `start_dir`, proposing file names made
/// from `stem` (the dataset's name).
pub fn spawn(job: &mut DialogJob, kind: DialogKind, start_dir: Option<PathBuf>, stem: String) {
    job.start("dialog", move |_| {
        // rfd's portal backend is thread-safe; the UI keeps running.
        let mut d = rfd::FileDialog::new();
        if let Some(dir) = start_dir {
            d = d.set_directory(dir);
        }
        let path = match kind {
            DialogKind::Open => d.set_title("Open a volume").pick_file(),
            DialogKind::ExportContours => d
                .set_title("Export contours")
                .add_filter("mesh", &["ply", "obj", "stl"])
                .set_file_name(format!("{stem}_contours.ply"))
                .save_file(),
            DialogKind::Screenshot => d
                .set_title("Save the 3D view")
                .add_filter("PNG", &["png"])
                .set_file_name(format!("{stem}.png"))
                .save_file(),
            DialogKind::TreeJson => d
                .set_title("Export the contour tree")
                .add_filter("JSON", &["json"])
                .set_file_name(format!("{stem}_tree.json"))
                .save_file(),
        };
        Ok(path.map(|p| (kind, p)))
    });
}
