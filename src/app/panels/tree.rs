//! The contour tree panel: the simplified tree drawn with y = isovalue and
//! x from the library's branch layout ([`crate::simplify::layout`]), nodes
//! coloured by kind,
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
//!
//! Hovering an arc says what it is: its values and costs, the size of the
//! region its contours enclose (vertices and physical volume, from the
//! collapsed tree's region summaries, [`crate::simplify::overview::arc_regions`]),
//! where its contours lie (box and centroid of its vertices in the
//! augmented tree, [`crate::simplify::overview::arc_extent`]), the genus
//! of its contour, and (drawn by the app) a dimmed preview of that contour
//! in the 3D view.

use egui::{Color32, Pos2, Rect, Sense, Stroke, Vec2, pos2, vec2};

use crate::contour::path_seed_in_chain;
use crate::field::Isovalue;
use crate::simplify::overview::{ArcSides, Extent, arc_extent, arc_regions};
use crate::simplify::{SimplifiedArcId, SimplifiedNodeId, SimplifiedTree};

use crate::app::dataset::Dataset;
use crate::app::format::{fmt_value, tick_step};
use crate::app::selection::{ContourId, Selection};

/// Node colours: maxima, minima, saddles.
const MAX_COLOUR: Color32 = Color32::from_rgb(230, 90, 80);
const MIN_COLOUR: Color32 = Color32::from_rgb(80, 140, 240);
const SADDLE_COLOUR: Color32 = Color32::from_rgb(230, 200, 80);
const ARC_COLOUR: Color32 = Color32::from_rgb(150, 150, 150);
const ISO_COLOUR: Color32 = Color32::from_rgb(120, 220, 160);

/// What is being dragged.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Drag {
    Marker(ContourId),
    IsoLine,
    Pan,
}

/// What the last frame drew, for tests and for picking.
#[derive(Clone, Debug, Default)]
pub struct Drawn {
    /// The panel's rect.
    pub rect: Option<Rect>,
    /// Live arcs drawn, with a screen point on each (the middle of its
    /// vertical part, where a click selects it).
    pub arcs: Vec<(SimplifiedArcId, Pos2)>,
    /// Screen height of each drawn arc (parallel to `arcs`).
    pub arc_heights: Vec<f32>,
    /// Screen ends (upper, lower) of each drawn arc (parallel to `arcs`).
    pub arc_ends: Vec<(Pos2, Pos2)>,
    /// Markers drawn: contour id and position.
    pub markers: Vec<(ContourId, Pos2)>,
    /// Screen y of the global isovalue line.
    pub iso_y: f32,
    /// Value labels drawn beside important nodes: node, the label's
    /// screen rect, its text.
    pub value_labels: Vec<(SimplifiedNodeId, Rect, String)>,
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
    /// What the hovered arc is (computed once per arc and level).
    pub hover_info: Option<HoverInfo>,
    /// A line on the hover preview in the 3D view (set by the app).
    pub preview_note: Option<String>,
}

/// Vertices read at most to place a hovered arc's contours (a trunk arc
/// of a big volume holds millions: a strided sample then).
const EXTENT_BUDGET: usize = 1 << 20;

/// What a hovered arc is: the sides of its contours and where they lie.
#[derive(Clone, Debug)]
pub struct HoverInfo {
    /// The arc.
    pub arc: SimplifiedArcId,
    /// The level's step.
    pub step: usize,
    /// Vertices on either side of its contours.
    pub sides: Option<ArcSides>,
    /// Where its contours lie (grid indices).
    pub extent: Option<Extent>,
}

impl HoverInfo {
    /// The info of `arc` at `level`.
    pub fn of(ds: &Dataset, level: &SimplifiedTree, arc: SimplifiedArcId) -> Self {
        let sim = level.simplification();
        HoverInfo {
            arc,
            step: level.step(),
            sides: arc_regions(sim, &ds.collapsed, arc),
            extent: arc_extent(&ds.tree, sim, ds.field.dims(), arc, EXTENT_BUDGET),
        }
    }

