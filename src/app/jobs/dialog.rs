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
    /// Where to save the session.
    SaveSession,
    /// A session to open.
    OpenSession,
}

impl DialogKind {
    /// What the typed-path window asks for this kind.
    pub fn title(self) -> &'static str {
        match self {
            DialogKind::Open => "Open a volume",
            DialogKind::ExportContours => "Export contours (.ply, .obj or .stl)",
            DialogKind::Screenshot => "Save the 3D view (.png)",
            DialogKind::TreeJson => "Export the contour tree (.json)",
            DialogKind::SaveSession => "Save the session (.json)",
            DialogKind::OpenSession => "Open a session (.json)",
        }
    }
}

/// A dialog's answer: what it asked and the path chosen.
pub type Answer = (DialogKind, PathBuf);

/// What a dialog came back with.
#[derive(Clone, Debug, PartialEq)]
pub enum DialogAnswer {
    /// A path was chosen.
    Chosen(Answer),
    /// The user cancelled.
    Cancelled,
    /// No system dialog could show (no portal, no zenity; or
    /// `FLEXISO_NO_DIALOG` set): ask for a typed path instead.
    Unavailable(DialogKind),
}

/// The dialog job.
pub type DialogJob = Job<DialogAnswer>;

/// A dialog that answers "cancelled" quicker than this never showed:
/// no person closes a file dialog in a quarter of a second.
const TOO_QUICK: std::time::Duration = std::time::Duration::from_millis(250);

/// Opens a dialog for `kind` in `start_dir`, proposing file names made
/// from `stem` (the dataset's name).
pub fn spawn(job: &mut DialogJob, kind: DialogKind, start_dir: Option<PathBuf>, stem: String) {
    job.start("dialog", move |_| {
        if std::env::var_os("FLEXISO_NO_DIALOG").is_some() {
            return Ok(DialogAnswer::Unavailable(kind));
        }
        let t0 = std::time::Instant::now();
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
            DialogKind::SaveSession => d
                .set_title("Save the session")
                .add_filter("flexiso session", &["json"])
                .set_file_name(format!("{stem}_session.json"))
                .save_file(),
            DialogKind::OpenSession => d
                .set_title("Open a session")
                .add_filter("flexiso session", &["json"])
                .pick_file(),
        };
        Ok(match path {
            Some(p) => DialogAnswer::Chosen((kind, p)),
            None if t0.elapsed() < TOO_QUICK => DialogAnswer::Unavailable(kind),
            None => DialogAnswer::Cancelled,
        })
    });
}
