//! The contour tree panel: the simplified tree drawn with y = isovalue and
//! x from the branch layout ([`super::layout`]), nodes coloured by kind,
//! the global isovalue as a draggable horizontal line, one marker per
//! selected contour that drags its isovalue along its arc.
//!
//! Mouse: click an arc selects its contour (at the global isovalue when
//! the arc spans it, else at the arc's middle); shift-click adds; drag a
//! marker moves that contour along the level set (past a join going up it
//! becomes the contours of the arcs above, and contours that meet at a node
//! merge; at an extremum it stops); drag the
//! dashed line moves the global isovalue; wheel zooms, right or middle
//! drag pans, double-click resets the view.

use egui::{Color32, Pos2, Rect, Sense, Stroke, Vec2, pos2, vec2};

use crate::contour::path_seed_in_chain;
use crate::field::Isovalue;
use crate::simplify::{SimplifiedArcId, SimplifiedTree};

use super::pipeline::Dataset;
use super::selection::Selection;

/// Node colours: maxima, minima, saddles.
const MAX_COLOUR: Color32 = Color32::from_rgb(230, 90, 80);
const MIN_COLOUR: Color32 = Color32::from_rgb(80, 140, 240);
const SADDLE_COLOUR: Color32 = Color32::from_rgb(230, 200, 80);
const ARC_COLOUR: Color32 = Color32::from_rgb(150, 150, 150);
const ISO_COLOUR: Color32 = Color32::from_rgb(120, 220, 160);

/// What is being dragged.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Drag {
    Marker(u64),
    IsoLine,
    Pan,
}

/// What the last frame drew, for tests and for picking.
#[derive(Clone, Debug, Default)]
pub struct Drawn {
    /// The panel's rect.
    pub rect: Option<Rect>,
    /// Live arcs drawn, with the screen midpoint of each.
    pub arcs: Vec<(SimplifiedArcId, Pos2)>,
    /// Screen height of each drawn arc (parallel to `arcs`).
    pub arc_heights: Vec<f32>,
    /// Screen ends (upper, lower) of each drawn arc (parallel to `arcs`).
    pub arc_ends: Vec<(Pos2, Pos2)>,
    /// Markers drawn: contour id and position.
    pub markers: Vec<(u64, Pos2)>,
    /// Screen y of the global isovalue line.
    pub iso_y: f32,
}

/// The tree panel's own state (view transform, drag, caches).
#[derive(Default)]
pub struct TreePanel {
    zoom: f32,
    pan: Vec2,
    drag: Option<Drag>,
    /// Node columns at `columns_key` (only live nodes' entries are
    /// current).
    columns: Vec<f32>,
    columns_key: Option<(usize, usize)>,
    /// What the last frame drew.
    pub drawn: Drawn,
    /// The arc under the pointer.
    pub hovered: Option<SimplifiedArcId>,
    /// Betti numbers of the superarcs' contours, once computed.
    pub betti: Option<std::sync::Arc<crate::measure::betti::ContourTopology>>,
}

/// Maps values and columns to the screen and back.
#[derive(Clone, Copy)]
struct Transform {
    plot: Rect,
    lo: f64,
    hi: f64,
    zoom: f32,
    pan: Vec2,
}

impl Transform {
    fn screen(&self, x: f32, v: f64) -> Pos2 {
        let t = if self.hi > self.lo {
            ((v - self.lo) / (self.hi - self.lo)) as f32
        } else {
            0.5
        };
        let base = pos2(
            self.plot.left() + x * self.plot.width(),
            self.plot.bottom() - t * self.plot.height(),
        );
        let c = self.plot.center();
        c + (base - c) * self.zoom + self.pan
    }

    fn value_at(&self, y: f32) -> f64 {
        let c = self.plot.center();
        let base_y = (y - self.pan.y - c.y) / self.zoom + c.y;
        let t = (self.plot.bottom() - base_y) / self.plot.height().max(1.0);
        self.lo + t as f64 * (self.hi - self.lo)
    }
}