    /// Lines for the tooltip: the enclosed region in vertices and
    /// physical volume (`spacing` per axis), and the box and centre in
    /// world units.
    pub fn describe(&self, spacing: [f64; 3]) -> String {
        let mut out = String::new();
        let voxel = spacing[0] * spacing[1] * spacing[2];
        if let Some(s) = self.sides {
            let (n, above) = s.enclosed();
            out.push_str(&format!(
                "encloses {n} voxels ({} units³) {} its contours; {} on the other side",
                fmt_value(n as f64 * voxel),
                if above { "above" } else { "below" },
                if above { s.below } else { s.above },
            ));
        }
        if let Some(e) = self.extent {
            let w = |k: usize, i: f64| i * spacing[k];
            if !out.is_empty() {
                out.push('\n');
            }
            out.push_str(&format!(
                "lies in x {}..{}  y {}..{}  z {}..{}, centre ({}, {}, {})",
                fmt_value(w(0, e.min[0] as f64)),
                fmt_value(w(0, e.max[0] as f64)),
                fmt_value(w(1, e.min[1] as f64)),
                fmt_value(w(1, e.max[1] as f64)),
                fmt_value(w(2, e.min[2] as f64)),
                fmt_value(w(2, e.max[2] as f64)),
                fmt_value(w(0, e.centroid[0])),
                fmt_value(w(1, e.centroid[1])),
                fmt_value(w(2, e.centroid[2])),
            ));
        }
        out
    }
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

/// A selected contour's marker on the live arc holding it, or the one that absorbed it.
#[derive(Clone, Copy)]
struct Marker {
    id: ContourId,
    pos: Pos2,
    colour: Color32,
    arc: SimplifiedArcId,
}

/// One frame's geometry: where every node and arc is on the screen.
struct Frame {
    rect: Rect,
    plot: Rect,
    tf: Transform,
    /// Live arcs: id and screen ends (upper, lower), by id.
    segs: Vec<(SimplifiedArcId, Pos2, Pos2)>,
    /// The polyline drawn for each (the library's layout), upper end first.
    paths: Vec<Vec<Pos2>>,
    /// A point on each arc's vertical part, for clicks and scripts.
    picks: Vec<Pos2>,
    markers: Vec<Marker>,
}

impl Frame {
    /// The arc nearest to `p` within 6 points; among those about as near
    /// (at a crossing, or where arcs meet at a node), one holding a
    /// selected contour, else the shortest on the screen
    /// ([`nearest_arc`]).
    fn nearest(&self, p: Pos2) -> Option<SimplifiedArcId> {
        let arcs = self
            .segs
            .iter()
            .zip(&self.paths)
            .map(|(&(id, _, _), path)| {
                let selected = self.markers.iter().any(|m| m.arc == id);
                (id, path.as_slice(), selected)
            });
        nearest_arc(p, arcs)
    }
}

/// How near an arc must be to `p` to be picked, in points.
const PICK_TOLERANCE: f32 = 6.0;

/// Arcs this much farther than the nearest still count as tied with it
/// (at a crossing; small enough that on a dense tree, columns a few
/// points apart, a click on a column still picks that column).
const PICK_TIE: f32 = 1.0;

/// The arc picked at `p` among `arcs` (id, screen polyline, whether it
/// holds a selected contour): the nearest within [`PICK_TOLERANCE`];
/// among those within [`PICK_TIE`] of the nearest, a selected one, then
/// the shortest polyline, then the lowest id. So at a crossing, or at a
/// node where a short arc meets a long one, the short (or selected) arc
/// wins and stays clickable.
fn nearest_arc<'a>(
    p: Pos2,
    arcs: impl Iterator<Item = (SimplifiedArcId, &'a [Pos2], bool)>,
) -> Option<SimplifiedArcId> {
    let near: Vec<(f32, bool, f32, SimplifiedArcId)> = arcs
        .filter_map(|(id, path, selected)| {
            let d = path
                .windows(2)
                .map(|w| segment_distance(p, w[0], w[1]))
                .fold(f32::INFINITY, f32::min);
            let length: f32 = path.windows(2).map(|w| w[0].distance(w[1])).sum();
            (d <= PICK_TOLERANCE).then_some((d, selected, length, id))
        })
        .collect();
    let best = near.iter().map(|a| a.0).fold(f32::INFINITY, f32::min);
    near.into_iter()
        .filter(|a| a.0 <= best + PICK_TIE)
        .min_by(|x, y| {
            y.1.cmp(&x.1)
                .then(x.2.total_cmp(&y.2))
                .then(x.3.0.cmp(&y.3.0))
        })
        .map(|a| a.3)
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
        let frame = self.frame(rect, ds, level, sel);
        let pointer = response.hover_pos();
        self.hovered = pointer.and_then(|p| frame.nearest(p));
        match self.hovered {
            Some(a)
                if self
                    .hover_info
                    .as_ref()
                    .is_none_or(|i| i.arc != a || i.step != level.step()) =>
            {
                self.hover_info = Some(HoverInfo::of(ds, level, a));
            }
            Some(_) => {}
            None => self.hover_info = None,
        }
        self.interact(ui, &response, &frame, ds, level, sel, global_h);

        let painter = ui.painter_at(rect);
        painter.rect_filled(rect, 0.0, ui.visuals().extreme_bg_color);
        self.draw_axis(ui, &painter, &frame);
        let (iso_y, iso_label) = self.draw_iso_line(&painter, &frame, *global_h);
        let names = marker_names(&painter, &frame, sel);
        self.draw_tree(&painter, &frame, level, sel, &names);
        let legend = draw_legend(ui, &painter, &frame);
        let value_labels =
            self.draw_value_labels(ui, &painter, &frame, ds, level, &names, (legend, iso_label));
        if let Some(a) = self.hovered
            && self.drag.is_none()
        {
            let hv = pointer.map(|p| frame.tf.value_at(p.y));
            let tip = self.arc_tooltip(ds, level, a, hv);
            response.clone().on_hover_text_at_pointer(tip);
        }

        let segs = &frame.segs;
        self.drawn = Drawn {
            rect: Some(rect),
            arcs: segs
                .iter()
                .zip(&frame.picks)
                .map(|(&(id, _, _), &p)| (id, p))
                .collect(),
            arc_heights: segs.iter().map(|&(_, a, b)| (b.y - a.y).abs()).collect(),
            arc_ends: segs.iter().map(|&(_, a, b)| (a, b)).collect(),
            markers: frame.markers.iter().map(|m| (m.id, m.pos)).collect(),
            iso_y,
            value_labels,
        };
    }

