//! Showing the renderer's texture in egui: keeps one egui texture id bound
//! to [`Renderer::colour_view`], re-pointing it when the target is recreated.

use super::Renderer;

/// The egui side of a [`Renderer`]'s colour texture.
#[derive(Debug, Default)]
pub struct EguiTexture {
    id: Option<egui::TextureId>,
    generation: u64,
}

impl EguiTexture {
    /// Nothing registered yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Registers the renderer's current colour view with egui (first call)
    /// or re-points the id at it after a resize; call after
    /// [`Renderer::render`] each frame, then `ui.image((id, size))`. None
    /// before the first render.
    pub fn update(
        &mut self,
        egui_renderer: &mut egui_wgpu::Renderer,
        device: &wgpu::Device,
        renderer: &Renderer,
    ) -> Option<egui::TextureId> {
        let view = renderer.colour_view()?;
        let generation = renderer.target_generation();
        match self.id {
            Some(_) if self.generation == generation => {}
            Some(id) => egui_renderer.update_egui_texture_from_wgpu_texture(
                device,
                view,
                wgpu::FilterMode::Linear,
                id,
            ),
            None => {
                self.id = Some(egui_renderer.register_native_texture(
                    device,
                    view,
                    wgpu::FilterMode::Linear,
                ));
            }
        }
        self.generation = generation;
        self.id
    }

    /// The registered id, if any.
    pub fn id(&self) -> Option<egui::TextureId> {
        self.id
    }

    /// Frees the egui texture (e.g. when the view is closed).
    pub fn free(&mut self, egui_renderer: &mut egui_wgpu::Renderer) {
        if let Some(id) = self.id.take() {
            egui_renderer.free_texture(&id);
        }
    }
}
