//! The renderer inside egui, the way the explorer's 3D view uses it: render
//! into the renderer's texture each frame, show it through [`EguiTexture`],
//! and check that egui shows the same colours a headless render writes
//! (the sRGB conventions agree). Needs an adapter: skipped without one
//! unless `FLEXISO_REQUIRE_GPU=1`.

mod common;

use egui_kittest::Harness;
use flexiso::render::{Camera, EguiTexture, Renderer, icosphere};

struct View {
    renderer: Option<Renderer>,
    camera: Camera,
    texture: EguiTexture,
    shown: bool,
}

impl eframe::App for View {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        egui::CentralPanel::default()
            .frame(egui::Frame::NONE)
            .show(ui, |ui| {
                let Some(rs) = frame.wgpu_render_state() else {
                    ui.label("no wgpu");
                    return;
                };
                let renderer = self.renderer.get_or_insert_with(|| {
                    let mut r = Renderer::new(&rs.device, Renderer::sample_count_for(&rs.adapter));
                    let (p, n, i) = icosphere([0.0; 3], 1.0, 3);
                    r.set_mesh(&rs.device, &rs.queue, 7, &p, &n, &i)
                        .expect("sphere");
                    r.set_style(7, [0.2, 0.5, 0.9, 1.0], true, false);
                    r
                });
                let rect = ui.available_rect_before_wrap();
                let px = (rect.size() * ui.pixels_per_point()).round();
                renderer.render(
                    &rs.device,
                    &rs.queue,
                    &self.camera,
                    px.x as u32,
                    px.y as u32,
                );
                let id = self
                    .texture
                    .update(&mut rs.renderer.write(), &rs.device, renderer);
                if let Some(id) = id {
                    ui.put(rect, egui::Image::new((id, rect.size())));
                    self.shown = true;
                }
            });
    }
}

#[test]
fn egui_shows_the_renderer_texture_with_headless_colours() {
    let Some(gpu) = common::gpu() else {
        return;
    };
    let mut camera = Camera::default();
    camera.fit([-1.2; 3], [1.2; 3]);
    let (w, h) = (160u32, 120u32);

    // The reference: the same scene rendered headless.
    let mut r = gpu.renderer();
    let (p, n, i) = icosphere([0.0; 3], 1.0, 3);
    r.set_mesh(&gpu.device, &gpu.queue, 7, &p, &n, &i)
        .expect("sphere");
    r.set_style(7, [0.2, 0.5, 0.9, 1.0], true, false);
    r.render(&gpu.device, &gpu.queue, &camera, w, h);
    let reference = r.read_image(&gpu.device, &gpu.queue).expect("read");

    let mut harness = Harness::builder()
        .with_size(egui::vec2(w as f32, h as f32))
        .with_pixels_per_point(1.0)
        .wgpu()
        .build_eframe(|_cc| View {
            renderer: None,
            camera,
            texture: EguiTexture::new(),
            shown: false,
        });
    harness.run_steps(2);
    assert!(harness.state().shown, "the view drew its texture");
    let shot = harness.render().expect("egui render");
    if let Ok(dir) = std::env::var("FLEXISO_RENDER_TEST_OUT") {
        shot.save(std::path::Path::new(&dir).join("egui_view.png"))
            .expect("save");
        reference
            .save(std::path::Path::new(&dir).join("egui_reference.png"))
            .expect("save");
    }
    // Compare a few pixels well inside the sphere and the background.
    let (sw, sh) = shot.dimensions();
    for (fx, fy) in [(0.5, 0.5), (0.45, 0.4), (0.55, 0.6), (0.05, 0.05)] {
        let a = reference
            .get_pixel((fx * w as f32) as u32, (fy * h as f32) as u32)
            .0;
        let b = shot
            .get_pixel((fx * sw as f32) as u32, (fy * sh as f32) as u32)
            .0;
        for k in 0..3 {
            assert!(
                (i32::from(a[k]) - i32::from(b[k])).abs() <= 6,
                "at ({fx}, {fy}): headless {a:?}, egui {b:?}"
            );
        }
    }
}
