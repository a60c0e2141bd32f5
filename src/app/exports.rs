//! Exports as the File menu does them: contour meshes (PLY with each
//! contour's colour per vertex, OBJ with a `.mtl` of the colours, STL,
//! VTP), on request with a session beside them (`NAME.session.json`),
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
        Ok(self.contour_export(path)?()?.0)
    }

    /// Where the session written beside exported meshes goes:
    /// `NAME.session.json` for `NAME.ply`.
    pub fn session_beside(mesh_path: &std::path::Path) -> PathBuf {
        mesh_path.with_extension("session.json")
    }

    /// What [`FlexisoApp::export_contours`] writes, gathered (cheaply, on
    /// the UI thread) into a closure that writes it (anywhere).
    fn contour_export(
        &self,
        path: &std::path::Path,
    ) -> anyhow::Result<impl FnOnce() -> anyhow::Result<(usize, Vec<PathBuf>)> + Send + 'static>
    {
        let mut meshes: Vec<Arc<ContourMesh>> = Vec::new();
        let mut names = Vec::new();
        let mut colours = Vec::new();
        for c in &self.selection.contours {
            if let Some(m) = &c.mesh
                && self.selection.shown(c)
            {
                meshes.push(Arc::clone(m));
                // The user's name when given (one word: OBJ and PLY
                // comments split on spaces), else the contour's number.
                let name = c.name.split_whitespace().collect::<Vec<_>>().join("_");
                names.push(if name.is_empty() {
                    format!("contour_{}_h{}", c.id, fmt_value(c.h))
                } else {
                    name
                });
                colours.push([c.colour.r(), c.colour.g(), c.colour.b()]);
            }
        }
        if meshes.is_empty() && self.show_all {
            for (i, m) in self.all.meshes.iter().enumerate() {
                meshes.push(Arc::clone(m));
                names.push(format!("component_{i}_h{}", fmt_value(self.global_h)));
                let c = super::selection::palette(i);
                colours.push([c.r(), c.g(), c.b()]);
            }
        }
        if meshes.is_empty() {
            anyhow::bail!("no contour to export: select one in the tree first");
        }
        // The session, when asked for, is gathered here (cheap) and
        // written with the meshes.
        let session = if self.menu.session_with_export {
            let p = Self::session_beside(path);
            Some((
                self.session(&p)
                    .ok_or_else(|| anyhow::anyhow!("no volume is open"))?,
                p,
            ))
        } else {
            None
        };
        let path = path.to_path_buf();
        Ok(move || {
            let mut files = crate::contour::export::write_contours_coloured(
                &path, &meshes, &names, &colours, "",
            )?;
            if let Some((s, p)) = session {
                s.write(&p)
                    .map_err(|e| anyhow::anyhow!("the session beside the meshes: {e}"))?;
                files.push(p);
            }
            Ok((meshes.len(), files))
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
            // Written node by node and arc by arc, beside the file and
            // moved over it once whole.
            crate::simplify::json::TreeDocument {
                collapsed: Some(&collapsed),
                simplified: Some(crate::simplify::json::simplified_tree_json(&level, &tree)),
                ..crate::simplify::json::TreeDocument::of(&tree, &field)
            }
            .write_file(&path)
            .map_err(|e| anyhow::anyhow!("{}: cannot write: {e}", path.display()))
        })
    }

    /// Exports the contours as File > Export does: gathered now, written
    /// on another thread (a whole isosurface is tens of megabytes), the
    /// outcome in the info line.
    pub fn start_contour_export(&mut self, p: PathBuf) {
        match self.contour_export(&p) {
            Ok(write) => self.export_in_background(move || match write() {
                Ok((n, files)) => {
                    let others: Vec<String> = files
                        .iter()
                        .filter(|f| **f != p)
                        .map(|f| f.display().to_string())
                        .collect();
                    let also = if others.is_empty() {
                        String::new()
                    } else {
                        format!(" (and {})", others.join(", "))
                    };
                    Ok(format!(
                        "wrote {n} contour{} to {}{also}",
                        if n == 1 { "" } else { "s" },
                        p.display()
                    ))
                }
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
        // The legend as the view shows it (View > Legend).
        let legend = if self.menu.view.legend {
            self.legend_entries()
        } else {
            Vec::new()
        };
        match image {
            // PNG encoding takes tens of milliseconds: not on this thread.
            Ok(mut img) => {
                // The names as the view shows them (View > Contour names).
                let labels = if self.menu.view.labels {
                    self.view3d.image_labels(img.width(), img.height())
                } else {
                    Vec::new()
                };
                self.export_in_background(move || {
                    crate::render::overlay::draw_labels(&mut img, &labels);
                    crate::render::overlay::draw_legend(&mut img, &legend);
                    match crate::output::save_image(&path, &img) {
                        Ok(()) => Ok(format!("saved {}", path.display())),
                        Err(e) => Err(format!("screenshot: {}: {e}", path.display())),
                    }
                })
            }
            Err(e) => self.error = Some(format!("screenshot: {e:#}")),
        }
    }

    /// Saves the 3D view at the next frame (tests, scripts).
    pub fn request_screenshot(&mut self, path: PathBuf) {
        self.pending_screenshot = Some(path);
    }
}