/// Distance from `p` to the segment `a b`, and the segment parameter.
fn segment_distance(p: Pos2, a: Pos2, b: Pos2) -> f32 {
    let ab = b - a;
    let t = if ab.length_sq() > 0.0 {
        ((p - a).dot(ab) / ab.length_sq()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + ab * t).distance(p)
}

/// Round tick spacing for about `n` ticks over `range`.
fn tick_step(range: f64, n: f64) -> f64 {
    if !(range.is_finite() && range > 0.0) {
        return 1.0;
    }
    let raw = range / n;
    let mag = 10f64.powf(raw.log10().floor());
    let r = raw / mag;
    mag * if r < 1.5 {
        1.0
    } else if r < 3.5 {
        2.0
    } else if r < 7.5 {
        5.0
    } else {
        10.0
    }
}

/// Formats a value compactly.
pub fn fmt_value(v: f64) -> String {
    if v == 0.0 || (v.abs() >= 0.01 && v.abs() < 1e5) {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{v:.3e}")
    }
}

impl TreePanel {
    /// A panel showing the whole tree.
    pub fn new() -> Self {
        Self {
            zoom: 1.0,
            ..Self::default()
        }
    }

    /// Forgets caches and the view (a new dataset).
    pub fn reset(&mut self) {
        *self = Self::new();
    }

    fn refresh(&mut self, ds: &Dataset, level: &SimplifiedTree) {
        let key = (level.step(), std::sync::Arc::as_ptr(&ds.sim) as usize);
        if self.columns_key != Some(key) {
            if self.columns_key.is_none_or(|(_, sim)| sim != key.1) {
                self.columns.clear();
            }
            ds.layout.live_columns(level, &mut self.columns);
            self.columns_key = Some(key);
        }
    }

    /// Draws the panel; edits the selection and the global isovalue.
    pub fn ui(
        &mut self,
        ui: &mut egui::Ui,
        ds: &Dataset,
        level: &SimplifiedTree,
        sel: &mut Selection,
        global_h: &mut f64,
    ) {
        if self.zoom <= 0.0 {
            self.zoom = 1.0;
        }
        self.refresh(ds, level);
        let rect = ui.available_rect_before_wrap();
        let response = ui
            .allocate_rect(rect, Sense::click_and_drag())
            .on_hover_cursor(egui::CursorIcon::Crosshair);
        response
            .widget_info(|| egui::WidgetInfo::labeled(egui::Role::Canvas, true, "contour tree"));
        let painter = ui.painter_at(rect);
        painter.rect_filled(rect, 0.0, ui.visuals().extreme_bg_color);
        let plot = Rect::from_min_max(rect.min + vec2(60.0, 14.0), rect.max - vec2(14.0, 14.0));
        let (lo, hi) = ds.range;
        let tf = Transform {
            plot,
            lo,
            hi,
            zoom: self.zoom,
            pan: self.pan,
        };
        let sim = level.simplification();
        let node_pos = |n: crate::simplify::SimplifiedNodeId| -> Pos2 {
            let x = self.columns.get(n.0 as usize).copied().unwrap_or(0.5);
            tf.screen(if x.is_finite() { x } else { 0.5 }, sim.node_value(n))
        };

        // Arcs: segments and hit testing.
        let pointer = response.hover_pos();
        let mut segs: Vec<(SimplifiedArcId, Pos2, Pos2)> = Vec::with_capacity(level.num_arcs());
        for a in level.arcs() {
            segs.push((a.id, node_pos(a.upper), node_pos(a.lower)));
        }
        segs.sort_by_key(|s| s.0);
        let nearest = |p: Pos2| -> Option<SimplifiedArcId> {
            segs.iter()
                .map(|&(id, a, b)| (segment_distance(p, a, b), id))
                .filter(|(d, _)| *d <= 6.0)
                .min_by(|x, y| x.0.total_cmp(&y.0))
                .map(|(_, id)| id)
        };
        self.hovered = pointer.and_then(nearest);

        // Markers: each selected contour on the live arc holding it.
        let mut markers: Vec<(u64, Pos2, Color32, SimplifiedArcId)> = Vec::new();
        for c in &sel.contours {
            if let Some(a) = level.live_arc_of(c.superarc) {
                let la = level.arc(a);
                let (pu, pl) = (node_pos(la.upper), node_pos(la.lower));
                let (vu, vl) = (sim.node_value(la.upper), sim.node_value(la.lower));
                let t = if vu > vl {
                    ((c.h - vl) / (vu - vl)).clamp(0.0, 1.0) as f32
                } else {
                    0.5
                };
                markers.push((c.id, pl + (pu - pl) * t, c.colour, a));
            }
        }

        // Interaction.
        let press = ui.input(|i| i.pointer.press_origin());
        if response.drag_started() {
            let by_primary = ui.input(|i| i.pointer.primary_down());
            self.drag = if !by_primary {
                Some(Drag::Pan)
            } else if let Some(p) = press {
                let on_marker = markers
                    .iter()
                    .map(|m| (m.1.distance(p), m.0))
                    .filter(|(d, _)| *d <= 9.0)
                    .min_by(|x, y| x.0.total_cmp(&y.0));
                if let Some((_, id)) = on_marker {
                    sel.active = Some(id);
                    Some(Drag::Marker(id))
                } else if (p.y - tf.screen(0.0, *global_h).y).abs() <= 6.0 {
                    Some(Drag::IsoLine)
                } else {
                    Some(Drag::Pan)
                }
            } else {
                None
            };
        }
        if response.dragged()
            && let Some(p) = response.interact_pointer_pos()
        {
            match self.drag {
                Some(Drag::Marker(id)) => {
                    self.drag_marker(ds, level, sel, id, tf.value_at(p.y));
                }
                Some(Drag::IsoLine) => {
                    *global_h = tf.value_at(p.y).clamp(lo, hi);
                }
                Some(Drag::Pan) => self.pan += response.drag_delta(),
                None => {}
            }
        }
        if response.drag_stopped() {
            self.drag = None;
        }
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0
                && let Some(q) = pointer
            {
                let z = self.zoom;
                let nz = (z * (0.002 * scroll).exp()).clamp(0.2, 500.0);
                let c = plot.center();
                self.pan = (q - c) - (q - c - self.pan) * (nz / z);
                self.zoom = nz;
            }
        }
        if response.double_clicked() {
            self.zoom = 1.0;
            self.pan = Vec2::ZERO;
        } else if response.clicked()
            && let Some(p) = response.interact_pointer_pos()
            && let Some(arc) = nearest(p)
        {
            let shift = ui.input(|i| i.modifiers.shift);
            Self::select_arc(ds, level, sel, arc, *global_h, !shift);
        }

        // Drawing: axis, iso line, arcs, nodes, markers.
        let text = ui.visuals().text_color();
        let font = egui::FontId::monospace(10.0);
        let (v_top, v_bottom) = (tf.value_at(plot.top()), tf.value_at(plot.bottom()));
        let step = tick_step(v_top - v_bottom, 8.0);
        let mut v = (v_bottom / step).ceil() * step;
        painter.line_segment(
            [
                pos2(plot.left() - 8.0, rect.top()),
                pos2(plot.left() - 8.0, rect.bottom()),
            ],
            Stroke::new(1.0, text.gamma_multiply(0.5)),
        );
        let mut guard = 0;
        while v <= v_top && guard < 100 {
            let y = tf.screen(0.0, v).y;
            painter.line_segment(
                [pos2(plot.left() - 12.0, y), pos2(plot.left() - 8.0, y)],
                Stroke::new(1.0, text.gamma_multiply(0.5)),
            );
            painter.line_segment(
                [pos2(plot.left() - 8.0, y), pos2(rect.right(), y)],
                Stroke::new(1.0, text.gamma_multiply(0.06)),
            );
            painter.text(
                pos2(plot.left() - 14.0, y),
                egui::Align2::RIGHT_CENTER,
                fmt_value(v),
                font.clone(),
                text.gamma_multiply(0.8),
            );
            v += step;
            guard += 1;
        }
        let iso_y = tf.screen(0.0, *global_h).y;
        let dash = Stroke::new(
            if self.drag == Some(Drag::IsoLine) {
                2.0
            } else {
                1.2
            },
            ISO_COLOUR,
        );
        painter.add(egui::Shape::dashed_line(
            &[pos2(plot.left() - 8.0, iso_y), pos2(rect.right(), iso_y)],
            dash,
            6.0,
            4.0,
        ));
        painter.text(
            pos2(rect.right() - 4.0, iso_y - 2.0),
            egui::Align2::RIGHT_BOTTOM,
            format!("h = {}", fmt_value(*global_h)),
            font.clone(),
            ISO_COLOUR,
        );

        let selected_arcs: Vec<(SimplifiedArcId, Color32)> =
            markers.iter().map(|m| (m.3, m.2)).collect();
        for &(id, a, b) in &segs {
            let (width, colour) = if let Some(&(_, c)) = selected_arcs.iter().find(|s| s.0 == id) {
                (3.0, c)
            } else if self.hovered == Some(id) {
                (3.0, Color32::WHITE)
            } else {
                (1.5, ARC_COLOUR)
            };
            painter.line_segment([a, b], Stroke::new(width, colour));
        }
        if level.num_arcs() <= 5000 {
            for n in level.nodes() {
                let (up, down) = level.degree(n);
                let colour = match (up, down) {
                    (0, _) => MAX_COLOUR,
                    (_, 0) => MIN_COLOUR,
                    _ => SADDLE_COLOUR,
                };
                painter.circle_filled(node_pos(n), 3.5, colour);
            }
        }
        for &(id, p, colour, _) in &markers {
            let active = sel.active == Some(id);
            painter.circle(
                p,
                if active { 7.0 } else { 6.0 },
                colour,
                Stroke::new(if active { 2.0 } else { 1.0 }, Color32::WHITE),
            );
        }
        // Legend.
        let mut lx = plot.left();
        for (name, c) in [
            ("max", MAX_COLOUR),
            ("min", MIN_COLOUR),
            ("saddle", SADDLE_COLOUR),
        ] {
            painter.circle_filled(pos2(lx, rect.top() + 7.0), 3.5, c);
            let r = painter.text(
                pos2(lx + 6.0, rect.top() + 7.0),
                egui::Align2::LEFT_CENTER,
                name,
                font.clone(),
                text,
            );
            lx = r.right() + 10.0;
        }

        if let Some(a) = self.hovered
            && self.drag.is_none()
        {
            let la = level.arc(a);
            let (vu, vl) = (sim.node_value(la.upper), sim.node_value(la.lower));
            // Genus of the contour at the pointer's value (or the middle).
            let hv = pointer
                .map(|p| tf.value_at(p.y))
                .filter(|h| *h >= vl && *h < vu)
                .unwrap_or(0.5 * (vl + vu));
            let genus = match &self.betti {
                Some(b) => {
                    let iso = Isovalue::new(hv);
                    match path_seed_in_chain(&ds.tree, &ds.field, la.chain, iso) {
                        Some(seed) => {
                            let seg = b.at(seed.arc, &ds.field, iso);
                            format!(
                                "contour at {}: genus {}{}",
                                fmt_value(hv),
                                seg.genus(),
                                if seg.closed() { ", closed" } else { ", open" }
                            )
                        }
                        None => String::new(),
                    }
                }
                None => "genus: computing…".into(),
            };
            let tip = format!(
                "arc {}: values {} .. {}\nup cost {}  down cost {}\n{} superarc(s)\n{genus}\nclick: select its contour, shift-click: add",
                a.0,
                fmt_value(vl),
                fmt_value(vu),
                fmt_value(la.up_cost),
                fmt_value(la.down_cost),
                la.chain.len(),
            );
            response.clone().on_hover_text_at_pointer(tip);
        }

        self.drawn = Drawn {
            rect: Some(rect),
            arcs: segs
                .iter()
                .map(|&(id, a, b)| (id, a + (b - a) * 0.5))
                .collect(),
            arc_heights: segs.iter().map(|&(_, a, b)| (b.y - a.y).abs()).collect(),
            arc_ends: segs.iter().map(|&(_, a, b)| (a, b)).collect(),
            markers: markers.iter().map(|m| (m.0, m.1)).collect(),
            iso_y,
        };
    }

    /// Selects the contour of live arc `arc`: at `global_h` when the arc
    /// spans it, else at the middle of its range.
    pub fn select_arc(
        ds: &Dataset,
        level: &SimplifiedTree,
        sel: &mut Selection,
        arc: SimplifiedArcId,
        global_h: f64,
        replace: bool,
    ) {
        let sim = level.simplification();
        let la = level.arc(arc);
        let (vu, vl) = (sim.node_value(la.upper), sim.node_value(la.lower));
        let h = if global_h >= vl && global_h < vu {
            global_h
        } else {
            0.5 * (vl + vu)
        };
        if let Some(seed) = path_seed_in_chain(&ds.tree, &ds.field, la.chain, Isovalue::new(h)) {
            sel.add(&ds.field, &ds.tree, seed.arc, h, replace);
        }
    }

    /// Moves contour `id` (and the contours of its group) to value `v`
    /// along the level set: on its arc while `v` stays in the arc's range;
    /// past the upper node into every arc above it (a join splits the
    /// contour going up), past the lower node into every arc below (a
    /// split); contours that meet on one arc merge. At a maximum or
    /// minimum the contour stops at the end of its arc.
    fn drag_marker(
        &self,
        ds: &Dataset,
        level: &SimplifiedTree,
        sel: &mut Selection,
        id: u64,
        v: f64,
    ) {
        let Some(group) = sel.get(id).map(|c| c.group) else {
            return;
        };
        // The dragged contour first, so it keeps following the pointer.
        let mut starts: Vec<SimplifiedArcId> = Vec::new();
        let lead = sel.get(id).and_then(|c| level.live_arc_of(c.superarc));
        starts.extend(lead);
        for c in sel
            .contours
            .iter()
            .filter(|c| c.group == group && c.id != id)
        {
            if let Some(a) = level.live_arc_of(c.superarc) {
                starts.push(a);
            }
        }
        let sim = level.simplification();
        let mut arcs: Vec<SimplifiedArcId> = Vec::new();
        for s in starts {
            for a in level_set_arcs(level, s, v) {
                if !arcs.contains(&a) {
                    arcs.push(a);
                }
            }
        }
        let mut positions = Vec::new();
        for a in arcs {
            let la = level.arc(a);
            let (vu, vl) = (sim.node_value(la.upper), sim.node_value(la.lower));
            // The contours of an arc exist at h + ε for h in [bottom, top).
            let top = vu - (vu - vl) * 1e-4;
            let h = v.clamp(vl, top.max(vl));
            if let Some(seed) = path_seed_in_chain(&ds.tree, &ds.field, la.chain, Isovalue::new(h))
            {
                positions.push((seed.arc, h));
            }
        }
        sel.set_group(&ds.field, &ds.tree, id, &positions);
    }
}