    /// Where everything is this frame: the transform, the live arcs' ends
    /// and the markers.
    fn frame(&self, rect: Rect, ds: &Dataset, level: &SimplifiedTree, sel: &Selection) -> Frame {
        // The legend has its own strip above the plot, never over the tree.
        let plot = Rect::from_min_max(rect.min + vec2(60.0, 26.0), rect.max - vec2(14.0, 14.0));
        let (lo, hi) = ds.range;
        let tf = Transform {
            plot,
            lo,
            hi,
            zoom: self.zoom,
            pan: self.pan,
        };
        let sim = level.simplification();
        let node_pos = |n: SimplifiedNodeId| -> Pos2 { self.node_pos(&tf, level, n) };
        let mut segs: Vec<(SimplifiedArcId, Pos2, Pos2)> = level
            .arcs()
            .map(|a| (a.id, node_pos(a.upper), node_pos(a.lower)))
            .collect();
        segs.sort_by_key(|s| s.0);
        let column = |n: SimplifiedNodeId| {
            let x = self.columns.get(n.0 as usize).copied().unwrap_or(0.5);
            if x.is_finite() { x } else { 0.5 }
        };
        let paths: Vec<Vec<Pos2>> = segs
            .iter()
            .map(|&(id, _, _)| {
                ds.layout
                    .arc_points(level, id, column)
                    .as_slice()
                    .iter()
                    .map(|p| tf.screen(p[0] as f32, p[1]))
                    .collect()
            })
            .collect();
        // The vertical part of each path: (x, upper y, lower y).
        let vertical = |path: &[Pos2]| -> Option<(f32, f32, f32)> {
            path.windows(2)
                .find(|w| (w[0].x - w[1].x).abs() < 0.01 && (w[0].y - w[1].y).abs() > 0.0)
                .map(|w| (w[0].x, w[0].y, w[1].y))
        };
        let picks: Vec<Pos2> = paths
            .iter()
            .map(|path| match vertical(path) {
                Some((x, a, b)) => pos2(x, 0.5 * (a + b)),
                None => path[0] + (path[path.len() - 1] - path[0]) * 0.5,
            })
            .collect();
        // Markers: each selected contour on the live arc holding it, or
        // absorbing it when its branch is pruned (none when neither).
        let mut markers = Vec::new();
        for c in &sel.contours {
            if let Some(a) = level.absorbing_arc_of(c.superarc) {
                let la = level.arc(a);
                let (pu, pl) = (node_pos(la.upper), node_pos(la.lower));
                let (vu, vl) = (sim.node_value(la.upper), sim.node_value(la.lower));
                let t = if vu > vl {
                    ((c.h - vl) / (vu - vl)).clamp(0.0, 1.0) as f32
                } else {
                    0.5
                };
                let on_path = segs
                    .binary_search_by_key(&a, |s| s.0)
                    .ok()
                    .and_then(|i| vertical(&paths[i]))
                    .map(|(x, _, _)| pos2(x, tf.screen(0.0, c.h.clamp(vl, vu)).y));
                let mut pos = on_path.unwrap_or(pl + (pu - pl) * t);
                // Never stacked: a marker on another's spot (contours of
                // one arc at one value, e.g. absorbed by the same arc) goes
                // beside it, so each can be seen and grabbed.
                while markers.iter().any(|m: &Marker| m.pos.distance(pos) < 4.0) {
                    pos.x += 13.0;
                }
                markers.push(Marker {
                    id: c.id,
                    pos,
                    colour: c.colour,
                    arc: a,
                });
            }
        }
        Frame {
            rect,
            plot,
            tf,
            segs,
            paths,
            picks,
            markers,
        }
    }

    fn node_pos(&self, tf: &Transform, level: &SimplifiedTree, n: SimplifiedNodeId) -> Pos2 {
        let x = self.columns.get(n.0 as usize).copied().unwrap_or(0.5);
        let x = if x.is_finite() { x } else { 0.5 };
        tf.screen(x, level.simplification().node_value(n))
    }

