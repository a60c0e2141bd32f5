//! The contour colour picker: a swatch button whose popup offers the
//! palette, hue, saturation and value sliders, R G B values and a hex
//! field. egui's own picker shows a clipboard glyph the default fonts
//! lack (a missing-glyph box) and alpha blending options ("Additive")
//! that mean nothing for a contour: contours are opaque.

use egui::ecolor::Hsva;
use egui::{Color32, Popup, PopupCloseBehavior, Sense};

/// A button showing `colour`; a click opens the picker. The response is
/// marked changed when the colour changed.
pub fn colour_button(ui: &mut egui::Ui, colour: &mut Color32) -> egui::Response {
    let popup_id = ui.auto_id_with("flexiso colour popup");
    let size = egui::vec2(
        2.0 * ui.spacing().interact_size.y,
        ui.spacing().interact_size.y,
    );
    let (rect, response) = ui.allocate_exact_size(size, Sense::click());
    response.widget_info(|| egui::WidgetInfo::labeled(egui::Role::Button, true, "colour"));
    let visuals = ui.style().interact(&response);
    ui.painter().rect_filled(rect, 3.0, *colour);
    ui.painter()
        .rect_stroke(rect, 3.0, visuals.fg_stroke, egui::StrokeKind::Inside);
    let response = response.on_hover_text("Click to change the colour");
    let mut changed = false;
    Popup::menu(&response)
        .id(popup_id)
        .close_behavior(PopupCloseBehavior::CloseOnClickOutside)
        .show(|ui| {
            changed = picker(ui, popup_id, colour);
        });
    let mut response = response;
    if changed {
        response.mark_changed();
    }
    response
}

/// The picker's contents; true when the colour changed.
fn picker(ui: &mut egui::Ui, id: egui::Id, colour: &mut Color32) -> bool {
    let before = *colour;
    // The HSV values are kept between frames: grey has no hue, and
    // deriving them from the colour each frame would lose it.
    let mut hsva = ui
        .data(|d| d.get_temp::<(Color32, Hsva)>(id))
        .filter(|(c, _)| *c == *colour)
        .map(|(_, h)| h)
        .unwrap_or_else(|| Hsva::from_srgb([colour.r(), colour.g(), colour.b()]));
    ui.horizontal_wrapped(|ui| {
        ui.set_max_width(260.0);
        for i in 0..crate::render::PALETTE.len() {
            let c = crate::app::selection::palette(i);
            let (r, resp) = ui.allocate_exact_size(egui::vec2(22.0, 18.0), Sense::click());
            resp.widget_info(|| {
                egui::WidgetInfo::labeled(egui::Role::Button, true, format!("palette {i}"))
            });
            ui.painter().rect_filled(r, 2.0, c);
            if c == *colour {
                ui.painter().rect_stroke(
                    r,
                    2.0,
                    egui::Stroke::new(2.0, Color32::WHITE),
                    egui::StrokeKind::Inside,
                );
            }
            if resp.clicked() {
                *colour = c;
                hsva = Hsva::from_srgb([c.r(), c.g(), c.b()]);
            }
        }
    });
    ui.separator();
    let mut hsv_changed = false;
    hsv_changed |= ui
        .add(egui::Slider::new(&mut hsva.h, 0.0..=1.0).text("hue"))
        .changed();
    hsv_changed |= ui
        .add(egui::Slider::new(&mut hsva.s, 0.0..=1.0).text("saturation"))
        .changed();
    hsv_changed |= ui
        .add(egui::Slider::new(&mut hsva.v, 0.0..=1.0).text("value"))
        .changed();
    if hsv_changed {
        let [r, g, b] = hsva.to_srgb();
        *colour = Color32::from_rgb(r, g, b);
    }
    let [mut r, mut g, mut b] = [colour.r(), colour.g(), colour.b()];
    let mut rgb_changed = false;
    ui.horizontal(|ui| {
        rgb_changed |= ui.add(egui::DragValue::new(&mut r).prefix("R ")).changed();
        rgb_changed |= ui.add(egui::DragValue::new(&mut g).prefix("G ")).changed();
        rgb_changed |= ui.add(egui::DragValue::new(&mut b).prefix("B ")).changed();
    });
    // What is typed is kept while the field has the focus: a partial
    // code ("#1f") is no colour yet, and rebuilding the text from the
    // colour each frame would throw each keystroke away.
    let hex_id = id.with("hex");
    let mut hex = ui
        .data(|d| d.get_temp::<String>(hex_id))
        .unwrap_or_else(|| crate::session::format_colour([colour.r(), colour.g(), colour.b()]));
    ui.horizontal(|ui| {
        let label = ui.label("hex");
        let resp = ui
            .add(egui::TextEdit::singleline(&mut hex).desired_width(80.0))
            .labelled_by(label.id);
        if resp.has_focus() {
            ui.data_mut(|d| d.insert_temp(hex_id, hex.clone()));
        } else {
            ui.data_mut(|d| d.remove::<String>(hex_id));
        }
        if resp.changed()
            && let Some([hr, hg, hb]) = crate::session::parse_colour(hex.trim())
        {
            (r, g, b) = (hr, hg, hb);
            rgb_changed = true;
        }
    });
    if rgb_changed {
        *colour = Color32::from_rgb(r, g, b);
        hsva = Hsva::from_srgb([r, g, b]);
    }
    ui.data_mut(|d| d.insert_temp(id, (*colour, hsva)));
    *colour != before
}