/// The live arcs holding the level set at `v` reached from arc `start` by
/// following it monotonically through the nodes in between (all arcs
/// above an upper node, all below a lower one); an arc ending at an
/// extremum keeps the contour at its end.
pub fn level_set_arcs(
    level: &SimplifiedTree,
    start: SimplifiedArcId,
    v: f64,
) -> Vec<SimplifiedArcId> {
    let sim = level.simplification();
    let mut out = Vec::new();
    let mut stack = vec![start];
    while let Some(a) = stack.pop() {
        let (u, l) = (sim.upper(a), sim.lower(a));
        let (top, bottom) = (sim.node_value(u), sim.node_value(l));
        let next: Vec<SimplifiedArcId> = if v >= top {
            level
                .arc_ids()
                .iter()
                .map(|&b| SimplifiedArcId(b))
                .filter(|&b| sim.lower(b) == u)
                .collect()
        } else if v < bottom {
            level
                .arc_ids()
                .iter()
                .map(|&b| SimplifiedArcId(b))
                .filter(|&b| sim.upper(b) == l)
                .collect()
        } else {
            Vec::new()
        };
        if next.is_empty() {
            if !out.contains(&a) {
                out.push(a);
            }
        } else {
            let mut next = next;
            next.sort();
            stack.extend(next.into_iter().rev());
        }
    }
    out
}
