//! Exports as the File menu does them: contour meshes (PLY, OBJ, STL),
//! the tree as JSON, the 3D view as PNG. What to write is gathered on the
//! UI thread (cheap: shared meshes, the tree's `Arc`s), the writing runs
//! as a job ([`super::jobs::export`]), its outcome lands in the info line.

use std::path::PathBuf;
use std::sync::Arc;

use super::FlexisoApp;
use super::format::fmt_value;
use crate::contour::ContourMesh;

impl FlexisoApp {
    /// Writes the visible selected contours (or, with none selected, the
    /// contours at h shown) to a mesh file.
    pub fn export_contours(&self, path: &std::path::Path) -> anyhow::Result<usize> {
        self.contour_export(path)?()
    }

    /// What [`FlexisoApp::export_contours`] writes, gathered (cheaply, on
    /// the UI thread) into a closure that writes it (anywhere).
    fn contour_export(
        &self,
        path: &std::path::Path,
    ) -> anyhow::Result<impl FnOnce() -> anyhow::Result<usize> + Send + 'static> {
        let mut meshes: Vec<Arc<ContourMesh>> = Vec::new();
        let mut names = Vec::new();
        for c in &self.selection.contours {
            if let Some(m) = &c.mesh
                && self.selection.shown(c)
            {
                meshes.push(Arc::clone(m));
                names.push(format!("contour_{}_h{}", c.id, fmt_value(c.h)));
            }
        }
        if meshes.is_empty() && self.show_all {
            for (i, m) in self.all.meshes.iter().enumerate() {
                meshes.push(Arc::clone(m));
                names.push(format!("component_{i}_h{}", fmt_value(self.global_h)));
            }
        }
        if meshes.is_empty() {
            anyhow::bail!("no contour to export: select one in the tree first");
        }
        let path = path.to_path_buf();
        Ok(move || {
            crate::contour::export::write_contours(&path, &meshes, &names)?;
            Ok(meshes.len())
        })
    }

    /// Writes the tree, the collapsed tree and the level shown as JSON.
    pub fn export_tree_json(&self, path: &std::path::Path) -> anyhow::Result<()> {
        self.tree_export(path)?()
    }

    /// What [`FlexisoApp::export_tree_json`] writes, as a closure.
    fn tree_export(
        &self,
        path: &std::path::Path,
    ) -> anyhow::Result<impl FnOnce() -> anyhow::Result<()> + Send + 'static> {
        let (Some(ds), Some(level)) = (&self.dataset, &self.level) else {
            anyhow::bail!("no dataset loaded");
        };
        let (tree, field, collapsed) = (
            Arc::clone(&ds.tree),
            Arc::clone(&ds.field),
            Arc::clone(&ds.collapsed),
        );
        let level = level.clone();
        let path = path.to_path_buf();
        Ok(move || {
            let mut json = crate::tree::json::tree_json(&tree, &field);
            if let Some(obj) = json.as_object_mut() {
                obj.insert(
                    "collapsed".into(),
                    crate::simplify::json::collapsed_tree_json(&collapsed, &tree),
                );
                obj.insert(
                    "simplified".into(),
                    crate::simplify::json::simplified_tree_json(&level, &tree),
                );
            }
            std::fs::write(&path, serde_json::to_string(&json)?)
                .map_err(|e| anyhow::anyhow!("{}: cannot write: {e}", path.display()))?;
            Ok(())
        })
    }

    /// Exports the contours as File > Export does: gathered now, written
    /// on another thread (a whole isosurface is tens of megabytes), the
    /// outcome in the info line.
    pub fn start_contour_export(&mut self, p: PathBuf) {
        match self.contour_export(&p) {
            Ok(write) => self.export_in_background(move || match write() {
                Ok(n) => Ok(format!("wrote {n} contour(s) to {}", p.display())),
                Err(e) => Err(format!("{e:#}")),
            }),
            Err(e) => self.error = Some(format!("{e:#}")),
        }
    }

    /// Exports the tree as JSON as File > Export does, on another thread.
    pub fn start_tree_export(&mut self, p: PathBuf) {
        match self.tree_export(&p) {
            Ok(write) => self.export_in_background(move || match write() {
                Ok(()) => Ok(format!("wrote {}", p.display())),
                Err(e) => Err(format!("{e:#}")),
            }),
            Err(e) => self.error = Some(format!("{e:#}")),
        }
    }

    /// Runs an export's writing as a job; its outcome shows in the info
    /// line when done.
    pub(super) fn export_in_background(
        &mut self,
        write: impl FnOnce() -> Result<String, String> + Send + 'static,
    ) {
        self.info = Some("writing…".into());
        self.exports.start(self.notify.clone(), write);
    }

    /// Installs the outcomes of finished exports.
    pub(super) fn poll_exports(&mut self) {
        for outcome in self.exports.poll() {
            self.export_done(outcome);
        }
    }

    fn export_done(&mut self, outcome: Result<String, super::jobs::JobError>) {
        match outcome {
            Ok(msg) => self.info = Some(msg),
            Err(e) => self.error = Some(e.to_string()),
        }
    }

    /// Waits for the exports in flight (tests).
    pub fn wait_for_exports(&mut self) {
        for outcome in self.exports.wait() {
            self.export_done(outcome);
        }
    }

    /// Saves the 3D view, if asked, from this frame's render: read back
    /// here, encoded by a job.
    pub(super) fn save_screenshot(&mut self, rs: Option<&egui_wgpu::RenderState>) {
        let Some(path) = self.pending_screenshot.take() else {
            return;
        };
        let image = rs
            .ok_or_else(|| anyhow::anyhow!("no GPU render state"))
            .and_then(|rs| self.view3d.read_image(rs));
        match image {
            // PNG encoding takes tens of milliseconds: not on this thread.
            Ok(img) => self.export_in_background(move || match img.save(&path) {
                Ok(()) => Ok(format!("saved {}", path.display())),
                Err(e) => Err(format!("screenshot: {}: {e}", path.display())),
            }),
            Err(e) => self.error = Some(format!("screenshot: {e:#}")),
        }
    }

    /// Saves the 3D view at the next frame (tests, scripts).
    pub fn request_screenshot(&mut self, path: PathBuf) {
        self.pending_screenshot = Some(path);
    }
}