    /// Clicks, drags (marker, iso line, pan), wheel zoom, double-click.
    #[allow(clippy::too_many_arguments)]
    fn interact(
        &mut self,
        ui: &egui::Ui,
        response: &egui::Response,
        frame: &Frame,
        ds: &Dataset,
        level: &SimplifiedTree,
        sel: &mut Selection,
        global_h: &mut f64,
    ) {
        let tf = &frame.tf;
        let press = ui.input(|i| i.pointer.press_origin());
        if response.drag_started() {
            let by_primary = ui.input(|i| i.pointer.primary_down());
            self.drag = if !by_primary {
                Some(Drag::Pan)
            } else if let Some(p) = press {
                let on_marker = frame
                    .markers
                    .iter()
                    .map(|m| (m.pos.distance(p), m.id))
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
                    Self::drag_marker(ds, level, sel, id, tf.value_at(p.y));
                }
                Some(Drag::IsoLine) => {
                    *global_h = tf.value_at(p.y).clamp(ds.range.0, ds.range.1);
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
                && let Some(q) = response.hover_pos()
            {
                let z = self.zoom;
                let nz = (z * (0.002 * scroll).exp()).clamp(0.2, 500.0);
                let c = frame.plot.center();
                self.pan = (q - c) - (q - c - self.pan) * (nz / z);
                self.zoom = nz;
            }
        }
        if response.double_clicked() {
            self.zoom = 1.0;
            self.pan = Vec2::ZERO;
        } else if response.clicked()
            && let Some(p) = response.interact_pointer_pos()
            && let Some(arc) = frame.nearest(p)
        {
            let shift = ui.input(|i| i.modifiers.shift);
            Self::select_arc(ds, level, sel, arc, *global_h, !shift);
        }
    }

    /// The value axis with its ticks and faint grid lines.
    fn draw_axis(&self, ui: &egui::Ui, painter: &egui::Painter, frame: &Frame) {
        let (rect, plot, tf) = (frame.rect, frame.plot, &frame.tf);
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
    }

    /// The global isovalue as a dashed line with its value; its screen y
    /// and the rect of its value's label.
    fn draw_iso_line(&self, painter: &egui::Painter, frame: &Frame, global_h: f64) -> (f32, Rect) {
        let (rect, plot) = (frame.rect, frame.plot);
        let iso_y = frame.tf.screen(0.0, global_h).y;
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
        let label = painter.text(
            pos2(rect.right() - 4.0, iso_y - 2.0),
            egui::Align2::RIGHT_BOTTOM,
            format!("h = {}", fmt_value(global_h)),
            egui::FontId::monospace(10.0),
            ISO_COLOUR,
        );
        (iso_y, label)
    }

    /// Arcs (selected ones in their contour's colour), nodes by kind, and
    /// the markers.
    fn draw_tree(
        &self,
        painter: &egui::Painter,
        frame: &Frame,
        level: &SimplifiedTree,
        sel: &Selection,
        names: &[MarkerName],
    ) {
        for (&(id, _, _), path) in frame.segs.iter().zip(&frame.paths) {
            let (width, colour) = if let Some(m) = frame.markers.iter().find(|m| m.arc == id) {
                (3.0, m.colour)
            } else if self.hovered == Some(id) {
                (3.0, Color32::WHITE)
            } else {
                (1.5, ARC_COLOUR)
            };
            painter.add(egui::Shape::line(path.clone(), Stroke::new(width, colour)));
        }
        if level.num_arcs() <= 5000 {
            for n in level.nodes() {
                let (up, down) = level.degree(n);
                let colour = match (up, down) {
                    (0, _) => MAX_COLOUR,
                    (_, 0) => MIN_COLOUR,
                    _ => SADDLE_COLOUR,
                };
                painter.circle_filled(self.node_pos(&frame.tf, level, n), 3.5, colour);
            }
        }
        for m in &frame.markers {
            let active = sel.active == Some(m.id);
            painter.circle(
                m.pos,
                if active { 7.0 } else { 6.0 },
                m.colour,
                Stroke::new(if active { 2.0 } else { 1.0 }, Color32::WHITE),
            );
        }
        for (rect, galley, colour) in names {
            painter.galley(rect.min, galley.clone(), *colour);
        }
    }

    /// Values beside the important nodes ([`important_nodes`]), each
    /// value once, placed by [`place_labels`] clear of each other, the
    /// node dots, the arcs, the markers and their names, the legend and
    /// the isovalue's label; what does not fit is left out. What was
    /// drawn.
    #[allow(clippy::too_many_arguments)]
    fn draw_value_labels(
        &self,
        ui: &egui::Ui,
        painter: &egui::Painter,
        frame: &Frame,
        ds: &Dataset,
        level: &SimplifiedTree,
        names: &[MarkerName],
        (legend, iso_label): (Rect, Rect),
    ) -> Vec<(SimplifiedNodeId, Rect, String)> {
        let sim = level.simplification();
        let font = egui::FontId::monospace(VALUE_LABEL_SIZE);
        // A value already labelled is not repeated (many maxima of an
        // 8-bit volume sit at 255).
        let mut nodes = important_nodes(ds.layout.branches(), level, 3 * MAX_VALUE_LABELS);
        let mut texts: Vec<String> = Vec::with_capacity(nodes.len());
        nodes.retain(|&n| {
            let t = fmt_value(sim.node_value(n));
            let new = !texts.contains(&t);
            if new {
                texts.push(t);
            }
            new
        });
        let colour = ui.visuals().text_color().gamma_multiply(0.85);
        let galleys: Vec<_> = texts
            .iter()
            .map(|t| painter.layout_no_wrap(t.clone(), font.clone(), colour))
            .collect();
        let anchors: Vec<(Pos2, Vec2)> = nodes
            .iter()
            .zip(&galleys)
            .map(|(&n, g)| (self.node_pos(&frame.tf, level, n), g.size()))
            .collect();
        // What a label must keep clear of: every labelled node's dot, the
        // arcs (a label never hides the tree), the markers and their
        // names, the legend, the isovalue's label.
        let mut obstacles: Vec<Rect> = anchors
            .iter()
            .map(|&(p, _)| Rect::from_center_size(p, vec2(8.0, 8.0)))
            .collect();
        for path in &frame.paths {
            for w in path.windows(2) {
                obstacles.push(Rect::from_two_pos(w[0], w[1]).expand(1.5));
            }
        }
        obstacles.push(legend.expand(2.0));
        obstacles.push(iso_label.expand(2.0));
        for m in &frame.markers {
            obstacles.push(Rect::from_center_size(m.pos, vec2(16.0, 16.0)));
        }
        for (r, _, _) in names {
            obstacles.push(r.expand(2.0));
        }
        // Inside the plot, never in the legend's strip above it.
        let bounds = Rect::from_min_max(
            pos2(frame.plot.left() - 6.0, frame.plot.top() - 8.0),
            pos2(frame.rect.right() - 2.0, frame.rect.bottom() - 2.0),
        );
        let placed = place_labels(&anchors, &obstacles, bounds, MAX_VALUE_LABELS);
        placed
            .into_iter()
            .map(|(i, r)| {
                painter.galley(r.min, galleys[i].clone(), colour);
                (nodes[i], r, texts[i].clone())
            })
            .collect()
    }

    /// What the tooltip of arc `a` says: its values, costs, and the genus
    /// of its contour at the pointer's value `hv` (or the middle).
    fn arc_tooltip(
        &self,
        ds: &Dataset,
        level: &SimplifiedTree,
        a: SimplifiedArcId,
        hv: Option<f64>,
    ) -> String {
        let sim = level.simplification();
        let la = level.arc(a);
        let (vu, vl) = (sim.node_value(la.upper), sim.node_value(la.lower));
        let hv = hv
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
        let what = self
            .hover_info
            .as_ref()
            .filter(|i| i.arc == a)
            .map(|i| i.describe(ds.field.spacing()))
            .unwrap_or_default();
        let preview = self.preview_note.clone().unwrap_or_default();
        format!(
            "arc {}: values {} .. {}\nup cost {}  down cost {}\n{} superarc(s)\n{what}\n{genus}\n{preview}\nclick: select its contour, shift-click: add",
            a.0,
            fmt_value(vl),
            fmt_value(vu),
            fmt_value(la.up_cost),
            fmt_value(la.down_cost),
            la.chain.len(),
        )
    }

    /// The contour a click on live arc `arc` selects: (superarc,
    /// isovalue) at `global_h` when the arc spans it, else at the middle
    /// of its range.
    pub fn contour_of_arc(
        ds: &Dataset,
        level: &SimplifiedTree,
        arc: SimplifiedArcId,
        global_h: f64,
    ) -> Option<(crate::tree::ArcId, f64)> {
        let sim = level.simplification();
        let la = level.arc(arc);
        let (vu, vl) = (sim.node_value(la.upper), sim.node_value(la.lower));
        let h = if global_h >= vl && global_h < vu {
            global_h
        } else {
            0.5 * (vl + vu)
        };
        path_seed_in_chain(&ds.tree, &ds.field, la.chain, Isovalue::new(h)).map(|s| (s.arc, h))
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
        if let Some((s, h)) = Self::contour_of_arc(ds, level, arc, global_h) {
            sel.add(&ds.field, &ds.tree, s, h, replace);
        }
    }

    /// True while something in the panel is dragged.
    pub fn dragging(&self) -> bool {
        self.drag.is_some()
    }

    /// Moves contour `id` (and the contours of its group) to value `v`
    /// along the level set: on its arc while `v` stays in the arc's range;
    /// past the upper node into every arc above it (a join splits the
    /// contour going up), past the lower node into every arc below (a
    /// split); contours that meet on one arc merge. At a maximum or
    /// minimum the contour stops at the end of its arc.
    fn drag_marker(
        ds: &Dataset,
        level: &SimplifiedTree,
        sel: &mut Selection,
        id: ContourId,
        v: f64,
    ) {
        let Some(group) = sel.get(id).map(|c| c.group) else {
            return;
        };
        // The dragged contour first, so it keeps following the pointer.
        let mut starts: Vec<SimplifiedArcId> = Vec::new();
        let lead = sel.get(id).and_then(|c| level.absorbing_arc_of(c.superarc));
        starts.extend(lead);
        for c in sel
            .contours
            .iter()
            .filter(|c| c.group == group && c.id != id)
        {
            if let Some(a) = level.absorbing_arc_of(c.superarc) {
                starts.push(a);
            }
        }
        let sim = level.simplification();
        let mut arcs: Vec<SimplifiedArcId> = Vec::new();
        for s in starts {
            for a in level.level_set_arcs(s, v) {
                if !arcs.contains(&a) {
                    arcs.push(a);
                }
            }
        }
        let mut positions: Vec<(crate::tree::ArcId, f64)> = Vec::new();
        for (i, a) in arcs.into_iter().enumerate() {
            let la = level.arc(a);
            let (vu, vl) = (sim.node_value(la.upper), sim.node_value(la.lower));
            // A contour other than the dragged one whose arc ends before
            // `v` (at an extremum) has vanished there: it is dropped, not
            // left as a point at the extremum. The dragged one stops at
            // the end of its arc.
            if i > 0 && !(vl..=vu).contains(&v) {
                continue;
            }
            // The contours of an arc exist at h + ε for h in [bottom, top).
            let top = vu - (vu - vl) * 1e-4;
            let h = v.clamp(vl, top.max(vl));
            if let Some(seed) = path_seed_in_chain(&ds.tree, &ds.field, la.chain, Isovalue::new(h))
                && !positions.iter().any(|p| p.0 == seed.arc)
            {
                positions.push((seed.arc, h));
            }
        }
        sel.set_group(&ds.field, &ds.tree, id, &positions);
    }
}

/// The node colours' legend, above the plot; the rect it covers.
fn draw_legend(ui: &egui::Ui, painter: &egui::Painter, frame: &Frame) -> Rect {
    let text = ui.visuals().text_color();
    let font = egui::FontId::monospace(10.0);
    let mut lx = frame.plot.left();
    let y = frame.rect.top() + 7.0;
    let mut covered = Rect::from_center_size(pos2(lx, y), vec2(7.0, 7.0));
    for (name, c) in [
        ("max", MAX_COLOUR),
        ("min", MIN_COLOUR),
        ("saddle", SADDLE_COLOUR),
    ] {
        painter.circle_filled(pos2(lx, y), 3.5, c);
        let r = painter.text(
            pos2(lx + 6.0, y),
            egui::Align2::LEFT_CENTER,
            name,
            font.clone(),
            text,
        );
        covered = covered.union(r);
        lx = r.right() + 10.0;
    }
    covered
}

/// At most this many value labels in the tree panel.
pub const MAX_VALUE_LABELS: usize = 12;

/// Font size of the value labels (the axis's is 10).
const VALUE_LABEL_SIZE: f32 = 9.5;

/// Font size of a marker's name.
const MARKER_NAME_SIZE: f32 = 12.0;

/// A marker's name where it is drawn: its rect, its text, its colour.
type MarkerName = (Rect, std::sync::Arc<egui::Galley>, Color32);

/// A marker's name left-aligned 10 points right of it, centred on it:
/// where [`place_marker_names`] puts a name that fits nowhere clear.
fn marker_name_rect(marker: Pos2, size: Vec2) -> Rect {
    Rect::from_min_size(marker + vec2(10.0, -0.5 * size.y), size)
}

/// The names of the named markers, each placed by [`place_labels`] clear
/// of every marker and of the names before it (markers in selection
/// order), else right of its marker. Laid out once a frame, for the
/// markers and for the value labels that keep clear of them.
fn marker_names(painter: &egui::Painter, frame: &Frame, sel: &Selection) -> Vec<MarkerName> {
    let named: Vec<(&Marker, std::sync::Arc<egui::Galley>)> = frame
        .markers
        .iter()
        .filter_map(|m| {
            let c = sel.get(m.id)?;
            (!c.name.is_empty()).then(|| {
                let g = painter.layout_no_wrap(
                    c.name.clone(),
                    egui::FontId::proportional(MARKER_NAME_SIZE),
                    m.colour,
                );
                (m, g)
            })
        })
        .collect();
    if named.is_empty() {
        return Vec::new();
    }
    let all: Vec<Pos2> = frame.markers.iter().map(|m| m.pos).collect();
    let names: Vec<(Pos2, Vec2)> = named.iter().map(|(m, g)| (m.pos, g.size())).collect();
    let rects = place_marker_names(&all, &names, frame.rect);
    named
        .into_iter()
        .zip(rects)
        .map(|((m, g), rect)| (rect, g, m.colour))
        .collect()
}

/// Where each name goes: `names` holds (its marker, its text's size) in
/// selection order, `markers` every marker. Each name is placed by
/// [`place_labels`] right of, left of, above or below its marker, clear
/// of every marker's core (smaller than the labels' gap, so that a name's
/// own marker never blocks it) and of the names before it, padded by 4
/// points a side to keep clear of the markers' rims; a name that fits
/// nowhere goes right of its marker.
fn place_marker_names(markers: &[Pos2], names: &[(Pos2, Vec2)], bounds: Rect) -> Vec<Rect> {
    const PAD: f32 = 4.0;
    let obstacles: Vec<Rect> = markers
        .iter()
        .map(|&p| Rect::from_center_size(p, vec2(10.0, 10.0)))
        .collect();
    let anchors: Vec<(Pos2, Vec2)> = names
        .iter()
        .map(|&(p, size)| (p, size + vec2(2.0 * PAD, 2.0 * PAD)))
        .collect();
    let mut at: Vec<Option<Rect>> = vec![None; names.len()];
    for (i, r) in place_labels(&anchors, &obstacles, bounds, usize::MAX) {
        at[i] = Some(r);
    }
    names
        .iter()
        .zip(at)
        .map(|(&(p, size), r)| match r {
            // Inside the padded rect, on the side away from the marker.
            Some(r) if r.center().x > p.x + 1.0 => {
                Rect::from_min_size(pos2(r.max.x - size.x, r.center().y - 0.5 * size.y), size)
            }
            Some(r) if r.center().x < p.x - 1.0 => {
                Rect::from_min_size(pos2(r.min.x, r.center().y - 0.5 * size.y), size)
            }
            Some(r) => Rect::from_center_size(r.center(), size),
            None => marker_name_rect(p, size),
        })
        .collect()
}

/// The live nodes worth a value label at `level`, most important first
/// and without repeats, at most `most`: the ends of the root branches
/// (the tree's global extrema when it is one arc), then the tip and the
/// saddle of each live branch in the order of the branch decomposition
/// (pruned last first, [`crate::simplify::branches`]).
pub fn important_nodes(
    branches: &crate::simplify::branches::Branches,
    level: &SimplifiedTree,
    most: usize,
) -> Vec<SimplifiedNodeId> {
    use crate::simplify::branches::BranchId;
    let sim = level.simplification();
    let mut out: Vec<SimplifiedNodeId> = Vec::new();
    let push = |n: SimplifiedNodeId, out: &mut Vec<SimplifiedNodeId>| {
        if out.len() < most && !out.contains(&n) {
            out.push(n);
        }
    };
    // The roots' ends: each root branch's live nodes' highest and lowest.
    let nodes = level.nodes();
    for r in branches.roots() {
        let on: Vec<SimplifiedNodeId> = nodes
            .iter()
            .copied()
            .filter(|&n| branches.of_node(n) == r)
            .collect();
        let by_value = |a: &&SimplifiedNodeId, b: &&SimplifiedNodeId| {
            sim.node_value(**a).total_cmp(&sim.node_value(**b))
        };
        if let Some(&top) = on.iter().max_by(by_value) {
            push(top, &mut out);
        }
        if let Some(&bottom) = on.iter().min_by(by_value) {
            push(bottom, &mut out);
        }
    }
    let step = level.step();
    for k in (step..branches.steps()).rev() {
        if out.len() >= most {
            break;
        }
        let b = BranchId(k as u32);
        for n in [branches.tip(b), branches.attachment(b)]
            .into_iter()
            .flatten()
        {
            push(n, &mut out);
        }
    }
    out
}

/// Places labels of the given sizes beside their anchors, in the order
/// given (most important first): each at the first of right of, left
/// of, above or below its anchor that lies inside `bounds` and overlaps
/// neither an obstacle nor a label placed before it; one that fits
/// nowhere is left out, and at most `most` are placed. Returns (index,
/// rect) of the placed ones, in order.
pub fn place_labels(
    anchors: &[(Pos2, Vec2)],
    obstacles: &[Rect],
    bounds: Rect,
    most: usize,
) -> Vec<(usize, Rect)> {
    const GAP: f32 = 6.0;
    let mut placed: Vec<(usize, Rect)> = Vec::new();
    for (i, &(p, size)) in anchors.iter().enumerate() {
        if placed.len() >= most {
            break;
        }
        let options = [
            Rect::from_min_size(pos2(p.x + GAP, p.y - 0.5 * size.y), size),
            Rect::from_min_size(pos2(p.x - GAP - size.x, p.y - 0.5 * size.y), size),
            Rect::from_min_size(pos2(p.x - 0.5 * size.x, p.y - GAP - size.y), size),
            Rect::from_min_size(pos2(p.x - 0.5 * size.x, p.y + GAP), size),
        ];
        let free = |r: &Rect| {
            bounds.contains_rect(*r)
                && !obstacles.iter().any(|o| o.intersects(*r))
                && !placed.iter().any(|(_, q)| q.intersects(*r))
        };
        if let Some(r) = options.into_iter().find(free) {
            placed.push((i, r));
        }
    }
    placed
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn marker_names_side_by_side_go_apart_clear_of_every_marker() {
        let bounds = Rect::from_min_max(pos2(0.0, 0.0), pos2(400.0, 300.0));
        // Two markers 22 points apart on one row (the eyes of colin27),
        // a third just above the second, each with a name wider than the
        // gap between them.
        let markers = [pos2(80.0, 150.0), pos2(102.0, 150.0), pos2(102.0, 128.0)];
        let size = vec2(50.0, 12.0);
        let names: Vec<(Pos2, Vec2)> = markers.iter().map(|&p| (p, size)).collect();
        let rects = place_marker_names(&markers, &names, bounds);
        assert_eq!(rects.len(), 3);
        for (i, r) in rects.iter().enumerate() {
            assert!(bounds.contains_rect(*r), "{i}: {r:?}");
            for (j, q) in rects.iter().enumerate().skip(i + 1) {
                assert!(!r.intersects(*q), "names {i} and {j} overlap: {r:?} {q:?}");
            }
            for (k, &m) in markers.iter().enumerate() {
                let rim = Rect::from_center_size(m, vec2(12.0, 12.0));
                assert!(!r.intersects(rim), "name {i} covers marker {k}: {r:?}");
            }
        }
        // The first keeps its usual place when nothing is in the way.
        let alone = place_marker_names(&markers[..1], &names[..1], bounds);
        assert!(alone[0].min.x > markers[0].x && (alone[0].center().y - 150.0).abs() < 0.5);
    }

    #[test]
    fn value_labels_never_overlap_each_other_or_obstacles_and_are_at_most_n() {
        let bounds = Rect::from_min_max(pos2(0.0, 0.0), pos2(400.0, 300.0));
        let size = vec2(30.0, 10.0);
        // Nodes crowded in a corner and spread out, a legend-like strip
        // and a marker name in the middle.
        let mut anchors = Vec::new();
        let mut seed = 7u32;
        let mut next = || {
            seed = seed.wrapping_mul(1_103_515_245).wrapping_add(12_345);
            (seed >> 16) as f32 / 65_536.0
        };
        for _ in 0..40 {
            anchors.push((pos2(20.0 + 60.0 * next(), 20.0 + 40.0 * next()), size));
        }
        for _ in 0..40 {
            anchors.push((pos2(400.0 * next(), 300.0 * next()), size));
        }
        let obstacles = [
            Rect::from_min_max(pos2(0.0, 0.0), pos2(200.0, 14.0)),
            Rect::from_min_max(pos2(180.0, 140.0), pos2(240.0, 156.0)),
        ];
        for most in [0, 1, 5, 12, 100] {
            let placed = place_labels(&anchors, &obstacles, bounds, most);
            assert!(placed.len() <= most);
            if most > 0 {
                assert!(!placed.is_empty(), "room for at least one of {most}");
            }
            for (k, &(i, r)) in placed.iter().enumerate() {
                assert!(bounds.contains_rect(r));
                assert!(
                    obstacles.iter().all(|o| !o.intersects(r)),
                    "label {i} on an obstacle"
                );
                assert!(
                    placed[k + 1..].iter().all(|(_, q)| !q.intersects(r)),
                    "label {i} overlaps another"
                );
                // Beside its own node, not somewhere else.
                let p = anchors[i].0;
                assert!(r.expand(7.0).contains(p), "label {i} away from its node");
            }
            // Earlier (more important) labels are placed first: the
            // indices increase.
            assert!(placed.windows(2).all(|w| w[0].0 < w[1].0));
        }
        // The crowded corner cannot hold all 40 there.
        let placed = place_labels(&anchors[..40], &[], bounds, 100);
        assert!(
            placed.len() < 40,
            "{} labels in a 60×40 corner",
            placed.len()
        );
    }

    fn arc(id: u32, points: &[(f32, f32)]) -> (SimplifiedArcId, Vec<Pos2>) {
        (
            SimplifiedArcId(id),
            points.iter().map(|&(x, y)| Pos2::new(x, y)).collect(),
        )
    }

    #[test]
    fn at_a_crossing_the_shorter_arc_wins_unless_the_longer_is_selected() {
        // A long vertical arc and a short horizontal one crossing at (50, 50).
        let long = arc(1, &[(50.0, 0.0), (50.0, 400.0)]);
        let short = arc(2, &[(40.0, 50.0), (60.0, 50.0)]);
        let pick = |p: Pos2, selected: u32| {
            let arcs = [&long, &short]
                .into_iter()
                .map(|(id, path)| (*id, path.as_slice(), id.0 == selected));
            nearest_arc(p, arcs)
        };
        let crossing = Pos2::new(50.5, 50.5);
        assert_eq!(pick(crossing, 0), Some(SimplifiedArcId(2)));
        assert_eq!(pick(crossing, 1), Some(SimplifiedArcId(1)));
        // Away from the crossing the nearest arc wins, selected or not.
        assert_eq!(pick(Pos2::new(51.0, 200.0), 2), Some(SimplifiedArcId(1)));
        assert_eq!(pick(Pos2::new(41.0, 51.0), 1), Some(SimplifiedArcId(2)));
        // Nothing within the tolerance.
        assert_eq!(pick(Pos2::new(100.0, 200.0), 0), None);
    }
}
